// The distributed solver in exact mode, run by ctest through mpirun with 1, 2 and 3 ranks:
// every rank builds the same scene, steps it with DistributedSolver and, on its own, with
// the single-process Solver; rank 0 compares the gathered positions bitwise. Covers every
// family the shell and solid scenes make (distance, dihedral, isometric bending, strain and FEM
// triangles, FEM and strain tetrahedra, volume, tethers), 1 and 2 threads per rank, and the
// refusals every rank must agree on.
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mpi.h>

#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/model_graph.hpp>
#include <tessera/coloring/run_colouring.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/fingerprint.hpp>
#include <tessera/distributed/agreement.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/io/scene_description.hpp>
#include <tessera/io/scene_file.hpp>

namespace tessera {
namespace {

int world_rank() {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank;
}

int world_size() {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  return size;
}

/// The colouring the tool uses: the strategy, then the locality pass (which renumbers the
/// particles for one process's cache; the ranks ignore that numbering).
Colouring colour(const Model& model, const char* strategy) {
  return run_colouring(ColouringRegistry::with_builtin_strategies().get(strategy),
                       constraint_graph(model), ColouringOptions{.locality = true})
      .colouring;
}

SolverSettings settings_for(std::size_t threads) {
  SolverSettings settings;
  settings.mode = SolverMode::gs;
  settings.substeps = 4;
  settings.iterations = 2;
  settings.threads = threads;
  return settings;
}

/// Every rank's copy of every particle it holds equals its owner's, bitwise (checked on rank
/// 0, whose verdict every rank returns): ghosts are current after a step.
bool ghosts_are_current(DistributedSolver& solver) {
  const std::vector<Vector3r> owners = solver.gather_positions();
  std::vector<double> mine;  // id, x, y, z per held particle
  const auto& held = solver.held_particles();
  for (std::size_t i = 0; i < held.size(); ++i) {
    const Vector3r x = solver.local_solver().position(ParticleIndex(i));
    mine.insert(mine.end(), {double(held[i]), double(x.x()), double(x.y()), double(x.z())});
  }
  int count = int(mine.size());
  const auto ranks = static_cast<std::size_t>(world_size());
  std::vector<int> counts(ranks), offsets(ranks);
  MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  int total = 0;
  for (std::size_t r = 0; r < counts.size(); ++r) offsets[r] = total, total += counts[r];
  std::vector<double> all(static_cast<std::size_t>(world_rank() == 0 ? total : 0));
  MPI_Gatherv(mine.data(), count, MPI_DOUBLE, all.data(), counts.data(), offsets.data(),
              MPI_DOUBLE, 0, MPI_COMM_WORLD);
  int current = 1;
  for (std::size_t k = 0; k + 3 < all.size(); k += 4) {
    const Vector3r& owner = owners[std::size_t(all[k])];
    current &= double(owner.x()) == all[k + 1] && double(owner.y()) == all[k + 2] &&
               double(owner.z()) == all[k + 3];
  }
  MPI_Bcast(&current, 1, MPI_INT, 0, MPI_COMM_WORLD);
  return current != 0;
}

/// Steps `frames` frames both ways; on rank 0 the two state hashes, elsewhere "".
std::pair<std::string, std::string> both_ways(const Model& model, const char* strategy,
                                              std::size_t threads, std::size_t frames) {
  const Colouring colouring = colour(model, strategy);
  DistributedSolver distributed(model, colouring, settings_for(threads), MPI_COMM_WORLD);
  for (std::size_t f = 0; f < frames; ++f) distributed.step();
  EXPECT_TRUE(ghosts_are_current(distributed));
  const std::vector<Vector3r> gathered = distributed.gather_positions();
  if (world_rank() != 0) return {"", ""};
  Solver one(model, colouring, settings_for(threads));
  for (std::size_t f = 0; f < frames; ++f) one.step();
  return {state_hash(one.positions()), state_hash(gathered)};
}

Model scene_model(const std::string& spec, const std::string& material) {
  io::SceneDescription description = io::parse_scene_spec(spec);
  if (spec.rfind("cloth", 0) == 0) {
    if (material == "isometric") {
      description.shell.bending = io::ShellBending::isometric;
    } else if (material == "strain_triangle") {
      description.shell.material = io::ShellMaterial::strain_triangle;
    } else if (material == "fem_triangle") {
      description.shell.material = io::ShellMaterial::fem_triangle;
    }
  } else {
    if (material == "strain_tetra") description.solid.material = io::SolidMaterial::strain_tetra;
    if (material == "volume_and_distance")
      description.solid.material = io::SolidMaterial::volume_and_distance;
  }
  return io::build_scene(description).model;
}

TEST(DistributedExact, EveryFamilyGivesBitwiseTheSingleProcessState) {
  const std::vector<std::pair<std::string, std::string>> scenes = {
      {"cloth:12x10", "distance"},         {"cloth:12x10", "isometric"},
      {"cloth:12x10", "strain_triangle"},  {"cloth:12x10", "fem_triangle"},
      {"bar:2x2x5", "fem_tetra"},          {"bar:2x2x5", "strain_tetra"},
      {"bar:2x2x5", "volume_and_distance"}};
  for (const auto& [spec, material] : scenes) {
    SCOPED_TRACE(spec + " " + material + ", " + std::to_string(world_size()) + " ranks");
    const Model model = scene_model(spec, material);
    ASSERT_GT(model.constraints.tether.size(), 0u) << "the scenes are pinned and tethered";
    const auto [one, distributed] = both_ways(model, "stencil", 1, 3);
    EXPECT_EQ(distributed, one);
  }
}

TEST(DistributedExact, AnyThreadCountPerRankAndStrategyGivesTheSameState) {
  const Model cloth = scene_model("cloth:24x20", "distance");
  for (const char* strategy : {"greedy", "stencil", "dsatur", "metis"})
    for (const std::size_t threads : {1, 2}) {
      SCOPED_TRACE(std::string(strategy) + ", " + std::to_string(threads) + " threads per rank");
      const auto [one, distributed] = both_ways(cloth, strategy, threads, 4);
      EXPECT_EQ(distributed, one);
    }
}

TEST(DistributedExact, ResidualsAndStatisticsAddUpOverTheRanks) {
  const Model cloth = scene_model("cloth:16x16", "distance");
  const Colouring colouring = colour(cloth, "stencil");
  DistributedSolver distributed(cloth, colouring, settings_for(1), MPI_COMM_WORLD);
  distributed.step();
  const Residual residual = distributed.residual();
  Solver one(cloth, colouring, settings_for(1));
  one.step();
  const Residual single = one.residual();
  EXPECT_EQ(residual.constraints, single.constraints);
  EXPECT_DOUBLE_EQ(residual.max, single.max) << "the max does not depend on the order";
  EXPECT_NEAR(residual.rms, single.rms, 1e-6 * single.rms + 1e-12);
  // Each particle owned once, each constraint by one rank.
  unsigned long long mine[2] = {distributed.statistics().owned_particles,
                                distributed.statistics().constraints};
  unsigned long long total[2] = {0, 0};
  MPI_Allreduce(mine, total, 2, MPI_UNSIGNED_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(total[0], cloth.particles.size());
  EXPECT_EQ(total[1], cloth.constraints.size());
  if (world_size() == 1) {
    EXPECT_EQ(distributed.statistics().ghost_particles, 0u);
    EXPECT_EQ(distributed.statistics().messages_sent, 0u);
  } else {
    EXPECT_GT(distributed.statistics().ghost_particles, 0u);
  }
}

/// Block mode's state hash and final residual on rank 0 (elsewhere "" and the residual).
std::pair<std::string, Residual> block_run(const Model& model, std::size_t threads,
                                           std::size_t frames) {
  const Colouring colouring = colour(model, "stencil");
  DistributedSolver solver(model, colouring, settings_for(threads), MPI_COMM_WORLD,
                           DistributedMode::block);
  for (std::size_t f = 0; f < frames; ++f) solver.step();
  EXPECT_TRUE(ghosts_are_current(solver)) << "every holder has the owner's mean";
  const Residual residual = solver.residual();
  const std::vector<Vector3r> positions = solver.gather_positions();
  return {world_rank() == 0 ? state_hash(positions) : std::string(), residual};
}

TEST(DistributedBlock, OneRankIsExactAndEveryRankCountIsRepeatableAndConverges) {
  for (const auto& [spec, material] : std::vector<std::pair<std::string, std::string>>{
           {"cloth:24x20", "distance"}, {"bar:3x3x10", "fem_tetra"}}) {
    SCOPED_TRACE(spec + ", " + std::to_string(world_size()) + " ranks");
    const Model model = scene_model(spec, material);
    constexpr std::size_t kFrames = 10;
    const auto [hash, residual] = block_run(model, 1, kFrames);
    // The same answer again, and with 2 threads per rank.
    EXPECT_EQ(block_run(model, 1, kFrames).first, hash);
    EXPECT_EQ(block_run(model, 2, kFrames).first, hash);
    // One process with the same colouring.
    Solver one(model, colour(model, "stencil"), settings_for(1));
    for (std::size_t f = 0; f < kFrames; ++f) one.step();
    const Residual single = one.residual();
    if (world_rank() == 0 && world_size() == 1) {
      EXPECT_EQ(hash, state_hash(one.positions()));
    }
    // Jacobi across the rank boundaries converges: within twice one process's residual.
    EXPECT_TRUE(std::isfinite(residual.rms) && std::isfinite(residual.max));
    EXPECT_LT(residual.rms, 2 * single.rms + 1e-9);
    EXPECT_LT(residual.max, 2 * single.max + 1e-9);
  }
}

TEST(Agreement, AFailureOnOneRankEndsEveryRankWithTheLowestFailingRanksMessage) {
  const int last = world_size() - 1;
  // Bad input seen by the last rank alone: every rank learns it (and none waits forever).
  const RankFailure alone = run_agreed(MPI_COMM_WORLD, [&] {
    if (world_rank() == last) throw InvalidInput("rank " + std::to_string(last) + " saw bad input");
  });
  EXPECT_EQ(alone.code, 2);
  EXPECT_EQ(alone.message, "rank " + std::to_string(last) + " saw bad input");
  // Several fail: the lowest failing rank's failure wins; other exceptions give code 1.
  const RankFailure many = run_agreed(MPI_COMM_WORLD, [&] {
    if (world_rank() == last) throw std::runtime_error("numerical trouble on " + std::to_string(last));
    if (world_rank() > 0 && world_rank() < last) throw InvalidInput("not this one");
  });
  EXPECT_EQ(many.code, world_size() > 2 ? 2 : 1);
  EXPECT_EQ(many.message, world_size() > 2 ? std::string("not this one")
                                           : "numerical trouble on " + std::to_string(last));
  const RankFailure none = run_agreed(MPI_COMM_WORLD, [] {});
  EXPECT_EQ(none.code, 0);
  EXPECT_TRUE(none.message.empty());
}

TEST(DistributedExact, AutoSweepOrderSweepsEveryRankColourByColour) {
  // With runs of 4 particles, auto picks part-major in one process. A rank exchanges its
  // ghosts between colours, so it sweeps colour by colour: the ranks give the single
  // process's colour-major state (not an error from the phase hook).
  const Model cloth = scene_model("cloth:24x20", "distance");
  const Colouring colouring = colour(cloth, "stencil");
  SolverSettings automatic = settings_for(2);
  automatic.particles_per_part = 4;
  ASSERT_EQ(automatic.sweep_order, SweepOrder::automatic) << "the default";
  DistributedSolver distributed(cloth, colouring, automatic, MPI_COMM_WORLD);
  for (int step = 0; step < 3; ++step) distributed.step();
  const std::vector<Vector3r> gathered = distributed.gather_positions();
  if (world_rank() != 0) return;
  ASSERT_EQ(Solver(cloth, colouring, automatic).schedule().options().sweep_order,
            SweepOrder::part_major);
  SolverSettings colour_major = settings_for(2);
  colour_major.sweep_order = SweepOrder::colour_major;
  Solver one(cloth, colouring, colour_major);
  for (int step = 0; step < 3; ++step) one.step();
  EXPECT_EQ(state_hash(gathered), state_hash(one.positions()));
}

TEST(DistributedExact, RefusalsAreTheSameOnEveryRank) {
  const Model cloth = scene_model("cloth:8x8", "distance");
  const Colouring colouring = colour(cloth, "stencil");
  SolverSettings jacobi = settings_for(1);
  jacobi.mode = SolverMode::jacobi;
  try {
    DistributedSolver solver(cloth, colouring, jacobi, MPI_COMM_WORLD);
    ADD_FAILURE() << "mode jacobi was accepted";
  } catch (const InvalidInput& error) {
    EXPECT_STREQ(error.what(), "distributed exact mode: solver mode must be gs, not jacobi");
  }
  ASSERT_TRUE(colouring.renumbers_particles()) << "the locality pass's numbering is ignored";
  const Colouring other = colour(scene_model("cloth:9x8", "distance"), "stencil");
  EXPECT_THROW(DistributedSolver(cloth, other, settings_for(1), MPI_COMM_WORLD), InvalidInput);
}

}  // namespace
}  // namespace tessera

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  if (tessera::world_rank() != 0) {
    // One report: the other ranks' failures still fail the run (their exit code).
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  const int local = RUN_ALL_TESTS();
  int any = 0;
  MPI_Allreduce(&local, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return any;
}
