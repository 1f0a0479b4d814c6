// Tethers (long-range attachments) as an SoA batch: C = |p0 − p1| − d ≤ 0 (Kim, Chentanez,
// Müller 2012), PBD stiffness or XPBD compliance, acting only when stretched. p0 is the
// tethered particle, p1 its attachment: a static particle, so tethers of different particles
// never share a movable one and colour freely. make_long_range_attachments
// (long_range_attachments.hpp) builds them from a mesh's edges with d the geodesic distance.
// Not in the seed's API: its scalar form is PositionBasedDynamicsExtensions::solve_TetherConstraint
// (position_based_dynamics_extensions.hpp).
#pragma once

#include <cstddef>
#include <span>

#include <tessera/core/constraint_batch.hpp>

namespace tessera {

struct TetherConstraintInput {
  /// Two particle indices per tether: the tethered particle, then its attachment.
  std::span<const ParticleIndex> particles;
  /// Rest position of every particle: a tether's reach is its rest distance |p0 − p1| here,
  /// unless a reach is given.
  std::span<const Vector3r> rest_positions;
  /// The reach d > 0 of every tether (one per tether), or empty: then every tether reaches
  /// max_distance, or its rest distance where max_distance is 0.
  std::span<const Real> max_distances = {};
  Real max_distance = 0;
  /// PBD stiffness k ∈ [0, 1] and XPBD compliance α ≥ 0 of every tether.
  Real stiffness = 1;
  Real compliance = 0;
};

struct TetherConstraints {
  static constexpr const char* kFamily = "tether";
  static constexpr FamilyTraits kTraits = {
      .arity = 2, .xpbd = true, .multiplier = true, .velocity_pass = false,
      .cell = CellShape::segment};
  /// Its arrays by constraint and its batch-wide fields (see constraint_families.hpp).
  template <class Self>
  static auto per_constraint_arrays(Self& b) {
    return std::tie(b.max_distance, b.stiffness, b.compliance, b.lambda);
  }
  template <class Self>
  static auto batch_wide_fields(Self&) {
    return std::tie();
  }
  ConstraintParticles<2> particles;
  AlignedVector<Real> max_distance;
  AlignedVector<Real> stiffness;
  AlignedVector<Real> compliance;
  /// XPBD multiplier (≤ 0: a tether only pulls), reset to 0 at the start of each substep.
  AlignedVector<Real> lambda;

  std::size_t size() const { return particles.count; }
};

/// Validates and builds the batch. Throws InvalidInput naming the tether for: an index out of
/// range, a particle tethered to itself, an index count that is not even, a non-finite rest
/// position, a max_distance count that differs from the tether count, a reach that is not
/// positive and finite (a zero rest distance included), a stiffness or compliance that is
/// negative or not finite.
TetherConstraints make_tether_constraints(const TetherConstraintInput& input);

/// Projects tethers [begin, end) once, W at a time on the active SIMD target (the range rules
/// of every batched kernel, constraint_batch.hpp).
void project_tether_constraints(ParticleArrays particles, TetherConstraints& constraints,
                                std::size_t begin, std::size_t end,
                                const ProjectionSettings& settings);

// ------------------------------------------------------------ the family's entry points
// project_sequentially, Tether: stiffness semantics →
// PositionBasedDynamicsExtensions::solve_TetherConstraint with (max_distance, stiffness);
// compliance semantics → XPBDExtensions::solve_TetherConstraint with (max_distance,
// compliance, settings.dt, lambda).
// constraint_residuals, Tether: relative overshoot max(0, ‖p0 − p1‖ − d) / d (dimensionless;
// 0 while the particle is within reach).
TESSERA_FAMILY_ENTRY_POINTS(TetherConstraints, project_tether_constraints)
// xpbd_residuals, Tether: max(0, C + α̃λ) / d.
TESSERA_XPBD_RESIDUAL_ENTRY_POINT(TetherConstraints)

}  // namespace tessera
