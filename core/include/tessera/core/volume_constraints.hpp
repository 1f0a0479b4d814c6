// Tetrahedron volume constraints as an SoA batch: C = V - V0 with the signed volume
// V = (1/6) ((p1 - p0) × (p2 - p0)) · (p3 - p0) (Müller et al. 2007), PBD stiffness or XPBD
// compliance. Keeps soft bodies from collapsing and un-inverts inverted tetrahedra.
#pragma once

#include <cstddef>
#include <span>

#include <tessera/core/constraint_batch.hpp>

namespace tessera {

struct VolumeConstraintInput {
  /// Four particle indices per constraint (p0, p1, p2, p3, as in
  /// PositionBasedDynamics::solve_VolumeConstraint).
  std::span<const ParticleIndex> particles;
  /// Rest position of every particle; each rest volume V0 is measured here (signed: a
  /// tetrahedron listed with negative orientation keeps a negative volume).
  std::span<const Vector3r> rest_positions;
  /// PBD stiffness k ∈ [0, 1] and XPBD compliance α ≥ 0 of every constraint (each
  /// constraint's value can be changed afterwards in the arrays of the result).
  Real stiffness = 1;
  Real compliance = 0;
};

struct VolumeConstraints {
  static constexpr const char* kFamily = "volume";
  static constexpr FamilyTraits kTraits = {
      .arity = 4, .xpbd = true, .multiplier = true, .velocity_pass = false,
      .cell = CellShape::tetrahedron};
  /// Its arrays by constraint and its batch-wide fields (see constraint_families.hpp).
  template <class Self>
  static auto per_constraint_arrays(Self& b) {
    return std::tie(b.rest_volume, b.stiffness, b.compliance, b.lambda);
  }
  template <class Self>
  static auto batch_wide_fields(Self&) {
    return std::tie();
  }
  ConstraintParticles<4> particles;
  /// Signed rest volume V0.
  AlignedVector<Real> rest_volume;
  AlignedVector<Real> stiffness;
  AlignedVector<Real> compliance;
  /// XPBD multiplier, reset to 0 by the caller at the start of each time step.
  AlignedVector<Real> lambda;

  std::size_t size() const { return particles.count; }
};

/// Validates and builds the batch. Throws InvalidInput naming the constraint for: an index out
/// of range, a particle named twice, an index count that is not a multiple of 4, a non-finite
/// rest position, a flat rest tetrahedron (6 |V0| ≤ kDegenerateTolerance · L³ with L its
/// longest rest edge: degenerate whatever its size), a stiffness or compliance that is
/// negative or not finite.
VolumeConstraints make_volume_constraints(const VolumeConstraintInput& input);

/// Projects constraints [begin, end) once, W at a time on the active SIMD target, writing
/// the corrected positions of movable particles (the same result as
/// PositionBasedDynamics / XPBD::solve_VolumeConstraint per constraint, up to rounding).
/// The constraints of the range must share no movable particle; ranges projected
/// concurrently must not share a block of kMaxLanes consecutive constraints.
void project_volume_constraints(ParticleArrays particles, VolumeConstraints& constraints,
                                std::size_t begin, std::size_t end,
                                const ProjectionSettings& settings);

// ------------------------------------------------------------ the family's entry points
// project_sequentially, Volume: PositionBasedDynamics::solve_VolumeConstraint with (rest_volume,
// stiffness), or XPBD::solve_VolumeConstraint with (rest_volume, compliance, settings.dt, lambda).
// constraint_residuals, Volume: relative volume change |V − V0| / |V0| (dimensionless), V the
// signed volume (1/6) ((p1 − p0) × (p2 − p0)) · (p3 − p0) with p0 the reference vertex, as in the
// kernel; an inverted tetrahedron counts its full signed change (inverting a unit tet reads 2). A
// flat or collapsed tetrahedron reads 1. (A zero V0, which the builder rejects, would read |V|.)
TESSERA_FAMILY_ENTRY_POINTS(VolumeConstraints, project_volume_constraints)
// xpbd_residuals, Volume: |C + α̃λ| / V0.
TESSERA_XPBD_RESIDUAL_ENTRY_POINT(VolumeConstraints)

}  // namespace tessera
