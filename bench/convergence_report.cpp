// convergence_report: the residual after every iteration of one time step, per solver mode
// and per colouring strategy, as JSON for the convergence plot of scripts/bench.
//
//   convergence_report [--quick] [--out FILE] [--cloth N] [--bar n] [--iterations K]
//                      [--warmup-steps S]
//
// Scenes: "cloth", an N×N cloth pinned at two corners (distance + dihedral, N = 128; 48 with
// --quick), and "bar", an n×n×4n-cell FEM tetrahedral bar fixed at one end (E = 10⁶; n = 12;
// 6 with --quick), both from the tests' scene builders. Each scene is first stepped S times (10) by
// gs so it is deformed and moving; from that same state every run takes one step of K
// iterations (100; 40 with --quick) with record_convergence set and reports
// last_step().history: the normalised residual (rms and max over all constraints) after 0…K
// iterations. Runs: modes gs, hybrid, jacobi, sequential (gs, hybrid and jacobi coloured by
// greedy), and gs under each built-in colouring strategy. Single thread: the positions do not
// depend on the thread count.
//
// Output (stdout, or FILE):
//   {"iterations": K, …, "scenes": {"cloth": {"measure": "rms_distance", "particles": …,
//     "constraints": …, "modes": {"gs": {"rms": [...], "max": [...], "rms_distance": [...],
//     "rms_dihedral": [...]}, …}, "strategies": {"greedy": {…}, …}}, "bar": {…}}}
// "measure" is the series the plot shows: for the cloth the distance constraints' residual
// (relative length error; they are inextensible, so it should go to 0, while the compliant
// bending's angle error is the drape itself), for the FEM bar (E = 10⁶, as tetbar200k) the
// residual of all its constraints (Green strain).
#include <cmath>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/parallel/solver.hpp>

#include "scenes.hpp"

namespace {

using namespace tessera;

/// The bar of the solver benchmarks (tetbar200k): stiff enough that its equilibrium strain
/// is small, so the residual shows how far the iterations are from it.
constexpr Real kBarYoungsModulus = Real(1e6);

struct Options {
  bool quick = false;
  std::string out;
  std::size_t cloth = 0;
  std::size_t bar = 0;
  std::size_t iterations = 0;
  std::size_t warmup_steps = 10;
};

[[noreturn]] void usage_error(const std::string& message) {
  std::cerr << "convergence_report: " << message << "\n";
  std::exit(2);
}

Options parse(int argc, char** argv) {
  Options options;
  auto count = [&](int& i) -> std::size_t {
    if (i + 1 >= argc) usage_error(std::string(argv[i]) + " needs a number");
    const std::string text = argv[++i];
    char* end = nullptr;
    const unsigned long value = std::strtoul(text.c_str(), &end, 10);
    if (text.empty() || *end != '\0' || value == 0) usage_error("not a positive count: " + text);
    return std::size_t(value);
  };
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (arg == "--quick") options.quick = true;
    else if (arg == "--out") {
      if (i + 1 >= argc) usage_error("--out needs a file");
      options.out = argv[++i];
    } else if (arg == "--cloth") options.cloth = count(i);
    else if (arg == "--bar") options.bar = count(i);
    else if (arg == "--iterations") options.iterations = count(i);
    else if (arg == "--warmup-steps") options.warmup_steps = count(i);
    else usage_error("unknown option '" + std::string(arg) + "'");
  }
  if (options.cloth == 0) options.cloth = options.quick ? 48 : 128;
  if (options.bar == 0) options.bar = options.quick ? 6 : 12;
  if (options.iterations == 0) options.iterations = options.quick ? 40 : 100;
  return options;
}

struct State {
  std::vector<Vector3r> positions, velocities;
};

/// The state after `steps` gs steps of the default settings (10 iterations).
State warm_up(const Model& model, std::size_t steps) {
  SolverSettings settings;
  settings.threads = 1;
  settings.report_residuals = false;
  Solver solver(model, test::colour_model(model, "greedy"), settings);
  for (std::size_t s = 0; s < steps; ++s) solver.step();
  return {solver.positions(), solver.velocities()};
}

/// JSON has no NaN or infinity: a diverged run's residual is written as null.
std::string json_number(double value) {
  if (!std::isfinite(value)) return "null";
  std::ostringstream text;
  text.precision(9);
  text << value;
  return text.str();
}

/// One recorded step from `start`: {"rms": [...], "max": [...], "rms_<family>": [...] for
/// every family of the model}.
std::string recorded_step(const Model& model, const State& start, SolverMode mode,
                          const char* strategy, std::size_t iterations) {
  SolverSettings settings;
  settings.mode = mode;
  settings.threads = 1;
  settings.iterations = iterations;
  settings.record_convergence = true;
  Solver solver = mode == SolverMode::sequential
                      ? Solver(model, settings)
                      : Solver(model, test::colour_model(model, strategy), settings);
  for (std::size_t p = 0; p < start.positions.size(); ++p) {
    solver.set_position(ParticleIndex(p), start.positions[p]);
    solver.set_velocity(ParticleIndex(p), start.velocities[p]);
  }
  solver.step();
  const std::vector<Residual>& history = solver.last_step().history;
  auto series = [&](const std::string& key, auto&& value) {
    std::string text = "\"" + key + "\": [";
    const char* separator = "";
    for (const Residual& residual : history) {
      text += separator + json_number(value(residual));
      separator = ", ";
    }
    return text + "]";
  };
  std::string json = "{" + series("rms", [](const Residual& r) { return r.rms; }) + ", " +
                     series("max", [](const Residual& r) { return r.max; });
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f) {
    if (history.empty() || history.front().families[f].constraints == 0) continue;
    const std::string family(family_name(ConstraintFamily(f)));
    json += ", " + series("rms_" + family, [f](const Residual& r) { return r.families[f].rms; });
  }
  return json + "}";
}

/// `measure` names the series the plot shows for this scene.
std::string scene_report(const Model& model, const char* measure, const Options& options) {
  const State start = warm_up(model, options.warmup_steps);
  std::ostringstream json;
  json << "{\"measure\": \"" << measure << "\", \"particles\": " << model.particles.size()
       << ", \"constraints\": " << model.constraints.size() << ",\n    \"modes\": {";
  const char* separator = "";
  for (const SolverMode mode :
       {SolverMode::gs, SolverMode::hybrid, SolverMode::jacobi, SolverMode::sequential}) {
    json << separator << "\n      \"" << solver_mode_name(mode)
         << "\": " << recorded_step(model, start, mode, "greedy", options.iterations);
    separator = ",";
  }
  json << "},\n    \"strategies\": {";
  separator = "";
  for (const std::string_view strategy : ColouringRegistry::with_builtin_strategies().names()) {
    const std::string name(strategy);
    json << separator << "\n      \"" << name << "\": "
         << recorded_step(model, start, SolverMode::gs, name.c_str(), options.iterations);
    separator = ",";
  }
  json << "}}";
  return json.str();
}

}  // namespace

int main(int argc, char** argv) {
  const Options options = parse(argc, argv);
  try {
    const Model cloth = test::cloth_model(options.cloth, options.cloth);
    const Model bar = test::tet_bar_model(options.bar, options.bar, 4 * options.bar,
                                          test::BarMaterial::fem_tetra, kBarYoungsModulus);
    std::ostringstream json;
    json << "{\"iterations\": " << options.iterations
         << ", \"warmup_steps\": " << options.warmup_steps << ", \"cloth_size\": "
         << options.cloth << ", \"bar_size\": " << options.bar << ",\n  \"scenes\": {\n  \"cloth\": "
         << scene_report(cloth, "rms_distance", options)
         << ",\n  \"bar\": " << scene_report(bar, "rms", options)
         << "}}\n";
    if (options.out.empty()) {
      std::cout << json.str();
    } else {
      std::ofstream file(options.out);
      file << json.str();
      if (!file) {
        std::cerr << "convergence_report: cannot write " << options.out << "\n";
        return 1;
      }
    }
  } catch (const std::exception& error) {
    std::cerr << "convergence_report: " << error.what() << "\n";
    return 1;
  }
  return 0;
}
