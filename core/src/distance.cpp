// Distance constraint C = |p0 - p1| - l0: the one formula of the family (value and gradients)
// and its PBD (stiffness) and XPBD (compliance) projections. Edges of cloth and rods, struts
// of soft bodies, and the building block every other family is checked against.
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "projection.hpp"

namespace tessera {
namespace {

/// C and ∇C of the distance constraint. False when p0 and p1 coincide (the direction is
/// undefined).
bool evaluate_distance(const Vector3r& p0, const Vector3r& p1, Real rest_length, Real& C,
                       detail::Gradients<2>& grad) {
  const Vector3r difference = p0 - p1;
  const Real length = difference.norm();
  if (!(length > kDegenerateTolerance)) return false;
  const Vector3r direction = difference / length;
  C = length - rest_length;
  grad = {direction, -direction};
  return true;
}

}  // namespace

bool PositionBasedDynamics::solve_DistanceConstraint(const Vector3r& p0, Real invMass0,
                                                     const Vector3r& p1, Real invMass1,
                                                     const Real restLength,
                                                     const Real stiffness, Vector3r& corr0,
                                                     Vector3r& corr1) {
  Vector3r* const corr[2] = {&corr0, &corr1};
  Real C = 0;
  detail::Gradients<2> grad;
  if (!evaluate_distance(p0, p1, restLength, C, grad)) {
    detail::zero_corrections<2>(corr);
    return false;
  }
  return detail::project_pbd<2>(C, grad, {invMass0, invMass1}, stiffness, corr);
}

bool XPBD::solve_DistanceConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                    Real invMass1, const Real restLength, const Real compliance,
                                    const Real dt, Real& lambda, Vector3r& corr0,
                                    Vector3r& corr1) {
  Vector3r* const corr[2] = {&corr0, &corr1};
  Real C = 0;
  detail::Gradients<2> grad;
  if (!evaluate_distance(p0, p1, restLength, C, grad)) {
    detail::zero_corrections<2>(corr);
    return false;
  }
  return detail::project_xpbd<2>(C, grad, {invMass0, invMass1}, compliance, dt, lambda, corr);
}

}  // namespace tessera
