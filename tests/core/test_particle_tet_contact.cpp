// Tests of the particle–tetrahedron contact: the info block of init_, the one-sided position
// solve (pushes out to C = 0, multiplier never negative, separated contacts untouched,
// corrections along the weighted gradient of C, momentum balanced) and Coulomb friction in the
// velocity solve (bounded by frictionCoeff · lambda, never reversing the sliding).
#include <tessera/core/position_based_dynamics.hpp>

#include "test_support.hpp"

namespace tessera::test {
namespace particle_tet_contact_tests {

using PBD = PositionBasedDynamics;
using Info = Eigen::Matrix<Real, 3, 3, Eigen::DontAlign>;

/// A particle, a tetrahedron and a contact point given by barycentric coordinates.
struct Scene {
  Real w0 = 1;
  Vector3r x0, v0 = Vector3r::Zero();
  std::array<Real, 4> w = {1, 1, 1, 1};
  std::array<Vector3r, 4> x, v = {Vector3r::Zero(), Vector3r::Zero(), Vector3r::Zero(),
                                  Vector3r::Zero()};
  Vector3r bary;
  Vector3r normal;

  Vector4r weights() const { return Vector4r(1 - bary.sum(), bary[0], bary[1], bary[2]); }
  Vector3r contact_point() const {
    const Vector4r b = weights();
    return b[0] * x[0] + b[1] * x[1] + b[2] * x[2] + b[3] * x[3];
  }
  Real C() const { return normal.dot(x0 - contact_point()); }
  Real inverse_effective_mass() const {
    const Vector4r b = weights();
    Real k = w0;
    for (int i = 0; i < 4; ++i) k += b[i] * b[i] * w[i];
    return k;
  }
  Vector3r relative_velocity() const {
    const Vector4r b = weights();
    return v0 - b[0] * v[0] - b[1] * v[1] - b[2] * v[2] - b[3] * v[3];
  }
  bool init(Info& info) const {
    return PBD::init_ParticleTetContactConstraint(w0, x0, v0, w.data(), x.data(), v.data(), bary,
                                                  normal, info);
  }
};

/// A particle 0.1 below the top face of a tet whose contact point is inside it, with random
/// masses, positions jittered, normal +z.
Scene penetrating_scene(Random& random) {
  Scene s;
  s.x = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0), Vector3r(0, 0, 1)};
  for (auto& p : s.x) p += Real(0.05) * random.vector();
  s.bary = Vector3r(random.uniform(Real(0.1), Real(0.3)), random.uniform(Real(0.1), Real(0.3)),
                    random.uniform(Real(0.1), Real(0.3)));
  s.normal = Vector3r(0, 0, 1);
  s.x0 = s.contact_point() - Real(0.1) * s.normal + Vector3r(Real(0.01), Real(-0.02), 0);
  s.w0 = random.inverse_mass();
  for (auto& m : s.w) m = random.inverse_mass();
  return s;
}

struct PositionStep {
  bool ok;
  Vector3r corr0;
  std::array<Vector3r, 4> corr;
};

PositionStep position_solve(const Scene& s, Info& info, Real& lambda) {
  PositionStep r;
  r.ok = PBD::solve_ParticleTetContactConstraint(s.w0, s.x0, s.w.data(), s.x.data(), s.bary,
                                                 info, lambda, r.corr0, r.corr.data());
  return r;
}

void apply(Scene& s, const PositionStep& r) {
  s.x0 += r.corr0;
  for (int i = 0; i < 4; ++i) s.x[i] += r.corr[i];
}

TEST(ParticleTetContact, InitInfoByHand) {
  Scene s;
  s.x = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0), Vector3r(0, 0, 1)};
  s.x0 = Vector3r(Real(0.25), Real(0.25), Real(0.2));
  s.v0 = Vector3r(1, 0, -2);
  s.bary = Vector3r(Real(0.25), Real(0.25), Real(0.25));
  s.normal = Vector3r(0, 0, 1);
  Info info;
  ASSERT_TRUE(s.init(info));
  // K = (1 + 4 · 1/16) I = 1.25 I; u = (1, 0, -2), u_t = (1, 0, 0).
  EXPECT_TRUE(near_relative(info.col(0), Vector3r(0, 0, 1)));
  EXPECT_TRUE(near_relative(info.col(1), Vector3r(1, 0, 0)));
  EXPECT_NEAR(info(0, 2), Real(0.8), kRoundOff);
  EXPECT_NEAR(info(1, 2), Real(0.8), kRoundOff);
  EXPECT_NEAR(info(2, 2), Real(-2), kRoundOff);

  // Pure normal approach: no tangent, no tangential impulse.
  s.v0 = Vector3r(0, 0, -3);
  ASSERT_TRUE(s.init(info));
  EXPECT_EQ(Vector3r(info.col(1)), Vector3r::Zero());
  EXPECT_EQ(info(1, 2), 0);
}

TEST(ParticleTetContact, InitRejectsStaticPairsAndNonUnitNormals) {
  Random random(91);
  Scene s = penetrating_scene(random);
  Info info;
  s.normal = Vector3r(0, 0, 2);
  EXPECT_FALSE(s.init(info));
  EXPECT_TRUE(info.isZero());
  s.normal = Vector3r(0, 0, 1);
  s.w0 = 0;
  s.w = {0, 0, 0, 0};
  EXPECT_FALSE(s.init(info));
  // The solver then does nothing.
  Real lambda = 0;
  const PositionStep r = position_solve(s, info, lambda);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.corr0, Vector3r::Zero());
  for (const auto& c : r.corr) EXPECT_EQ(c, Vector3r::Zero());
  EXPECT_EQ(lambda, 0);
}

TEST(ParticleTetContact, PenetrationIsResolvedInOneSolve) {
  Random random(92);
  for (int trial = 0; trial < 10; ++trial) {
    Scene s = penetrating_scene(random);
    Info info;
    ASSERT_TRUE(s.init(info));
    ASSERT_LT(s.C(), 0);
    const Scene before = s;
    Real lambda = 0;
    const PositionStep r = position_solve(s, info, lambda);
    ASSERT_TRUE(r.ok);
    EXPECT_GT(lambda, 0);
    EXPECT_NEAR(lambda, -before.C() / before.inverse_effective_mass(), kRoundOff);

    // Along -w ∇C (here Δλ = -C/(nᵀKn) > 0 pushes along +∇C).
    std::array<Vector3r, 5> corr = {r.corr0, r.corr[0], r.corr[1], r.corr[2], r.corr[3]};
    const std::array<Real, 5> w = {s.w0, s.w[0], s.w[1], s.w[2], s.w[3]};
    const std::array<Vector3r, 5> points = {s.x0, s.x[0], s.x[1], s.x[2], s.x[3]};
    auto constraint = [&](const std::array<Vector3r, 5>& y) {
      Scene t = before;
      t.x0 = y[0];
      for (int i = 0; i < 4; ++i) t.x[i] = y[i + 1];
      return t.C();
    };
    EXPECT_TRUE(along_weighted_gradient(corr, w, numeric_gradient<5>(constraint, points)));
    EXPECT_TRUE(conserves_linear_momentum(corr, w));

    apply(s, r);
    EXPECT_NEAR(s.C(), 0, 10 * kRoundOff);
    // Resolved: another iteration changes nothing.
    const PositionStep again = position_solve(s, info, lambda);
    EXPECT_LT(again.corr0.norm(), 10 * kRoundOff);
  }
}

TEST(ParticleTetContact, SeparatedContactIsLeftAlone) {
  Random random(93);
  Scene s = penetrating_scene(random);
  s.x0 = s.contact_point() + Real(0.2) * s.normal;
  Info info;
  ASSERT_TRUE(s.init(info));
  Real lambda = 0;
  const PositionStep r = position_solve(s, info, lambda);
  EXPECT_TRUE(r.ok);
  EXPECT_EQ(lambda, 0);
  EXPECT_EQ(r.corr0, Vector3r::Zero());
  for (const auto& c : r.corr) EXPECT_EQ(c, Vector3r::Zero());
}

TEST(ParticleTetContact, MultiplierNeverGoesNegative) {
  Random random(94);
  Scene s = penetrating_scene(random);
  Info info;
  ASSERT_TRUE(s.init(info));
  Real lambda = 0;
  apply(s, position_solve(s, info, lambda));
  const Real pushed = lambda;
  ASSERT_GT(pushed, 0);
  // Something else lifts the particle far away: the contact may only release what it pushed
  // (λ stops at 0), which leaves it separated (C > 0) instead of pulling it back to C = 0.
  s.x0 += Real(0.5) * s.normal;
  const Vector3r x0_before = s.x0;
  const PositionStep release = position_solve(s, info, lambda);
  EXPECT_EQ(lambda, 0);
  EXPECT_NEAR((release.corr0 - (-s.w0 * pushed * s.normal)).norm(), 0, kRoundOff);
  apply(s, release);
  EXPECT_GT(s.C(), 0);
  EXPECT_LT(s.x0.z(), x0_before.z());
  // Random wiggles never drive λ below zero.
  for (int iteration = 0; iteration < 50; ++iteration) {
    s.x0 += Real(0.1) * random.vector();
    apply(s, position_solve(s, info, lambda));
    EXPECT_GE(lambda, 0);
    EXPECT_GE(s.C(), -10 * kRoundOff);
  }
}

TEST(ParticleTetContact, StaticSidesAreNeverMoved) {
  Random random(95);
  Scene s = penetrating_scene(random);
  s.w0 = 0;  // a pinned particle: only the tet moves
  s.w[2] = 0;
  Info info;
  ASSERT_TRUE(s.init(info));
  Real lambda = 0;
  const PositionStep r = position_solve(s, info, lambda);
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.corr0, Vector3r::Zero());
  EXPECT_EQ(r.corr[2], Vector3r::Zero());
  apply(s, r);
  EXPECT_NEAR(s.C(), 0, 10 * kRoundOff);
}

TEST(ParticleTetContact, ContactRotatesWithTheScene) {
  Random random(96);
  const Scene s = penetrating_scene(random);
  const Matrix3r R = random.rotation();
  const Vector3r t = random.vector(-3, 3);
  Scene moved = s;
  moved.x0 = R * s.x0 + t;
  for (int i = 0; i < 4; ++i) moved.x[i] = R * s.x[i] + t;
  moved.normal = R * s.normal;
  Info info, moved_info;
  ASSERT_TRUE(s.init(info));
  ASSERT_TRUE(moved.init(moved_info));
  Real lambda = 0, moved_lambda = 0;
  const PositionStep a = position_solve(s, info, lambda);
  const PositionStep b = position_solve(moved, moved_info, moved_lambda);
  EXPECT_NEAR(lambda, moved_lambda, kRoundOff * lambda);
  EXPECT_TRUE(near_relative(b.corr0, R * a.corr0));
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(near_relative(b.corr[i], R * a.corr[i]));
}

struct VelocityStep {
  bool ok;
  Vector3r corr0;
  std::array<Vector3r, 4> corr;
};

VelocityStep velocity_solve(const Scene& s, Info& info, Real lambda, Real friction) {
  VelocityStep r;
  r.ok = PBD::velocitySolve_ParticleTetContactConstraint(s.w0, s.x0, s.v0, s.w.data(),
                                                         s.x.data(), s.v.data(), s.bary, lambda,
                                                         friction, info, r.corr0, r.corr.data());
  return r;
}

TEST(ParticleTetContact, FrictionIsBoundedAndNeverReversesSliding) {
  Random random(97);
  for (int trial = 0; trial < 20; ++trial) {
    Scene s = penetrating_scene(random);
    s.v0 = random.vector(-2, 2);
    for (auto& v : s.v) v = Real(0.3) * random.vector();
    Info info;
    ASSERT_TRUE(s.init(info));
    const Real lambda = random.uniform(Real(0.01), Real(3));
    const Real friction = random.uniform(Real(0.1), Real(1));
    const Vector3r u = s.relative_velocity();
    const Vector3r u_t = u - u.dot(s.normal) * s.normal;
    const VelocityStep r = velocity_solve(s, info, lambda, friction);
    ASSERT_TRUE(r.ok);

    // The applied impulse: Σ over the particle side is |corr_v0| / w0.
    const Real impulse = r.corr0.norm() / s.w0;
    EXPECT_LE(impulse, friction * lambda * (1 + kRoundOff));
    EXPECT_NEAR(impulse, std::min(u_t.norm() / s.inverse_effective_mass(), friction * lambda),
                kRoundOff * (1 + impulse));
    std::array<Vector3r, 5> dv = {r.corr0, r.corr[0], r.corr[1], r.corr[2], r.corr[3]};
    EXPECT_TRUE(conserves_linear_momentum(dv, {s.w0, s.w[0], s.w[1], s.w[2], s.w[3]}));

    s.v0 += r.corr0;
    for (int i = 0; i < 4; ++i) s.v[i] += r.corr[i];
    const Vector3r u_after = s.relative_velocity();
    const Vector3r u_t_after = u_after - u_after.dot(s.normal) * s.normal;
    EXPECT_NEAR(u_after.dot(s.normal), u.dot(s.normal), kRoundOff * (1 + u.norm()));
    EXPECT_GE(u_t_after.dot(u_t), -kRoundOff * u_t.squaredNorm());  // never reversed
    EXPECT_LE(u_t_after.norm(), u_t.norm() * (1 + kRoundOff));
    EXPECT_NEAR(u_t_after.norm(),
                std::max(u_t.norm() - s.inverse_effective_mass() * friction * lambda, Real(0)),
                10 * kRoundOff * (1 + u_t.norm()));
  }
}

TEST(ParticleTetContact, StrongFrictionSticks) {
  Random random(98);
  Scene s = penetrating_scene(random);
  s.v0 = Vector3r(2, -1, Real(-0.5));
  Info info;
  ASSERT_TRUE(s.init(info));
  const VelocityStep r = velocity_solve(s, info, Real(100), Real(1));
  ASSERT_TRUE(r.ok);
  s.v0 += r.corr0;
  for (int i = 0; i < 4; ++i) s.v[i] += r.corr[i];
  const Vector3r u = s.relative_velocity();
  EXPECT_LT((u - u.dot(s.normal) * s.normal).norm(), 10 * kRoundOff);
}

TEST(ParticleTetContact, NoFrictionWithoutSlidingOrNormalImpulse) {
  Random random(99);
  Scene s = penetrating_scene(random);
  s.v0 = Vector3r(1, 0, 0);
  Info info;
  ASSERT_TRUE(s.init(info));
  auto expect_none = [](const VelocityStep& r) {
    EXPECT_FALSE(r.ok);
    EXPECT_EQ(r.corr0, Vector3r::Zero());
    for (const auto& c : r.corr) EXPECT_EQ(c, Vector3r::Zero());
  };
  expect_none(velocity_solve(s, info, 0, Real(0.5)));
  expect_none(velocity_solve(s, info, Real(1), 0));
  s.v0 = Vector3r(0, 0, -1);  // purely normal
  expect_none(velocity_solve(s, info, Real(1), Real(0.5)));
}

}  // namespace particle_tet_contact_tests
}  // namespace tessera::test
