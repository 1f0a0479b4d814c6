// Contact between a particle and a point inside (or on) a tetrahedron, e.g. a particle of one
// deformable body that has entered a tetrahedron of another. The position solve keeps the
// particle on the outer side of the contact plane with an accumulated, non-negative multiplier
// (a one-sided constraint must only push); the velocity solve then applies Coulomb friction
// bounded by that normal impulse. The contact point moves with the tet through its barycentric
// coordinates, so every quantity is a weighted sum over the five particles, and the inverse
// effective mass along any direction is w0 + Σ b_i² w_i.
#include <algorithm>
#include <cmath>

#include <tessera/core/position_based_dynamics.hpp>

namespace tessera {
namespace {

/// How far |n|² may be from 1 for a normal to count as a unit vector.
constexpr Real kUnitNormalTolerance = Real(1e-4);

/// The four barycentric weights b0..b3 of the tet's particles from bary = (b1, b2, b3).
Vector4r tet_weights(const Vector3r& bary) {
  return Vector4r(1 - bary.sum(), bary[0], bary[1], bary[2]);
}

/// w0 + Σ b_i² w_i: the inverse effective mass of the contact along any direction.
Real inverse_effective_mass(Real invMass0, const Real invMass[], const Vector4r& b) {
  Real k = invMass0;
  for (int i = 0; i < 4; ++i) k += b[i] * b[i] * invMass[i];
  return k;
}

/// u = v0 - Σ b_i v[i], the particle's velocity relative to the tet's contact point.
Vector3r relative_velocity(const Vector3r& v0, const Vector3r v[], const Vector4r& b) {
  Vector3r u = v0;
  for (int i = 0; i < 4; ++i) u -= b[i] * v[i];
  return u;
}

}  // namespace

bool PositionBasedDynamics::init_ParticleTetContactConstraint(
    const Real invMass0, const Vector3r& /*x0*/, const Vector3r& v0, const Real invMass[],
    const Vector3r /*x*/[], const Vector3r v[], const Vector3r& bary, const Vector3r& normal,
    Eigen::Matrix<Real, 3, 3, Eigen::DontAlign>& constraintInfo) {
  constraintInfo.setZero();
  const Vector4r b = tet_weights(bary);
  const Real k = inverse_effective_mass(invMass0, invMass, b);
  if (!(k > kDegenerateTolerance) || !(std::abs(normal.squaredNorm() - 1) <= kUnitNormalTolerance))
    return false;

  const Vector3r u = relative_velocity(v0, v, b);
  const Real normal_speed = u.dot(normal);
  const Vector3r tangential = u - normal_speed * normal;
  const Real tangential_speed = tangential.norm();

  constraintInfo.col(0) = normal;
  if (tangential_speed > kDegenerateTolerance) {
    constraintInfo.col(1) = tangential / tangential_speed;
    constraintInfo(1, 2) = tangential_speed / k;
  }
  constraintInfo(0, 2) = 1 / k;
  constraintInfo(2, 2) = normal_speed;
  return true;
}

bool PositionBasedDynamics::solve_ParticleTetContactConstraint(
    const Real invMass0, const Vector3r& x0, const Real invMass[], const Vector3r x[],
    const Vector3r& bary, Eigen::Matrix<Real, 3, 3, Eigen::DontAlign>& constraintInfo,
    Real& lambda, Vector3r& corr0, Vector3r corr[]) {
  corr0.setZero();
  for (int i = 0; i < 4; ++i) corr[i].setZero();
  const Real effective_mass = constraintInfo(0, 2);
  if (!(effective_mass > 0)) return false;  // init_ failed: nothing can be pushed

  const Vector4r b = tet_weights(bary);
  const Vector3r normal = constraintInfo.col(0);
  Vector3r contact_point = Vector3r::Zero();
  for (int i = 0; i < 4; ++i) contact_point += b[i] * x[i];
  const Real C = normal.dot(x0 - contact_point);

  // Accumulate, clamp the total at zero (the contact may only push), apply only the change.
  const Real accumulated = std::max(lambda - C * effective_mass, Real(0));
  const Real delta_lambda = accumulated - lambda;
  lambda = accumulated;
  if (delta_lambda == 0) return true;

  corr0 = invMass0 * delta_lambda * normal;
  for (int i = 0; i < 4; ++i) corr[i] = -invMass[i] * b[i] * delta_lambda * normal;
  return true;
}

bool PositionBasedDynamics::velocitySolve_ParticleTetContactConstraint(
    const Real invMass0, const Vector3r& /*x0*/, const Vector3r& v0, const Real invMass[],
    const Vector3r /*x*/[], const Vector3r v[], const Vector3r& bary, const Real lambda,
    const Real frictionCoeff, Eigen::Matrix<Real, 3, 3, Eigen::DontAlign>& constraintInfo,
    Vector3r& corr_v0, Vector3r corr_v[]) {
  corr_v0.setZero();
  for (int i = 0; i < 4; ++i) corr_v[i].setZero();

  const Vector4r b = tet_weights(bary);
  const Real k = inverse_effective_mass(invMass0, invMass, b);
  const Real friction_bound = frictionCoeff * lambda;
  if (!(k > kDegenerateTolerance) || !(friction_bound > 0)) return false;

  const Vector3r normal = constraintInfo.col(0);
  const Vector3r u = relative_velocity(v0, v, b);
  const Vector3r tangential = u - u.dot(normal) * normal;
  const Real tangential_speed = tangential.norm();
  if (!(tangential_speed > kDegenerateTolerance)) return false;

  // The impulse that stops the sliding, bounded by the Coulomb cone: it removes k·p of the
  // tangential speed, never more than all of it.
  const Vector3r tangent = tangential / tangential_speed;
  const Real impulse = std::min(tangential_speed / k, friction_bound);
  corr_v0 = -invMass0 * impulse * tangent;
  for (int i = 0; i < 4; ++i) corr_v[i] = invMass[i] * b[i] * impulse * tangent;
  return true;
}

}  // namespace tessera
