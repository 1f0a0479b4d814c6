// io::SimulationSettings → SolverSettings (see solver_settings.hpp).
#include "solver_settings.hpp"

namespace tessera::cli {

SolverSettings solver_settings(const io::SimulationSettings& simulation) {
  SolverSettings settings;
  settings.mode = parse_solver_mode(simulation.mode);
  settings.threads = simulation.threads;
  settings.time_step = simulation.time_step;
  settings.substeps = simulation.substeps;
  settings.iterations = simulation.iterations;
  settings.gravity = simulation.gravity;
  settings.velocity_damping = simulation.velocity_damping;
  settings.sequential_order = parse_sequential_order(simulation.sequential_order);
  settings.divergence_rms = simulation.divergence_rms;
  if (simulation.chebyshev) settings.chebyshev = *simulation.chebyshev;
  if (simulation.chebyshev_rho) settings.chebyshev_rho = *simulation.chebyshev_rho;
  return settings;
}

}  // namespace tessera::cli
