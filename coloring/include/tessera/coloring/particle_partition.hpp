// Partitioning the movable particles into parts of about a core's cache worth (METIS k-way on
// the particle graph: particles adjacent when a constraint joins them). Used by the metis
// strategy and by the locality reordering.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <tessera/coloring/constraint_graph.hpp>

namespace tessera {

struct ParticlePartition {
  /// Marks static particles, which belong to no part.
  static constexpr std::uint32_t kNoPart = ~std::uint32_t(0);
  std::size_t part_count = 0;
  /// Part of each particle (kNoPart for static particles).
  std::vector<std::uint32_t> part_of_particle;
};

/// Movable particles per part so that a part's particle state and its constraints' data fit
/// in `cache_bytes` (0: this machine's L2 size per core, 1 MiB if unknown). Estimates each
/// particle's share as 8 Reals of state (position, prediction, inverse mass, padding) plus
/// 8 bytes per incidence (an index and a per-constraint parameter), so it is a sizing rule of
/// thumb, not a measurement; see bench/coloring_benchmarks.cpp for the sweep over it.
std::size_t cache_sized_particles_per_part(const ConstraintGraph& graph, std::size_t cache_bytes = 0);

/// Splits the movable particles into `part_count` parts with METIS_PartGraphKway (seeded with
/// `seed`, so repeatable). Handles what METIS 5.1 does not: part_count 0 or 1, graphs with
/// fewer movable particles than parts, and graphs without edges, by contiguous blocks.
ParticlePartition partition_particles(const ConstraintGraph& graph, std::size_t part_count,
                                      std::uint64_t seed);

}  // namespace tessera
