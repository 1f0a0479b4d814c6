// Point–edge distance constraints as an SoA batch: keeps a point at distance d0 from a
// segment (cloth thickness against an edge, self-collision response, attaching a point to a
// rod). Closest point q = (1 - t) p0 + t p1 of segment p0-p1 to p, t ∈ [0, 1] held fixed,
// n = (p - q)/|p - q| (Müller et al. 2007):
//   C = |p - q| - d0,   ∇_p C = n,   ∇_{p0} C = -(1 - t) n,   ∇_{p1} C = -t n.
// Particle order per constraint: p, p0, p1. PBD stiffness semantics only (the seed has no
// XPBD form): the compression stiffness applies where C < 0, the stretch stiffness where
// C ≥ 0. Degenerate (no correction) when p lies on the segment; a zero-length segment is the
// point p0.
#pragma once

#include <cstddef>
#include <span>
#include <tessera/core/constraint_batch.hpp>

namespace tessera {

struct EdgePointDistanceConstraintInput {
  /// Three particle indices per constraint: the point p, then the edge's p0 and p1.
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

struct EdgePointDistanceConstraints {
  static constexpr const char* kFamily = "edge_point_distance";
  ConstraintParticles<3> particles;
  AlignedVector<Real> rest_distance;
  AlignedVector<Real> compression_stiffness;
  AlignedVector<Real> stretch_stiffness;

  std::size_t size() const { return particles.count; }
};

/// Validates and builds the batch. Throws InvalidInput naming the constraint for: an index
/// out of range, a particle named twice, a rest distance that is negative or not finite, an
/// index count that is not a multiple of 3, a rest_distances span whose length differs from
/// the constraint count, a stiffness that is negative or not finite.
EdgePointDistanceConstraints make_edge_point_distance_constraints(
    const EdgePointDistanceConstraintInput& input);

/// Projects constraints [begin, end) once, W at a time on the active SIMD target, writing
/// the corrected positions of movable particles. The constraints of the range must share no
/// movable particle; ranges projected concurrently must not share a block of kMaxLanes
/// consecutive constraints. Only stiffness semantics: settings asking for compliance throw
/// InvalidInput.
void project_edge_point_distance_constraints(ParticleArrays particles,
                                             const EdgePointDistanceConstraints& constraints,
                                             std::size_t begin, std::size_t end,
                                             const ProjectionSettings& settings = {});

}  // namespace tessera
