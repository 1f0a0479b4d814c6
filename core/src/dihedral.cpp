// Dihedral bending constraint C = φ - φ0, φ the unsigned angle between the normals of the two
// triangles of a bending stencil: the one formula of the family and its PBD and XPBD
// projections. Gives cloth and shells a bending resistance independent of stretching.
//
// The angle is measured through the signed angle ψ about the shared edge e = p3 - p2,
//   ψ = atan2((N1 × N2) · ê, N1 · N2),   φ = |ψ| = acos(n̂1 · n̂2),
// which stays accurate near 0 and π where acos of a rounded dot product does not. The
// gradient of ψ (Bridson, Marino, Fedkiw 2003) has no 1/sin φ factor, so it stays finite at a
// flat or fully folded stencil:
//   ∇_{p0} ψ = -|e| N1 / |N1|²,   ∇_{p1} ψ = -|e| N2 / |N2|²,
//   ∇_{p2} ψ = -(1 - s0) ∇_{p0} ψ - (1 - s1) ∇_{p1} ψ,
//   ∇_{p3} ψ = -s0 ∇_{p0} ψ - s1 ∇_{p1} ψ,
// where s_k = (p_k - p2) · e / |e|² is where wing p_k projects onto the edge.
// ∇φ = sign(ψ) ∇ψ, with sign(ψ) taken as +1 at ψ = 0 (the one-sided gradient of φ for
// ψ ≥ 0): a flat stencil with a non-zero rest angle buckles deterministically towards
// positive ψ.
#include <cmath>

#include <Eigen/Geometry>

#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "projection.hpp"

namespace tessera {
namespace {

/// C and ∇C of the dihedral constraint. False for a zero-length shared edge or a triangle of
/// zero area.
bool evaluate_dihedral(const Vector3r& p0, const Vector3r& p1, const Vector3r& p2,
                       const Vector3r& p3, Real rest_angle, Real& C,
                       detail::Gradients<4>& grad) {
  const Vector3r edge = p3 - p2;
  const Real edge_length_squared = edge.squaredNorm();
  const Real tolerance_squared = kDegenerateTolerance * kDegenerateTolerance;
  if (!(edge_length_squared > tolerance_squared)) return false;
  const Vector3r normal0 = (p2 - p0).cross(p3 - p0);  // N1, twice the area of (p0, p2, p3)
  const Vector3r normal1 = (p3 - p1).cross(p2 - p1);  // N2, twice the area of (p1, p3, p2)
  const Real normal0_squared = normal0.squaredNorm();
  const Real normal1_squared = normal1.squaredNorm();
  if (!(normal0_squared > tolerance_squared) || !(normal1_squared > tolerance_squared))
    return false;

  const Real edge_length = std::sqrt(edge_length_squared);
  const Real sine_part = normal0.cross(normal1).dot(edge) / edge_length;  // |N1||N2| sin ψ
  const Real cosine_part = normal0.dot(normal1);                          // |N1||N2| cos ψ
  const Real signed_angle = std::atan2(sine_part, cosine_part);
  const Real sign = sine_part >= 0 ? Real(1) : Real(-1);
  C = std::abs(signed_angle) - rest_angle;

  const Vector3r grad_wing0 = (-sign * edge_length / normal0_squared) * normal0;
  const Vector3r grad_wing1 = (-sign * edge_length / normal1_squared) * normal1;
  const Real s0 = (p0 - p2).dot(edge) / edge_length_squared;
  const Real s1 = (p1 - p2).dot(edge) / edge_length_squared;
  grad[0] = grad_wing0;
  grad[1] = grad_wing1;
  grad[2] = -(1 - s0) * grad_wing0 - (1 - s1) * grad_wing1;
  grad[3] = -s0 * grad_wing0 - s1 * grad_wing1;
  return true;
}

}  // namespace

bool PositionBasedDynamics::solve_DihedralConstraint(
    const Vector3r& p0, Real invMass0, const Vector3r& p1, Real invMass1, const Vector3r& p2,
    Real invMass2, const Vector3r& p3, Real invMass3, const Real restAngle,
    const Real stiffness, Vector3r& corr0, Vector3r& corr1, Vector3r& corr2, Vector3r& corr3) {
  Vector3r* const corr[4] = {&corr0, &corr1, &corr2, &corr3};
  Real C = 0;
  detail::Gradients<4> grad;
  if (!evaluate_dihedral(p0, p1, p2, p3, restAngle, C, grad)) {
    detail::zero_corrections<4>(corr);
    return false;
  }
  return detail::project_pbd<4>(C, grad, {invMass0, invMass1, invMass2, invMass3}, stiffness,
                                corr);
}

bool XPBD::solve_DihedralConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                    Real invMass1, const Vector3r& p2, Real invMass2,
                                    const Vector3r& p3, Real invMass3, const Real restAngle,
                                    const Real compliance, const Real dt, Real& lambda,
                                    Vector3r& corr0, Vector3r& corr1, Vector3r& corr2,
                                    Vector3r& corr3) {
  Vector3r* const corr[4] = {&corr0, &corr1, &corr2, &corr3};
  Real C = 0;
  detail::Gradients<4> grad;
  if (!evaluate_dihedral(p0, p1, p2, p3, restAngle, C, grad)) {
    detail::zero_corrections<4>(corr);
    return false;
  }
  return detail::project_xpbd<4>(C, grad, {invMass0, invMass1, invMass2, invMass3}, compliance,
                                 dt, lambda, corr);
}

}  // namespace tessera
