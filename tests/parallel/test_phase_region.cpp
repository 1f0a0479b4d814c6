// detail::PhaseRegion (parallel/src/phase_region.hpp): every share of every phase runs exactly
// once and no share of a phase starts before the previous phase has finished, whether all the
// shares' threads run or only some (the others' shares are taken over); and the solver gives
// the same bits with its phases in regions or a parallel_for each.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

#include <tessera/parallel/solver.hpp>

#include "batch_test_support.hpp"
#include "phase_region.hpp"
#include "scenes.hpp"

namespace tessera {
namespace {

/// Runs a region of `phases` × `shares` on `threads` threads (thread t runs share t; shares
/// without a thread are taken over) and checks each share ran once, in phase order.
void check_region(std::size_t phases, std::size_t shares, std::size_t threads) {
  detail::PhaseRegion region(phases, shares);
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

TEST(PhaseRegion, EveryShareRunsOnceInPhaseOrder) { check_region(20, 2, 2); }

TEST(PhaseRegion, SharesWithoutAThreadAreTakenOver) {
  check_region(7, 3, 1);  // one thread does all three shares of every phase
  check_region(5, 8, 3);
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

}  // namespace
}  // namespace tessera
