// The scalar API of the particle–tetrahedron contact: one lane of the family's formula
// (kernels/particle_tet_contact-inl.h), the same code the batched kernels run on W lanes.
// The position solve keeps the particle on the outer side of the contact plane with an
// accumulated, non-negative multiplier (a one-sided constraint must only push); the velocity
// solve then applies Coulomb friction bounded by that normal impulse.
#include <tessera/core/position_based_dynamics.hpp>

#include "kernels/particle_tet_contact-inl.h"

namespace tessera {
namespace {

namespace lanes = HWY_NAMESPACE;
using Vec3 = lanes::Vec3<Real>;

void to_lanes(const Vector3r in[], Vec3 (&out)[4]) {
  for (int i = 0; i < 4; ++i) out[i] = lanes::from_eigen(in[i]);
}

void to_lanes(const Real in[], Real (&out)[4]) {
  for (int i = 0; i < 4; ++i) out[i] = in[i];
}

void from_lanes(const lanes::ContactCorrection<Real>& c, Vector3r& corr0, Vector3r corr[]) {
  corr0 = lanes::to_eigen(c.particle);
  for (int i = 0; i < 4; ++i) corr[i] = lanes::to_eigen(c.tet[i]);
}

}  // namespace

bool PositionBasedDynamics::init_ParticleTetContactConstraint(
    const Real invMass0, const Vector3r& /*x0*/, const Vector3r& v0, const Real invMass[],
    const Vector3r /*x*/[], const Vector3r v[], const Vector3r& bary, const Vector3r& normal,
    Eigen::Matrix<Real, 3, 3, Eigen::DontAlign>& constraintInfo) {
  Real w[4];
  Vec3 velocities[4];
  to_lanes(invMass, w);
  to_lanes(v, velocities);
  const auto info = lanes::contact_init<Real>(invMass0, w, lanes::from_eigen(v0), velocities,
                                              lanes::from_eigen(bary), lanes::from_eigen(normal));
  constraintInfo.setZero();
  constraintInfo.col(0) = lanes::to_eigen(info.normal);
  constraintInfo.col(1) = lanes::to_eigen(info.tangent);
  constraintInfo(0, 2) = info.effective_mass;
  constraintInfo(1, 2) = info.max_tangential_impulse;
  constraintInfo(2, 2) = info.normal_speed;
  return info.valid;
}

bool PositionBasedDynamics::solve_ParticleTetContactConstraint(
    const Real invMass0, const Vector3r& x0, const Real invMass[], const Vector3r x[],
    const Vector3r& bary, Eigen::Matrix<Real, 3, 3, Eigen::DontAlign>& constraintInfo,
    Real& lambda, Vector3r& corr0, Vector3r corr[]) {
  Real w[4];
  Vec3 positions[4];
  to_lanes(invMass, w);
  to_lanes(x, positions);
  const auto correction = lanes::contact_position_solve<Real>(
      invMass0, w, lanes::from_eigen(x0), positions, lanes::from_eigen(bary),
      lanes::from_eigen(Vector3r(constraintInfo.col(0))), constraintInfo(0, 2), lambda);
  from_lanes(correction, corr0, corr);
  return correction.valid;
}

bool PositionBasedDynamics::velocitySolve_ParticleTetContactConstraint(
    const Real invMass0, const Vector3r& /*x0*/, const Vector3r& v0, const Real invMass[],
    const Vector3r /*x*/[], const Vector3r v[], const Vector3r& bary, const Real lambda,
    const Real frictionCoeff, Eigen::Matrix<Real, 3, 3, Eigen::DontAlign>& constraintInfo,
    Vector3r& corr_v0, Vector3r corr_v[]) {
  Real w[4];
  Vec3 velocities[4];
  to_lanes(invMass, w);
  to_lanes(v, velocities);
  const auto correction = lanes::contact_velocity_solve<Real>(
      invMass0, w, lanes::from_eigen(v0), velocities, lanes::from_eigen(bary),
      lanes::from_eigen(Vector3r(constraintInfo.col(0))), lambda, frictionCoeff);
  from_lanes(correction, corr_v0, corr_v);
  return correction.valid;
}

}  // namespace tessera
