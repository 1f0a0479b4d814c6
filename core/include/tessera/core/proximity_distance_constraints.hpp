// The three proximity distance families as SoA batches: each keeps two pieces of a mesh at a
// rest distance d0 (cloth thickness, self-collision response, attaching a point to a rod or a
// surface), with the closest-point parameters held fixed while differentiating and
// n = (a - b)/|a - b| the unit direction between the closest points (Müller et al. 2007):
//
//   edge_point_distance      particles p, p0, p1      q = (1 - t) p0 + t p1, t ∈ [0, 1]
//     C = |p - q| - d0,   ∇_p C = n,   ∇_{p0} C = -(1 - t) n,   ∇_{p1} C = -t n.
//     A zero-length segment is the point p0.
//   triangle_point_distance  particles p, p0, p1, p2  q = b0 p0 + b1 p1 + b2 p2 (barycentric)
//     C = |p - q| - d0,   ∇_p C = n,   ∇_{pi} C = -b_i n.
//     A triangle of zero area, or too thin for face coordinates, is measured to its longest
//     edge (see position_based_dynamics.hpp for the threshold).
//   edge_edge_distance       particles p0, p1, p2, p3  a = (1 - s) p0 + s p1,
//                                                      b = (1 - t) p2 + t p3, (s, t) ∈ [0, 1]²
//     C = |a - b| - d0,  ∇_{p0} C = (1 - s) n,  ∇_{p1} C = s n,  ∇_{p2} C = -(1 - t) n,
//     ∇_{p3} C = -t n. A zero-length segment is its first point; parallel segments use the
//     closest pair from s = 0.
//
// PBD stiffness semantics only (the spec has no XPBD form for them): the compression
// stiffness applies where C < 0, the stretch stiffness where C ≥ 0. A constraint is
// degenerate (no correction) where the two closest points coincide.
#pragma once

#include <cstddef>
#include <span>

#include <tessera/core/constraint_batch.hpp>

namespace tessera {

enum class ProximityKind { edge_point, triangle_point, edge_edge };

/// Plain input of any proximity family.
struct ProximityDistanceConstraintInput {
  /// Particle indices, in the order of the family's table above (3 per edge_point
  /// constraint, 4 per triangle_point or edge_edge constraint).
  std::span<const ParticleIndex> particles;
  /// Number of particles the indices refer to (indices must be below it).
  std::size_t particle_count = 0;
  /// Rest distance d0 ≥ 0 of every constraint (e.g. a thickness)...
  Real rest_distance = 0;
  /// ...or, when not empty, one rest distance per constraint (each finite and ≥ 0).
  std::span<const Real> rest_distances;
  /// Stiffness k ≥ 0 when closer than d0 (compression) and when farther (stretch); each
  /// constraint's values can be changed afterwards in the arrays of the result.
  Real compression_stiffness = 1;
  Real stretch_stiffness = 1;
};

template <ProximityKind Kind>
struct ProximityDistanceConstraints {
  static constexpr int kParticles = Kind == ProximityKind::edge_point ? 3 : 4;
  static constexpr const char* kFamily = Kind == ProximityKind::edge_point
                                             ? "edge_point_distance"
                                             : (Kind == ProximityKind::triangle_point
                                                    ? "triangle_point_distance"
                                                    : "edge_edge_distance");
  static constexpr FamilyTraits kTraits = {
      .arity = kParticles, .xpbd = false, .multiplier = false, .velocity_pass = false,
      .cell = CellShape::none};
  /// Its arrays by constraint and its batch-wide fields (see constraint_families.hpp).
  template <class Self>
  static auto per_constraint_arrays(Self& b) {
    return std::tie(b.rest_distance, b.compression_stiffness, b.stretch_stiffness);
  }
  template <class Self>
  static auto batch_wide_fields(Self&) {
    return std::tie();
  }
  ConstraintParticles<kParticles> particles;
  AlignedVector<Real> rest_distance;
  AlignedVector<Real> compression_stiffness;
  AlignedVector<Real> stretch_stiffness;

  std::size_t size() const { return particles.count; }
};

using EdgePointDistanceConstraintInput = ProximityDistanceConstraintInput;
using TrianglePointDistanceConstraintInput = ProximityDistanceConstraintInput;
using EdgeEdgeDistanceConstraintInput = ProximityDistanceConstraintInput;
using EdgePointDistanceConstraints = ProximityDistanceConstraints<ProximityKind::edge_point>;
using TrianglePointDistanceConstraints =
    ProximityDistanceConstraints<ProximityKind::triangle_point>;
using EdgeEdgeDistanceConstraints = ProximityDistanceConstraints<ProximityKind::edge_edge>;

/// Validate and build a batch. Each throws InvalidInput naming the constraint for: an index
/// out of range, a particle named twice, a rest distance that is negative or not finite, an
/// index count that is not a multiple of the family's particle count, a rest_distances span
/// whose length differs from the constraint count, a stiffness that is negative or not finite.
EdgePointDistanceConstraints make_edge_point_distance_constraints(
    const ProximityDistanceConstraintInput& input);
TrianglePointDistanceConstraints make_triangle_point_distance_constraints(
    const ProximityDistanceConstraintInput& input);
EdgeEdgeDistanceConstraints make_edge_edge_distance_constraints(
    const ProximityDistanceConstraintInput& input);
/// The same into `out`: every field replaced, its arrays keep their capacity (the collision
/// stage rebuilds its contacts into the same batches every substep and allocates nothing
/// once they stop growing). On InvalidInput `out` is left empty. The input's spans must not
/// point into `out`.
void make_edge_point_distance_constraints(const ProximityDistanceConstraintInput& input,
                                          EdgePointDistanceConstraints& out);
void make_triangle_point_distance_constraints(const ProximityDistanceConstraintInput& input,
                                              TrianglePointDistanceConstraints& out);
void make_edge_edge_distance_constraints(const ProximityDistanceConstraintInput& input,
                                         EdgeEdgeDistanceConstraints& out);

/// Project constraints [begin, end) once, W at a time on the active SIMD target, writing the
/// corrected positions of movable particles. The constraints of the range must share no
/// movable particle; ranges projected concurrently must not share a block of kMaxLanes
/// consecutive constraints. Only stiffness semantics: settings asking for compliance throw
/// InvalidInput.
void project_edge_point_distance_constraints(ParticleArrays particles,
                                             const EdgePointDistanceConstraints& constraints,
                                             std::size_t begin, std::size_t end,
                                             const ProjectionSettings& settings = {});
void project_triangle_point_distance_constraints(
    ParticleArrays particles, const TrianglePointDistanceConstraints& constraints,
    std::size_t begin, std::size_t end, const ProjectionSettings& settings = {});
void project_edge_edge_distance_constraints(ParticleArrays particles,
                                            const EdgeEdgeDistanceConstraints& constraints,
                                            std::size_t begin, std::size_t end,
                                            const ProjectionSettings& settings = {});

// ------------------------------------------------------------ the family's entry points
// project_sequentially, Point–edge distance:
// PositionBasedDynamics::solve_EdgePointDistanceConstraint with (rest_distance,
// compression_stiffness, stretch_stiffness). Stiffness semantics only, like
// project_edge_point_distance_constraints: compliance semantics throw InvalidInput (the family has
// no XPBD form).
// constraint_residuals, Edge–point distance: |d − d0| / d0 with d the current point–segment
// distance (closest point as in the kernel) and d0 the rest distance; |d| where d0 = 0.
// Dimensionless for d0 > 0, a length for d0 = 0. For every proximity family, a side whose
// stiffness is 0 counts nothing (a compression-only contact, stretch stiffness 0, has no
// residual while d ≥ d0).
TESSERA_FAMILY_ENTRY_POINTS(EdgePointDistanceConstraints, project_edge_point_distance_constraints)

// project_sequentially, Point–triangle distance:
// PositionBasedDynamics::solve_TrianglePointDistanceConstraint with (rest_distance,
// compression_stiffness, stretch_stiffness). Stiffness semantics only (compliance throws
// InvalidInput, as in the batched kernel).
// constraint_residuals, Triangle–point distance: |d − d0| / d0 (|d| where d0 = 0), d the current
// point–triangle distance (a zero-area triangle is measured to its longest edge, as in the kernel).
TESSERA_FAMILY_ENTRY_POINTS(TrianglePointDistanceConstraints, project_triangle_point_distance_constraints)

// project_sequentially, Edge–edge distance: PositionBasedDynamics::solve_EdgeEdgeDistanceConstraint
// with (rest_distance, compression_stiffness, stretch_stiffness). Stiffness semantics only
// (compliance throws InvalidInput, as in the batched kernel).
// constraint_residuals, Edge–edge distance: |d − d0| / d0 (|d| where d0 = 0), d the current
// segment–segment distance (closest pair as in the kernel).
TESSERA_FAMILY_ENTRY_POINTS(EdgeEdgeDistanceConstraints, project_edge_edge_distance_constraints)

}  // namespace tessera
