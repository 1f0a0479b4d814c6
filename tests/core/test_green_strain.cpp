// Tests of the St. Venant–Kirchhoff helpers of a tetrahedron: Green strain, first Piola
// stress and energy against closed forms (uniaxial stretch, rotation, inversion), the energy
// gradient of computeGradCGreen against finite differences, rigid-motion invariance, and
// finiteness on degenerate input.
#include <Eigen/Eigenvalues>

#include <tessera/core/position_based_dynamics.hpp>

#include "test_support.hpp"

namespace tessera::test {
namespace green_strain_tests {

using PBD = PositionBasedDynamics;

constexpr Real kMu = Real(3);
constexpr Real kLambda = Real(2);

/// Rest tetrahedron 0, e_x, e_y, e_z: invRestMat = I, volume 1/6, and F equals the edge matrix.
const std::array<Vector3r, 4> kUnitTet = {Vector3r(0, 0, 0), Vector3r(1, 0, 0),
                                          Vector3r(0, 1, 0), Vector3r(0, 0, 1)};
constexpr Real kUnitVolume = Real(1) / 6;

struct Material {
  Matrix3r epsilon;
  Matrix3r sigma;
  Real energy;
};

Material plain(const std::array<Vector3r, 4>& x, const Matrix3r& inv_rest = Matrix3r::Identity(),
               Real volume = kUnitVolume) {
  Material m;
  PBD::computeGreenStrainAndPiolaStress(x[0], x[1], x[2], x[3], inv_rest, volume, kMu, kLambda,
                                        m.epsilon, m.sigma, m.energy);
  return m;
}

Material inversion(const std::array<Vector3r, 4>& x,
                   const Matrix3r& inv_rest = Matrix3r::Identity(), Real volume = kUnitVolume) {
  Material m;
  PBD::computeGreenStrainAndPiolaStressInversion(x[0], x[1], x[2], x[3], inv_rest, volume, kMu,
                                                 kLambda, m.epsilon, m.sigma, m.energy);
  return m;
}

/// A tetrahedron deformed by F from kUnitTet (x1 fixed at the origin).
std::array<Vector3r, 4> deformed(const Matrix3r& F) {
  return {Vector3r::Zero(), F.col(0), F.col(1), F.col(2)};
}

::testing::AssertionResult matrices_near(const Matrix3r& a, const Matrix3r& b,
                                         Real tolerance = kRoundOff) {
  const Real scale = std::max({Real(1), a.norm(), b.norm()});
  if ((a - b).norm() <= tolerance * scale) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "\n" << a << "\nvs\n" << b;
}

std::array<Vector3r, 4> gradient_of(Real volume, const Matrix3r& inv_rest, const Matrix3r& sigma) {
  std::array<Vector3r, 4> J;
  PBD::computeGradCGreen(volume, inv_rest, sigma, J.data());
  return J;
}

TEST(GreenStrain, GradientOfUnitStressOnUnitTetIsTheEdgeFrame) {
  const auto J = gradient_of(1, Matrix3r::Identity(), Matrix3r::Identity());
  EXPECT_TRUE(near_relative(J[1], Vector3r(1, 0, 0)));
  EXPECT_TRUE(near_relative(J[2], Vector3r(0, 1, 0)));
  EXPECT_TRUE(near_relative(J[3], Vector3r(0, 0, 1)));
  EXPECT_TRUE(near_relative(J[0], Vector3r(-1, -1, -1)));
}

TEST(GreenStrain, UniaxialStretchMatchesClosedForm) {
  for (const Real s : {Real(1.3), Real(0.8), Real(2)}) {
    const Material m = plain(deformed(Vector3r(s, 1, 1).asDiagonal()));
    const Real e = Real(0.5) * (s * s - 1);
    const Matrix3r expected_strain = Vector3r(e, 0, 0).asDiagonal();
    const Matrix3r expected_stress =
        Vector3r(s * (2 * kMu + kLambda) * e, kLambda * e, kLambda * e).asDiagonal();
    EXPECT_TRUE(matrices_near(m.epsilon, expected_strain));
    EXPECT_TRUE(matrices_near(m.sigma, expected_stress));
    EXPECT_NEAR(m.energy, kUnitVolume * (kMu * e * e + Real(0.5) * kLambda * e * e),
                kRoundOff * m.energy);

    // Above the clamp and uninverted, the inversion-robust variant is the same material.
    const Material robust = inversion(deformed(Vector3r(s, 1, 1).asDiagonal()));
    EXPECT_TRUE(matrices_near(robust.epsilon, expected_strain));
    EXPECT_TRUE(matrices_near(robust.sigma, expected_stress));
    EXPECT_NEAR(robust.energy, m.energy, kRoundOff * m.energy);
  }
}

TEST(GreenStrain, PureRotationHasNoStrainStressOrEnergy) {
  Random random(7);
  for (int trial = 0; trial < 10; ++trial) {
    const Matrix3r R = random.rotation();
    for (const Material& m : {plain(deformed(R)), inversion(deformed(R))}) {
      EXPECT_LT(m.epsilon.norm(), 10 * kRoundOff);
      EXPECT_LT(m.sigma.norm(), 100 * kRoundOff);
      EXPECT_LT(std::abs(m.energy), kRoundOff);
    }
  }
}

TEST(GreenStrain, InversionVariantEqualsPlainAboveTheClamp) {
  Random random(11);
  int compared = 0;
  while (compared < 20) {
    Matrix3r F = Matrix3r::Identity();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) F(i, j) += random.uniform(Real(-0.3), Real(0.3));
    // Smallest singular value of F from the eigenvalues of FᵀF (ascending).
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<Real, 3, 3>> eigen(F.transpose() * F);
    const Real smallest_stretch = std::sqrt(eigen.eigenvalues()[0]);
    if (F.determinant() <= 0 || smallest_stretch < PBD::kInversionMinStretch + Real(0.05))
      continue;
    // A general rest shape, so invRestMat and the volume enter as well.
    Matrix3r rest = Matrix3r::Identity();
    for (int k = 0; k < 3; ++k) rest.col(k) += Real(0.3) * random.vector();
    const Matrix3r inv_rest = rest.inverse();
    const Vector3r origin(Real(0.1), Real(0.2), Real(0.3));
    std::array<Vector3r, 4> y = {origin, origin, origin, origin};
    const Matrix3r edges = F * rest;
    for (int k = 0; k < 3; ++k) y[k + 1] += edges.col(k);
    const Real volume = std::abs(rest.determinant()) / 6;
    const Material a = plain(y, inv_rest, volume), b = inversion(y, inv_rest, volume);
    EXPECT_TRUE(matrices_near(a.epsilon, b.epsilon, 10 * kRoundOff));
    EXPECT_TRUE(matrices_near(a.sigma, b.sigma, 10 * kRoundOff));
    EXPECT_NEAR(a.energy, b.energy, 10 * kRoundOff * std::max(a.energy, Real(1e-3)));
    ++compared;
  }
}

TEST(GreenStrain, InvertedStretchIsClampedAndCarriesItsSign) {
  // F = diag(1, 1, -0.5): the reflection sits on the smallest singular value, which is then
  // clamped to kInversionMinStretch, so the element is evaluated as if compressed to 0.577.
  const Material m = inversion(deformed(Vector3r(1, 1, Real(-0.5)).asDiagonal()));
  const Real c = PBD::kInversionMinStretch;
  const Real e = Real(0.5) * (c * c - 1);
  EXPECT_TRUE(matrices_near(m.epsilon, Vector3r(0, 0, e).asDiagonal()));
  EXPECT_TRUE(matrices_near(
      m.sigma, Vector3r(kLambda * e, kLambda * e, c * (2 * kMu + kLambda) * e).asDiagonal()));
  EXPECT_NEAR(m.energy, kUnitVolume * (kMu + Real(0.5) * kLambda) * e * e,
              kRoundOff * m.energy);
  // Its stress pushes the inverted axis back: the energy gradient on x4 points along -z,
  // so the correction -∇ moves x4 towards +z, out of the inversion.
  const auto J = gradient_of(kUnitVolume, Matrix3r::Identity(), m.sigma);
  EXPECT_LT(J[3].z(), 0);
}

TEST(GreenStrain, GradientMatchesFiniteDifferenceOfEnergy) {
  Random random(3);
  for (int trial = 0; trial < 10; ++trial) {
    std::array<Vector3r, 4> rest;
    Matrix3r D;
    do {
      for (auto& p : rest) p = random.vector();
      for (int k = 0; k < 3; ++k) D.col(k) = rest[k + 1] - rest[0];
    } while (std::abs(D.determinant()) < Real(0.1));
    const Matrix3r inv_rest = D.inverse();
    const Real volume = std::abs(D.determinant()) / 6;
    std::array<Vector3r, 4> x = rest;
    for (auto& p : x) p += Real(0.2) * random.vector();

    auto energy_plain = [&](const std::array<Vector3r, 4>& y) {
      return plain(y, inv_rest, volume).energy;
    };
    const auto numeric = numeric_gradient<4>(energy_plain, x);
    const auto J = gradient_of(volume, inv_rest, plain(x, inv_rest, volume).sigma);
    const Real scale = max_norm(numeric);
    for (int i = 0; i < 4; ++i)
      EXPECT_TRUE(near_relative(J[i], numeric[i], kFiniteDifferenceTolerance * std::max(scale, Real(1))))
          << "vertex " << i;
  }
}

TEST(GreenStrain, RigidMotionLeavesEnergyAndRotatesTheGradient) {
  Random random(5);
  const Matrix3r F = (Matrix3r() << 1.2, 0.1, 0, -0.2, 0.9, 0.1, 0.05, 0, 1.1).finished();
  const std::array<Vector3r, 4> x = deformed(F);
  for (int trial = 0; trial < 5; ++trial) {
    const Matrix3r R = random.rotation();
    const Vector3r t = random.vector(-5, 5);
    const std::array<Vector3r, 4> y = transformed(x, R, t);
    for (const bool robust : {false, true}) {
      const Material a = robust ? inversion(x) : plain(x);
      const Material b = robust ? inversion(y) : plain(y);
      EXPECT_NEAR(a.energy, b.energy, 10 * kRoundOff * a.energy);
      EXPECT_TRUE(matrices_near(b.epsilon, a.epsilon, 10 * kRoundOff));  // material strain
      EXPECT_TRUE(matrices_near(b.sigma, R * a.sigma, 10 * kRoundOff));  // P rotates with x
      const auto Ja = gradient_of(kUnitVolume, Matrix3r::Identity(), a.sigma);
      const auto Jb = gradient_of(kUnitVolume, Matrix3r::Identity(), b.sigma);
      for (int i = 0; i < 4; ++i) EXPECT_TRUE(near_relative(Jb[i], R * Ja[i], 10 * kRoundOff));
      // The forces of an element balance and exert no torque.
      EXPECT_TRUE(conserves_linear_momentum(Jb, {1, 1, 1, 1}));
      EXPECT_TRUE(conserves_angular_momentum(y, Jb, {1, 1, 1, 1}, 10 * kRoundOff));
    }
  }
}

TEST(GreenStrain, DegenerateInputStaysFinite) {
  const std::array<std::array<Vector3r, 4>, 3> cases = {{
      {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0), Vector3r(1, 1, 0)},  // flat
      {Vector3r(1, 1, 1), Vector3r(1, 1, 1), Vector3r(1, 1, 1), Vector3r(1, 1, 1)},  // point
      {Vector3r(0, 0, 0), Vector3r(0, 0, 1), Vector3r(0, 1, 0), Vector3r(1, 0, 0)},  // inverted
  }};
  for (const auto& x : cases) {
    for (const Material& m : {plain(x), inversion(x)}) {
      EXPECT_TRUE(m.epsilon.allFinite());
      EXPECT_TRUE(m.sigma.allFinite());
      EXPECT_TRUE(std::isfinite(m.energy));
      EXPECT_GE(m.energy, 0);
    }
  }
  // Collapsed to a point, the robust material sees every axis compressed to the clamp.
  const Material point = inversion(cases[1]);
  const Real c = PBD::kInversionMinStretch, e = Real(0.5) * (c * c - 1);
  EXPECT_NEAR(point.energy, kUnitVolume * (3 * kMu * e * e + Real(4.5) * kLambda * e * e),
              kRoundOff * point.energy);
}

}  // namespace green_strain_tests
}  // namespace tessera::test
