// The model (core/include/tessera/core/model.hpp) and its constraint graph
// (coloring/include/tessera/coloring/model_graph.hpp): what a solver user includes.
#pragma once

#include <tessera/coloring/model_graph.hpp>
#include <tessera/core/model.hpp>
