// The rank-one factor of an isometric bending matrix: Q = k kᵀ. init_IsometricBendingConstraint
// builds Q as (3/(A0+A1)) K Kᵀ; the solvers evaluate C and ∇C through k (see
// kernels/isometric_bending-inl.h for why), so the scalar API and the batch builder both
// recover k from Q here, the same way.
#pragma once

#include <tessera/core/real.hpp>

namespace tessera::detail {

/// k with Q = k kᵀ, taken from Q's row with the largest diagonal entry: Q_mj / √Q_mm (its sign
/// is irrelevant, C and ∇C are even in k). Zero for a Q without a positive diagonal entry.
Vector4r isometric_bending_factor(const Matrix4r& Q);

}  // namespace tessera::detail
