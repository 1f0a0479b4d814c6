// Tests of shape matching: rigid and affine motions are matched exactly, the goal is a rigid
// (or best linear) image of the rest shape that rotates with the input, the corrections carry
// no momentum and follow the gradient of the matching energy, static particles anchor the
// goal, and degenerate clusters are refused.
#include <Eigen/LU>

#include <tessera/core/position_based_dynamics.hpp>

#include "test_support.hpp"

namespace tessera::test {
namespace shape_matching_tests {

using PBD = PositionBasedDynamics;
constexpr int kPoints = 7;
using Cluster = std::array<Vector3r, kPoints>;
using Masses = std::array<Real, kPoints>;

struct Match {
  bool ok;
  Cluster corr;
  Matrix3r rot;
};

Match solve(const Cluster& x0, const Cluster& x, const Masses& w, Real stiffness,
            bool allow_stretch) {
  Vector3r rest_cm;
  EXPECT_TRUE(PBD::init_ShapeMatchingConstraint(x0.data(), w.data(), kPoints, rest_cm));
  Match m;
  m.ok = PBD::solve_ShapeMatchingConstraint(x0.data(), x.data(), w.data(), kPoints, rest_cm,
                                            stiffness, allow_stretch, m.corr.data(), &m.rot);
  return m;
}

Cluster random_cluster(Random& random) {
  Cluster x;
  for (auto& p : x) p = random.vector(-1, 1);
  return x;
}

Masses random_masses(Random& random) {
  Masses w;
  for (auto& m : w) m = random.inverse_mass();
  return w;
}

Vector3r centre_of_mass(const Cluster& x, const Masses& w) {
  Vector3r c = Vector3r::Zero();
  Real total = 0;
  for (int i = 0; i < kPoints; ++i) {
    c += x[i] / w[i];
    total += 1 / w[i];
  }
  return c / total;
}

::testing::AssertionResult is_rotation(const Matrix3r& R) {
  if ((R.transpose() * R - Matrix3r::Identity()).norm() < 10 * kRoundOff &&
      std::abs(R.determinant() - 1) < 10 * kRoundOff)
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "not a rotation:\n" << R;
}

TEST(ShapeMatching, InitComputesTheWeightedRestCentre) {
  const Cluster x0 = {Vector3r(0, 0, 0), Vector3r(2, 0, 0), Vector3r(0, 2, 0), Vector3r(0, 0, 2),
                      Vector3r(1, 1, 1), Vector3r(-1, 0, 0), Vector3r(0, 0, 0)};
  const Masses w = {1, Real(0.5), 1, 1, 1, 1, 1};  // masses 1, 2, 1, 1, 1, 1, 1
  Vector3r rest_cm;
  ASSERT_TRUE(PBD::init_ShapeMatchingConstraint(x0.data(), w.data(), kPoints, rest_cm));
  EXPECT_TRUE(near_relative(rest_cm, Vector3r(4, 3, 3) / 8));

  // A static particle weighs kShapeMatchingStaticMass times the heaviest movable one (2).
  Masses pinned = w;
  pinned[3] = 0;
  ASSERT_TRUE(PBD::init_ShapeMatchingConstraint(x0.data(), pinned.data(), kPoints, rest_cm));
  const Real heavy = 2 * PBD::kShapeMatchingStaticMass;
  EXPECT_TRUE(near_relative(rest_cm, (Vector3r(4, 3, 1) + heavy * Vector3r(0, 0, 2)) / (7 + heavy)));

  EXPECT_FALSE(PBD::init_ShapeMatchingConstraint(x0.data(), w.data(), 0, rest_cm));
  EXPECT_FALSE(PBD::init_ShapeMatchingConstraint(nullptr, w.data(), kPoints, rest_cm));
  EXPECT_FALSE(PBD::init_ShapeMatchingConstraint(x0.data(), nullptr, kPoints, rest_cm));
}

TEST(ShapeMatching, RigidMotionIsMatchedExactly) {
  Random random(71);
  for (int trial = 0; trial < 10; ++trial) {
    const Cluster x0 = random_cluster(random);
    const Masses w = random_masses(random);
    const Matrix3r R = random.rotation();
    const Match m = solve(x0, transformed(x0, R, random.vector(-5, 5)), w, 1, false);
    ASSERT_TRUE(m.ok);
    EXPECT_LT(max_norm(m.corr), 20 * kRoundOff);
    EXPECT_TRUE(m.rot.isApprox(R, 10 * kRoundOff));
  }
}

TEST(ShapeMatching, StiffnessOneMovesOntoARigidImageOfTheRestShape) {
  Random random(72);
  for (int trial = 0; trial < 10; ++trial) {
    const Cluster x0 = random_cluster(random);
    const Masses w = random_masses(random);
    Cluster x = transformed(x0, random.rotation(), random.vector(-2, 2));
    for (auto& p : x) p += Real(0.3) * random.vector();
    const Match m = solve(x0, x, w, 1, false);
    ASSERT_TRUE(m.ok);
    ASSERT_TRUE(is_rotation(m.rot));
    const Vector3r c = centre_of_mass(x, w), c0 = centre_of_mass(x0, w);
    for (int i = 0; i < kPoints; ++i)
      EXPECT_TRUE(near_relative(x[i] + m.corr[i], m.rot * (x0[i] - c0) + c, 10 * kRoundOff));
    // Stiffness scales the correction.
    const Match half = solve(x0, x, w, Real(0.5), false);
    for (int i = 0; i < kPoints; ++i)
      EXPECT_TRUE(near_relative(half.corr[i], Real(0.5) * m.corr[i], 10 * kRoundOff));
    // Mass-weighted corrections carry neither linear nor angular momentum.
    EXPECT_TRUE(conserves_linear_momentum(m.corr, w, 10 * kRoundOff));
    EXPECT_TRUE(conserves_angular_momentum(x, m.corr, w, 10 * kRoundOff));
  }
}

TEST(ShapeMatching, AffineMotionIsMatchedExactlyWithStretch) {
  Random random(73);
  for (int trial = 0; trial < 10; ++trial) {
    const Cluster x0 = random_cluster(random);
    const Masses w = random_masses(random);
    Matrix3r A = Matrix3r::Identity();
    for (int k = 0; k < 3; ++k) A.col(k) += Real(0.4) * random.vector();
    const Match exact = solve(x0, transformed(x0, A, random.vector(-2, 2)), w, 1, true);
    ASSERT_TRUE(exact.ok);
    EXPECT_LT(max_norm(exact.corr), 50 * kRoundOff);
    EXPECT_TRUE(exact.rot.isApprox(A, 20 * kRoundOff));

    // With noise: the goal is an affine image of the rest shape, the corrections balanced.
    Cluster x = transformed(x0, A, Vector3r::Zero());
    for (auto& p : x) p += Real(0.2) * random.vector();
    const Match m = solve(x0, x, w, 1, true);
    ASSERT_TRUE(m.ok);
    const Vector3r c = centre_of_mass(x, w), c0 = centre_of_mass(x0, w);
    for (int i = 0; i < kPoints; ++i)
      EXPECT_TRUE(near_relative(x[i] + m.corr[i], m.rot * (x0[i] - c0) + c, 20 * kRoundOff));
    EXPECT_TRUE(conserves_linear_momentum(m.corr, w, 10 * kRoundOff));
    EXPECT_TRUE(conserves_angular_momentum(x, m.corr, w, 10 * kRoundOff));
  }
}

TEST(ShapeMatching, GoalRotatesWithTheInput) {
  Random random(74);
  const Cluster x0 = random_cluster(random);
  const Masses w = random_masses(random);
  Cluster x = x0;
  for (auto& p : x) p += Real(0.4) * random.vector();
  for (const bool stretch : {false, true}) {
    const Match m = solve(x0, x, w, Real(0.8), stretch);
    const Matrix3r Q = random.rotation();
    const Match moved = solve(x0, transformed(x, Q, random.vector(-3, 3)), w, Real(0.8), stretch);
    ASSERT_TRUE(m.ok && moved.ok);
    EXPECT_TRUE(moved.rot.isApprox(Q * m.rot, 10 * kRoundOff));
    for (int i = 0; i < kPoints; ++i)
      EXPECT_TRUE(near_relative(moved.corr[i], Q * m.corr[i], 10 * kRoundOff));
  }
}

TEST(ShapeMatching, CorrectionFollowsTheMatchingEnergyGradient) {
  // E(x) = ½ Σ m |T q + c - x|² at the optimal T and c; by the envelope theorem
  // ∇_i E = m_i (x_i - goal_i), so corr_i = -k w_i ∇_i E.
  Random random(75);
  const Cluster x0 = random_cluster(random);
  const Masses w = random_masses(random);
  Cluster x = transformed(x0, random.rotation(), Vector3r::Zero());
  for (auto& p : x) p += Real(0.3) * random.vector();
  for (const bool stretch : {false, true}) {
    auto energy = [&](const Cluster& y) {
      const Match m = solve(x0, y, w, 1, stretch);
      Real e = 0;
      for (int i = 0; i < kPoints; ++i) e += Real(0.5) / w[i] * m.corr[i].squaredNorm();
      return e;
    };
    const Match m = solve(x0, x, w, Real(0.7), stretch);
    Real fitted = 0;
    EXPECT_TRUE(along_weighted_gradient(m.corr, w, numeric_gradient<kPoints>(energy, x),
                                        kFiniteDifferenceTolerance, &fitted));
    EXPECT_NEAR(fitted, Real(0.7), 2 * kFiniteDifferenceTolerance);
  }
}

TEST(ShapeMatching, StaticParticlesStayAndAnchorTheGoal) {
  Random random(76);
  const Cluster x0 = random_cluster(random);
  Masses w = random_masses(random);
  w[2] = 0;
  // Rotate the cluster about the static particle: a rigid motion that keeps it in place.
  const Matrix3r R = random.rotation();
  const Cluster x = transformed(x0, R, x0[2] - R * x0[2]);
  const Match m = solve(x0, x, w, 1, false);
  ASSERT_TRUE(m.ok);
  EXPECT_EQ(m.corr[2], Vector3r::Zero());
  EXPECT_LT(max_norm(m.corr), 50 * kRoundOff);

  // Displace everything else: the goal passes (nearly) through the static particle.
  Cluster y = x;
  for (int i = 0; i < kPoints; ++i)
    if (i != 2) y[i] += Vector3r(Real(0.5), 0, 0) + Real(0.1) * random.vector();
  const Match pulled = solve(x0, y, w, 1, false);
  ASSERT_TRUE(pulled.ok);
  EXPECT_EQ(pulled.corr[2], Vector3r::Zero());
  Vector3r rest_cm;
  PBD::init_ShapeMatchingConstraint(x0.data(), w.data(), kPoints, rest_cm);
  Vector3r centre = Vector3r::Zero();
  Real total = 0;
  Real heaviest = 0;
  for (int i = 0; i < kPoints; ++i)
    if (w[i] > 0) heaviest = std::max(heaviest, 1 / w[i]);
  for (int i = 0; i < kPoints; ++i) {
    const Real mass = w[i] > 0 ? 1 / w[i] : PBD::kShapeMatchingStaticMass * heaviest;
    centre += mass * y[i];
    total += mass;
  }
  centre /= total;
  const Vector3r goal_of_static = pulled.rot * (x0[2] - rest_cm) + centre;
  EXPECT_LT((goal_of_static - y[2]).norm(), Real(0.01));
}

TEST(ShapeMatching, ReflectedClusterGetsAProperRotation) {
  Random random(77);
  const Cluster x0 = random_cluster(random);
  const Masses w = random_masses(random);
  const Matrix3r mirror = Vector3r(1, 1, -1).asDiagonal();
  const Match m = solve(x0, transformed(x0, mirror, Vector3r::Zero()), w, 1, false);
  ASSERT_TRUE(m.ok);
  EXPECT_TRUE(is_rotation(m.rot));
  EXPECT_TRUE(all_finite(m.corr));
  EXPECT_TRUE(conserves_linear_momentum(m.corr, w, 10 * kRoundOff));
}

TEST(ShapeMatching, PlanarClusterHasARotationButNoStretchFit) {
  Random random(78);
  Cluster x0;
  for (auto& p : x0) p = Vector3r(random.uniform(-1, 1), random.uniform(-1, 1), 0);
  const Masses w = random_masses(random);
  const Matrix3r R = random.rotation();
  const Match rigid = solve(x0, transformed(x0, R, Vector3r(1, 2, 3)), w, 1, false);
  ASSERT_TRUE(rigid.ok);
  EXPECT_TRUE(rigid.rot.isApprox(R, 10 * kRoundOff));
  EXPECT_LT(max_norm(rigid.corr), 20 * kRoundOff);

  const Match stretch = solve(x0, transformed(x0, R, Vector3r(1, 2, 3)), w, 1, true);
  EXPECT_FALSE(stretch.ok);
  EXPECT_EQ(stretch.rot, Matrix3r::Identity());
  for (const auto& c : stretch.corr) EXPECT_EQ(c, Vector3r::Zero());
}

TEST(ShapeMatching, RepeatedProjectionRestoresTheShape) {
  Random random(79);
  const Cluster x0 = random_cluster(random);
  const Masses w = random_masses(random);
  Cluster x = x0;
  for (auto& p : x) p += Real(0.5) * random.vector();
  auto residual = [&] {
    const Match m = solve(x0, x, w, 1, false);
    return max_norm(m.corr);
  };
  const Real initial = residual();
  for (int iteration = 0; iteration < 30; ++iteration) {
    const Match m = solve(x0, x, w, Real(0.5), false);
    for (int i = 0; i < kPoints; ++i) x[i] += m.corr[i];
  }
  EXPECT_LT(residual(), 1e-4 * initial + 20 * kRoundOff);
}

TEST(ShapeMatching, DegenerateClustersAreRefused) {
  Random random(80);
  const Masses w = random_masses(random);
  const Cluster x0 = random_cluster(random);
  auto expect_refused = [](const Match& m) {
    EXPECT_FALSE(m.ok);
    EXPECT_EQ(m.rot, Matrix3r::Identity());
    for (const auto& c : m.corr) EXPECT_EQ(c, Vector3r::Zero());
  };
  // Every current point on one line: the rotation about it is undetermined.
  Cluster line;
  const Vector3r direction = random.unit_vector();
  for (auto& p : line) p = Vector3r(1, 2, 3) + random.uniform(-1, 1) * direction;
  expect_refused(solve(x0, line, w, 1, false));
  // The best linear map onto a line is defined: it flattens the rest shape onto it.
  const Match flattened = solve(x0, line, w, 1, true);
  EXPECT_TRUE(flattened.ok);
  EXPECT_TRUE(all_finite(flattened.corr));
  // Every point coincident, rest or current.
  Cluster point;
  point.fill(Vector3r(1, 1, 1));
  expect_refused(solve(x0, point, w, 1, false));
  expect_refused(solve(point, x0, w, 1, false));
  expect_refused(solve(point, x0, w, 1, true));
  // Every particle static.
  Cluster moved = x0;
  moved[0] += Vector3r(1, 0, 0);
  Masses fixed;
  fixed.fill(0);
  expect_refused(solve(x0, moved, fixed, 1, false));
  // Null arrays and empty clusters.
  Vector3r rest_cm = Vector3r::Zero();
  Cluster corr;
  EXPECT_FALSE(PBD::solve_ShapeMatchingConstraint(x0.data(), x0.data(), w.data(), 0, rest_cm, 1,
                                                  false, corr.data()));
  EXPECT_FALSE(PBD::solve_ShapeMatchingConstraint(x0.data(), nullptr, w.data(), kPoints, rest_cm,
                                                  1, false, corr.data()));
}

}  // namespace shape_matching_tests
}  // namespace tessera::test
