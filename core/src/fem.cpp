// Finite-element constraints (Bender, Koschier, Charrier, Weber 2014, "Position-Based
// Simulation of Continuous Materials"), the scalar API: the init functions build the rest
// frame, the solve functions are one lane of the families' formula (kernels/fem-inl.h), the
// same code the batched FEM triangle and FEM tetrahedron kernels run on W lanes, including
// the branch-free SVD of the inversion-robust material (kernels/svd3-inl.h). The triangle uses
// an orthotropic St. Venant–Kirchhoff material in plane stress; the tetrahedron the isotropic
// one of green_strain.cpp, optionally made robust to inversion. The XPBD tetrahedron writes
// the energy E·V·ψ₁ as ½ α⁻¹ C² with α = 1/E, so Young's modulus becomes the compliance.
#include <Eigen/LU>
#include <cmath>

#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "degenerate_shape.hpp"
#include "kernels/fem-inl.h"
#include "scalar_projection.hpp"

namespace tessera {
namespace {

namespace lanes = HWY_NAMESPACE;

using Matrix3 = Eigen::Matrix<Real, 3, 3>;
using Matrix2 = Eigen::Matrix<Real, 2, 2>;

using detail::write_corrections;

}  // namespace

// ---------------------------------------------------------------------------------------------
// Triangle

bool PositionBasedDynamics::init_FEMTriangleConstraint(const Vector3r& p0, const Vector3r& p1,
                                                       const Vector3r& p2, Real& area,
                                                       Matrix2r& invRestMat) {
  const Vector3r edge1 = p1 - p0;
  const Vector3r edge2 = p2 - p0;
  const Vector3r normal = edge1.cross(edge2);
  const Real twice_area = normal.norm();
  if (detail::flat_triangle(twice_area, detail::longest_edge({p0, p1, p2}))) {
    area = 0;
    invRestMat.setZero();
    return false;
  }
  // An orthonormal frame of the triangle's plane whose first axis is the edge p0→p1.
  const Vector3r axis_a = edge1.normalized();
  const Vector3r axis_b = (normal / twice_area).cross(axis_a);
  Matrix2 rest;
  rest << axis_a.dot(edge1), axis_a.dot(edge2), axis_b.dot(edge1), axis_b.dot(edge2);
  area = Real(0.5) * twice_area;
  invRestMat = rest.inverse();
  return true;
}

bool PositionBasedDynamics::solve_FEMTriangleConstraint(
    const Vector3r& p0, Real invMass0, const Vector3r& p1, Real invMass1, const Vector3r& p2,
    Real invMass2, const Real& area, const Matrix2r& invRestMat, const Real youngsModulusX,
    const Real youngsModulusY, const Real youngsModulusShear, const Real poissonRatioXY,
    const Real poissonRatioYX, Vector3r& corr0, Vector3r& corr1, Vector3r& corr2) {
  const lanes::Vec3<Real> p[3] = {lanes::from_eigen(p0), lanes::from_eigen(p1),
                                  lanes::from_eigen(p2)};
  const Real w[3] = {invMass0, invMass1, invMass2};
  const Real m[2][2] = {{invRestMat(0, 0), invRestMat(0, 1)},
                        {invRestMat(1, 0), invRestMat(1, 1)}};
  lanes::Vec3<Real> result[3];
  const bool ok = lanes::fem_triangle_pbd<Real>(p, w, area, m, youngsModulusX, youngsModulusY,
                                                youngsModulusShear, poissonRatioXY,
                                                poissonRatioYX, result);
  write_corrections<3>(result, {&corr0, &corr1, &corr2});
  return ok;
}

// ---------------------------------------------------------------------------------------------
// Tetrahedron

bool PositionBasedDynamics::init_FEMTetraConstraint(const Vector3r& p0, const Vector3r& p1,
                                                    const Vector3r& p2, const Vector3r& p3,
                                                    Real& volume, Matrix3r& invRestMat) {
  Matrix3 rest;
  rest.col(0) = p1 - p0;
  rest.col(1) = p2 - p0;
  rest.col(2) = p3 - p0;
  const Real signed_volume = rest.determinant() / 6;
  if (detail::flat_tetrahedron(6 * std::abs(signed_volume),
                               detail::longest_edge({p0, p1, p2, p3}))) {
    volume = 0;
    invRestMat.setZero();
    return false;
  }
  volume = std::abs(signed_volume);
  invRestMat = rest.inverse();
  return true;
}

bool PositionBasedDynamics::solve_FEMTetraConstraint(
    const Vector3r& p0, Real invMass0, const Vector3r& p1, Real invMass1, const Vector3r& p2,
    Real invMass2, const Vector3r& p3, Real invMass3, const Real restVolume,
    const Matrix3r& invRestMat, const Real youngsModulus, const Real poissonRatio,
    const bool handleInversion, Vector3r& corr0, Vector3r& corr1, Vector3r& corr2,
    Vector3r& corr3) {
  const lanes::Vec3<Real> p[4] = {lanes::from_eigen(p0), lanes::from_eigen(p1),
                                  lanes::from_eigen(p2), lanes::from_eigen(p3)};
  const Real w[4] = {invMass0, invMass1, invMass2, invMass3};
  lanes::Vec3<Real> result[4];
  const bool ok = lanes::fem_tetra_pbd<Real>(p, w, restVolume, lanes::from_eigen(invRestMat),
                                             youngsModulus, poissonRatio, handleInversion,
                                             result);
  write_corrections<4>(result, {&corr0, &corr1, &corr2, &corr3});
  return ok;
}

bool XPBD::solve_FEMTetraConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                    Real invMass1, const Vector3r& p2, Real invMass2,
                                    const Vector3r& p3, Real invMass3, const Real restVolume,
                                    const Matrix3r& invRestMat, const Real poissonRatio,
                                    const Real compliance, const bool handleInversion,
                                    const Real dt, Real& lambda, Vector3r& corr0,
                                    Vector3r& corr1, Vector3r& corr2, Vector3r& corr3) {
  const lanes::Vec3<Real> p[4] = {lanes::from_eigen(p0), lanes::from_eigen(p1),
                                  lanes::from_eigen(p2), lanes::from_eigen(p3)};
  const Real w[4] = {invMass0, invMass1, invMass2, invMass3};
  lanes::Vec3<Real> result[4];
  const bool ok = lanes::fem_tetra_xpbd<Real>(p, w, restVolume, lanes::from_eigen(invRestMat),
                                              poissonRatio, compliance,
                                              lanes::TimeStep<Real>::of(dt), handleInversion,
                                              lambda, result);
  write_corrections<4>(result, {&corr0, &corr1, &corr2, &corr3});
  return ok;
}

}  // namespace tessera
