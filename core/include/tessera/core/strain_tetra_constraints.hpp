// Strain tetrahedron constraints as an SoA batch (Müller, Chentanez, Kim, Macklin 2014,
// "Strain Based Dynamics"): each entry of S = FᵀF of a tetrahedron is its own PBD
// sub-constraint — stretch xx, yy, zz, then shear xy, xz, yz — projected in that Gauss–Seidel
// order with its own stiffness. Soft bodies with direction-dependent stiffness.
// The formula is the scalar API's (PositionBasedDynamics::solve_StrainTetraConstraint).
#pragma once

#include <array>
#include <cstddef>
#include <span>

#include <tessera/core/constraint_batch.hpp>

namespace tessera {

struct StrainTetraConstraintInput {
  /// Four particle indices per constraint; p0 is the reference vertex.
  std::span<const ParticleIndex> particles;
  /// Rest position of every particle; either orientation of a non-flat rest tetrahedron is
  /// accepted (F is measured relative to it, so F = I at rest either way).
  std::span<const Vector3r> rest_positions;
  /// PBD stiffness of stretch xx, yy, zz and of shear xy, xz, yz, for every constraint (each
  /// one can be changed afterwards in the arrays of the result); 0 switches one off.
  Vector3r stretch_stiffness = Vector3r::Ones();
  Vector3r shear_stiffness = Vector3r::Ones();
  bool normalize_stretch = false;
  bool normalize_shear = false;
};

struct StrainTetraConstraints {
  static constexpr const char* kFamily = "strain tetra";
  static constexpr FamilyTraits kTraits = {
      .arity = 4, .xpbd = false, .multiplier = false, .velocity_pass = false,
      .cell = CellShape::tetrahedron};
  /// Its arrays by constraint and its batch-wide fields (see constraint_families.hpp).
  template <class Self>
  static auto per_constraint_arrays(Self& b) {
    return std::tie(b.rest_inverse, b.stretch_stiffness, b.shear_stiffness);
  }
  template <class Self>
  static auto batch_wide_fields(Self& b) {
    return std::tie(b.normalize_stretch, b.normalize_shear);
  }
  ConstraintParticles<4> particles;
  /// invRestMat(k, j) of every constraint in rest_inverse[3k + j].
  std::array<AlignedVector<Real>, 9> rest_inverse;
  /// stretch_stiffness[i]: axis i; shear_stiffness[0, 1, 2]: xy, xz, yz.
  std::array<AlignedVector<Real>, 3> stretch_stiffness;
  std::array<AlignedVector<Real>, 3> shear_stiffness;
  bool normalize_stretch = false;
  bool normalize_shear = false;

  std::size_t size() const { return particles.count; }
};

/// Validates and builds the batch. Throws InvalidInput naming the constraint for: an index out
/// of range, a particle named twice, an index count not a multiple of 4, a non-finite rest
/// position, a flat rest tetrahedron (volume ≤ kDegenerateTolerance), a stiffness that is
/// negative or not finite.
StrainTetraConstraints make_strain_tetra_constraints(const StrainTetraConstraintInput& input);

/// Projects constraints [begin, end) once, W at a time on the active SIMD target. The family
/// has no XPBD form: it projects with its PBD stiffnesses under either semantics. Same range
/// rules as every batched kernel (constraint_batch.hpp).
void project_strain_tetra_constraints(ParticleArrays particles,
                                      StrainTetraConstraints& constraints, std::size_t begin,
                                      std::size_t end, const ProjectionSettings& settings);

// ------------------------------------------------------------ the family's entry points
// project_sequentially, Strain tetrahedron: PositionBasedDynamics::solve_StrainTetraConstraint with
// (invRestMat from rest_inverse, stretch_stiffness[0..2], shear_stiffness[0..2] = xy, xz, yz,
// normalize_stretch, normalize_shear). No XPBD form: the PBD form under either semantics.
// constraint_residuals, Strain tetrahedron: ‖E‖_F of the 3×3 Green strain E = ½ (FᵀF − I), F = [p1
// − p0, p2 − p0, p3 − p0] · invRestMat (p0 the reference vertex). Dimensionless; 0 at any rigid
// motion of the rest shape (also of a mirrored one: Green strain does not see inversion). A
// tetrahedron collapsed to one point reads √3 / 2.
TESSERA_FAMILY_ENTRY_POINTS(StrainTetraConstraints, project_strain_tetra_constraints)

}  // namespace tessera
