// Strain triangle constraints as an SoA batch (Müller, Chentanez, Kim, Macklin 2014, "Strain
// Based Dynamics"): each entry of S = FᵀF of a triangle is its own PBD sub-constraint —
// stretch xx, yy and shear xy — projected in that Gauss–Seidel order, each with its own
// stiffness. Cloth and membranes whose warp, weft and shear need different stiffnesses.
// The formula is the scalar API's (PositionBasedDynamics::solve_StrainTriangleConstraint).
#pragma once

#include <array>
#include <cstddef>
#include <span>

#include <tessera/core/constraint_batch.hpp>

namespace tessera {

struct StrainTriangleConstraintInput {
  /// Three particle indices per constraint; p0 is the reference vertex.
  std::span<const ParticleIndex> particles;
  /// Rest position of every particle. As in init_StrainTriangleConstraint the rest triangle is
  /// taken in the xy plane (z ignored), so pass material (e.g. UV) coordinates here.
  std::span<const Vector3r> rest_positions;
  /// PBD stiffness k ∈ [0, 1] of each sub-constraint, for every constraint (each one can be
  /// changed afterwards in the arrays of the result); 0 switches a sub-constraint off.
  Real xx_stiffness = 1;
  Real yy_stiffness = 1;
  Real xy_stiffness = 1;
  /// Stretch C = |f_i| - 1 instead of |f_i|² - 1; shear C = f̂_0 · f̂_1 instead of f_0 · f_1.
  bool normalize_stretch = false;
  bool normalize_shear = false;
};

struct StrainTriangleConstraints {
  static constexpr const char* kFamily = "strain triangle";
  static constexpr FamilyTraits kTraits = {
      .arity = 3, .xpbd = false, .multiplier = false, .velocity_pass = false,
      .cell = CellShape::triangle};
  /// Its arrays by constraint and its batch-wide fields (see constraint_families.hpp).
  template <class Self>
  static auto per_constraint_arrays(Self& b) {
    return std::tie(b.rest_inverse, b.xx_stiffness, b.yy_stiffness, b.xy_stiffness);
  }
  template <class Self>
  static auto batch_wide_fields(Self& b) {
    return std::tie(b.normalize_stretch, b.normalize_shear);
  }
  ConstraintParticles<3> particles;
  /// invRestMat(k, j) of every constraint in rest_inverse[2k + j].
  std::array<AlignedVector<Real>, 4> rest_inverse;
  AlignedVector<Real> xx_stiffness;
  AlignedVector<Real> yy_stiffness;
  AlignedVector<Real> xy_stiffness;
  bool normalize_stretch = false;
  bool normalize_shear = false;

  std::size_t size() const { return particles.count; }
};

/// Validates and builds the batch. Throws InvalidInput naming the constraint for: an index out
/// of range, a particle named twice, an index count not a multiple of 3, a non-finite rest
/// position, a rest triangle of zero area in the xy plane, a stiffness that is negative or
/// not finite.
StrainTriangleConstraints make_strain_triangle_constraints(
    const StrainTriangleConstraintInput& input);

/// Projects constraints [begin, end) once, W at a time on the active SIMD target. The family
/// has no XPBD form: it projects with its PBD stiffnesses under either semantics. The
/// constraints of the range must share no movable particle; ranges projected concurrently
/// must not share a block of kMaxLanes consecutive constraints.
void project_strain_triangle_constraints(ParticleArrays particles,
                                         StrainTriangleConstraints& constraints,
                                         std::size_t begin, std::size_t end,
                                         const ProjectionSettings& settings);

// ------------------------------------------------------------ the family's entry points
// project_sequentially, Strain triangle: PositionBasedDynamics::solve_StrainTriangleConstraint with
// (invRestMat from rest_inverse, xx/yy/xy_stiffness, normalize_stretch, normalize_shear). No XPBD
// form: the PBD form under either semantics (settings are not used).
// constraint_residuals, Strain triangle: ‖E‖_F, the Frobenius norm of the 2×2 Green strain E = ½
// (FᵀF − I) with F = [p1 − p0, p2 − p0] · invRestMat (3×2, p0 the reference vertex, as in the
// kernel). Dimensionless; 0 for a rigid motion of the rest triangle. Note the family's convention:
// the rest triangle is taken in the xy plane (init_StrainTriangleConstraint), so the rest positions
// a batch was built from read 0 only when they lie in that plane. A triangle collapsed to one point
// reads √2 / 2.
TESSERA_FAMILY_ENTRY_POINTS(StrainTriangleConstraints, project_strain_triangle_constraints)

}  // namespace tessera
