// Tests of the dihedral bending constraint, PBD and XPBD forms: the angle convention (flat is
// 0), a hand-checked correction, momentum, static particles, rigid-motion invariance, the
// direction of the correction against a finite-difference gradient of acos(n̂1 · n̂2),
// convergence, the flat and fully folded stencils (no NaN), degenerate input and the XPBD
// multiplier.
#include <numbers>

#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "test_support.hpp"

namespace tessera::test {
namespace dihedral_tests {

using Points = std::array<Vector3r, 4>;
using Masses = std::array<Real, 4>;
constexpr Real kPi = std::numbers::pi_v<Real>;

using Projection = ScalarProjection<4>;

Projection project(const Points& x, const Masses& w, Real rest_angle, Real stiffness) {
  Projection r;
  r.ok = PositionBasedDynamics::solve_DihedralConstraint(
      x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3], rest_angle, stiffness, r.corr[0],
      r.corr[1], r.corr[2], r.corr[3]);
  return r;
}

Projection project_xpbd(const Points& x, const Masses& w, Real rest_angle, Real compliance,
                        Real dt, Real& lambda) {
  Projection r;
  r.ok = XPBD::solve_DihedralConstraint(x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3],
                                        rest_angle, compliance, dt, lambda, r.corr[0],
                                        r.corr[1], r.corr[2], r.corr[3]);
  return r;
}

/// The documented angle, evaluated directly: acos of the dot product of the unit normals of
/// (p0, p2, p3) and (p1, p3, p2).
Real dihedral_angle(const Points& x) {
  const Vector3r n1 = (x[2] - x[0]).cross(x[3] - x[0]).normalized();
  const Vector3r n2 = (x[3] - x[1]).cross(x[2] - x[1]).normalized();
  return std::acos(std::clamp(n1.dot(n2), Real(-1), Real(1)));
}

/// Shared edge p2 = 0, p3 = e_x; wing p0 = (0.5, 1, 0); wing p1 rotated about the edge so the
/// angle between the normals is `angle`.
Points hinge(Real angle) {
  return {Vector3r(0.5, 1, 0), Vector3r(0.5, -std::cos(angle), std::sin(angle)),
          Vector3r(0, 0, 0), Vector3r(1, 0, 0)};
}

/// A random stencil with triangles of area above 0.1 and an angle in (0.3, π - 0.3).
Points random_stencil(Random& random) {
  for (;;) {
    const Points x = {random.vector(), random.vector(), random.vector(), random.vector()};
    const Real area0 = (x[2] - x[0]).cross(x[3] - x[0]).norm() / 2;
    const Real area1 = (x[3] - x[1]).cross(x[2] - x[1]).norm() / 2;
    const Real angle = dihedral_angle(x);
    if (area0 > Real(0.1) && area1 > Real(0.1) && angle > Real(0.3) && angle < kPi - Real(0.3))
      return x;
  }
}

Masses random_masses(Random& random) {
  return {random.inverse_mass(), random.inverse_mass(), random.inverse_mass(),
          random.inverse_mass()};
}

TEST(DihedralConstraint, AngleConventionFlatIsZero) {
  for (const Real angle : {Real(0), Real(0.4), kPi / 2, Real(2.5)}) {
    EXPECT_NEAR(dihedral_angle(hinge(angle)), angle, 10 * kRoundOff);
    // At the rest angle of its own shape the constraint is satisfied.
    const Projection r = project(hinge(angle), {1, 1, 1, 1}, angle, 1);
    EXPECT_TRUE(r.ok);
    EXPECT_LE(max_norm(r.corr), 10 * kRoundOff);
  }
}

TEST(DihedralConstraint, HandCheckedRightAngleHinge) {
  // φ = π/2, only p0 movable: |e| = 1, N1 = (0, 0, 1), so ∇_{p0} φ = (0, 0, 1) (lifting p0
  // folds the wings together). Rest 0: C = π/2, s = C / 1, Δp0 = -(π/2) (0, 0, 1).
  const Projection r = project(hinge(kPi / 2), {1, 0, 0, 0}, 0, 1);
  ASSERT_TRUE(r.ok);
  EXPECT_TRUE(near_relative(r.corr[0], Vector3r(0, 0, -kPi / 2)));
  for (int i = 1; i < 4; ++i) EXPECT_EQ(r.corr[i], Vector3r::Zero());
}

TEST(DihedralConstraint, InvariantsOnRandomInput) {
  expect_pbd_invariants_on_random_input<4>(
      301, 20, random_stencil, random_masses,
      [](Random& random) { return random.uniform(0, kPi); }, dihedral_angle, project,
      100 * kRoundOff);
}

TEST(DihedralConstraint, StaticParticleIsNeverMoved) {
  expect_static_particle_never_moved<4>(302, 8, random_stencil, random_masses, Real(1), project);
}

TEST(DihedralConstraint, RepeatedProjectionConvergesMonotonically) {
  Random random(303);
  for (int trial = 0; trial < 6; ++trial) {
    Points x = random_stencil(random);
    const Masses w = random_masses(random);
    const Real rest = std::clamp(dihedral_angle(x) + random.uniform(-1, 1), Real(0.1), Real(3));
    Real previous = std::abs(dihedral_angle(x) - rest);
    for (int iteration = 0; iteration < 40; ++iteration) {
      const Projection r = project(x, w, rest, Real(0.5));
      ASSERT_TRUE(r.ok);
      x = applied(x, r.corr);
      const Real violation = std::abs(dihedral_angle(x) - rest);
      EXPECT_LE(violation, previous + 10 * kRoundOff);
      previous = violation;
    }
    EXPECT_LE(previous, 100 * kRoundOff);
  }
}

TEST(DihedralConstraint, FlatAndFoldedStencilsStayFinite) {
  // Flat, rest 0: satisfied. Flat with a rest angle: buckles (finite, towards the rest angle).
  {
    const Projection r = project(hinge(0), {1, 1, 1, 1}, 0, 1);
    EXPECT_TRUE(r.ok);
    EXPECT_LE(max_norm(r.corr), kRoundOff);
    Points x = hinge(0);
    for (int iteration = 0; iteration < 30; ++iteration) {
      const Projection step = project(x, {1, 1, 1, 1}, Real(0.7), 1);
      ASSERT_TRUE(step.ok);
      ASSERT_TRUE(all_finite(step.corr));
      x = applied(x, step.corr);
    }
    EXPECT_NEAR(dihedral_angle(x), Real(0.7), 100 * kRoundOff);
  }
  // Fully folded (φ = π) and nearly so, and nearly flat: finite corrections towards the rest.
  for (const Real angle : {kPi, kPi - Real(1e-4), Real(1e-4), Real(1e-7)}) {
    Points x = hinge(angle);
    const Real rest = kPi / 2;
    for (int iteration = 0; iteration < 30; ++iteration) {
      const Projection step = project(x, {1, 1, 1, 1}, rest, 1);
      ASSERT_TRUE(step.ok) << angle;
      ASSERT_TRUE(all_finite(step.corr)) << angle;
      x = applied(x, step.corr);
    }
    EXPECT_NEAR(dihedral_angle(x), rest, 100 * kRoundOff) << angle;
  }
}

TEST(DihedralConstraint, DegenerateInputGivesFalseAndZeroCorrection) {
  const auto expect_degenerate = [](const Points& x, const Masses& w) {
    Points corr;
    corr.fill(Vector3r::Constant(7));
    EXPECT_FALSE(PositionBasedDynamics::solve_DihedralConstraint(
        x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3], Real(1), 1, corr[0], corr[1], corr[2],
        corr[3]));
    for (const Vector3r& c : corr) EXPECT_EQ(c, Vector3r::Zero());
  };
  Points x = hinge(1);
  x[3] = x[2];
  expect_degenerate(x, {1, 1, 1, 1});  // zero-length shared edge
  x = hinge(1);
  x[0] = Vector3r(3, 0, 0);
  expect_degenerate(x, {1, 1, 1, 1});  // wing on the edge line: zero-area triangle
  x = hinge(1);
  x[1] = x[2];
  expect_degenerate(x, {1, 1, 1, 1});  // coincident points
  expect_degenerate(hinge(1), {0, 0, 0, 0});  // every particle static
}

TEST(XPBDDihedralConstraint, ZeroComplianceEqualsPBDWithStiffnessOne) {
  expect_zero_compliance_equals_pbd<4>(304, 10, random_stencil, random_masses, Real(1), project,
                                       project_xpbd);
}

TEST(XPBDDihedralConstraint, MultiplierConvergesToComplianceBalance) {
  Random random(305);
  for (int trial = 0; trial < 5; ++trial) {
    Points x = random_stencil(random);
    const Masses w = random_masses(random);
    const Real rest = std::clamp(dihedral_angle(x) + random.uniform(-1, 1), Real(0.1), Real(3));
    const Real compliance = Real(1e-4);
    const Real dt = Real(1) / 60;
    const Real alpha_tilde = compliance / (dt * dt);
    Real lambda = 0;
    for (int iteration = 0; iteration < 60; ++iteration) {
      const Projection r = project_xpbd(x, w, rest, compliance, dt, lambda);
      ASSERT_TRUE(r.ok);
      x = applied(x, r.corr);
    }
    const Real C = dihedral_angle(x) - rest;
    EXPECT_NEAR(C + alpha_tilde * lambda, 0, 100 * kRoundOff);
    EXPECT_NE(lambda, 0);
  }
}

TEST(XPBDDihedralConstraint, InvalidTimeStepOrComplianceReturnsFalseAndKeepsLambda) {
  for (const auto& [compliance, dt] :
       {std::pair<Real, Real>{Real(0.01), Real(0)}, {Real(-1), Real(0.01)}}) {
    Real lambda = Real(0.125);
    const Projection r = project_xpbd(hinge(1), {1, 1, 1, 1}, 0, compliance, dt, lambda);
    EXPECT_FALSE(r.ok);
    EXPECT_EQ(lambda, Real(0.125));
    EXPECT_EQ(max_norm(r.corr), 0);
  }
  Points x = hinge(1);
  x[3] = x[2];
  Real lambda = Real(0.125);
  const Projection r = project_xpbd(x, {1, 1, 1, 1}, 0, 0, Real(0.01), lambda);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(lambda, Real(0.125));
}

TEST(DihedralConstraint, NearDegenerateInputStaysFinite) {
  expect_near_degenerate_input_stays_finite<4>(
      306, 3, [](Random& random) { return random.uniform(0, kPi); }, project, project_xpbd);
}

}  // namespace dihedral_tests
}  // namespace tessera::test
