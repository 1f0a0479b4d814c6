// Locality: renumbering particles and ordering constraints within each colour so that the
// gathers and scatters of one colour's sweep walk memory mostly forward and in small strides.
//
// The particle order is reverse Cuthill–McKee on the particle graph (particles adjacent when a
// constraint joins them), which keeps neighbours' numbers close (small bandwidth); within each
// colour, constraints are then listed by their smallest renumbered particle, so consecutive
// constraints (one SIMD batch, one worker's slice) touch nearby particles. The renumbering is
// carried in the Colouring both ways (particle_new_to_old / particle_old_to_new), so a
// schedule can lay out its arrays in the new order and results map back to the user's
// particle numbering. Colours themselves are not changed.
#pragma once

#include <vector>

#include <tessera/coloring/colouring.hpp>
#include <tessera/coloring/constraint_graph.hpp>

namespace tessera {

/// Reverse Cuthill–McKee order of the particles: new_to_old[n] is the user's index of new
/// particle n. Each connected component starts from a particle of least constraint degree
/// (first by index); neighbours are visited by increasing constraint degree, then index; the
/// whole sequence is reversed. Static particles (and movable particles no constraint touches)
/// come last, in their original order. Deterministic; linear in Σ_p deg(p) × arity plus the
/// per-particle neighbour sorts.
std::vector<ParticleIndex> reverse_cuthill_mckee_order(const ConstraintGraph& graph);

/// A copy of `colouring` with the same colours, in which particles are renumbered by reverse
/// Cuthill–McKee and each colour lists its constraints by increasing smallest renumbered movable
/// particle (ties keep the previous order). A colouring that already renumbers particles (metis,
/// blocks) comes back unchanged: its strategy ordered its colours for its own numbering (parts,
/// then crossing constraints), which sorting would undo.
Colouring improve_locality(const ConstraintGraph& graph, const Colouring& colouring);

/// Mean over colours and over windows of `window` consecutive constraints of a colour of the
/// spread (largest − smallest) of the renumbered movable particle ids they touch: the smaller,
/// the more compact each batch's gathers. Uses the colouring's renumbering if any, else the
/// user's numbering. 0 when no colour has a full window.
double mean_gather_spread(const ConstraintGraph& graph, const Colouring& colouring,
                          std::size_t window = 16);

}  // namespace tessera
