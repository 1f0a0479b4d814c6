// Isometric bending (Bergou, Wardetzky, Harmon, Zorin, Grinspun 2006): for nearly
// inextensible surfaces the bending energy of a two-triangle stencil is a constant quadratic
// form in the positions, C = ½ Σ_ij Q_ij p_i · p_j, so Q is computed once from the rest shape
// and each projection is a matrix–vector product. This file builds Q from the rest shape
// (plain Eigen: set-up, not the hot path; the batch builder calls the same function) and runs
// the scalar API as one lane of the family's formula (kernels/isometric_bending-inl.h), the
// code the batched kernel runs on W lanes.
//
// Q = 3 / (A0 + A1) · K Kᵀ, where K is the cotangent-weighted Laplacian row of the stencil.
// With the shared edge p2-p3, wing p0 in triangle (p0, p2, p3), wing p1 in (p1, p3, p2), and
// cot_{v,k} the cotangent of the interior angle at edge vertex v in the triangle of wing k:
//   K_{p0} = -(cot_{2,0} + cot_{3,0}),   K_{p1} = -(cot_{2,1} + cot_{3,1}),
//   K_{p2} =   cot_{3,0} + cot_{3,1},    K_{p3} =   cot_{2,0} + cot_{2,1}.
// Σ K = 0 and Σ K_i p_i = 0 for any planar stencil (the discrete mean curvature vanishes), so
// C = 0 exactly when the stencil is flat.
#include <Eigen/Geometry>

#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "degenerate_shape.hpp"
#include "isometric_bending_factor.hpp"
#include "kernels/isometric_bending-inl.h"
#include "scalar_projection.hpp"

namespace tessera {
namespace {

/// Cotangent of the angle between u and v: cos / sin = (u·v) / |u × v|.
Real cotangent(const Vector3r& u, const Vector3r& v, Real twice_area) {
  return u.dot(v) / twice_area;
}

bool build_bending_matrix(const Vector3r& p0, const Vector3r& p1, const Vector3r& p2,
                          const Vector3r& p3, Matrix4r& Q) {
  Q.setZero();
  const Vector3r edge = p3 - p2;
  const Real twice_area0 = (p2 - p0).cross(p3 - p0).norm();
  const Real twice_area1 = (p3 - p1).cross(p2 - p1).norm();
  if (!(edge.norm() > kDegenerateTolerance) ||
      detail::flat_triangle(twice_area0, detail::longest_edge({p0, p2, p3})) ||
      detail::flat_triangle(twice_area1, detail::longest_edge({p1, p3, p2})))
    return false;

  const Real cot_p2_wing0 = cotangent(p0 - p2, edge, twice_area0);
  const Real cot_p3_wing0 = cotangent(p0 - p3, -edge, twice_area0);
  const Real cot_p2_wing1 = cotangent(p1 - p2, edge, twice_area1);
  const Real cot_p3_wing1 = cotangent(p1 - p3, -edge, twice_area1);
  const Vector4r K(-(cot_p2_wing0 + cot_p3_wing0), -(cot_p2_wing1 + cot_p3_wing1),
                   cot_p3_wing0 + cot_p3_wing1, cot_p2_wing0 + cot_p2_wing1);
  // 3 / (A0 + A1) with A_k = twice_area_k / 2.
  const Real scale = Real(6) / (twice_area0 + twice_area1);
  Q = scale * (K * K.transpose());
  return true;
}

namespace lanes = HWY_NAMESPACE;

lanes::ConstraintValue<Real, 4> evaluate(const Vector3r& p0, const Vector3r& p1,
                                         const Vector3r& p2, const Vector3r& p3,
                                         const Matrix4r& Q) {
  const lanes::Vec3<Real> p[4] = {lanes::from_eigen(p0), lanes::from_eigen(p1),
                                  lanes::from_eigen(p2), lanes::from_eigen(p3)};
  const Vector4r factor = detail::isometric_bending_factor(Q);
  const Real k[4] = {factor[0], factor[1], factor[2], factor[3]};
  return lanes::isometric_bending_constraint<Real>(p, k);
}

}  // namespace

namespace detail {

Vector4r isometric_bending_factor(const Matrix4r& Q) {
  int largest = 0;
  for (int i = 1; i < 4; ++i)
    if (Q(i, i) > Q(largest, largest)) largest = i;
  if (!(Q(largest, largest) > 0)) return Vector4r::Zero();
  return Vector4r(Q.row(largest).transpose()) / std::sqrt(Q(largest, largest));
}

}  // namespace detail

bool PositionBasedDynamics::init_IsometricBendingConstraint(const Vector3r& p0,
                                                            const Vector3r& p1,
                                                            const Vector3r& p2,
                                                            const Vector3r& p3, Matrix4r& Q) {
  return build_bending_matrix(p0, p1, p2, p3, Q);
}

bool PositionBasedDynamics::solve_IsometricBendingConstraint(
    const Vector3r& p0, Real invMass0, const Vector3r& p1, Real invMass1, const Vector3r& p2,
    Real invMass2, const Vector3r& p3, Real invMass3, const Matrix4r& Q, const Real stiffness,
    Vector3r& corr0, Vector3r& corr1, Vector3r& corr2, Vector3r& corr3) {
  const auto value = evaluate(p0, p1, p2, p3, Q);
  const Real w[4] = {invMass0, invMass1, invMass2, invMass3};
  const bool projected =
      detail::project_scalar_pbd<4>(value, w, stiffness, {&corr0, &corr1, &corr2, &corr3});
  return projected || lanes::bending_is_flat(value);  // flat: satisfied
}

bool XPBD::init_IsometricBendingConstraint(const Vector3r& p0, const Vector3r& p1,
                                           const Vector3r& p2, const Vector3r& p3,
                                           Matrix4r& Q) {
  return build_bending_matrix(p0, p1, p2, p3, Q);
}

bool XPBD::solve_IsometricBendingConstraint(const Vector3r& p0, Real invMass0,
                                            const Vector3r& p1, Real invMass1,
                                            const Vector3r& p2, Real invMass2,
                                            const Vector3r& p3, Real invMass3,
                                            const Matrix4r& Q, const Real compliance,
                                            const Real dt, Real& lambda, Vector3r& corr0,
                                            Vector3r& corr1, Vector3r& corr2, Vector3r& corr3) {
  const auto value = evaluate(p0, p1, p2, p3, Q);
  const Real w[4] = {invMass0, invMass1, invMass2, invMass3};
  const bool projected = detail::project_scalar_xpbd<4>(value, w, compliance, dt, lambda,
                                                        {&corr0, &corr1, &corr2, &corr3});
  // Flat: satisfied, λ unchanged (but a bad time step or compliance is still an error).
  return projected || (lanes::bending_is_flat(value) &&
                       lanes::xpbd_inputs_valid(lanes::TimeStep<Real>::of(dt), compliance));
}

}  // namespace tessera
