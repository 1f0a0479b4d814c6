// The scalar API of the distance constraint: one lane of the family's formula
// (kernels/distance-inl.h), the same code the batched kernel runs on W lanes.
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "kernels/distance-inl.h"

namespace tessera {

namespace lanes = HWY_NAMESPACE;

bool PositionBasedDynamics::solve_DistanceConstraint(const Vector3r& p0, Real invMass0,
                                                     const Vector3r& p1, Real invMass1,
                                                     const Real restLength,
                                                     const Real stiffness, Vector3r& corr0,
                                                     Vector3r& corr1) {
  const auto value =
      lanes::distance_constraint<Real>(lanes::from_eigen(p0), lanes::from_eigen(p1), restLength);
  const Real w[2] = {invMass0, invMass1};
  lanes::Vec3<Real> corr[2];
  const bool projected = lanes::project_pbd(value, w, stiffness, corr);
  corr0 = lanes::to_eigen(corr[0]);
  corr1 = lanes::to_eigen(corr[1]);
  return projected;
}

bool XPBD::solve_DistanceConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                    Real invMass1, const Real restLength, const Real compliance,
                                    const Real dt, Real& lambda, Vector3r& corr0,
                                    Vector3r& corr1) {
  const auto value =
      lanes::distance_constraint<Real>(lanes::from_eigen(p0), lanes::from_eigen(p1), restLength);
  const Real w[2] = {invMass0, invMass1};
  lanes::Vec3<Real> corr[2];
  const bool projected = lanes::project_xpbd(value, w, compliance, dt, lambda, corr);
  corr0 = lanes::to_eigen(corr[0]);
  corr1 = lanes::to_eigen(corr[1]);
  return projected;
}

}  // namespace tessera
