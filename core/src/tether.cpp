// The scalar API of the tether: one lane of the family's formula (kernels/tether-inl.h), the
// same code the batched kernel runs on W lanes.
#include <tessera/core/position_based_dynamics_extensions.hpp>

#include "kernels/tether-inl.h"
#include "scalar_projection.hpp"

namespace tessera {

namespace lanes = HWY_NAMESPACE;

bool PositionBasedDynamicsExtensions::solve_TetherConstraint(
    const Vector3r& p0, Real invMass0, const Vector3r& p1, Real invMass1, const Real maxDistance,
    const Real stiffness, Vector3r& corr0, Vector3r& corr1) {
  const auto value =
      lanes::tether_constraint<Real>(lanes::from_eigen(p0), lanes::from_eigen(p1), maxDistance);
  const Real w[2] = {invMass0, invMass1};
  return detail::project_scalar_pbd<2>(value, w, stiffness, {&corr0, &corr1});
}

bool XPBDExtensions::solve_TetherConstraint(const Vector3r& p0, Real invMass0,
                                            const Vector3r& p1, Real invMass1,
                                            const Real maxDistance, const Real compliance,
                                            const Real dt, Real& lambda, Vector3r& corr0,
                                            Vector3r& corr1) {
  const auto value =
      lanes::tether_constraint<Real>(lanes::from_eigen(p0), lanes::from_eigen(p1), maxDistance);
  const Real w[2] = {invMass0, invMass1};
  return detail::project_scalar_xpbd<2>(value, w, compliance, dt, lambda, {&corr0, &corr1});
}

}  // namespace tessera
