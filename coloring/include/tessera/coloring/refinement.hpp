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
/// Stops at the graph's lower bound or after options.reduction_rounds rounds. Deterministic
/// for a given options.seed. The particle renumbering of `colouring`, if any, is kept.
Colouring reduce_colours(const ConstraintGraph& graph, const Colouring& colouring,
                         const ColouringOptions& options);

/// Evens out colour sizes without adding colours: moves constraints from colours above the
/// mean into smaller colours free at all their particles, as long as each move shrinks the
/// gap between the two colours. Ends when no such move remains. The particle renumbering of
/// `colouring`, if any, is kept, and so is the relative order of constraints in each colour.
Colouring balance_colours(const ConstraintGraph& graph, const Colouring& colouring);

}  // namespace tessera
