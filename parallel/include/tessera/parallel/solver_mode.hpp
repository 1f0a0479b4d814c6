// How the solver projects the constraints each iteration: the modes, their names, and the
// stages each one runs (stage.hpp). A mode is a choice of layout (what the schedule colours,
// what goes to a Jacobi set) plus the stage list built from it; adding one means a value here
// and one stage-list builder (Schedule::build_stages).
#pragma once

#include <cstdint>
#include <span>
#include <string_view>

namespace tessera {

enum class SolverMode : std::uint8_t {
  /// Coloured Gauss–Seidel: colour after colour, each colour in parallel.
  gs,
  /// Jacobi with constraint averaging: every constraint from the same positions, then
  /// x += ω · (sum of corrections) / (count) per particle.
  jacobi,
  /// gs for the colours with at least hybrid_threshold constraints, one Jacobi phase for the
  /// smaller ones after them.
  hybrid,
  /// The classic PBD loop and reference: one thread, constraints in input order (family by
  /// family), the scalar API per constraint; no colouring.
  sequential,
};

/// Every mode, in declaration order.
inline constexpr SolverMode kSolverModes[] = {SolverMode::gs, SolverMode::jacobi,
                                              SolverMode::hybrid, SolverMode::sequential};

/// "gs", "jacobi", "hybrid", "sequential".
std::string_view solver_mode_name(SolverMode mode);
/// The mode of that name; throws InvalidInput listing the names for any other.
SolverMode parse_solver_mode(std::string_view name);

}  // namespace tessera
