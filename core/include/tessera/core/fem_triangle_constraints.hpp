// FEM triangle constraints as an SoA batch (Bender, Koschier, Charrier, Weber 2014,
// "Position-Based Simulation of Continuous Materials"): C is the energy of an orthotropic
// St. Venant–Kirchhoff membrane in plane stress, projected with the PBD rule (stiffness 1: the
// material sets the stiffness). Cloth with measured warp/weft/shear moduli.
// The formula is the scalar API's (PositionBasedDynamics::solve_FEMTriangleConstraint).
#pragma once

#include <array>
#include <cstddef>
#include <span>

#include <tessera/core/constraint_batch.hpp>

namespace tessera {

struct FEMTriangleConstraintInput {
  /// Three particle indices per constraint; the material x axis is the rest edge p0 → p1.
  std::span<const ParticleIndex> particles;
  /// Rest position of every particle (any orientation in space: each triangle is mapped to
  /// its own plane as in init_FEMTriangleConstraint).
  std::span<const Vector3r> rest_positions;
  /// The material of every constraint (each value can be changed afterwards in the arrays of
  /// the result, keeping it positive definite).
  Real youngs_modulus_x = 1;
  Real youngs_modulus_y = 1;
  Real youngs_modulus_shear = 1;
  Real poisson_ratio_xy = Real(0.3);
  Real poisson_ratio_yx = Real(0.3);
};

struct FEMTriangleConstraints {
  static constexpr const char* kFamily = "FEM triangle";
  static constexpr FamilyTraits kTraits = {
      .arity = 3, .xpbd = false, .multiplier = false, .velocity_pass = false,
      .cell = CellShape::triangle};
  /// Its arrays by constraint and its batch-wide fields (see constraint_families.hpp).
  template <class Self>
  static auto per_constraint_arrays(Self& b) {
    return std::tie(b.area, b.rest_inverse, b.youngs_modulus_x, b.youngs_modulus_y,
                    b.youngs_modulus_shear, b.poisson_ratio_xy, b.poisson_ratio_yx);
  }
  template <class Self>
  static auto batch_wide_fields(Self&) {
    return std::tie();
  }
  ConstraintParticles<3> particles;
  AlignedVector<Real> area;
  /// invRestMat(k, j) of every constraint in rest_inverse[2k + j].
  std::array<AlignedVector<Real>, 4> rest_inverse;
  AlignedVector<Real> youngs_modulus_x;
  AlignedVector<Real> youngs_modulus_y;
  AlignedVector<Real> youngs_modulus_shear;
  AlignedVector<Real> poisson_ratio_xy;
  AlignedVector<Real> poisson_ratio_yx;

  std::size_t size() const { return particles.count; }
};

/// Validates and builds the batch. Throws InvalidInput naming the constraint for: an index out
/// of range, a particle named twice, an index count not a multiple of 3, a non-finite rest
/// position, a rest triangle of zero area; and naming the input for a material that is not
/// finite or not positive definite (E_x, E_y or G ≤ 0, ν_xy ν_yx ≥ 1, or a symmetrised
/// normal block with non-positive determinant).
FEMTriangleConstraints make_fem_triangle_constraints(const FEMTriangleConstraintInput& input);

/// Projects constraints [begin, end) once, W at a time on the active SIMD target. The family
/// has no XPBD form: it is projected with the PBD rule under either semantics. Same range
/// rules as every batched kernel (constraint_batch.hpp).
void project_fem_triangle_constraints(ParticleArrays particles,
                                      FEMTriangleConstraints& constraints, std::size_t begin,
                                      std::size_t end, const ProjectionSettings& settings);

// ------------------------------------------------------------ the family's entry points
// project_sequentially, FEM triangle: PositionBasedDynamics::solve_FEMTriangleConstraint with
// (area, invRestMat, youngs_modulus_x/y/shear, poisson_ratio_xy/yx). No XPBD form: the PBD form
// under either semantics.
// constraint_residuals, FEM triangle: ‖E‖_F of the 2×2 Green strain E = ½ (FᵀF − I), F = [p1 − p0,
// p2 − p0] · invRestMat in the triangle's own rest frame (any orientation in space), as in the
// kernel. Dimensionless and independent of the material; collapsed to one point: √2 / 2.
TESSERA_FAMILY_ENTRY_POINTS(FEMTriangleConstraints, project_fem_triangle_constraints)

}  // namespace tessera
