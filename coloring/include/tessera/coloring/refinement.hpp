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

/// Evens out colour sizes without adding colours. Moves constraints from colours above the
/// mean into the smallest colour free at all their particles when that narrows the gap;
/// then also by ejection (c takes colour b from its single blocker there, which moves to a
/// smaller colour free for it); then swaps two colours along short Kempe chains (at most 48
/// constraints) that move constraints into one of the 3 smallest colours below the mean.
/// Sweeps are capped at 32 and all neighbourhood scans together at 6 visits per incidence, so
/// the pass costs a bounded number of graph sweeps whatever the input; it may stop short of
/// perfect balance (at the lower bound, colour sizes are often forced). The particle
/// renumbering of `colouring`, if any, is kept, and so is the relative order of constraints
/// in each colour.
Colouring balance_colours(const ConstraintGraph& graph, const Colouring& colouring);

}  // namespace tessera
