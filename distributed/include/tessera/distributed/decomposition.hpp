// Domain decomposition for running one solve on many ranks (processes, later MPI): who owns
// which particle and constraint, which particles each rank holds a copy of, and which
// positions go where after each colour, so that the ranks together compute bitwise what one
// process computes with the same colouring. Nothing here sends a message; this is the plan
// the exchange carries out.
//
//   particles ──METIS k-way──► owner rank         (partition_particles: same answer everywhere)
//   constraint ──► owner of its smallest movable particle
//   rank r holds: its owned particles + ghosts (read or written by its constraints, static
//                 particles included)
//
//         rank 0            │           rank 1
//     ○───○───○───●(ghost)  │  ○(ghost)───●───●───●       ○ owned by 0, ● owned by 1
//                constraint c (owned by 0) writes ● ─────► sent to 1 after c's colour
//
// Why this is exact. A colour's constraints share no movable particle, so in colour k a
// movable particle p is written by at most one constraint c, and read by no other. If c's
// owner sends p's new position to every other rank holding p at the end of colour k, then
// at the start of every colour each rank's copy of every particle it holds is the value one
// process would have there. Each constraint is projected by exactly one rank, on the same
// values and by the same code as in one process, so the positions are bitwise the same for
// any rank count. Static particles (inverse mass 0) never change and are never sent.
//
// The sends are per colour and per neighbour, each list in ascending global particle id;
// receives mirror them (rank s receives from r in colour k exactly what r sends s).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <tessera/coloring/colouring.hpp>
#include <tessera/core/indices.hpp>
#include <tessera/core/model.hpp>

namespace tessera {

using Rank = std::uint32_t;

/// The particles one rank sends to, or receives from, one other rank (global ids, ascending).
struct RankExchange {
  Rank rank = 0;
  std::vector<ParticleIndex> particles;
};

/// What one rank holds and does.
struct RankDomain {
  /// Particles this rank owns (its answer for them is the answer), global ids ascending.
  std::vector<ParticleIndex> owned;
  /// Particles its constraints read or write that other ranks own, global ids ascending.
  std::vector<ParticleIndex> ghosts;
  /// Constraints it projects, global ids ascending.
  std::vector<ConstraintIndex> constraints;
  /// sends[k] / receives[k]: the exchanges after colour k, by ascending rank; empty lists
  /// are left out.
  std::vector<std::vector<RankExchange>> sends;
  std::vector<std::vector<RankExchange>> receives;
  /// The ranks it exchanges with in any colour, ascending.
  std::vector<Rank> neighbours;
};

struct Decomposition {
  std::size_t rank_count = 0;
  /// Owner of every particle and constraint (global ids).
  std::vector<Rank> owner_of_particle;
  std::vector<Rank> owner_of_constraint;
  /// One per rank.
  std::vector<RankDomain> ranks;
};

/// Splits the model's particles into `rank_count` ranks (METIS k-way on the particle graph,
/// constraint_graph(model), seeded with `seed`: the same decomposition on every rank and every run),
/// each constraint owned by the owner of its smallest movable particle (of its smallest
/// particle when none is movable), each static particle by the owner of the first constraint
/// that reads it (rank 0 when none does), and plans the exchanges after each colour of
/// `colouring`. Throws InvalidInput when rank_count is 0, when the colouring is of another
/// graph (a different constraint count), or when a colour holds two constraints that share a
/// movable particle (the plan's exactness rests on it), naming the colour, the constraints and
/// the particle.
Decomposition decompose(const Model& model, const Colouring& colouring, std::size_t rank_count,
                        std::uint64_t seed = 1);

}  // namespace tessera
