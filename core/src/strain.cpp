// The scalar API of strain based dynamics (Müller, Chentanez, Kim, Macklin 2014): one lane of
// the families' formula (kernels/strain-inl.h), the same code the batched strain triangle and
// strain tetrahedron kernels run on W lanes. The init functions invert the rest edge matrix.
#include <Eigen/LU>
#include <cmath>

#include <tessera/core/position_based_dynamics.hpp>

#include "degenerate_shape.hpp"
#include "kernels/strain-inl.h"
#include "scalar_projection.hpp"

namespace tessera {
namespace {

namespace lanes = HWY_NAMESPACE;

template <int Dim, int Count>
bool solve_strain(const Vector3r (&position)[Dim + 1], const Real (&inverse_mass)[Dim + 1],
                  const Eigen::Matrix<Real, Dim, Dim>& rest_inverse,
                  const lanes::StrainEntry (&entries)[Count], const Real (&stiffness)[Count],
                  bool normalizeStretch, bool normalizeShear, Vector3r* const (&corr)[Dim + 1]) {
  lanes::Vec3<Real> p[Dim + 1];
  for (int i = 0; i <= Dim; ++i) p[i] = lanes::from_eigen(position[i]);
  Real m[Dim][Dim];
  for (int k = 0; k < Dim; ++k)
    for (int j = 0; j < Dim; ++j) m[k][j] = rest_inverse(k, j);
  lanes::Vec3<Real> result[Dim + 1];
  const bool ok = lanes::project_strain<Dim>(p, inverse_mass, m, entries, stiffness,
                                             normalizeStretch, normalizeShear, result);
  detail::write_corrections<Dim + 1>(result, corr);
  return ok;
}

}  // namespace

bool PositionBasedDynamics::init_StrainTriangleConstraint(const Vector3r& p0,
                                                          const Vector3r& p1,
                                                          const Vector3r& p2,
                                                          Matrix2r& invRestMat) {
  Eigen::Matrix<Real, 2, 2> rest;
  rest << p1.x() - p0.x(), p2.x() - p0.x(), p1.y() - p0.y(), p2.y() - p0.y();
  // The rest triangle is taken in the xy plane: its edges there.
  const auto in_plane = [](const Vector3r& p) { return Vector3r(p.x(), p.y(), 0); };
  if (detail::flat_triangle(std::abs(rest.determinant()),
                            detail::longest_edge({in_plane(p0), in_plane(p1), in_plane(p2)}))) {
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
  const Real stiffness[3] = {xxStiffness, yyStiffness, xyStiffness};
  return solve_strain<2>({p0, p1, p2}, {invMass0, invMass1, invMass2},
                         Eigen::Matrix<Real, 2, 2>(invRestMat), lanes::kStrainTriangleEntries,
                         stiffness, normalizeStretch, normalizeShear, {&corr0, &corr1, &corr2});
}

bool PositionBasedDynamics::init_StrainTetraConstraint(const Vector3r& p0, const Vector3r& p1,
                                                       const Vector3r& p2, const Vector3r& p3,
                                                       Matrix3r& invRestMat) {
  Eigen::Matrix<Real, 3, 3> rest;
  rest.col(0) = p1 - p0;
  rest.col(1) = p2 - p0;
  rest.col(2) = p3 - p0;
  if (detail::flat_tetrahedron(std::abs(rest.determinant()),
                               detail::longest_edge({p0, p1, p2, p3}))) {
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
  const Real stiffness[6] = {stretchStiffness[0], stretchStiffness[1], stretchStiffness[2],
                             shearStiffness[0],   shearStiffness[1],   shearStiffness[2]};
  return solve_strain<3>({p0, p1, p2, p3}, {invMass0, invMass1, invMass2, invMass3},
                         Eigen::Matrix<Real, 3, 3>(invRestMat), lanes::kStrainTetraEntries,
                         stiffness, normalizeStretch, normalizeShear,
                         {&corr0, &corr1, &corr2, &corr3});
}

}  // namespace tessera
