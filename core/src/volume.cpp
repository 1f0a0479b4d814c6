// The scalar API of the tetrahedron volume constraint (C = V - V0, V the signed volume): one
// lane of the family's formula (kernels/volume-inl.h), the same code the batched kernel runs
// on W lanes, with its PBD and XPBD projections.
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "kernels/volume-inl.h"
#include "scalar_projection.hpp"

namespace tessera {
namespace {

namespace lanes = HWY_NAMESPACE;

lanes::ConstraintValue<Real, 4> evaluate(const Vector3r& p0, const Vector3r& p1,
                                         const Vector3r& p2, const Vector3r& p3,
                                         Real rest_volume) {
  return lanes::volume_constraint<Real>(lanes::from_eigen(p0), lanes::from_eigen(p1),
                                        lanes::from_eigen(p2), lanes::from_eigen(p3),
                                        rest_volume);
}

}  // namespace

bool PositionBasedDynamics::solve_VolumeConstraint(
    const Vector3r& p0, Real invMass0, const Vector3r& p1, Real invMass1, const Vector3r& p2,
    Real invMass2, const Vector3r& p3, Real invMass3, const Real restVolume,
    const Real stiffness, Vector3r& corr0, Vector3r& corr1, Vector3r& corr2, Vector3r& corr3) {
  const auto value = evaluate(p0, p1, p2, p3, restVolume);
  const Real w[4] = {invMass0, invMass1, invMass2, invMass3};
  return detail::project_scalar_pbd<4>(value, w, stiffness, {&corr0, &corr1, &corr2, &corr3});
}

bool XPBD::solve_VolumeConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                  Real invMass1, const Vector3r& p2, Real invMass2,
                                  const Vector3r& p3, Real invMass3, const Real restVolume,
                                  const Real compliance, const Real dt, Real& lambda,
                                  Vector3r& corr0, Vector3r& corr1, Vector3r& corr2,
                                  Vector3r& corr3) {
  const auto value = evaluate(p0, p1, p2, p3, restVolume);
  const Real w[4] = {invMass0, invMass1, invMass2, invMass3};
  return detail::project_scalar_xpbd<4>(value, w, compliance, dt, lambda,
                                        {&corr0, &corr1, &corr2, &corr3});
}

}  // namespace tessera
