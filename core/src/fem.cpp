// Finite-element constraints (Bender, Koschier, Charrier, Weber 2014, "Position-Based
// Simulation of Continuous Materials"): the constraint of an element is its elastic energy and
// the constraint gradient is the energy gradient, so one PBD projection is a Newton step
// towards zero energy along the inverse-mass-weighted forces. The triangle uses an
// orthotropic St. Venant–Kirchhoff material in plane stress; the tetrahedron the isotropic one
// of green_strain.cpp, optionally made robust to inversion. The XPBD tetrahedron writes the
// energy E·V·ψ₁ as ½ α⁻¹ C² with α = 1/E, so Young's modulus becomes the compliance.
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "projection.hpp"

namespace tessera {
namespace {

using Matrix3 = Eigen::Matrix<Real, 3, 3>;
using Matrix32 = Eigen::Matrix<Real, 3, 2>;
using Matrix2 = Eigen::Matrix<Real, 2, 2>;

/// Largest |ε_ij| at or below which an element counts as being at its rest shape: its energy
/// and energy gradient vanish, so there is nothing to project.
bool at_rest(Real largest_strain) { return largest_strain <= kDegenerateTolerance; }

struct LameParameters {
  Real mu;
  Real lambda;
};

bool valid_poisson_ratio(Real poissonRatio) {
  return poissonRatio > Real(-1) && poissonRatio < Real(0.5);
}

LameParameters lame_parameters(Real youngsModulus, Real poissonRatio) {
  return {youngsModulus / (2 * (1 + poissonRatio)),
          youngsModulus * poissonRatio / ((1 + poissonRatio) * (1 - 2 * poissonRatio))};
}

/// The energy of a tetrahedron, its gradient with respect to p0..p3, and the largest strain
/// component, with the material switch of solve_FEMTetraConstraint.
struct TetraEnergy {
  Real energy;
  detail::Gradients<4> gradient;
  Real largest_strain;
};

TetraEnergy tetra_energy(const Vector3r& p0, const Vector3r& p1, const Vector3r& p2,
                         const Vector3r& p3, Real restVolume, const Matrix3r& invRestMat,
                         const LameParameters& material, bool handleInversion) {
  Matrix3 edges;
  edges.col(0) = p1 - p0;
  edges.col(1) = p2 - p0;
  edges.col(2) = p3 - p0;
  const Real det_F = (edges * Matrix3(invRestMat)).determinant();

  Matrix3r epsilon, sigma;
  TetraEnergy result{};
  if (handleInversion &&
      det_F <= PositionBasedDynamics::kInversionDeterminantThreshold)
    PositionBasedDynamics::computeGreenStrainAndPiolaStressInversion(
        p0, p1, p2, p3, invRestMat, restVolume, material.mu, material.lambda, epsilon, sigma,
        result.energy);
  else
    PositionBasedDynamics::computeGreenStrainAndPiolaStress(p0, p1, p2, p3, invRestMat,
                                                            restVolume, material.mu,
                                                            material.lambda, epsilon, sigma,
                                                            result.energy);
  PositionBasedDynamics::computeGradCGreen(restVolume, invRestMat, sigma,
                                           result.gradient.data());
  result.largest_strain = epsilon.cwiseAbs().maxCoeff();
  return result;
}

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
  if (!(Real(0.5) * twice_area > kDegenerateTolerance)) {
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
  Vector3r* const corr[3] = {&corr0, &corr1, &corr2};

  // Plane-stress orthotropic elasticity in Voigt form, symmetrised.
  const Real poisson_product = poissonRatioXY * poissonRatioYX;
  const Real c_xx = youngsModulusX / (1 - poisson_product);
  const Real c_yy = youngsModulusY / (1 - poisson_product);
  const Real c_xy = Real(0.5) * (poissonRatioYX * youngsModulusX +
                                 poissonRatioXY * youngsModulusY) / (1 - poisson_product);
  const Real c_shear = youngsModulusShear;
  const bool positive_definite = youngsModulusX > 0 && youngsModulusY > 0 &&
                                 youngsModulusShear > 0 && poisson_product < 1 &&
                                 c_xx * c_yy - c_xy * c_xy > 0;
  if (!positive_definite) {
    detail::zero_corrections<3>(corr);
    return false;
  }

  Matrix32 edges;
  edges.col(0) = p1 - p0;
  edges.col(1) = p2 - p0;
  const Matrix2 inv_rest(invRestMat);
  const Matrix32 F = edges * inv_rest;
  const Matrix2 strain = Real(0.5) * (F.transpose() * F - Matrix2::Identity());
  if (at_rest(strain.cwiseAbs().maxCoeff())) {
    detail::zero_corrections<3>(corr);
    return true;
  }

  const Real stress_xx = c_xx * strain(0, 0) + c_xy * strain(1, 1);
  const Real stress_yy = c_xy * strain(0, 0) + c_yy * strain(1, 1);
  const Real stress_xy = c_shear * 2 * strain(0, 1);
  const Real energy = area * Real(0.5) *
                      (strain(0, 0) * stress_xx + strain(1, 1) * stress_yy +
                       2 * strain(0, 1) * stress_xy);
  Matrix2 stress;
  stress << stress_xx, stress_xy, stress_xy, stress_yy;
  const Matrix32 H = area * F * stress * inv_rest.transpose();

  detail::Gradients<3> gradient;
  gradient[1] = H.col(0);
  gradient[2] = H.col(1);
  gradient[0] = -(gradient[1] + gradient[2]);
  return detail::project_pbd<3>(energy, gradient, {invMass0, invMass1, invMass2}, Real(1),
                                corr);
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
  if (!(std::abs(signed_volume) > kDegenerateTolerance)) {
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
  Vector3r* const corr[4] = {&corr0, &corr1, &corr2, &corr3};
  if (!(youngsModulus > 0) || !valid_poisson_ratio(poissonRatio)) {
    detail::zero_corrections<4>(corr);
    return false;
  }
  const TetraEnergy element =
      tetra_energy(p0, p1, p2, p3, restVolume, invRestMat,
                   lame_parameters(youngsModulus, poissonRatio), handleInversion);
  if (at_rest(element.largest_strain)) {
    detail::zero_corrections<4>(corr);
    return true;
  }
  return detail::project_pbd<4>(element.energy, element.gradient,
                                {invMass0, invMass1, invMass2, invMass3}, Real(1), corr);
}

bool XPBD::solve_FEMTetraConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                    Real invMass1, const Vector3r& p2, Real invMass2,
                                    const Vector3r& p3, Real invMass3, const Real restVolume,
                                    const Matrix3r& invRestMat, const Real poissonRatio,
                                    const Real compliance, const bool handleInversion,
                                    const Real dt, Real& lambda, Vector3r& corr0,
                                    Vector3r& corr1, Vector3r& corr2, Vector3r& corr3) {
  Vector3r* const corr[4] = {&corr0, &corr1, &corr2, &corr3};
  if (!valid_poisson_ratio(poissonRatio) || !(restVolume > 0) || !(dt > 0) ||
      !(compliance >= 0)) {
    detail::zero_corrections<4>(corr);
    return false;
  }
  // Young's modulus 1: the energy is V ψ₁ and the real modulus enters as 1 / compliance.
  const TetraEnergy element = tetra_energy(p0, p1, p2, p3, restVolume, invRestMat,
                                           lame_parameters(Real(1), poissonRatio),
                                           handleInversion);
  // ψ₁ ≥ 0 for ν ∈ (-1, 0.5); the clamp only absorbs round-off.
  const Real C = std::sqrt(2 * std::max(element.energy, Real(0)));
  if (!(C > kDegenerateTolerance)) {
    detail::zero_corrections<4>(corr);
    return true;
  }
  detail::Gradients<4> gradient;
  for (int i = 0; i < 4; ++i) gradient[i] = element.gradient[i] / C;
  return detail::project_xpbd<4>(C, gradient, {invMass0, invMass1, invMass2, invMass3},
                                 compliance, dt, lambda, corr);
}

}  // namespace tessera
