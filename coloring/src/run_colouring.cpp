// run_colouring: the strategy, then reduce, balance and locality in that order when asked,
// each post-pass adding its name to the strategy's; the clock covers all of them.
#include <tessera/coloring/run_colouring.hpp>

#include <chrono>
#include <string>
#include <utility>

#include <tessera/coloring/locality.hpp>
#include <tessera/coloring/refinement.hpp>

namespace tessera {

ColouringRun run_colouring(const ColouringStrategy& strategy, const ConstraintGraph& graph,
                           const ColouringOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  Colouring colouring = strategy.colour(graph, options);
  std::string name(strategy.name());
  if (options.reduce) {
    colouring = reduce_colours(graph, colouring, options);
    name += "+reduce";
  }
  if (options.balance) {
    colouring = balance_colours(graph, colouring);
    name += "+balance";
  }
  if (options.locality) {
    colouring = improve_locality(graph, colouring);
    name += "+locality";
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ColouringStatistics statistics = compute_statistics(graph, colouring, std::move(name), seconds);
  return {std::move(colouring), std::move(statistics)};
}

}  // namespace tessera
