// `tessera run --distributed MODE`: the run command on many ranks (built with TESSERA_MPI).
#pragma once

#include <functional>

#include <tessera/io/scene_description.hpp>
#include <tessera/parallel/solver.hpp>

#include "commands.hpp"

namespace tessera::cli {

/// The scene and settings a run uses, from its options.
struct RunSetup {
  io::SceneDescription description;
  io::SimulationSettings simulation;
  SolverSettings settings;
};

/// Runs the scene `setup()` describes (called on every rank: it checks the options) with
/// DistributedSolver on MPI_COMM_WORLD, initialising MPI if needed, and prints the summary on
/// rank 0. Returns the exit code: on a failure agreed over the ranks, rank 0 prints its one
/// line and every rank returns its code (2 for bad input, 1 otherwise).
int run_distributed(const RunOptions& options, const std::function<RunSetup()>& setup);

}  // namespace tessera::cli
