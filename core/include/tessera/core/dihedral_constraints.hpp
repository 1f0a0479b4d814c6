// Dihedral bending constraints as an SoA batch: C = φ - φ0, φ the unsigned angle between the
// normals of the two triangles of a stencil (Müller et al. 2007; gradients of Bridson et al.
// 2003), PBD stiffness or XPBD compliance. Bending resistance for cloth and shells.
#pragma once

#include <cstddef>
#include <span>

#include <tessera/core/constraint_batch.hpp>

namespace tessera {

struct DihedralConstraintInput {
  /// Four particle indices per constraint, in the order of
  /// PositionBasedDynamics::solve_DihedralConstraint: wing p0, wing p1, then the shared edge
  /// p2-p3; the triangles are (p0, p2, p3) and (p1, p3, p2).
  std::span<const ParticleIndex> particles;
  /// Rest position of every particle; each rest angle φ0 is measured here.
  std::span<const Vector3r> rest_positions;
  /// PBD stiffness k ∈ [0, 1] and XPBD compliance α ≥ 0 of every constraint (each
  /// constraint's value can be changed afterwards in the arrays of the result).
  Real stiffness = 1;
  Real compliance = 0;
};

struct DihedralConstraints {
  static constexpr const char* kFamily = "dihedral";
  static constexpr FamilyTraits kTraits = {
      .arity = 4, .xpbd = true, .multiplier = true, .velocity_pass = false,
      .cell = CellShape::hinge};
  /// Its arrays by constraint and its batch-wide fields (see constraint_families.hpp).
  template <class Self>
  static auto per_constraint_arrays(Self& b) {
    return std::tie(b.rest_angle, b.stiffness, b.compliance, b.lambda);
  }
  template <class Self>
  static auto batch_wide_fields(Self&) {
    return std::tie();
  }
  ConstraintParticles<4> particles;
  /// φ0 ∈ [0, π], the angle between the rest normals (0 for a flat rest stencil).
  AlignedVector<Real> rest_angle;
  AlignedVector<Real> stiffness;
  AlignedVector<Real> compliance;
  /// XPBD multiplier, reset to 0 by the caller at the start of each time step.
  AlignedVector<Real> lambda;

  std::size_t size() const { return particles.count; }
};

/// Validates and builds the batch. Throws InvalidInput naming the constraint for: an index out
/// of range, a particle named twice, an index count that is not a multiple of 4, a non-finite
/// rest position, a degenerate rest stencil (shared edge of zero length or a triangle of zero
/// area, the cases the constraint itself rejects), a stiffness or compliance that is negative
/// or not finite.
DihedralConstraints make_dihedral_constraints(const DihedralConstraintInput& input);

/// Projects constraints [begin, end) once, W at a time on the active SIMD target, writing
/// the corrected positions of movable particles (the same result as
/// PositionBasedDynamics / XPBD::solve_DihedralConstraint per constraint, up to rounding).
/// The constraints of the range must share no movable particle; ranges projected
/// concurrently must not share a block of kMaxLanes consecutive constraints.
void project_dihedral_constraints(ParticleArrays particles, DihedralConstraints& constraints,
                                  std::size_t begin, std::size_t end,
                                  const ProjectionSettings& settings);

// ------------------------------------------------------------ the family's entry points
// project_sequentially, Dihedral: PositionBasedDynamics::solve_DihedralConstraint with (rest_angle,
// stiffness), or XPBD::solve_DihedralConstraint with (rest_angle, compliance, settings.dt, lambda).
// constraint_residuals, Dihedral: |φ − φ0| in radians, φ ∈ [0, π] the angle between the wing
// normals exactly as the dihedral formula computes it. A degenerate stencil (zero-length shared
// edge or a zero-area wing) has no defined angle; it reads the formula's value there, φ = 0 for a
// stencil collapsed to one point (so the residual is φ0), always finite and ≤ π.
TESSERA_FAMILY_ENTRY_POINTS(DihedralConstraints, project_dihedral_constraints)
// xpbd_residuals, Dihedral: |C + α̃λ| in radians.
TESSERA_XPBD_RESIDUAL_ENTRY_POINT(DihedralConstraints)

}  // namespace tessera
