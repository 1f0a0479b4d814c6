// (being written)
#include "batch_test_support.hpp"
