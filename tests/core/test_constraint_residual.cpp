// constraint_residual for every family: what the solver reports as the per-family residual.
// For each family: 0 at the rest configuration, a hand-computed answer for a simple
// deformation, invariance under rigid motions, and a finite value (with its documented
// reading) for degenerate configurations: all particles at one point, and points near a
// point, a line or a plane.
#include <tessera/core/constraint_residual.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <numeric>
#include <vector>

#include "batch_test_support.hpp"
#include "test_support.hpp"

namespace tessera {
namespace constraint_residual_tests {

using test::Random;

/// Round-off of a residual that should be zero, or agree with a hand-computed value, after a
/// few dozen flops on O(1) coordinates.
constexpr Real kResidualTolerance = kDoublePrecision ? Real(1e-12) : Real(2e-5);

std::vector<Real> unit_masses(std::size_t n) { return std::vector<Real>(n, Real(1)); }

/// The residual of constraint c of `batch` with the particles at `positions`.
template <class Batch>
Real residual(const Batch& batch, const std::vector<Vector3r>& positions, std::size_t c = 0) {
  ParticleState state(positions, unit_masses(positions.size()));
  return constraint_residual(ParticleArrays::of(state), batch, c);
}

/// x ↦ A (x − origin) + origin for every point.
std::vector<Vector3r> deformed(const std::vector<Vector3r>& x, const Matrix3r& A,
                               const Vector3r& origin) {
  std::vector<Vector3r> y;
  for (const Vector3r& p : x) y.push_back(A * (p - origin) + origin);
  return y;
}

std::vector<Vector3r> scaled(const std::vector<Vector3r>& x, Real s, const Vector3r& origin) {
  return deformed(x, s * Matrix3r::Identity(), origin);
}

std::vector<Vector3r> rigidly_moved(const std::vector<Vector3r>& x, const Matrix3r& R,
                                    const Vector3r& t) {
  std::vector<Vector3r> y;
  for (const Vector3r& p : x) y.push_back(R * p + t);
  return y;
}

Vector3r centroid(const std::vector<Vector3r>& x) {
  Vector3r sum = Vector3r::Zero();
  for (const Vector3r& p : x) sum += p;
  return sum / Real(x.size());
}

/// The rotation by `angle` about the unit `axis` through `point`, applied to p.
Vector3r rotated_about(const Vector3r& p, const Vector3r& point, const Vector3r& axis,
                       Real angle) {
  return Eigen::AngleAxis<Real>(angle, axis) * (p - point) + point;
}

/// ‖½ (FᵀF − I)‖_F, computed with Eigen (the hand reference of the strain families).
template <int Rows, int Cols>
Real green_strain_norm(const Eigen::Matrix<Real, Rows, Cols>& F) {
  const Eigen::Matrix<Real, Cols, Cols> strain =
      Real(0.5) * (F.transpose() * F - Eigen::Matrix<Real, Cols, Cols>::Identity());
  return strain.norm();
}

/// The residual is unchanged (to round-off) by five random rigid motions of the positions.
template <class Batch>
void expect_rigid_invariance(const Batch& batch, const std::vector<Vector3r>& positions,
                             std::size_t c = 0) {
  const Real reference = residual(batch, positions, c);
  Random random(77);
  for (int trial = 0; trial < 5; ++trial) {
    const Matrix3r R = random.rotation();
    const Vector3r t = random.vector(-5, 5);
    EXPECT_NEAR(residual(batch, rigidly_moved(positions, R, t), c), reference,
                test::kRoundOff * std::max(Real(1), reference))
        << "trial " << trial;
  }
}

/// Finite and ≥ 0 on N points near one point, a line or a plane (test::near_degenerate_points,
/// every scale down to the exact degenerate shape).
template <std::size_t N, class Batch>
void expect_finite_near_degenerate(const Batch& batch) {
  Random random(5);
  for (int pattern = 0; pattern < 3; ++pattern)
    for (const Real scale : test::kNearDegenerateScales)
      for (int trial = 0; trial < 20; ++trial) {
        const auto points = test::near_degenerate_points<N>(random, pattern, scale);
        const Real r = residual(batch, std::vector<Vector3r>(points.begin(), points.end()));
        ASSERT_TRUE(std::isfinite(r)) << "pattern " << pattern << ", scale " << scale;
        ASSERT_GE(r, 0) << "pattern " << pattern << ", scale " << scale;
      }
}

/// n copies of one point.
std::vector<Vector3r> collapsed(std::size_t n) {
  return std::vector<Vector3r>(n, Vector3r(Real(0.3), Real(-0.2), Real(0.7)));
}

/// A well-shaped, slightly irregular tetrahedron away from the origin (positive orientation).
std::vector<Vector3r> rest_tetrahedron() {
  const Vector3r o(Real(0.4), Real(-0.3), Real(1.2));
  return {o, o + Vector3r(Real(1.1), Real(0.1), Real(-0.05)),
          o + Vector3r(Real(0.15), Real(0.9), Real(0.1)),
          o + Vector3r(Real(-0.1), Real(0.2), Real(1.05))};
}

const std::vector<ParticleIndex> kFirstThree = {0, 1, 2};
const std::vector<ParticleIndex> kFirstFour = {0, 1, 2, 3};

/// A moderate general deformation: F = A for every element under x ↦ A x.
Matrix3r general_deformation() {
  Matrix3r A;
  A << Real(1.1), Real(0.2), Real(-0.05),  //
      Real(0.05), Real(0.9), Real(0.1),    //
      Real(-0.1), Real(0.15), Real(1.2);
  return A;
}

// ------------------------------------------------------------------------------- distance
TEST(DistanceResidual, RelativeStretchOfTheRestLength) {
  const Vector3r p0(Real(0.1), Real(0.2), Real(0.3));
  const Vector3r direction = Vector3r(1, 2, 2) / 3;
  const std::vector<Vector3r> rest = {p0, p0 + 2 * direction};
  const std::vector<ParticleIndex> edge = {0, 1};
  const DistanceConstraints batch = make_distance_constraints({edge, rest});
  EXPECT_NEAR(residual(batch, rest), 0, kResidualTolerance);
  EXPECT_NEAR(residual(batch, {p0, p0 + Real(2.2) * direction}), Real(0.1), kResidualTolerance);
  EXPECT_NEAR(residual(batch, {p0, p0 + Real(1.5) * direction}), Real(0.25), kResidualTolerance);
  expect_rigid_invariance(batch, {p0, p0 + Real(2.6) * direction});
  EXPECT_EQ(residual(batch, collapsed(2)), Real(1));
  expect_finite_near_degenerate<2>(batch);
}

TEST(DistanceResidual, EachConstraintReadsItsOwnParticles) {
  // A chain 0 - 1 - 2 with rest lengths 1 and 2; only the second edge is stretched (by 30 %).
  const std::vector<Vector3r> rest = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(3, 0, 0)};
  const std::vector<ParticleIndex> chain = {0, 1, 1, 2};
  const DistanceConstraints batch = make_distance_constraints({chain, rest});
  const std::vector<Vector3r> current = {rest[0], rest[1], Vector3r(Real(3.6), 0, 0)};
  EXPECT_NEAR(residual(batch, current, 0), 0, kResidualTolerance);
  EXPECT_NEAR(residual(batch, current, 1), Real(0.3), kResidualTolerance);
}

// ------------------------------------------------------------------ the XPBD residual
/// xpbd_residuals measures C + α̃λ in the family's units: distance |C + α̃λ| / l0, and it is
/// the plain residual where λ = 0 or α = 0.
TEST(XpbdResidual, DistanceMeasuresCPlusAlphaTildeLambda) {
  const std::vector<Vector3r> rest = {Vector3r(0, 0, 0), Vector3r(2, 0, 0)};
  const std::vector<ParticleIndex> edge = {0, 1};
  DistanceConstraints batch = make_distance_constraints({edge, rest, 1, Real(1e-4)});
  const std::vector<Vector3r> stretched = {Vector3r(0, 0, 0), Vector3r(Real(2.2), 0, 0)};
  ParticleState state(stretched, unit_masses(2));
  const ParticleArrays particles = ParticleArrays::of(state);
  const Real dt = Real(0.01);  // α̃ = 1e-4 / 1e-4 = 1
  Real out = -1;
  xpbd_residuals(particles, batch, 0, 1, dt, &out);
  EXPECT_NEAR(out, Real(0.1), kResidualTolerance) << "λ = 0: the plain residual";
  batch.lambda[0] = Real(-0.15);  // C + α̃λ = 0.2 - 0.15
  xpbd_residuals(particles, batch, 0, 1, dt, &out);
  EXPECT_NEAR(out, Real(0.025), kResidualTolerance);
  batch.lambda[0] = Real(-0.2);  // the compliant equilibrium: C = -α̃λ
  xpbd_residuals(particles, batch, 0, 1, dt, &out);
  EXPECT_NEAR(out, 0, kResidualTolerance);
  EXPECT_NEAR(constraint_residual(particles, batch, 0), Real(0.1), kResidualTolerance)
      << "constraint_residuals ignores λ";
  batch.compliance[0] = 0;
  xpbd_residuals(particles, batch, 0, 1, dt, &out);
  EXPECT_NEAR(out, Real(0.1), kResidualTolerance) << "a hard constraint: the violation";
  // A time step so small that 1/dt² overflows: a hard constraint is still its violation, as
  // the projection still projects it (α̃ = 0 for α = 0), not NaN.
  xpbd_residuals(particles, batch, 0, 1, std::sqrt(std::numeric_limits<Real>::min()) / 4, &out);
  EXPECT_NEAR(out, Real(0.1), kResidualTolerance) << "a hard constraint, tiny dt";
}

/// Converging one compliant constraint by repeated XPBD projections drives the XPBD residual
/// to zero while the violation |C| stays: every XPBD family.
template <class Batch, class Project>
void expect_xpbd_residual_converges(Batch batch, std::vector<Vector3r> positions,
                                    Project&& project, Real compliance) {
  std::fill(batch.compliance.begin(), batch.compliance.end(), compliance);
  ParticleState state(positions, unit_masses(positions.size()));
  const ParticleArrays particles = ParticleArrays::of(state);
  const ProjectionSettings settings{ConstraintSemantics::compliance, Real(0.01)};
  for (int i = 0; i < 200; ++i) project(particles, batch, 0, 1, settings);
  Real xpbd = -1;
  xpbd_residuals(particles, batch, 0, 1, settings.dt, &xpbd);
  EXPECT_LT(xpbd, Real(1e-3) * constraint_residual(particles, batch, 0));
  EXPECT_GT(constraint_residual(particles, batch, 0), Real(1e-3)) << "a compliant constraint stays violated";
}

TEST(XpbdResidual, VanishesAtTheCompliantSolutionOfEveryXpbdFamily) {
  const std::vector<Vector3r> rest = rest_tetrahedron();
  std::vector<Vector3r> squashed = rest;
  squashed[3] = rest[0] + Real(0.5) * (rest[3] - rest[0]);
  expect_xpbd_residual_converges(make_volume_constraints({kFirstFour, rest}), squashed,
                                 project_volume_constraints, Real(1e-4));
  const std::vector<ParticleIndex> edge = {0, 1};
  expect_xpbd_residual_converges(make_distance_constraints({edge, rest}),
                                 {rest[0], rest[1] + (rest[1] - rest[0]), rest[2], rest[3]},
                                 project_distance_constraints, Real(1e-4));
  expect_xpbd_residual_converges(
      make_fem_tetra_constraints({kFirstFour, rest, Real(1e4), Real(0.3), true}), squashed,
      project_fem_tetra_constraints, Real(1e-3));
}

// --------------------------------------------------------------------------------- volume
TEST(VolumeResidual, RelativeChangeOfTheSignedVolume) {
  const std::vector<Vector3r> rest = rest_tetrahedron();
  const VolumeConstraints batch = make_volume_constraints({kFirstFour, rest});
  EXPECT_NEAR(residual(batch, rest), 0, kResidualTolerance);
  const Real s = Real(1.2);
  EXPECT_NEAR(residual(batch, scaled(rest, s, centroid(rest))), s * s * s - 1,
              kResidualTolerance);
  EXPECT_NEAR(residual(batch, scaled(rest, Real(0.5), rest[2])), Real(0.875),
              kResidualTolerance);
  // Mirrored: V = -V0, a change of 2 V0.
  const Matrix3r mirror = Eigen::DiagonalMatrix<Real, 3>(1, 1, -1).toDenseMatrix();
  EXPECT_NEAR(residual(batch, deformed(rest, mirror, centroid(rest))), 2, kResidualTolerance);
  expect_rigid_invariance(batch, deformed(rest, general_deformation(), centroid(rest)));
  EXPECT_EQ(residual(batch, collapsed(4)), Real(1));
  expect_finite_near_degenerate<4>(batch);
}

// ------------------------------------------------------------------------------- dihedral
/// Wings p0, p1 about the shared edge p2 = origin → p3 along y; p1 folded by `fold` radians.
std::vector<Vector3r> dihedral_stencil(Real fold) {
  const Vector3r p2(0, 0, 0), p3(0, 1, 0), axis(0, 1, 0);
  const Vector3r p0(-1, Real(0.4), 0);
  const Vector3r p1 = rotated_about(Vector3r(Real(0.9), Real(0.7), 0), p2, axis, fold);
  return {p0, p1, p2, p3};
}

TEST(DihedralResidual, AngleChangeInRadians) {
  for (const Real rest_fold : {Real(0), Real(0.5), Real(-1.2)}) {
    SCOPED_TRACE(rest_fold);
    const std::vector<Vector3r> rest = dihedral_stencil(rest_fold);
    const DihedralConstraints batch = make_dihedral_constraints({kFirstFour, rest});
    EXPECT_NEAR(residual(batch, rest), 0, kResidualTolerance);
    // Folding further in the rest fold's direction (away from φ = 0 and φ = π).
    const Real direction = rest_fold < 0 ? Real(-1) : Real(1);
    EXPECT_NEAR(residual(batch, dihedral_stencil(rest_fold + direction * Real(0.3))), Real(0.3),
                kResidualTolerance);
    EXPECT_NEAR(residual(batch, dihedral_stencil(rest_fold + direction * Real(0.7))), Real(0.7),
                kResidualTolerance);
    expect_rigid_invariance(batch, dihedral_stencil(rest_fold + direction * Real(0.4)));
    // Collapsed: no angle; the formula reads φ = 0, so the residual is φ0.
    EXPECT_NEAR(residual(batch, collapsed(4)), batch.rest_angle[0], kResidualTolerance);
    expect_finite_near_degenerate<4>(batch);
  }
}

TEST(DihedralResidual, NeverExceedsPi) {
  const DihedralConstraints batch = make_dihedral_constraints({kFirstFour, dihedral_stencil(0)});
  Random random(3);
  for (int trial = 0; trial < 200; ++trial) {
    const std::vector<Vector3r> x = {random.vector(), random.vector(), random.vector(),
                                     random.vector()};
    const Real r = residual(batch, x);
    EXPECT_GE(r, 0);
    EXPECT_LE(r, std::numbers::pi_v<Real> + kResidualTolerance);
  }
}

// ---------------------------------------------------------------------- isometric bending
/// A flat, asymmetric stencil in the xy plane: wings p0, p1, shared edge p2-p3.
std::vector<Vector3r> flat_bending_stencil() {
  return {Vector3r(-1, Real(0.3), 0), Vector3r(Real(0.8), Real(0.6), 0), Vector3r(0, 0, 0),
          Vector3r(Real(0.1), 1, 0)};
}

TEST(IsometricBendingResidual, MeanCurvatureVectorOfTheStencil) {
  const std::vector<Vector3r> rest = flat_bending_stencil();
  const IsometricBendingConstraints batch = make_isometric_bending_constraints({kFirstFour, rest});
  EXPECT_NEAR(residual(batch, rest), 0, kResidualTolerance);
  // From a flat stencil u = Σ k_j p_j is 0, so moving wing p0 by d gives |u| = |k_0| |d|,
  // with k_0² = Q_00 (Q = k kᵀ), whatever the direction of d.
  const Real k0 = std::sqrt(batch.matrix(0)(0, 0));
  for (const Vector3r& d : {Vector3r(0, 0, Real(0.2)), Vector3r(Real(0.1), Real(-0.1), Real(0.05))}) {
    std::vector<Vector3r> x = rest;
    x[0] += d;
    EXPECT_NEAR(residual(batch, x), k0 * d.norm(), kResidualTolerance);
  }
  // Also for a general fold, against C = ½ pᵀ Q p per coordinate: |u| = sqrt(pᵀ Q p).
  std::vector<Vector3r> folded = rest;
  folded[1] = rotated_about(rest[1], rest[2], (rest[3] - rest[2]).normalized(), Real(0.6));
  folded[0].z() += Real(0.1);
  Real quadratic = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      quadratic += batch.matrix(0)(i, j) * folded[std::size_t(i)].dot(folded[std::size_t(j)]);
  EXPECT_NEAR(residual(batch, folded), std::sqrt(quadratic), test::kRoundOff);
  expect_rigid_invariance(batch, folded);
  EXPECT_NEAR(residual(batch, collapsed(4)), 0, kResidualTolerance);
  expect_finite_near_degenerate<4>(batch);
}

TEST(IsometricBendingResidual, IsDimensionless) {
  // Scaling rest and current shape together leaves |u| unchanged (k ~ 1/length).
  const std::vector<Vector3r> rest = flat_bending_stencil();
  std::vector<Vector3r> folded = rest;
  folded[1] = rotated_about(rest[1], rest[2], (rest[3] - rest[2]).normalized(), Real(0.5));
  const IsometricBendingConstraints batch = make_isometric_bending_constraints({kFirstFour, rest});
  const Vector3r origin = Vector3r::Zero();
  const IsometricBendingConstraints big =
      make_isometric_bending_constraints({kFirstFour, scaled(rest, 3, origin)});
  EXPECT_NEAR(residual(big, scaled(folded, 3, origin)), residual(batch, folded),
              test::kRoundOff);
}

// ---------------------------------------------------------------------- proximity families
/// One proximity constraint on particles 0 .. count−1 with rest distance d0.
ProximityDistanceConstraintInput proximity_input(const std::vector<ParticleIndex>& particles,
                                                 Real rest_distance) {
  ProximityDistanceConstraintInput input;
  input.particles = particles;
  input.particle_count = particles.size();
  input.rest_distance = rest_distance;
  return input;
}

TEST(EdgePointDistanceResidual, RelativeChangeOfThePointSegmentDistance) {
  // Particle order (p, p0, p1): the point above the segment p0-p1 at the rest distance 0.5.
  const std::vector<Vector3r> rest = {Vector3r(Real(0.5), Real(0.5), 0), Vector3r(0, 0, 0),
                                      Vector3r(2, 0, 0)};
  const EdgePointDistanceConstraints batch =
      make_edge_point_distance_constraints(proximity_input(kFirstThree, Real(0.5)));
  EXPECT_NEAR(residual(batch, rest), 0, kResidualTolerance);
  EXPECT_NEAR(residual(batch, {Vector3r(Real(0.5), Real(0.6), 0), rest[1], rest[2]}),
              Real(0.2), kResidualTolerance);
  // Beyond the end p1 the closest point is p1 itself: d = 1.
  EXPECT_NEAR(residual(batch, {Vector3r(3, 0, 0), rest[1], rest[2]}), 1, kResidualTolerance);
  expect_rigid_invariance(batch, {Vector3r(Real(1.5), Real(0.3), Real(0.2)), rest[1], rest[2]});
  EXPECT_EQ(residual(batch, collapsed(3)), Real(1));  // d = 0
  expect_finite_near_degenerate<3>(batch);

  // With d0 = 0 the residual is the distance itself.
  const EdgePointDistanceConstraints touching =
      make_edge_point_distance_constraints(proximity_input(kFirstThree, 0));
  EXPECT_NEAR(residual(touching, rest), Real(0.5), kResidualTolerance);
  EXPECT_EQ(residual(touching, collapsed(3)), Real(0));
}

TEST(TrianglePointDistanceResidual, RelativeChangeOfThePointTriangleDistance) {
  // Particle order (p, p0, p1, p2): the point 0.4 above the face.
  const std::vector<Vector3r> rest = {Vector3r(Real(0.2), Real(0.2), Real(0.4)),
                                      Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0)};
  const TrianglePointDistanceConstraints batch =
      make_triangle_point_distance_constraints(proximity_input(kFirstFour, Real(0.4)));
  EXPECT_NEAR(residual(batch, rest), 0, kResidualTolerance);
  std::vector<Vector3r> closer = rest;
  closer[0].z() = Real(0.3);
  EXPECT_NEAR(residual(batch, closer), Real(0.25), kResidualTolerance);
  // Below the face by 0.2: d = 0.2 again (distance, not signed).
  closer[0].z() = Real(-0.2);
  EXPECT_NEAR(residual(batch, closer), Real(0.5), kResidualTolerance);
  std::vector<Vector3r> off_face = rest;
  off_face[0] = Vector3r(Real(1.5), Real(0.5), Real(0.1));
  expect_rigid_invariance(batch, off_face);
  EXPECT_EQ(residual(batch, collapsed(4)), Real(1));
  expect_finite_near_degenerate<4>(batch);
}

TEST(EdgeEdgeDistanceResidual, RelativeChangeOfTheSegmentSegmentDistance) {
  // Two crossing segments, one 0.5 above the other.
  const auto crossing = [](Real height) {
    return std::vector<Vector3r>{Vector3r(-1, 0, 0), Vector3r(1, 0, 0), Vector3r(0, -1, height),
                                 Vector3r(Real(0.2), 1, height)};
  };
  const EdgeEdgeDistanceConstraints batch =
      make_edge_edge_distance_constraints(proximity_input(kFirstFour, Real(0.5)));
  EXPECT_NEAR(residual(batch, crossing(Real(0.5))), 0, kResidualTolerance);
  EXPECT_NEAR(residual(batch, crossing(Real(0.45))), Real(0.1), kResidualTolerance);
  EXPECT_NEAR(residual(batch, crossing(Real(0.8))), Real(0.6), kResidualTolerance);
  expect_rigid_invariance(batch, crossing(Real(0.3)));
  EXPECT_EQ(residual(batch, collapsed(4)), Real(1));
  expect_finite_near_degenerate<4>(batch);
}

// ------------------------------------------------------------------------ strain families
/// A triangle in the xy plane (the strain triangle's rest convention), off the origin.
std::vector<Vector3r> rest_triangle_xy() {
  const Vector3r o(Real(0.3), Real(-0.4), Real(0.25));
  return {o, o + Vector3r(1, Real(0.1), 0), o + Vector3r(Real(0.2), Real(0.9), 0)};
}

/// A triangle in a tilted plane.
std::vector<Vector3r> rest_triangle_tilted() {
  const Vector3r o(Real(-0.2), Real(0.5), Real(0.9));
  return {o, o + Vector3r(Real(0.8), Real(0.3), Real(0.4)),
          o + Vector3r(Real(-0.1), Real(0.7), Real(0.6))};
}

/// F of a triangle deformed by x ↦ A x: A restricted to the rest triangle's plane, in the
/// frame (p1 − p0 normalised, its in-plane normal), which F's Green strain does not depend on.
Eigen::Matrix<Real, 3, 2> triangle_deformation(const std::vector<Vector3r>& rest,
                                              const Matrix3r& A) {
  const Vector3r a = (rest[1] - rest[0]).normalized();
  const Vector3r normal = (rest[1] - rest[0]).cross(rest[2] - rest[0]).normalized();
  Eigen::Matrix<Real, 3, 2> frame;
  frame.col(0) = a;
  frame.col(1) = normal.cross(a);
  return A * frame;
}

/// The residual checks of a triangle family on rest triangle `rest` (every stretch in-plane).
template <class Batch>
void expect_triangle_green_strain(const Batch& batch, const std::vector<Vector3r>& rest) {
  EXPECT_NEAR(residual(batch, rest), 0, kResidualTolerance);
  for (const Real s : {Real(1.1), Real(0.8)})
    EXPECT_NEAR(residual(batch, scaled(rest, s, centroid(rest))),
                std::sqrt(Real(2)) * Real(0.5) * std::abs(s * s - 1), kResidualTolerance);
  const Matrix3r A = general_deformation();
  const std::vector<Vector3r> x = deformed(rest, A, rest[1]);
  EXPECT_NEAR(residual(batch, x), green_strain_norm(triangle_deformation(rest, A)),
              kResidualTolerance);
  expect_rigid_invariance(batch, x);
  EXPECT_NEAR(residual(batch, collapsed(3)), std::sqrt(Real(2)) / 2, kResidualTolerance);
  expect_finite_near_degenerate<3>(batch);
}

/// The residual checks of a tetrahedron family on rest_tetrahedron().
template <class Batch>
void expect_tetra_green_strain(const Batch& batch) {
  const std::vector<Vector3r> rest = rest_tetrahedron();
  EXPECT_NEAR(residual(batch, rest), 0, kResidualTolerance);
  for (const Real s : {Real(1.1), Real(0.8)})
    EXPECT_NEAR(residual(batch, scaled(rest, s, centroid(rest))),
                std::sqrt(Real(3)) * Real(0.5) * std::abs(s * s - 1), kResidualTolerance);
  const Matrix3r A = general_deformation();
  const std::vector<Vector3r> x = deformed(rest, A, rest[2]);
  EXPECT_NEAR(residual(batch, x), green_strain_norm(Eigen::Matrix<Real, 3, 3>(A)),
              kResidualTolerance);
  // A shear x += γ y: ‖E‖ = ½ γ sqrt(2 + γ²).
  Matrix3r shear = Matrix3r::Identity();
  shear(0, 1) = Real(0.3);
  EXPECT_NEAR(residual(batch, deformed(rest, shear, rest[0])),
              Real(0.15) * std::sqrt(Real(2.09)), kResidualTolerance);
  expect_rigid_invariance(batch, x);
  // Green strain does not see inversion: a mirrored tetrahedron reads 0.
  const Matrix3r mirror = Eigen::DiagonalMatrix<Real, 3>(-1, 1, 1).toDenseMatrix();
  EXPECT_NEAR(residual(batch, deformed(rest, mirror, rest[3])), 0, kResidualTolerance);
  EXPECT_NEAR(residual(batch, collapsed(4)), std::sqrt(Real(3)) / 2, kResidualTolerance);
  expect_finite_near_degenerate<4>(batch);
}

TEST(StrainTriangleResidual, GreenStrainNormInThePlane) {
  const std::vector<Vector3r> rest = rest_triangle_xy();
  expect_triangle_green_strain(make_strain_triangle_constraints({kFirstThree, rest}), rest);
}

TEST(StrainTriangleResidual, RestTriangleIsTakenInTheXyPlane) {
  // The family's convention (init_StrainTriangleConstraint ignores z): a tilted rest triangle
  // is stretched at its own rest positions, a rigid motion of its xy projection is not.
  const std::vector<Vector3r> rest = rest_triangle_tilted();
  const StrainTriangleConstraints batch = make_strain_triangle_constraints({kFirstThree, rest});
  EXPECT_GT(residual(batch, rest), Real(0.1));
  std::vector<Vector3r> projected = rest;
  for (Vector3r& p : projected) p.z() = 0;
  EXPECT_NEAR(residual(batch, projected), 0, kResidualTolerance);
}

TEST(StrainTetraResidual, GreenStrainNorm) {
  expect_tetra_green_strain(make_strain_tetra_constraints({kFirstFour, rest_tetrahedron()}));
}

TEST(FEMTriangleResidual, GreenStrainNormInTheTrianglesOwnPlane) {
  for (const auto& rest : {rest_triangle_xy(), rest_triangle_tilted()})
    expect_triangle_green_strain(make_fem_triangle_constraints({kFirstThree, rest}), rest);
}

TEST(FEMTetraResidual, GreenStrainNormWhateverTheMaterial) {
  const std::vector<Vector3r> rest = rest_tetrahedron();
  FEMTetraConstraintInput input{kFirstFour, rest};
  expect_tetra_green_strain(make_fem_tetra_constraints(input));
  input.youngs_modulus = 1000;
  input.poisson_ratio = Real(0.1);
  input.handle_inversion = false;
  expect_tetra_green_strain(make_fem_tetra_constraints(input));
}

// ---------------------------------------------------------------------------- shape matching
/// Two clusters: a jittered cube (particles 0..7) and a flat square of four (8..11).
struct ClusterScene {
  std::vector<Vector3r> rest;
  std::vector<Real> inverse_masses;
  std::vector<std::uint32_t> offsets = {0, 8, 12};
  std::vector<ParticleIndex> particles;
};

ClusterScene cluster_scene() {
  ClusterScene scene;
  Random random(11);
  for (int i = 0; i < 8; ++i)
    scene.rest.push_back(Vector3r(Real(i & 1), Real((i >> 1) & 1), Real((i >> 2) & 1)) +
                         Real(0.1) * random.vector() + Vector3r(2, -1, Real(0.5)));
  for (int i = 0; i < 4; ++i)
    scene.rest.push_back(Vector3r(Real(i & 1), Real((i >> 1) & 1), 0) * 2 +
                         Vector3r(-3, 0, 1));
  for (std::size_t i = 0; i < scene.rest.size(); ++i) {
    scene.particles.push_back(ParticleIndex(i));
    scene.inverse_masses.push_back(i == 3 ? Real(0) : random.uniform(Real(0.5), 2));
  }
  return scene;
}

ShapeMatchingConstraints build(const ClusterScene& scene, bool allow_stretch) {
  ShapeMatchingInput input{scene.offsets, scene.particles, scene.rest, scene.inverse_masses};
  input.allow_stretch = allow_stretch;
  return make_shape_matching_constraints(input);
}

/// The positions with cluster `first .. last` moved by x ↦ A (x − o) + o.
std::vector<Vector3r> with_cluster_deformed(std::vector<Vector3r> x, std::size_t first,
                                            std::size_t last, const Matrix3r& A,
                                            const Vector3r& o) {
  for (std::size_t i = first; i < last; ++i) x[i] = A * (x[i] - o) + o;
  return x;
}

TEST(ShapeMatchingResidual, GoalDistanceRelativeToTheClusterSize) {
  const ClusterScene scene = cluster_scene();
  const ShapeMatchingConstraints rigid = build(scene, false);
  for (std::size_t c = 0; c < 2; ++c) {
    SCOPED_TRACE(c);
    const std::size_t first = scene.offsets[c], last = scene.offsets[c + 1];
    EXPECT_NEAR(residual(rigid, scene.rest, c), 0, kResidualTolerance);
    // A rigid motion of the cluster alone leaves it satisfied.
    Random random(unsigned(c) + 1);
    const Matrix3r R = random.rotation();
    const Vector3r o = random.vector();
    EXPECT_NEAR(residual(rigid, with_cluster_deformed(scene.rest, first, last, R, o), c), 0,
                kResidualTolerance);
    // A uniform scaling by s (also rotated): the best rotation is R, every particle is
    // |s − 1| |q_i| from its goal, so the residual is |s − 1|.
    for (const Real s : {Real(1.2), Real(0.7)})
      EXPECT_NEAR(residual(rigid, with_cluster_deformed(scene.rest, first, last, s * R, o), c),
                  std::abs(s - 1), kResidualTolerance);
    // A cluster collapsed to one point is |q_i| from every goal: 1.
    std::vector<Vector3r> x = scene.rest;
    for (std::size_t i = first; i < last; ++i) x[i] = Vector3r(Real(0.3), Real(-0.2), Real(0.7));
    EXPECT_NEAR(residual(rigid, x, c), 1, kResidualTolerance);
  }
  // The other cluster is unaffected by a deformation of the first.
  const std::vector<Vector3r> first_scaled =
      with_cluster_deformed(scene.rest, 0, 8, Real(1.5) * Matrix3r::Identity(), scene.rest[0]);
  EXPECT_NEAR(residual(rigid, first_scaled, 0), Real(0.5), kResidualTolerance);
  EXPECT_NEAR(residual(rigid, first_scaled, 1), 0, kResidualTolerance);
}

TEST(ShapeMatchingResidual, WithStretchTheGoalIsTheBestLinearMap) {
  // A linear fit needs a cluster that is not flat: only the cube.
  ClusterScene cube = cluster_scene();
  cube.offsets = {0, 8};
  cube.particles.resize(8);
  const ShapeMatchingConstraints stretchy = build(cube, true);
  EXPECT_NEAR(residual(stretchy, cube.rest), 0, kResidualTolerance);
  // Any affine map is matched exactly.
  EXPECT_NEAR(residual(stretchy, deformed(cube.rest, general_deformation(), cube.rest[5])), 0,
              kResidualTolerance);
  // So is a collapse to one point (by the zero map): the goal is where the particles are.
  EXPECT_NEAR(residual(stretchy, collapsed(8)), 0, kResidualTolerance);
  // A change that no linear map makes is not: one corner of the cube moved.
  std::vector<Vector3r> x = cube.rest;
  x[0] += Vector3r(Real(0.2), Real(-0.1), Real(0.3));
  EXPECT_GT(residual(stretchy, x), Real(0.05));
}

TEST(ShapeMatchingResidual, RigidInvariantAndFinite) {
  const ClusterScene scene = cluster_scene();
  for (const bool allow_stretch : {false, true}) {
    ClusterScene cube = scene;
    cube.offsets = {0, 8};
    cube.particles.resize(8);
    const ShapeMatchingConstraints batch = build(cube, allow_stretch);
    Random random(9);
    std::vector<Vector3r> x = cube.rest;
    for (Vector3r& p : x) p += Real(0.2) * random.vector();  // not a linear map of the rest
    const Real r = residual(batch, x);
    EXPECT_GT(r, Real(0.05));
    expect_rigid_invariance(batch, x);
    expect_finite_near_degenerate<8>(batch);
  }
}

// ------------------------------------------------------------------- particle–tet contact
/// A unit tet (slots 1..4), the contact point on its bottom face z = 0 with the normal −z
/// (out of the tet), and the particle (slot 0) at height z over the contact point.
struct ContactScene {
  std::vector<Vector3r> positions;
  std::vector<Vector3r> barycentric = {Vector3r(Real(0.2), Real(0.2), 0)};
  std::vector<Vector3r> normals = {Vector3r(0, 0, -1)};
};

ContactScene contact_scene(Real z) {
  ContactScene scene;
  const Vector3r contact_point(Real(0.2), Real(0.2), 0);
  scene.positions = {contact_point + Vector3r(0, 0, z), Vector3r(0, 0, 0), Vector3r(1, 0, 0),
                     Vector3r(0, 1, 0), Vector3r(0, 0, 1)};
  return scene;
}

ParticleTetContacts build(const ContactScene& scene) {
  const std::vector<ParticleIndex> contact = {0, 1, 2, 3, 4};
  const ParticleState state(scene.positions, unit_masses(scene.positions.size()));
  return make_particle_tet_contacts({contact, scene.barycentric, scene.normals}, state);
}

TEST(ParticleTetContactResidual, PenetrationDepthInLengthUnits) {
  const ParticleTetContacts contacts = build(contact_scene(0));
  EXPECT_EQ(residual(contacts, contact_scene(0).positions), 0);
  // Outside (below the face, along the normal): satisfied.
  EXPECT_EQ(residual(contacts, contact_scene(Real(-0.1)).positions), 0);
  // Inside the tet by 0.15.
  EXPECT_NEAR(residual(contacts, contact_scene(Real(0.15)).positions), Real(0.15),
              kResidualTolerance);
  // Moving the tet away from the particle (the face up by 0.25) also penetrates.
  std::vector<Vector3r> x = contact_scene(0).positions;
  for (std::size_t i = 1; i < 5; ++i) x[i].z() -= Real(0.25);
  EXPECT_NEAR(residual(contacts, x), Real(0.25), kResidualTolerance);
  EXPECT_NEAR(residual(contacts, collapsed(5)), 0, kResidualTolerance);
  expect_finite_near_degenerate<5>(contacts);
}

TEST(ParticleTetContactResidual, RigidInvariantWithTheNormal) {
  // The normal is contact data: a rigid motion of the scene moves it too.
  const ContactScene scene = contact_scene(Real(0.3));
  const Real reference = residual(build(scene), scene.positions);
  EXPECT_NEAR(reference, Real(0.3), kResidualTolerance);
  Random random(4);
  for (int trial = 0; trial < 5; ++trial) {
    const Matrix3r R = random.rotation();
    ContactScene moved = scene;
    moved.positions = rigidly_moved(scene.positions, R, random.vector(-5, 5));
    moved.normals[0] = R * scene.normals[0];
    EXPECT_NEAR(residual(build(moved), moved.positions), reference, test::kRoundOff);
  }
}

// ------------------------------------------------------------------ batched: constraint_residuals
// constraint_residuals over a range agrees with constraint_residual constraint by constraint,
// on every SIMD target, and writes out[0, end − begin) and nothing else.

constexpr std::size_t kBatchedCount = 101;

/// The rest stencil of one N-particle constraint: a unit simplex (plus a fifth point inside
/// for contacts) with noise, translated; never degenerate. Not rotated, so the strain
/// triangle's xy-plane rest convention stays well-conditioned.
template <int N>
std::array<Vector3r, N> rest_stencil(Random& random) {
  static const Vector3r base[5] = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0),
                                   Vector3r(0, 0, 1), Vector3r(Real(0.3), Real(0.3), Real(0.3))};
  const Vector3r shift = random.vector(-5, 5);
  std::array<Vector3r, N> p;
  for (std::size_t k = 0; k < std::size_t(N); ++k)
    p[k] = base[k] + Real(0.15) * random.vector() + shift;
  return p;
}

/// A current configuration of a stencil: mostly a random affine map plus noise, sometimes
/// the rest shape, a rigid motion, one point, points on a line, points in a plane.
/// I + 0.4 B with B uniform in [−1, 1]³ˣ³ (drawn from `random`, so a scene is reproducible).
Matrix3r random_deformation(Random& random) {
  Matrix3r B;
  B << random.vector(), random.vector(), random.vector();
  return Matrix3r::Identity() + Real(0.4) * B;
}

enum class Deformation { rest, rigid, point, line, plane, general };

template <std::size_t N>
Deformation deform_stencil(Random& random, std::array<Vector3r, N>& p) {
  const int mode = random.integer(0, 9);
  const Vector3r origin = p[0];
  if (mode == 0) return Deformation::rest;
  if (mode == 1) {        // rigid motion
    const Matrix3r R = random.rotation();
    const Vector3r t = random.vector();
    for (Vector3r& x : p) x = R * (x - origin) + origin + t;
    return Deformation::rigid;
  }
  if (mode == 2) {
    const Vector3r at = origin + random.vector();
    for (Vector3r& x : p) x = at;
    return Deformation::point;
  }
  if (mode == 3) {
    const Vector3r direction = random.unit_vector();
    for (Vector3r& x : p) x = origin + random.uniform(-1, 1) * direction;
    return Deformation::line;
  }
  if (mode == 4) {
    for (Vector3r& x : p) x.z() = origin.z();
    return Deformation::plane;
  }
  const Matrix3r A = random_deformation(random);
  for (Vector3r& x : p) x = A * (x - origin) + origin + Real(0.1) * random.vector();
  return Deformation::general;
}

/// A batch of kBatchedCount N-particle constraints on a randomly numbered particle set: the
/// rest stencils, the indices (N per constraint) and the deformed current positions.
template <int N>
struct BatchedScene {
  std::vector<Vector3r> rest;
  std::vector<Vector3r> current;
  std::vector<ParticleIndex> indices;
  std::vector<Deformation> deformation;  // per constraint
};

template <int N>
BatchedScene<N> batched_scene(Random& random) {
  BatchedScene<N> scene;
  const std::size_t particle_count = kBatchedCount * N;
  std::vector<ParticleIndex> permutation(particle_count);
  std::iota(permutation.begin(), permutation.end(), ParticleIndex(0));
  for (std::size_t i = particle_count - 1; i > 0; --i)
    std::swap(permutation[i], permutation[std::size_t(random.integer(0, int(i)))]);
  scene.rest.assign(particle_count, Vector3r::Zero());
  scene.current.assign(particle_count, Vector3r::Zero());
  for (std::size_t c = 0; c < kBatchedCount; ++c) {
    const std::array<Vector3r, N> rest = rest_stencil<N>(random);
    std::array<Vector3r, N> current = rest;
    scene.deformation.push_back(deform_stencil(random, current));
    for (std::size_t k = 0; k < std::size_t(N); ++k) {
      const ParticleIndex index = permutation[c * N + k];
      scene.indices.push_back(index);
      scene.rest[index] = rest[k];
      scene.current[index] = current[k];
    }
  }
  return scene;
}

/// Checks constraint_residuals of `batch` at `current` over [0, size) and random sub-ranges
/// (empty, shorter than a vector, unaligned) on every SIMD target against the scalar function.
/// line_bound > 0: the family's value on points on a line is ill-conditioned (the dihedral
/// angle between two wing normals made of round-off), so there the batched value is only
/// checked to be finite and in [0, line_bound].
template <class Batch>
void expect_batched_residuals_match(const Batch& batch, const std::vector<Vector3r>& current,
                                    Random& random,
                                    const std::vector<Deformation>& deformations,
                                    Real line_bound = 0) {
  ParticleState state(current, unit_masses(current.size()));
  const ParticleArrays particles = ParticleArrays::of(state);
  const std::size_t n = batch.size();
  std::vector<Real> scalar(n);
  for (std::size_t c = 0; c < n; ++c) {
    scalar[c] = constraint_residual(particles, batch, c);
    ASSERT_TRUE(std::isfinite(scalar[c])) << "constraint " << c;
  }
  std::vector<std::array<std::size_t, 2>> ranges = {{0, n}, {0, 0}, {n, n}, {n - 1, n}};
  for (int r = 0; r < 8; ++r) {
    const std::size_t a = std::size_t(random.integer(0, int(n)));
    const std::size_t b = std::size_t(random.integer(0, int(n)));
    ranges.push_back({std::min(a, b), std::max(a, b)});
  }
  const std::size_t short_begin = std::size_t(random.integer(0, int(n) - 3));
  ranges.push_back({short_begin, short_begin + 3});
  constexpr Real kSentinel = Real(-12345.5);
  test::for_each_simd_target([&](const std::string&) {
    for (const auto& [begin, end] : ranges) {
      SCOPED_TRACE("range [" + std::to_string(begin) + ", " + std::to_string(end) + ")");
      // out[0, kMaxLanes) and everything past the range's end are guards.
      std::vector<Real> out(n + 2 * kMaxLanes, kSentinel);
      constraint_residuals(particles, batch, begin, end, out.data() + kMaxLanes);
      for (std::size_t k = 0; k < out.size(); ++k) {
        const bool inside = k >= kMaxLanes && k < kMaxLanes + (end - begin);
        if (!inside) {
          ASSERT_EQ(out[k], kSentinel) << "written outside the range at " << k;
          continue;
        }
        const std::size_t c = begin + k - kMaxLanes;
        if (line_bound > 0 && deformations[c] == Deformation::line) {
          ASSERT_TRUE(std::isfinite(out[k]) && out[k] >= 0 && out[k] <= line_bound)
              << "constraint " << c << " reads " << out[k];
          continue;
        }
        const Real expected = scalar[c];
        ASSERT_NEAR(out[k], expected,
                    test::kBatchTolerance * std::max(Real(1), std::abs(expected)))
            << "constraint " << c << " deformation " << int(deformations[c]);
      }
    }
  });
}

/// Builds batches of N-particle constraints with build(indices, rest, random) on a few random
/// scenes and checks each.
template <int N, class Build>
void expect_batched_family(unsigned seed, Build&& build, Real line_bound = 0) {
  for (unsigned scene_number = 0; scene_number < 4; ++scene_number) {
    SCOPED_TRACE("scene " + std::to_string(scene_number));
    Random random(seed + 1000 * scene_number);
    const BatchedScene<N> scene = batched_scene<N>(random);
    const auto batch = build(scene.indices, scene.rest, random);
    ASSERT_EQ(batch.size(), kBatchedCount);
    expect_batched_residuals_match(batch, scene.current, random, scene.deformation, line_bound);
  }
}

using Indices = std::vector<ParticleIndex>;
using Points = std::vector<Vector3r>;

TEST(BatchedResiduals, Distance) {
  expect_batched_family<2>(101, [](const Indices& i, const Points& rest, Random&) {
    return make_distance_constraints({i, rest});
  });
}

TEST(BatchedResiduals, Dihedral) {
  // On a line the wing normals are round-off: the angle is finite and ≤ π, nothing more.
  expect_batched_family<4>(
      102,
      [](const Indices& i, const Points& rest, Random&) {
        return make_dihedral_constraints({i, rest});
      },
      std::numbers::pi_v<Real>);
}

TEST(BatchedResiduals, Volume) {
  expect_batched_family<4>(103, [](const Indices& i, const Points& rest, Random&) {
    return make_volume_constraints({i, rest});
  });
}

TEST(BatchedResiduals, IsometricBending) {
  expect_batched_family<4>(104, [](const Indices& i, const Points& rest, Random&) {
    return make_isometric_bending_constraints({i, rest});
  });
}

/// Proximity constraints with random rest distances, a fifth of them 0.
ProximityDistanceConstraintInput batched_proximity_input(const Indices& i, const Points& rest,
                                                         Random& random,
                                                         std::vector<Real>& rest_distances,
                                                         std::size_t particles_per_constraint) {
  rest_distances.clear();
  for (std::size_t c = 0; c < i.size() / particles_per_constraint; ++c)
    rest_distances.push_back(random.uniform(0, 1) < Real(0.2) ? Real(0)
                                                              : random.uniform(Real(0.05), 1));
  ProximityDistanceConstraintInput input;
  input.particles = i;
  input.particle_count = rest.size();
  input.rest_distances = rest_distances;
  return input;
}

TEST(BatchedResiduals, EdgePointDistance) {
  expect_batched_family<3>(105, [](const Indices& i, const Points& rest, Random& random) {
    std::vector<Real> d;
    return make_edge_point_distance_constraints(batched_proximity_input(i, rest, random, d, 3));
  });
}

TEST(BatchedResiduals, TrianglePointDistance) {
  expect_batched_family<4>(106, [](const Indices& i, const Points& rest, Random& random) {
    std::vector<Real> d;
    return make_triangle_point_distance_constraints(
        batched_proximity_input(i, rest, random, d, 4));
  });
}

TEST(BatchedResiduals, EdgeEdgeDistance) {
  expect_batched_family<4>(107, [](const Indices& i, const Points& rest, Random& random) {
    std::vector<Real> d;
    return make_edge_edge_distance_constraints(batched_proximity_input(i, rest, random, d, 4));
  });
}

TEST(BatchedResiduals, StrainTriangle) {
  expect_batched_family<3>(108, [](const Indices& i, const Points& rest, Random&) {
    return make_strain_triangle_constraints({i, rest});
  });
}

TEST(BatchedResiduals, StrainTetra) {
  expect_batched_family<4>(109, [](const Indices& i, const Points& rest, Random&) {
    return make_strain_tetra_constraints({i, rest});
  });
}

TEST(BatchedResiduals, FEMTriangle) {
  expect_batched_family<3>(110, [](const Indices& i, const Points& rest, Random&) {
    return make_fem_triangle_constraints({i, rest});
  });
}

TEST(BatchedResiduals, FEMTetra) {
  for (const bool handle_inversion : {false, true})
    expect_batched_family<4>(111, [&](const Indices& i, const Points& rest, Random&) {
      FEMTetraConstraintInput input{i, rest};
      input.handle_inversion = handle_inversion;
      return make_fem_tetra_constraints(input);
    });
}

TEST(BatchedResiduals, ParticleTetContact) {
  Random random(112);
  const BatchedScene<5> scene = batched_scene<5>(random);
  std::vector<Vector3r> barycentric, normals;
  for (std::size_t c = 0; c < kBatchedCount; ++c) {
    const Real b1 = random.uniform(0, 1), b2 = random.uniform(0, 1 - b1);
    barycentric.push_back(Vector3r(b1, b2, random.uniform(0, 1 - b1 - b2)));
    normals.push_back(random.unit_vector());
  }
  const ParticleState rest_state(scene.rest, unit_masses(scene.rest.size()));
  const ParticleTetContacts contacts =
      make_particle_tet_contacts({scene.indices, barycentric, normals}, rest_state);
  // The contact particle (slot 0) moved anywhere near its tet: about half penetrate.
  std::vector<Vector3r> current = scene.current;
  for (std::size_t c = 0; c < kBatchedCount; ++c)
    current[scene.indices[5 * c]] = current[scene.indices[5 * c + 1]] + random.vector();
  expect_batched_residuals_match(contacts, current, random, scene.deformation);
}

TEST(BatchedResiduals, ColliderContact) {
  // One particle per contact (a random numbering), each against a random plane through a
  // point up to 1 away: about half penetrate.
  Random random(114);
  std::vector<Vector3r> current(kBatchedCount);
  std::vector<ParticleIndex> particles(kBatchedCount);
  std::iota(particles.begin(), particles.end(), ParticleIndex(0));
  for (std::size_t i = kBatchedCount - 1; i > 0; --i)
    std::swap(particles[i], particles[std::size_t(random.integer(0, int(i)))]);
  std::vector<Vector3r> normals, anchors;
  std::vector<Real> offsets, speeds(kBatchedCount, Real(0));
  for (std::size_t c = 0; c < kBatchedCount; ++c) {
    current[particles[c]] = random.vector(-5, 5);
    normals.push_back(random.unit_vector());
    offsets.push_back(normals.back().dot(current[particles[c]]) + random.uniform(-1, 1));
    anchors.push_back(current[particles[c]]);
  }
  const ColliderContacts contacts = make_collider_contacts(
      {particles, kBatchedCount, normals, offsets, anchors, speeds});
  expect_batched_residuals_match(contacts, current, random,
                                 std::vector<Deformation>(kBatchedCount, Deformation::general));
}

TEST(BatchedResiduals, ShapeMatching) {
  // Clusters of 4 to 12 particles over a random numbering, rigid and stretchy.
  Random random(113);
  std::vector<std::uint32_t> offsets = {0};
  for (std::size_t c = 0; c < kBatchedCount; ++c)
    offsets.push_back(offsets.back() + std::uint32_t(random.integer(4, 12)));
  const std::size_t particle_count = offsets.back();
  std::vector<ParticleIndex> particles(particle_count);
  std::iota(particles.begin(), particles.end(), ParticleIndex(0));
  for (std::size_t i = particle_count - 1; i > 0; --i)
    std::swap(particles[i], particles[std::size_t(random.integer(0, int(i)))]);
  std::vector<Vector3r> rest(particle_count), current(particle_count);
  std::vector<Deformation> deformations;
  for (std::size_t c = 0; c < kBatchedCount; ++c) {
    deformations.push_back(c % 7 == 3 ? Deformation::point : Deformation::general);
    const Matrix3r A = random_deformation(random);
    const Vector3r centre = random.vector(-5, 5);
    for (std::size_t e = offsets[c]; e < offsets[c + 1]; ++e) {
      // The first four entries a noisy unit simplex, so no rest cluster is flat.
      const std::size_t k = e - offsets[c];
      const Vector3r corner =
          k == 0 || k >= 4 ? Vector3r(Vector3r::Zero())
                           : Vector3r(Vector3r::Unit(Eigen::Index(k - 1)));
      rest[particles[e]] =
          centre + (k < 4 ? corner + Real(0.1) * random.vector() : random.vector());
      current[particles[e]] = c % 7 == 3 ? centre : A * (rest[particles[e]] - centre) + centre;
    }
  }
  const std::vector<Real> inverse_masses(particle_count, Real(1));
  for (const bool allow_stretch : {false, true}) {
    ShapeMatchingInput input{offsets, particles, rest, inverse_masses};
    input.allow_stretch = allow_stretch;
    expect_batched_residuals_match(make_shape_matching_constraints(input), current, random,
                                   deformations);
  }
}

}  // namespace constraint_residual_tests
}  // namespace tessera
