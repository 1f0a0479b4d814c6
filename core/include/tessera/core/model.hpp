// A model: what the solver simulates. Particles (SoA, the user's numbering) and one batch per
// constraint family, each built and validated by make_<family>_constraints. Core types only,
// so scene generators and mesh readers (io) can build models without the solver.
//
//   Model ──► constraint_graph(model) ──► a ColouringStrategy ──► Colouring
//         ──► Solver(model, colouring)                      (coloring/ and parallel/)
//
// Constraints have a global id: the families' constraints concatenated in the fixed order
// of ConstraintFamily (constraint_families.hpp: every constraint of the first family, then
// of the second, ...). The constraint graph, the colouring and the solver's lookups (lambda,
// residuals) all speak of that id.
#pragma once

#include <cstddef>

#include <tessera/core/constraint_families.hpp>
#include <tessera/core/indices.hpp>
#include <tessera/core/particle_state.hpp>

namespace tessera {

struct Model {
  ParticleState particles;
  ConstraintSets constraints;

  /// The global id of constraint `index` of `family`.
  ConstraintIndex constraint_id(ConstraintFamily family, std::size_t index) const;
};

}  // namespace tessera
