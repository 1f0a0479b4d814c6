// Isometric bending (Bergou, Wardetzky, Harmon, Zorin, Grinspun 2006): for nearly
// inextensible surfaces the bending energy of a two-triangle stencil is a constant quadratic
// form in the positions, C = ½ Σ_ij Q_ij p_i · p_j, so Q is computed once from the rest shape
// and each projection is a matrix–vector product. This file holds that one formula, the
// construction of Q and the PBD and XPBD projections.
//
// Q = 3 / (A0 + A1) · K Kᵀ, where K is the cotangent-weighted Laplacian row of the stencil.
// With the shared edge p2-p3, wing p0 in triangle (p0, p2, p3), wing p1 in (p1, p3, p2), and
// cot_{v,k} the cotangent of the interior angle at edge vertex v in the triangle of wing k:
//   K_{p0} = -(cot_{2,0} + cot_{3,0}),   K_{p1} = -(cot_{2,1} + cot_{3,1}),
//   K_{p2} =   cot_{3,0} + cot_{3,1},    K_{p3} =   cot_{2,0} + cot_{2,1}.
// Σ K = 0 and Σ K_i p_i = 0 for any planar stencil (the discrete mean curvature vanishes), so
// C = 0 exactly when the stencil is flat.
#include <array>

#include <Eigen/Geometry>

#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "projection.hpp"

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
  if (!(edge.norm() > kDegenerateTolerance) || !(twice_area0 > kDegenerateTolerance) ||
      !(twice_area1 > kDegenerateTolerance))
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

/// C = ½ Σ_ij Q_ij p_i · p_j and ∇_{pi} C = Σ_j Q_ij p_j. The rows of Q sum to zero, so the
/// positions are taken relative to their centroid first: the same values, without the
/// cancellation that far-from-origin coordinates would cause. Returns false when the gradient
/// vanishes (a flat stencil: the constraint is satisfied and there is no direction to move).
bool evaluate_bending(const std::array<const Vector3r*, 4>& p, const Matrix4r& Q, Real& C,
                      detail::Gradients<4>& grad) {
  const Vector3r centroid = Real(0.25) * (*p[0] + *p[1] + *p[2] + *p[3]);
  std::array<Vector3r, 4> relative;
  for (int i = 0; i < 4; ++i) relative[i] = *p[i] - centroid;
  Real gradient_norm_squared = 0;
  C = 0;
  for (int i = 0; i < 4; ++i) {
    grad[i].setZero();
    for (int j = 0; j < 4; ++j) grad[i] += Q(i, j) * relative[j];
    C += relative[i].dot(grad[i]);
    gradient_norm_squared += grad[i].squaredNorm();
  }
  C *= Real(0.5);
  return gradient_norm_squared > kDegenerateTolerance * kDegenerateTolerance;
}

}  // namespace

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
  Vector3r* const corr[4] = {&corr0, &corr1, &corr2, &corr3};
  Real C = 0;
  detail::Gradients<4> grad;
  if (!evaluate_bending({&p0, &p1, &p2, &p3}, Q, C, grad)) {
    detail::zero_corrections<4>(corr);
    return true;  // flat: satisfied
  }
  return detail::project_pbd<4>(C, grad, {invMass0, invMass1, invMass2, invMass3}, stiffness,
                                corr);
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
  Vector3r* const corr[4] = {&corr0, &corr1, &corr2, &corr3};
  if (!(dt > 0) || !(compliance >= 0)) {
    detail::zero_corrections<4>(corr);
    return false;
  }
  Real C = 0;
  detail::Gradients<4> grad;
  if (!evaluate_bending({&p0, &p1, &p2, &p3}, Q, C, grad)) {
    detail::zero_corrections<4>(corr);
    return true;  // flat: satisfied, λ unchanged
  }
  return detail::project_xpbd<4>(C, grad, {invMass0, invMass1, invMass2, invMass3}, compliance,
                                 dt, lambda, corr);
}

}  // namespace tessera
