// (being written)
#include "test_support.hpp"
