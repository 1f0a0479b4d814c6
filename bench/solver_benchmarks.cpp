// Solver benchmarks: solver/<mode>/<scene>/threads:<T>, the throughput of whole projection
// sweeps (items_per_second = constraint projections per second);
// solver_layout/<layout>/<scene>/threads:<T>, gs with each ParticleLayout side by side; and
// solver_strategy/<strategy>/<scene>/threads:<T>, gs under each colouring strategy (with
// "+locality" the locality pass, "metis@<k>" METIS parts of k particles), which is how the
// strategies and METIS's part size were compared on solver throughput.
//
// Threads: 1, then 2, 4, … up to the hardware thread count (1 and 2 on a 2-core machine).
// Scenes (each built once per process): cloth256 and cloth1024, 256² and 1024² cloths in the
// xz plane pinned at two corners with distance + dihedral constraints; cloth256_distance,
// distance only; tetbar200k, a 20×20×84 bar of 201,600 FEM tetrahedra fixed at one end.
// Each benchmark builds its solver outside the timed loop, takes one time step so the state
// is deformed, then times `project(1)`: one sweep over every constraint (XPBD semantics).
// Residual reports and the finiteness guard are off (they cost per call, not per sweep).
// Counters: colours (Gauss–Seidel phases), jacobi (constraints in the Jacobi set),
// colouring_s (time the strategy took), schedule_s, bytes_per_projection (the traffic model
// below, mean over the scene's constraints).
//
// solver_size/gs/<scene>:<size>/threads:<T>: gs throughput against problem size, for the size
// scaling plot of scripts/bench: cloth:<N> is an N×N cloth (N = 64 … 2048), tetbar:<n> an
// n×n×4n-cell FEM bar (n = 10 … 100, about as many particles as the cloths). Counters as above
// plus particles, constraints and model_bytes_per_second (projections/s × bytes/projection).
// Only one size scene is kept in memory at a time (the 2048² cloth takes gigabytes).
// solver_size_separate/gs/<largest size>: the same with ParticleLayout::separate;
// solver_size_part_major/gs/<largest size>: with SweepOrder::part_major on METIS parts of
// 16,384 particles. solver_order/<order>/<strategy>/<scene>: both sweep orders on the same
// METIS colourings, and on stencil+locality (part-major over runs of its particle order).
//
// Traffic model, bytes a projection must move between memory and the core when nothing is
// reused from cache: for each of its N particles, x, y, z and inverse mass gathered (4 reals)
// and x, y, z scattered (3 reals), plus its N particle indices; per constraint, the rest data
// the kernel loads, the XPBD compliance, and λ read and written (2 reals). Rest data: distance
// and dihedral 1 real (length, angle), volume 1 (rest volume), FEM tetra 11 (volume, 3×3
// inverse rest matrix, Poisson ratio).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <optional>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <tessera/coloring/run_colouring.hpp>
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

/// Bytes one projection of a constraint of N particles with `rest_reals` reals of rest data
/// moves under the traffic model above.
constexpr double modelled_bytes(std::size_t particles, std::size_t rest_reals) {
  return double(particles * ((4 + 3) * sizeof(Real) + sizeof(ParticleIndex)) +
                (rest_reals + 1 + 2) * sizeof(Real));
}

/// The traffic model's mean bytes per projection over every constraint of `model`. Throws for
/// a family the model does not cover (the benchmark scenes use none).
double bytes_per_projection(const Model& model) {
  const ConstraintSets& sets = model.constraints;
  const std::pair<std::size_t, double> families[] = {
      {sets.distance.size(), modelled_bytes(2, 1)},
      {sets.dihedral.size(), modelled_bytes(4, 1)},
      {sets.volume.size(), modelled_bytes(4, 1)},
      {sets.fem_tetra.size(), modelled_bytes(4, 11)},
  };
  double bytes = 0;
  std::size_t modelled = 0;
  for (const auto& [count, per_projection] : families) {
    bytes += double(count) * per_projection;
    modelled += count;
  }
  if (modelled != sets.size())
    throw std::logic_error("bytes_per_projection: the scene has a family the model lacks");
  return modelled ? bytes / double(modelled) : 0.0;
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
                const std::string& strategy,
                ParticleLayout layout = kDefaultParticleLayout,
                SweepOrder order = SweepOrder::colour_major, bool phase_regions = true) {
  const Model& model = scene(scene_name);
  SolverSettings settings;
  settings.phase_regions = phase_regions;
  settings.mode = mode;
  settings.particle_layout = layout;
  settings.sweep_order = order;
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
  state.counters["bytes_per_projection"] = bytes_per_projection(model);
}

constexpr const char* kDefaultStrategy = "greedy";

/// The cost of one colour phase: a 16×16 distance-only cloth (6 colours of ~120 constraints),
/// so each phase is one tiny share per thread and a barrier. Counter time_per_phase = wall time per sweep / phases (the kernels' own work, ~700
/// distance projections per sweep, is included and is well under a microsecond per phase).
void BM_PhaseOverhead(benchmark::State& state) {
  const Model model = test::cloth_model(16, 16, test::ClothBending::none);
  SolverSettings settings;
  settings.threads = std::size_t(state.range(0));
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

/// solver/step_tiny: one step() of a 2-particle model with 1 distance constraint (one pinned
/// end), default settings on one thread (residual reports and the finiteness guard on): the
/// fixed cost of a step, the C++ side of the Python binding's call overhead
/// (bench/python_overhead.py times the same call through tessera.Solver.step, side by side).
void BM_StepTiny(benchmark::State& state) {
  const std::vector<Vector3r> points = {Vector3r(0, 0, 0), Vector3r(1, 0, 0)};
  const std::vector<Real> inverse_masses = {0, 1};
  const std::vector<ParticleIndex> edge = {0, 1};
  Model model;
  model.particles = ParticleState(points, inverse_masses);
  model.constraints.distance = make_distance_constraints({edge, points});
  SolverSettings settings;
  settings.threads = 1;
  Solver solver(model, test::colour_model(model), settings);
  for (auto _ : state) solver.step();
}
BENCHMARK(BM_StepTiny)->Name("solver/step_tiny")->UseRealTime();

/// solver/positions/cloth1024: Solver::positions() on the 1024² cloth coloured with the
/// locality pass (particles renumbered, as `tessera run` does): the user-order copy the Python
/// binding's Solver.positions makes as an (N, 3) array.
void BM_PositionsCopy(benchmark::State& state) {
  const Model& model = scene("cloth1024");
  SolverSettings settings;
  settings.threads = 1;
  const ColouringRun run = run_colouring(ColouringRegistry::with_builtin_strategies().get("stencil"),
                                         constraint_graph(model), ColouringOptions{.locality = true});
  Solver solver(model, run.colouring, settings);
  for (auto _ : state) benchmark::DoNotOptimize(solver.positions());
  state.SetBytesProcessed(state.iterations() * std::int64_t(3 * sizeof(Real) * solver.particle_count()));
}
BENCHMARK(BM_PositionsCopy)->Name("solver/positions/cloth1024")->UseRealTime()->Unit(benchmark::kMillisecond);

/// Thread counts of the thread-scaling benchmarks beyond 1: 2, 4, 8, … below the hardware
/// thread count, then the hardware thread count itself (just 2 on a 2-core machine).
std::vector<int> scaling_thread_counts() {
  const int hardware_threads = std::max(2, int(std::thread::hardware_concurrency()));
  std::vector<int> counts;
  for (int threads = 2; threads < hardware_threads; threads *= 2) counts.push_back(threads);
  counts.push_back(hardware_threads);
  return counts;
}

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
      if (mode != SolverMode::sequential)
        for (const int threads : scaling_thread_counts()) b->Arg(threads);
    }
  for (const ParticleLayout layout : {ParticleLayout::separate, ParticleLayout::interleaved})
    for (const char* scene_name : scenes) {
      const std::string name = "solver_layout/" + std::string(particle_layout_name(layout)) +
                               "/" + scene_name;
      auto* b = benchmark::RegisterBenchmark(
          name.c_str(), [layout, scene_name](benchmark::State& state) {
            run_solver(state, SolverMode::gs, scene_name, kDefaultStrategy, layout);
          });
      b->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond)->Arg(1)->Arg(2);
    }
  // The phases of an iteration in one region with a spin barrier, or a parallel_for each.
  for (const bool regions : {true, false})
    for (const char* scene_name : scenes) {
      const std::string name = std::string("solver_phases/") + (regions ? "region" : "parallel_for") +
                               "/" + scene_name;
      auto* b = benchmark::RegisterBenchmark(
          name.c_str(), [regions, scene_name](benchmark::State& state) {
            run_solver(state, SolverMode::gs, scene_name, kDefaultStrategy, kDefaultParticleLayout,
                       SweepOrder::colour_major, regions);
          });
      b->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond)->Arg(2);
    }
  // Part-major against colour-major on the same METIS colourings (part sizes: 4,096 and
  // 16,384 particles, 64 and 256 KiB of interleaved floats, against L2; 65,536, the default),
  // and on the tool's default colouring, whose part-major parts are runs of 65,536 particles
  // of its locality order.
  for (const SweepOrder order : {SweepOrder::colour_major, SweepOrder::part_major})
    for (const char* strategy : {"metis@4096", "metis@16384", "metis", "stencil+locality"})
      for (const char* scene_name : {"cloth256", "cloth1024", "tetbar200k"}) {
        const std::string name = "solver_order/" + std::string(sweep_order_name(order)) + "/" +
                                 strategy + "/" + scene_name;
        auto* b = benchmark::RegisterBenchmark(
            name.c_str(), [order, strategy, scene_name](benchmark::State& state) {
              run_solver(state, SolverMode::gs, scene_name, strategy, kDefaultParticleLayout,
                         order);
            });
        b->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond)->Arg(1)->Arg(2);
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

/// The scene of the size sweep now in memory with its greedy colouring: "cloth:<N>" or
/// "tetbar:<n>". Benchmarks run in registration order, so each size is built once.
struct SizeScene {
  std::string name;
  std::unique_ptr<Model> model;
  Colouring colouring;
  /// metis with kPartMajorParticlesPerPart, made on first use (SweepOrder::part_major).
  std::optional<Colouring> part_colouring;
};

/// Part size of the part-major size benchmark: 16,384 particles, 256 KiB of interleaved
/// floats, which stay in a core's L2 while its colours sweep (solver_order measured 4,096,
/// 16,384 and 65,536).
constexpr std::size_t kPartMajorParticlesPerPart = 16384;

SizeScene& size_scene(const std::string& kind, std::size_t size) {
  static SizeScene current;
  const std::string name = kind + ":" + std::to_string(size);
  if (current.name != name) {
    current = SizeScene{};  // free the previous scene before building the next
    if (kind == "cloth")
      current.model = std::make_unique<Model>(test::cloth_model(size, size));
    else
      current.model = std::make_unique<Model>(
          test::tet_bar_model(size, size, 4 * size, test::BarMaterial::fem_tetra, Real(1e6)));
    current.colouring = test::colour_model(*current.model, kDefaultStrategy);
    current.name = name;
  }
  return current;
}

void BM_SolverSize(benchmark::State& state, const std::string& kind, std::size_t size,
                   ParticleLayout layout = kDefaultParticleLayout,
                   SweepOrder order = SweepOrder::colour_major) {
  SizeScene& scene = size_scene(kind, size);
  if (order == SweepOrder::part_major && !scene.part_colouring)
    scene.part_colouring = test::colour_model(
        *scene.model, "metis", ColouringOptions{.particles_per_part = kPartMajorParticlesPerPart});
  SolverSettings settings;
  settings.particle_layout = layout;
  settings.sweep_order = order;
  settings.threads = std::size_t(state.range(0));
  settings.iterations = 1;
  settings.report_residuals = false;
  settings.check_finite = false;
  Solver solver(*scene.model,
                order == SweepOrder::part_major ? *scene.part_colouring : scene.colouring,
                settings);
  solver.step();
  for (auto _ : state) solver.project(1, settings.time_step);
  const auto constraints = std::int64_t(scene.model->constraints.size());
  state.SetItemsProcessed(state.iterations() * constraints);
  const double bytes = bytes_per_projection(*scene.model);
  state.counters["bytes_per_projection"] = bytes;
  state.counters["model_bytes_per_second"] = benchmark::Counter(
      double(state.iterations()) * double(constraints) * bytes, benchmark::Counter::kIsRate);
  state.counters["particles"] = double(scene.model->particles.size());
  state.counters["constraints"] = double(constraints);
  state.counters["colours"] = double(solver.statistics().coloured_phases);
}

void register_size_benchmarks() {
  const int hardware_threads = int(std::thread::hardware_concurrency());
  const std::pair<const char*, std::vector<std::size_t>> sweeps[] = {
      {"cloth", {64, 128, 256, 512, 1024, 2048}},
      {"tetbar", {10, 16, 25, 40, 63, 100}},
  };
  for (const auto& [kind, sizes] : sweeps)
    for (const std::size_t size : sizes) {
      const std::string scene_kind = kind;
      const std::string name = "solver_size/gs/" + scene_kind + ":" + std::to_string(size);
      auto* b = benchmark::RegisterBenchmark(
          name.c_str(), [scene_kind, size](benchmark::State& state) {
            BM_SolverSize(state, scene_kind, size);
          });
      b->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond)->Arg(1);
      if (hardware_threads > 1) b->Arg(hardware_threads);
      // The largest size once more with the separate arrays, for the layout's gain out of
      // cache (registered right after it, so the scene is still built).
      if (size != sizes.back()) continue;
      auto* separate = benchmark::RegisterBenchmark(
          ("solver_size_separate/gs/" + scene_kind + ":" + std::to_string(size)).c_str(),
          [scene_kind, size](benchmark::State& state) {
            BM_SolverSize(state, scene_kind, size, ParticleLayout::separate);
          });
      separate->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond)->Arg(1);
      // And part-major (metis parts of kPartMajorParticlesPerPart): cache blocking across
      // colours.
      auto* part_major = benchmark::RegisterBenchmark(
          ("solver_size_part_major/gs/" + scene_kind + ":" + std::to_string(size)).c_str(),
          [scene_kind, size](benchmark::State& state) {
            BM_SolverSize(state, scene_kind, size, kDefaultParticleLayout, SweepOrder::part_major);
          });
      part_major->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond)->Arg(1);
      if (hardware_threads > 1) part_major->Arg(hardware_threads);
    }
}

/// solver/block_size/<scene>/block:<B>/threads:2: mode jacobi with work blocks of B
/// constraints, how kDefaultBlockSize was chosen (block_size cuts Jacobi sets only; a colour
/// phase is cut into one share per thread whatever it is).
void BM_BlockSize(benchmark::State& state, const std::string& scene_name) {
  const Model& model = scene(scene_name);
  SolverSettings settings;
  settings.mode = SolverMode::jacobi;
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

/// solver/chebyshev/<scene>/chebyshev:<0|1>/threads:<T>: mode jacobi without and with the
/// Chebyshev acceleration (SolverSettings::chebyshev), timing project(16), so that 15 of the
/// 16 iterations keep or extrapolate the positions (project(1) would only run iteration 1,
/// which does neither); items are constraint projections, so items_per_second compares the
/// cost per iteration directly.
constexpr std::size_t kChebyshevIterations = 16;
void BM_Chebyshev(benchmark::State& state, const std::string& scene_name) {
  const Model& model = scene(scene_name);
  SolverSettings settings;
  settings.mode = SolverMode::jacobi;
  settings.chebyshev = state.range(0) != 0;
  settings.threads = std::size_t(state.range(1));
  settings.iterations = 1;
  settings.report_residuals = false;
  settings.check_finite = false;
  Solver solver(model, colouring(scene_name, kDefaultStrategy).colouring, settings);
  solver.step();
  for (auto _ : state) solver.project(kChebyshevIterations, settings.time_step);
  state.SetItemsProcessed(state.iterations() * std::int64_t(kChebyshevIterations) *
                          std::int64_t(model.constraints.size()));
}
BENCHMARK_CAPTURE(BM_Chebyshev, cloth256, std::string("cloth256"))
    ->Name("solver/chebyshev/cloth256")->ArgNames({"chebyshev", "threads"})
    ->ArgsProduct({{0, 1}, {1, 2}})->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Chebyshev, tetbar200k, std::string("tetbar200k"))
    ->Name("solver/chebyshev/tetbar200k")->ArgNames({"chebyshev", "threads"})
    ->ArgsProduct({{0, 1}, {1, 2}})->UseRealTime()->Unit(benchmark::kMillisecond);

const int kRegistered = (register_benchmarks(), register_size_benchmarks(), 0);

}  // namespace
