// Edge–edge distance constraints as an SoA batch: keeps two segments at distance d0 (cloth
// thickness between crossing edges, edge–edge self-collision response, rods in contact).
// Closest points a = (1 - s) p0 + s p1 and b = (1 - t) p2 + t p3, (s, t) ∈ [0, 1]² held
// fixed, n = (a - b)/|a - b| (Müller et al. 2007):
//   C = |a - b| - d0,  ∇_{p0} C = (1 - s) n,  ∇_{p1} C = s n,  ∇_{p2} C = -(1 - t) n,
//   ∇_{p3} C = -t n.
// Particle order per constraint: p0, p1 (first edge), p2, p3 (second edge). PBD stiffness
// semantics only (the seed has no XPBD form): the compression stiffness applies where C < 0,
// the stretch stiffness where C ≥ 0. Degenerate (no correction) when the segments touch; a
// zero-length segment is its first point; parallel segments use the closest pair from s = 0.
#pragma once

#include <cstddef>
#include <span>
#include <tessera/core/constraint_batch.hpp>

namespace tessera {

struct EdgeEdgeDistanceConstraintInput {
  /// Four particle indices per constraint: the first edge's p0, p1, then the second's p2, p3.
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

struct EdgeEdgeDistanceConstraints {
  static constexpr const char* kFamily = "edge_edge_distance";
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
EdgeEdgeDistanceConstraints make_edge_edge_distance_constraints(
    const EdgeEdgeDistanceConstraintInput& input);

/// Projects constraints [begin, end) once, W at a time on the active SIMD target, writing
/// the corrected positions of movable particles. The constraints of the range must share no
/// movable particle; ranges projected concurrently must not share a block of kMaxLanes
/// consecutive constraints. Only stiffness semantics: settings asking for compliance throw
/// InvalidInput.
void project_edge_edge_distance_constraints(ParticleArrays particles,
                                            const EdgeEdgeDistanceConstraints& constraints,
                                            std::size_t begin, std::size_t end,
                                            const ProjectionSettings& settings = {});

}  // namespace tessera
