// Residuals: how far the constraints are from satisfied, normalised per family so that
// families and scenes compare (the measure of each family is documented with
// tessera::constraint_residual in <tessera/core/constraint_residual.hpp>: relative length or
// volume error, angle error in radians, Green strain norm, ...).
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
};

struct Residual {
  std::array<FamilyResidual, kConstraintFamilyCount> families{};
  /// Over all constraints of all families.
  std::size_t constraints = 0;
  double rms = 0;
  double max = 0;

  const FamilyResidual& of(ConstraintFamily family) const {
    return families[std::size_t(family)];
  }
};

/// "rms 1.2e-3, max 4.5e-2 (per family: <name> rms ..., max ...; ...)" for logs and tools.
std::string format_residual(const Residual& residual);

}  // namespace tessera
