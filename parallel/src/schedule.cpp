// Building the colour-major layout (see schedule.hpp for the picture), in four steps:
//
//   place_by_colour      per family, the model's constraint each scheduled slot takes
//                        (kPadding for the gaps that align each colour to kMaxLanes), or its
//                        place in the Jacobi set's list; the phases' blocks (place_by_part
//                        for SweepOrder::part_major: each part's colours first, one block per
//                        colour and family, then the crossing constraints' phases; the parts
//                        the colouring's, or runs of the particle order when it has none)
//   reorder_batch        every batch gathered through its list (batch_reorder.hpp)
//   build_jacobi_set     the Jacobi set and its incidences (jacobi_set.cpp)
//   build_stages         the mode's stage list (stage.hpp)
//
// Mode sequential lays out greedy groups the same way (no Jacobi set) and sweeps every block
// in one sequential stage; in input order it skips the first three steps: the model's batches
// as they are, one block per family.
#include <tessera/parallel/schedule.hpp>

#include <algorithm>
#include <limits>
#include <string>

#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/particle_partition.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/simd.hpp>
#include <tessera/parallel/threads.hpp>

#include <tessera/core/batch_reorder.hpp>
#include "jacobi_set.hpp"

namespace tessera {

namespace {

/// A scheduled slot that holds no constraint (the gap that aligns a colour).
constexpr std::uint32_t kPadding = std::numeric_limits<std::uint32_t>::max();
/// Slots are 32-bit, with room to spare.
constexpr std::size_t kMostConstraintsPerFamily = std::size_t(1) << 30;

using detail::round_up;

ScheduleOptions checked(ScheduleOptions options) {
  if (options.block_size == 0)
    throw InvalidInput("schedule: block size must be at least 1 constraint");
  options.block_size = round_up(options.block_size, kMaxLanes);
  options.threads = worker_threads(options.threads);
  const bool has_colour_phases =
      options.mode == SolverMode::gs || options.mode == SolverMode::hybrid;
  if (options.sweep_order == SweepOrder::automatic && !has_colour_phases)
    options.sweep_order = SweepOrder::colour_major;
  if (options.sweep_order == SweepOrder::part_major && !has_colour_phases)
    throw InvalidInput("schedule: sweep order part-major needs mode gs or hybrid (mode " +
                       std::string(solver_mode_name(options.mode)) + " has no colour phases)");
  // Checked here, before mode sequential's input order returns early.
  if (options.particles_per_part != 0 && !has_colour_phases)
    throw InvalidInput("schedule: particles per part sizes the runs of a part-major sweep, "
                       "which mode " + std::string(solver_mode_name(options.mode)) +
                       " does not run (modes gs and hybrid do)");
  return options;
}

/// A colouring's parts run at the same time, so its claim that a part's interior constraints
/// share no movable particle with another part's is checked, not trusted: a wrong claim would
/// be a race.
void check_claimed_parts(const ConstraintGraph& graph, std::span<const std::uint32_t> part_of,
                         std::size_t parts) {
  constexpr std::uint32_t kNoOwner = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> owner(graph.particle_count(), kNoOwner);
  for (ConstraintIndex c = 0; c < graph.constraint_count(); ++c) {
    const std::uint32_t part = part_of[c];
    if (part == parts) continue;
    for (const ParticleIndex p : graph.particles_of(c)) {
      if (owner[p] == kNoOwner) owner[p] = part;
      else if (owner[p] != part)
        throw InvalidInput("schedule: the colouring puts constraint " + std::to_string(c) +
                           " in part " + std::to_string(part) + ", but its particle " +
                           std::to_string(p) + " is in part " + std::to_string(owner[p]) +
                           " (a part's constraints may share movable particles with no other "
                           "part's)");
    }
  }
}

}  // namespace

namespace detail {

void split_into_blocks(ConstraintFamily family, std::size_t begin, std::size_t end,
                       const ScheduleOptions& options, std::vector<ScheduleBlock>& blocks) {
  const std::size_t per_thread =
      (end - begin + kBlocksPerThread * options.threads - 1) / (kBlocksPerThread * options.threads);
  const std::size_t block_size =
      std::clamp(round_up(per_thread, kMaxLanes), std::min(kSmallestSplitBlock, options.block_size),
                 options.block_size);
  for (std::size_t b = begin; b < end; b += block_size)
    blocks.push_back({family, std::uint32_t(b), std::uint32_t(std::min(end, b + block_size))});
}

}  // namespace detail

Schedule::Schedule(const Model& model, const Colouring* colouring, const ScheduleOptions& options)
    : options_(checked(options)) {
  const auto sizes = model.constraints.sizes();
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f) {
    family_first_[f + 1] = family_first_[f] + ConstraintIndex(sizes[f]);
    remap_[f].resize(sizes[f]);
  }
  // Mode sequential sweeps the reference library's groups (solver_mode.hpp): greedy colours,
  // laid out like any colouring, swept by one sequential stage; or the input order as is.
  Colouring groups;
  if (options_.mode == SolverMode::sequential) {
    if (options_.sequential_order == SequentialOrder::input) {
      lay_out_in_input_order(model);
      build_stages();
      return;
    }
    groups = make_greedy_strategy()->colour(constraint_graph(model), {});
    colouring = &groups;
  }
  if (colouring == nullptr)
    throw InvalidInput("schedule: mode " + std::string(solver_mode_name(options_.mode)) +
                       " needs a colouring");
  if (colouring->constraint_count() != constraint_count())
    throw InvalidInput("schedule: the colouring colours " +
                       std::to_string(colouring->constraint_count()) +
                       " constraints, the model has " + std::to_string(constraint_count()));
  const std::size_t particle_count = model.particles.size();
  take_particle_order(*colouring, particle_count);

  SourceLists& coloured_source = coloured_source_;
  SourceLists& jacobi_source = jacobi_source_;
  if (options_.particles_per_part != 0 &&
      (options_.sweep_order == SweepOrder::colour_major || colouring->has_parts()))
    throw InvalidInput(
        "schedule: particles per part sizes the runs a part-major sweep makes of a colouring "
        "without parts; " +
        std::string(options_.sweep_order == SweepOrder::colour_major
                        ? "this sweep is colour-major"
                        : "this colouring has its own parts (its strategy's particles per part "
                          "sizes them)"));
  const std::size_t particles_per_run =
      options_.particles_per_part != 0 ? options_.particles_per_part : kDefaultParticlesPerRun;
  if (options_.sweep_order == SweepOrder::automatic) {
    // Counted as the constraint graph counts them (movable: inverse mass > 0), without
    // building the graph a colour-major sweep does not need.
    const auto& inverse_mass = model.particles.inverse_mass;
    const std::size_t parts =
        colouring->has_parts()
            ? colouring->part_count()
            : part_count_for(std::size_t(std::count_if(inverse_mass.begin(), inverse_mass.end(),
                                                       [](Real w) { return w > 0; })),
                             particles_per_run);
    options_.sweep_order =
        parts >= kPartMajorFromParts ? SweepOrder::part_major : SweepOrder::colour_major;
  }
  if (options_.sweep_order == SweepOrder::part_major && colouring->has_parts()) {
    const ConstraintGraph graph = constraint_graph(model);
    check_claimed_parts(graph, colouring->part_of_constraint(), colouring->part_count());
    place_by_part(*colouring, colouring->part_of_constraint(), colouring->part_count(),
                  coloured_source, jacobi_source);
  } else if (options_.sweep_order == SweepOrder::part_major) {
    // Parts of the colouring's own particle order: any colouring keeps its guarantee within a
    // part, and the schedule lays the particles out in that order, so a run of it is a
    // contiguous range of the particle arrays (and, with the locality pass, a compact piece of
    // the mesh). Made here, so they need no check (constraint_parts puts a constraint in a
    // part only when all its movable particles are there).
    const ConstraintGraph graph = constraint_graph(model);
    const std::size_t parts = part_count_for(graph.movable_particle_count(), particles_per_run);
    const ParticlePartition partition =
        new_to_old_.empty() ? partition_particles_in_blocks(graph, parts)
                            : partition_particles_in_runs(graph, new_to_old_, parts);
    place_by_part(*colouring, constraint_parts(graph, partition), partition.part_count,
                  coloured_source, jacobi_source);
  } else {
    place_by_colour(*colouring, coloured_source, jacobi_source);
  }
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f)
    if (std::max(coloured_source[f].size(), jacobi_source[f].size()) >= kMostConstraintsPerFamily)
      throw InvalidInput("schedule: more than 2^30 constraints in one family");

  const auto renumber = [&](std::size_t, std::size_t, ParticleIndex p) {
    return scheduled_particle(p);
  };
  coloured_.for_each([&](ConstraintFamily family, auto& batch) {
    batch = detail::reorder_batch(model.constraints.of_type<std::decay_t<decltype(batch)>>(),
                                  coloured_source[std::size_t(family)], kPadding,
                                  particle_count, renumber);
  });

  // The Jacobi set (sorts each family's list, see build_jacobi_set), then its slots.
  jacobi_ = detail::build_jacobi_set(
      model.constraints, jacobi_source, particle_count,
      [&](ParticleIndex p) { return scheduled_particle(p); },
      [&](ParticleIndex scheduled) {
        return model.particles.inverse_mass[user_particle(scheduled)] > 0;
      },
      options_);
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f)
    for (std::size_t j = 0; j < jacobi_source[f].size(); ++j)
      remap_[f][jacobi_source[f][j]] = {true, std::uint32_t(j)};
  build_stages();
}

void Schedule::lay_out_in_input_order(const Model& model) {
  coloured_ = model.constraints;
  const auto sizes = model.constraints.sizes();
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f) {
    if (sizes[f] == 0) continue;
    const ScheduleBlock all{ConstraintFamily(f), 0, std::uint32_t(sizes[f])};
    ranges_[f].push_back(all);
    blocks_.push_back(all);
    for (std::size_t i = 0; i < sizes[f]; ++i) remap_[f][i] = {false, std::uint32_t(i)};
  }
}

void Schedule::take_particle_order(const Colouring& colouring, std::size_t particle_count) {
  if (!colouring.renumbers_particles()) return;
  if (colouring.particle_new_to_old().size() != particle_count)
    throw InvalidInput("schedule: the colouring renumbers " +
                       std::to_string(colouring.particle_new_to_old().size()) +
                       " particles, the model has " + std::to_string(particle_count));
  new_to_old_.assign(colouring.particle_new_to_old().begin(),
                     colouring.particle_new_to_old().end());
  old_to_new_.assign(colouring.particle_old_to_new().begin(),
                     colouring.particle_old_to_new().end());
}

namespace {

/// The family of global constraint c, given each family's first id.
std::size_t family_of(std::span<const ConstraintIndex> family_first, ConstraintIndex c) {
  std::size_t f = 0;
  while (c >= family_first[f + 1]) ++f;
  return f;
}

}  // namespace

void Schedule::split_by_family(std::span<const ConstraintIndex> constraints,
                               SourceLists& members) const {
  for (auto& m : members) m.clear();
  for (const ConstraintIndex c : constraints) {
    const std::size_t f = family_of(family_first_, c);
    members[f].push_back(c - family_first_[f]);
  }
}

void Schedule::append_group(const SourceLists& members, SourceLists& coloured) {
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f) {
    if (members[f].empty()) continue;
    auto& source = coloured[f];
    source.resize(round_up(source.size(), kMaxLanes), kPadding);
    const std::size_t begin = source.size();
    for (const std::uint32_t local : members[f]) {
      remap_[f][local] = {false, std::uint32_t(source.size())};
      source.push_back(local);
    }
    const ScheduleBlock range{ConstraintFamily(f), std::uint32_t(begin),
                              std::uint32_t(source.size())};
    ranges_[f].push_back(range);
    blocks_.push_back(range);
  }
}

void Schedule::append_phase(const SourceLists& members, std::size_t size, bool to_jacobi,
                            SourceLists& coloured, SourceLists& jacobi) {
  if (to_jacobi) {
    // Jacobi slots are known only once build_jacobi_set has sorted the set.
    for (std::size_t f = 0; f < kConstraintFamilyCount; ++f)
      jacobi[f].insert(jacobi[f].end(), members[f].begin(), members[f].end());
    return;
  }
  append_group(members, coloured);
  phase_offsets_.push_back(blocks_.size());
  phase_sizes_.push_back(size);
}

void Schedule::place_by_colour(const Colouring& colouring, SourceLists& coloured,
                               SourceLists& jacobi) {
  SourceLists members;
  phase_offsets_.push_back(0);
  for (Colour k = 0; k < colouring.colour_count(); ++k) {
    const auto colour = colouring.constraints_of(k);
    split_by_family(colour, members);
    append_phase(members, colour.size(), to_jacobi(colour.size()), coloured, jacobi);
  }
}

// Part-major: every part's interior constraints colour after colour (one block per colour and
// family: the part is one worker's), then the crossing constraints as colour phases.
void Schedule::place_by_part(const Colouring& colouring, std::span<const std::uint32_t> part_of,
                             std::size_t parts, SourceLists& coloured, SourceLists& jacobi) {
  // Each part's members colour after colour, then the crossing ones (part `parts`): a stable
  // counting sort by part of the constraints in colour order (memory linear in the
  // constraints and parts, not their product: parts may be as small as one particle).
  std::vector<std::uint32_t> part_start(parts + 2, 0);
  for (ConstraintIndex c = 0; c < constraint_count(); ++c) ++part_start[part_of[c] + 1];
  for (std::size_t b = 0; b <= parts; ++b) part_start[b + 1] += part_start[b];
  std::vector<ConstraintIndex> by_part(constraint_count());
  {
    std::vector<std::uint32_t> cursor(part_start.begin(), part_start.end() - 1);
    for (Colour k = 0; k < colouring.colour_count(); ++k)
      for (const ConstraintIndex c : colouring.constraints_of(k)) by_part[cursor[part_of[c]]++] = c;
  }
  // For each colour's run of part b's members, in colour order: the run split by family into
  // `members`, then place(the run's size).
  SourceLists members;
  const auto for_each_colour_of = [&](std::size_t b, auto&& place) {
    for (std::uint32_t i = part_start[b]; i < part_start[b + 1];) {
      const Colour k = colouring.colour_of(by_part[i]);
      std::uint32_t end = i;
      while (end < part_start[b + 1] && colouring.colour_of(by_part[end]) == k) ++end;
      split_by_family({by_part.data() + i, by_part.data() + end}, members);
      place(end - i);
      i = end;
    }
  };
  part_offsets_.push_back(0);
  for (std::size_t part = 0; part < parts; ++part) {
    for_each_colour_of(part, [&](std::size_t) { append_group(members, coloured); });
    part_offsets_.push_back(blocks_.size());
  }
  phase_offsets_.push_back(blocks_.size());
  for_each_colour_of(parts, [&](std::size_t size) {
    append_phase(members, size, to_jacobi(size), coloured, jacobi);
  });
}

void Schedule::build_stages() {
  const auto has_velocity_pass = [&](std::span<const ScheduleBlock> blocks) {
    return std::any_of(blocks.begin(), blocks.end(), [](const ScheduleBlock& b) {
      return family_traits(b.family).velocity_pass;
    });
  };
  const auto whole = [](std::size_t blocks) {
    return std::pair{std::uint32_t(0), std::uint32_t(blocks)};
  };
  if (options_.mode == SolverMode::sequential) {
    const auto [first, last] = whole(blocks_.size());
    iteration_stages_.push_back({StageKind::sequential_sweep, StageSet::coloured, first, last});
    if (has_velocity_pass(blocks_))
      velocity_stages_.push_back({StageKind::velocity_pass, StageSet::coloured, first, last});
    return;
  }
  if (part_count() != 0) {
    const Stage parts{StageKind::part_sweep, StageSet::coloured, 0, std::uint32_t(part_count())};
    iteration_stages_.push_back(parts);
    if (has_velocity_pass({blocks_.data(), blocks_.data() + part_offsets_.back()}))
      velocity_stages_.push_back({StageKind::part_velocity_pass, StageSet::coloured, 0,
                                  parts.last_block});
  }
  for (std::size_t phase = 0; phase < phase_count(); ++phase) {
    const Stage stage{StageKind::coloured_phase, StageSet::coloured,
                      std::uint32_t(phase_offsets_[phase]),
                      std::uint32_t(phase_offsets_[phase + 1])};
    iteration_stages_.push_back(stage);
    if (has_velocity_pass(phase_blocks(phase)))
      velocity_stages_.push_back({StageKind::velocity_pass, StageSet::coloured,
                                  stage.first_block, stage.last_block});
  }
  if (jacobi_.constraint_count != 0) {
    const auto [first, last] = whole(jacobi_.blocks.size());
    iteration_stages_.push_back({StageKind::jacobi_projection, StageSet::jacobi, first, last});
    iteration_stages_.push_back({StageKind::jacobi_reduction, StageSet::jacobi, first, last});
    if (has_velocity_pass(jacobi_.blocks))
      velocity_stages_.push_back({StageKind::velocity_pass, StageSet::jacobi, first, last});
  }
}

ConstraintIndex Schedule::user_constraint(ConstraintFamily family, bool in_jacobi_set,
                                          std::uint32_t slot) const {
  const std::size_t f = std::size_t(family);
  const auto& source = in_jacobi_set ? jacobi_source_[f] : coloured_source_[f];
  const std::uint32_t local = source.empty() ? slot : source[slot];
  return family_first_[f] + local;
}

ConstraintLocation Schedule::locate(ConstraintIndex user_constraint) const {
  if (user_constraint >= constraint_count())
    throw InvalidInput("constraint " + std::to_string(user_constraint) +
                       " does not exist (the schedule has " +
                       std::to_string(constraint_count()) + ")");
  std::size_t f = 0;
  while (user_constraint >= family_first_[f + 1]) ++f;
  const ConstraintSlot slot = remap_[f][user_constraint - family_first_[f]];
  return {slot.in_jacobi_set, ConstraintFamily(f), slot.slot};
}

}  // namespace tessera
