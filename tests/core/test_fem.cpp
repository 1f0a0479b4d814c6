// Tests of the FEM constraints: the orthotropic plane-stress triangle, the St. Venant–Kirchhoff
// tetrahedron (with and without inversion handling) and its XPBD form. Each projection is
// checked against a reference energy written from the documented formulas: the correction
// must be -C / Σ w |∇C|² · w ∇C with ∇C from finite differences of that energy.
#include <limits>

#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "test_support.hpp"

namespace tessera::test {
namespace fem_tests {

using PBD = PositionBasedDynamics;

// ---------------------------------------------------------------------------------------------
// Triangle

struct Orthotropic {
  Real Ex, Ey, G, nu_xy, nu_yx;
};

/// An isotropic material in the orthotropic parameters.
Orthotropic isotropic(Real E, Real nu) { return {E, E, E / (2 * (1 + nu)), nu, nu}; }

const Orthotropic kCloth{Real(1000), Real(600), Real(200), Real(0.3), Real(0.18)};

/// The documented energy: area · ½ (ε_xx S_xx + ε_yy S_yy + 2 ε_xy S_xy).
Real triangle_energy(const std::array<Vector3r, 3>& p, Real area, const Matrix2r& inv_rest,
                     const Orthotropic& m) {
  Eigen::Matrix<Real, 3, 2> edges;
  edges.col(0) = p[1] - p[0];
  edges.col(1) = p[2] - p[0];
  const Eigen::Matrix<Real, 3, 2> F = edges * inv_rest;
  const Matrix2r e = Real(0.5) * (F.transpose() * F - Matrix2r::Identity());
  const Real d = 1 - m.nu_xy * m.nu_yx;
  const Real c_xy = Real(0.5) * (m.nu_yx * m.Ex + m.nu_xy * m.Ey) / d;
  const Real s_xx = m.Ex / d * e(0, 0) + c_xy * e(1, 1);
  const Real s_yy = c_xy * e(0, 0) + m.Ey / d * e(1, 1);
  const Real s_xy = m.G * 2 * e(0, 1);
  return area * Real(0.5) * (e(0, 0) * s_xx + e(1, 1) * s_yy + 2 * e(0, 1) * s_xy);
}

struct TriangleResult {
  bool ok;
  std::array<Vector3r, 3> corr;
};

TriangleResult solve_triangle(const std::array<Vector3r, 3>& p, const std::array<Real, 3>& w,
                              Real area, const Matrix2r& inv_rest, const Orthotropic& m) {
  TriangleResult r;
  r.ok = PBD::solve_FEMTriangleConstraint(p[0], w[0], p[1], w[1], p[2], w[2], area, inv_rest,
                                          m.Ex, m.Ey, m.G, m.nu_xy, m.nu_yx, r.corr[0],
                                          r.corr[1], r.corr[2]);
  return r;
}

/// A random rest triangle in 3D, initialised.
struct RestTriangle {
  std::array<Vector3r, 3> p;
  Real area;
  Matrix2r inv_rest;
};

RestTriangle random_rest_triangle(Random& random) {
  RestTriangle t;
  do {
    for (auto& x : t.p) x = random.vector();
  } while ((t.p[1] - t.p[0]).cross(t.p[2] - t.p[0]).norm() < Real(0.3));
  EXPECT_TRUE(PBD::init_FEMTriangleConstraint(t.p[0], t.p[1], t.p[2], t.area, t.inv_rest));
  return t;
}

/// Checks Δp = -C / Σ w|∇C|² · w ∇C with C the reference energy and ∇C by finite differences.
template <std::size_t N, class Energy>
void expect_pbd_projection_of(const Energy& energy, const std::array<Vector3r, N>& x,
                              const std::array<Real, N>& w,
                              const std::array<Vector3r, N>& corr) {
  const auto gradient = numeric_gradient<int(N)>(energy, x);
  Real fitted = 0;
  ASSERT_TRUE(along_weighted_gradient(corr, w, gradient, kFiniteDifferenceTolerance, &fitted));
  Real weighted = 0;
  for (std::size_t i = 0; i < N; ++i) weighted += w[i] * gradient[i].squaredNorm();
  const Real expected = energy(x) / weighted;
  EXPECT_NEAR(fitted, expected, 2 * kFiniteDifferenceTolerance * std::abs(expected));
}

TEST(FEMTriangle, InitBuildsThePlaneFrameOfTheRestTriangle) {
  Real area = 0;
  Matrix2r inv_rest;
  ASSERT_TRUE(PBD::init_FEMTriangleConstraint(Vector3r(0, 0, 0), Vector3r(2, 0, 0),
                                              Vector3r(0, 1, 0), area, inv_rest));
  EXPECT_NEAR(area, 1, kRoundOff);
  EXPECT_TRUE(inv_rest.isApprox(Vector2r(Real(0.5), 1).asDiagonal().toDenseMatrix(), kRoundOff));

  // A tilted triangle: the first axis is the edge p0→p1, the second is in the plane.
  const Vector3r a(1, 1, 1), b(1, 4, 5), c(3, 1, 1);  // |b - a| = 5
  ASSERT_TRUE(PBD::init_FEMTriangleConstraint(a, b, c, area, inv_rest));
  EXPECT_NEAR(area, Real(0.5) * (b - a).cross(c - a).norm(), kRoundOff * area);
  const Matrix2r rest = inv_rest.inverse();
  EXPECT_NEAR(rest(0, 0), 5, 10 * kRoundOff);
  EXPECT_NEAR(rest(1, 0), 0, 10 * kRoundOff);
  EXPECT_NEAR(rest(0, 1), (c - a).dot(b - a) / 5, 10 * kRoundOff);
  EXPECT_NEAR(std::abs(rest(1, 1)), 2 * area / 5, 10 * kRoundOff);
}

TEST(FEMTriangle, InitRejectsZeroArea) {
  Real area = 7;
  Matrix2r inv_rest;
  EXPECT_FALSE(PBD::init_FEMTriangleConstraint(Vector3r(0, 0, 0), Vector3r(1, 1, 1),
                                               Vector3r(2, 2, 2), area, inv_rest));
  EXPECT_EQ(area, 0);
  EXPECT_TRUE(inv_rest.allFinite());
  EXPECT_FALSE(PBD::init_FEMTriangleConstraint(Vector3r(1, 2, 3), Vector3r(1, 2, 3),
                                               Vector3r(0, 1, 0), area, inv_rest));
}

TEST(FEMTriangle, RestShapeAndRigidMotionsNeedNoCorrection) {
  Random random(21);
  for (int trial = 0; trial < 10; ++trial) {
    const RestTriangle t = random_rest_triangle(random);
    const auto moved = transformed(t.p, random.rotation(), random.vector(-3, 3));
    for (const auto& p : {t.p, moved}) {
      EXPECT_LT(triangle_energy(p, t.area, t.inv_rest, kCloth), 1e3 * kRoundOff * kRoundOff);
      const TriangleResult r = solve_triangle(p, {1, 1, 1}, t.area, t.inv_rest, kCloth);
      EXPECT_TRUE(r.ok);
      EXPECT_LT(max_norm(r.corr), 10 * kRoundOff);
    }
  }
}

TEST(FEMTriangle, IsotropicUniaxialStretchMatchesClosedForm) {
  Real area;
  Matrix2r inv_rest;
  ASSERT_TRUE(PBD::init_FEMTriangleConstraint(Vector3r(0, 0, 0), Vector3r(1, 0, 0),
                                              Vector3r(0, 1, 0), area, inv_rest));
  const Real E = 100, nu = Real(0.25), s = Real(1.2);
  const std::array<Vector3r, 3> p = {Vector3r(0, 0, 0), Vector3r(s, 0, 0), Vector3r(0, 1, 0)};
  // F = diag(s, 1): ε_xx = e, S_xx = E e / (1 - ν²), S_yy = ν E e / (1 - ν²).
  const Real e = Real(0.5) * (s * s - 1);
  const Real s_xx = E * e / (1 - nu * nu), s_yy = nu * E * e / (1 - nu * nu);
  const Real energy = area * Real(0.5) * e * s_xx;
  EXPECT_NEAR(triangle_energy(p, area, inv_rest, isotropic(E, nu)), energy, kRoundOff * energy);
  // ∇_{p1} = area (s S_xx, 0, 0), ∇_{p2} = area (0, S_yy, 0), ∇_{p0} = -(sum).
  const std::array<Vector3r, 3> gradient = {Vector3r(-area * s * s_xx, -area * s_yy, 0),
                                            Vector3r(area * s * s_xx, 0, 0),
                                            Vector3r(0, area * s_yy, 0)};
  const std::array<Real, 3> w = {1, Real(0.5), 2};
  Real weighted = 0;
  for (int i = 0; i < 3; ++i) weighted += w[i] * gradient[i].squaredNorm();
  const TriangleResult r = solve_triangle(p, w, area, inv_rest, isotropic(E, nu));
  ASSERT_TRUE(r.ok);
  for (int i = 0; i < 3; ++i)
    EXPECT_TRUE(near_relative(r.corr[i], -energy / weighted * w[i] * gradient[i]));
}

TEST(FEMTriangle, CorrectionIsTheProjectionOfTheEnergy) {
  Random random(22);
  for (int trial = 0; trial < 20; ++trial) {
    const RestTriangle t = random_rest_triangle(random);
    std::array<Vector3r, 3> p = t.p;
    for (auto& x : p) x += Real(0.15) * random.vector();
    const std::array<Real, 3> w = {random.inverse_mass(), random.inverse_mass(),
                                   random.inverse_mass()};
    const TriangleResult r = solve_triangle(p, w, t.area, t.inv_rest, kCloth);
    ASSERT_TRUE(r.ok);
    ASSERT_TRUE(all_finite(r.corr));
    expect_pbd_projection_of(
        [&](const std::array<Vector3r, 3>& y) {
          return triangle_energy(y, t.area, t.inv_rest, kCloth);
        },
        p, w, r.corr);
    EXPECT_TRUE(conserves_linear_momentum(r.corr, w));
    EXPECT_TRUE(conserves_angular_momentum(p, r.corr, w, Real(0.05)));

    // Rigidly moving the input rotates the correction.
    const Matrix3r R = random.rotation();
    const TriangleResult moved =
        solve_triangle(transformed(p, R, random.vector(-2, 2)), w, t.area, t.inv_rest, kCloth);
    for (int i = 0; i < 3; ++i)
      EXPECT_TRUE(near_relative(moved.corr[i], R * r.corr[i], 20 * kRoundOff));

    // A static particle is never moved; the others still follow the energy gradient.
    const std::array<Real, 3> pinned = {w[0], 0, w[2]};
    const TriangleResult fixed = solve_triangle(p, pinned, t.area, t.inv_rest, kCloth);
    EXPECT_TRUE(fixed.ok);
    EXPECT_EQ(fixed.corr[1], Vector3r::Zero());
  }
}

TEST(FEMTriangle, RepeatedProjectionReachesTheRestShape) {
  Random random(23);
  const RestTriangle t = random_rest_triangle(random);
  std::array<Vector3r, 3> p = t.p;
  for (auto& x : p) x += Real(0.3) * random.vector();
  const std::array<Real, 3> w = {1, 2, Real(0.5)};
  const Real initial = triangle_energy(p, t.area, t.inv_rest, kCloth);
  ASSERT_GT(initial, 0);
  Real energy = initial;
  for (int iteration = 0; iteration < 200; ++iteration) {
    const TriangleResult r = solve_triangle(p, w, t.area, t.inv_rest, kCloth);
    for (int i = 0; i < 3; ++i) p[i] += r.corr[i];
    energy = triangle_energy(p, t.area, t.inv_rest, kCloth);
    // Newton steps on C = energy do not decrease it monotonically for an anisotropic
    // element; the trend is what converges.
    if (iteration == 40) {
      EXPECT_LT(energy, Real(0.01) * initial);
    }
  }
  EXPECT_LT(energy, 1e-6 * initial);
}

TEST(FEMTriangle, DegenerateInputGivesFalseAndZeroCorrections) {
  Random random(24);
  const RestTriangle t = random_rest_triangle(random);
  const Vector3r q(Real(0.3), Real(-0.2), Real(0.5));
  // Collapsed to one point: F = 0, the energy gradient vanishes.
  TriangleResult r = solve_triangle({q, q, q}, {1, 1, 1}, t.area, t.inv_rest, kCloth);
  EXPECT_FALSE(r.ok);
  for (const auto& c : r.corr) EXPECT_EQ(c, Vector3r::Zero());
  // Every particle static.
  std::array<Vector3r, 3> stretched = t.p;
  stretched[1] += Vector3r(Real(0.4), 0, 0);
  r = solve_triangle(stretched, {0, 0, 0}, t.area, t.inv_rest, kCloth);
  EXPECT_FALSE(r.ok);
  for (const auto& c : r.corr) EXPECT_EQ(c, Vector3r::Zero());
  // Collinear current shape: still a finite projection.
  r = solve_triangle({Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(2, 0, 0)}, {1, 1, 1},
                     t.area, t.inv_rest, kCloth);
  EXPECT_TRUE(all_finite(r.corr));
  // Materials that are not positive definite.
  for (const Orthotropic& bad : {Orthotropic{0, 1, 1, 0, 0}, Orthotropic{1, 1, -1, 0, 0},
                                 Orthotropic{1, 1, 1, 2, Real(0.5)},
                                 Orthotropic{1, 100, 1, Real(0.9), Real(0.9)}}) {
    r = solve_triangle(stretched, {1, 1, 1}, t.area, t.inv_rest, bad);
    EXPECT_FALSE(r.ok);
    for (const auto& c : r.corr) EXPECT_EQ(c, Vector3r::Zero());
  }
}

// ---------------------------------------------------------------------------------------------
// Tetrahedron

constexpr Real kYoung = Real(1000);
constexpr Real kPoisson = Real(0.3);

struct RestTet {
  std::array<Vector3r, 4> p;
  Real volume;
  Matrix3r inv_rest;
};

RestTet random_rest_tet(Random& random) {
  RestTet t;
  for (;;) {
    for (auto& x : t.p) x = random.vector();
    Matrix3r D;
    for (int k = 0; k < 3; ++k) D.col(k) = t.p[k + 1] - t.p[0];
    if (std::abs(D.determinant()) > Real(0.2)) break;
  }
  EXPECT_TRUE(PBD::init_FEMTetraConstraint(t.p[0], t.p[1], t.p[2], t.p[3], t.volume, t.inv_rest));
  return t;
}

Real lame_mu(Real E, Real nu) { return E / (2 * (1 + nu)); }
Real lame_lambda(Real E, Real nu) { return E * nu / ((1 + nu) * (1 - 2 * nu)); }

Real tet_energy(const std::array<Vector3r, 4>& p, const RestTet& t, Real E = kYoung,
                Real nu = kPoisson) {
  Matrix3r epsilon, sigma;
  Real energy;
  PBD::computeGreenStrainAndPiolaStress(p[0], p[1], p[2], p[3], t.inv_rest, t.volume,
                                        lame_mu(E, nu), lame_lambda(E, nu), epsilon, sigma,
                                        energy);
  return energy;
}

Real signed_volume(const std::array<Vector3r, 4>& p) {
  return (p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]) / 6;
}

struct TetResult {
  bool ok;
  std::array<Vector3r, 4> corr;
};

TetResult solve_tet(const std::array<Vector3r, 4>& p, const std::array<Real, 4>& w,
                    const RestTet& t, bool handle_inversion, Real E = kYoung,
                    Real nu = kPoisson) {
  TetResult r;
  r.ok = PBD::solve_FEMTetraConstraint(p[0], w[0], p[1], w[1], p[2], w[2], p[3], w[3], t.volume,
                                       t.inv_rest, E, nu, handle_inversion, r.corr[0],
                                       r.corr[1], r.corr[2], r.corr[3]);
  return r;
}

TEST(FEMTetra, InitOfTheUnitTetrahedron) {
  Real volume;
  Matrix3r inv_rest;
  ASSERT_TRUE(PBD::init_FEMTetraConstraint(Vector3r(0, 0, 0), Vector3r(2, 0, 0),
                                           Vector3r(0, 1, 0), Vector3r(0, 0, 3), volume,
                                           inv_rest));
  EXPECT_NEAR(volume, 1, kRoundOff);
  EXPECT_TRUE(inv_rest.isApprox(Vector3r(Real(0.5), 1, Real(1) / 3).asDiagonal().toDenseMatrix(),
                                kRoundOff));
  // The mirrored tetrahedron is accepted with a positive volume.
  ASSERT_TRUE(PBD::init_FEMTetraConstraint(Vector3r(0, 0, 0), Vector3r(0, 1, 0),
                                           Vector3r(2, 0, 0), Vector3r(0, 0, 3), volume,
                                           inv_rest));
  EXPECT_NEAR(volume, 1, kRoundOff);
  EXPECT_FALSE(PBD::init_FEMTetraConstraint(Vector3r(0, 0, 0), Vector3r(1, 0, 0),
                                            Vector3r(0, 1, 0), Vector3r(1, 1, 0), volume,
                                            inv_rest));
  EXPECT_EQ(volume, 0);
  EXPECT_TRUE(inv_rest.allFinite());
}

TEST(FEMTetra, RestShapeAndRigidMotionsNeedNoCorrection) {
  Random random(31);
  for (int trial = 0; trial < 10; ++trial) {
    const RestTet t = random_rest_tet(random);
    for (const auto& p : {t.p, transformed(t.p, random.rotation(), random.vector(-3, 3))}) {
      for (const bool inversion : {false, true}) {
        const TetResult r = solve_tet(p, {1, 1, 1, 1}, t, inversion);
        EXPECT_TRUE(r.ok);
        EXPECT_LT(max_norm(r.corr), 10 * kRoundOff);
      }
    }
  }
}

TEST(FEMTetra, CorrectionIsTheProjectionOfTheEnergy) {
  Random random(32);
  for (int trial = 0; trial < 20; ++trial) {
    const RestTet t = random_rest_tet(random);
    std::array<Vector3r, 4> p = t.p;
    for (auto& x : p) x += Real(0.1) * random.vector();
    if (signed_volume(p) * signed_volume(t.p) <= 0) continue;
    const std::array<Real, 4> w = {random.inverse_mass(), random.inverse_mass(),
                                   random.inverse_mass(), random.inverse_mass()};
    const TetResult r = solve_tet(p, w, t, false);
    ASSERT_TRUE(r.ok);
    ASSERT_TRUE(all_finite(r.corr));
    expect_pbd_projection_of([&](const std::array<Vector3r, 4>& y) { return tet_energy(y, t); },
                             p, w, r.corr);
    EXPECT_TRUE(conserves_linear_momentum(r.corr, w));
    EXPECT_TRUE(conserves_angular_momentum(p, r.corr, w, Real(0.05)));

    const Matrix3r R = random.rotation();
    const TetResult moved = solve_tet(transformed(p, R, random.vector(-2, 2)), w, t, false);
    for (int i = 0; i < 4; ++i)
      EXPECT_TRUE(near_relative(moved.corr[i], R * r.corr[i], 20 * kRoundOff));

    const std::array<Real, 4> pinned = {0, w[1], w[2], w[3]};
    const TetResult fixed = solve_tet(p, pinned, t, false);
    EXPECT_TRUE(fixed.ok);
    EXPECT_EQ(fixed.corr[0], Vector3r::Zero());
  }
}

TEST(FEMTetra, InversionHandlingUsesTheRobustStressWhenNearlyFlat) {
  Random random(33);
  const RestTet t = random_rest_tet(random);
  // Push the last vertex through the opposite face: det F < 0.
  std::array<Vector3r, 4> p = t.p;
  const Vector3r face_normal = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
  const Real height = (p[3] - p[0]).dot(face_normal);
  p[3] -= Real(1.5) * height * face_normal;
  const std::array<Real, 4> w = {1, 1, 1, 1};
  const Real mu = lame_mu(kYoung, kPoisson), lambda = lame_lambda(kYoung, kPoisson);
  Matrix3r epsilon, sigma;
  Real energy;
  PBD::computeGreenStrainAndPiolaStressInversion(p[0], p[1], p[2], p[3], t.inv_rest, t.volume,
                                                 mu, lambda, epsilon, sigma, energy);
  std::array<Vector3r, 4> gradient;
  PBD::computeGradCGreen(t.volume, t.inv_rest, sigma, gradient.data());
  Real weighted = 0;
  for (int i = 0; i < 4; ++i) weighted += w[i] * gradient[i].squaredNorm();
  const TetResult r = solve_tet(p, w, t, true);
  ASSERT_TRUE(r.ok);
  for (int i = 0; i < 4; ++i)
    EXPECT_TRUE(near_relative(r.corr[i], -energy / weighted * w[i] * gradient[i], 10 * kRoundOff));
}

TEST(FEMTetra, InvertedTetrahedronRecoversWithInversionHandling) {
  Random random(34);
  for (int trial = 0; trial < 5; ++trial) {
    const RestTet t = random_rest_tet(random);
    std::array<Vector3r, 4> p = t.p;
    const Vector3r face_normal = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
    const Real height = (p[3] - p[0]).dot(face_normal);
    p[3] -= Real(1.6) * height * face_normal;  // mirrored to 60% height
    const Real rest_sign = signed_volume(t.p) > 0 ? Real(1) : Real(-1);
    ASSERT_LT(rest_sign * signed_volume(p), 0);
    const std::array<Real, 4> w = {1, Real(0.5), 2, 1};
    for (int iteration = 0; iteration < 100; ++iteration) {
      const TetResult r = solve_tet(p, w, t, true);
      ASSERT_TRUE(all_finite(r.corr)) << iteration;
      for (int i = 0; i < 4; ++i) p[i] += r.corr[i];
    }
    EXPECT_GT(rest_sign * signed_volume(p), Real(0.5) * t.volume);
    EXPECT_LT(tet_energy(p, t), 1e-3 * kYoung * t.volume);
  }
}

TEST(FEMTetra, RepeatedProjectionReachesTheRestShape) {
  Random random(35);
  const RestTet t = random_rest_tet(random);
  std::array<Vector3r, 4> p = t.p;
  for (auto& x : p) x += Real(0.15) * random.vector();
  const std::array<Real, 4> w = {1, 2, Real(0.5), 1};
  const Real initial = tet_energy(p, t);
  Real energy = initial;
  for (int iteration = 0; iteration < 200; ++iteration) {
    const TetResult r = solve_tet(p, w, t, false);
    for (int i = 0; i < 4; ++i) p[i] += r.corr[i];
    energy = tet_energy(p, t);
    // Newton steps on C = energy do not decrease it monotonically for an anisotropic
    // element; the trend is what converges.
    if (iteration == 40) {
      EXPECT_LT(energy, Real(0.01) * initial);
    }
  }
  EXPECT_LT(energy, 1e-6 * initial);
}

TEST(FEMTetra, DegenerateInputGivesFalseOrFiniteCorrections) {
  Random random(36);
  const RestTet t = random_rest_tet(random);
  std::array<Vector3r, 4> stretched = t.p;
  stretched[3] += Vector3r(Real(0.3), 0, 0);
  auto expect_zero_false = [](const TetResult& r) {
    EXPECT_FALSE(r.ok);
    for (const auto& c : r.corr) EXPECT_EQ(c, Vector3r::Zero());
  };
  expect_zero_false(solve_tet(stretched, {0, 0, 0, 0}, t, false));
  expect_zero_false(solve_tet(stretched, {1, 1, 1, 1}, t, false, 0));
  expect_zero_false(solve_tet(stretched, {1, 1, 1, 1}, t, false, kYoung, Real(0.5)));
  expect_zero_false(solve_tet(stretched, {1, 1, 1, 1}, t, false, kYoung, Real(-1)));
  const Vector3r q(1, 2, 3);
  for (const bool inversion : {false, true}) {
    // Collapsed to a point: finite, and without inversion handling the gradient vanishes.
    const TetResult point = solve_tet({q, q, q, q}, {1, 1, 1, 1}, t, inversion);
    EXPECT_TRUE(all_finite(point.corr));
    if (!inversion) expect_zero_false(point);
    // Flat.
    std::array<Vector3r, 4> flat = t.p;
    flat[3] = (t.p[0] + t.p[1] + t.p[2]) / 3;
    EXPECT_TRUE(all_finite(solve_tet(flat, {1, 1, 1, 1}, t, inversion).corr));
  }
}

// ---------------------------------------------------------------------------------------------
// XPBD tetrahedron

/// C = sqrt(2 V ψ₁) with ψ₁ the energy density for Young's modulus 1.
Real xpbd_constraint(const std::array<Vector3r, 4>& p, const RestTet& t) {
  return std::sqrt(2 * tet_energy(p, t, 1, kPoisson));
}

struct XpbdResult {
  bool ok;
  std::array<Vector3r, 4> corr;
};

XpbdResult solve_xpbd(const std::array<Vector3r, 4>& p, const std::array<Real, 4>& w,
                      const RestTet& t, Real compliance, Real dt, Real& lambda,
                      Real nu = kPoisson) {
  XpbdResult r;
  r.ok = XPBD::solve_FEMTetraConstraint(p[0], w[0], p[1], w[1], p[2], w[2], p[3], w[3],
                                        t.volume, t.inv_rest, nu, compliance, false, dt, lambda,
                                        r.corr[0], r.corr[1], r.corr[2], r.corr[3]);
  return r;
}

TEST(XPBDFEMTetra, MultiplierFollowsTheComplianceFormula) {
  Random random(41);
  const RestTet t = random_rest_tet(random);
  std::array<Vector3r, 4> p = t.p;
  for (auto& x : p) x += Real(0.1) * random.vector();
  const std::array<Real, 4> w = {1, 2, Real(0.5), Real(1.5)};
  const Real compliance = Real(1e-3), dt = Real(0.01);
  const Real alpha = compliance / (dt * dt);
  auto constraint = [&](const std::array<Vector3r, 4>& y) { return xpbd_constraint(y, t); };

  Real lambda = 0;
  for (int iteration = 0; iteration < 3; ++iteration) {
    const Real C = constraint(p);
    const auto gradient = numeric_gradient<4>(constraint, p);
    Real weighted = 0;
    for (int i = 0; i < 4; ++i) weighted += w[i] * gradient[i].squaredNorm();
    const Real expected_delta = (-C - alpha * lambda) / (weighted + alpha);
    const Real before = lambda;
    const XpbdResult r = solve_xpbd(p, w, t, compliance, dt, lambda);
    ASSERT_TRUE(r.ok);
    // Once λ settles, Δλ is a small difference of C and α̃λ, and λ + Δλ is rounded to λ's
    // precision: allow that round-off (a few ulps of C, α̃λ and λ) besides the FD error.
    const Real round_off = 8 * std::numeric_limits<Real>::epsilon() *
                           ((C + alpha * std::abs(before)) / (weighted + alpha) +
                            std::abs(before));
    EXPECT_NEAR(lambda - before, expected_delta,
                2 * kFiniteDifferenceTolerance * std::abs(expected_delta) + round_off);
    ASSERT_TRUE(along_weighted_gradient(r.corr, w, gradient));
    for (int i = 0; i < 4; ++i)
      EXPECT_TRUE(near_relative(r.corr[i], (lambda - before) * w[i] * gradient[i],
                                kFiniteDifferenceTolerance));
    EXPECT_TRUE(conserves_linear_momentum(r.corr, w));
    for (int i = 0; i < 4; ++i) p[i] += r.corr[i];
  }
  EXPECT_LT(lambda, 0);  // λ accumulates: the element is stretched, C > 0, Δλ < 0 each time
}

TEST(XPBDFEMTetra, ZeroComplianceDrivesTheConstraintToZero) {
  Random random(42);
  const RestTet t = random_rest_tet(random);
  std::array<Vector3r, 4> p = t.p;
  for (auto& x : p) x += Real(0.15) * random.vector();
  const std::array<Real, 4> w = {1, 1, 2, Real(0.5)};
  const Real initial = xpbd_constraint(p, t);
  Real lambda = 0;
  for (int iteration = 0; iteration < 200; ++iteration) {
    const XpbdResult r = solve_xpbd(p, w, t, 0, Real(0.01), lambda);
    ASSERT_TRUE(all_finite(r.corr));
    for (int i = 0; i < 4; ++i) p[i] += r.corr[i];
  }
  EXPECT_LT(xpbd_constraint(p, t), 1e-3 * initial);

  // A large compliance (a soft material) moves much less in one step than a stiff one.
  std::array<Vector3r, 4> q = t.p;
  q[1] += Vector3r(Real(0.2), 0, 0);
  Real stiff_lambda = 0, soft_lambda = 0;
  const XpbdResult stiff = solve_xpbd(q, w, t, 0, Real(0.01), stiff_lambda);
  const XpbdResult soft = solve_xpbd(q, w, t, Real(1), Real(0.01), soft_lambda);
  EXPECT_LT(max_norm(soft.corr), Real(0.01) * max_norm(stiff.corr));
}

TEST(XPBDFEMTetra, InvalidInputLeavesTheMultiplierUnchanged) {
  Random random(43);
  const RestTet t = random_rest_tet(random);
  std::array<Vector3r, 4> p = t.p;
  p[2] += Vector3r(0, Real(0.3), 0);
  for (const Real dt : {Real(0), Real(-0.01)}) {
    Real lambda = Real(-0.25);
    const XpbdResult r = solve_xpbd(p, {1, 1, 1, 1}, t, Real(1e-4), dt, lambda);
    EXPECT_FALSE(r.ok);
    EXPECT_EQ(lambda, Real(-0.25));
    for (const auto& c : r.corr) EXPECT_EQ(c, Vector3r::Zero());
  }
  Real lambda = Real(-0.25);
  EXPECT_FALSE(solve_xpbd(p, {1, 1, 1, 1}, t, Real(1e-4), Real(0.01), lambda, Real(0.5)).ok);
  EXPECT_FALSE(solve_xpbd(p, {1, 1, 1, 1}, t, Real(-1), Real(0.01), lambda).ok);
  EXPECT_FALSE(solve_xpbd(p, {0, 0, 0, 0}, t, Real(1e-4), Real(0.01), lambda).ok);
  EXPECT_EQ(lambda, Real(-0.25));
  // NaN positions: no rest shape, so false, with zero corrections and λ unchanged.
  std::array<Vector3r, 4> not_a_number = p;
  not_a_number[1].x() = std::numeric_limits<Real>::quiet_NaN();
  const XpbdResult nan_result =
      solve_xpbd(not_a_number, {1, 1, 1, 1}, t, Real(1e-4), Real(0.01), lambda);
  EXPECT_FALSE(nan_result.ok);
  EXPECT_EQ(lambda, Real(-0.25));
  for (const auto& c : nan_result.corr) EXPECT_EQ(c, Vector3r::Zero());
  // At rest the gradient is undefined: zero corrections, true, λ unchanged.
  const XpbdResult rest = solve_xpbd(t.p, {1, 1, 1, 1}, t, Real(1e-4), Real(0.01), lambda);
  EXPECT_TRUE(rest.ok);
  EXPECT_EQ(lambda, Real(-0.25));
  for (const auto& c : rest.corr) EXPECT_EQ(c, Vector3r::Zero());
}

// The rest test is on the strain, not on C = sqrt(2 V ψ₁), which scales with sqrt(V): a
// millimetre element strained by 1 % is projected (in float, C ≈ 1e-7 is below the tolerance).
TEST(XPBDFEMTetra, ASmallElementStrainedByOnePercentIsProjected) {
  Random random(45);
  const RestTet unit = random_rest_tet(random);
  for (const Real size : {Real(1), Real(1e-3)}) {
    std::array<Vector3r, 4> rest;
    for (int i = 0; i < 4; ++i) rest[i] = unit.p[i] * size;
    RestTet t;
    t.p = rest;
    ASSERT_TRUE(PBD::init_FEMTetraConstraint(rest[0], rest[1], rest[2], rest[3], t.volume,
                                             t.inv_rest));
    std::array<Vector3r, 4> p = rest;
    for (auto& x : p) x.x() *= Real(1.01);
    Real lambda = 0;
    const XpbdResult r = solve_xpbd(p, {1, 1, 1, 1}, t, Real(1e-4), Real(0.01), lambda);
    EXPECT_TRUE(r.ok) << size;
    EXPECT_NE(lambda, Real(0)) << size;
    Real moved = 0;
    for (const auto& c : r.corr) moved += c.norm();
    EXPECT_GT(moved, 0) << size;
  }
}

// Σ w |∇E|² grows as the cube of C: an element stretched so far that it overflows (float;
// double's range holds these) is left alone, never reported projected with a zero or NaN step.
TEST(XPBDFEMTetra, AnOverflowingStretchIsLeftAloneNotSteppedByZero) {
  Random random(44);
  const RestTet t = random_rest_tet(random);
  for (const Real scale : {Real(1e5), Real(1e6), Real(1e7), Real(1e8)}) {
    std::array<Vector3r, 4> p = t.p;
    for (auto& x : p) x *= scale;
    Real lambda = Real(-0.25);
    const XpbdResult r = solve_xpbd(p, {1, 1, 1, 1}, t, Real(1e-4), Real(0.01), lambda);
    EXPECT_TRUE(std::isfinite(lambda)) << scale;
    Real moved = 0;
    for (const auto& c : r.corr) {
      EXPECT_TRUE(c.allFinite()) << scale;
      moved += c.norm();
    }
    if (r.ok) {
      EXPECT_NE(lambda, Real(-0.25)) << scale;
      EXPECT_GT(moved, 0) << scale;
    } else {
      EXPECT_EQ(lambda, Real(-0.25)) << scale;
      EXPECT_EQ(moved, 0) << scale;
    }
  }
}

}  // namespace fem_tests
}  // namespace tessera::test
