// SweepOrder::part_major: each part's interior constraints colour after colour on one
// worker, the parts in parallel, then the crossing constraints' colour phases. The parts are
// the colouring's (metis, blocks), or runs of its particle order (any other). Checked: it
// projects every constraint once per iteration (with one part it is colour-major's sweep,
// bit for bit), any thread count gives the same bits, it converges like colour-major, and the
// colouring's claim about its parts is verified, not trusted.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/particle_partition.hpp>
#include <tessera/coloring/run_colouring.hpp>
#include <tessera/parallel/solver.hpp>

#include "batch_test_support.hpp"
#include "scenes.hpp"

namespace tessera {
namespace sweep_order_tests {

SolverSettings settings_with(SweepOrder order, std::size_t threads) {
  SolverSettings settings;
  settings.sweep_order = order;
  settings.threads = threads;
  settings.substeps = 4;
  settings.iterations = 3;
  return settings;
}

Colouring part_colouring(const Model& model, std::size_t particles_per_part,
                          const char* strategy = "metis") {
  ColouringOptions options;
  options.particles_per_part = particles_per_part;
  return test::colour_model(model, strategy, options);
}

std::vector<Vector3r> after_steps(const Model& model, const Colouring& colouring,
                                  const SolverSettings& settings, int steps) {
  Solver solver(model, colouring, settings);
  for (int step = 0; step < steps; ++step) solver.step();
  return solver.positions();
}

TEST(SweepOrder, WithOnePartItIsTheColourMajorSweepBitForBit) {
  // One part: every constraint is interior, so part-major sweeps the same colours in the same
  // order on one worker; a constraint skipped or projected twice would change the bits.
  const Model cloth = test::cloth_model(24, 20);
  const Colouring colouring = part_colouring(cloth, 1 << 20);
  ASSERT_TRUE(colouring.has_parts());
  ASSERT_EQ(colouring.part_count(), 1u);
  const auto colour_major = after_steps(cloth, colouring, settings_with(SweepOrder::colour_major, 2), 3);
  const auto part_major = after_steps(cloth, colouring, settings_with(SweepOrder::part_major, 2), 3);
  EXPECT_TRUE(test::same_bits(colour_major, part_major));
}

TEST(SweepOrder, PartMajorGivesTheSameBitsForAnyThreadCount) {
  const Model cloth = test::cloth_model(40, 32);
  const Model bar = test::tet_bar_model(4, 4, 16, test::BarMaterial::fem_tetra, Real(1e6));
  // Both part strategies: METIS parts, and runs of the numbering.
  for (const char* strategy : {"metis", "blocks"})
    for (const Model* model : {&cloth, &bar}) {
      const Colouring colouring = part_colouring(*model, 128, strategy);
      ASSERT_GE(colouring.part_count(), 4u) << strategy;
      const auto one = after_steps(*model, colouring, settings_with(SweepOrder::part_major, 1), 4);
      for (const std::size_t threads : {2u, 3u, 7u})
        EXPECT_TRUE(test::same_bits(
            one, after_steps(*model, colouring, settings_with(SweepOrder::part_major, threads), 4)))
            << strategy << ", " << threads << " threads";
      // A different Gauss–Seidel order from colour-major: other bits (so the option acts).
      EXPECT_FALSE(test::same_bits(
          one, after_steps(*model, colouring, settings_with(SweepOrder::colour_major, 1), 4)))
          << strategy;
    }
}

TEST(SweepOrder, AColouringWithoutPartsSweepsRunsOfItsParticleOrder) {
  // The tool's default colouring (stencil, particles renumbered by the locality pass) and one
  // that keeps the user's numbering (greedy): parts of at most 128 movable particles of the
  // schedule's order, the same bits for any thread count, another order than colour-major.
  const Model cloth = test::cloth_model(40, 32);
  const ConstraintGraph graph = constraint_graph(cloth);
  const std::size_t movable = graph.movable_particle_count();
  const Colouring stencil =
      run_colouring(*make_stencil_strategy(), graph, {.locality = true}).colouring;
  ASSERT_TRUE(stencil.renumbers_particles());
  const Colouring greedy = test::colour_model(cloth, "greedy");
  for (const Colouring* colouring : {&stencil, &greedy}) {
    ASSERT_FALSE(colouring->has_parts());
    SolverSettings settings = settings_with(SweepOrder::part_major, 1);
    settings.particles_per_part = 128;
    const auto one = after_steps(cloth, *colouring, settings, 4);
    for (const std::size_t threads : {2u, 3u, 7u}) {
      settings.threads = threads;
      EXPECT_TRUE(test::same_bits(one, after_steps(cloth, *colouring, settings, 4)))
          << threads << " threads";
    }
    EXPECT_FALSE(test::same_bits(
        one, after_steps(cloth, *colouring, settings_with(SweepOrder::colour_major, 1), 4)));
    // The runs: ceil(movable / 128) parts; a constraint is interior when its movable
    // particles' scheduled ranks fall in one run of 128.
    const Solver solver(cloth, *colouring, settings);
    EXPECT_EQ(solver.statistics().part_count, (movable + 127) / 128);
    std::vector<std::size_t> rank(cloth.particles.size(), 0);
    {
      std::vector<std::pair<ParticleIndex, ParticleIndex>> scheduled;
      for (std::size_t p = 0; p < cloth.particles.size(); ++p)
        if (graph.is_movable(ParticleIndex(p)))
          scheduled.emplace_back(colouring->renumbers_particles()
                                     ? colouring->particle_old_to_new()[p]
                                     : ParticleIndex(p),
                                 ParticleIndex(p));
      std::sort(scheduled.begin(), scheduled.end());
      for (std::size_t r = 0; r < scheduled.size(); ++r) rank[scheduled[r].second] = r;
    }
    const std::size_t parts = (movable + 127) / 128;
    std::size_t interior = 0;
    for (ConstraintIndex c = 0; c < graph.constraint_count(); ++c) {
      const auto particles = graph.particles_of(c);
      if (particles.empty()) continue;
      const std::size_t first = rank[particles[0]] * parts / movable;
      interior += std::all_of(particles.begin(), particles.end(), [&](ParticleIndex p) {
        return rank[p] * parts / movable == first;
      });
    }
    EXPECT_EQ(solver.statistics().part_constraints, interior);
    EXPECT_GT(interior, graph.constraint_count() / 2);
  }
  // One part holding every movable particle (exactly, or with room to spare): colour-major's
  // sweep, bit for bit.
  for (const std::size_t per_part : {movable, 10 * movable}) {
    SolverSettings whole = settings_with(SweepOrder::part_major, 2);
    whole.particles_per_part = per_part;
    EXPECT_TRUE(test::same_bits(
        after_steps(cloth, stencil, whole, 3),
        after_steps(cloth, stencil, settings_with(SweepOrder::colour_major, 2), 3)))
        << per_part << " per part";
    EXPECT_EQ(Solver(cloth, stencil, whole).statistics().part_count, 1u);
  }
}

TEST(SweepOrder, WithoutMovableParticlesThereAreNoPartsAndNothingMoves) {
  // Every particle static: no runs, every constraint in the phases, the colour-major bits.
  Model pinned = test::cloth_model(12, 10);
  for (std::size_t p = 0; p < pinned.particles.size(); ++p) pinned.particles.inverse_mass[p] = 0;
  const Colouring colouring = test::colour_model(pinned, "greedy");
  const Solver solver(pinned, colouring, settings_with(SweepOrder::part_major, 2));
  EXPECT_EQ(solver.statistics().part_count, 0u);
  EXPECT_EQ(solver.statistics().part_constraints, 0u);
  const auto part_major = after_steps(pinned, colouring, settings_with(SweepOrder::part_major, 2), 2);
  EXPECT_TRUE(test::same_bits(
      part_major, after_steps(pinned, colouring, settings_with(SweepOrder::colour_major, 2), 2)));
  for (std::size_t p = 0; p < pinned.particles.size(); ++p)
    EXPECT_TRUE(test::same_bits(std::vector<Vector3r>{part_major[p]},
                                std::vector<Vector3r>{pinned.particles.position(p)}))
        << "particle " << p;
}

TEST(SweepOrder, EveryConstraintIsInAPartOrAPhaseAndTheStatisticsSaySo) {
  const Model cloth = test::cloth_model(40, 32);
  const Colouring colouring = part_colouring(cloth, 128);
  Solver solver(cloth, colouring, settings_with(SweepOrder::part_major, 2));
  const SolverStatistics& statistics = solver.statistics();
  EXPECT_EQ(statistics.part_count, colouring.part_count());
  std::size_t interior = 0;
  for (const std::uint32_t part : colouring.part_of_constraint()) interior += part != colouring.part_count();
  EXPECT_EQ(statistics.part_constraints, interior);
  std::size_t in_phases = 0;
  for (const std::size_t size : statistics.phase_sizes) in_phases += size;
  EXPECT_EQ(statistics.part_constraints + in_phases + statistics.jacobi_constraints,
            cloth.constraints.size());
  EXPECT_GT(in_phases, 0u) << "some constraints cross parts";
}

TEST(SweepOrder, PartMajorConvergesLikeColourMajor) {
  // The same cloth swinging for 20 steps: the two orders of the same sweep leave residuals
  // within 10 % of each other and end within 1 % of the cloth's size of each other.
  const Model cloth = test::cloth_model(48, 48);
  const Colouring colouring = part_colouring(cloth, 256);
  double rms[2] = {};
  std::vector<Vector3r> end[2];
  for (const SweepOrder order : {SweepOrder::colour_major, SweepOrder::part_major}) {
    SolverSettings settings = settings_with(order, 2);
    settings.report_residuals = true;
    Solver solver(cloth, colouring, settings);
    for (int step = 0; step < 20; ++step) solver.step();
    const std::size_t k = order == SweepOrder::part_major;
    rms[k] = solver.last_step().residual_after.rms;
    end[k] = solver.positions();
  }
  EXPECT_GT(rms[0], 0);
  EXPECT_LT(rms[1], 1.1 * rms[0]);
  EXPECT_GT(rms[1], 0.9 * rms[0]);
  double largest = 0;
  for (std::size_t p = 0; p < end[0].size(); ++p)
    largest = std::max(largest, double((end[0][p] - end[1][p]).norm()));
  EXPECT_LT(largest, 0.01);
  EXPECT_GT(largest, 0) << "different orders";
}

TEST(SweepOrder, StaticParticlesStayPutAndHybridRunsTheSmallCrossingColoursAsJacobi) {
  // METIS's parts, and runs of 96 particles of a colouring without parts.
  const Model cloth = test::cloth_model(32, 24);  // pinned at two corners
  const Colouring metis = part_colouring(cloth, 96);
  const Colouring greedy = test::colour_model(cloth, "greedy");
  for (const Colouring* colouring : {&metis, &greedy}) {
    SolverSettings settings = settings_with(SweepOrder::part_major, 2);
    settings.mode = SolverMode::hybrid;
    settings.hybrid_threshold = 64;
    if (!colouring->has_parts()) settings.particles_per_part = 96;
    Solver solver(cloth, *colouring, settings);
    for (int step = 0; step < 5; ++step) solver.step();
    const auto positions = solver.positions();
    for (std::size_t p = 0; p < cloth.particles.size(); ++p)
      if (cloth.particles.inverse_mass[p] == 0) {
        EXPECT_TRUE(test::same_bits(std::vector<Vector3r>{positions[p]},
                                    std::vector<Vector3r>{cloth.particles.position(p)}))
            << "particle " << p;
      }
    EXPECT_GE(solver.statistics().part_count, 4u);
    EXPECT_GT(solver.statistics().jacobi_constraints, 0u);
  }
}

std::size_t movable_count(const Model& model) {
  const auto& w = model.particles.inverse_mass;
  return std::size_t(std::count_if(w.begin(), w.end(), [](Real m) { return m > 0; }));
}

TEST(SweepOrder, AutoIsPartMajorFromThePartCountUpWithTheChosenOrdersBits) {
  // Runs sized so the cloth makes one part fewer than kPartMajorFromParts, then exactly as
  // many: auto sweeps colour-major, then part-major, each bit for bit as that order set by
  // hand, on 1 and 2 threads.
  const Model cloth = test::cloth_model(40, 32);
  const Colouring stencil = test::colour_model(cloth, "stencil");
  const std::size_t movable = movable_count(cloth);
  for (const std::size_t parts : {kPartMajorFromParts - 1, kPartMajorFromParts}) {
    const std::size_t per_run = (movable + parts - 1) / parts;
    ASSERT_EQ(part_count_for(movable, per_run), parts);
    const SweepOrder chosen =
        parts >= kPartMajorFromParts ? SweepOrder::part_major : SweepOrder::colour_major;
    SolverSettings by_hand = settings_with(chosen, 1);
    if (chosen == SweepOrder::part_major) by_hand.particles_per_part = per_run;
    const auto expected = after_steps(cloth, stencil, by_hand, 3);
    for (const std::size_t threads : {1, 2}) {
      SCOPED_TRACE(std::to_string(parts) + " parts, " + std::to_string(threads) + " threads");
      SolverSettings automatic = settings_with(SweepOrder::automatic, threads);
      automatic.particles_per_part = per_run;
      Solver solver(cloth, stencil, automatic);
      EXPECT_EQ(solver.schedule().options().sweep_order, chosen);
      EXPECT_EQ(solver.statistics().part_count, chosen == SweepOrder::part_major ? parts : 0);
      for (int step = 0; step < 3; ++step) solver.step();
      EXPECT_TRUE(test::same_bits(solver.positions(), expected));
    }
  }
  // The default settings, on this small cloth: colour-major.
  EXPECT_EQ(SolverSettings{}.sweep_order, SweepOrder::automatic);
  EXPECT_EQ(Solver(cloth, stencil, SolverSettings{}).schedule().options().sweep_order,
            SweepOrder::colour_major);
}

TEST(SweepOrder, AutoCountsAColouringsOwnPartsAndLeavesModesWithoutColourPhasesAlone) {
  const Model cloth = test::cloth_model(40, 32);
  const std::size_t movable = movable_count(cloth);
  for (const std::size_t parts : {kPartMajorFromParts - 1, kPartMajorFromParts}) {
    const Colouring blocks =
        part_colouring(cloth, (movable + parts - 1) / parts, "blocks");
    ASSERT_EQ(blocks.part_count(), parts);
    Solver solver(cloth, blocks, settings_with(SweepOrder::automatic, 2));
    EXPECT_EQ(solver.schedule().options().sweep_order,
              parts >= kPartMajorFromParts ? SweepOrder::part_major : SweepOrder::colour_major);
  }
  // Modes without colour phases: colour-major even where the parts would be enough, not the
  // error part-major would be; a part size there sizes nothing (InvalidInput), in sequential's
  // input order too.
  const Colouring blocks = part_colouring(cloth, 4, "blocks");
  ASSERT_GE(blocks.part_count(), kPartMajorFromParts);
  for (const SolverMode mode : {SolverMode::jacobi, SolverMode::sequential}) {
    SolverSettings settings = settings_with(SweepOrder::automatic, 2);
    settings.mode = mode;
    EXPECT_EQ(Solver(cloth, blocks, settings).schedule().options().sweep_order,
              SweepOrder::colour_major);
    settings.particles_per_part = 4;
    const Colouring greedy = test::colour_model(cloth, "greedy");
    EXPECT_THROW(Solver(cloth, greedy, settings), InvalidInput);
    settings.sequential_order = SequentialOrder::input;
    EXPECT_THROW(Solver(cloth, greedy, settings), InvalidInput);
  }
}

TEST(SweepOrder, AutoByDefaultCountsDefaultRunsOfMovableParticles) {
  // One particle short of 32 default runs of movable particles, and exactly enough; 20,000
  // static particles more each time, which would tip the first over if they were counted.
  // Particles on a line, four of the movable ones joined by distance constraints.
  const std::size_t enough = (kPartMajorFromParts - 1) * kDefaultParticlesPerRun + 1;
  constexpr std::size_t kStatic = 20000;
  for (const std::size_t movable : {enough - 1, enough}) {
    std::vector<Vector3r> positions(kStatic + movable);
    for (std::size_t p = 0; p < positions.size(); ++p)
      positions[p] = Vector3r(Real(0.01) * Real(p), 0, 0);
    std::vector<Real> inverse_masses(positions.size(), Real(1));
    std::fill_n(inverse_masses.begin(), kStatic, Real(0));
    std::vector<ParticleIndex> pairs;
    for (ParticleIndex p = kStatic; p < kStatic + 4; ++p) pairs.insert(pairs.end(), {p, p + 1});
    Model model;
    model.particles = ParticleState(positions, inverse_masses);
    model.constraints.distance = make_distance_constraints({pairs, positions});
    Solver solver(model, test::colour_model(model, "greedy"), SolverSettings{});
    const bool part_major = movable >= enough;
    EXPECT_EQ(solver.schedule().options().sweep_order,
              part_major ? SweepOrder::part_major : SweepOrder::colour_major)
        << movable << " movable particles";
    EXPECT_EQ(solver.statistics().part_count, part_major ? kPartMajorFromParts : 0);
  }
}

TEST(SweepOrder, RunsWithoutASizeHoldTheDefaultRunSize) {
  // 130 × 128 particles, two pinned: more than one default run, fewer than two.
  const Model cloth = test::cloth_model(130, 128);
  const std::size_t movable = movable_count(cloth);
  ASSERT_GT(movable, kDefaultParticlesPerRun);
  ASSERT_LT(movable, 2 * kDefaultParticlesPerRun);
  Solver solver(cloth, test::colour_model(cloth, "stencil"),
                settings_with(SweepOrder::part_major, 2));
  EXPECT_EQ(solver.statistics().part_count, 2u);
}

TEST(SweepOrder, WrongUseIsAClearError) {
  const Model cloth = test::cloth_model(16, 16);
  const auto expect_error = [](auto&& make, const std::string& words) {
    try {
      make();
      FAIL() << "no error; expected one naming " << words;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  // A mode without colour phases.
  const Colouring metis = part_colouring(cloth, 64);
  SolverSettings jacobi = settings_with(SweepOrder::part_major, 1);
  jacobi.mode = SolverMode::jacobi;
  expect_error([&] { Solver(cloth, metis, jacobi); }, "needs mode gs or hybrid");
  // A false claim: every constraint said to be interior to part 0 of 2 while part 1 owns one.
  Colouring lying = metis;
  std::vector<std::uint32_t> parts(lying.constraint_count(), 0);
  parts.back() = 1;
  lying.set_parts(parts, 2);
  expect_error([&] { Solver(cloth, lying, settings_with(SweepOrder::part_major, 1)); }, "in part 1");
  // Parts of the wrong size, or past the count.
  expect_error([&] { lying.set_parts({0, 1}, 2); }, "parts name 2 constraints");
  expect_error([&] { lying.set_parts(std::vector<std::uint32_t>(lying.constraint_count(), 5), 2); },
               "in part 5 of 2");
  // A part size that would size nothing: a colour-major sweep, or a colouring with parts.
  SolverSettings sized = settings_with(SweepOrder::colour_major, 1);
  sized.particles_per_part = 64;
  expect_error([&] { Solver(cloth, test::colour_model(cloth, "greedy"), sized); },
               "this sweep is colour-major");
  sized.sweep_order = SweepOrder::part_major;
  expect_error([&] { Solver(cloth, metis, sized); }, "this colouring has its own parts");
  // A phase hook needs phase boundaries, and says when auto chose the order without them.
  Solver solver(cloth, metis, settings_with(SweepOrder::part_major, 1));
  expect_error([&] { solver.set_phase_hook([](std::size_t, ParticleArrays) {}); }, "part-major");
  SolverSettings automatic = settings_with(SweepOrder::automatic, 1);
  automatic.particles_per_part = 2;
  Solver chosen(cloth, test::colour_model(cloth, "greedy"), automatic);
  expect_error([&] { chosen.set_phase_hook([](std::size_t, ParticleArrays) {}); },
               "sweep order part-major (chosen by auto for " +
                   std::to_string(chosen.statistics().part_count) + " parts)");
  // Names.
  EXPECT_EQ(parse_sweep_order("part-major"), SweepOrder::part_major);
  EXPECT_EQ(parse_sweep_order("auto"), SweepOrder::automatic);
  EXPECT_EQ(sweep_order_name(SweepOrder::colour_major), "colour-major");
  expect_error([] { parse_sweep_order("row-major"); }, "unknown sweep order 'row-major'");
}

}  // namespace sweep_order_tests
}  // namespace tessera
