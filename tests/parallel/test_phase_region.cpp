// detail::PhaseRegion (parallel/src/phase_region.hpp): every share of every phase runs exactly
// once and no share of a phase starts before the previous phase has finished, whether all the
// shares' threads run or only some (the others' shares are taken over); and the solver gives
// the same bits with its phases in regions or a parallel_for each; a phase's shares are the
// same slice of each family; a substep's first iteration zeroing λ range by range gives the
// bits of a λ reset before it.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <latch>
#include <thread>
#include <vector>

#include <tessera/parallel/solver.hpp>

#include "batch_test_support.hpp"
#include "phase_region.hpp"
#include "scenes.hpp"

namespace tessera {
namespace phase_region_tests {

/// Runs a region of `phases` × `shares` on `threads` threads (thread t runs share t; shares
/// without a thread are taken over) and checks each share ran once, in phase order.
void check_region(detail::PhaseRegion& region, std::size_t phases, std::size_t shares,
                  std::size_t threads) {
  std::vector<std::atomic<int>> runs(phases * shares);
  std::vector<std::atomic<int>> finished(phases);
  std::atomic<int> out_of_order{0};
  const auto run_share = [&](std::size_t phase, std::size_t share) {
    if (phase != 0 && finished[phase - 1].load() != int(shares)) ++out_of_order;
    ++runs[phase * shares + share];
    ++finished[phase];
  };
  std::vector<std::thread> workers;
  for (std::size_t t = 0; t < threads; ++t)
    workers.emplace_back([&, t] { region.run(t, run_share); });
  for (std::thread& worker : workers) worker.join();
  for (std::size_t i = 0; i < phases * shares; ++i)
    EXPECT_EQ(runs[i].load(), 1) << "phase " << i / shares << " share " << i % shares;
  EXPECT_EQ(out_of_order.load(), 0);
}

void check_region(std::size_t phases, std::size_t shares, std::size_t threads) {
  detail::PhaseRegion region(phases, shares);
  check_region(region, phases, shares, threads);
}

TEST(PhaseRegion, EveryShareRunsOnceInPhaseOrder) { check_region(20, 2, 2); }

/// The solver keeps one region and resets it per iteration: smaller, then larger than before.
TEST(PhaseRegion, AResetRegionRunsLikeANewOne) {
  detail::PhaseRegion region(20, 2);
  check_region(region, 20, 2, 2);
  region.reset(5, 3);
  check_region(region, 5, 3, 3);
  region.reset(20, 2);
  check_region(region, 20, 2, 2);
  region.reset(40, 4);
  check_region(region, 40, 4, 2);
}

TEST(PhaseRegion, SharesWithoutAThreadAreTakenOver) {
  check_region(7, 3, 1);  // one thread does all three shares of every phase
  check_region(5, 8, 3);
}

TEST(PhaseRegion, AThreadLeftAloneStopsWaitingForTheAbsentOnes) {
  // Two shares and one thread (TBB gave the region no worker: an affinity mask of one core,
  // or more threads asked for than the machine has). The thread waits once, in the first
  // region's first phase, for the share nobody claimed; from then on it runs the others'
  // shares right after its own, in every later phase and region. (Before, it waited
  // kHelpAfterSpins pauses at every phase: a 2-thread run on one core took 100 times as long
  // as one thread.)
  detail::PhaseRegion region;
  std::size_t long_waits = 0;
  for (int round = 0; round < 5; ++round) {
    region.reset(30, 2);
    check_region(region, 30, 2, 1);
    long_waits += region.long_waits();
  }
  EXPECT_EQ(long_waits, 1u);
}

TEST(PhaseRegion, AWaiterThatSleepsWakesWhenTheShareFinishes) {
  // Share 1 takes 20 ms in every phase, and share 0's thread starts once share 1 of phase 0
  // has begun: it runs its share, finds nothing to take over, and sleeps until share 1
  // finishes (20 ms is far beyond kSleepAfterSpins pauses). Every share still runs once, in
  // phase order, and the sleeper wakes each time (a lost wake-up hangs here).
  detail::PhaseRegion region(4, 2);
  std::vector<std::atomic<int>> runs(8);
  std::atomic<int> finished[4] = {0, 0, 0, 0};
  std::atomic<int> out_of_order{0};
  std::latch share_1_began(1);
  const auto run_share = [&](std::size_t phase, std::size_t share) {
    if (phase != 0 && finished[phase - 1].load() != 2) ++out_of_order;
    if (share == 1) {
      if (phase == 0) share_1_began.count_down();
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    ++runs[phase * 2 + share];
    ++finished[phase];
  };
  std::thread other([&] { region.run(1, run_share); });
  share_1_began.wait();
  region.run(0, run_share);
  other.join();
  for (std::size_t i = 0; i < runs.size(); ++i) EXPECT_EQ(runs[i].load(), 1) << i;
  EXPECT_EQ(out_of_order.load(), 0);
  EXPECT_GE(region.sleeps(), 1u) << "share 0's thread slept in phase 0's wait";
}

TEST(PhaseRegion, StressedRegionsRunEveryShareOnceInOrder) {
  // Random share counts, threads that start late or not at all, shares that take long: every
  // share runs once and the phases keep their order (the take-over, the lone thread's
  // shortcut and the sleep all take turns here).
  std::uint32_t seed = 2026;
  const auto next = [&](std::uint32_t below) {
    seed = seed * 1664525u + 1013904223u;
    return (seed >> 8) % below;
  };
  detail::PhaseRegion region;
  for (int round = 0; round < 60; ++round) {
    const std::size_t shares = 1 + next(4), threads = 1 + next(std::uint32_t(shares)),
                      phases = 2 + next(12);
    const std::uint32_t slow_share = next(std::uint32_t(shares)), late_thread = next(4);
    region.reset(phases, shares);
    std::vector<std::atomic<int>> runs(phases * shares);
    std::vector<std::atomic<int>> finished(phases);
    std::atomic<int> out_of_order{0};
    const auto run_share = [&](std::size_t phase, std::size_t share) {
      if (phase != 0 && finished[phase - 1].load() != int(shares)) ++out_of_order;
      if (share == slow_share && phase % 3 == 0)
        std::this_thread::sleep_for(std::chrono::microseconds(300));
      ++runs[phase * shares + share];
      ++finished[phase];
    };
    std::vector<std::thread> workers;
    for (std::size_t t = 0; t < threads; ++t)
      workers.emplace_back([&, t] {
        if (t == late_thread) std::this_thread::sleep_for(std::chrono::microseconds(500));
        region.run(t, run_share);
      });
    for (std::thread& worker : workers) worker.join();
    for (std::size_t i = 0; i < phases * shares; ++i)
      ASSERT_EQ(runs[i].load(), 1) << "round " << round << " phase " << i / shares;
    ASSERT_EQ(out_of_order.load(), 0) << "round " << round;
  }
}

TEST(PhaseRegion, TheSolverGivesTheSameBitsWithOrWithoutRegions) {
  const Model cloth = test::cloth_model(40, 30);
  std::vector<std::vector<Vector3r>> results;
  for (const bool regions : {false, true})
    for (const std::size_t threads : {2u, 3u}) {
      SolverSettings settings;
      settings.threads = threads;
      settings.substeps = 4;
      settings.iterations = 3;
      settings.phase_regions = regions;
      Solver solver = test::make_solver(cloth, settings, "stencil");
      for (int step = 0; step < 4; ++step) solver.step();
      results.push_back(solver.positions());
    }
  for (std::size_t i = 1; i < results.size(); ++i)
    EXPECT_TRUE(test::same_bits(results[0], results[i])) << i;
}

/// Shares of a phase with 40 distance constraints in three blocks, then 100 dihedral ones in
/// two (the dihedral run begins at a lane multiple, as Schedule::append_group lays it out).
TEST(PhaseRegion, SharesAreTheSameSliceOfEachFamily) {
  const std::vector<ScheduleBlock> blocks = {
      {ConstraintFamily::distance, 0, 16}, {ConstraintFamily::distance, 16, 32},
      {ConstraintFamily::distance, 32, 40}, {ConstraintFamily::dihedral, 48, 112},
      {ConstraintFamily::dihedral, 112, 148}};
  for (const std::size_t shares : {1u, 2u, 3u, 7u}) {
    std::vector<int> covered(148, 0);
    std::vector<std::size_t> per_family[2];
    for (std::size_t share = 0; share < shares; ++share) {
      std::size_t counts[2] = {0, 0};
      detail::for_share_of_phase(blocks, share, shares,
                                 [&](ConstraintFamily f, std::size_t begin, std::size_t end) {
                                   EXPECT_LT(begin, end);
                                   EXPECT_EQ((begin - (f == ConstraintFamily::distance ? 0 : 48)) % kMaxLanes, 0u);
                                   for (std::size_t c = begin; c < end; ++c) ++covered[c];
                                   counts[f == ConstraintFamily::distance ? 0 : 1] += end - begin;
                                 });
      per_family[0].push_back(counts[0]);
      per_family[1].push_back(counts[1]);
    }
    for (std::size_t c = 0; c < covered.size(); ++c)
      EXPECT_EQ(covered[c], (c < 40 || c >= 48) ? 1 : 0) << "slot " << c << ", " << shares << " shares";
    // Each family is cut into shares within two SIMD widths of each other: the dihedral
    // constraints are not all in the last shares.
    for (const auto& counts : per_family) {
      const auto [low, high] = std::minmax_element(counts.begin(), counts.end());
      EXPECT_LE(*high - *low, 2 * kMaxLanes) << shares << " shares";
      if (shares <= 2) {
        EXPECT_GT(*low, 0u) << shares << " shares";
      }
    }
  }
}

/// A last substep with residual reports resets λ before its iterations, one without zeroes
/// them range by range in the first: the same bits, with 1 substep per step and with 3 (the
/// first two zeroing in either run), for colour-major on 1 and 2 threads (a phase region),
/// hybrid, and part-major. Without the zeroing, λ would carry over from substep to substep.
TEST(PhaseRegion, FreshLambdasGiveTheBitsOfAReset) {
  const Model cloth = test::cloth_model(24, 20);
  struct Case {
    SolverMode mode;
    SweepOrder order;
    const char* strategy;
    std::size_t threads;
  };
  for (const Case& c : {Case{SolverMode::gs, SweepOrder::colour_major, "stencil", 1},
                        Case{SolverMode::gs, SweepOrder::colour_major, "stencil", 2},
                        Case{SolverMode::hybrid, SweepOrder::colour_major, "greedy", 2},
                        Case{SolverMode::gs, SweepOrder::part_major, "metis", 2}}) {
    for (const std::size_t substeps : {1u, 3u}) {
      std::vector<std::vector<Vector3r>> results;
      for (const bool report : {true, false}) {
        SolverSettings settings;
        settings.mode = c.mode;
        settings.sweep_order = c.order;
        settings.threads = c.threads;
        settings.substeps = substeps;
        settings.iterations = 3;
        settings.report_residuals = report;
        ColouringOptions options;
        options.particles_per_part = 96;
        Solver solver(cloth, test::colour_model(cloth, c.strategy, options), settings);
        for (int step = 0; step < 6; ++step) solver.step();
        results.push_back(solver.positions());
      }
      EXPECT_TRUE(test::same_bits(results[0], results[1]))
          << solver_mode_name(c.mode) << " " << sweep_order_name(c.order) << " " << c.threads
          << " threads, " << substeps << " substeps";
    }
  }
}

// step() runs every substep but the last as the phases of one region (prediction, the
// iterations' colours, the velocity update fused with the next prediction). The same bits
// as a parallel_for per phase and per particle pass, and as one thread, in both particle
// layouts; the statistics say which steps took the region.
TEST(PhaseRegion, SubstepsInOneRegionGiveTheBitsOfOneByOne) {
  // 1,271 particles: the particle passes' shares are cut at whole vectors, not at n / threads.
  const Model cloth = test::cloth_model(41, 31);
  // Hybrid on this cloth sweeps a Jacobi set each iteration: one by one, the same bits.
  for (const SolverMode mode : {SolverMode::gs, SolverMode::hybrid}) {
    const std::uint64_t region_steps = mode == SolverMode::gs ? 5 : 0;
    for (const ParticleLayout layout : {ParticleLayout::interleaved, ParticleLayout::separate}) {
      std::vector<std::vector<Vector3r>> positions, velocities;
      std::vector<std::uint64_t> in_region;
      for (const auto& [threads, regions] :
           {std::pair{std::size_t(1), true}, std::pair{std::size_t(2), false},
            std::pair{std::size_t(2), true}, std::pair{std::size_t(3), true}}) {
        SolverSettings settings;
        settings.mode = mode;
        settings.particle_layout = layout;
        settings.threads = threads;
        settings.phase_regions = regions;
        settings.substeps = 4;
        settings.iterations = 3;
        settings.report_residuals = true;  // read in the last substep, which runs alone
        Solver solver(cloth, test::colour_model(cloth, "greedy"), settings);
        for (int step = 0; step < 5; ++step) solver.step();
        positions.push_back(solver.positions());
        velocities.push_back(solver.velocities());
        in_region.push_back(solver.statistics().steps_in_one_region);
      }
      for (std::size_t k = 1; k < positions.size(); ++k) {
        EXPECT_TRUE(test::same_bits(positions[0], positions[k])) << k;
        EXPECT_TRUE(test::same_bits(velocities[0], velocities[k])) << k;
      }
      EXPECT_EQ(in_region[0], 0u);  // one thread: nothing to fork
      EXPECT_EQ(in_region[1], 0u);  // phase regions off
      EXPECT_EQ(in_region[2], region_steps);
      EXPECT_EQ(in_region[3], region_steps);
    }
  }
}

// Past 4,096 phases a step's substeps go to several regions, each after the last's fused
// prediction: still the bits of one by one.
TEST(PhaseRegion, ManySubstepsSplitIntoRegionsGiveTheBitsOfOneByOne) {
  const Model cloth = test::cloth_model(17, 13);
  std::vector<std::vector<Vector3r>> positions;
  for (const bool regions : {false, true}) {
    SolverSettings settings;
    settings.threads = 2;
    settings.phase_regions = regions;
    settings.substeps = 300;
    settings.iterations = 2;
    Solver solver(cloth, test::colour_model(cloth, "greedy"), settings);
    const std::size_t phases = solver.statistics().coloured_phases;
    ASSERT_GT((settings.substeps - 1) * (settings.iterations * phases + 1), 4096u);
    for (int step = 0; step < 2; ++step) solver.step();
    EXPECT_EQ(solver.statistics().steps_in_one_region, regions ? 2u : 0u);
    positions.push_back(solver.positions());
  }
  EXPECT_TRUE(test::same_bits(positions[0], positions[1]));
}

}  // namespace phase_region_tests
}  // namespace tessera
