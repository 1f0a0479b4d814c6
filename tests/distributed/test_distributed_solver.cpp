// The distributed solver in exact mode, run by ctest through mpirun with 1, 2 and 3 ranks:
// every rank builds the same scene, steps it with DistributedSolver and, on its own, with
// the single-process Solver; rank 0 compares the gathered positions bitwise. Covers every
// family the shell and solid scenes make (distance, dihedral, isometric bending, strain and FEM
// triangles, FEM and strain tetrahedra, volume, tethers), 1 and 2 threads per rank, and the
// refusals every rank must agree on.
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mpi.h>

#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/model_graph.hpp>
#include <tessera/coloring/run_colouring.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/fingerprint.hpp>
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

/// Steps `frames` frames both ways; on rank 0 the two state hashes, elsewhere "".
std::pair<std::string, std::string> both_ways(const Model& model, const char* strategy,
                                              std::size_t threads, std::size_t frames) {
  const Colouring colouring = colour(model, strategy);
  DistributedSolver distributed(model, colouring, settings_for(threads), MPI_COMM_WORLD);
  for (std::size_t f = 0; f < frames; ++f) distributed.step();
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
