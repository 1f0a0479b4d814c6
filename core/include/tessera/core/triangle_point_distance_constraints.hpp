// Point–triangle distance constraints as an SoA batch: keeps a point at distance d0 from a
// triangle (cloth thickness, self-collision response between a vertex and a face, attaching
// a point to a surface). Closest point q = b0 p0 + b1 p1 + b2 p2 of triangle (p0, p1, p2) to
// p, barycentric b held fixed, n = (p - q)/|p - q| (Müller et al. 2007):
//   C = |p - q| - d0,   ∇_p C = n,   ∇_{pi} C = -b_i n.
// Particle order per constraint: p, p0, p1, p2. PBD stiffness semantics only (the seed has
// no XPBD form): the compression stiffness applies where C < 0, the stretch stiffness where
// C ≥ 0. Degenerate (no correction) when p lies on the triangle; a triangle of zero area or
// too thin for face coordinates is measured to its edges, i.e. to its longest edge (see
// position_based_dynamics.hpp for the threshold).
#pragma once

#include <cstddef>
#include <span>
#include <tessera/core/constraint_batch.hpp>

namespace tessera {

struct TrianglePointDistanceConstraintInput {
  /// Four particle indices per constraint: the point p, then the triangle's p0, p1, p2.
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

struct TrianglePointDistanceConstraints {
  static constexpr const char* kFamily = "triangle_point_distance";
  ConstraintParticles<4> particles;
  AlignedVector<Real> rest_distance;
  AlignedVector<Real> compression_stiffness;
  AlignedVector<Real> stretch_stiffness;

  std::size_t size() const { return particles.count; }
};

/// Validates and builds the batch. Throws InvalidInput naming the constraint for: an index
/// out of range, a particle named twice, a rest distance that is negative or not finite, an
/// index count that is not a multiple of 4, a rest_distances span whose length differs from
/// the constraint count, a stiffness that is negative or not finite.
TrianglePointDistanceConstraints make_triangle_point_distance_constraints(
    const TrianglePointDistanceConstraintInput& input);

/// Projects constraints [begin, end) once, W at a time on the active SIMD target, writing
/// the corrected positions of movable particles. The constraints of the range must share no
/// movable particle; ranges projected concurrently must not share a block of kMaxLanes
/// consecutive constraints. Only stiffness semantics: settings asking for compliance throw
/// InvalidInput.
void project_triangle_point_distance_constraints(
    ParticleArrays particles, const TrianglePointDistanceConstraints& constraints,
    std::size_t begin, std::size_t end, const ProjectionSettings& settings = {});

}  // namespace tessera
