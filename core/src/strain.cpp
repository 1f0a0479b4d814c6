// Strain based dynamics (Müller, Chentanez, Kim, Macklin 2014, "Strain Based Dynamics"):
// instead of one energy per element, each entry of the right Cauchy–Green tensor S = FᵀF is
// its own constraint — stretch along each rest axis (S_ii = 1) and shear between two axes
// (S_ij = 0) — so every direction gets its own stiffness. The sub-constraints are projected
// one after the other on the positions the previous ones corrected (Gauss–Seidel inside the
// element), each with the shared PBD rule of projection.hpp.
//
// Gradients: with F = Ds · M (Ds the edge matrix [p1 - p0, ...], M = invRestMat) the columns
// are f_j = Σ_k M_kj (p_{k+1} - p0), so for any C(f) the chain rule gives
//   ∇_{p_{k+1}} C = Σ_j M_kj ∂C/∂f_j,   ∇_{p0} C = -Σ_k ∇_{p_{k+1}} C,
// and the partial derivatives are
//   C = |f_i|² - 1:           ∂C/∂f_i = 2 f_i;
//   C = |f_i| - 1:            ∂C/∂f_i = f_i / |f_i|;
//   C = f_i · f_j:            ∂C/∂f_i = f_j, ∂C/∂f_j = f_i;
//   C = f_i · f_j / (|f_i||f_j|) = f̂_i · f̂_j:
//                             ∂C/∂f_i = (f̂_j - C f̂_i) / |f_i|  (and symmetrically for j).
#include <Eigen/LU>
#include <array>
#include <cmath>

#include <tessera/core/position_based_dynamics.hpp>

#include "projection.hpp"

namespace tessera {
namespace {

/// One sub-constraint: stretch of column `first` (first == second) or shear between columns
/// `first` and `second`, with its stiffness.
struct SubConstraint {
  int first;
  int second;
  Real stiffness;
};

/// Projects the sub-constraints in order on a local copy of the positions and sums the
/// corrections. Dim is the number of columns of F (2 for a triangle, 3 for a tetrahedron);
/// the element has Dim + 1 particles. Returns false with zero corrections when an active
/// sub-constraint meets a degenerate configuration (a collapsed column, or a vanishing
/// weighted gradient).
template <int Dim, std::size_t Count>
bool project_strain(std::array<Vector3r, Dim + 1> position,
                    const std::array<Real, Dim + 1>& inverse_mass,
                    const Eigen::Matrix<Real, Dim, Dim>& rest_inverse,
                    const std::array<SubConstraint, Count>& sub_constraints,
                    bool normalizeStretch, bool normalizeShear,
                    Vector3r* const (&corr)[Dim + 1]) {
  constexpr int N = Dim + 1;
  std::array<Vector3r, N> total;
  for (auto& t : total) t.setZero();

  for (const SubConstraint& sub : sub_constraints) {
    if (sub.stiffness == 0) continue;

    std::array<Vector3r, Dim> column;
    for (int j = 0; j < Dim; ++j) {
      column[j].setZero();
      for (int k = 0; k < Dim; ++k) column[j] += rest_inverse(k, j) * (position[k + 1] - position[0]);
    }

    // C and its partial derivatives with respect to the two columns involved.
    Real C = 0;
    Vector3r d_first = Vector3r::Zero(), d_second = Vector3r::Zero();
    const Vector3r& fa = column[sub.first];
    const Vector3r& fb = column[sub.second];
    bool degenerate = false;
    if (sub.first == sub.second) {
      const Real length = fa.norm();
      if (normalizeStretch) {
        degenerate = !(length > kDegenerateTolerance);
        C = length - 1;
        if (!degenerate) d_first = fa / length;
      } else {
        C = fa.squaredNorm() - 1;
        d_first = 2 * fa;
      }
    } else if (normalizeShear) {
      const Real length_a = fa.norm(), length_b = fb.norm();
      degenerate = !(length_a > kDegenerateTolerance) || !(length_b > kDegenerateTolerance);
      if (!degenerate) {
        const Vector3r unit_a = fa / length_a, unit_b = fb / length_b;
        C = unit_a.dot(unit_b);
        d_first = (unit_b - C * unit_a) / length_a;
        d_second = (unit_a - C * unit_b) / length_b;
      }
    } else {
      C = fa.dot(fb);
      d_first = fb;
      d_second = fa;
    }

    detail::Gradients<N> gradient;
    gradient[0].setZero();
    for (int k = 0; k < Dim; ++k) {
      gradient[k + 1] = rest_inverse(k, sub.first) * d_first;
      if (sub.first != sub.second) gradient[k + 1] += rest_inverse(k, sub.second) * d_second;
      gradient[0] -= gradient[k + 1];
    }

    std::array<Vector3r, N> step;
    Vector3r* step_ptr[N];
    for (int i = 0; i < N; ++i) step_ptr[i] = &step[i];
    if (degenerate ||
        !detail::project_pbd<N>(C, gradient, inverse_mass, sub.stiffness, step_ptr)) {
      detail::zero_corrections<N>(corr);
      return false;
    }
    for (int i = 0; i < N; ++i) {
      position[i] += step[i];
      total[i] += step[i];
    }
  }
  for (int i = 0; i < N; ++i) *corr[i] = total[i];
  return true;
}

}  // namespace

bool PositionBasedDynamics::init_StrainTriangleConstraint(const Vector3r& p0,
                                                          const Vector3r& p1,
                                                          const Vector3r& p2,
                                                          Matrix2r& invRestMat) {
  Eigen::Matrix<Real, 2, 2> rest;
  rest << p1.x() - p0.x(), p2.x() - p0.x(), p1.y() - p0.y(), p2.y() - p0.y();
  const Real area = Real(0.5) * std::abs(rest.determinant());
  if (!(area > kDegenerateTolerance)) {
    invRestMat.setZero();
    return false;
  }
  invRestMat = rest.inverse();
  return true;
}

bool PositionBasedDynamics::solve_StrainTriangleConstraint(
    const Vector3r& p0, Real invMass0, const Vector3r& p1, Real invMass1, const Vector3r& p2,
    Real invMass2, const Matrix2r& invRestMat, const Real xxStiffness, const Real yyStiffness,
    const Real xyStiffness, const bool normalizeStretch, const bool normalizeShear,
    Vector3r& corr0, Vector3r& corr1, Vector3r& corr2) {
  Vector3r* const corr[3] = {&corr0, &corr1, &corr2};
  const std::array<SubConstraint, 3> sub_constraints = {
      SubConstraint{0, 0, xxStiffness}, SubConstraint{1, 1, yyStiffness},
      SubConstraint{0, 1, xyStiffness}};
  return project_strain<2>({p0, p1, p2}, {invMass0, invMass1, invMass2},
                           Eigen::Matrix<Real, 2, 2>(invRestMat), sub_constraints,
                           normalizeStretch, normalizeShear, corr);
}

bool PositionBasedDynamics::init_StrainTetraConstraint(const Vector3r& p0, const Vector3r& p1,
                                                       const Vector3r& p2, const Vector3r& p3,
                                                       Matrix3r& invRestMat) {
  Eigen::Matrix<Real, 3, 3> rest;
  rest.col(0) = p1 - p0;
  rest.col(1) = p2 - p0;
  rest.col(2) = p3 - p0;
  const Real volume = std::abs(rest.determinant()) / 6;
  if (!(volume > kDegenerateTolerance)) {
    invRestMat.setZero();
    return false;
  }
  invRestMat = rest.inverse();
  return true;
}

bool PositionBasedDynamics::solve_StrainTetraConstraint(
    const Vector3r& p0, Real invMass0, const Vector3r& p1, Real invMass1, const Vector3r& p2,
    Real invMass2, const Vector3r& p3, Real invMass3, const Matrix3r& invRestMat,
    const Vector3r& stretchStiffness, const Vector3r& shearStiffness,
    const bool normalizeStretch, const bool normalizeShear, Vector3r& corr0, Vector3r& corr1,
    Vector3r& corr2, Vector3r& corr3) {
  Vector3r* const corr[4] = {&corr0, &corr1, &corr2, &corr3};
  const std::array<SubConstraint, 6> sub_constraints = {
      SubConstraint{0, 0, stretchStiffness[0]}, SubConstraint{1, 1, stretchStiffness[1]},
      SubConstraint{2, 2, stretchStiffness[2]}, SubConstraint{0, 1, shearStiffness[0]},
      SubConstraint{0, 2, shearStiffness[1]},   SubConstraint{1, 2, shearStiffness[2]}};
  return project_strain<3>({p0, p1, p2, p3}, {invMass0, invMass1, invMass2, invMass3},
                           Eigen::Matrix<Real, 3, 3>(invRestMat), sub_constraints,
                           normalizeStretch, normalizeShear, corr);
}

}  // namespace tessera
