// METIS k-way partitioning of the particle graph, the partitioner-free split into runs of a
// particle order (partition_particles_in_blocks, _in_runs), and each constraint's part.
//
// The particle graph is built in METIS's CSR form (xadj/adjncy over the movable particles,
// renumbered densely): two passes over particles, each collecting the neighbours through the
// particle's constraints, sorting and deduplicating them in a per-thread scratch vector. The
// first pass counts, the second fills, so the arrays do not depend on the thread count.
// METIS itself runs sequentially with a fixed seed, so the partition is repeatable.
//
// Debian's METIS 5.1.0 divides by zero for one part and misbehaves on tiny inputs, so
// those cases never reach it: they become contiguous blocks of the movable particles.
#include <tessera/coloring/particle_partition.hpp>

#include <algorithm>
#include <limits>
#include <new>
#include <string>

#include <metis.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <tessera/core/error.hpp>

namespace tessera {
namespace {

/// The movable particles, by increasing index.
std::vector<ParticleIndex> movable_particles(const ConstraintGraph& graph) {
  std::vector<ParticleIndex> movable;
  movable.reserve(graph.movable_particle_count());
  for (std::size_t p = 0; p < graph.particle_count(); ++p)
    if (graph.is_movable(static_cast<ParticleIndex>(p)))
      movable.push_back(static_cast<ParticleIndex>(p));
  return movable;
}

void contiguous_blocks(ParticlePartition& partition, const std::vector<ParticleIndex>& movable,
                       std::size_t part_count) {
  partition.part_count = part_count;
  for (std::size_t i = 0; i < movable.size(); ++i)
    partition.part_of_particle[movable[i]] = static_cast<std::uint32_t>(i * part_count / movable.size());
}

/// Runs of the movable particles in the order `movable` lists them.
ParticlePartition runs_of(const ConstraintGraph& graph, const std::vector<ParticleIndex>& movable,
                          std::size_t part_count) {
  ParticlePartition partition;
  partition.part_of_particle.assign(graph.particle_count(), ParticlePartition::kNoPart);
  if (movable.empty()) return partition;
  contiguous_blocks(partition, movable, std::clamp<std::size_t>(part_count, 1, movable.size()));
  return partition;
}

}  // namespace

ParticlePartition partition_particles(const ConstraintGraph& graph, std::size_t part_count,
                                      std::uint64_t seed) {
  ParticlePartition partition;
  partition.part_of_particle.assign(graph.particle_count(), ParticlePartition::kNoPart);
  const std::vector<ParticleIndex> movable = movable_particles(graph);
  std::vector<idx_t> local(graph.particle_count(), -1);
  for (std::size_t i = 0; i < movable.size(); ++i) local[movable[i]] = static_cast<idx_t>(i);
  if (movable.empty()) return partition;
  part_count = std::clamp<std::size_t>(part_count, 1, movable.size());
  // METIS needs a few vertices per part to do anything useful (and 5.1 fails on one part).
  if (part_count == 1 || movable.size() < 8 * part_count) {
    contiguous_blocks(partition, movable, std::max<std::size_t>(1, std::min(part_count, movable.size() / 8)));
    return partition;
  }

  const std::size_t n = movable.size();
  std::vector<idx_t> xadj(n + 1, 0);
  tbb::enumerable_thread_specific<std::vector<idx_t>> scratch;
  auto neighbours = [&](std::size_t i, std::vector<idx_t>& out) {
    out.clear();
    const ParticleIndex p = movable[i];
    for (ConstraintIndex c : graph.constraints_of(p))
      for (ParticleIndex q : graph.particles_of(c))
        if (q != p) out.push_back(local[q]);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& range) {
    std::vector<idx_t>& out = scratch.local();
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      neighbours(i, out);
      xadj[i + 1] = static_cast<idx_t>(out.size());
    }
  });
  std::size_t edges = 0;
  for (std::size_t i = 0; i < n; ++i) {
    edges += static_cast<std::size_t>(xadj[i + 1]);
    if (edges > static_cast<std::size_t>(std::numeric_limits<idx_t>::max()))
      throw InvalidInput("partition_particles: the particle graph has more than " +
                         std::to_string(std::numeric_limits<idx_t>::max()) +
                         " adjacency entries, beyond this METIS build's 32-bit indices");
    xadj[i + 1] += xadj[i];
  }
  if (edges == 0) {
    contiguous_blocks(partition, movable, part_count);
    return partition;
  }
  std::vector<idx_t> adjncy(edges);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const auto& range) {
    std::vector<idx_t>& out = scratch.local();
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      neighbours(i, out);
      std::copy(out.begin(), out.end(), adjncy.begin() + xadj[i]);
    }
  });

  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_SEED] = static_cast<idx_t>(seed & 0x7FFFFFFF);
  options[METIS_OPTION_NUMBERING] = 0;
  idx_t vertex_count = static_cast<idx_t>(n), constraints_per_vertex = 1;
  idx_t parts = static_cast<idx_t>(part_count), edge_cut = 0;
  std::vector<idx_t> part(n, 0);
  const int status = METIS_PartGraphKway(&vertex_count, &constraints_per_vertex, xadj.data(),
                                         adjncy.data(), nullptr, nullptr, nullptr, &parts, nullptr,
                                         nullptr, options, &edge_cut, part.data());
  if (status == METIS_ERROR_MEMORY) throw std::bad_alloc();
  if (status != METIS_OK)
    throw InvalidInput("partition_particles: METIS_PartGraphKway failed (status " +
                       std::to_string(status) + ") for " + std::to_string(n) + " particles in " +
                       std::to_string(part_count) + " parts");
  partition.part_count = part_count;
  for (std::size_t i = 0; i < n; ++i)
    partition.part_of_particle[movable[i]] = static_cast<std::uint32_t>(part[i]);
  return partition;
}

ParticlePartition partition_particles_in_blocks(const ConstraintGraph& graph,
                                                std::size_t part_count) {
  return runs_of(graph, movable_particles(graph), part_count);
}

ParticlePartition partition_particles_in_runs(const ConstraintGraph& graph,
                                              std::span<const ParticleIndex> order,
                                              std::size_t part_count) {
  const std::size_t n = graph.particle_count();
  if (order.size() != n)
    throw InvalidInput("partition_particles_in_runs: the order lists " +
                       std::to_string(order.size()) + " particles, the graph has " +
                       std::to_string(n));
  std::vector<std::uint8_t> seen(n, 0);
  std::vector<ParticleIndex> movable;
  movable.reserve(graph.movable_particle_count());
  for (std::size_t i = 0; i < n; ++i) {
    const ParticleIndex p = order[i];
    if (p >= n || seen[p])
      throw InvalidInput("partition_particles_in_runs: position " + std::to_string(i) +
                         " of the order names particle " + std::to_string(p) +
                         (p >= n ? ", past the " + std::to_string(n) + " particles"
                                 : ", listed before"));
    seen[p] = 1;
    if (graph.is_movable(p)) movable.push_back(p);
  }
  return runs_of(graph, movable, part_count);
}

std::vector<std::uint32_t> constraint_parts(const ConstraintGraph& graph,
                                            const ParticlePartition& partition) {
  const auto& part_of = partition.part_of_particle;
  if (part_of.size() != graph.particle_count())
    throw InvalidInput("constraint_parts: the partition is of " + std::to_string(part_of.size()) +
                       " particles, the graph has " + std::to_string(graph.particle_count()));
  for (std::size_t p = 0; p < part_of.size(); ++p)
    if (graph.is_movable(ParticleIndex(p)) && part_of[p] >= partition.part_count)
      throw InvalidInput("constraint_parts: movable particle " + std::to_string(p) +
                         (part_of[p] == ParticlePartition::kNoPart
                              ? std::string(" is in no part")
                              : " is in part " + std::to_string(part_of[p]) + " of " +
                                    std::to_string(partition.part_count)));
  const std::size_t count = graph.constraint_count();
  const std::uint32_t crossing = static_cast<std::uint32_t>(partition.part_count);
  std::vector<std::uint32_t> part_of_constraint(count, crossing);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 4096), [&](const auto& range) {
    for (std::size_t c = range.begin(); c != range.end(); ++c) {
      const auto particles = graph.particles_of(static_cast<ConstraintIndex>(c));
      if (particles.empty()) continue;
      const std::uint32_t first = part_of[particles[0]];
      if (std::all_of(particles.begin(), particles.end(),
                      [&](ParticleIndex p) { return part_of[p] == first; }))
        part_of_constraint[c] = first;
    }
  });
  return part_of_constraint;
}

}  // namespace tessera
