// Tests of the tetrahedron volume constraint, PBD and XPBD forms: known answers, momentum,
// static particles, rigid-motion invariance, the direction of the correction against a
// finite-difference gradient, convergence (also of an inverted tetrahedron), degenerate input
// and the XPBD multiplier.
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "test_support.hpp"

namespace tessera::test {
namespace volume_tests {

using Points = std::array<Vector3r, 4>;
using Masses = std::array<Real, 4>;

using Projection = ScalarProjection<4>;

Projection project(const Points& x, const Masses& w, Real rest_volume, Real stiffness) {
  Projection r;
  r.ok = PositionBasedDynamics::solve_VolumeConstraint(x[0], w[0], x[1], w[1], x[2], w[2], x[3],
                                                       w[3], rest_volume, stiffness, r.corr[0],
                                                       r.corr[1], r.corr[2], r.corr[3]);
  return r;
}

Projection project_xpbd(const Points& x, const Masses& w, Real rest_volume, Real compliance,
                        Real dt, Real& lambda) {
  Projection r;
  r.ok = XPBD::solve_VolumeConstraint(x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3],
                                      rest_volume, compliance, dt, lambda, r.corr[0], r.corr[1],
                                      r.corr[2], r.corr[3]);
  return r;
}

/// Signed volume from the determinant of the edge matrix (independent of the kernel's form).
Real signed_volume(const Points& x) {
  Matrix3r edges;
  edges << x[1] - x[0], x[2] - x[0], x[3] - x[0];
  return edges.determinant() / 6;
}

/// A random tetrahedron of reasonable shape (volume magnitude above 0.02).
Points random_tetrahedron(Random& random) {
  for (;;) {
    const Points x = {random.vector(), random.vector(), random.vector(), random.vector()};
    if (std::abs(signed_volume(x)) > Real(0.02)) return x;
  }
}

Masses random_masses(Random& random) {
  return {random.inverse_mass(), random.inverse_mass(), random.inverse_mass(),
          random.inverse_mass()};
}

const Points kUnitTetrahedron = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0),
                                 Vector3r(0, 0, 1)};

TEST(VolumeConstraint, HandCheckedUnitTetrahedron) {
  // V = 1/6, V0 = 1/3: C = -1/6; ∇p1 = e_x/6, ∇p2 = e_y/6, ∇p3 = e_z/6, ∇p0 = -(1,1,1)/6;
  // Σ |∇|² = 1/6, so s = -1 and Δp_i = ∇_i C.
  const Projection r = project(kUnitTetrahedron, {1, 1, 1, 1}, Real(1) / 3, 1);
  ASSERT_TRUE(r.ok);
  const Real sixth = Real(1) / 6;
  EXPECT_TRUE(near_relative(r.corr[0], Vector3r(-sixth, -sixth, -sixth)));
  EXPECT_TRUE(near_relative(r.corr[1], Vector3r(sixth, 0, 0)));
  EXPECT_TRUE(near_relative(r.corr[2], Vector3r(0, sixth, 0)));
  EXPECT_TRUE(near_relative(r.corr[3], Vector3r(0, 0, sixth)));
}

TEST(VolumeConstraint, SignFollowsOrientation) {
  // Swapping p1 and p2 inverts the tetrahedron: V = -1/6.
  const Points inverted = {kUnitTetrahedron[0], kUnitTetrahedron[2], kUnitTetrahedron[1],
                           kUnitTetrahedron[3]};
  const Projection r = project(inverted, {1, 1, 1, 1}, -Real(1) / 6, 1);
  ASSERT_TRUE(r.ok);
  EXPECT_LE(max_norm(r.corr), kRoundOff);  // satisfied at its signed rest volume
  const Projection pushed = project(inverted, {1, 1, 1, 1}, Real(1) / 6, 1);
  ASSERT_TRUE(pushed.ok);
  EXPECT_GT(signed_volume(applied(inverted, pushed.corr)), signed_volume(inverted));
}

TEST(VolumeConstraint, InvariantsOnRandomInput) {
  expect_pbd_invariants_on_random_input<4>(
      201, 20, random_tetrahedron, random_masses,
      [](Random& random) { return random.uniform(Real(-0.2), Real(0.2)); }, signed_volume,
      project, 50 * kRoundOff);
}

TEST(VolumeConstraint, StaticParticleIsNeverMoved) {
  expect_static_particle_never_moved<4>(202, 10, random_tetrahedron, random_masses, Real(0.3),
                                        project);
}

TEST(VolumeConstraint, RepeatedProjectionConvergesMonotonically) {
  Random random(203);
  for (int trial = 0; trial < 5; ++trial) {
    Points x = random_tetrahedron(random);
    const Masses w = random_masses(random);
    // Trial 0 starts inverted with respect to the rest volume.
    const Real rest = trial == 0 ? -signed_volume(x) : signed_volume(x) * random.uniform(0.5, 1.5);
    Real previous = std::abs(signed_volume(x) - rest);
    for (int iteration = 0; iteration < 30; ++iteration) {
      const Projection r = project(x, w, rest, 1);
      if (!r.ok) break;
      x = applied(x, r.corr);
      const Real violation = std::abs(signed_volume(x) - rest);
      EXPECT_LE(violation, previous + 10 * kRoundOff * std::abs(rest));
      previous = violation;
    }
    EXPECT_LE(previous, 10 * kRoundOff * std::abs(rest));
  }
}

TEST(VolumeConstraint, FlatTetrahedronIsInflated) {
  // p3 in the plane of the base: V = 0, but the gradient is not degenerate.
  Points x = kUnitTetrahedron;
  x[3] = Vector3r(Real(0.3), Real(0.3), 0);
  const Projection r = project(x, {1, 1, 1, 1}, Real(0.1), 1);
  ASSERT_TRUE(r.ok);
  EXPECT_GT(signed_volume(applied(x, r.corr)), 0);
}

TEST(VolumeConstraint, DegenerateInputGivesFalseAndZeroCorrection) {
  const auto expect_degenerate = [](const Points& x, const Masses& w, Real rest) {
    Points corr;
    corr.fill(Vector3r::Constant(7));
    EXPECT_FALSE(PositionBasedDynamics::solve_VolumeConstraint(
        x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3], rest, 1, corr[0], corr[1], corr[2],
        corr[3]));
    for (const Vector3r& c : corr) EXPECT_EQ(c, Vector3r::Zero());
  };
  const Vector3r p(0.1, 0.2, 0.3);
  expect_degenerate({p, p, p, p}, {1, 1, 1, 1}, Real(0.1));                // coincident
  expect_degenerate({p, 2 * p, 3 * p, -p}, {1, 1, 1, 1}, Real(0.1));       // collinear
  expect_degenerate(kUnitTetrahedron, {0, 0, 0, 0}, Real(0.5));             // all static
}

TEST(XPBDVolumeConstraint, ZeroComplianceEqualsPBDWithStiffnessOne) {
  expect_zero_compliance_equals_pbd<4>(204, 10, random_tetrahedron, random_masses, Real(0.1),
                                       project, project_xpbd);
}

TEST(XPBDVolumeConstraint, MultiplierConvergesToComplianceBalance) {
  Random random(205);
  for (int trial = 0; trial < 5; ++trial) {
    Points x = random_tetrahedron(random);
    const Masses w = random_masses(random);
    const Real rest = 2 * signed_volume(x);
    const Real compliance = Real(1e-5);
    const Real dt = Real(1) / 60;
    const Real alpha_tilde = compliance / (dt * dt);
    Real lambda = 0;
    for (int iteration = 0; iteration < 60; ++iteration) {
      const Projection r = project_xpbd(x, w, rest, compliance, dt, lambda);
      ASSERT_TRUE(r.ok);
      x = applied(x, r.corr);
    }
    const Real C = signed_volume(x) - rest;
    EXPECT_NEAR(C + alpha_tilde * lambda, 0, 50 * kRoundOff * std::abs(rest));
    EXPECT_NE(lambda, 0);
  }
}

TEST(XPBDVolumeConstraint, InvalidTimeStepOrComplianceReturnsFalseAndKeepsLambda) {
  for (const auto& [compliance, dt] :
       {std::pair<Real, Real>{Real(0.01), Real(0)}, {Real(-1), Real(0.01)}}) {
    Real lambda = Real(-0.5);
    const Projection r = project_xpbd(kUnitTetrahedron, {1, 1, 1, 1}, 1, compliance, dt, lambda);
    EXPECT_FALSE(r.ok);
    EXPECT_EQ(lambda, Real(-0.5));
    EXPECT_EQ(max_norm(r.corr), 0);
  }
}

TEST(VolumeConstraint, NearDegenerateInputStaysFinite) {
  expect_near_degenerate_input_stays_finite<4>(
      206, 3, [](Random& random) { return random.uniform(-0.2, 0.2); }, project, project_xpbd);
}

}  // namespace volume_tests
}  // namespace tessera::test
