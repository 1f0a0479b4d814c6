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
  static constexpr FamilyTraits kTraits = {
      .arity = 4, .xpbd = true, .multiplier = true, .velocity_pass = false,
      .cell = CellShape::hinge};
  /// Its arrays by constraint and its batch-wide fields (see constraint_families.hpp).
  template <class Self>
  static auto per_constraint_arrays(Self& b) {
    return std::tie(b.factor, b.stiffness, b.compliance, b.lambda);
  }
  template <class Self>
  static auto batch_wide_fields(Self&) {
    return std::tie();
  }
  /// Q = k kᵀ of constraint c.
  Matrix4r matrix(std::size_t c) const;

  ConstraintParticles<4> particles;
  /// The rank-one factor of each Q = k kᵀ: factor[j][c] is k_j of constraint c.
  std::array<AlignedVector<Real>, 4> factor;
  AlignedVector<Real> stiffness;
  AlignedVector<Real> compliance;
  /// XPBD multiplier, reset to 0 by the caller at the start of each time step.
  AlignedVector<Real> lambda;

  std::size_t size() const { return particles.count; }
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

// ------------------------------------------------------------ the family's entry points
// project_sequentially, Isometric bending: PositionBasedDynamics::solve_IsometricBendingConstraint
// with (Q = batch.matrix(c), stiffness), or XPBD::solve_IsometricBendingConstraint with (Q,
// compliance, settings.dt, lambda). Q = k kᵀ is rebuilt from the stored factor k.
// constraint_residuals, Isometric bending: |u| = |Σ_j k_j p_j| = sqrt(2C), the discrete
// mean-curvature vector of the kernel's C = ½ |u|² (Q = k kᵀ). Dimensionless: k scales as 1/length
// (Q as 1/area), so scaling a stencil leaves |u| unchanged, like the bending energy. The model
// assumes a flat rest shape: a rigid motion of a flat rest stencil reads 0, while a curved rest
// stencil reads its own rest curvature (the kernel's C is not 0 there either). A stencil collapsed
// to one point reads 0.
TESSERA_FAMILY_ENTRY_POINTS(IsometricBendingConstraints, project_isometric_bending_constraints)
// xpbd_residuals, Isometric bending: sqrt(2 |C + α̃λ|) (the units of |u|).
TESSERA_XPBD_RESIDUAL_ENTRY_POINT(IsometricBendingConstraints)

}  // namespace tessera
