// FEM tetrahedron constraints as an SoA batch (Bender, Koschier, Charrier, Weber 2014,
// "Position-Based Simulation of Continuous Materials"): C is the St. Venant–Kirchhoff energy
// of the element, optionally with the inversion-robust material of Irving et al. 2004 (a
// branch-free SVD per lane). PBD (stiffness 1, C = energy) or XPBD (C = sqrt(2 V ψ₁),
// compliance = 1/E, Macklin et al. 2016). Volumetric soft bodies.
// The formulas are the scalar API's (PositionBasedDynamics / XPBD::solve_FEMTetraConstraint).
#pragma once

#include <array>
#include <cstddef>
#include <span>

#include <tessera/core/constraint_batch.hpp>

namespace tessera {

struct FEMTetraConstraintInput {
  /// Four particle indices per constraint; p0 is the reference vertex.
  std::span<const ParticleIndex> particles;
  /// Rest position of every particle. Either orientation of a non-flat rest tetrahedron is
  /// accepted: F = Ds Dm⁻¹ is measured relative to the rest shape (F = I at rest either way),
  /// so an element is "inverted" when its orientation differs from its rest orientation.
  std::span<const Vector3r> rest_positions;
  /// Young's modulus E > 0 and Poisson ratio ν ∈ (-1, 0.5) of every constraint (each value
  /// can be changed afterwards in the arrays of the result). The XPBD compliance of each
  /// constraint starts at 1/E.
  Real youngs_modulus = 1;
  Real poisson_ratio = Real(0.3);
  /// Switch to the inversion-robust material where det F ≤ 0.2.
  bool handle_inversion = true;
};

struct FEMTetraConstraints {
  static constexpr const char* kFamily = "FEM tetra";
  static constexpr FamilyTraits kTraits = {
      .arity = 4, .xpbd = true, .multiplier = true, .velocity_pass = false,
      .cell = CellShape::tetrahedron};
  /// Its arrays by constraint and its batch-wide fields (see constraint_families.hpp).
  template <class Self>
  static auto per_constraint_arrays(Self& b) {
    return std::tie(b.volume, b.rest_inverse, b.youngs_modulus, b.poisson_ratio, b.compliance,
                    b.lambda);
  }
  template <class Self>
  static auto batch_wide_fields(Self& b) {
    return std::tie(b.handle_inversion);
  }
  ConstraintParticles<4> particles;
  AlignedVector<Real> volume;
  /// invRestMat(k, j) of every constraint in rest_inverse[3k + j].
  std::array<AlignedVector<Real>, 9> rest_inverse;
  AlignedVector<Real> youngs_modulus;
  AlignedVector<Real> poisson_ratio;
  /// XPBD compliance α (1/E at construction).
  AlignedVector<Real> compliance;
  /// XPBD multiplier, reset to 0 by the caller at the start of each time step.
  AlignedVector<Real> lambda;
  bool handle_inversion = true;

  std::size_t size() const { return particles.count; }
};

/// Validates and builds the batch. Throws InvalidInput naming the constraint for: an index out
/// of range, a particle named twice, an index count not a multiple of 4, a non-finite rest
/// position, a flat rest tetrahedron (volume ≤ kDegenerateTolerance); and naming the input
/// for E ≤ 0 or not finite, or ν ∉ (-1, 0.5).
FEMTetraConstraints make_fem_tetra_constraints(const FEMTetraConstraintInput& input);

/// Projects constraints [begin, end) once, W at a time on the active SIMD target: PBD with
/// (youngs_modulus, poisson_ratio) under stiffness semantics, XPBD with (poisson_ratio,
/// compliance, λ) under compliance semantics. Same range rules as
/// every batched kernel (constraint_batch.hpp).
void project_fem_tetra_constraints(ParticleArrays particles, FEMTetraConstraints& constraints,
                                   std::size_t begin, std::size_t end,
                                   const ProjectionSettings& settings);

// ------------------------------------------------------------ the family's entry points
// project_sequentially, FEM tetrahedron: PositionBasedDynamics::solve_FEMTetraConstraint with
// (volume, invRestMat, youngs_modulus, poisson_ratio, handle_inversion), or
// XPBD::solve_FEMTetraConstraint with (volume, invRestMat, poisson_ratio, compliance,
// handle_inversion, settings.dt, lambda).
// constraint_residuals, FEM tetrahedron: ‖E‖_F of the 3×3 Green strain E = ½ (FᵀF − I), F = [p1 −
// p0, p2 − p0, p3 − p0] · invRestMat (the kernel's F and ε; the plain strain even where the
// kernel's inversion handling evaluates a clamped one, so a mirrored element reads 0).
// Dimensionless and independent of the material; collapsed to one point: √3 / 2.
TESSERA_FAMILY_ENTRY_POINTS(FEMTetraConstraints, project_fem_tetra_constraints)
// xpbd_residuals, FEM tetrahedron: |C + α̃λ| / sqrt(V0) with the XPBD form's C = sqrt(2 V0 ψ₁(F))
// (ψ₁ the energy density for E = 1; a strain-sized number, as the Green strain above).
TESSERA_XPBD_RESIDUAL_ENTRY_POINT(FEMTetraConstraints)

}  // namespace tessera
