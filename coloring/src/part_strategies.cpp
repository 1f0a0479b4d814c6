// The part strategies, metis and blocks: partition the movable particles into parts, colour
// the constraints that cross parts, then each part's interior constraints in parallel with
// the same palette, and renumber particles part by part. They differ only in the partition:
// METIS k-way on the particle graph (metis), or contiguous runs of the particles' own
// numbering (blocks: no graph partitioner, for meshes numbered with locality, such as the
// generators' grids and most meshers' output; a scrambled numbering gives parts that
// cross everywhere, and a colouring that is still valid but mostly crossing constraints).
//
// Why it is race-free: a part's interior constraints touch only that part's particles, so the
// per-particle colour sets written by one part's worker are never read or written by another;
// the crossing constraints are coloured before, sequentially, and only read afterwards. Each
// part colours first-fit in the global stencil order restricted to the part, so its colours
// depend on the part alone (and on the fixed crossing colours). Hence the colouring is a
// function of (graph, seed, part size), independent of the thread count.
//
// Crossing first: coloured last, first-fit on the crossing constraints had to avoid whatever
// both neighbouring parts had chosen and added colours (25 instead of 18-20 on the cloth with
// bending). Coloured first they see an empty palette, and the parts, which have more freedom,
// fit around them.
//
// Layout: new particle ids run part by part (movable particles in their original order within
// a part, static particles last), and each colour lists its interior constraints part by part,
// then its crossing constraints, so a worker's contiguous slice of a colour gathers from a
// compact range of the renumbered particle arrays.
#include <algorithm>
#include <numeric>

#include <tbb/parallel_for.h>

#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/particle_partition.hpp>
#include <tessera/core/huge_pages.hpp>

#include "colour_masks.hpp"

namespace tessera {
namespace {

/// How a part strategy splits the movable particles into `parts` parts.
using Partitioner = ParticlePartition (*)(const ConstraintGraph& graph, std::size_t parts,
                                         std::uint64_t seed);

class PartStrategy final : public ColouringStrategy {
 public:
  PartStrategy(std::string_view name, std::string_view description, Partitioner partitioner)
      : name_(name), description_(description), partitioner_(partitioner) {}
  std::string_view name() const override { return name_; }
  std::string_view description() const override { return description_; }
  bool makes_parts() const override { return true; }

  Colouring colour(const ConstraintGraph& graph, const ColouringOptions& options) const override {
    const std::size_t count = graph.constraint_count();
    const ParticlePartition partition = partitioner_(
        graph, part_count_for(graph.movable_particle_count(), options.particles_per_part),
        options.seed);
    const std::size_t parts = partition.part_count;

    // Part of each constraint: its particles' common part, or `parts` (crossing, or touching
    // no movable particle).
    std::vector<std::uint32_t> part_of_constraint = constraint_parts(graph, partition);

    // Constraints grouped by part (crossing last), each group in stencil order (linear, and on
    // regular meshes it packs like the periodic optimum; smallest-last cost seconds here and
    // gave 20 colours instead of 18 on the cloth with bending).
    const detail::LargeBuffer<ConstraintIndex> order = detail::stencil_order(graph);
    std::vector<std::uint32_t> group_start(parts + 2, 0);
    for (std::uint32_t part : part_of_constraint) ++group_start[part + 1];
    std::partial_sum(group_start.begin(), group_start.end(), group_start.begin());
    std::vector<ConstraintIndex> grouped(count);
    {
      std::vector<std::uint32_t> cursor(group_start.begin(), group_start.end() - 1);
      for (ConstraintIndex c : order) grouped[cursor[part_of_constraint[c]]++] = c;
    }

    std::vector<Colour> colours = make_large_vector<Colour>(count, 0);
    detail::ParticleColourMasks masks(graph.particle_count(),
                                      std::max<std::size_t>(graph.colour_lower_bound(), 64));
    // Crossing constraints first, sequentially: they are the constrained ones (their particles
    // see several parts), and colouring them last, against whatever the parts left, is what
    // used to add colours. The parts then fill in around them.
    const std::span<const ConstraintIndex> crossing_members(grouped.data() + group_start[parts],
                                                            grouped.data() + group_start[parts + 1]);
    detail::first_fit_in_order(graph, crossing_members, masks, colours);
    // Per part, in parallel. A part's interior constraints touch only its own particles, so
    // each worker reads and writes only its part's colour sets (the crossing constraints'
    // colours there are already fixed). The sets cannot grow while workers use them, so a part
    // that would need more colours than their capacity undoes its own colours and stops.
    std::vector<std::uint8_t> overflow(parts, 0);
    tbb::parallel_for(std::size_t(0), parts, [&](std::size_t part) {
      const std::span<const ConstraintIndex> members(grouped.data() + group_start[part],
                                                     grouped.data() + group_start[part + 1]);
      for (std::size_t i = 0; i < members.size(); ++i) {
        const auto particles = graph.particles_of(members[i]);
        const Colour k = masks.first_free(particles);
        if (k >= masks.capacity()) {
          for (std::size_t j = 0; j < i; ++j) masks.release(graph.particles_of(members[j]), colours[members[j]]);
          overflow[part] = 1;
          return;
        }
        masks.take(particles, k);
        colours[members[i]] = k;
      }
    });
    // Parts that ran out of capacity were undone; redo them after the sets grow (sequential
    // first-fit grows as needed and makes the same choices).
    for (std::size_t part = 0; part < parts; ++part) {
      if (!overflow[part]) continue;
      const std::span<const ConstraintIndex> members(grouped.data() + group_start[part],
                                                     grouped.data() + group_start[part + 1]);
      detail::first_fit_in_order(graph, members, masks, colours);
    }
    // Schedule order: by part, then by id (parts listed in their new particle order).
    std::vector<ConstraintIndex> schedule(count);
    {
      std::vector<std::uint32_t> cursor(group_start.begin(), group_start.end() - 1);
      for (std::size_t c = 0; c < count; ++c)
        schedule[cursor[part_of_constraint[c]]++] = static_cast<ConstraintIndex>(c);
    }
    Colouring colouring = Colouring::from_colours(std::move(colours), schedule);

    // Particles part by part, static ones last.
    std::vector<std::uint32_t> particle_start(parts + 2, 0);
    for (std::uint32_t part : partition.part_of_particle)
      ++particle_start[(part == ParticlePartition::kNoPart ? parts : part) + 1];
    std::partial_sum(particle_start.begin(), particle_start.end(), particle_start.begin());
    std::vector<ParticleIndex> new_to_old(graph.particle_count());
    for (std::size_t p = 0; p < graph.particle_count(); ++p) {
      const std::uint32_t part = partition.part_of_particle[p];
      new_to_old[particle_start[part == ParticlePartition::kNoPart ? parts : part]++] =
          static_cast<ParticleIndex>(p);
    }
    colouring.set_particle_order(std::move(new_to_old));
    colouring.set_parts(std::move(part_of_constraint), parts);
    return colouring;
  }

 private:
  std::string_view name_, description_;
  Partitioner partitioner_;
};

}  // namespace

std::shared_ptr<const ColouringStrategy> make_metis_strategy() {
  return std::make_shared<PartStrategy>(
      "metis",
      "METIS parts of 65,536 particles (measured), crossing constraints coloured first, then "
      "the parts in parallel; particles renumbered by part",
      &partition_particles);
}

std::shared_ptr<const ColouringStrategy> make_blocks_strategy() {
  return std::make_shared<PartStrategy>(
      "blocks",
      "parts of 65,536 consecutively numbered particles (no partitioner: for meshes numbered "
      "with locality), then as metis",
      [](const ConstraintGraph& graph, std::size_t parts, std::uint64_t) {
        return partition_particles_in_blocks(graph, parts);
      });
}

}  // namespace tessera
