// Failing together (agreement.hpp): one reduction to find the lowest failing rank, two
// broadcasts to share its code and message.
#include <tessera/distributed/agreement.hpp>

#include <exception>

#include <tessera/core/error.hpp>

namespace tessera {

RankFailure run_agreed(MPI_Comm communicator, const std::function<void()>& work) {
  int rank = 0, size = 1;
  MPI_Comm_rank(communicator, &rank);
  MPI_Comm_size(communicator, &size);
  RankFailure mine;
  try {
    work();
  } catch (const InvalidInput& error) {
    mine = {2, error.what()};
  } catch (const std::exception& error) {
    mine = {1, error.what()};
  }
  int failing = mine.code != 0 ? rank : size;
  int first = size;
  MPI_Allreduce(&failing, &first, 1, MPI_INT, MPI_MIN, communicator);
  if (first == size) return {};
  int header[2] = {mine.code, int(mine.message.size())};
  MPI_Bcast(header, 2, MPI_INT, first, communicator);
  std::string message(std::size_t(header[1]), ' ');
  if (rank == first) message = mine.message;
  MPI_Bcast(message.data(), header[1], MPI_CHAR, first, communicator);
  return {header[0], std::move(message)};
}

}  // namespace tessera
