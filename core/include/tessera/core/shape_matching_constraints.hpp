// Shape-matching clusters as a batch (Müller et al. 2005, "Meshless Deformations Based on
// Shape Matching"): each cluster pulls its particles towards the best rigid (or, with
// allow_stretch, the best linear) placement of its rest shape. Clusters have any size, so the
// particles are stored in a CSR layout:
//
//   offsets[c] .. offsets[c+1]   the entries of cluster c
//   particle[e], rest_offset[e] = x0 - c0 (c0 the cluster's rest centre), mass[e]   per entry
//   rest_centre[c], stiffness[c], inverse_rest_moment[c] (A_qq⁻¹, with stretch)     per cluster
//
// The batched kernel projects W clusters at once (one cluster per lane), taking the rotation
// from a branch-free polar decomposition (kernels/polar_rotation-inl.h).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include <tessera/core/constraint_batch.hpp>

namespace tessera {

struct ShapeMatchingInput {
  /// count + 1 entry offsets: cluster c is entries [offsets[c], offsets[c+1]) of `particles`
  /// (offsets[0] = 0, non-decreasing, offsets[count] = particles.size()).
  std::span<const std::uint32_t> offsets;
  /// The particle of every entry.
  std::span<const ParticleIndex> particles;
  /// Rest position and inverse mass of every particle. Masses enter the matching as
  /// m = 1/w, a static particle (w = 0) as PositionBasedDynamics::kShapeMatchingStaticMass
  /// times the cluster's heaviest movable one (as in the scalar API); they are taken here, so
  /// rebuild the batch when masses change.
  std::span<const Vector3r> rest_positions;
  std::span<const Real> inverse_masses;
  /// PBD stiffness k ∈ [0, 1] of every cluster (changeable afterwards per cluster).
  Real stiffness = 1;
  /// Match the best linear map A_pq A_qq⁻¹ instead of the best rotation.
  bool allow_stretch = false;
};

struct ShapeMatchingConstraints {
  static constexpr const char* kFamily = "shape matching";
  std::size_t count = 0;
  /// Number of particles the indices were validated against.
  std::size_t particle_count = 0;
  /// The size of the largest cluster.
  std::size_t max_cluster_size = 0;
  bool allow_stretch = false;
  /// count + 1 offsets, padded with the entry count (padding clusters are empty).
  AlignedVector<std::uint32_t> offsets;
  AlignedVector<ParticleIndex> particle;
  std::array<AlignedVector<Real>, 3> rest_offset;
  AlignedVector<Real> mass;
  std::array<AlignedVector<Real>, 3> rest_centre;
  /// A_qq⁻¹ column-major (element 3j + i is row i, column j); only filled with allow_stretch.
  std::array<AlignedVector<Real>, 9> inverse_rest_moment;
  AlignedVector<Real> stiffness;

  std::size_t size() const { return count; }
  std::size_t entry_count() const { return count == 0 ? 0 : offsets[count]; }
};

/// Validates and builds the batch. Throws InvalidInput naming the cluster for: an empty
/// cluster, an index out of range, a particle named twice in one cluster, a non-finite rest
/// position, a negative or non-finite inverse mass, a degenerate rest cluster (all points on
/// one line, or with allow_stretch all in one plane: its rotation, or linear fit, would be
/// undetermined); and about the input as a whole for offsets that do not start at 0, decrease
/// or end elsewhere than at the number of entries, sizes of rest positions and inverse masses
/// that differ, more than 2³¹ - 1 entries or particles, and a stiffness that is negative or
/// not finite.
ShapeMatchingConstraints make_shape_matching_constraints(const ShapeMatchingInput& input);

/// Projects clusters [begin, end) once, W clusters at a time on the active SIMD target,
/// writing the corrected positions of movable particles (each cluster's corrections are
/// computed from the positions before that cluster moves, as in the scalar API). The
/// clusters of the range must share no movable particle; ranges projected concurrently must
/// not share a block of kMaxLanes consecutive clusters.
void project_shape_matching_constraints(ParticleArrays particles,
                                        ShapeMatchingConstraints& constraints, std::size_t begin,
                                        std::size_t end);

}  // namespace tessera
