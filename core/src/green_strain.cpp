// Green strain, St. Venant–Kirchhoff stress and energy of a tetrahedron, and the energy's
// gradient with respect to the four vertices. These are the building blocks of the FEM
// tetrahedron constraint (Bender et al. 2014): the constraint is the element's energy, its
// gradient comes from the first Piola–Kirchhoff stress. The inversion-robust variant follows
// Irving et al. 2004: evaluate the material on the diagonalised deformation gradient, where an
// inverted element shows up as one negative singular value that can be clamped.
//
// computeGradCGreen and computeGreenStrainAndPiolaStress are one lane of the FEM formula
// (kernels/fem-inl.h). computeGreenStrainAndPiolaStressInversion stays on Eigen's JacobiSVD:
// it is the independent reference the branch-free lane SVD (kernels/svd3-inl.h) that the FEM
// solve functions and batch kernels use is tested against.
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>

#include <tessera/core/position_based_dynamics.hpp>

#include "kernels/fem-inl.h"

namespace tessera {
namespace {

namespace lanes = HWY_NAMESPACE;

using Matrix3 = Eigen::Matrix<Real, 3, 3>;

/// F = [x2 - x1, x3 - x1, x4 - x1] · invRestMat.
Matrix3 deformation_gradient(const Vector3r& x1, const Vector3r& x2, const Vector3r& x3,
                             const Vector3r& x4, const Matrix3r& invRestMat) {
  Matrix3 edges;
  edges.col(0) = x2 - x1;
  edges.col(1) = x3 - x1;
  edges.col(2) = x4 - x1;
  return edges * Matrix3(invRestMat);
}

}  // namespace

void PositionBasedDynamics::computeGradCGreen(Real restVolume, const Matrix3r& invRestMat,
                                              const Matrix3r& sigma, Vector3r* J) {
  // ψ depends on the vertices through F = Ds · Dm⁻¹, so dE = V P : dF = (V P Dm⁻ᵀ) : dDs.
  lanes::Vec3<Real> gradient[4];
  lanes::green_strain_gradient<Real>(restVolume, lanes::from_eigen(invRestMat),
                                     lanes::from_eigen(sigma), gradient);
  for (int i = 0; i < 4; ++i) J[i] = lanes::to_eigen(gradient[i]);
}

void PositionBasedDynamics::computeGreenStrainAndPiolaStress(
    const Vector3r& x1, const Vector3r& x2, const Vector3r& x3, const Vector3r& x4,
    const Matrix3r& invRestMat, const Real restVolume, const Real mu, const Real lambda,
    Matrix3r& epsilon, Matrix3r& sigma, Real& energy) {
  const lanes::Vec3<Real> x[4] = {lanes::from_eigen(x1), lanes::from_eigen(x2),
                                  lanes::from_eigen(x3), lanes::from_eigen(x4)};
  const auto material = lanes::green_strain_material<Real>(
      lanes::deformation_gradient<Real>(x, lanes::from_eigen(invRestMat)), restVolume, mu,
      lambda);
  epsilon = lanes::to_eigen(material.strain);
  sigma = lanes::to_eigen(material.stress);
  energy = material.energy;
}

void PositionBasedDynamics::computeGreenStrainAndPiolaStressInversion(
    const Vector3r& x1, const Vector3r& x2, const Vector3r& x3, const Vector3r& x4,
    const Matrix3r& invRestMat, const Real restVolume, const Real mu, const Real lambda,
    Matrix3r& epsilon, Matrix3r& sigma, Real& energy) {
  const Matrix3 F = deformation_gradient(x1, x2, x3, x4, invRestMat);
  const Eigen::JacobiSVD<Matrix3> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Matrix3 U = svd.matrixU();
  Matrix3 V = svd.matrixV();
  Eigen::Matrix<Real, 3, 1> stretch = svd.singularValues();  // sorted, largest first

  // Make U and V proper rotations. Flipping the same column of both keeps F = U Σ Vᵀ; a
  // remaining reflection in U is moved onto the smallest singular value, which is where an
  // inverted element carries its sign.
  if (V.determinant() < 0) {
    V.col(2) = -V.col(2);
    U.col(2) = -U.col(2);
  }
  if (U.determinant() < 0) {
    U.col(2) = -U.col(2);
    stretch[2] = -stretch[2];
  }
  for (int i = 0; i < 3; ++i) stretch[i] = std::max(stretch[i], kInversionMinStretch);

  // The material on the diagonal F̂: ε̂, Ŝ and P̂ = F̂ Ŝ are diagonal too.
  const Eigen::Matrix<Real, 3, 1> strain =
      Real(0.5) * (stretch.cwiseProduct(stretch) - Eigen::Matrix<Real, 3, 1>::Ones());
  const Real trace = strain.sum();
  const Eigen::Matrix<Real, 3, 1> second_piola =
      2 * mu * strain + Eigen::Matrix<Real, 3, 1>::Constant(lambda * trace);
  const Eigen::Matrix<Real, 3, 1> first_piola = stretch.cwiseProduct(second_piola);

  epsilon = V * strain.asDiagonal() * V.transpose();
  sigma = U * first_piola.asDiagonal() * V.transpose();
  energy = restVolume * (mu * strain.squaredNorm() + Real(0.5) * lambda * trace * trace);
}

}  // namespace tessera
