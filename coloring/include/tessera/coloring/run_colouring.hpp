// One colouring run, as the tool, the benchmarks and an embedder do it: a strategy, then the
// post-passes the options ask for (reduce, balance, locality), timed as a whole and checked
// with validate(), so what comes back is a colouring together with its statistics.
#pragma once

#include <tessera/coloring/colouring.hpp>
#include <tessera/coloring/colouring_statistics.hpp>
#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/constraint_graph.hpp>

namespace tessera {

/// A colouring and its statistics.
struct ColouringRun {
  Colouring colouring;
  ColouringStatistics statistics;
};

/// Runs `strategy`, then the post-passes the options ask for (reduce, balance, locality), timing
/// the whole and validating the result. The strategy name in the statistics says which passes
/// ran ("stencil+balance+locality").
ColouringRun run_colouring(const ColouringStrategy& strategy, const ConstraintGraph& graph,
                           const ColouringOptions& options = {});

}  // namespace tessera
