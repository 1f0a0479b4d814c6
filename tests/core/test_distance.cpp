// Tests of the distance constraint, PBD and XPBD forms: known answers, momentum, static
// particles, rigid-motion invariance, the direction of the correction against a
// finite-difference gradient, one-step satisfaction, degenerate input and the XPBD multiplier;
// and the one-division rule distance constraints are projected by (DirectionValue) against the
// general rule with n = d/|d|.
#include <limits>

#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

// The lane formula itself, compiled here for the static SIMD target only, on one lane.
#include "../../core/src/kernels/distance-inl.h"

#include "test_support.hpp"

namespace tessera::test {
namespace distance_tests {

using Points = std::array<Vector3r, 2>;
using Masses = std::array<Real, 2>;

using Projection = ScalarProjection<2>;

Projection project(const Points& x, const Masses& w, Real rest_length, Real stiffness) {
  Projection r;
  r.ok = PositionBasedDynamics::solve_DistanceConstraint(x[0], w[0], x[1], w[1], rest_length,
                                                         stiffness, r.corr[0], r.corr[1]);
  return r;
}

Projection project_xpbd(const Points& x, const Masses& w, Real rest_length, Real compliance,
                        Real dt, Real& lambda) {
  Projection r;
  r.ok = XPBD::solve_DistanceConstraint(x[0], w[0], x[1], w[1], rest_length, compliance, dt,
                                        lambda, r.corr[0], r.corr[1]);
  return r;
}

Real distance_constraint(const Points& x, Real rest_length) {
  return (x[0] - x[1]).norm() - rest_length;
}

TEST(DistanceConstraint, HandCheckedStretchedPair) {
  // Length 3 along x, rest 1, w = (1, 3): C = 2, s = 2 / 4, Δp0 = -0.5·1·(1,0,0),
  // Δp1 = -0.5·3·(-1,0,0).
  const Points x = {Vector3r(3, 0, 0), Vector3r(0, 0, 0)};
  const Projection r = project(x, {1, 3}, 1, 1);
  ASSERT_TRUE(r.ok);
  EXPECT_TRUE(near_relative(r.corr[0], Vector3r(-0.5, 0, 0)));
  EXPECT_TRUE(near_relative(r.corr[1], Vector3r(1.5, 0, 0)));
  // Half stiffness halves the correction.
  const Projection half = project(x, {1, 3}, 1, Real(0.5));
  EXPECT_TRUE(near_relative(half.corr[0], Vector3r(-0.25, 0, 0)));
  EXPECT_TRUE(near_relative(half.corr[1], Vector3r(0.75, 0, 0)));
}

TEST(DistanceConstraint, CompressedPairIsPushedApart) {
  const Points x = {Vector3r(0, 0, 0), Vector3r(0, 0.5, 0)};
  const Projection r = project(x, {1, 1}, 2, 1);
  ASSERT_TRUE(r.ok);
  EXPECT_TRUE(near_relative(r.corr[0], Vector3r(0, -0.75, 0)));
  EXPECT_TRUE(near_relative(r.corr[1], Vector3r(0, 0.75, 0)));
}

TEST(DistanceConstraint, SatisfiedConstraintGivesZeroCorrectionAndTrue) {
  const Points x = {Vector3r(1, 2, 3), Vector3r(1, 2, 5)};
  const Projection r = project(x, {1, 1}, 2, 1);
  EXPECT_TRUE(r.ok);
  EXPECT_LE(max_norm(r.corr), kRoundOff);
}

TEST(DistanceConstraint, InvariantsOnRandomInput) {
  Random random(101);
  for (int trial = 0; trial < 20; ++trial) {
    const Points x = {random.vector(), random.vector()};
    const Masses w = {random.inverse_mass(), random.inverse_mass()};
    const Real rest = random.uniform(Real(0.1), Real(2));
    const Real stiffness = random.uniform(Real(0.2), Real(1));
    const Projection r = project(x, w, rest, stiffness);
    ASSERT_TRUE(r.ok);
    ASSERT_TRUE(all_finite(r.corr));
    EXPECT_TRUE(conserves_linear_momentum(r.corr, w));
    EXPECT_TRUE(conserves_angular_momentum(x, r.corr, w));

    // Along -w∇C with the finite-difference gradient, scaled by k C / Σ w |∇C|².
    const auto constraint = [&](const Points& y) { return distance_constraint(y, rest); };
    const auto grad = numeric_gradient<2>(constraint, x);
    Real fitted = 0;
    EXPECT_TRUE(along_weighted_gradient(r.corr, w, grad, kFiniteDifferenceTolerance, &fitted));
    const Real C = distance_constraint(x, rest);
    EXPECT_NEAR(fitted, stiffness * C / (w[0] + w[1]),
                kFiniteDifferenceTolerance * std::abs(C / (w[0] + w[1])) + kRoundOff);

    // Rigid motion: the same C, corrections rotated.
    const Matrix3r R = random.rotation();
    const Vector3r t = random.vector(-5, 5);
    const Points y = transformed(x, R, t);
    EXPECT_NEAR(distance_constraint(y, rest), distance_constraint(x, rest), 10 * kRoundOff);
    const Projection moved = project(y, w, rest, stiffness);
    ASSERT_TRUE(moved.ok);
    for (int i = 0; i < 2; ++i)
      EXPECT_TRUE(near_relative(moved.corr[i], R * r.corr[i], 10 * kRoundOff));
  }
}

TEST(DistanceConstraint, StaticParticleIsNeverMoved) {
  Random random(102);
  for (int trial = 0; trial < 10; ++trial) {
    const Points x = {random.vector(), random.vector()};
    const Projection r = project(x, {0, random.inverse_mass()}, Real(0.3), 1);
    ASSERT_TRUE(r.ok);
    EXPECT_EQ(r.corr[0], Vector3r::Zero());
    // The movable particle alone satisfies the constraint in one step.
    EXPECT_NEAR(distance_constraint(applied(x, r.corr), Real(0.3)), 0, 10 * kRoundOff);
  }
}

TEST(DistanceConstraint, StiffnessOneSatisfiesTheConstraintInOneStep) {
  Random random(103);
  for (int trial = 0; trial < 20; ++trial) {
    const Points x = {random.vector(), random.vector()};
    const Masses w = {random.inverse_mass(), random.inverse_mass()};
    const Real rest = random.uniform(Real(0), Real(2));
    const Projection r = project(x, w, rest, 1);
    ASSERT_TRUE(r.ok);
    EXPECT_NEAR(distance_constraint(applied(x, r.corr), rest), 0, 10 * kRoundOff);
  }
}

TEST(DistanceConstraint, DegenerateInputGivesFalseAndZeroCorrection) {
  Points corr;
  const Vector3r p(0.3, -0.2, 0.7);
  // Coincident points (with and without a rest length).
  for (const Real rest : {Real(0), Real(1)}) {
    corr = {Vector3r::Constant(7), Vector3r::Constant(7)};
    EXPECT_FALSE(PositionBasedDynamics::solve_DistanceConstraint(p, 1, p, 1, rest, 1, corr[0],
                                                                 corr[1]));
    EXPECT_EQ(corr[0], Vector3r::Zero());
    EXPECT_EQ(corr[1], Vector3r::Zero());
  }
  // Every particle static.
  corr = {Vector3r::Constant(7), Vector3r::Constant(7)};
  EXPECT_FALSE(PositionBasedDynamics::solve_DistanceConstraint(p, 0, Vector3r(1, 2, 3), 0, 1, 1,
                                                               corr[0], corr[1]));
  EXPECT_EQ(corr[0], Vector3r::Zero());
  EXPECT_EQ(corr[1], Vector3r::Zero());
  // Zero rest length with distinct points is an ordinary constraint: it pulls them together.
  const Projection r = project({p, Vector3r(1, 1, 1)}, {1, 1}, 0, 1);
  ASSERT_TRUE(r.ok);
  EXPECT_TRUE(near_relative(p + r.corr[0], Vector3r(1, 1, 1) + r.corr[1]));
}

TEST(XPBDDistanceConstraint, ZeroComplianceEqualsPBDWithStiffnessOne) {
  Random random(104);
  for (int trial = 0; trial < 10; ++trial) {
    const Points x = {random.vector(), random.vector()};
    const Masses w = {random.inverse_mass(), random.inverse_mass()};
    const Real rest = random.uniform(Real(0.1), Real(2));
    Real lambda = 0;
    const Projection xpbd = project_xpbd(x, w, rest, 0, Real(0.01), lambda);
    const Projection pbd = project(x, w, rest, 1);
    ASSERT_TRUE(xpbd.ok);
    for (int i = 0; i < 2; ++i) EXPECT_TRUE(near_relative(xpbd.corr[i], pbd.corr[i]));
    // λ = -C / Σ w |∇C|².
    EXPECT_NEAR(lambda, -distance_constraint(x, rest) / (w[0] + w[1]), 10 * kRoundOff);
  }
}

TEST(XPBDDistanceConstraint, FirstIterationHandChecked) {
  // C = 2, w = (1, 1), α = 0.02, dt = 0.1: α̃ = 2, Δλ = -2 / (2 + 2) = -0.5,
  // Δp0 = -0.5 (1, 0, 0).
  const Points x = {Vector3r(3, 0, 0), Vector3r(0, 0, 0)};
  Real lambda = 0;
  const Projection r = project_xpbd(x, {1, 1}, 1, Real(0.02), Real(0.1), lambda);
  ASSERT_TRUE(r.ok);
  EXPECT_NEAR(lambda, -0.5, kRoundOff);
  EXPECT_TRUE(near_relative(r.corr[0], Vector3r(-0.5, 0, 0)));
  EXPECT_TRUE(near_relative(r.corr[1], Vector3r(0.5, 0, 0)));
}

TEST(XPBDDistanceConstraint, MultiplierConvergesToComplianceBalance) {
  Random random(105);
  for (int trial = 0; trial < 5; ++trial) {
    Points x = {random.vector(), random.vector()};
    const Masses w = {random.inverse_mass(), random.inverse_mass()};
    const Real rest = random.uniform(Real(0.1), Real(0.5));
    const Real compliance = random.uniform(Real(1e-4), Real(1e-2));
    const Real dt = Real(1) / 60;
    const Real alpha_tilde = compliance / (dt * dt);
    Real lambda = 0;
    for (int iteration = 0; iteration < 50; ++iteration) {
      const Projection r = project_xpbd(x, w, rest, compliance, dt, lambda);
      ASSERT_TRUE(r.ok);
      x = applied(x, r.corr);
    }
    const Real C = distance_constraint(x, rest);
    EXPECT_NEAR(C + alpha_tilde * lambda, 0, 10 * kRoundOff * (1 + alpha_tilde * std::abs(lambda)));
    // The soft constraint settles between the initial state and the rest length.
    EXPECT_GT(std::abs(lambda), 0);
  }
}

TEST(XPBDDistanceConstraint, InvalidTimeStepOrComplianceReturnsFalseAndKeepsLambda) {
  const Points x = {Vector3r(3, 0, 0), Vector3r(0, 0, 0)};
  for (const auto& [compliance, dt] : {std::pair<Real, Real>{Real(0.01), Real(0)},
                                       {Real(0.01), Real(-0.1)},
                                       {Real(-1e-3), Real(0.1)}}) {
    Real lambda = Real(0.25);
    const Projection r = project_xpbd(x, {1, 1}, 1, compliance, dt, lambda);
    EXPECT_FALSE(r.ok);
    EXPECT_EQ(lambda, Real(0.25));
    EXPECT_EQ(max_norm(r.corr), 0);
  }
  // Degenerate input too.
  Real lambda = Real(0.25);
  const Projection r = project_xpbd({x[0], x[0]}, {1, 1}, 1, Real(0.01), Real(0.1), lambda);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(lambda, Real(0.25));
  EXPECT_EQ(max_norm(r.corr), 0);
}

TEST(XPBDDistanceConstraint, StaticParticleIsNeverMoved) {
  const Points x = {Vector3r(0, 0, 0), Vector3r(0, 2, 0)};
  Real lambda = 0;
  const Projection r = project_xpbd(x, {2, 0}, 1, Real(1e-3), Real(0.01), lambda);
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.corr[1], Vector3r::Zero());
  EXPECT_GT(r.corr[0].y(), 0);
}

TEST(DistanceConstraint, NearDegenerateInputStaysFinite) {
  expect_near_degenerate_input_stays_finite<2>(
      106, 1, [](Random& random) { return random.uniform(0, 1); }, project, project_xpbd);
}

namespace lanes = HWY_NAMESPACE;

/// The general rule's value of the same constraint: gradients n = d/|d| and −n.
lanes::ConstraintValue<Real, 2> general_value(const lanes::DirectionValue<Real>& value) {
  lanes::ConstraintValue<Real, 2> general;
  general.C = value.C;
  general.valid = value.valid;
  const lanes::Vec3<Real> n =
      value.difference * (value.valid ? Real(1) / value.length : Real(0));
  general.gradient[0] = n;
  general.gradient[1] = -n;
  return general;
}

Vector3r correction(const lanes::Vec3<Real>& corr) { return lanes::to_eigen(corr); }

TEST(DistanceConstraint, OneDivisionRuleMatchesTheGeneralRule) {
  // Both semantics over random pairs, masses (one static at times), compliances and
  // multipliers: the same corrections and λ as the general rule up to rounding, and exactly
  // zero for a static particle.
  Random random(17);
  for (int trial = 0; trial < 500; ++trial) {
    const Points x = {random.vector(), random.vector()};
    const Real w[2] = {trial % 5 == 0 ? Real(0) : random.inverse_mass(), random.inverse_mass()};
    const Real rest = random.uniform(Real(0.1), Real(2));
    const auto value = lanes::distance_constraint<Real>(lanes::from_eigen(x[0]),
                                                        lanes::from_eigen(x[1]), rest);
    ASSERT_TRUE(value.valid);
    const auto general = general_value(value);
    const auto static_is_still = [&](const lanes::Vec3<Real> (&corr)[2]) {
      for (int i = 0; i < 2; ++i)
        if (w[i] == 0) EXPECT_EQ(correction(corr[i]), Vector3r::Zero()) << "static particle";
    };

    const Real stiffness = random.uniform(Real(0.1), Real(1));
    lanes::Vec3<Real> by_direction[2], by_general[2];
    EXPECT_TRUE(lanes::project_pbd(value, w, stiffness, by_direction));
    EXPECT_TRUE(lanes::project_pbd(general, w, stiffness, by_general));
    for (int i = 0; i < 2; ++i)
      EXPECT_TRUE(near_relative(correction(by_direction[i]), correction(by_general[i])))
          << "PBD, particle " << i << ", trial " << trial;
    static_is_still(by_direction);

    const Real compliance = trial % 3 == 0 ? Real(0) : random.uniform(Real(1e-6), Real(1e-2));
    const auto step = lanes::TimeStep<Real>::of(random.uniform(Real(1e-3), Real(1e-1)));
    Real lambda_direction = random.uniform(Real(-1), Real(1)), lambda_general = lambda_direction;
    EXPECT_TRUE(lanes::project_xpbd(value, w, compliance, step, lambda_direction, by_direction));
    EXPECT_TRUE(lanes::project_xpbd(general, w, compliance, step, lambda_general, by_general));
    EXPECT_NEAR(lambda_direction, lambda_general, kRoundOff * (1 + std::abs(lambda_general)))
        << "trial " << trial;
    for (int i = 0; i < 2; ++i)
      EXPECT_TRUE(near_relative(correction(by_direction[i]), correction(by_general[i])))
          << "XPBD, particle " << i << ", trial " << trial;
    static_is_still(by_direction);
  }
}

TEST(DistanceConstraint, OneDivisionRuleLeavesInvalidLanesAlone) {
  // Coincident points, two static particles, a NaN or infinite position, a time step that is
  // zero, negative or NaN, a negative compliance, or a compliance made infinite by a time
  // step whose square is subnormal or rounds to 0: no correction, and λ keeps its value (a
  // NaN |d| must not reach it). PBD and XPBD on the DirectionValue, on a sentinel-filled
  // output.
  const Real nan = std::numeric_limits<Real>::quiet_NaN();
  const Real inf = std::numeric_limits<Real>::infinity();
  const Real subnormal_square = std::sqrt(std::numeric_limits<Real>::min()) / 4;
  const Real zero_square = std::sqrt(std::numeric_limits<Real>::denorm_min()) / 4;
  struct Case {
    const char* what;
    Points x;
    Real w0, w1, compliance, dt;
    bool pbd_invalid;  // whether the stiffness rule (no dt, no α) must refuse it too
  };
  const Points apart = {Vector3r(0, 0, 0), Vector3r(2, 0, 0)};
  const Case cases[] = {
      {"coincident", {Vector3r(1, 2, 3), Vector3r(1, 2, 3)}, 1, 1, 0, Real(0.01), true},
      {"both static", apart, 0, 0, 0, Real(0.01), true},
      {"NaN position", {Vector3r(nan, 0, 0), Vector3r(2, 0, 0)}, 1, 1, 0, Real(0.01), true},
      {"infinite position", {Vector3r(inf, 0, 0), Vector3r(2, 0, 0)}, 1, 1, 0, Real(0.01), true},
      {"zero time step", apart, 1, 1, Real(1e-3), 0, false},
      {"negative time step", apart, 1, 1, Real(1e-3), Real(-0.1), false},
      {"NaN time step", apart, 1, 1, Real(1e-3), nan, false},
      {"negative compliance", apart, 1, 1, -1, Real(0.01), false},
      {"subnormal dt²", apart, 1, 1, Real(1e-3), subnormal_square, false},
      {"dt² rounds to 0", apart, 1, 1, Real(1e-3), zero_square, false},
  };
  const lanes::Vec3<Real> sentinel{Real(7), Real(7), Real(7)};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    const auto value = lanes::distance_constraint<Real>(lanes::from_eigen(c.x[0]),
                                                        lanes::from_eigen(c.x[1]), Real(1));
    const Real w[2] = {c.w0, c.w1};
    lanes::Vec3<Real> corr[2] = {sentinel, sentinel};
    Real lambda = Real(0.25);
    const auto step = lanes::TimeStep<Real>::of(c.dt);
    EXPECT_FALSE(lanes::project_xpbd(value, w, c.compliance, step, lambda, corr));
    EXPECT_EQ(lambda, Real(0.25));
    for (const auto& v : corr) EXPECT_EQ(correction(v), Vector3r::Zero());
    if (c.pbd_invalid) {
      corr[0] = corr[1] = sentinel;
      EXPECT_FALSE(lanes::project_pbd(value, w, Real(1), corr));
      for (const auto& v : corr) EXPECT_EQ(correction(v), Vector3r::Zero());
    }
  }
}

TEST(XPBDDistanceConstraint, ZeroComplianceProjectsWhateverThePositiveTimeStep) {
  // A hard constraint needs no 1/dt²: with a time step whose square is subnormal, rounds to
  // 0 or is infinite, zero compliance still projects as PBD with stiffness 1 does
  // (λ = −C/(w0 + w1)); the hand-checked pair of HandCheckedStretchedPair.
  const Points x = {Vector3r(3, 0, 0), Vector3r(0, 0, 0)};
  const Real dts[] = {std::sqrt(std::numeric_limits<Real>::min()) / 4,
                      std::sqrt(std::numeric_limits<Real>::denorm_min()) / 4,
                      std::numeric_limits<Real>::infinity()};
  for (const Real dt : dts) {
    SCOPED_TRACE(dt);
    Real lambda = 0;
    const Projection r = project_xpbd(x, {1, 3}, 1, 0, dt, lambda);
    ASSERT_TRUE(r.ok);
    EXPECT_TRUE(near_relative(r.corr[0], Vector3r(-0.5, 0, 0)));
    EXPECT_TRUE(near_relative(r.corr[1], Vector3r(1.5, 0, 0)));
    EXPECT_NEAR(lambda, Real(-0.5), kRoundOff);
  }
}

}  // namespace distance_tests
}  // namespace tessera::test
