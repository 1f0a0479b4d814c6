// Tetrahedron volume constraint C = V(p0..p3) - V0 with the signed volume
// V = (1/6) ((p1 - p0) × (p2 - p0)) · (p3 - p0): the one formula of the family and its PBD and
// XPBD projections. Keeps soft bodies from collapsing; the sign lets it also un-invert a
// tetrahedron.
#include <Eigen/Geometry>

#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "projection.hpp"

namespace tessera {
namespace {

/// C and ∇C of the volume constraint. Each ∇_{pi} C is the area-weighted normal of the face
/// opposite p_i (over 3), pointing away from p_i's opposite face when V > 0. Always defined;
/// a degenerate tetrahedron (every point on one line) shows up as a vanishing gradient, which
/// the projection rejects.
void evaluate_volume(const Vector3r& p0, const Vector3r& p1, const Vector3r& p2,
                     const Vector3r& p3, Real rest_volume, Real& C, detail::Gradients<4>& grad) {
  const Vector3r e1 = p1 - p0;
  const Vector3r e2 = p2 - p0;
  const Vector3r e3 = p3 - p0;
  constexpr Real kSixth = Real(1) / Real(6);
  grad[1] = kSixth * e2.cross(e3);
  grad[2] = kSixth * e3.cross(e1);
  grad[3] = kSixth * e1.cross(e2);
  grad[0] = -(grad[1] + grad[2] + grad[3]);
  C = grad[3].dot(e3) - rest_volume;
}

}  // namespace

bool PositionBasedDynamics::solve_VolumeConstraint(
    const Vector3r& p0, Real invMass0, const Vector3r& p1, Real invMass1, const Vector3r& p2,
    Real invMass2, const Vector3r& p3, Real invMass3, const Real restVolume,
    const Real stiffness, Vector3r& corr0, Vector3r& corr1, Vector3r& corr2, Vector3r& corr3) {
  Vector3r* const corr[4] = {&corr0, &corr1, &corr2, &corr3};
  Real C = 0;
  detail::Gradients<4> grad;
  evaluate_volume(p0, p1, p2, p3, restVolume, C, grad);
  return detail::project_pbd<4>(C, grad, {invMass0, invMass1, invMass2, invMass3}, stiffness,
                                corr);
}

bool XPBD::solve_VolumeConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                  Real invMass1, const Vector3r& p2, Real invMass2,
                                  const Vector3r& p3, Real invMass3, const Real restVolume,
                                  const Real compliance, const Real dt, Real& lambda,
                                  Vector3r& corr0, Vector3r& corr1, Vector3r& corr2,
                                  Vector3r& corr3) {
  Vector3r* const corr[4] = {&corr0, &corr1, &corr2, &corr3};
  Real C = 0;
  detail::Gradients<4> grad;
  evaluate_volume(p0, p1, p2, p3, restVolume, C, grad);
  return detail::project_xpbd<4>(C, grad, {invMass0, invMass1, invMass2, invMass3}, compliance,
                                 dt, lambda, corr);
}

}  // namespace tessera
