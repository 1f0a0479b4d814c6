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
  static constexpr FamilyTraits kTraits = {
      .arity = 0, .xpbd = false, .multiplier = false, .velocity_pass = false,
      .cell = CellShape::none};
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
  /// Its description (see constraint_families.hpp): the CSR layout (count, particle_count,
  /// max_cluster_size, offsets, particle: kLayoutFields fields), the arrays by entry, by
  /// cluster and the batch-wide fields.
  static constexpr std::size_t kLayoutFields = 5;
  template <class Self>
  static auto per_entry_arrays(Self& b) {
    return std::tie(b.rest_offset, b.mass);
  }
  template <class Self>
  static auto per_constraint_arrays(Self& b) {
    return std::tie(b.rest_centre, b.inverse_rest_moment, b.stiffness);
  }
  template <class Self>
  static auto batch_wide_fields(Self& b) {
    return std::tie(b.allow_stretch);
  }
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

// ------------------------------------------------------------ the family's entry points
// project_sequentially, Shape matching, one cluster after another: PositionBasedDynamics::
// solve_ShapeMatchingConstraint with the cluster's rest shape in centre-of-mass coordinates (x0 =
// the stored rest offsets q, restCm = 0, so x0 - restCm is q exactly), the current positions and
// inverse masses of its particles, stiffness and allow_stretch. PBD only, like
// project_shape_matching_constraints: settings are not used. The scalar API weighs the particles by
// their current inverse masses, the batch by the masses it was built with: the two agree as long as
// the masses have not changed since the batch was built.
// constraint_residuals, Shape matching, c = the cluster: RMS_i |x_i − g_i| / RMS_i |q_i|
// (dimensionless), with q_i the cluster's rest offsets, g_i = T q_i + centre the kernel's goal
// positions (centre mass-weighted; T the kernel's rotation of A_pq, or A_pq A_qq⁻¹ when the batch
// allows stretch) and both RMS plain averages over the cluster's particles. Rigid clusters: a
// uniform scaling by s reads |s − 1|; where the kernel finds no rotation (A_pq of rank < 2, e.g.
// the cluster collapsed to a point) the rotation its iteration still returns is used, and since |R
// q_i| = |q_i| a cluster collapsed to one point reads 1. With stretch allowed, any affine image of
// the rest cluster reads 0, a collapse to one point included (the zero map matches it, and the
// kernel would not move it either). An empty cluster, or one whose rest offsets are all zero, reads
// 0.
TESSERA_FAMILY_ENTRY_POINTS(ShapeMatchingConstraints, project_shape_matching_constraints)

/// The same for one cluster (the batched form loops over it: clusters do not fit lanes).
Real constraint_residual(const ParticleArrays& particles, const ShapeMatchingConstraints& batch,
                         std::size_t c);

}  // namespace tessera
