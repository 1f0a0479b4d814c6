// The solver on many ranks (MPI), exact mode: every rank holds its part of the model (its
// owned particles, the ghosts its constraints read, the constraints it owns; decomposition.hpp)
// and runs the ordinary Solver on it in mode gs with the global colouring, exchanging after
// each colour the positions the decomposition's plan names. The final positions are bitwise
// those of one process running the same colouring, for any number of ranks and threads.
//
//   rank r, every iteration, for each global colour k in order:
//     project k's boundary constraints (those writing a particle another rank holds)
//     post k's receives and sends (non-blocking)
//     project k's interior constraints while the messages travel
//     wait, and copy the received positions in
//
// Each part is a colour of the rank's own Solver (a part of a colour is conflict-free too),
// and the exchange runs from its phase hook. The interior cannot read what colour k brings:
// a particle written in k by another rank's constraint is in no other constraint of k.
//
// A rank with no constraint of global colour k still takes part in k's exchange: it may
// receive positions of its ghosts written in k. Time integration, λ resets and velocity
// updates run on owned and ghost particles alike: the same arithmetic on the same values
// gives the same bits, so ghosts need no exchange outside the colours.
//
// Block mode instead exchanges once per iteration: each rank sweeps all its colours on its own
// (Gauss–Seidel inside its part), then a particle that several ranks' constraints moved gets
// the mean of their corrections: the ghost holders send their corrections to the owner, which
// adds them to its own in rank order and sends the result back (block Jacobi across the
// ranks, additive Schwarz with one layer of overlap). Two rounds per iteration instead of one
// per colour; deterministic for a given rank count, but not the same answer for every count
// (one rank gives exact mode's answer). docs/distributed.md measures what it costs in
// convergence.
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

/// How the ranks meet: after every colour (exact) or after every iteration (block).
enum class DistributedMode { exact, block };

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
  /// Collective over `communicator`. settings.mode must be gs (exact mode follows the colours); the
  /// colouring must colour constraint_graph(model). Its particle renumbering, if any (metis,
  /// blocks, the locality pass), is one process's memory layout and is not used: each rank numbers
  /// what it holds in ascending global order, and no constraint's arithmetic depends on the
  /// numbering. Throws InvalidInput otherwise, or for what Solver refuses. settings.check_finite
  /// and the divergence bound are applied collectively after each step (step() throws
  /// NumericalFailure on every rank when any rank has a non-finite position). Each rank
  /// sweeps colour by colour (its ghosts are exchanged between colours): SweepOrder::automatic
  /// becomes colour_major, with particles_per_part dropped; part_major is refused.
  DistributedSolver(const Model& model, const Colouring& colouring, SolverSettings settings,
                    MPI_Comm communicator, DistributedMode mode = DistributedMode::exact);

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
  struct Transfer {
    int rank;
    std::vector<std::uint32_t> local;  // local indices, in the plan's order
  };
  /// Exact mode: posts colour k's receives and sends, and completes them.
  void start_exchange(std::size_t k, ParticleArrays particles);
  void finish_exchange(ParticleArrays particles);
  /// The exchanges after local phase `phase` (or before the first: Solver::kBeforePhases).
  void exchange_after(std::size_t phase, ParticleArrays particles);
  /// Block mode: the positions of the shared particles at the start of the iteration, and the
  /// two rounds at its end (corrections to the owners, means back to the holders).
  void remember_shared(ParticleArrays particles);
  void combine_shared(ParticleArrays particles);
  /// Posts the sends of `sends` from `send_values` (3 reals per particle, in list order) and
  /// the receives of `receives` into receive_buffer_ (requests_); send_and_receive also waits.
  void post(const std::vector<Transfer>& sends, const std::vector<Real>& send_values,
            const std::vector<Transfer>& receives, int tag);
  void send_and_receive(const std::vector<Transfer>& sends,
                        const std::vector<Real>& send_values,
                        const std::vector<Transfer>& receives, int tag);

  MPI_Comm communicator_;
  DistributedMode mode_;
  int rank_ = 0, rank_count_ = 1;
  bool check_finite_ = true;
  Real divergence_rms_;
  std::size_t colour_count_ = 0;
  struct Phase {
    std::size_t colour;  // global colour
    bool boundary;       // its constraints write particles other ranks hold
  };
  std::vector<Phase> phases_;             // the rank's Solver's colours, in order
  std::size_t open_colour_;               // the colour whose exchange is in flight, or npos
  std::vector<std::vector<Transfer>> sends_, receives_;  // per global colour
  std::vector<ParticleIndex> held_;                       // local → global
  std::vector<std::vector<ParticleIndex>> owned_of_rank_;  // rank 0's gather map
  std::vector<std::uint32_t> owned_local_;                 // this rank's owned, local indices
  std::unique_ptr<Solver> solver_;
  std::vector<Real> send_buffer_, receive_buffer_;
  // Block mode: my movable ghosts by owner (corrections out, means in), my owned particles
  // that others hold by holder (corrections in, means out; ascending holder rank), the owned
  // shared particles' accumulator slots and 1 / (ranks that move them).
  std::vector<Transfer> ghosts_by_owner_, shared_by_holder_;
  std::vector<std::uint32_t> shared_owned_;                    // local indices
  std::vector<std::vector<std::uint32_t>> holder_slot_;        // per holder group: accumulator slot
  std::vector<Real> shared_weight_;                            // per slot
  std::vector<std::uint32_t> remembered_;                      // local indices of all shared
  std::vector<Real> start_;                                    // their positions, 3 per particle
  std::vector<Real> values_;
  std::vector<MPI_Request> requests_;
  DistributedStatistics statistics_;
};

}  // namespace tessera
