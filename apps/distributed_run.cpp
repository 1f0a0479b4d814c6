// `tessera run --distributed exact|block` under mpirun: every rank loads the scene and colours it
// (the same answer everywhere), keeps its part (DistributedSolver), and steps it; rank 0
// gathers the positions, writes the frames and prints the summary. Failures are agreed on
// collectively, so that bad input on one rank ends every rank, with one line on stderr (the
// lowest failing rank's message, printed by rank 0) and the same exit code, never a hang.
#include "distributed_run.hpp"

#include <algorithm>
#include <chrono>
#include <functional>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <mpi.h>

#include <tessera/coloring/model_graph.hpp>
#include <tessera/coloring/run_colouring.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/fingerprint.hpp>
#include <tessera/distributed/agreement.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/io/scene_file.hpp>

#include "frame_output.hpp"
#include "progress_bar.hpp"
#include "solver_settings.hpp"
#include "summary.hpp"

namespace tessera::cli {
namespace {

/// MPI for the length of the command (initialised here unless the caller already did).
class MpiSession {
 public:
  MpiSession() {
    int initialised = 0;
    MPI_Initialized(&initialised);
    if (!initialised) {
      int provided = 0;
      // Only the calling thread talks to MPI (the solver's phase hook runs on it).
      MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
      owned_ = true;
    }
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  ~MpiSession() {
    if (owned_) MPI_Finalize();
  }
  int rank() const { return rank_; }
  int size() const { return size_; }

 private:
  bool owned_ = false;
  int rank_ = 0, size_ = 1;
};

/// The work on every rank, then the agreement on what failed (agreement.hpp).
template <class Work>
RankFailure agreed(const MpiSession&, Work&& work) {
  return run_agreed(MPI_COMM_WORLD, std::function<void()>(std::forward<Work>(work)));
}

/// Rank 0 prints the agreed failure; every rank returns its exit code once it has (mpirun
/// stops the job when the first rank exits with an error, which must not be before the line).
int end_with(const MpiSession& mpi, const RankFailure& failure) {
  if (mpi.rank() == 0) print_error("run", failure.message);
  MPI_Barrier(MPI_COMM_WORLD);
  return failure.code;
}

double max_over_ranks(double value) {
  double result = 0;
  MPI_Allreduce(&value, &result, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return result;
}

std::uint64_t sum_over_ranks(std::uint64_t value) {
  unsigned long long in = value, out = 0;
  MPI_Allreduce(&in, &out, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  return out;
}

}  // namespace

int run_distributed(const RunOptions& options, const std::function<RunSetup()>& setup) {
  const auto start = std::chrono::steady_clock::now();
  const MpiSession mpi;
  io::SceneDescription description;
  io::SimulationSettings simulation;
  SolverSettings settings;

  std::optional<io::Scene> scene;
  std::optional<ColouringRun> colouring;
  std::optional<DistributedSolver> solver;
  std::optional<FrameOutput> output;
  std::size_t colour_lower_bound = 0;
  double seconds_coloring = 0;
  RankFailure failure = agreed(mpi, [&] {
    RunSetup chosen = setup();
    description = std::move(chosen.description);
    simulation = std::move(chosen.simulation);
    settings = chosen.settings;
    if (options.distributed != "exact" && options.distributed != "block")
      throw InvalidInput("--distributed: unknown value '" + *options.distributed +
                         "' (known: exact, block)");
    if (settings.mode != SolverMode::gs)
      throw InvalidInput("--distributed " + *options.distributed + ": mode must be gs, not " +
                         std::string(solver_mode_name(settings.mode)));
    scene.emplace(io::build_scene(description));
    if (description.collisions.enabled())
      throw InvalidInput("--distributed: scene '" + description.name +
                         "' has collisions, which the distributed solver does not run");
    if (scene->model.constraints.size() == 0)
      throw InvalidInput("scene '" + description.name + "' has no constraints");
    const auto colouring_start = std::chrono::steady_clock::now();
    const ConstraintGraph graph = constraint_graph(scene->model);
    colour_lower_bound = graph.colour_lower_bound();
    const ColouringRegistry registry = ColouringRegistry::with_builtin_strategies();
    colouring.emplace(run_colouring(registry.get(simulation.strategy), graph,
                                    ColouringOptions{.balance = options.balance, .locality = true}));
    seconds_coloring = seconds_since(colouring_start);
    solver.emplace(scene->model, colouring->colouring, settings, MPI_COMM_WORLD,
                   options.distributed == "block" ? DistributedMode::block : DistributedMode::exact);
    if (options.out && mpi.rank() == 0)
      output.emplace(*options.out, *scene, &colouring->colouring, options.write_obj);
    if (mpi.rank() != 0) {  // the rank keeps its part only; rank 0 keeps the scene to report
      scene.reset();
      colouring.reset();
    }
  });
  if (failure.code != 0) return end_with(mpi, failure);

  Residual initial, final;
  failure = agreed(mpi, [&] {
    initial = solver->residual();
    std::optional<ProgressBar> progress;
    if (mpi.rank() == 0) progress.emplace(simulation.frames, "frames");
    if (options.out) {  // every rank gathers (collective), rank 0 writes
      const std::vector<Vector3r> positions = solver->gather_positions();
      if (output) output->write(0, 0.0, positions, {});
    }
    for (std::size_t frame = 1; frame <= simulation.frames; ++frame) {
      solver->step();
      if (options.out) {
        const std::vector<Vector3r> positions = solver->gather_positions();
        if (output) output->write(frame, double(frame) * double(simulation.time_step), positions, {});
      }
      if (progress) progress->update(frame);
    }
    final = solver->residual();
  });
  if (failure.code != 0) return end_with(mpi, failure);

  // Figures over the ranks: times are the slowest rank's, counts are sums.
  const SolverStatistics& local = solver->local_solver().statistics();
  const DistributedStatistics& exchange = solver->statistics();
  const double seconds_stepping = max_over_ranks(local.seconds_stepping);
  const double seconds_projection = max_over_ranks(local.seconds_projection);
  const double seconds_exchange = max_over_ranks(exchange.seconds_exchange);
  const std::uint64_t projections = sum_over_ranks(local.projections);
  const std::uint64_t messages = sum_over_ranks(exchange.messages_sent);
  const std::uint64_t bytes = sum_over_ranks(exchange.bytes_sent);
  std::vector<unsigned long long> ghosts(std::size_t(mpi.size()));
  const unsigned long long my_ghosts = exchange.ghost_particles;
  MPI_Gather(&my_ghosts, 1, MPI_UNSIGNED_LONG_LONG, ghosts.data(), 1, MPI_UNSIGNED_LONG_LONG, 0,
             MPI_COMM_WORLD);
  const std::vector<Vector3r> positions = solver->gather_positions();
  if (mpi.rank() != 0) return 0;

  const double sweeps =
      double(simulation.frames) * double(simulation.substeps) * double(simulation.iterations);
  Summary summary;
  summary.add("scene", description.name);
  summary.add("particles", scene->model.particles.size());
  summary.add("pinned", scene->pinned.size());
  summary.add("constraints", scene->model.constraints.size());
  summary.add("colours", colouring->statistics.colours);
  summary.add("colour_lower_bound", colour_lower_bound);
  summary.add("strategy", simulation.strategy);
  summary.add("mode", std::string(solver_mode_name(settings.mode)));
  summary.add("particle_layout", std::string(particle_layout_name(settings.particle_layout)));
  // Every rank sweeps colour by colour (DistributedSolver).
  summary.add("sweep_order", std::string(sweep_order_name(SweepOrder::colour_major)));
  summary.add("distributed", *options.distributed);
  summary.add("ranks", mpi.size());
  summary.add("threads", local.threads);
  summary.add("frames", simulation.frames);
  summary.add("substeps", simulation.substeps);
  summary.add("iterations", simulation.iterations);
  summary.add("time_step", double(simulation.time_step));
  summary.add("seconds_coloring", seconds_coloring);
  summary.add("seconds_stepping", seconds_stepping);
  summary.add("seconds_projection", seconds_projection);
  summary.add("seconds_exchange", seconds_exchange);
  summary.add("exchange_share", seconds_stepping > 0 ? seconds_exchange / seconds_stepping : 0.0);
  summary.add("projections", projections);
  summary.add("projections_per_second",
              seconds_stepping > 0 ? double(projections) / seconds_stepping : 0.0);
  summary.add("ghost_particles", ghosts);
  summary.add("messages_per_iteration", sweeps > 0 ? double(messages) / sweeps : 0.0);
  summary.add("bytes_per_iteration", sweeps > 0 ? double(bytes) / sweeps : 0.0);
  add_residuals(summary, initial, final);
  summary.add("state_hash", state_hash(positions));
  if (output) {
    summary.add("output", output->folder().string());
    summary.add("files_written", output->files_written());
  }
  summary.add("seconds_total", seconds_since(start));
  summary.print(std::cout, options.json);
  return 0;
}

}  // namespace tessera::cli
