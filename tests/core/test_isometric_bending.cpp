// Tests of isometric bending, PBD and XPBD forms: Q for hand-computed stencils, its structure
// (symmetric, positive semi-definite, rows summing to zero, vanishing on planar stencils,
// invariant under rigid motion of the rest shape), hand-checked corrections, momentum, static
// particles, the gradient against finite differences of C, convergence, degenerate input and
// the XPBD multiplier.
#include <Eigen/Eigenvalues>

#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "test_support.hpp"

namespace tessera::test {
namespace isometric_bending_tests {

using Points = std::array<Vector3r, 4>;
using Masses = std::array<Real, 4>;

using Projection = ScalarProjection<4>;

Matrix4r bending_matrix(const Points& rest) {
  Matrix4r Q;
  EXPECT_TRUE(PositionBasedDynamics::init_IsometricBendingConstraint(rest[0], rest[1], rest[2],
                                                                     rest[3], Q));
  return Q;
}

Projection project(const Points& x, const Masses& w, const Matrix4r& Q, Real stiffness) {
  Projection r;
  r.ok = PositionBasedDynamics::solve_IsometricBendingConstraint(
      x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3], Q, stiffness, r.corr[0], r.corr[1],
      r.corr[2], r.corr[3]);
  return r;
}

Projection project_xpbd(const Points& x, const Masses& w, const Matrix4r& Q, Real compliance,
                        Real dt, Real& lambda) {
  Projection r;
  r.ok = XPBD::solve_IsometricBendingConstraint(x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3],
                                                Q, compliance, dt, lambda, r.corr[0], r.corr[1],
                                                r.corr[2], r.corr[3]);
  return r;
}

/// C = ½ Σ_ij Q_ij p_i · p_j, as documented, with the points taken relative to p2 (the rows
/// of Q sum to zero, so this changes nothing but the round-off of far-off coordinates).
Real bending_energy(const Matrix4r& Q, const Points& x) {
  Real C = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) C += Q(i, j) * (x[i] - x[2]).dot(x[j] - x[2]);
  return C / 2;
}

/// Shared edge p2 = 0, p3 = e_x, wings at height ±1 above the middle of the edge.
const Points kSymmetricStencil = {Vector3r(0.5, 1, 0), Vector3r(0.5, -1, 0), Vector3r(0, 0, 0),
                                  Vector3r(1, 0, 0)};

/// A random stencil with triangle areas above 0.15 (bent, in general).
Points random_stencil(Random& random) {
  for (;;) {
    const Points x = {random.vector(), random.vector(), random.vector(), random.vector()};
    const Real area0 = (x[2] - x[0]).cross(x[3] - x[0]).norm() / 2;
    const Real area1 = (x[3] - x[1]).cross(x[2] - x[1]).norm() / 2;
    if (area0 > Real(0.15) && area1 > Real(0.15)) return x;
  }
}

/// A random planar stencil (wings on opposite sides of the edge), then rigidly moved.
Points random_planar_stencil(Random& random) {
  const Points flat = {Vector3r(random.uniform(-0.5, 1.5), random.uniform(0.3, 1.5), 0),
                       Vector3r(random.uniform(-0.5, 1.5), -random.uniform(0.3, 1.5), 0),
                       Vector3r(0, 0, 0), Vector3r(random.uniform(0.5, 1.5), 0, 0)};
  return transformed(flat, random.rotation(), random.vector(-3, 3));
}

Masses random_masses(Random& random) {
  return {random.inverse_mass(), random.inverse_mass(), random.inverse_mass(),
          random.inverse_mass()};
}

TEST(IsometricBending, HandCheckedMatrices) {
  // Symmetric stencil: every cotangent at the edge is 0.5, K = (-1, -1, 1, 1), A0 = A1 = ½,
  // Q = 3 K Kᵀ.
  Vector4r K(-1, -1, 1, 1);
  EXPECT_TRUE(bending_matrix(kSymmetricStencil).isApprox(Matrix4r(3 * K * K.transpose()),
                                                         kRoundOff));
  // Right angle at p2 in the first triangle: cot = 0 at p2 and 1 at p3 for wing p0;
  // wing p1 = (0.5, -1, 0) has cot ½ at both. K = (-1, -1, 1.5, 0.5), A0 = A1 = ½.
  const Points right = {Vector3r(0, 1, 0), Vector3r(0.5, -1, 0), Vector3r(0, 0, 0),
                        Vector3r(1, 0, 0)};
  K = Vector4r(-1, -1, 1.5, 0.5);
  EXPECT_TRUE(bending_matrix(right).isApprox(Matrix4r(3 * K * K.transpose()), kRoundOff));
}

TEST(IsometricBending, MatrixStructure) {
  Random random(501);
  for (int trial = 0; trial < 20; ++trial) {
    const Points rest = trial % 2 ? random_stencil(random) : random_planar_stencil(random);
    const Matrix4r Q = bending_matrix(rest);
    ASSERT_TRUE(Q.allFinite());
    const Real scale = Q.cwiseAbs().maxCoeff();
    EXPECT_LE((Q - Q.transpose()).cwiseAbs().maxCoeff(), kRoundOff * scale);
    EXPECT_LE(Q.rowwise().sum().cwiseAbs().maxCoeff(), 10 * kRoundOff * scale);
    using AlignedMatrix4 = Eigen::Matrix<Real, 4, 4>;
    const Eigen::SelfAdjointEigenSolver<AlignedMatrix4> eigen{AlignedMatrix4(Q)};
    EXPECT_GE(eigen.eigenvalues().minCoeff(), -10 * kRoundOff * scale);
    // Rank one: only one non-zero eigenvalue.
    EXPECT_LE(std::abs(eigen.eigenvalues()[2]), 10 * kRoundOff * scale);
    // The rest shape's rigid motion leaves Q unchanged.
    const Matrix4r moved =
        bending_matrix(transformed(rest, random.rotation(), random.vector(-3, 3)));
    EXPECT_LE((moved - Q).cwiseAbs().maxCoeff(), 50 * kRoundOff * scale);
    // Q x = 0 for every coordinate of a planar stencil, so C = 0 and no correction.
    if (trial % 2 == 0) {
      Eigen::Matrix<Real, 4, 3> X;
      for (int i = 0; i < 4; ++i) X.row(i) = rest[i].transpose();
      EXPECT_LE((Q * X).cwiseAbs().maxCoeff(), 50 * kRoundOff * scale);
    }
  }
}

TEST(IsometricBending, HandCheckedCorrection) {
  // Symmetric stencil with p0 lifted to z = 1: Kᵀz = -1, C = ½ · 3 · 1 = 1.5,
  // ∇ = 3 K (0, 0, -1) = (0,0,3), (0,0,3), (0,0,-3), (0,0,-3); Σ|∇|² = 36, s = 1/24,
  // Δp = ∓(0, 0, 1/8).
  const Matrix4r Q = bending_matrix(kSymmetricStencil);
  Points x = kSymmetricStencil;
  x[0].z() = 1;
  EXPECT_NEAR(bending_energy(Q, x), 1.5, kRoundOff);
  const Projection r = project(x, {1, 1, 1, 1}, Q, 1);
  ASSERT_TRUE(r.ok);
  const Real eighth = Real(0.125);
  EXPECT_TRUE(near_relative(r.corr[0], Vector3r(0, 0, -eighth)));
  EXPECT_TRUE(near_relative(r.corr[1], Vector3r(0, 0, -eighth)));
  EXPECT_TRUE(near_relative(r.corr[2], Vector3r(0, 0, eighth)));
  EXPECT_TRUE(near_relative(r.corr[3], Vector3r(0, 0, eighth)));
  // The quadratic C falls to a quarter: the curvature Kᵀz halves.
  EXPECT_NEAR(bending_energy(Q, applied(x, r.corr)), 1.5 / 4, kRoundOff);
}

TEST(IsometricBending, InvariantsOnRandomInput) {
  Random random(502);
  for (int trial = 0; trial < 20; ++trial) {
    const Points rest = random_planar_stencil(random);
    const Matrix4r Q = bending_matrix(rest);
    Points x = rest;
    for (Vector3r& p : x) p += random.vector(Real(-0.3), Real(0.3));
    const Masses w = random_masses(random);
    const Real stiffness = random.uniform(Real(0.2), Real(1));
    const Projection r = project(x, w, Q, stiffness);
    ASSERT_TRUE(r.ok);
    ASSERT_TRUE(all_finite(r.corr));
    EXPECT_TRUE(conserves_linear_momentum(r.corr, w));
    EXPECT_TRUE(conserves_angular_momentum(x, r.corr, w));

    const auto energy = [&](const Points& y) { return bending_energy(Q, y); };
    expect_pbd_step(energy, x, w, r.corr, energy(x), stiffness);

    const Matrix3r R = random.rotation();
    const Vector3r t = random.vector(-5, 5);
    const Points y = transformed(x, R, t);
    EXPECT_NEAR(energy(y), energy(x), 100 * kRoundOff * (1 + energy(x)));
    const Projection moved = project(y, w, Q, stiffness);
    ASSERT_TRUE(moved.ok);
    for (int i = 0; i < 4; ++i)
      EXPECT_TRUE(near_relative(moved.corr[i], R * r.corr[i], 200 * kRoundOff));
  }
}

TEST(IsometricBending, StaticParticleIsNeverMoved) {
  Random random(503);
  for (int trial = 0; trial < 8; ++trial) {
    const Matrix4r Q = bending_matrix(random_planar_stencil(random));
    const Points x = random_stencil(random);
    Masses w = random_masses(random);
    w[trial % 4] = 0;
    const Projection r = project(x, w, Q, 1);
    ASSERT_TRUE(r.ok);
    EXPECT_EQ(r.corr[trial % 4], Vector3r::Zero());
  }
}

TEST(IsometricBending, RepeatedProjectionConvergesMonotonically) {
  Random random(504);
  for (int trial = 0; trial < 6; ++trial) {
    const Points rest = random_planar_stencil(random);
    const Matrix4r Q = bending_matrix(rest);
    Points x = rest;
    for (Vector3r& p : x) p += random.vector(Real(-0.5), Real(0.5));
    const Masses w = random_masses(random);
    const Real initial = bending_energy(Q, x);
    Real previous = initial;
    for (int iteration = 0; iteration < 30; ++iteration) {
      const Projection r = project(x, w, Q, 1);
      ASSERT_TRUE(r.ok);
      ASSERT_TRUE(all_finite(r.corr));
      x = applied(x, r.corr);
      const Real energy = bending_energy(Q, x);
      EXPECT_LE(energy, previous + kRoundOff * initial);
      previous = energy;
    }
    EXPECT_LE(previous, 10 * kRoundOff * initial);
  }
}

// A stencil at its flat rest shape, rotated and placed far from the origin, is flat only up to
// the rounding of its coordinates. Its projection must then move the particles by rounding
// size, not by the size of the stencil (C and ∇C are evaluated through the curvature vector
// u = Σ k_j p_j of Q = k kᵀ, so the step is proportional to u).
TEST(IsometricBending, NearlyFlatStencilsDoNotJitter) {
  Random random(99);
  for (int trial = 0; trial < 200; ++trial) {
    const Points planar = random_planar_stencil(random);
    const Points rest = transformed(planar, random.rotation(), random.vector(-100, 100));
    const Matrix4r Q = bending_matrix(rest);
    const Projection r = project(rest, {1, 1, 1, 1}, Q, 1);
    EXPECT_TRUE(r.ok);
    Real size = 0;
    for (const Vector3r& p : rest) size = std::max(size, Real((p - rest[2]).norm()));
    EXPECT_LE(max_norm(r.corr), 200 * kEpsilon * (size + 100)) << "trial " << trial;
  }
}

TEST(IsometricBending, DegenerateInput) {
  Matrix4r Q;
  Points x = kSymmetricStencil;
  x[3] = x[2];  // zero-length edge
  Q.setConstant(7);
  EXPECT_FALSE(PositionBasedDynamics::init_IsometricBendingConstraint(x[0], x[1], x[2], x[3], Q));
  EXPECT_TRUE(Q.isZero());
  x = kSymmetricStencil;
  x[0] = Vector3r(2, 0, 0);  // wing on the edge line: zero-area triangle
  Q.setConstant(7);
  EXPECT_FALSE(PositionBasedDynamics::init_IsometricBendingConstraint(x[0], x[1], x[2], x[3], Q));
  EXPECT_TRUE(Q.isZero());
  Q.setConstant(7);
  EXPECT_FALSE(XPBD::init_IsometricBendingConstraint(x[0], x[1], x[2], x[3], Q));
  EXPECT_TRUE(Q.isZero());

  // A flat stencil satisfies the constraint: true with zero corrections.
  Q = bending_matrix(kSymmetricStencil);
  const Projection flat = project(kSymmetricStencil, {1, 1, 1, 1}, Q, 1);
  EXPECT_TRUE(flat.ok);
  EXPECT_EQ(max_norm(flat.corr), 0);
  // A bent stencil with every particle static: false with zero corrections.
  x = kSymmetricStencil;
  x[0].z() = 1;
  const Projection frozen = project(x, {0, 0, 0, 0}, Q, 1);
  EXPECT_FALSE(frozen.ok);
  EXPECT_EQ(max_norm(frozen.corr), 0);
  // Coincident points of the current shape: finite.
  x = {Vector3r(0.5, 0, 0), Vector3r(0.5, 0, 0), Vector3r(0.5, 0, 0), Vector3r(1, 0, 1)};
  const Projection collapsed = project(x, {1, 1, 1, 1}, Q, 1);
  EXPECT_TRUE(all_finite(collapsed.corr));
}

TEST(XPBDIsometricBending, InitMatchesPBD) {
  Random random(505);
  for (int trial = 0; trial < 5; ++trial) {
    const Points rest = random_stencil(random);
    Matrix4r Q;
    ASSERT_TRUE(XPBD::init_IsometricBendingConstraint(rest[0], rest[1], rest[2], rest[3], Q));
    EXPECT_EQ(Q, bending_matrix(rest));
  }
}

TEST(XPBDIsometricBending, ZeroComplianceEqualsPBDWithStiffnessOne) {
  Random random(506);
  for (int trial = 0; trial < 10; ++trial) {
    const Matrix4r Q = bending_matrix(random_planar_stencil(random));
    const Points x = random_stencil(random);
    const Masses w = random_masses(random);
    Real lambda = 0;
    const Projection xpbd = project_xpbd(x, w, Q, 0, Real(0.01), lambda);
    const Projection pbd = project(x, w, Q, 1);
    ASSERT_TRUE(xpbd.ok);
    for (int i = 0; i < 4; ++i) EXPECT_TRUE(near_relative(xpbd.corr[i], pbd.corr[i]));
  }
}

TEST(XPBDIsometricBending, MultiplierConvergesToComplianceBalance) {
  Random random(507);
  for (int trial = 0; trial < 5; ++trial) {
    const Points rest = random_planar_stencil(random);
    const Matrix4r Q = bending_matrix(rest);
    Points x = rest;
    for (Vector3r& p : x) p += random.vector(Real(-0.3), Real(0.3));
    const Masses w = random_masses(random);
    const Real compliance = Real(1e-4);
    const Real dt = Real(1) / 60;
    const Real alpha_tilde = compliance / (dt * dt);
    Real lambda = 0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      const Projection r = project_xpbd(x, w, Q, compliance, dt, lambda);
      ASSERT_TRUE(r.ok);
      x = applied(x, r.corr);
    }
    const Real C = bending_energy(Q, x);
    EXPECT_NEAR(C + alpha_tilde * lambda, 0, 100 * kRoundOff);
    EXPECT_LT(lambda, 0);
  }
}

TEST(XPBDIsometricBending, InvalidTimeStepOrComplianceReturnsFalseAndKeepsLambda) {
  const Matrix4r Q = bending_matrix(kSymmetricStencil);
  Points x = kSymmetricStencil;
  x[0].z() = 1;
  for (const auto& [compliance, dt] :
       {std::pair<Real, Real>{Real(0.01), Real(0)}, {Real(-1), Real(0.01)}}) {
    Real lambda = Real(-0.75);
    const Projection r = project_xpbd(x, {1, 1, 1, 1}, Q, compliance, dt, lambda);
    EXPECT_FALSE(r.ok);
    EXPECT_EQ(lambda, Real(-0.75));
    EXPECT_EQ(max_norm(r.corr), 0);
  }
  // Flat: satisfied, λ untouched.
  Real lambda = Real(-0.75);
  const Projection flat = project_xpbd(kSymmetricStencil, {1, 1, 1, 1}, Q, 0, Real(0.01), lambda);
  EXPECT_TRUE(flat.ok);
  EXPECT_EQ(lambda, Real(-0.75));
  EXPECT_EQ(max_norm(flat.corr), 0);
}

TEST(IsometricBending, NearDegenerateInputStaysFinite) {
  Random random(508);
  for (int trial = 0; trial < 300; ++trial) {
    const Real scale = kNearDegenerateScales[trial % kNearDegenerateScales.size()];
    // A near-degenerate rest shape (init may reject it) and a near-degenerate current shape.
    const Points rest = near_degenerate_points<4>(random, trial % 3, scale);
    Matrix4r Q;
    const bool valid = PositionBasedDynamics::init_IsometricBendingConstraint(
        rest[0], rest[1], rest[2], rest[3], Q);
    ASSERT_TRUE(Q.allFinite());
    if (!valid) {
      EXPECT_TRUE(Q.isZero());
    }
    const Points x = near_degenerate_points<4>(random, (trial / 3) % 3, scale);
    const Masses w = masses_with_static<4>(random);
    for (const Matrix4r& matrix : {Q, bending_matrix(random_stencil(random))}) {
      const Projection r = project(x, w, matrix, 1);
      EXPECT_TRUE(finite_or_rejected(r.ok, r.corr)) << "scale " << scale;
      Real lambda = 0;
      const Projection soft = project_xpbd(x, w, matrix, Real(1e-6), Real(0.01), lambda);
      EXPECT_TRUE(finite_or_rejected(soft.ok, soft.corr)) << "scale " << scale;
      EXPECT_TRUE(std::isfinite(lambda));
    }
  }
}

}  // namespace isometric_bending_tests
}  // namespace tessera::test
