// Residuals: how far the constraints are from satisfied, normalised per family so that
// families and scenes compare (the measure of each family is documented with
// tessera::constraint_residual in <tessera/core/constraint_residual.hpp>: relative length or
// volume error, angle error in radians, Green strain norm, ...).
//
// A compliant constraint is not meant to be satisfied: a cloth folds against its bending
// compliance. What an XPBD solve leaves undone is the residual of the equation it solves,
// C(x) + α̃λ = 0 (Macklin, Müller, Chentanez 2016, eq. 11), so under compliance semantics the
// solver measures that for every family with an XPBD form (xpbd_residuals, in the same units
// as the family's violation); for a hard constraint (α = 0) it is the violation itself.
//
// The sums run over fixed chunks of constraints in a fixed order, so a residual is bitwise the
// same for any thread count.
#pragma once

#include <array>
#include <cstddef>
#include <string>

#include <tessera/core/real.hpp>
#include <tessera/core/constraint_families.hpp>

namespace tessera {

struct FamilyResidual {
  std::size_t constraints = 0;
  /// sqrt(mean of the squared residuals) and the largest residual.
  double rms = 0;
  double max = 0;
  /// The constraint whose residual is max (the first of equal ones in schedule order): its
  /// global id (see Model), or, when worst_is_dynamic, its index among the family's dynamic
  /// constraints (Solver::set_dynamic_constraints), or, when worst_is_contact, its index
  /// among the family's contacts of the last substep (Solver::set_collisions).
  std::size_t worst = 0;
  bool worst_is_dynamic = false;
  bool worst_is_contact = false;
};

struct Residual {
  std::array<FamilyResidual, kConstraintFamilyCount> families{};
  /// Over all constraints of all families.
  std::size_t constraints = 0;
  double rms = 0;
  double max = 0;
  /// The family holding the largest residual (the first such family).
  ConstraintFamily worst_family = ConstraintFamily(0);

  const FamilyResidual& of(ConstraintFamily family) const {
    return families[std::size_t(family)];
  }
};

/// "rms 1.2e-3, max 4.5e-2 (per family: <name> rms ..., max ...; ...)" for logs and tools.
std::string format_residual(const Residual& residual);

}  // namespace tessera
