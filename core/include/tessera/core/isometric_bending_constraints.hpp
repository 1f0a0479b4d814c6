// Isometric bending constraints as an SoA batch: C = ½ Σ_ij Q_ij p_i · p_j with the constant
// 4×4 matrix Q of each stencil's rest shape (Bergou et al. 2006, "A Quadratic Bending Model
// for Inextensible Surfaces"), PBD stiffness or XPBD compliance. Cheap bending for cloth that
// hardly stretches: Q has rank one, Q = k kᵀ, and each projection is C = ½ |Σ k_j p_j|².
#pragma once

#include <array>
#include <cstddef>
#include <span>

#include <tessera/core/constraint_batch.hpp>

namespace tessera {

struct IsometricBendingConstraintInput {
  /// Four particle indices per constraint, in the order of
  /// PositionBasedDynamics::solve_IsometricBendingConstraint: wing p0, wing p1, then the
  /// shared edge p2-p3; the triangles are (p0, p2, p3) and (p1, p3, p2).
  std::span<const ParticleIndex> particles;
  /// Rest position of every particle; each Q is built here by
  /// PositionBasedDynamics::init_IsometricBendingConstraint.
  std::span<const Vector3r> rest_positions;
  /// PBD stiffness k ∈ [0, 1] and XPBD compliance α ≥ 0 of every constraint (each
  /// constraint's value can be changed afterwards in the arrays of the result).
  Real stiffness = 1;
  Real compliance = 0;
};

struct IsometricBendingConstraints {
  static constexpr const char* kFamily = "isometric bending";

  ConstraintParticles<4> particles;
  /// The rank-one factor of each Q = k kᵀ: factor[j][c] is k_j of constraint c.
  std::array<AlignedVector<Real>, 4> factor;
  AlignedVector<Real> stiffness;
  AlignedVector<Real> compliance;
  /// XPBD multiplier, reset to 0 by the caller at the start of each time step.
  AlignedVector<Real> lambda;

  std::size_t size() const { return particles.count; }
  /// Q = k kᵀ of constraint c.
  Matrix4r matrix(std::size_t c) const;
};

/// Validates and builds the batch. Throws InvalidInput naming the constraint for: an index out
/// of range, a particle named twice, an index count that is not a multiple of 4, a non-finite
/// rest position, a degenerate rest stencil (shared edge of zero length or a triangle of zero
/// area: init_IsometricBendingConstraint fails), a stiffness or compliance that is negative
/// or not finite.
IsometricBendingConstraints make_isometric_bending_constraints(
    const IsometricBendingConstraintInput& input);

/// Projects constraints [begin, end) once, W at a time on the active SIMD target, writing
/// the corrected positions of movable particles (the same result as
/// PositionBasedDynamics / XPBD::solve_IsometricBendingConstraint per constraint, up to
/// rounding; a stencil flat for its Q is left as it is, λ unchanged). The constraints of the
/// range must share no movable particle; ranges projected concurrently must not share a
/// block of kMaxLanes consecutive constraints.
void project_isometric_bending_constraints(ParticleArrays particles,
                                           IsometricBendingConstraints& constraints,
                                           std::size_t begin, std::size_t end,
                                           const ProjectionSettings& settings);

}  // namespace tessera
