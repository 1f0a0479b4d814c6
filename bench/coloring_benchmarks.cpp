// Colouring benchmarks: coloring/<strategy>/<mesh> for every registered strategy, plus the
// balance post-pass, graph construction, and the thread scaling of `random`.
//
// Start-up: startup/graph/<scene>, startup/graph+<strategy>/<scene> time what a run pays
// before its first step, constraint_graph(model) and then the strategy, on the tool's scenes
// (io::build_scene, so the model's families and their slot arrays are the solver's):
// cloth1024_tethers (the tool's default cloth:1024, 8.4 M) and, without tethers, cloth1024
// and cloth256 (distance + dihedral: 6.3 M and 0.39 M constraints), cloth256_distance
// (distance only, 0.2 M), fembar (bar:20x20x80, FEM tetrahedra, 0.19 M) and bar (FEM
// tetrahedra of a 40x40x160-cell bar, 1.5 M: the strain bar's graph, one four-particle
// constraint per tetrahedron). startup/tool/<scene> is what `tessera run`
// pays: the graph, the default strategy (stencil), the locality order and the validation
// (run_colouring with ColouringOptions::locality).
//
// Meshes: a 1024×1024 cloth with distance + bending constraints (≈ 6.3 M), the same cloth with
// its constraints shuffled into a random order, the cloth with distance constraints only, and
// a tetrahedral bar of ≈ 1 M tetrahedra (volume) plus its edges (distance). Each is built
// once per process. Counters: colours, lower_bound, colours/lower_bound and
// largest/smallest colour size; time is wall-clock per colouring.
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <random>

#include <tbb/task_arena.h>

#include <tessera/coloring/locality.hpp>
#include <tessera/coloring/colouring_statistics.hpp>
#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/refinement.hpp>
#include <tessera/coloring/run_colouring.hpp>
#include <tessera/coloring/model_graph.hpp>
#include <tessera/io/generators.hpp>
#include <tessera/io/scene_description.hpp>
#include <tessera/io/scene_file.hpp>
#include <tessera/io/scenes.hpp>

namespace {

using namespace tessera;

/// Constraint index arrays plus the graph over them (the graph copies, the arrays are kept so
/// graph construction can be benchmarked too).
struct BenchmarkMesh {
  std::vector<Real> inverse_masses;
  std::vector<std::vector<ParticleIndex>> indices;
  std::vector<std::size_t> arities;
  std::vector<std::string> names;
  std::vector<ConstraintGroup> groups() const {
    std::vector<ConstraintGroup> result;
    for (std::size_t g = 0; g < indices.size(); ++g)
      result.push_back(ConstraintGroup::fixed_arity(names[g], arities[g], indices[g]));
    return result;
  }
  ConstraintGraph graph;
};

/// Fisher–Yates over whole constraints with a fixed seed.
void shuffle_constraints(std::vector<ParticleIndex>& indices, std::size_t arity, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  const std::size_t count = indices.size() / arity;
  for (std::size_t i = count; i > 1; --i) {
    const std::size_t j = random() % i;
    for (std::size_t k = 0; k < arity; ++k) std::swap(indices[(i - 1) * arity + k], indices[j * arity + k]);
  }
}

std::unique_ptr<BenchmarkMesh> make_cloth(bool bending, bool shuffled) {
  const io::ClothGrid cloth = io::make_cloth_grid(1024, 1024);
  auto mesh = std::make_unique<BenchmarkMesh>();
  mesh->inverse_masses.assign(cloth.vertex_count(), Real(1));
  mesh->indices.push_back(cloth.edge_indices);
  mesh->arities.push_back(2);
  mesh->names.push_back("distance");
  if (bending) {
    mesh->indices.push_back(cloth.bending_indices);
    mesh->arities.push_back(4);
    mesh->names.push_back("bending");
  }
  if (shuffled)
    for (std::size_t g = 0; g < mesh->indices.size(); ++g) shuffle_constraints(mesh->indices[g], mesh->arities[g], 42 + g);
  mesh->graph = ConstraintGraph(mesh->inverse_masses, mesh->groups());
  return mesh;
}

std::unique_ptr<BenchmarkMesh> make_tet_bar() {
  const io::TetrahedralBar bar = io::make_tetrahedral_bar(100, 41, 41);  // 1,008,600 tets
  auto mesh = std::make_unique<BenchmarkMesh>();
  mesh->inverse_masses.assign(bar.vertex_count(), Real(1));
  mesh->indices = {bar.tetrahedron_indices, bar.edge_indices};
  mesh->arities = {4, 2};
  mesh->names = {"volume", "distance"};
  mesh->graph = ConstraintGraph(mesh->inverse_masses, mesh->groups());
  return mesh;
}

const BenchmarkMesh& mesh(const std::string& name) {
  static std::map<std::string, std::unique_ptr<BenchmarkMesh>> meshes;
  auto it = meshes.find(name);
  if (it != meshes.end()) return *it->second;
  std::unique_ptr<BenchmarkMesh> built;
  if (name == "cloth1024") built = make_cloth(true, false);
  else if (name == "cloth1024_shuffled") built = make_cloth(true, true);
  else if (name == "cloth1024_distance") built = make_cloth(false, false);
  else if (name == "cloth1024_distance_shuffled") built = make_cloth(false, true);
  else built = make_tet_bar();
  return *meshes.emplace(name, std::move(built)).first->second;
}

const std::vector<std::string> kMeshes = {"cloth1024", "cloth1024_shuffled", "cloth1024_distance",
                                          "cloth1024_distance_shuffled", "tetbar1M"};

void report(benchmark::State& state, const ConstraintGraph& graph, const Colouring& colouring) {
  const ColouringStatistics s = compute_statistics(graph, colouring);
  if (!s.valid) state.SkipWithError(("invalid colouring: " + s.problem).c_str());
  state.counters["colours"] = double(s.colours);
  state.counters["lower_bound"] = double(s.lower_bound);
  state.counters["colours_per_bound"] = s.colours_per_lower_bound;
  state.counters["largest_per_smallest"] = s.size_ratio;
  state.counters["constraints"] = double(s.constraints);
}

void colour_benchmark(benchmark::State& state, std::string strategy, std::string mesh_name,
                      bool balance, int threads) {
  const ConstraintGraph& graph = mesh(mesh_name).graph;
  static const ColouringRegistry registry = ColouringRegistry::with_builtin_strategies();
  const ColouringStrategy& chosen = registry.get(strategy);
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  Colouring colouring;
  for (auto _ : state) {
    arena.execute([&] {
      colouring = chosen.colour(graph, {});
      if (balance) colouring = balance_colours(graph, colouring);
    });
    benchmark::DoNotOptimize(colouring.colours().data());
  }
  report(state, graph, colouring);
}

// metis with a given part size: how the part size trades colours (more crossing constraints
// with small parts) against compact gathers (mean spread of particle ids per 16 constraints
// of a colour, small parts keep a worker's slice of a colour in fewer cache lines).
void metis_part_size_benchmark(benchmark::State& state, std::string mesh_name,
                               std::size_t particles_per_part) {
  const ConstraintGraph& graph = mesh(mesh_name).graph;
  static const ColouringRegistry registry = ColouringRegistry::with_builtin_strategies();
  ColouringOptions options;
  options.particles_per_part = particles_per_part;
  Colouring colouring;
  for (auto _ : state) {
    colouring = registry.get("metis").colour(graph, options);
    benchmark::DoNotOptimize(colouring.colours().data());
  }
  report(state, graph, colouring);
  state.counters["gather_spread"] = mean_gather_spread(graph, colouring);
  state.counters["particles_per_part"] = double(particles_per_part);
}

// The graph as the constructor builds it, or with the particle → constraint lists that a
// strategy walking the conflict graph builds on first use.
void graph_build_benchmark(benchmark::State& state, std::string mesh_name, bool with_particle_lists) {
  const BenchmarkMesh& m = mesh(mesh_name);
  const std::vector<ConstraintGroup> groups = m.groups();
  for (auto _ : state) {
    ConstraintGraph graph(m.inverse_masses, groups);
    if (with_particle_lists) benchmark::DoNotOptimize(graph.particle_constraints().data());
    benchmark::DoNotOptimize(graph.constraint_particles().data());
  }
  state.counters["constraints"] = double(m.graph.constraint_count());
  state.counters["incidences"] = double(m.graph.incidence_count());
}

const Model& startup_model(const std::string& name) {
  static std::map<std::string, std::unique_ptr<Model>> models;
  auto it = models.find(name);
  if (it != models.end()) return *it->second;
  const bool tethers = name == "cloth1024_tethers";
  const std::map<std::string, std::string> specs = {
      {"cloth256", "cloth:256"}, {"cloth256_distance", "cloth:256"}, {"fembar", "bar:20x20x80"},
      {"bar", "bar:40x40x160"}};
  io::SceneDescription description =
      io::parse_scene_spec(specs.count(name) ? specs.at(name) : "cloth:1024");
  if (!tethers) description.tethers = io::TetherRule::none;
  if (name == "cloth256_distance") description.shell.bending = io::ShellBending::none;
  auto model = std::make_unique<Model>(io::build_scene(description).model);
  return *models.emplace(name, std::move(model)).first->second;
}

const std::vector<std::string> kStartupScenes = {"cloth1024", "cloth1024_tethers", "cloth256",
                                                 "cloth256_distance", "fembar", "bar"};

// constraint_graph(model), then the strategy when one is named: the start-up cost.
void startup_benchmark(benchmark::State& state, std::string strategy, std::string scene) {
  const Model& model = startup_model(scene);
  static const ColouringRegistry registry = ColouringRegistry::with_builtin_strategies();
  std::size_t colours = 0, constraints = 0;
  for (auto _ : state) {
    const ConstraintGraph graph = constraint_graph(model);
    constraints = graph.constraint_count();
    if (strategy == "tool") {
      const ColouringRun run =
          run_colouring(registry.get("stencil"), graph, ColouringOptions{.locality = true});
      colours = run.colouring.colour_count();
      if (!run.statistics.valid) state.SkipWithError(run.statistics.problem.c_str());
    } else if (!strategy.empty()) {
      const Colouring colouring = registry.get(strategy).colour(graph, {});
      colours = colouring.colour_count();
      benchmark::DoNotOptimize(colouring.colours().data());
    }
    benchmark::DoNotOptimize(graph.constraint_particles().data());
  }
  state.counters["constraints"] = double(constraints);
  if (!strategy.empty()) state.counters["colours"] = double(colours);
}

void register_all() {
  for (const std::string& scene : kStartupScenes) {
    benchmark::RegisterBenchmark(("startup/graph/" + scene).c_str(), startup_benchmark, std::string(), scene)
        ->Unit(benchmark::kMillisecond)->UseRealTime();
    for (const char* strategy : {"greedy", "stencil", "blocks"})
      benchmark::RegisterBenchmark(("startup/graph+" + std::string(strategy) + "/" + scene).c_str(),
                                   startup_benchmark, std::string(strategy), scene)
          ->Unit(benchmark::kMillisecond)->UseRealTime();
    benchmark::RegisterBenchmark(("startup/tool/" + scene).c_str(), startup_benchmark,
                                 std::string("tool"), scene)
        ->Unit(benchmark::kMillisecond)->UseRealTime();
  }
  const std::vector<std::string> strategies = {"greedy",  "largest-first",   "smallest-last",
                                               "dsatur",  "stencil",         "iterated-greedy",
                                               "random",  "metis",           "blocks"};
  for (const std::string& m : kMeshes) {
    benchmark::RegisterBenchmark(("graph/build/" + m).c_str(), graph_build_benchmark, m, false)
        ->Unit(benchmark::kMillisecond)->UseRealTime();
    benchmark::RegisterBenchmark(("graph/build+particle_lists/" + m).c_str(), graph_build_benchmark, m, true)
        ->Unit(benchmark::kMillisecond)->UseRealTime();
    for (const std::string& s : strategies) {
      benchmark::RegisterBenchmark(("coloring/" + s + "/" + m).c_str(), colour_benchmark, s, m, false, 0)
          ->Unit(benchmark::kMillisecond)->UseRealTime();
      benchmark::RegisterBenchmark(("coloring/" + s + "+balance/" + m).c_str(), colour_benchmark, s, m, true, 0)
          ->Unit(benchmark::kMillisecond)->UseRealTime();
    }
    for (std::size_t per_part : {std::size_t(1024), std::size_t(4096), std::size_t(16384),
                                 std::size_t(65536), std::size_t(262144)})
      benchmark::RegisterBenchmark(
          ("coloring/metis/" + m + "/particles_per_part:" + std::to_string(per_part)).c_str(),
          metis_part_size_benchmark, m, per_part)
          ->Unit(benchmark::kMillisecond)->UseRealTime();
    for (int threads : {1, 2})
      benchmark::RegisterBenchmark(("coloring/random/" + m + "/threads:" + std::to_string(threads)).c_str(),
                                   colour_benchmark, std::string("random"), m, false, threads)
          ->Unit(benchmark::kMillisecond)->UseRealTime();
  }
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
