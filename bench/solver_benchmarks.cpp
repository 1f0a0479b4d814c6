// Solver benchmarks: solver/<mode>/<scene>/threads:<T>, the throughput of whole projection
// sweeps (items_per_second = constraint projections per second), and
// solver_strategy/<strategy>/<scene>/threads:<T>, gs under each colouring strategy (with
// "+locality" the locality pass, "metis@<k>" METIS parts of k particles), which is how the
// strategies and METIS's part size were compared on solver throughput.
//
// Scenes (each built once per process): cloth256 and cloth1024, 256² and 1024² cloths in the
// xz plane pinned at two corners with distance + dihedral constraints; cloth256_distance,
// distance only; tetbar200k, a 20×20×84 bar of 201,600 FEM tetrahedra fixed at one end.
// Each benchmark builds its solver outside the timed loop, takes one time step so the state
// is deformed, then times `project(1)`: one sweep over every constraint (XPBD semantics).
// Residual reports and the finiteness guard are off (they cost per call, not per sweep).
// Counters: colours (Gauss–Seidel phases), jacobi (constraints in the Jacobi set),
// colouring_s (time the strategy took), schedule_s.
#include <benchmark/benchmark.h>

#include <chrono>
#include <map>
#include <memory>
#include <string>

#include <tessera/coloring/colouring_statistics.hpp>
#include <tessera/parallel/solver.hpp>

#include "scenes.hpp"

namespace {

using namespace tessera;

const Model& scene(const std::string& name) {
  static std::map<std::string, std::unique_ptr<Model>> cache;
  auto& slot = cache[name];
  if (!slot) {
    if (name == "cloth256") slot = std::make_unique<Model>(test::cloth_model(256, 256));
    if (name == "cloth256_distance")
      slot = std::make_unique<Model>(test::cloth_model(256, 256, test::ClothBending::none));
    if (name == "cloth1024") slot = std::make_unique<Model>(test::cloth_model(1024, 1024));
    if (name == "tetbar200k")
      slot = std::make_unique<Model>(
          test::tet_bar_model(20, 20, 84, test::BarMaterial::fem_tetra, Real(1e6)));
  }
  return *slot;
}

struct TimedColouring {
  Colouring colouring;
  double seconds = 0;
};

const TimedColouring& colouring(const std::string& scene_name, const std::string& strategy) {
  static std::map<std::string, std::unique_ptr<TimedColouring>> cache;
  auto& slot = cache[scene_name + "/" + strategy];
  if (!slot) {
    const ConstraintGraph graph = constraint_graph(scene(scene_name));
    ColouringOptions options;
    std::string name = strategy;
    if (const auto plus = name.find("+locality"); plus != std::string::npos) {
      options.locality = true;
      name.erase(plus);
    }
    if (const auto at = name.find('@'); at != std::string::npos) {  // metis@<particles per part>
      options.particles_per_part = std::stoul(name.substr(at + 1));
      name.erase(at);
    }
    ColouringRun run =
        run_colouring(ColouringRegistry::with_builtin_strategies().get(name), graph, options);
    slot = std::make_unique<TimedColouring>(
        TimedColouring{std::move(run.colouring), run.statistics.seconds});
  }
  return *slot;
}

void run_solver(benchmark::State& state, SolverMode mode, const std::string& scene_name,
                const std::string& strategy) {
  const Model& model = scene(scene_name);
  SolverSettings settings;
  settings.mode = mode;
  settings.threads = std::size_t(state.range(0));
  settings.iterations = 1;
  settings.substeps = 1;
  settings.report_residuals = false;
  settings.check_finite = false;
  const TimedColouring* coloured = nullptr;
  if (mode != SolverMode::sequential) coloured = &colouring(scene_name, strategy);
  Solver solver = coloured ? Solver(model, coloured->colouring, settings) : Solver(model, settings);
  solver.step();
  for (auto _ : state) solver.project(1, settings.time_step);
  state.SetItemsProcessed(state.iterations() * std::int64_t(model.constraints.size()));
  state.counters["colours"] = double(solver.statistics().coloured_phases);
  state.counters["jacobi"] = double(solver.statistics().jacobi_constraints);
  state.counters["colouring_s"] = coloured ? coloured->seconds : 0.0;
  state.counters["schedule_s"] = solver.statistics().seconds_schedule;
}

constexpr const char* kDefaultStrategy = "greedy";

/// The cost of one colour phase: a 16×16 distance-only cloth (6 colours of ~120 constraints)
/// cut into blocks of kMaxLanes constraints, so each phase is a parallel_for over ~8 tiny
/// blocks. Counter time_per_phase = wall time per sweep / phases (the kernels' own work, ~700
/// distance projections per sweep, is included and is well under a microsecond per phase).
void BM_PhaseOverhead(benchmark::State& state) {
  const Model model = test::cloth_model(16, 16, test::ClothBending::none);
  SolverSettings settings;
  settings.threads = std::size_t(state.range(0));
  settings.block_size = kMaxLanes;
  settings.report_residuals = false;
  settings.check_finite = false;
  Solver solver(model, test::colour_model(model, "stencil"), settings);
  solver.step();
  for (auto _ : state) solver.project(1, settings.time_step);
  state.SetItemsProcessed(state.iterations() * std::int64_t(model.constraints.size()));
  const double phases = double(solver.statistics().coloured_phases);
  state.counters["colours"] = phases;
  state.counters["time_per_phase"] = benchmark::Counter(
      double(state.iterations()) * phases,
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert, benchmark::Counter::kIs1000);
}
BENCHMARK(BM_PhaseOverhead)->Name("solver/phase_overhead")->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime();

void register_benchmarks() {
  const char* scenes[] = {"cloth256", "cloth256_distance", "cloth1024", "tetbar200k"};
  for (const SolverMode mode :
       {SolverMode::gs, SolverMode::jacobi, SolverMode::hybrid, SolverMode::sequential})
    for (const char* scene_name : scenes) {
      const std::string name =
          "solver/" + std::string(solver_mode_name(mode)) + "/" + scene_name;
      auto* b = benchmark::RegisterBenchmark(
          name.c_str(), [mode, scene_name](benchmark::State& state) {
            run_solver(state, mode, scene_name, kDefaultStrategy);
          });
      b->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);
      b->Arg(1);
      if (mode != SolverMode::sequential) b->Arg(2);
    }
  for (const char* strategy : {"greedy", "greedy+locality", "stencil", "stencil+locality",
                               "dsatur", "random", "metis", "metis@1024", "metis@4096",
                               "metis@16384"})
    for (const char* scene_name : {"cloth1024", "tetbar200k"}) {
      const std::string name = "solver_strategy/" + std::string(strategy) + "/" + scene_name;
      auto* b = benchmark::RegisterBenchmark(
          name.c_str(), [strategy, scene_name](benchmark::State& state) {
            run_solver(state, SolverMode::gs, scene_name, strategy);
          });
      b->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond)->Arg(1)->Arg(2);
    }
}

/// solver/block_size/<scene>/block:<B>/threads:2: gs with work blocks of B constraints, how
/// kDefaultBlockSize was chosen.
void BM_BlockSize(benchmark::State& state, const std::string& scene_name) {
  const Model& model = scene(scene_name);
  SolverSettings settings;
  settings.threads = 2;
  settings.block_size = std::size_t(state.range(0));
  settings.report_residuals = false;
  settings.check_finite = false;
  Solver solver(model, colouring(scene_name, kDefaultStrategy).colouring, settings);
  solver.step();
  for (auto _ : state) solver.project(1, settings.time_step);
  state.SetItemsProcessed(state.iterations() * std::int64_t(model.constraints.size()));
}
BENCHMARK_CAPTURE(BM_BlockSize, cloth256, std::string("cloth256"))
    ->Name("solver/block_size/cloth256")->ArgName("block")->RangeMultiplier(4)->Range(64, 16384)
    ->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BlockSize, tetbar200k, std::string("tetbar200k"))
    ->Name("solver/block_size/tetbar200k")->ArgName("block")->RangeMultiplier(4)
    ->Range(64, 16384)->UseRealTime()->Unit(benchmark::kMillisecond);

const int kRegistered = (register_benchmarks(), 0);

}  // namespace
