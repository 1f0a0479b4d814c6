// Distance constraints as an SoA batch: C = |p0 - p1| - l0 (Müller et al. 2007), PBD
// stiffness or XPBD compliance. Edges of cloth, rods and soft-body struts.
#pragma once

#include <cstddef>
#include <span>

#include <tessera/core/constraint_batch.hpp>

namespace tessera {

struct DistanceConstraintInput {
  /// Two particle indices per constraint.
  std::span<const ParticleIndex> particles;
  /// Rest position of every particle; each rest length is measured here.
  std::span<const Vector3r> rest_positions;
  /// PBD stiffness k ∈ [0, 1] and XPBD compliance α ≥ 0 of every constraint (each
  /// constraint's value can be changed afterwards in the arrays of the result).
  Real stiffness = 1;
  Real compliance = 0;
};

struct DistanceConstraints {
  static constexpr const char* kFamily = "distance";
  static constexpr FamilyTraits kTraits = {
      .arity = 2, .xpbd = true, .multiplier = true, .velocity_pass = false,
      .cell = CellShape::segment};
  /// Its arrays by constraint and its batch-wide fields (see constraint_families.hpp).
  template <class Self>
  static auto per_constraint_arrays(Self& b) {
    return std::tie(b.rest_length, b.stiffness, b.compliance, b.lambda);
  }
  template <class Self>
  static auto batch_wide_fields(Self&) {
    return std::tie();
  }
  ConstraintParticles<2> particles;
  AlignedVector<Real> rest_length;
  AlignedVector<Real> stiffness;
  AlignedVector<Real> compliance;
  /// XPBD multiplier, reset to 0 by the caller at the start of each time step.
  AlignedVector<Real> lambda;

  std::size_t size() const { return particles.count; }
};

/// Validates and builds the batch. Throws InvalidInput naming the constraint for: an index out
/// of range, a particle named twice, a non-finite rest position, a zero rest length, an index
/// count that is not even, a stiffness or compliance that is negative or not finite.
DistanceConstraints make_distance_constraints(const DistanceConstraintInput& input);

/// Projects constraints [begin, end) once, W at a time on the active SIMD target, writing
/// the corrected positions of movable particles. The constraints of the range must share no
/// movable particle; ranges projected concurrently must not share a block of kMaxLanes
/// consecutive constraints.
void project_distance_constraints(ParticleArrays particles, DistanceConstraints& constraints,
                                  std::size_t begin, std::size_t end,
                                  const ProjectionSettings& settings);

// ------------------------------------------------------------ the family's entry points
// project_sequentially, Distance: stiffness semantics →
// PositionBasedDynamics::solve_DistanceConstraint with (rest_length, stiffness); compliance
// semantics → XPBD::solve_DistanceConstraint with (rest_length, compliance, settings.dt, lambda).
// constraint_residuals, Distance: relative stretch |‖p0 − p1‖ − l0| / l0 (dimensionless).
// Coincident particles read 1. (A zero l0, which the builder rejects, would read |‖p0 − p1‖|.)
TESSERA_FAMILY_ENTRY_POINTS(DistanceConstraints, project_distance_constraints)
// xpbd_residuals, Distance: |C + α̃λ| / l0.
TESSERA_XPBD_RESIDUAL_ENTRY_POINT(DistanceConstraints)

}  // namespace tessera
