// (being written)
#include <tessera/core/position_based_dynamics.hpp>
