// The scalar API of the particle–collider contact: one lane of the family's formula
// (kernels/collider_contact-inl.h), the same code the batched kernels run on W lanes.
#include <tessera/core/position_based_dynamics_extensions.hpp>

#include "kernels/collider_contact-inl.h"

namespace tessera {

namespace lanes = HWY_NAMESPACE;

bool PositionBasedDynamicsExtensions::solve_ColliderContactConstraint(
    const Vector3r& p0, Real invMass0, const Vector3r& normal, const Real offset,
    const Vector3r& anchor, const Real staticFriction, const Real dynamicFriction, Real& lambda,
    Vector3r& corr0) {
  const auto solved = lanes::collider_contact_position_solve<Real>(
      invMass0, lanes::from_eigen(p0), lanes::from_eigen(normal), offset,
      lanes::from_eigen(anchor), staticFriction, dynamicFriction, lambda);
  corr0 = lanes::to_eigen(solved.correction);
  return solved.valid;
}

bool PositionBasedDynamicsExtensions::velocitySolve_ColliderContactConstraint(
    const Vector3r& v0, Real invMass0, const Vector3r& normal, const Real normalSpeed,
    const Real restitution, const Real lambda, Vector3r& corr_v0) {
  const auto solved = lanes::collider_contact_velocity_solve<Real>(
      invMass0, lanes::from_eigen(v0), lanes::from_eigen(normal), normalSpeed, restitution,
      lambda);
  corr_v0 = lanes::to_eigen(solved.correction);
  return solved.valid;
}

}  // namespace tessera
