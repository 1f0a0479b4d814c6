// The XPBD (compliance) forms of the scalar kernels (Macklin, Müller, Chentanez 2016,
// "XPBD: Position-Based Simulation of Compliant Constrained Dynamics", eq. 17-18).
//
// Each constraint keeps a Lagrange multiplier λ that the caller resets to 0 at the start of a
// time step and passes back on every iteration. With α̃ = compliance / dt²:
//     Δλ = (-C - α̃ λ) / (Σ_j w_j |∇_j C|² + α̃),   λ ← λ + Δλ,   Δp_i = w_i Δλ ∇_i C.
// Compliance is the inverse stiffness (m/N for a distance constraint); compliance 0 is a hard
// constraint and equals one PBD projection with stiffness 1. The constraint functions,
// gradients, vertex orders and degenerate cases are those of the PositionBasedDynamics
// function of the same name. On false (degenerate input, dt ≤ 0, negative compliance) the
// corrections are zero and λ is left unchanged.
// The reference implementation takes a stiffness k (α̃ = 1/(k dt²), k = 0 hard): pass
// compliance 1/k, and 0 for k = 0 (docs/differences-from-pbd.md, "XPBD takes compliance").
#pragma once

#include <tessera/core/real.hpp>

namespace tessera {

class XPBD {
 public:
  /// C = |p0 - p1| - l0. Both ends static: false, λ unchanged (the reference still changes
  /// λ; docs/differences-from-pbd.md, C6).
  static bool solve_DistanceConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                       Real invMass1, const Real restLength,
                                       const Real compliance, const Real dt, Real& lambda,
                                       Vector3r& corr0, Vector3r& corr1);

  /// C = acos(n̂1 · n̂2) - φ0 (vertex order of PositionBasedDynamics::solve_DihedralConstraint).
  /// Differs from the reference as the PBD form does (docs/differences-from-pbd.md, C6, C7).
  static bool solve_DihedralConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                       Real invMass1, const Vector3r& p2, Real invMass2,
                                       const Vector3r& p3, Real invMass3, const Real restAngle,
                                       const Real compliance, const Real dt, Real& lambda,
                                       Vector3r& corr0, Vector3r& corr1, Vector3r& corr2,
                                       Vector3r& corr3);

  /// C = (1/6) ((p1 - p0) × (p2 - p0)) · (p3 - p0) - V0. The reference's ∇C lacks the 1/6
  /// (docs/differences-from-pbd.md, B1).
  static bool solve_VolumeConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                     Real invMass1, const Vector3r& p2, Real invMass2,
                                     const Vector3r& p3, Real invMass3, const Real restVolume,
                                     const Real compliance, const Real dt, Real& lambda,
                                     Vector3r& corr0, Vector3r& corr1, Vector3r& corr2,
                                     Vector3r& corr3);

  /// Same Q as PositionBasedDynamics::init_IsometricBendingConstraint: -2 times the
  /// reference's, reordered (docs/differences-from-pbd.md, C1).
  static bool init_IsometricBendingConstraint(const Vector3r& p0, const Vector3r& p1,
                                              const Vector3r& p2, const Vector3r& p3,
                                              Matrix4r& Q);

  /// C = ½ Σ_ij Q_ij p_i · p_j. A stencil with ∇C = 0 (flat for its Q) returns true with zero
  /// corrections and λ unchanged.
  /// Compliance scale: our Q is -2 times the reference's, so its C is a·C with a = -½. XPBD on
  /// a·C with compliance α is XPBD on C with compliance α/a² = 4α: the reference's stiffness
  /// k (α̃ = 1/(k dt²)) is compliance 4/k here (our compliance 4c is its stiffness 1/c), and
  /// λ = -λ_ref / 2 (docs/differences-from-pbd.md, C1).
  static bool solve_IsometricBendingConstraint(const Vector3r& p0, Real invMass0,
                                               const Vector3r& p1, Real invMass1,
                                               const Vector3r& p2, Real invMass2,
                                               const Vector3r& p3, Real invMass3,
                                               const Matrix4r& Q, const Real compliance,
                                               const Real dt, Real& lambda, Vector3r& corr0,
                                               Vector3r& corr1, Vector3r& corr2,
                                               Vector3r& corr3);

  /// St. Venant–Kirchhoff tetrahedron as an XPBD constraint. The elastic energy is
  /// E · V · ψ₁(F), where ψ₁ is the energy density of computeGreenStrainAndPiolaStress for
  /// Young's modulus 1 and the given Poisson ratio. Writing it as ½ α⁻¹ C² gives
  ///   C = sqrt(2 V ψ₁(F)),   ∇C = V ∇ψ₁ / C,   α = compliance = 1 / E.
  /// handleInversion selects the inversion-robust material as in the PBD form. At the rest
  /// shape (ψ₁ ≤ tol²/2, i.e. C ≤ tol · sqrt(V) with tol the degenerate tolerance, whatever the
  /// element's size) the gradient is undefined: the corrections are
  /// zero and true is returned (λ unchanged). Returns false for ν ∉ (-1, 0.5) or
  /// restVolume ≤ 0, besides the shared cases (dt ≤ 0, negative compliance, degenerate
  /// gradient). The reference takes (youngsModulus, poissonRatio) where this takes
  /// (poissonRatio, compliance = 1/E), and its multiplier accumulates Δλ/C
  /// (docs/differences-from-pbd.md, B10).
  static bool solve_FEMTetraConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                       Real invMass1, const Vector3r& p2, Real invMass2,
                                       const Vector3r& p3, Real invMass3, const Real restVolume,
                                       const Matrix3r& invRestMat, const Real poissonRatio,
                                       const Real compliance, const bool handleInversion,
                                       const Real dt, Real& lambda, Vector3r& corr0,
                                       Vector3r& corr1, Vector3r& corr2, Vector3r& corr3);
};

}  // namespace tessera
