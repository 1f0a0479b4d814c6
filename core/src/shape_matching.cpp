// Shape matching (Müller, Heidelberger, Teschner, Gross 2005, "Meshless Deformations Based on
// Shape Matching"): a cluster of particles is pulled towards the best rigid (or, with
// allowStretch, the best linear) placement of its rest shape. The best rotation is the
// rotation factor of the polar decomposition of A_pq = Σ m (x - c) qᵀ, taken from an SVD so
// that it stays well defined when the cluster is planar and can be forced to det R = +1 when
// the cluster is inverted.
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <limits>
#include <utility>
#include <vector>

#include <tessera/core/position_based_dynamics.hpp>

namespace tessera {
namespace {

using Matrix3 = Eigen::Matrix<Real, 3, 3>;

/// Relative size below which a singular value (or eigenvalue) of a cluster matrix counts as
/// zero: a few hundred round-off units, so collinear input rounded to Real is still caught.
constexpr Real kRankTolerance = 256 * std::numeric_limits<Real>::epsilon();

/// Particle weights of a cluster: m = 1/w for movable particles, kShapeMatchingStaticMass
/// times the heaviest movable mass for static ones, 1 for all when every particle is static
/// (then nothing moves, but the centre of mass stays defined). The second member says whether
/// any particle is movable.
std::pair<std::vector<Real>, bool> cluster_masses(const Real invMasses[], int numPoints) {
  Real heaviest = 0;
  for (int i = 0; i < numPoints; ++i)
    if (invMasses[i] > 0) heaviest = std::max(heaviest, 1 / invMasses[i]);
  const bool any_movable = heaviest > 0;
  const Real static_mass =
      any_movable ? PositionBasedDynamics::kShapeMatchingStaticMass * heaviest : Real(1);
  std::vector<Real> mass(static_cast<std::size_t>(numPoints));
  for (int i = 0; i < numPoints; ++i) mass[i] = invMasses[i] > 0 ? 1 / invMasses[i] : static_mass;
  return {std::move(mass), any_movable};
}

}  // namespace

bool PositionBasedDynamics::init_ShapeMatchingConstraint(const Vector3r x0[],
                                                         const Real invMasses[],
                                                         const int numPoints,
                                                         Vector3r& restCm) {
  restCm.setZero();
  if (numPoints < 1 || x0 == nullptr || invMasses == nullptr) return false;
  const auto [mass, any_movable] = cluster_masses(invMasses, numPoints);
  Real total = 0;
  for (int i = 0; i < numPoints; ++i) {
    restCm += mass[i] * x0[i];
    total += mass[i];
  }
  restCm /= total;
  return true;
}

bool PositionBasedDynamics::solve_ShapeMatchingConstraint(
    const Vector3r x0[], const Vector3r x[], const Real invMasses[], const int numPoints,
    const Vector3r& restCm, const Real stiffness, const bool allowStretch, Vector3r corr[],
    Matrix3r* rot) {
  if (rot != nullptr) rot->setIdentity();
  if (numPoints < 1 || x0 == nullptr || x == nullptr || invMasses == nullptr ||
      corr == nullptr)
    return false;
  for (int i = 0; i < numPoints; ++i) corr[i].setZero();

  const auto [mass, any_movable] = cluster_masses(invMasses, numPoints);
  if (!any_movable) return false;

  Vector3r centre = Vector3r::Zero();
  Real total = 0;
  for (int i = 0; i < numPoints; ++i) {
    centre += mass[i] * x[i];
    total += mass[i];
  }
  centre /= total;

  Matrix3 A_pq = Matrix3::Zero();
  for (int i = 0; i < numPoints; ++i)
    A_pq += mass[i] * (x[i] - centre) * (x0[i] - restCm).transpose();

  Matrix3 transform;
  if (allowStretch) {
    Matrix3 A_qq = Matrix3::Zero();
    for (int i = 0; i < numPoints; ++i) {
      const Vector3r q = x0[i] - restCm;
      A_qq += mass[i] * q * q.transpose();
    }
    // A_qq is symmetric positive semi-definite; invert it through its eigen-decomposition so
    // a (nearly) coplanar rest cluster is recognised instead of producing a huge inverse.
    const Eigen::SelfAdjointEigenSolver<Matrix3> eigen(A_qq);
    const auto& values = eigen.eigenvalues();  // ascending
    if (!(values[2] > kDegenerateTolerance * kDegenerateTolerance) ||
        !(values[0] > kRankTolerance * values[2]))
      return false;
    transform = A_pq * eigen.eigenvectors() * values.cwiseInverse().asDiagonal() *
                eigen.eigenvectors().transpose();
  } else {
    // Polar decomposition A_pq = R S via A_pq = U Σ Vᵀ: R = U Vᵀ, with the column of the
    // smallest singular value flipped when U Vᵀ would be a reflection. The rotation is
    // determined as long as two singular values are non-zero (a planar cluster is fine).
    const Eigen::JacobiSVD<Matrix3> svd(A_pq, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const auto& singular = svd.singularValues();  // descending
    if (!(singular[0] > kDegenerateTolerance * kDegenerateTolerance) ||
        !(singular[1] > kRankTolerance * singular[0]))
      return false;
    Matrix3 U = svd.matrixU();
    const Matrix3& V = svd.matrixV();
    if ((U * V.transpose()).determinant() < 0) U.col(2) = -U.col(2);
    transform = U * V.transpose();
  }

  if (!transform.allFinite()) return false;
  for (int i = 0; i < numPoints; ++i)
    if (invMasses[i] > 0)
      corr[i] = stiffness * (transform * (x0[i] - restCm) + centre - x[i]);
  if (rot != nullptr) *rot = transform;
  return true;
}

}  // namespace tessera
