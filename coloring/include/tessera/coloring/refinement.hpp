// Post-passes that improve any valid colouring without breaking it: fewer colours
// (reduce_colours) and evenly sized colours (balance_colours).
#pragma once

#include <tessera/coloring/colouring.hpp>
#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/constraint_graph.hpp>

namespace tessera {

/// Lowers the colour count of a valid colouring; never raises it. Alternates
///  - iterated greedy (Culberson): recolour first-fit visiting whole colour classes in some
///    order (reverse, largest first, seeded shuffles); since each class is independent,
///    the i-th class visited never gets a colour above i, so the count cannot grow;
///  - colour elimination: move the constraints of the smallest colour into other colours,
///    directly when a colour is free at all their particles, or after moving the single
///    constraint that blocks a colour (a one-step Kempe-style exchange).
/// Stops at the graph's lower bound, after options.reduction_rounds rounds, or after 4 rounds
/// in a row that did not lower the count. Deterministic
/// for a given options.seed. The particle renumbering of `colouring`, if any, is kept.
Colouring reduce_colours(const ConstraintGraph& graph, const Colouring& colouring,
                         const ColouringOptions& options);

/// Evens out colour sizes without adding colours. Sweeps the constraints colour by colour and
/// moves a constraint when that lowers the sum of squared colour sizes: into the smallest
/// colour free at all its particles, or by ejection (into a colour b whose constraints at its
/// particles each move on to the smallest colour then free for them); when that stalls short
/// of balance, by Kempe swaps (a large colour and a smaller one exchange colours over a small
/// connected group of their constraints holding more of the large one). Stops once the
/// largest and smallest colours are within 0.5 % of the mean (at least 1 apart), when
/// progress stalls (a sweep moving under 0.1 % of the constraints, or 1/16 of a sweep under
/// 1 %), or when a work budget of a few sweeps' worth of candidate moves per phase is spent;
/// it may stop short of perfect balance (at the lower bound, colour sizes are often forced by
/// the mesh).
/// Single-threaded and deterministic. The particle renumbering of `colouring`, if any, is
/// kept, and so is the relative order of constraints in each colour.
Colouring balance_colours(const ConstraintGraph& graph, const Colouring& colouring);

}  // namespace tessera
