// The solver on many ranks (MPI), exact mode: every rank holds its part of the model (its
// owned particles, the ghosts its constraints read, the constraints it owns; decomposition.hpp)
// and runs the ordinary Solver on it in mode gs with the global colouring, exchanging after
// each colour the positions the decomposition's plan names. The final positions are bitwise
// those of one process running the same colouring, for any number of ranks and threads.
//
//   rank r, every iteration:   exchange colours [0, g0)            (receives only)
//                               project local colour 0 (= global g0), exchange [g0, g1)
//                               project local colour 1 (= global g1), exchange [g1, g2)
//                               ...                                  up to the last colour
//
// A rank with no constraint of global colour k still takes part in k's exchange: it may
// receive positions of its ghosts written in k. Time integration, λ resets and velocity
// updates run on owned and ghost particles alike: the same arithmetic on the same values
// gives the same bits, so ghosts need no exchange outside the colours.
//
// Collective: every rank constructs it with the same model, colouring and settings, and calls
// step(), residual() and gather_positions() together.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <mpi.h>

#include <tessera/coloring/colouring.hpp>
#include <tessera/core/model.hpp>
#include <tessera/distributed/decomposition.hpp>
#include <tessera/parallel/residual.hpp>
#include <tessera/parallel/solver.hpp>

namespace tessera {

/// What one rank holds and how much it exchanged (over all steps so far).
struct DistributedStatistics {
  std::size_t ranks = 0;
  std::size_t owned_particles = 0;
  std::size_t ghost_particles = 0;
  std::size_t constraints = 0;
  /// Messages and bytes this rank sent, and the wall time it spent in exchanges (posting,
  /// waiting, packing and unpacking).
  std::uint64_t messages_sent = 0;
  std::uint64_t bytes_sent = 0;
  double seconds_exchange = 0;
};

class DistributedSolver {
 public:
  /// Collective over `communicator`. settings.mode must be gs (exact mode follows the
  /// colours); the colouring must colour constraint_graph(model). Its particle renumbering,
  /// if any (metis, the locality pass), is one process's memory layout and is not used: each
  /// rank numbers what it holds in ascending global order, and no constraint's arithmetic
  /// depends on the numbering. Throws InvalidInput otherwise, or for what Solver refuses. settings.check_finite and the
  /// divergence bound are applied collectively after each step (step() throws
  /// NumericalFailure on every rank when any rank has a non-finite position).
  DistributedSolver(const Model& model, const Colouring& colouring, SolverSettings settings,
                    MPI_Comm communicator);

  /// One time step on every rank (collective).
  void step();
  /// The residual over every rank's constraints (collective; per family and overall, RMS and
  /// max; worst names a constraint of this rank's part only).
  Residual residual();
  /// Every particle's position in the model's numbering on rank 0, empty elsewhere
  /// (collective).
  std::vector<Vector3r> gather_positions();

  int rank() const { return rank_; }
  int rank_count() const { return rank_count_; }
  const DistributedStatistics& statistics() const { return statistics_; }
  /// This rank's solver and its particles' global ids (local particle i is held[i]).
  const Solver& local_solver() const { return *solver_; }
  const std::vector<ParticleIndex>& held_particles() const { return held_; }

 private:
  /// The exchanges of global colours [first, last).
  void exchange(std::size_t first, std::size_t last, ParticleArrays particles);

  struct Transfer {
    int rank;
    std::vector<std::uint32_t> local;  // local indices, in the plan's order
  };
  MPI_Comm communicator_;
  int rank_ = 0, rank_count_ = 1;
  bool check_finite_ = true;
  Real divergence_rms_;
  std::size_t colour_count_ = 0;
  std::vector<std::size_t> phase_colour_;  // global colour of local phase j
  std::vector<std::vector<Transfer>> sends_, receives_;  // per global colour
  std::vector<ParticleIndex> held_;                       // local → global
  std::vector<std::vector<ParticleIndex>> owned_of_rank_;  // rank 0's gather map
  std::vector<std::uint32_t> owned_local_;                 // this rank's owned, local indices
  std::unique_ptr<Solver> solver_;
  std::vector<Real> send_buffer_, receive_buffer_;
  std::vector<MPI_Request> requests_;
  DistributedStatistics statistics_;
};

}  // namespace tessera
