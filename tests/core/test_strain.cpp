// Tests of strain based dynamics (triangle and tetrahedron): each sub-constraint, isolated by
// zeroing the other stiffnesses, must be a PBD projection of its documented C (checked with
// finite differences); together they must be the Gauss–Seidel sequence in the documented
// order; and the usual invariants, convergence and degenerate cases.
#include <tessera/core/position_based_dynamics.hpp>

#include "test_support.hpp"

namespace tessera::test {
namespace strain_tests {

using PBD = PositionBasedDynamics;

/// Column j of F = [p1 - p0, ...] · M.
template <int Dim>
Vector3r column(const std::array<Vector3r, Dim + 1>& p,
                const Eigen::Matrix<Real, Dim, Dim, Eigen::DontAlign>& M, int j) {
  Vector3r f = Vector3r::Zero();
  for (int k = 0; k < Dim; ++k) f += M(k, j) * (p[k + 1] - p[0]);
  return f;
}

/// The documented C of the stretch (i == j) or shear (i != j) sub-constraint.
template <int Dim>
Real strain_constraint(const std::array<Vector3r, Dim + 1>& p,
                       const Eigen::Matrix<Real, Dim, Dim, Eigen::DontAlign>& M, int i, int j,
                       bool normalize_stretch, bool normalize_shear) {
  const Vector3r fi = column<Dim>(p, M, i), fj = column<Dim>(p, M, j);
  if (i == j) return normalize_stretch ? fi.norm() - 1 : fi.squaredNorm() - 1;
  return normalize_shear ? fi.dot(fj) / (fi.norm() * fj.norm()) : fi.dot(fj);
}

// ---------------------------------------------------------------------------------------------
// Triangle

struct Triangle {
  std::array<Vector3r, 3> rest;
  Matrix2r inv_rest;
};

Triangle random_triangle(Random& random) {
  Triangle t;
  do {
    for (auto& x : t.rest) x = Vector3r(random.uniform(-1, 1), random.uniform(-1, 1), 0);
  } while (std::abs((t.rest[1] - t.rest[0]).cross(t.rest[2] - t.rest[0]).z()) < Real(0.4));
  EXPECT_TRUE(PBD::init_StrainTriangleConstraint(t.rest[0], t.rest[1], t.rest[2], t.inv_rest));
  return t;
}

struct Result3 {
  bool ok;
  std::array<Vector3r, 3> corr;
};

Result3 solve_triangle(const std::array<Vector3r, 3>& p, const std::array<Real, 3>& w,
                       const Matrix2r& M, Real kxx, Real kyy, Real kxy, bool ns, bool nh) {
  Result3 r;
  r.ok = PBD::solve_StrainTriangleConstraint(p[0], w[0], p[1], w[1], p[2], w[2], M, kxx, kyy,
                                             kxy, ns, nh, r.corr[0], r.corr[1], r.corr[2]);
  return r;
}

/// Checks Δp = -k C / Σ w|∇C|² · w ∇C against a finite-difference gradient of C.
template <std::size_t N, class Constraint>
void expect_projection_of(const Constraint& C, Real stiffness,
                          const std::array<Vector3r, N>& p, const std::array<Real, N>& w,
                          const std::array<Vector3r, N>& corr) {
  const auto gradient = numeric_gradient<int(N)>(C, p);
  Real fitted = 0;
  ASSERT_TRUE(along_weighted_gradient(corr, w, gradient, kFiniteDifferenceTolerance, &fitted));
  Real weighted = 0;
  for (std::size_t i = 0; i < N; ++i) weighted += w[i] * gradient[i].squaredNorm();
  const Real expected = stiffness * C(p) / weighted;
  EXPECT_NEAR(fitted, expected, 2 * kFiniteDifferenceTolerance * std::abs(expected));
}

TEST(StrainTriangle, InitInvertsTheRestEdgesInTheXyPlane) {
  Matrix2r M;
  ASSERT_TRUE(PBD::init_StrainTriangleConstraint(Vector3r(1, 1, 5), Vector3r(3, 1, -2),
                                                 Vector3r(1, 2, 0), M));
  EXPECT_TRUE(M.isApprox(Vector2r(Real(0.5), 1).asDiagonal().toDenseMatrix(), kRoundOff));
  // Zero area in the xy plane (the z extent does not count).
  EXPECT_FALSE(PBD::init_StrainTriangleConstraint(Vector3r(0, 0, 0), Vector3r(1, 1, 0),
                                                  Vector3r(2, 2, 1), M));
  EXPECT_TRUE(M.allFinite());
}

TEST(StrainTriangle, StretchedEdgeByHand) {
  Matrix2r M;
  ASSERT_TRUE(PBD::init_StrainTriangleConstraint(Vector3r(0, 0, 0), Vector3r(1, 0, 0),
                                                 Vector3r(0, 1, 0), M));
  const std::array<Vector3r, 3> p = {Vector3r(0, 0, 0), Vector3r(2, 0, 0), Vector3r(0, 1, 0)};
  // C = |f0|² - 1 = 3, ∇p1 = 2 f0 = (4, 0, 0) = -∇p0, Σ w|∇C|² = 32: Δp1 = -3/32 · 4.
  Result3 r = solve_triangle(p, {1, 1, 1}, M, 1, 0, 0, false, false);
  ASSERT_TRUE(r.ok);
  EXPECT_TRUE(near_relative(r.corr[1], Vector3r(Real(-0.375), 0, 0)));
  EXPECT_TRUE(near_relative(r.corr[0], Vector3r(Real(0.375), 0, 0)));
  EXPECT_TRUE(near_relative(r.corr[2], Vector3r::Zero()));
  // Normalized: C = |f0| - 1 = 1, ∇p1 = (1, 0, 0): the edge returns to length 1 at once.
  r = solve_triangle(p, {1, 1, 1}, M, 1, 0, 0, true, false);
  ASSERT_TRUE(r.ok);
  EXPECT_TRUE(near_relative(r.corr[1], Vector3r(Real(-0.5), 0, 0)));
  EXPECT_TRUE(near_relative(r.corr[0], Vector3r(Real(0.5), 0, 0)));
  // The yy and shear constraints are satisfied: nothing to do.
  r = solve_triangle(p, {1, 1, 1}, M, 0, 1, 1, false, false);
  ASSERT_TRUE(r.ok);
  EXPECT_LT(max_norm(r.corr), kRoundOff);
}

TEST(StrainTriangle, EachSubConstraintIsAProjectionOfItsC) {
  Random random(51);
  for (int trial = 0; trial < 10; ++trial) {
    const Triangle t = random_triangle(random);
    std::array<Vector3r, 3> p = t.rest;
    for (auto& x : p) x += Real(0.2) * random.vector();
    const std::array<Real, 3> w = {random.inverse_mass(), random.inverse_mass(),
                                   random.inverse_mass()};
    const Real k = random.uniform(Real(0.3), 1);
    const std::array<std::array<int, 2>, 3> which = {{{0, 0}, {1, 1}, {0, 1}}};
    for (int s = 0; s < 3; ++s) {
      for (const bool normalize : {false, true}) {
        const Real kxx = s == 0 ? k : 0, kyy = s == 1 ? k : 0, kxy = s == 2 ? k : 0;
        const Result3 r = solve_triangle(p, w, t.inv_rest, kxx, kyy, kxy, normalize, normalize);
        ASSERT_TRUE(r.ok);
        auto C = [&](const std::array<Vector3r, 3>& y) {
          return strain_constraint<2>(y, t.inv_rest, which[s][0], which[s][1], normalize,
                                      normalize);
        };
        expect_projection_of(C, k, p, w, r.corr);
        EXPECT_TRUE(conserves_linear_momentum(r.corr, w));
        EXPECT_TRUE(conserves_angular_momentum(p, r.corr, w, Real(0.05)));
      }
    }
  }
}

TEST(StrainTriangle, SubConstraintsRunInGaussSeidelOrder) {
  Random random(52);
  const Triangle t = random_triangle(random);
  std::array<Vector3r, 3> p = t.rest;
  for (auto& x : p) x += Real(0.2) * random.vector();
  const std::array<Real, 3> w = {1, 2, Real(0.5)};
  for (const bool normalize : {false, true}) {
    const Result3 all = solve_triangle(p, w, t.inv_rest, Real(0.9), Real(0.8), Real(0.7),
                                       normalize, normalize);
    ASSERT_TRUE(all.ok);
    std::array<Vector3r, 3> q = p;
    const std::array<Vector3r, 3> stiff = {Vector3r(Real(0.9), 0, 0), Vector3r(0, Real(0.8), 0),
                                           Vector3r(0, 0, Real(0.7))};
    for (const auto& k : stiff) {
      const Result3 one = solve_triangle(q, w, t.inv_rest, k[0], k[1], k[2], normalize, normalize);
      for (int i = 0; i < 3; ++i) q[i] += one.corr[i];
    }
    for (int i = 0; i < 3; ++i) EXPECT_TRUE(near_relative(p[i] + all.corr[i], q[i]));
  }
}

TEST(StrainTriangle, RigidMotionRotatesAndStaticParticlesStay) {
  Random random(53);
  const Triangle t = random_triangle(random);
  std::array<Vector3r, 3> p = t.rest;
  for (auto& x : p) x += Real(0.2) * random.vector();
  const std::array<Real, 3> w = {1, 2, Real(0.5)};
  const Result3 r = solve_triangle(p, w, t.inv_rest, 1, 1, 1, false, true);
  const Matrix3r R = random.rotation();
  const Result3 moved =
      solve_triangle(transformed(p, R, random.vector(-3, 3)), w, t.inv_rest, 1, 1, 1, false, true);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(near_relative(moved.corr[i], R * r.corr[i], 10 * kRoundOff));
  const Result3 pinned = solve_triangle(p, {w[0], w[1], 0}, t.inv_rest, 1, 1, 1, true, true);
  EXPECT_TRUE(pinned.ok);
  EXPECT_EQ(pinned.corr[2], Vector3r::Zero());
  // At rest every sub-constraint is satisfied, for any placement of the triangle.
  const Result3 rest = solve_triangle(transformed(t.rest, R, Vector3r(1, 2, 3)), w, t.inv_rest,
                                      1, 1, 1, true, true);
  EXPECT_TRUE(rest.ok);
  EXPECT_LT(max_norm(rest.corr), 10 * kRoundOff);
}

TEST(StrainTriangle, RepeatedProjectionRestoresTheRestMetric) {
  Random random(54);
  for (const bool normalize : {false, true}) {
    const Triangle t = random_triangle(random);
    std::array<Vector3r, 3> p = t.rest;
    for (auto& x : p) x += Real(0.25) * random.vector();
    const std::array<Real, 3> w = {1, 2, Real(0.5)};
    auto residual = [&] {
      Real worst = 0;
      for (const auto& ij : {std::array<int, 2>{0, 0}, {1, 1}, {0, 1}})
        worst = std::max(worst, std::abs(strain_constraint<2>(p, t.inv_rest, ij[0], ij[1],
                                                              normalize, normalize)));
      return worst;
    };
    const Real initial = residual();
    for (int iteration = 0; iteration < 100; ++iteration) {
      const Result3 r = solve_triangle(p, w, t.inv_rest, 1, 1, 1, normalize, normalize);
      ASSERT_TRUE(r.ok);
      for (int i = 0; i < 3; ++i) p[i] += r.corr[i];
    }
    EXPECT_LT(residual(), 1e-3 * initial);
  }
}

TEST(StrainTriangle, DegenerateInputGivesFalseAndZeroCorrections) {
  Random random(55);
  const Triangle t = random_triangle(random);
  const Vector3r q(1, 2, 3);
  auto expect_zero_false = [](const Result3& r) {
    EXPECT_FALSE(r.ok);
    for (const auto& c : r.corr) EXPECT_EQ(c, Vector3r::Zero());
  };
  for (const bool normalize : {false, true}) {
    expect_zero_false(solve_triangle({q, q, q}, {1, 1, 1}, t.inv_rest, 1, 1, 1, normalize, normalize));
    std::array<Vector3r, 3> p = t.rest;
    p[1] += Vector3r(Real(0.3), 0, 0);
    expect_zero_false(solve_triangle(p, {0, 0, 0}, t.inv_rest, 1, 1, 1, normalize, normalize));
  }
  // A collinear current triangle still gets finite corrections.
  const Result3 line = solve_triangle({Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(2, 0, 0)},
                                      {1, 1, 1}, t.inv_rest, 1, 1, 1, true, true);
  EXPECT_TRUE(all_finite(line.corr));
}

// ---------------------------------------------------------------------------------------------
// Tetrahedron

struct Tet {
  std::array<Vector3r, 4> rest;
  Matrix3r inv_rest;
};

Tet random_tet(Random& random) {
  Tet t;
  for (;;) {
    for (auto& x : t.rest) x = random.vector();
    Matrix3r D;
    for (int k = 0; k < 3; ++k) D.col(k) = t.rest[k + 1] - t.rest[0];
    if (std::abs(D.determinant()) > Real(0.2)) break;
  }
  EXPECT_TRUE(PBD::init_StrainTetraConstraint(t.rest[0], t.rest[1], t.rest[2], t.rest[3],
                                              t.inv_rest));
  return t;
}

struct Result4 {
  bool ok;
  std::array<Vector3r, 4> corr;
};

Result4 solve_tet(const std::array<Vector3r, 4>& p, const std::array<Real, 4>& w,
                  const Matrix3r& M, const Vector3r& stretch, const Vector3r& shear, bool ns,
                  bool nh) {
  Result4 r;
  r.ok = PBD::solve_StrainTetraConstraint(p[0], w[0], p[1], w[1], p[2], w[2], p[3], w[3], M,
                                          stretch, shear, ns, nh, r.corr[0], r.corr[1],
                                          r.corr[2], r.corr[3]);
  return r;
}

/// The documented order: stretch xx, yy, zz, then shear xy, xz, yz.
const std::array<std::array<int, 2>, 6> kTetSubConstraints = {
    {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}}};

/// Stiffness vectors selecting sub-constraint s alone with stiffness k.
std::pair<Vector3r, Vector3r> only(int s, Real k) {
  Vector3r stretch = Vector3r::Zero(), shear = Vector3r::Zero();
  (s < 3 ? stretch[s] : shear[s - 3]) = k;
  return {stretch, shear};
}

TEST(StrainTetra, InitInvertsTheRestEdges) {
  Matrix3r M;
  ASSERT_TRUE(PBD::init_StrainTetraConstraint(Vector3r(0, 0, 0), Vector3r(2, 0, 0),
                                              Vector3r(0, 4, 0), Vector3r(0, 0, 1), M));
  EXPECT_TRUE(M.isApprox(Vector3r(Real(0.5), Real(0.25), 1).asDiagonal().toDenseMatrix(),
                         kRoundOff));
  ASSERT_TRUE(PBD::init_StrainTetraConstraint(Vector3r(0, 0, 0), Vector3r(0, 4, 0),
                                              Vector3r(2, 0, 0), Vector3r(0, 0, 1), M));
  EXPECT_FALSE(PBD::init_StrainTetraConstraint(Vector3r(0, 0, 0), Vector3r(1, 0, 0),
                                               Vector3r(0, 1, 0), Vector3r(3, 3, 0), M));
  EXPECT_TRUE(M.allFinite());
}

TEST(StrainTetra, ShearedTetByHand) {
  Matrix3r M;
  ASSERT_TRUE(PBD::init_StrainTetraConstraint(Vector3r(0, 0, 0), Vector3r(1, 0, 0),
                                              Vector3r(0, 1, 0), Vector3r(0, 0, 1), M));
  // f0 = (1, 0, 0), f1 = (a, 1, 0): shear xy C = a; ∇p1 = f1, ∇p2 = f0, ∇p0 = -(f0 + f1).
  const Real a = Real(0.5);
  const std::array<Vector3r, 4> p = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(a, 1, 0),
                                     Vector3r(0, 0, 1)};
  const auto [stretch, shear] = only(3, 1);
  const Result4 r = solve_tet(p, {1, 1, 1, 1}, M, stretch, shear, false, false);
  ASSERT_TRUE(r.ok);
  const Vector3r g1(a, 1, 0), g2(1, 0, 0), g0 = -(g1 + g2);
  const Real s = a / (g0.squaredNorm() + g1.squaredNorm() + g2.squaredNorm());
  EXPECT_TRUE(near_relative(r.corr[0], -s * g0));
  EXPECT_TRUE(near_relative(r.corr[1], -s * g1));
  EXPECT_TRUE(near_relative(r.corr[2], -s * g2));
  EXPECT_TRUE(near_relative(r.corr[3], Vector3r::Zero()));
}

TEST(StrainTetra, EachSubConstraintIsAProjectionOfItsC) {
  Random random(61);
  for (int trial = 0; trial < 6; ++trial) {
    const Tet t = random_tet(random);
    std::array<Vector3r, 4> p = t.rest;
    for (auto& x : p) x += Real(0.15) * random.vector();
    const std::array<Real, 4> w = {random.inverse_mass(), random.inverse_mass(),
                                   random.inverse_mass(), random.inverse_mass()};
    const Real k = random.uniform(Real(0.3), 1);
    for (int s = 0; s < 6; ++s) {
      for (const bool normalize : {false, true}) {
        const auto [stretch, shear] = only(s, k);
        const Result4 r = solve_tet(p, w, t.inv_rest, stretch, shear, normalize, normalize);
        ASSERT_TRUE(r.ok);
        auto C = [&](const std::array<Vector3r, 4>& y) {
          return strain_constraint<3>(y, t.inv_rest, kTetSubConstraints[s][0],
                                      kTetSubConstraints[s][1], normalize, normalize);
        };
        expect_projection_of(C, k, p, w, r.corr);
        EXPECT_TRUE(conserves_linear_momentum(r.corr, w));
        EXPECT_TRUE(conserves_angular_momentum(p, r.corr, w, Real(0.05)));
      }
    }
  }
}

TEST(StrainTetra, SubConstraintsRunInGaussSeidelOrder) {
  Random random(62);
  const Tet t = random_tet(random);
  std::array<Vector3r, 4> p = t.rest;
  for (auto& x : p) x += Real(0.15) * random.vector();
  const std::array<Real, 4> w = {1, 2, Real(0.5), 1};
  const std::array<Real, 6> k = {Real(0.9), Real(0.8), Real(0.7), Real(0.6), Real(0.5), Real(0.4)};
  for (const bool normalize : {false, true}) {
    const Result4 all = solve_tet(p, w, t.inv_rest, Vector3r(k[0], k[1], k[2]),
                                  Vector3r(k[3], k[4], k[5]), normalize, normalize);
    ASSERT_TRUE(all.ok);
    std::array<Vector3r, 4> q = p;
    for (int s = 0; s < 6; ++s) {
      const auto [stretch, shear] = only(s, k[s]);
      const Result4 one = solve_tet(q, w, t.inv_rest, stretch, shear, normalize, normalize);
      for (int i = 0; i < 4; ++i) q[i] += one.corr[i];
    }
    for (int i = 0; i < 4; ++i) EXPECT_TRUE(near_relative(p[i] + all.corr[i], q[i]));
  }
}

// The same chain with each normalisation flag on its own, a static vertex, and sub-constraints
// switched off (stiffness 0) between active ones: the element's result is still the single
// sub-constraints applied in order to the positions the previous ones moved.
TEST(StrainTetra, GaussSeidelOrderHoldsWithMixedFlagsStaticVerticesAndSkippedEntries) {
  Random random(65);
  const Tet t = random_tet(random);
  std::array<Vector3r, 4> p = t.rest;
  for (auto& x : p) x += Real(0.15) * random.vector();
  const std::array<std::array<Real, 4>, 3> masses = {
      {{1, 2, Real(0.5), 1}, {0, 2, Real(0.5), 1}, {1, 0, Real(0.5), 0}}};
  const std::array<Real, 6> k = {Real(0.9), 0, Real(0.7), Real(0.6), 0, Real(0.4)};
  for (const auto& w : masses) {
    for (const bool normalize_stretch : {false, true}) {
      for (const bool normalize_shear : {false, true}) {
        const Result4 all = solve_tet(p, w, t.inv_rest, Vector3r(k[0], k[1], k[2]),
                                      Vector3r(k[3], k[4], k[5]), normalize_stretch,
                                      normalize_shear);
        ASSERT_TRUE(all.ok);
        std::array<Vector3r, 4> q = p;
        for (int s = 0; s < 6; ++s) {
          if (k[std::size_t(s)] == 0) continue;
          const auto [stretch, shear] = only(s, k[std::size_t(s)]);
          const Result4 one =
              solve_tet(q, w, t.inv_rest, stretch, shear, normalize_stretch, normalize_shear);
          ASSERT_TRUE(one.ok);
          for (int i = 0; i < 4; ++i) q[i] += one.corr[i];
        }
        for (int i = 0; i < 4; ++i) {
          EXPECT_TRUE(near_relative(p[i] + all.corr[i], q[i]))
              << "vertex " << i << ", stretch " << normalize_stretch << ", shear "
              << normalize_shear;
          if (w[std::size_t(i)] == 0) EXPECT_EQ(all.corr[i], Vector3r::Zero());
        }
      }
    }
  }
}

// Switched-off sub-constraints that would be degenerate (zz and the shears with z, normalised,
// on a vanished column f_z) leave the active ones (xx, yy, xy) to run as if alone: ok, finite
// corrections, those of their chain. p0 is static, so f_z = p3 - p0 stays zero through the
// chain (with M = I only f_z's entries move p3).
TEST(StrainTetra, SwitchedOffDegenerateSubConstraintsLeaveTheOthers) {
  Matrix3r m;
  ASSERT_TRUE(PBD::init_StrainTetraConstraint(Vector3r(0, 0, 0), Vector3r(1, 0, 0),
                                              Vector3r(0, 1, 0), Vector3r(0, 0, 1), m));
  const Vector3r stretch(Real(0.9), Real(0.8), 0), shear(Real(0.7), 0, 0);
  const std::array<Real, 4> w = {0, 1, 2, 1};
  const Vector3r p0(Real(0.1), Real(-0.2), Real(0.05));
  const std::array<Vector3r, 4> p = {p0, Vector3r(Real(1.3), Real(0.1), Real(-0.1)),
                                     Vector3r(Real(0.4), Real(0.8), Real(0.2)), p0};
  const Result4 all = solve_tet(p, w, m, stretch, shear, true, true);
  ASSERT_TRUE(all.ok);
  EXPECT_TRUE(all_finite(all.corr));
  EXPECT_EQ(all.corr[0], Vector3r::Zero());
  EXPECT_EQ(all.corr[3], Vector3r::Zero());
  EXPECT_GT(all.corr[1].norm(), Real(0.1));
  EXPECT_GT(all.corr[2].norm(), Real(0.01));
  std::array<Vector3r, 4> q = p;
  for (const int s : {0, 1, 3}) {
    const auto [one_stretch, one_shear] = only(s, s < 3 ? stretch[s] : shear[s - 3]);
    const Result4 one = solve_tet(q, w, m, one_stretch, one_shear, true, true);
    ASSERT_TRUE(one.ok);
    for (int i = 0; i < 4; ++i) q[i] += one.corr[i];
  }
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(near_relative(p[i] + all.corr[i], q[i])) << i;
  // Switched on, the vanished column makes the element degenerate.
  EXPECT_FALSE(solve_tet(p, w, m, Vector3r::Ones(), Vector3r::Ones(), true, true).ok);
}

TEST(StrainTetra, InvariantsAndConvergence) {
  Random random(63);
  const Tet t = random_tet(random);
  std::array<Vector3r, 4> p = t.rest;
  for (auto& x : p) x += Real(0.2) * random.vector();
  const std::array<Real, 4> w = {1, 2, Real(0.5), 1};
  const Vector3r ones = Vector3r::Ones();
  const Result4 r = solve_tet(p, w, t.inv_rest, ones, ones, false, true);
  const Matrix3r R = random.rotation();
  const Result4 moved =
      solve_tet(transformed(p, R, random.vector(-3, 3)), w, t.inv_rest, ones, ones, false, true);
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(near_relative(moved.corr[i], R * r.corr[i], 10 * kRoundOff));
  const Result4 pinned = solve_tet(p, {0, w[1], w[2], w[3]}, t.inv_rest, ones, ones, true, true);
  EXPECT_TRUE(pinned.ok);
  EXPECT_EQ(pinned.corr[0], Vector3r::Zero());

  for (const bool normalize : {false, true}) {
    std::array<Vector3r, 4> q = p;
    auto residual = [&] {
      Real worst = 0;
      for (const auto& ij : kTetSubConstraints)
        worst = std::max(worst, std::abs(strain_constraint<3>(q, t.inv_rest, ij[0], ij[1],
                                                              normalize, normalize)));
      return worst;
    };
    const Real initial = residual();
    for (int iteration = 0; iteration < 300; ++iteration) {
      const Result4 step = solve_tet(q, w, t.inv_rest, ones, ones, normalize, normalize);
      ASSERT_TRUE(step.ok);
      for (int i = 0; i < 4; ++i) q[i] += step.corr[i];
    }
    EXPECT_LT(residual(), 1e-3 * initial);
  }
}

TEST(StrainTetra, DegenerateInputGivesFalseAndZeroCorrections) {
  Random random(64);
  const Tet t = random_tet(random);
  const Vector3r q(1, 2, 3);
  const Vector3r ones = Vector3r::Ones();
  for (const bool normalize : {false, true}) {
    Result4 r = solve_tet({q, q, q, q}, {1, 1, 1, 1}, t.inv_rest, ones, ones, normalize, normalize);
    EXPECT_FALSE(r.ok);
    for (const auto& c : r.corr) EXPECT_EQ(c, Vector3r::Zero());
    std::array<Vector3r, 4> p = t.rest;
    p[3] += Vector3r(Real(0.3), 0, 0);
    r = solve_tet(p, {0, 0, 0, 0}, t.inv_rest, ones, ones, normalize, normalize);
    EXPECT_FALSE(r.ok);
    for (const auto& c : r.corr) EXPECT_EQ(c, Vector3r::Zero());
  }
  // Flat current tetrahedron: finite.
  std::array<Vector3r, 4> flat = t.rest;
  flat[3] = (flat[0] + flat[1] + flat[2]) / 3;
  EXPECT_TRUE(all_finite(solve_tet(flat, {1, 1, 1, 1}, t.inv_rest, ones, ones, true, true).corr));
}

// A shear whose one movable vertex has a vanishing gradient: ∇_{p0} C_xy = c0^x f_y + c0^y f_x
// with c0 = -(column sums of M) = (-0.3, -0.7), zero for f_y = -(7/3) f_x. The denominator,
// a quadratic form in ∂C/∂f, is then rounding noise of its squares' size: the element is
// degenerate (false, zero corrections), never stepped by C divided by that noise.
TEST(StrainTetra, ShearWithAVanishingMovableGradientIsDegenerate) {
  Matrix3r m = Matrix3r::Zero();
  m(0, 0) = Real(0.3);
  m(1, 1) = Real(0.7);
  m(2, 2) = Real(1);
  const Vector3r p0(Real(0.5), Real(-0.25), Real(0.75));
  for (const Vector3r& edge : {Vector3r(Real(0.1), Real(0.2), Real(0.3)),
                               Vector3r(Real(0.7), Real(-0.3), Real(0.11)),
                               Vector3r(Real(1.3), Real(0.9), Real(-0.6))}) {
    // f_x = 0.3 (p1 - p0), f_y = 0.7 (p2 - p0) = -0.7 edge = -(7/3) f_x.
    const std::array<Vector3r, 4> p = {p0, p0 + edge, p0 - edge, p0 + Vector3r(0, 0, 1)};
    const Result4 r = solve_tet(p, {1, 0, 0, 0}, m, Vector3r::Zero(), Vector3r(1, 0, 0), false,
                                false);
    EXPECT_FALSE(r.ok) << edge.transpose();
    for (const auto& c : r.corr) EXPECT_EQ(c, Vector3r::Zero()) << edge.transpose();
  }
}

}  // namespace strain_tests
}  // namespace tessera::test
