// Partitioning the movable particles into parts of about a core's cache worth (METIS k-way on
// the particle graph: particles adjacent when a constraint joins them; or runs of a particle
// order), and the part each constraint then falls in. Used by the part strategies (metis,
// blocks) and by a part-major schedule of a colouring without parts (runs of its particle
// order).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
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

/// The default part size of the part strategies (metis and blocks), in movable particles (the
/// runs a part-major sweep makes of a colouring without parts have their own default,
/// kDefaultParticlesPerRun in parallel/solver_mode.hpp). Chosen for
/// metis by measurement (bench_coloring, coloring/metis/<mesh>/particles_per_part:<k>, 1024² cloth
/// with bending and a 2.2 M-constraint tet bar): parts of 1,024 / 4,096 / 16,384 / 65,536 particles
/// gave 23 / 24 / 23 / 23 colours on the cloth and 48 / 47 / 47 / 46 on the tet bar, a mean
/// particle-id spread per 16 constraints of a colour of 38,143 / 23,785 / 9,836 / 4,851 and 24,839
/// / 14,725 / 7,820 / 3,340, and colouring times of 2.1 / 1.3 / 1.1 / 1.2 s and 0.56 / 0.35 / 0.32
/// / 0.30 s. Larger parts are better on every measure; 65,536 still gives 16 parts per million
/// particles to colour in parallel. Fixed, not machine-dependent, so the colouring is the same on
/// every machine. Blocks' sweeps on the 1024² cloth measured best at it too (docs/performance.md,
/// "Parts without METIS").
inline constexpr std::size_t kDefaultParticlesPerPart = 65536;

/// How many parts hold `movable` particles at most `particles_per_part` each (0:
/// kDefaultParticlesPerPart): ⌈movable / particles_per_part⌉, 0 for no movable particle.
inline std::size_t part_count_for(std::size_t movable, std::size_t particles_per_part) {
  const std::size_t per_part =
      particles_per_part != 0 ? particles_per_part : kDefaultParticlesPerPart;
  return movable / per_part + (movable % per_part != 0);
}

/// Splits the movable particles into `part_count` parts with METIS_PartGraphKway (seeded with
/// `seed`, so repeatable). Handles what METIS 5.1 does not: part_count 0 or 1, graphs with
/// fewer movable particles than parts, and graphs without edges, by contiguous blocks.
ParticlePartition partition_particles(const ConstraintGraph& graph, std::size_t part_count,
                                      std::uint64_t seed);

/// Splits the movable particles, in index order, into `part_count` runs of consecutive
/// indices (sizes differing by at most one; fewer parts when there are fewer movable
/// particles, one when part_count is 0; none without movable particles): linear, no
/// partitioner. The parts are as compact as the numbering is.
ParticlePartition partition_particles_in_blocks(const ConstraintGraph& graph,
                                                std::size_t part_count);

/// The same, with the movable particles taken in the order `order` lists them (a permutation
/// of the particles: order[n] is the particle at position n, as Colouring::particle_new_to_old;
/// static particles anywhere in it). Throws tessera::InvalidInput when `order` names another
/// number of particles, or a particle past the count or twice.
ParticlePartition partition_particles_in_runs(const ConstraintGraph& graph,
                                              std::span<const ParticleIndex> order,
                                              std::size_t part_count);

/// The part of each constraint: the part all its movable particles are in, or
/// partition.part_count when they are in several parts or it has none (a crossing constraint,
/// for the colour phases of a part-major sweep). Static particles belong to no part and do not
/// make a constraint crossing: a sweep only reads them. Parallel; the same for any thread
/// count. Throws tessera::InvalidInput when the partition is of another number of particles,
/// or leaves a movable particle without a part or in one past its count.
std::vector<std::uint32_t> constraint_parts(const ConstraintGraph& graph,
                                            const ParticlePartition& partition);

}  // namespace tessera
