// chebyshev_report: iterations to a residual, plain Jacobi against Chebyshev-accelerated
// Jacobi (SolverSettings::chebyshev), over a sweep of ρ and delays; the measurement behind
// the setting's default (see solver.hpp).
//
//   chebyshev_report [--cloth N] [--bar n] [--iterations K] [--rho R,R,...]
//                    [--delay S,S,...] [--mode jacobi|hybrid] [--relaxation W]
//                    [--substeps S] [--threads T] [--scene cloth|bar|both] [--frames F]
//
// Scenes as in convergence_report: an N×N cloth (N = 256) pinned at two corners (distance +
// dihedral; measure: the distance constraints' RMS residual, since the compliant bending's
// angle error is the drape), and an n×n×4n-cell FEM bar (n = 12, E = 10⁶; measure: the RMS
// residual of all constraints). Each is stepped 10 times by gs, then from that state every
// run takes one step (of `substeps` substeps, 1 by default) of K iterations (256) with
// record_convergence. Targets: the measure plain Jacobi reaches after 32 iterations, after
// 128, and after K. Printed per run: the iterations each target takes (or "-" if not within
// K), the measure after 32 and after K iterations. With --frames F instead: F steps from rest
// of `substeps` × K, and the measure (RMS and max) at the end, or "diverged" (a non-finite
// value or an RMS residual above 10): whether the acceleration stays stable over a run.
#include <cstdlib>
#include <exception>
#include <iostream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <tessera/core/error.hpp>
#include <tessera/parallel/solver.hpp>

#include "scenes.hpp"

namespace {

using namespace tessera;

struct Options {
  std::size_t cloth = 256, bar = 12, iterations = 256, substeps = 1, threads = 0, frames = 0;
  std::vector<double> rhos = {0.5, 0.7, 0.8, 0.85, 0.9, 0.95, 0.98, 0.99};
  std::vector<std::size_t> delays = {1, 2, 4};
  SolverMode mode = SolverMode::jacobi;
  Real relaxation = kDefaultJacobiRelaxation;
  std::string scene = "both";
};

[[noreturn]] void usage_error(const std::string& message) {
  std::cerr << "chebyshev_report: " << message << "\n";
  std::exit(2);
}

template <class T>
std::vector<T> list(const std::string& text) {
  std::vector<T> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) values.push_back(T(std::stod(item)));
  return values;
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (i + 1 >= argc) usage_error(std::string(arg) + " needs a value");
    const std::string value = argv[++i];
    if (arg == "--cloth") o.cloth = std::stoul(value);
    else if (arg == "--bar") o.bar = std::stoul(value);
    else if (arg == "--iterations") o.iterations = std::stoul(value);
    else if (arg == "--substeps") o.substeps = std::stoul(value);
    else if (arg == "--threads") o.threads = std::stoul(value);
    else if (arg == "--frames") o.frames = std::stoul(value);
    else if (arg == "--rho") o.rhos = list<double>(value);
    else if (arg == "--delay") o.delays = list<std::size_t>(value);
    else if (arg == "--relaxation") o.relaxation = Real(std::stod(value));
    else if (arg == "--scene") o.scene = value;
    else if (arg == "--mode") o.mode = value == "hybrid" ? SolverMode::hybrid : SolverMode::jacobi;
    else usage_error("unknown option '" + std::string(arg) + "'");
  }
  return o;
}

struct State {
  std::vector<Vector3r> positions, velocities;
};

State warm_up(const Model& model, std::size_t steps, std::size_t threads) {
  SolverSettings settings;
  settings.threads = threads;
  settings.report_residuals = false;
  Solver solver(model, test::colour_model(model, "greedy"), settings);
  for (std::size_t s = 0; s < steps; ++s) solver.step();
  return {solver.positions(), solver.velocities()};
}

/// The measure after 0…K iterations of one step from `start`.
std::vector<double> history(const Model& model, const Colouring& colouring, const State& start,
                            const Options& o, bool chebyshev, double rho, std::size_t delay,
                            bool distance_measure) {
  SolverSettings settings;
  settings.mode = o.mode;
  settings.threads = o.threads;
  settings.iterations = o.iterations;
  settings.substeps = o.substeps;
  settings.jacobi_relaxation = o.relaxation;
  settings.record_convergence = true;
  settings.chebyshev = chebyshev;
  settings.chebyshev_rho = Real(rho);
  settings.chebyshev_delay = delay;
  Solver solver(model, colouring, settings);
  for (std::size_t p = 0; p < start.positions.size(); ++p) {
    solver.set_position(ParticleIndex(p), start.positions[p]);
    solver.set_velocity(ParticleIndex(p), start.velocities[p]);
  }
  std::vector<double> measure;
  try {
    solver.step();
  } catch (const NumericalFailure&) {
    return measure;  // diverged
  }
  for (const Residual& r : solver.last_step().history)
    measure.push_back(distance_measure ? r.of(ConstraintFamily::distance).rms : r.rms);
  return measure;
}

/// --frames F: F steps from rest; the measure (rms, max) at the end, or "diverged" (not
/// finite, or an RMS residual above 10).
void long_run(const char* name, const Model& model, bool distance_measure, const Options& o) {
  const Colouring colouring = test::colour_model(model, "greedy");
  std::cout << "# " << name << ": " << o.frames << " frames of " << o.substeps << " x "
            << o.iterations << ", relaxation " << o.relaxation << "\nrun\trho\tdelay\trms\tmax\n";
  const auto run = [&](bool chebyshev, double rho, std::size_t delay) {
    SolverSettings settings;
    settings.mode = o.mode;
    settings.threads = o.threads;
    settings.iterations = o.iterations;
    settings.substeps = o.substeps;
    settings.jacobi_relaxation = o.relaxation;
    settings.chebyshev = chebyshev;
    settings.chebyshev_rho = Real(rho);
    settings.chebyshev_delay = delay;
    Solver solver(model, colouring, settings);
    std::cout << (chebyshev ? "chebyshev" : "plain") << "\t" << rho << "\t" << delay << "\t";
    try {
      for (std::size_t f = 0; f < o.frames; ++f) {
        solver.step();
        const Residual r = solver.last_step().residual_after;
        if (!(r.rms <= 10)) throw NumericalFailure("diverged");
      }
    } catch (const NumericalFailure&) {
      std::cout << "diverged\n" << std::flush;
      return;
    }
    const Residual r = solver.last_step().residual_after;
    const FamilyResidual d = r.of(ConstraintFamily::distance);
    std::cout << (distance_measure ? d.rms : r.rms) << "\t" << (distance_measure ? d.max : r.max)
              << "\n" << std::flush;
  };
  run(false, 0.5, 1);
  for (const std::size_t delay : o.delays)
    for (const double rho : o.rhos) run(true, rho, delay);
}

std::string iterations_to(const std::vector<double>& measure, double target) {
  for (std::size_t k = 0; k < measure.size(); ++k)
    if (measure[k] <= target) return std::to_string(k);
  return "-";
}

void report(const char* name, const Model& model, bool distance_measure, const Options& o) {
  const State start = warm_up(model, 10, o.threads);
  const Colouring colouring = test::colour_model(model, "greedy");
  const std::size_t K = o.iterations;
  const std::vector<double> plain =
      history(model, colouring, start, o, false, 0.5, 1, distance_measure);
  const double t32 = plain.at(std::min<std::size_t>(32, K)), t128 = plain.at(std::min<std::size_t>(128, K)),
               tK = plain.at(K);
  std::cout << "# " << name << ": " << model.particles.size() << " particles, "
            << model.constraints.size() << " constraints, mode "
            << solver_mode_name(o.mode) << ", relaxation " << o.relaxation << ", substeps "
            << o.substeps << "; measure " << (distance_measure ? "rms_distance" : "rms")
            << " initial " << plain.at(0) << "\n# targets: plain@32 " << t32 << ", plain@128 "
            << t128 << ", plain@" << K << " " << tK << "\n";
  std::cout << "run\trho\tdelay\tto_plain32\tto_plain128\tto_plain" << K << "\tat32\tat" << K
            << "\n";
  const auto line = [&](const std::string& run, double rho, std::size_t delay,
                        const std::vector<double>& m) {
    std::cout << run << "\t" << rho << "\t" << delay << "\t";
    if (m.empty()) {
      std::cout << "diverged\n";
      return;
    }
    std::cout << iterations_to(m, t32) << "\t" << iterations_to(m, t128) << "\t"
              << iterations_to(m, tK) << "\t" << m.at(std::min<std::size_t>(32, K)) << "\t" << m.at(K) << "\n";
  };
  line("plain", 0, 0, plain);
  for (const std::size_t delay : o.delays)
    for (const double rho : o.rhos)
      line("chebyshev", rho, delay,
           history(model, colouring, start, o, true, rho, delay, distance_measure));
  std::cout << std::flush;
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  try {
    if (o.frames != 0) {
      if (o.scene != "bar") long_run("cloth", test::cloth_model(o.cloth, o.cloth), true, o);
      if (o.scene != "cloth")
        long_run("bar",
                 test::tet_bar_model(o.bar, o.bar, 4 * o.bar, test::BarMaterial::fem_tetra,
                                     Real(1e6)),
                 false, o);
      return 0;
    }
    if (o.scene != "bar")
      report("cloth", test::cloth_model(o.cloth, o.cloth), true, o);
    if (o.scene != "cloth")
      report("bar",
             test::tet_bar_model(o.bar, o.bar, 4 * o.bar, test::BarMaterial::fem_tetra, Real(1e6)),
             false, o);
  } catch (const std::exception& error) {
    std::cerr << "chebyshev_report: " << error.what() << "\n";
    return 1;
  }
  return 0;
}
