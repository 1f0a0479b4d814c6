// The schedule's layout: every constraint is placed exactly once, each phase's blocks cover
// exactly its colour (so a sweep projects each constraint once per iteration), no two
// constraints of one phase share a movable particle, blocks start on kMaxLanes boundaries,
// and the particle and constraint maps lead back to the user's numbering.
#include <gtest/gtest.h>

#include <array>
#include <algorithm>
#include <set>
#include <vector>

#include <tessera/core/error.hpp>
#include <tessera/coloring/colouring_statistics.hpp>
#include <tessera/coloring/run_colouring.hpp>
#include <tessera/parallel/schedule.hpp>

#include "scenes.hpp"

namespace tessera {
namespace schedule_tests {

using test::BarMaterial;
using test::ClothBending;

/// The particles of slot `slot` of a family's batch, as the schedule stores them.
std::vector<ParticleIndex> particles_of(const ConstraintSets& sets, ConstraintFamily family,
                                        std::size_t slot) {
  std::vector<ParticleIndex> result;
  sets.for_each([&](ConstraintFamily f, const auto& batch) {
    if (f != family) return;
    if constexpr (requires { batch.particles; }) {
      for (const auto& column : batch.particles.particle) result.push_back(column[slot]);
    } else {
      for (auto e = batch.offsets[slot]; e < batch.offsets[slot + 1]; ++e)
        result.push_back(batch.particle[e]);
    }
  });
  return result;
}

/// The user's particles of the user's constraint `id` (global id) of `model`.
std::vector<ParticleIndex> user_particles(const Model& model, ConstraintIndex id) {
  std::size_t first = 0;
  std::vector<ParticleIndex> result;
  model.constraints.for_each([&](ConstraintFamily, const auto& batch) {
    const std::size_t n = batch.size();
    if (id >= first && id < first + n) {
      const std::size_t c = id - first;
      if constexpr (requires { batch.particles; }) {
        for (const auto& column : batch.particles.particle) result.push_back(column[c]);
      } else {
        for (auto e = batch.offsets[c]; e < batch.offsets[c + 1]; ++e)
          result.push_back(batch.particle[e]);
      }
    }
    first += n;
  });
  return result;
}

struct Case {
  const char* name;
  Model model;
};

std::vector<Case> test_models() {
  std::vector<Case> cases;
  cases.push_back({"cloth", test::cloth_model(17, 13, ClothBending::dihedral)});
  cases.push_back({"cloth_isometric", test::cloth_model(9, 9, ClothBending::isometric)});
  cases.push_back({"bar_fem", test::tet_bar_model(3, 2, 6, BarMaterial::fem_tetra)});
  cases.push_back({"bar_volume", test::tet_bar_model(2, 2, 5, BarMaterial::volume_and_distance)});
  return cases;
}

void check_layout(const Model& model, const Colouring& colouring, const Schedule& schedule) {
  const std::size_t total = model.constraints.size();
  ASSERT_EQ(schedule.constraint_count(), total);
  // Every user constraint lands on a distinct slot holding its particles (renumbered).
  std::set<std::tuple<bool, int, std::uint32_t>> used;
  for (ConstraintIndex id = 0; id < total; ++id) {
    const ConstraintLocation where = schedule.locate(id);
    ASSERT_TRUE(used.insert({where.in_jacobi_set, int(where.family), where.slot}).second);
    std::vector<ParticleIndex> expected = user_particles(model, id);
    for (ParticleIndex& p : expected) p = schedule.scheduled_particle(p);
    if (!where.in_jacobi_set) {
      EXPECT_EQ(particles_of(schedule.coloured(), where.family, where.slot), expected) << id;
    } else {
      const JacobiSet& jacobi = schedule.jacobi();
      EXPECT_EQ(particles_of(jacobi.constraints, where.family, where.slot), expected) << id;
      // Slot k's incidence (where the kernel stores its result) names the same particle.
      const std::size_t f = std::size_t(where.family);
      if (where.family != ConstraintFamily::shape_matching) {
        for (std::size_t k = 0; k < expected.size(); ++k)
          EXPECT_EQ(jacobi.incidence_particle[jacobi.incidence_base[f] +
                                              k * jacobi.incidence_stride[f] + where.slot],
                    expected[k])
              << id;
      }
    }
  }
  // The phases' blocks cover each coloured constraint exactly once; within a phase no
  // movable particle is shared; blocks are aligned, one per family (the solver cuts a phase
  // per thread, not block_size).
  std::vector<int> projected(total, 0);
  std::size_t coloured = 0;
  std::vector<std::vector<std::uint32_t>> slot_owner(kConstraintFamilyCount);
  for (ConstraintIndex id = 0; id < total; ++id) {
    const ConstraintLocation where = schedule.locate(id);
    if (where.in_jacobi_set) continue;
    auto& owner = slot_owner[std::size_t(where.family)];
    if (owner.size() <= where.slot) owner.resize(where.slot + 1, ~0u);
    owner[where.slot] = id;
    ++coloured;
  }
  std::size_t covered = 0;
  for (std::size_t phase = 0; phase < schedule.phase_count(); ++phase) {
    std::set<ParticleIndex> touched;
    std::set<Colour> colours;
    std::set<ConstraintFamily> families;
    for (const ScheduleBlock& block : schedule.phase_blocks(phase)) {
      EXPECT_EQ(block.begin % kMaxLanes, 0u);
      EXPECT_TRUE(families.insert(block.family).second)
          << "family " << int(block.family) << " twice in phase " << phase;
      for (std::uint32_t slot = block.begin; slot < block.end; ++slot) {
        const std::uint32_t id = slot_owner[std::size_t(block.family)].at(slot);
        ASSERT_NE(id, ~0u) << "a block covers a padding slot";
        ++projected[id];
        ++covered;
        colours.insert(colouring.colour_of(id));
        for (const ParticleIndex p : particles_of(schedule.coloured(), block.family, slot)) {
          if (model.particles.inverse_mass[schedule.user_particle(p)] == 0) continue;
          EXPECT_TRUE(touched.insert(p).second) << "particle " << p << " twice in phase " << phase;
        }
      }
    }
    EXPECT_EQ(colours.size(), 1u) << "phase " << phase << " mixes colours";
  }
  EXPECT_EQ(covered, coloured);
  for (ConstraintIndex id = 0; id < total; ++id)
    if (!schedule.locate(id).in_jacobi_set) {
      EXPECT_EQ(projected[id], 1) << id;
    }
  // The Jacobi set's blocks cover it once too.
  std::size_t jacobi_covered = 0;
  for (const ScheduleBlock& block : schedule.jacobi().blocks) {
    EXPECT_EQ(block.begin % kMaxLanes, 0u);
    jacobi_covered += block.end - block.begin;
  }
  EXPECT_EQ(jacobi_covered, schedule.jacobi().constraint_count);
  EXPECT_EQ(coloured + schedule.jacobi().constraint_count, total);
}

TEST(Schedule, GaussSeidelLayoutCoversEveryConstraintOnceForEveryStrategy) {
  for (const Case& c : test_models())
    for (const auto name : ColouringRegistry::with_builtin_strategies().names()) {
      SCOPED_TRACE(std::string(c.name) + " / " + std::string(name));
      const Colouring colouring = test::colour_model(c.model, std::string(name).c_str());
      const Schedule schedule(c.model, &colouring, {SolverMode::gs, 64, 0});
      EXPECT_EQ(schedule.phase_count(), colouring.colour_count());
      EXPECT_EQ(schedule.jacobi().constraint_count, 0u);
      check_layout(c.model, colouring, schedule);
    }
}

TEST(Schedule, JacobiBlocksShrinkSoThatEveryThreadGetsWork) {
  const Model model = test::tet_bar_model(6, 6, 24);
  const Colouring colouring = test::colour_model(model, "stencil");
  for (const std::size_t threads : {1, 2, 8, 64}) {
    SCOPED_TRACE(threads);
    const Schedule schedule(model, &colouring, {SolverMode::jacobi, 512, 0, threads});
    std::array<std::size_t, kConstraintFamilyCount> blocks{}, sizes{};
    for (const ScheduleBlock& block : schedule.jacobi().blocks) {
      EXPECT_EQ(block.begin % kMaxLanes, 0u);
      EXPECT_LE(block.end - block.begin, 512u);  // never above block_size
      ++blocks[std::size_t(block.family)];
      sizes[std::size_t(block.family)] += block.end - block.begin;
    }
    std::size_t families = 0;
    for (std::size_t f = 0; f < kConstraintFamilyCount; ++f) {
      if (sizes[f] == 0) continue;
      ++families;
      // At least two blocks per thread while blocks can shrink; the smallest blocks split
      // for threads are kSmallestSplitBlock wide (a smaller one costs a task more than its
      // projections).
      if (sizes[f] >= 4 * threads * kSmallestSplitBlock) {
        EXPECT_GE(blocks[f], 2 * threads) << "family " << f;
      } else {
        EXPECT_EQ(blocks[f], (sizes[f] + kSmallestSplitBlock - 1) / kSmallestSplitBlock)
            << "family " << f;
      }
    }
    EXPECT_GT(families, 0u);
    if (threads == 1) {
      EXPECT_TRUE(std::any_of(sizes.begin(), sizes.end(), [&](std::size_t size) {
        return size > 4 * 512;
      })) << "the bar should have a family big enough to be cut by block_size";
    }
  }
}

TEST(Schedule, APhaseIsOneBlockPerFamilyWhateverTheBlockSize) {
  const Model model = test::tet_bar_model(4, 4, 12);
  const Colouring colouring = test::colour_model(model, "stencil");
  const Schedule small(model, &colouring, {SolverMode::gs, 16, 0, 8});
  const Schedule large(model, &colouring, {SolverMode::gs, 4096, 0, 1});
  ASSERT_EQ(small.phase_count(), large.phase_count());
  for (std::size_t phase = 0; phase < small.phase_count(); ++phase) {
    const auto a = small.phase_blocks(phase), b = large.phase_blocks(phase);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t k = 0; k < a.size(); ++k) {
      EXPECT_EQ(a[k].family, b[k].family);
      EXPECT_EQ(a[k].begin, b[k].begin);
      EXPECT_EQ(a[k].end, b[k].end);
    }
  }
  check_layout(model, colouring, small);
}

TEST(Schedule, LocalityRenumberingMapsBackToTheUsersParticles) {
  const Model model = test::cloth_model(20, 20);
  ColouringOptions options;
  options.locality = true;
  const ConstraintGraph graph = constraint_graph(model);
  const ColouringRun run = run_colouring(
      ColouringRegistry::with_builtin_strategies().get("greedy"), graph, options);
  ASSERT_TRUE(run.colouring.renumbers_particles());
  const Schedule schedule(model, &run.colouring, {});
  ASSERT_FALSE(schedule.particle_new_to_old().empty());
  for (ParticleIndex p = 0; p < model.particles.size(); ++p)
    EXPECT_EQ(schedule.user_particle(schedule.scheduled_particle(p)), p);
  check_layout(model, run.colouring, schedule);
}

TEST(Schedule, JacobiSetGivesEveryConstraintPrivateIncidences) {
  for (const Case& c : test_models()) {
    SCOPED_TRACE(c.name);
    const Colouring colouring = test::colour_model(c.model, "metis");
    const Schedule schedule(c.model, &colouring, {SolverMode::jacobi, 128, 0});
    EXPECT_EQ(schedule.phase_count(), 0u);
    EXPECT_EQ(schedule.jacobi().constraint_count, c.model.constraints.size());
    check_layout(c.model, colouring, schedule);
    // Each movable particle's incidence list has one entry per constraint touching it, and
    // each of them names that particle.
    const ConstraintGraph graph = constraint_graph(c.model);
    const JacobiSet& jacobi = schedule.jacobi();
    std::size_t listed = 0;
    for (std::size_t k = 0; k < jacobi.particles.size(); ++k) {
      const ParticleIndex p = jacobi.particles[k];
      const std::size_t count = jacobi.particle_offsets[k + 1] - jacobi.particle_offsets[k];
      EXPECT_EQ(count, graph.particle_degree(schedule.user_particle(p)));
      for (auto j = jacobi.particle_offsets[k]; j < jacobi.particle_offsets[k + 1]; ++j)
        EXPECT_EQ(jacobi.incidence_particle[jacobi.particle_incidences[j]], p);
      listed += count;
    }
    EXPECT_EQ(listed, graph.incidence_count());
  }
}

TEST(Schedule, HybridSendsTheSmallColoursToTheJacobiSet) {
  const Model model = test::tet_bar_model(3, 3, 8, BarMaterial::volume_and_distance);
  const Colouring colouring = test::colour_model(model, "greedy");
  std::size_t smallest = colouring.constraint_count(), largest = 0;
  for (Colour k = 0; k < colouring.colour_count(); ++k) {
    smallest = std::min(smallest, colouring.colour_size(k));
    largest = std::max(largest, colouring.colour_size(k));
  }
  const std::size_t threshold = (smallest + largest) / 2;
  const Schedule schedule(model, &colouring, {SolverMode::hybrid, 64, threshold});
  std::size_t small = 0, large = 0;
  for (Colour k = 0; k < colouring.colour_count(); ++k)
    (colouring.colour_size(k) < threshold ? small : large) += colouring.colour_size(k);
  ASSERT_GT(small, 0u);
  ASSERT_GT(large, 0u);
  EXPECT_EQ(schedule.jacobi().constraint_count, small);
  for (ConstraintIndex id = 0; id < model.constraints.size(); ++id)
    EXPECT_EQ(schedule.locate(id).in_jacobi_set,
              colouring.colour_size(colouring.colour_of(id)) < threshold);
  check_layout(model, colouring, schedule);
}

TEST(Schedule, SequentialInInputOrderKeepsTheModelAsItIs) {
  const Model model = test::cloth_model(6, 5);
  ScheduleOptions options{SolverMode::sequential};
  options.sequential_order = SequentialOrder::input;
  const Schedule schedule(model, nullptr, options);
  EXPECT_EQ(schedule.phase_count(), 0u);
  for (ConstraintIndex id = 0; id < model.constraints.size(); ++id) {
    const ConstraintLocation where = schedule.locate(id);
    EXPECT_FALSE(where.in_jacobi_set);
    EXPECT_EQ(where.slot, id - model.constraint_id(where.family, 0));
    EXPECT_EQ(schedule.user_constraint(where.family, false, where.slot), id);
  }
}

TEST(Schedule, SequentialInGroupsLaysOutTheGreedyColoursAndMapsBack) {
  const Model model = test::cloth_model(6, 5);
  const Schedule schedule(model, nullptr, {SolverMode::sequential});
  EXPECT_EQ(schedule.phase_count(), test::colour_model(model, "greedy").colour_count());
  ASSERT_EQ(schedule.iteration_stages().size(), 1u) << "one sequential sweep over every group";
  EXPECT_EQ(schedule.iteration_stages()[0].kind, StageKind::sequential_sweep);
  EXPECT_EQ(schedule.iteration_stages()[0].last_block, schedule.blocks().size());
  for (ConstraintIndex id = 0; id < model.constraints.size(); ++id) {
    const ConstraintLocation where = schedule.locate(id);
    EXPECT_FALSE(where.in_jacobi_set);
    EXPECT_EQ(schedule.user_constraint(where.family, false, where.slot), id);
  }
}

TEST(Schedule, RejectsAColouringOfAnotherModel) {
  const Model model = test::cloth_model(6, 5);
  const Colouring other = test::colour_model(test::cloth_model(7, 5));
  EXPECT_THROW(Schedule(model, &other, {}), InvalidInput);
  EXPECT_THROW(Schedule(model, nullptr, {SolverMode::gs}), InvalidInput);
  const Colouring colouring = test::colour_model(model);
  EXPECT_THROW(Schedule(model, &colouring, {SolverMode::gs, 0}), InvalidInput);
  EXPECT_THROW(model.constraint_id(ConstraintFamily::fem_tetra, 0), InvalidInput);
  const Schedule schedule(model, &colouring, {});
  EXPECT_THROW(schedule.locate(ConstraintIndex(model.constraints.size())), InvalidInput);
}

TEST(Schedule, ModeNamesRoundTrip) {
  for (const SolverMode mode :
       {SolverMode::gs, SolverMode::jacobi, SolverMode::hybrid, SolverMode::sequential})
    EXPECT_EQ(parse_solver_mode(solver_mode_name(mode)), mode);
  EXPECT_THROW(parse_solver_mode("gauss-seidel"), InvalidInput);
}

}  // namespace schedule_tests
}  // namespace tessera
