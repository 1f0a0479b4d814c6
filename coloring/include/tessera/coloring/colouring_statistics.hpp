// Measuring and checking a colouring: sizes, balance, distance from the lower bound, time,
// and validate(), the check that no two constraints of one colour share a movable particle.
// Running a strategy and measuring its result in one call is run_colouring.hpp.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <tessera/coloring/colouring.hpp>
#include <tessera/coloring/constraint_graph.hpp>

namespace tessera {

/// Outcome of validate(): valid, or the first problem found, in words.
struct ColouringValidation {
  bool valid = true;
  std::string problem;
  explicit operator bool() const { return valid; }
};

/// Checks that `colouring` fits `graph` (one colour per constraint, each constraint listed
/// once and in its own colour, a particle permutation of the right size if any) and that no
/// two constraints of one colour share a movable particle. Linear in the incidences (a particle
/// of 64 colours or more: n log n in its constraints), in parallel; builds the graph's
/// particle → constraint direction if it was not built yet. Of several problems it names the
/// same one whatever the thread count (empty colours, then ids out of range, constraints
/// listed twice, constraints in the wrong list, then the lowest particle two constraints of one
/// colour share).
ColouringValidation validate(const ConstraintGraph& graph, const Colouring& colouring);

/// What a colouring looks like, ready to print or compare.
struct ColouringStatistics {
  std::string strategy;
  std::size_t constraints = 0;
  std::size_t colours = 0;
  std::vector<std::size_t> sizes;  ///< constraints per colour
  std::size_t largest = 0;
  std::size_t smallest = 0;
  double mean = 0;
  double balance = 0;         ///< largest / mean (1 is perfect)
  double size_ratio = 0;      ///< largest / smallest
  std::size_t lower_bound = 0;  ///< most constraints meeting at one movable particle
  double colours_per_lower_bound = 0;
  double seconds = 0;         ///< time taken by the strategy and post-passes
  bool valid = false;
  std::string problem;        ///< validate()'s message when not valid
};

ColouringStatistics compute_statistics(const ConstraintGraph& graph, const Colouring& colouring,
                                       std::string strategy = {}, double seconds = 0);

/// "key: value" lines (strategy, constraints, colours, sizes, largest, ...), for tools.
std::string format_statistics(const ColouringStatistics& statistics);

}  // namespace tessera
