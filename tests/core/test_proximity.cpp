// Tests of the three proximity constraints (point–edge, point–triangle, edge–edge): closest
// points in every Voronoi region against independent reference distances, hand-checked
// corrections, momentum, static particles, rigid-motion invariance, the direction of the
// correction against a finite-difference gradient of the true distance, one-step
// satisfaction, compression/stretch stiffness selection and degenerate input.
#include <tessera/core/position_based_dynamics.hpp>

#include "test_support.hpp"

namespace tessera::test {
namespace proximity_tests {

template <std::size_t N>
using Points = std::array<Vector3r, N>;
template <std::size_t N>
using Masses = std::array<Real, N>;

template <std::size_t N>
using Projection = ScalarProjection<N>;

// The kernels under test, with the points in parameter order.
Projection<3> edge_point(const Points<3>& x, const Masses<3>& w, Real rest, Real compression,
                         Real stretch) {
  Projection<3> r;
  r.ok = PositionBasedDynamics::solve_EdgePointDistanceConstraint(
      x[0], w[0], x[1], w[1], x[2], w[2], rest, compression, stretch, r.corr[0], r.corr[1],
      r.corr[2]);
  return r;
}

Projection<4> triangle_point(const Points<4>& x, const Masses<4>& w, Real rest,
                             Real compression, Real stretch) {
  Projection<4> r;
  r.ok = PositionBasedDynamics::solve_TrianglePointDistanceConstraint(
      x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3], rest, compression, stretch, r.corr[0],
      r.corr[1], r.corr[2], r.corr[3]);
  return r;
}

Projection<4> edge_edge(const Points<4>& x, const Masses<4>& w, Real rest, Real compression,
                        Real stretch) {
  Projection<4> r;
  r.ok = PositionBasedDynamics::solve_EdgeEdgeDistanceConstraint(
      x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3], rest, compression, stretch, r.corr[0],
      r.corr[1], r.corr[2], r.corr[3]);
  return r;
}

// Reference distances, written independently of the kernels' region logic.
Real point_segment_distance(const Vector3r& p, const Vector3r& a, const Vector3r& b) {
  const Vector3r edge = b - a;
  if (edge.squaredNorm() == 0) return (p - a).norm();
  const Real t = std::clamp((p - a).dot(edge) / edge.squaredNorm(), Real(0), Real(1));
  return (p - (a + t * edge)).norm();
}

/// Plane distance when p projects inside the triangle, else the nearest edge.
Real point_triangle_distance(const Vector3r& p, const Vector3r& a, const Vector3r& b,
                             const Vector3r& c) {
  const Vector3r u = b - a, v = c - a, r = p - a;
  Matrix2r gram;
  gram << u.dot(u), u.dot(v), u.dot(v), v.dot(v);
  const Vector2r coords = gram.inverse() * Vector2r(u.dot(r), v.dot(r));
  Real best = std::min({point_segment_distance(p, a, b), point_segment_distance(p, b, c),
                        point_segment_distance(p, c, a)});
  if (coords[0] >= 0 && coords[1] >= 0 && coords[0] + coords[1] <= 1)
    best = std::min(best, (r - coords[0] * u - coords[1] * v).norm());
  return best;
}

/// The interior–interior stationary pair when it lies in [0, 1]², else an endpoint against
/// the other segment.
Real segment_segment_distance(const Vector3r& p0, const Vector3r& p1, const Vector3r& p2,
                              const Vector3r& p3) {
  Real best = std::min({point_segment_distance(p0, p2, p3), point_segment_distance(p1, p2, p3),
                        point_segment_distance(p2, p0, p1), point_segment_distance(p3, p0, p1)});
  const Vector3r d0 = p1 - p0, d1 = p3 - p2;
  Matrix2r normal_equations;
  normal_equations << d0.dot(d0), -d0.dot(d1), -d0.dot(d1), d1.dot(d1);
  if (std::abs(normal_equations.determinant()) > Real(1e-6) * d0.squaredNorm() * d1.squaredNorm()) {
    const Vector2r st =
        normal_equations.inverse() * Vector2r(-d0.dot(p0 - p2), d1.dot(p0 - p2));
    if (st[0] >= 0 && st[0] <= 1 && st[1] >= 0 && st[1] <= 1)
      best = std::min(best, ((p0 + st[0] * d0) - (p2 + st[1] * d1)).norm());
  }
  return best;
}

Real edge_point_distance(const Points<3>& x) { return point_segment_distance(x[0], x[1], x[2]); }
Real triangle_point_distance(const Points<4>& x) {
  return point_triangle_distance(x[0], x[1], x[2], x[3]);
}
Real edge_edge_distance(const Points<4>& x) {
  return segment_segment_distance(x[0], x[1], x[2], x[3]);
}

template <std::size_t N>
Masses<N> random_masses(Random& random) {
  Masses<N> w;
  for (Real& m : w) m = random.inverse_mass();
  return w;
}

/// A unit vector perpendicular to `direction`.
Vector3r random_perpendicular(Random& random, const Vector3r& direction) {
  for (;;) {
    const Vector3r v = random.unit_vector();
    const Vector3r perpendicular = v - v.dot(direction) / direction.squaredNorm() * direction;
    if (perpendicular.norm() > Real(0.3)) return perpendicular.normalized();
  }
}

// ---- Random inputs built inside one Voronoi region, so the distance is smooth there ----

/// Point–edge: p near the interior (region 0) or beyond an endpoint (regions 1, 2).
Points<3> random_edge_point(Random& random, int region) {
  const Vector3r a = random.vector(), b = a + random.unit_vector() * random.uniform(0.5, 2);
  const Vector3r edge = b - a;
  Vector3r p;
  if (region == 0) {
    p = a + random.uniform(0.15, 0.85) * edge +
        random.uniform(0.2, 1) * random_perpendicular(random, edge);
  } else {
    // Beyond an endpoint, at least 0.2 |edge| past it along the edge.
    const Vector3r outward = (region == 1 ? -edge : edge).normalized();
    const Vector3r end = region == 1 ? a : b;
    p = end + random.uniform(0.2, 1) * outward +
        random.uniform(0, 1) * random_perpendicular(random, edge);
  }
  return {p, a, b};
}

/// Point–triangle: p above the face (region 0), outside an edge (1) or at a vertex (2).
Points<4> random_triangle_point(Random& random, int region) {
  Points<4> x;
  for (;;) {
    x = {Vector3r::Zero(), random.vector(), random.vector(), random.vector()};
    if ((x[2] - x[1]).cross(x[3] - x[1]).norm() > Real(0.3)) break;
  }
  const Vector3r a = x[1], b = x[2], c = x[3];
  const Vector3r normal = (b - a).cross(c - a).normalized();
  if (region == 0) {
    Real b0, b1;
    do {
      b0 = random.uniform(0.1, 0.8);
      b1 = random.uniform(0.1, 0.8);
    } while (b0 + b1 > Real(0.9));
    x[0] = b0 * a + b1 * b + (1 - b0 - b1) * c + random.uniform(0.2, 1) * normal *
                                                     (random.integer(0, 1) ? 1 : -1);
  } else if (region == 1) {
    // Outside edge ab: perpendicular to the edge, with an outward in-plane component.
    const Vector3r edge = b - a;
    Vector3r outward = normal.cross(edge).normalized();
    if (outward.dot(c - a) > 0) outward = -outward;
    const Real angle = random.uniform(-1.2, 1.2);
    x[0] = a + random.uniform(0.15, 0.85) * edge +
           random.uniform(0.2, 1) * (std::cos(angle) * outward + std::sin(angle) * normal);
  } else {
    // In the normal cone of vertex a: away from both of its edges.
    Vector3r direction;
    do direction = random.unit_vector();
    while (!(direction.dot((b - a).normalized()) < -0.2 &&
             direction.dot((c - a).normalized()) < -0.2));
    x[0] = a + random.uniform(0.2, 1) * direction;
  }
  return x;
}

/// Edge–edge: closest points interior to both (region 0) or endpoint p1 of the first edge
/// against the interior of the second (region 1).
Points<4> random_edge_edge(Random& random, int region) {
  const Vector3r d1 = random.unit_vector();
  const Vector3r n = random_perpendicular(random, d1);
  const Vector3r foot = random.vector();
  const Real l1 = random.uniform(0.5, 2);
  const Real t = random.uniform(0.15, 0.85);
  const Vector3r p2 = foot - t * l1 * d1, p3 = foot + (1 - t) * l1 * d1;
  const Real gap = random.uniform(0.2, 1);
  const Vector3r a = foot + gap * n;
  if (region == 0) {
    // The first edge lies in the plane through a perpendicular to n, crossing d1.
    Vector3r d0 = random_perpendicular(random, n);
    if (std::abs(d0.dot(d1)) > Real(0.8)) d0 = n.cross(d1);
    const Real l0 = random.uniform(0.5, 2);
    const Real s = random.uniform(0.15, 0.85);
    return {a - s * l0 * d0, a + (1 - s) * l0 * d0, p2, p3};
  }
  Vector3r away;
  do away = random.unit_vector();
  while (!(away.dot(n) > Real(0.3)));
  return {a + random.uniform(0.5, 2) * away, a, p2, p3};
}

/// Momentum, static particles, rigid motion and the direction of the correction against the
/// finite-difference gradient of the reference distance.
template <std::size_t N, class Solve, class Distance>
void check_invariants(const Points<N>& x, const Masses<N>& w, Real rest, Solve solve,
                      Distance distance, Random& random) {
  const Real stiffness = random.uniform(Real(0.2), Real(1));
  const Projection<N> r = solve(x, w, rest, stiffness, stiffness);
  ASSERT_TRUE(r.ok);
  ASSERT_TRUE(all_finite(r.corr));
  EXPECT_TRUE(conserves_linear_momentum(r.corr, w));
  EXPECT_TRUE(conserves_angular_momentum(x, r.corr, w));

  expect_pbd_step(distance, x, w, r.corr, distance(x) - rest, stiffness);

  const Matrix3r R = random.rotation();
  const Vector3r t = random.vector(-5, 5);
  const Points<N> y = transformed(x, R, t);
  EXPECT_NEAR(distance(y), distance(x), 50 * kRoundOff);
  const Projection<N> moved = solve(y, w, rest, stiffness, stiffness);
  ASSERT_TRUE(moved.ok);
  for (std::size_t i = 0; i < N; ++i)
    EXPECT_TRUE(near_relative(moved.corr[i], R * r.corr[i], 100 * kRoundOff));

  for (std::size_t fixed = 0; fixed < N; ++fixed) {
    Masses<N> w_fixed = w;
    w_fixed[fixed] = 0;
    const Projection<N> anchored = solve(x, w_fixed, rest, stiffness, stiffness);
    ASSERT_TRUE(anchored.ok);
    EXPECT_EQ(anchored.corr[fixed], Vector3r::Zero());
  }
}

/// Correction with (compression, stretch) = (0.3, 0.9) is 0.3 or 0.9 times the stiffness-1
/// correction, by the sign of C.
template <std::size_t N, class Solve>
void check_stiffness_selection(const Points<N>& x, const Masses<N>& w, Real distance,
                               Solve solve) {
  for (const Real rest : {distance * Real(1.5), distance * Real(0.5)}) {
    const Real expected_stiffness = rest > distance ? Real(0.3) : Real(0.9);
    const Projection<N> full = solve(x, w, rest, 1, 1);
    const Projection<N> selected = solve(x, w, rest, Real(0.3), Real(0.9));
    ASSERT_TRUE(full.ok && selected.ok);
    for (std::size_t i = 0; i < N; ++i)
      EXPECT_TRUE(near_relative(selected.corr[i], expected_stiffness * full.corr[i]))
          << "rest " << rest;
  }
}

// ------------------------------------------------------------------------ point–edge ----

TEST(EdgePointDistanceConstraint, HandCheckedInteriorProjection) {
  // Edge (0,0,0)-(2,0,0), p = (0.5, 1, 0): t = 1/4, n = e_y, C = 1 - 0.5. ∇ = (n, -¾n, -¼n),
  // Σ w|∇|² = 1 + 9/16 + 1/16 = 13/8, s = 0.5 / (13/8) = 4/13.
  const Points<3> x = {Vector3r(0.5, 1, 0), Vector3r(0, 0, 0), Vector3r(2, 0, 0)};
  const Projection<3> r = edge_point(x, {1, 1, 1}, Real(0.5), Real(0.1), 1);
  ASSERT_TRUE(r.ok);
  const Real s = Real(4) / 13;
  EXPECT_TRUE(near_relative(r.corr[0], Vector3r(0, -s, 0)));
  EXPECT_TRUE(near_relative(r.corr[1], Vector3r(0, Real(0.75) * s, 0)));
  EXPECT_TRUE(near_relative(r.corr[2], Vector3r(0, Real(0.25) * s, 0)));
}

TEST(EdgePointDistanceConstraint, HandCheckedEndpointRegion) {
  // p beyond p1: closest point p1 (t = 1), n = (1, 0, 0), C = 1 - 2 = -1 (compression).
  const Points<3> x = {Vector3r(3, 0, 0), Vector3r(0, 0, 0), Vector3r(2, 0, 0)};
  const Projection<3> r = edge_point(x, {1, 1, 1}, 2, Real(0.5), 1);
  ASSERT_TRUE(r.ok);
  // s = 0.5 · (-1) / 2: p moves +0.25 along x, p1 -0.25, p0 untouched.
  EXPECT_TRUE(near_relative(r.corr[0], Vector3r(0.25, 0, 0)));
  EXPECT_EQ(r.corr[1], Vector3r::Zero());
  EXPECT_TRUE(near_relative(r.corr[2], Vector3r(-0.25, 0, 0)));
}

TEST(EdgePointDistanceConstraint, InvariantsOnRandomInput) {
  Random random(401);
  for (int trial = 0; trial < 18; ++trial) {
    const Points<3> x = random_edge_point(random, trial % 3);
    check_invariants<3>(x, random_masses<3>(random), random.uniform(0, 1), edge_point,
                        edge_point_distance, random);
  }
}

TEST(EdgePointDistanceConstraint, StiffnessOneSatisfiesTheConstraintInOneStep) {
  Random random(402);
  for (int trial = 0; trial < 18; ++trial) {
    const Points<3> x = random_edge_point(random, trial % 3);
    const Real rest = random.uniform(0, 1);
    // Static edge: only the point moves, along n, keeping its closest point.
    const Projection<3> r = edge_point(x, {random.inverse_mass(), 0, 0}, rest, 1, 1);
    ASSERT_TRUE(r.ok);
    EXPECT_NEAR(edge_point_distance(applied(x, r.corr)), rest, 10 * kRoundOff);
  }
  for (int trial = 0; trial < 6; ++trial) {
    // Closest point at the middle of the edge, equal edge masses: the edge translates.
    const Vector3r a(-1, 0, 0), b(1, 0, 0);
    const Points<3> x = {Vector3r(0, random.uniform(0.2, 2), random.uniform(-1, 1)), a, b};
    const Real w_edge = random.inverse_mass();
    const Projection<3> r = edge_point(x, {random.inverse_mass(), w_edge, w_edge}, Real(0.5), 1, 1);
    ASSERT_TRUE(r.ok);
    EXPECT_TRUE(near_relative(r.corr[1], r.corr[2]));
    EXPECT_NEAR(edge_point_distance(applied(x, r.corr)), Real(0.5), 10 * kRoundOff);
  }
}

TEST(EdgePointDistanceConstraint, CompressionAndStretchStiffnessSelection) {
  Random random(403);
  for (int region = 0; region < 3; ++region) {
    const Points<3> x = random_edge_point(random, region);
    check_stiffness_selection<3>(x, random_masses<3>(random), edge_point_distance(x),
                                 edge_point);
  }
}

TEST(EdgePointDistanceConstraint, DegenerateInput) {
  const Vector3r a(0, 0, 0), b(2, 0, 0);
  Points<3> corr;
  const auto solve = [&](const Points<3>& x, const Masses<3>& w, Real rest) {
    corr.fill(Vector3r::Constant(7));
    return PositionBasedDynamics::solve_EdgePointDistanceConstraint(
        x[0], w[0], x[1], w[1], x[2], w[2], rest, 1, 1, corr[0], corr[1], corr[2]);
  };
  const auto all_zero = [&] { return max_norm(corr) == 0; };
  EXPECT_FALSE(solve({Vector3r(0.5, 0, 0), a, b}, {1, 1, 1}, Real(0.1)));  // p on the edge
  EXPECT_TRUE(all_zero());
  EXPECT_FALSE(solve({b, a, b}, {1, 1, 1}, Real(0.1)));  // p on an endpoint
  EXPECT_TRUE(all_zero());
  EXPECT_FALSE(solve({a, a, a}, {1, 1, 1}, Real(0.1)));  // zero-length edge, p on it
  EXPECT_TRUE(all_zero());
  EXPECT_FALSE(solve({Vector3r(0, 1, 0), a, b}, {0, 0, 0}, Real(0.1)));  // all static
  EXPECT_TRUE(all_zero());
  // A zero-length edge away from p acts as the point p0 (t = 0): point–point distance.
  ASSERT_TRUE(solve({Vector3r(0, 1, 0), a, a}, {1, 1, 1}, Real(0.5)));
  EXPECT_TRUE(all_finite(corr));
  EXPECT_EQ(corr[2], Vector3r::Zero());
  EXPECT_NEAR(((Vector3r(0, 1, 0) + corr[0]) - (a + corr[1])).norm(), 0.5, 10 * kRoundOff);
  // Zero rest distance: pulls p onto the edge.
  ASSERT_TRUE(solve({Vector3r(1, 1, 0), a, b}, {1, 0, 0}, 0));
  EXPECT_TRUE(near_relative(Vector3r(1, 1, 0) + corr[0], Vector3r(1, 0, 0)));
}

// -------------------------------------------------------------------- point–triangle ----

TEST(TrianglePointDistanceConstraint, HandCheckedFaceRegion) {
  // Triangle (0,0,0), (1,0,0), (0,1,0); p = (0.25, 0.25, 1): b = (½, ¼, ¼), n = e_z, C = ½.
  // Σ w|∇|² = 1 + ¼ + 1/16 + 1/16 = 11/8, s = ½ / (11/8) = 4/11.
  const Points<4> x = {Vector3r(0.25, 0.25, 1), Vector3r(0, 0, 0), Vector3r(1, 0, 0),
                       Vector3r(0, 1, 0)};
  const Projection<4> r = triangle_point(x, {1, 1, 1, 1}, Real(0.5), Real(0.2), 1);
  ASSERT_TRUE(r.ok);
  const Real s = Real(4) / 11;
  EXPECT_TRUE(near_relative(r.corr[0], Vector3r(0, 0, -s)));
  EXPECT_TRUE(near_relative(r.corr[1], Vector3r(0, 0, Real(0.5) * s)));
  EXPECT_TRUE(near_relative(r.corr[2], Vector3r(0, 0, Real(0.25) * s)));
  EXPECT_TRUE(near_relative(r.corr[3], Vector3r(0, 0, Real(0.25) * s)));
}

TEST(TrianglePointDistanceConstraint, HandCheckedEdgeAndVertexRegions) {
  const Vector3r a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  // Below edge ab at its middle: b = (½, ½, 0), n = -e_y, C = 1 - 2 = -1, static triangle.
  Projection<4> r = triangle_point({Vector3r(0.5, -1, 0), a, b, c}, {1, 0, 0, 0}, 2, 1, 1);
  ASSERT_TRUE(r.ok);
  EXPECT_TRUE(near_relative(r.corr[0], Vector3r(0, -1, 0)));
  // Outside edge bc (the hypotenuse) at its middle, above the plane.
  const Vector3r mid(0.5, 0.5, 0);
  const Vector3r away = Vector3r(1, 1, 0).normalized() + Vector3r(0, 0, 1);
  r = triangle_point({mid + away, a, b, c}, {1, 1, 1, 1}, 0, 1, 1);
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.corr[1], Vector3r::Zero());  // b_a = 0
  EXPECT_TRUE(near_relative(r.corr[2], r.corr[3]));
  // Beyond vertex c: b = (0, 0, 1); only p and c move.
  r = triangle_point({Vector3r(-0.5, 2, 0.5), a, b, c}, {1, 1, 1, 1}, Real(0.1), 1, 1);
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.corr[1], Vector3r::Zero());
  EXPECT_EQ(r.corr[2], Vector3r::Zero());
  EXPECT_TRUE(near_relative(r.corr[0], -r.corr[3]));
  EXPECT_TRUE(near_relative(r.corr[0].normalized(), -Vector3r(-0.5, 1, 0.5).normalized()));
}

TEST(TrianglePointDistanceConstraint, InvariantsOnRandomInput) {
  Random random(411);
  for (int trial = 0; trial < 18; ++trial) {
    const Points<4> x = random_triangle_point(random, trial % 3);
    check_invariants<4>(x, random_masses<4>(random), random.uniform(0, 1), triangle_point,
                        triangle_point_distance, random);
  }
}

TEST(TrianglePointDistanceConstraint, StiffnessOneSatisfiesTheConstraintInOneStep) {
  Random random(412);
  for (int trial = 0; trial < 18; ++trial) {
    const Points<4> x = random_triangle_point(random, trial % 3);
    const Real rest = random.uniform(0, 1);
    const Projection<4> r = triangle_point(x, {random.inverse_mass(), 0, 0, 0}, rest, 1, 1);
    ASSERT_TRUE(r.ok);
    EXPECT_NEAR(triangle_point_distance(applied(x, r.corr)), rest, 10 * kRoundOff);
  }
  for (int trial = 0; trial < 6; ++trial) {
    // p above the centroid, equal triangle masses: the triangle translates rigidly.
    Points<4> x = random_triangle_point(random, 0);
    const Vector3r centroid = (x[1] + x[2] + x[3]) / 3;
    const Vector3r normal = (x[2] - x[1]).cross(x[3] - x[1]).normalized();
    x[0] = centroid + random.uniform(0.2, 1) * normal;
    const Real w = random.inverse_mass();
    const Projection<4> r = triangle_point(x, {random.inverse_mass(), w, w, w}, Real(0.4), 1, 1);
    ASSERT_TRUE(r.ok);
    EXPECT_TRUE(near_relative(r.corr[1], r.corr[3]));
    EXPECT_NEAR(triangle_point_distance(applied(x, r.corr)), Real(0.4), 10 * kRoundOff);
  }
}

TEST(TrianglePointDistanceConstraint, CompressionAndStretchStiffnessSelection) {
  Random random(413);
  for (int region = 0; region < 3; ++region) {
    const Points<4> x = random_triangle_point(random, region);
    check_stiffness_selection<4>(x, random_masses<4>(random), triangle_point_distance(x),
                                 triangle_point);
  }
}

TEST(TrianglePointDistanceConstraint, DegenerateInput) {
  const Vector3r a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  Points<4> corr;
  const auto solve = [&](const Points<4>& x, const Masses<4>& w, Real rest) {
    corr.fill(Vector3r::Constant(7));
    return PositionBasedDynamics::solve_TrianglePointDistanceConstraint(
        x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3], rest, 1, 1, corr[0], corr[1], corr[2],
        corr[3]);
  };
  EXPECT_FALSE(solve({Vector3r(0.2, 0.3, 0), a, b, c}, {1, 1, 1, 1}, Real(0.1)));  // on face
  EXPECT_EQ(max_norm(corr), 0);
  EXPECT_FALSE(solve({Vector3r(0.5, 0, 0), a, b, c}, {1, 1, 1, 1}, Real(0.1)));  // on an edge
  EXPECT_EQ(max_norm(corr), 0);
  EXPECT_FALSE(solve({Vector3r(0, 1, 1), a, b, c}, {0, 0, 0, 0}, Real(0.1)));  // all static
  EXPECT_EQ(max_norm(corr), 0);
  // Zero-area (collinear) triangle: measured to its edges; p on it is degenerate.
  const Vector3r mid(0.5, 0, 0);
  EXPECT_FALSE(solve({Vector3r(0.25, 0, 0), a, mid, b}, {1, 1, 1, 1}, Real(0.1)));
  EXPECT_EQ(max_norm(corr), 0);
  ASSERT_TRUE(solve({Vector3r(0.75, 1, 0), a, mid, b}, {1, 0, 0, 0}, Real(0.5)));
  EXPECT_TRUE(near_relative(Vector3r(0.75, 1, 0) + corr[0], Vector3r(0.75, 0.5, 0)));
  // Every vertex at one point: a point–point distance.
  ASSERT_TRUE(solve({Vector3r(0, 0, 2), a, a, a}, {1, 0, 0, 0}, Real(0.5)));
  EXPECT_TRUE(near_relative(corr[0], Vector3r(0, 0, -1.5)));
}

// ------------------------------------------------------------------------- edge–edge ----

TEST(EdgeEdgeDistanceConstraint, HandCheckedCrossingEdges) {
  // (0,0,0)-(2,0,0) under (1,-1,1)-(1,1,1): s = t = ½, n = -e_z, C = 1 - ½. Every gradient is
  // ±½ n, Σ w|∇|² = 1, s = ½: the first edge moves +¼ e_z, the second -¼ e_z.
  const Points<4> x = {Vector3r(0, 0, 0), Vector3r(2, 0, 0), Vector3r(1, -1, 1),
                       Vector3r(1, 1, 1)};
  const Projection<4> r = edge_edge(x, {1, 1, 1, 1}, Real(0.5), Real(0.3), 1);
  ASSERT_TRUE(r.ok);
  EXPECT_TRUE(near_relative(r.corr[0], Vector3r(0, 0, 0.25)));
  EXPECT_TRUE(near_relative(r.corr[1], Vector3r(0, 0, 0.25)));
  EXPECT_TRUE(near_relative(r.corr[2], Vector3r(0, 0, -0.25)));
  EXPECT_TRUE(near_relative(r.corr[3], Vector3r(0, 0, -0.25)));
  EXPECT_NEAR(edge_edge_distance(applied(x, r.corr)), 0.5, 10 * kRoundOff);
}

TEST(EdgeEdgeDistanceConstraint, ParallelAndCollinearSegments) {
  // Parallel, overlapping on [0.5, 1]: any closest pair of the overlap is fine.
  Points<4> x = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0.5, 1, 0), Vector3r(1.5, 1, 0)};
  Projection<4> r = edge_edge(x, {1, 1, 1, 1}, 2, 1, 1);
  ASSERT_TRUE(r.ok);
  ASSERT_TRUE(all_finite(r.corr));
  EXPECT_TRUE(conserves_linear_momentum(r.corr, Masses<4>{1, 1, 1, 1}));
  // Static second edge and equal masses on the first: the first edge translates to distance 2.
  r = edge_edge(x, {1, 1, 0, 0}, 2, 1, 1);
  ASSERT_TRUE(r.ok);
  EXPECT_NEAR(edge_edge_distance(applied(x, r.corr)), 2, 10 * kRoundOff);
  EXPECT_TRUE(near_relative(r.corr[0] + r.corr[1], Vector3r(0, -2, 0)));
  // Parallel and disjoint along the line direction: endpoint to endpoint.
  x = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(3, 0, 0), Vector3r(4, 0, 0)};
  r = edge_edge(x, {1, 1, 1, 1}, Real(2.5), 1, 1);
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.corr[0], Vector3r::Zero());
  EXPECT_EQ(r.corr[3], Vector3r::Zero());
  EXPECT_TRUE(near_relative(r.corr[1], Vector3r(-0.25, 0, 0)));
  EXPECT_TRUE(near_relative(r.corr[2], Vector3r(0.25, 0, 0)));
}

TEST(EdgeEdgeDistanceConstraint, InvariantsOnRandomInput) {
  Random random(421);
  for (int trial = 0; trial < 16; ++trial) {
    const Points<4> x = random_edge_edge(random, trial % 2);
    check_invariants<4>(x, random_masses<4>(random), random.uniform(0, 1), edge_edge,
                        edge_edge_distance, random);
  }
}

TEST(EdgeEdgeDistanceConstraint, StiffnessOneSatisfiesTheConstraintInOneStep) {
  Random random(422);
  for (int trial = 0; trial < 16; ++trial) {
    const Points<4> x = random_edge_edge(random, trial % 2);
    const Real rest = random.uniform(0, 1);
    // Static second edge. The first edge's endpoints move by (1 - s) w0 and s w1 along n, a
    // translation when w0 = s and w1 = 1 - s. Region 1 has s = 1: only p1 moves.
    Masses<4> w = {1, 1, 0, 0};
    const bool interior = trial % 2 == 0;
    if (interior) {
      const Vector3r d0 = x[1] - x[0], d1 = x[3] - x[2];
      Matrix2r normal_equations;
      normal_equations << d0.dot(d0), -d0.dot(d1), -d0.dot(d1), d1.dot(d1);
      const Vector2r st =
          normal_equations.inverse() * Vector2r(-d0.dot(x[0] - x[2]), d1.dot(x[0] - x[2]));
      w = {st[0], 1 - st[0], 0, 0};
    }
    const Projection<4> r = edge_edge(x, w, rest, 1, 1);
    ASSERT_TRUE(r.ok);
    if (interior) {
      EXPECT_TRUE(near_relative(r.corr[0], r.corr[1]));
    }
    EXPECT_NEAR(edge_edge_distance(applied(x, r.corr)), rest, 10 * kRoundOff);
  }
}

TEST(EdgeEdgeDistanceConstraint, CompressionAndStretchStiffnessSelection) {
  Random random(423);
  for (int region = 0; region < 2; ++region) {
    const Points<4> x = random_edge_edge(random, region);
    check_stiffness_selection<4>(x, random_masses<4>(random), edge_edge_distance(x), edge_edge);
  }
}

TEST(EdgeEdgeDistanceConstraint, DegenerateInput) {
  Points<4> corr;
  const auto solve = [&](const Points<4>& x, const Masses<4>& w, Real rest) {
    corr.fill(Vector3r::Constant(7));
    return PositionBasedDynamics::solve_EdgeEdgeDistanceConstraint(
        x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3], rest, 1, 1, corr[0], corr[1], corr[2],
        corr[3]);
  };
  const Vector3r a(0, 0, 0), b(2, 0, 0);
  // Crossing (touching) segments.
  EXPECT_FALSE(solve({a, b, Vector3r(1, -1, 0), Vector3r(1, 1, 0)}, {1, 1, 1, 1}, Real(0.1)));
  EXPECT_EQ(max_norm(corr), 0);
  // Overlapping collinear segments.
  EXPECT_FALSE(solve({a, b, Vector3r(1, 0, 0), Vector3r(3, 0, 0)}, {1, 1, 1, 1}, Real(0.1)));
  EXPECT_EQ(max_norm(corr), 0);
  // Shared endpoint.
  EXPECT_FALSE(solve({a, b, b, Vector3r(2, 1, 0)}, {1, 1, 1, 1}, Real(0.1)));
  EXPECT_EQ(max_norm(corr), 0);
  // All static.
  EXPECT_FALSE(solve({a, b, Vector3r(1, -1, 1), Vector3r(1, 1, 1)}, {0, 0, 0, 0}, Real(0.1)));
  EXPECT_EQ(max_norm(corr), 0);
  // Both segments of zero length: point–point distance between p0 and p2 (s = t = 0).
  ASSERT_TRUE(solve({a, a, Vector3r(0, 0, 1), Vector3r(0, 0, 1)}, {1, 1, 0, 0}, 2));
  EXPECT_TRUE(near_relative(corr[0], Vector3r(0, 0, -1)));
  EXPECT_EQ(corr[1], Vector3r::Zero());
  // One segment of zero length: point–segment distance.
  ASSERT_TRUE(solve({Vector3r(1, 1, 0), Vector3r(1, 1, 0), a, b}, {1, 1, 0, 0}, Real(0.5)));
  EXPECT_TRUE(near_relative(corr[0], Vector3r(0, -0.5, 0)));
  ASSERT_TRUE(solve({a, b, Vector3r(1, 1, 0), Vector3r(1, 1, 0)}, {0, 0, 1, 1}, Real(0.5)));
  EXPECT_TRUE(near_relative(corr[2], Vector3r(0, -0.5, 0)));
}

TEST(ProximityConstraints, NearDegenerateInputStaysFinite) {
  Random random(431);
  for (int trial = 0; trial < 600; ++trial) {
    const Real scale = kNearDegenerateScales[trial % kNearDegenerateScales.size()];
    const int pattern = (trial / 6) % 3;
    const Real rest = random.uniform(0, 1);
    const Points<3> x3 = near_degenerate_points<3>(random, pattern, scale);
    const Projection<3> ep = edge_point(x3, masses_with_static<3>(random), rest, 1, 1);
    EXPECT_TRUE(finite_or_rejected(ep.ok, ep.corr)) << "scale " << scale;
    const Points<4> x4 = near_degenerate_points<4>(random, pattern, scale);
    const Masses<4> w4 = masses_with_static<4>(random);
    const Projection<4> tp = triangle_point(x4, w4, rest, 1, 1);
    EXPECT_TRUE(finite_or_rejected(tp.ok, tp.corr)) << "scale " << scale;
    const Projection<4> ee = edge_edge(x4, w4, rest, 1, 1);
    EXPECT_TRUE(finite_or_rejected(ee.ok, ee.corr)) << "scale " << scale;
    // A thin sliver triangle, static, and a movable point: one step puts the point at the
    // rest distance, up to the sliver's width (a sliver too thin for face coordinates is
    // measured to its edges).
    const Real apex = random.uniform(0, 1);
    const Points<4> sliver = {
        Vector3r(apex, random.uniform(0, 1) * scale, random.uniform(-1, 1)) +
            (trial % 2 ? Vector3r::Zero() : random.vector()),  // over the face, or anywhere
        Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(apex, scale, 0)};
    const Projection<4> thin = triangle_point(sliver, {1, 0, 0, 0}, rest, 1, 1);
    EXPECT_TRUE(finite_or_rejected(thin.ok, thin.corr)) << "scale " << scale;
    if (thin.ok) {
      EXPECT_NEAR(triangle_point_distance(applied(sliver, thin.corr)), rest,
                  2 * scale + 100 * kRoundOff)
          << "scale " << scale;
    }
  }
}

}  // namespace proximity_tests
}  // namespace tessera::test
