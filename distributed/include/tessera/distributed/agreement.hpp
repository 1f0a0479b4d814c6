// Failing together: a piece of work that any rank may fail (bad input it alone sees, a file
// it alone cannot read) is followed by one agreement, so that every rank learns the same
// failure and stops, instead of the others waiting forever in their next collective call.
//
//   rank 0: work ✓ ─┐                       ┌─ failure {2, "mesh.obj: no such file"}
//   rank 1: work ✗ ─┼─ MPI_Allreduce (min) ─┼─ failure {2, "mesh.obj: no such file"}
//   rank 2: work ✓ ─┘   + MPI_Bcast message └─ failure {2, "mesh.obj: no such file"}
#pragma once

#include <functional>
#include <string>

#include <mpi.h>

namespace tessera {

/// What failed: an exit code (0 nothing, 2 bad input: InvalidInput, 1 anything else) and the
/// message.
struct RankFailure {
  int code = 0;
  std::string message;
};

/// Runs `work` on this rank, catching what it throws, then agrees over `communicator`
/// (collective): every rank returns the failure of the lowest-numbered rank that failed, or
/// {0, ""} when none did.
RankFailure run_agreed(MPI_Comm communicator, const std::function<void()>& work);

}  // namespace tessera
