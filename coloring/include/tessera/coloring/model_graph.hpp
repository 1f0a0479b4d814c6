// The constraint graph of a Model (core): the input of every colouring strategy, with the
// model's global constraint ids.
#pragma once

#include <tessera/coloring/constraint_graph.hpp>
#include <tessera/core/model.hpp>

namespace tessera {

/// The constraint ↔ movable-particle graph of all families of `model` (one group per
/// non-empty family, named by family_name). Throws InvalidInput when a batch was built for
/// more particles than the model has.
ConstraintGraph constraint_graph(const Model& model);

}  // namespace tessera
