// The batched proximity kernels (point–edge, point–triangle, edge–edge) against the scalar
// API, on every SIMD target the machine has. The random constraints mix every Voronoi region
// with the degenerate conventions (zero-length segments, collinear and sliver triangles,
// parallel and collinear segments, coincident points), and each constraint has its own rest
// distance and compression/stretch stiffness, so a vector holds lanes that take different
// regions, different stiffnesses and no correction at all side by side. Plus the validation
// of the batch input.
#include <tessera/core/proximity_distance_constraints.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/position_based_dynamics.hpp>

#include "batch_test_support.hpp"

namespace tessera {
namespace proximity_batch_tests {

using test::Random;

template <int N>
using Points = std::array<Vector3r, N>;

/// A direction perpendicular to v (not normalised to anything in particular, but not short).
Vector3r perpendicular_to(Random& random, const Vector3r& v) {
  for (;;) {
    const Vector3r u = random.unit_vector();
    const Vector3r p = u - u.dot(v) / v.squaredNorm() * v;
    if (p.norm() > Real(0.3)) return p.normalized();
  }
}

// Reference distances between the primitives, written independently of the kernels' region
// logic: the minimum over candidate closest points.
Real point_segment_distance(const Vector3r& p, const Vector3r& a, const Vector3r& b) {
  const Vector3r edge = b - a;
  if (edge.squaredNorm() == 0) return (p - a).norm();
  const Real t = std::clamp((p - a).dot(edge) / edge.squaredNorm(), Real(0), Real(1));
  return (p - (a + t * edge)).norm();
}

/// The nearest edge, or the plane where p projects inside a triangle that is not a sliver.
Real point_triangle_distance(const Vector3r& p, const Vector3r& a, const Vector3r& b,
                             const Vector3r& c) {
  Real best = std::min({point_segment_distance(p, a, b), point_segment_distance(p, b, c),
                        point_segment_distance(p, c, a)});
  const Vector3r u = b - a, v = c - a, normal = u.cross(v);
  if (normal.norm() > Real(0.1) * u.norm() * v.norm()) {
    const Vector3r r = p - a;
    const Real along_v = r.cross(u).dot(-normal) / normal.squaredNorm();
    const Real along_u = v.cross(r).dot(-normal) / normal.squaredNorm();
    if (along_u >= 0 && along_v >= 0 && along_u + along_v <= 1)
      best = std::min(best, std::abs(r.dot(normal)) / normal.norm());
  }
  return best;
}

/// Endpoints against the other segment, or the stationary interior pair of crossing lines.
Real segment_segment_distance(const Vector3r& p0, const Vector3r& p1, const Vector3r& p2,
                              const Vector3r& p3) {
  Real best = std::min({point_segment_distance(p0, p2, p3), point_segment_distance(p1, p2, p3),
                        point_segment_distance(p2, p0, p1), point_segment_distance(p3, p0, p1)});
  const Vector3r d0 = p1 - p0, d1 = p3 - p2, normal = d0.cross(d1);
  if (normal.norm() > Real(0.1) * d0.norm() * d1.norm()) {
    const Vector3r r = p2 - p0;
    const Real s = r.cross(d1).dot(normal) / normal.squaredNorm();
    const Real t = r.cross(d0).dot(normal) / normal.squaredNorm();
    if (s >= 0 && s <= 1 && t >= 0 && t <= 1)
      best = std::min(best, ((p0 + s * d0) - (p2 + t * d1)).norm());
  }
  return best;
}

// ------------------------------------------------------------- the three families' traits

struct EdgePoint {
  static constexpr int N = 3;
  static constexpr const char* kName = "edge_point_distance";
  using Constraints = EdgePointDistanceConstraints;
  using Input = EdgePointDistanceConstraintInput;

  static Constraints make(const Input& input) {
    return make_edge_point_distance_constraints(input);
  }
  static void project(ParticleArrays particles, const Constraints& constraints, std::size_t begin,
                      std::size_t end, const ProjectionSettings& settings = {}) {
    project_edge_point_distance_constraints(particles, constraints, begin, end, settings);
  }
  static bool solve(const Points<3>& x, const std::array<Real, 3>& w, Real rest, Real compression,
                    Real stretch, Points<3>& corr) {
    return PositionBasedDynamics::solve_EdgePointDistanceConstraint(
        x[0], w[0], x[1], w[1], x[2], w[2], rest, compression, stretch, corr[0], corr[1], corr[2]);
  }

  /// p before, along or beyond the segment, or one of the conventions: a zero-length
  /// segment, or p on an endpoint (degenerate: no correction).
  static Points<3> random_points(Random& random) {
    const Vector3r a = random.vector(-3, 3);
    const Vector3r edge = random.unit_vector() * random.uniform(Real(0.3), 2);
    const Vector3r b = a + edge;
    const Vector3r away = random.uniform(Real(0.1), Real(1.5)) * perpendicular_to(random, edge);
    const Vector3r p = a + random.uniform(Real(-0.6), Real(1.6)) * edge + away;
    switch (random.integer(0, 9)) {
      case 0:
        return {p, a, a};  // zero-length segment: point–point
      case 1:
        return {random.integer(0, 1) ? a : b, a, b};  // p on an endpoint
      default:
        return {p, a, b};
    }
  }
  static Real distance(const Points<3>& x) { return point_segment_distance(x[0], x[1], x[2]); }
  /// The slots that move in the convergence test (the primitive they face stays static).
  static constexpr int kMovable = 1;
  static bool regular(const Points<3>& x) { return (x[2] - x[1]).norm() > Real(0.1); }
  /// A constraint whose point lies exactly on its segment, at exact coordinates, and one
  /// whose primitives are exactly 1 apart.
  static Points<3> touching(const Vector3r& origin) {
    return {origin + Vector3r(1, 0, 0), origin, origin + Vector3r(2, 0, 0)};
  }
  static Points<3> separated(const Vector3r& origin) {
    return {origin + Vector3r(1, 0, 1), origin, origin + Vector3r(2, 0, 0)};
  }
};

struct TrianglePoint {
  static constexpr int N = 4;
  static constexpr const char* kName = "triangle_point_distance";
  using Constraints = TrianglePointDistanceConstraints;
  using Input = TrianglePointDistanceConstraintInput;

  static Constraints make(const Input& input) {
    return make_triangle_point_distance_constraints(input);
  }
  static void project(ParticleArrays particles, const Constraints& constraints, std::size_t begin,
                      std::size_t end, const ProjectionSettings& settings = {}) {
    project_triangle_point_distance_constraints(particles, constraints, begin, end, settings);
  }
  static bool solve(const Points<4>& x, const std::array<Real, 4>& w, Real rest, Real compression,
                    Real stretch, Points<4>& corr) {
    return PositionBasedDynamics::solve_TrianglePointDistanceConstraint(
        x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3], rest, compression, stretch, corr[0],
        corr[1], corr[2], corr[3]);
  }

  /// p anywhere around the triangle (every vertex, edge and face region), or a collinear
  /// triangle, a sliver far below the thin-triangle threshold, all vertices at one point, or
  /// p on a vertex (degenerate).
  static Points<4> random_points(Random& random) {
    Vector3r a, b, c;
    do {
      a = random.vector(-3, 3);
      b = a + random.vector();
      c = a + random.vector();
    } while ((b - a).cross(c - a).norm() < Real(0.2));
    const int kind = random.integer(0, 9);
    if (kind == 0) c = a + random.uniform(Real(0.2), Real(0.8)) * (b - a);  // collinear
    if (kind == 1) {                                                        // sliver
      const Vector3r along = a + random.uniform(Real(0.2), Real(0.8)) * (b - a);
      c = along + Real(1e-5) * perpendicular_to(random, b - a);
    }
    if (kind == 2) b = c = a;  // one point
    const Vector3r centroid = (a + b + c) / 3;
    const Vector3r p = kind == 3 ? b : centroid + Real(1.5) * random.vector();
    return {p, a, b, c};
  }
  static Real distance(const Points<4>& x) {
    return point_triangle_distance(x[0], x[1], x[2], x[3]);
  }
  static constexpr int kMovable = 1;
  static bool regular(const Points<4>& x) {
    const Vector3r u = x[2] - x[1], v = x[3] - x[1];
    return u.cross(v).norm() > Real(0.1) * u.norm() * v.norm();
  }
  static Points<4> touching(const Vector3r& origin) {
    return {origin + Vector3r(0.25, 0.5, 0), origin, origin + Vector3r(1, 0, 0),
            origin + Vector3r(0, 1, 0)};
  }
  static Points<4> separated(const Vector3r& origin) {
    return {origin + Vector3r(0.25, 0.5, 1), origin, origin + Vector3r(1, 0, 0),
            origin + Vector3r(0, 1, 0)};
  }
};

struct EdgeEdge {
  static constexpr int N = 4;
  static constexpr const char* kName = "edge_edge_distance";
  using Constraints = EdgeEdgeDistanceConstraints;
  using Input = EdgeEdgeDistanceConstraintInput;

  static Constraints make(const Input& input) { return make_edge_edge_distance_constraints(input); }
  static void project(ParticleArrays particles, const Constraints& constraints, std::size_t begin,
                      std::size_t end, const ProjectionSettings& settings = {}) {
    project_edge_edge_distance_constraints(particles, constraints, begin, end, settings);
  }
  static bool solve(const Points<4>& x, const std::array<Real, 4>& w, Real rest, Real compression,
                    Real stretch, Points<4>& corr) {
    return PositionBasedDynamics::solve_EdgeEdgeDistanceConstraint(
        x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3], rest, compression, stretch, corr[0],
        corr[1], corr[2], corr[3]);
  }

  /// Two segments in general position (interior or endpoint closest points), or parallel,
  /// collinear and disjoint, one or both of zero length, or sharing a point (degenerate).
  static Points<4> random_points(Random& random) {
    const Vector3r p0 = random.vector(-3, 3);
    const Vector3r d0 = random.unit_vector() * random.uniform(Real(0.3), 2);
    const Vector3r p1 = p0 + d0;
    const Vector3r offset = random.uniform(Real(0.1), Real(1.5)) * perpendicular_to(random, d0);
    const Vector3r p2 = p0 + random.uniform(Real(-0.5), Real(1.5)) * d0 + offset;
    switch (random.integer(0, 12)) {
      case 0:  // parallel (or anti-parallel), overlapping or not
        return {p0, p1, p2, p2 + random.uniform(Real(-1.5), Real(1.5)) * d0};
      case 1:  // collinear, disjoint
        return {p0, p1, p1 + Real(0.5) * d0, p1 + random.uniform(Real(1), Real(2)) * d0};
      case 2:  // second segment of zero length
        return {p0, p1, p2, p2};
      case 3:  // first segment of zero length
        return {p2, p2, p0, p1};
      case 4:  // both of zero length
        return {p0, p0, p2, p2};
      case 5:  // sharing an endpoint
        return {p0, p1, p1, p2};
      case 6:  // a point on the first segment's endpoint
        return {p0, p1, p1, p1};
      default:
        return {p0, p1, p2, p2 + random.vector() * 2};
    }
  }
  static Real distance(const Points<4>& x) {
    return segment_segment_distance(x[0], x[1], x[2], x[3]);
  }
  static constexpr int kMovable = 2;
  static bool regular(const Points<4>& x) {
    return (x[1] - x[0]).norm() > Real(0.1) && (x[3] - x[2]).norm() > Real(0.1);
  }
  static Points<4> touching(const Vector3r& origin) {
    return {origin, origin + Vector3r(2, 0, 0), origin + Vector3r(1, -1, 0),
            origin + Vector3r(1, 1, 0)};
  }
  static Points<4> separated(const Vector3r& origin) {
    return {origin + Vector3r(0, 0, 1), origin + Vector3r(2, 0, 1), origin + Vector3r(1, -1, 0),
            origin + Vector3r(1, 1, 0)};
  }
};

// ----------------------------------------------------------------------------- helpers

/// Random constraints of the family. A constraint whose only movable particles have tiny
/// gradient weights (say an edge–edge pair whose closest points sit at static endpoints) is
/// ill-conditioned: its correction is C divided by a tiny weight, and any rounding difference
/// (FMA or not) is amplified as much. Such constraints get all their own particles movable.
template <class Family>
test::DisjointConstraintSet<Family::N> random_set(Random& random, std::size_t count) {
  constexpr int N = Family::N;
  auto set = test::make_disjoint_constraints<N>(random, count, Real(0.2), Family::random_points);
  std::vector<int> uses(set.positions.size(), 0);
  for (const ParticleIndex i : set.indices) ++uses[i];
  for (std::size_t c = 0; c < count; ++c) {
    const Points<N> x = set.points(c);
    std::array<Real, N> w;
    for (int k = 0; k < N; ++k) w[k] = set.inverse_masses[set.indices[c * N + k]];
    const Real distance = Family::distance(x);  // rest 1.5 distance: |C| = distance / 2
    Points<N> corr;
    if (!Family::solve(x, w, Real(1.5) * distance, 1, 1, corr)) continue;
    Real largest = 0;
    for (const Vector3r& v : corr) largest = std::max(largest, v.norm());
    if (largest <= 10 * distance) continue;
    for (int k = 0; k < N; ++k) {
      const ParticleIndex i = set.indices[c * N + k];
      if (uses[i] == 1) set.inverse_masses[i] = 1;
    }
  }
  return set;
}

/// Builds the batch with per-constraint rest distances (half to twice the current distance,
/// so C takes both signs) and per-constraint stiffnesses.
template <class Family>
typename Family::Constraints build(const test::DisjointConstraintSet<Family::N>& set,
                                   Random& random) {
  std::vector<Real> rest(set.count);
  for (std::size_t c = 0; c < set.count; ++c)
    rest[c] = random.uniform(Real(0.5), 2) * Family::distance(set.points(c));
  typename Family::Input input;
  input.particles = set.indices;
  input.particle_count = set.positions.size();
  input.rest_distances = rest;
  typename Family::Constraints constraints = Family::make(input);
  for (std::size_t c = 0; c < set.count; ++c) {
    constraints.compression_stiffness[c] = random.uniform(Real(0.1), 1);
    constraints.stretch_stiffness[c] = random.uniform(Real(0.1), 1);
  }
  return constraints;
}

/// The scalar API applied constraint by constraint to constraints [begin, end).
template <class Family>
std::vector<Vector3r> scalar_reference(const test::DisjointConstraintSet<Family::N>& set,
                                       const typename Family::Constraints& constraints,
                                       std::size_t begin, std::size_t end,
                                       std::size_t* projected = nullptr) {
  constexpr int N = Family::N;
  std::vector<Vector3r> expected = set.positions;
  for (std::size_t c = begin; c < end; ++c) {
    Points<N> x;
    std::array<Real, N> w;
    for (int k = 0; k < N; ++k) {
      x[k] = expected[set.indices[c * N + k]];
      w[k] = set.inverse_masses[set.indices[c * N + k]];
    }
    Points<N> corr;
    const bool ok =
        Family::solve(x, w, constraints.rest_distance[c], constraints.compression_stiffness[c],
                      constraints.stretch_stiffness[c], corr);
    if (ok && projected) ++*projected;
    for (int k = 0; k < N; ++k)
      if (w[k] > 0) expected[set.indices[c * N + k]] += corr[k];
  }
  return expected;
}

template <class Family>
void check_matches_scalar_api() {
  test::for_each_simd_target([](const std::string&) {
    std::size_t projected = 0, total = 0;
    for (unsigned seed = 1; seed <= 8; ++seed) {
      Random random(seed);
      const std::size_t count = std::size_t(random.integer(1, 300));
      const auto set = random_set<Family>(random, count);
      const auto constraints = build<Family>(set, random);
      const auto [begin, end] = test::random_range(random, count);
      const std::vector<Vector3r> expected =
          scalar_reference<Family>(set, constraints, begin, end, &projected);
      total += end - begin;
      ParticleState state(set.positions, set.inverse_masses);
      Family::project(ParticleArrays::of(state), constraints, begin, end);
      EXPECT_TRUE(test::positions_match(state, expected, 10)) << "seed " << seed;
    }
    // The mix really holds both projected and degenerate lanes.
    EXPECT_GT(projected, total / 2);
    EXPECT_LT(projected, total);
  });
}

TEST(ProximityBatch, EdgePointMatchesScalarApiOnEveryTarget) {
  check_matches_scalar_api<EdgePoint>();
}
TEST(ProximityBatch, TrianglePointMatchesScalarApiOnEveryTarget) {
  check_matches_scalar_api<TrianglePoint>();
}
TEST(ProximityBatch, EdgeEdgeMatchesScalarApiOnEveryTarget) {
  check_matches_scalar_api<EdgeEdge>();
}

/// Every other constraint touches its primitive (exactly, at exact coordinates): those lanes
/// are left bitwise unchanged, and their neighbours in the same vector are still projected.
template <class Family>
void check_degenerate_lanes() {
  constexpr int N = Family::N;
  test::for_each_simd_target([](const std::string&) {
    Random random(77);
    const std::size_t count = 2 * kMaxLanes + 3;
    test::DisjointConstraintSet<N> set;
    set.count = count;
    for (std::size_t c = 0; c < count; ++c) {
      const Vector3r origin(Real(4 * c), 0, 0);
      const Points<N> x = c % 2 == 0 ? Family::touching(origin) : Family::separated(origin);
      for (int k = 0; k < N; ++k) {
        set.indices.push_back(ParticleIndex(set.positions.size()));
        set.positions.push_back(x[k]);
        set.inverse_masses.push_back(random.inverse_mass());
      }
    }
    typename Family::Input input;
    input.particles = set.indices;
    input.particle_count = set.positions.size();
    input.rest_distance = Real(0.5);
    const auto constraints = Family::make(input);
    const std::vector<Vector3r> expected = scalar_reference<Family>(set, constraints, 0, count);
    ParticleState state(set.positions, set.inverse_masses);
    Family::project(ParticleArrays::of(state), constraints, 0, count);
    EXPECT_TRUE(test::positions_match(state, expected, 10));
    for (std::size_t c = 0; c < count; ++c) {
      for (int k = 0; k < N; ++k) {
        const std::size_t i = c * N + std::size_t(k);
        if (c % 2 == 0) {
          EXPECT_EQ(state.position(i), set.positions[i]) << "degenerate constraint " << c;
        }
      }
      if (c % 2 == 1) {
        EXPECT_NE(state.position(c * N), set.positions[c * N]) << "constraint " << c;
      }
    }
  });
}

TEST(ProximityBatch, EdgePointDegenerateLanesAreNotMoved) { check_degenerate_lanes<EdgePoint>(); }
TEST(ProximityBatch, TrianglePointDegenerateLanesAreNotMoved) {
  check_degenerate_lanes<TrianglePoint>();
}
TEST(ProximityBatch, EdgeEdgeDegenerateLanesAreNotMoved) { check_degenerate_lanes<EdgeEdge>(); }

/// The compression stiffness where closer than d0, the stretch stiffness where farther: one
/// batch holds both, and a stiffness of 0 on one side leaves those constraints in place.
template <class Family>
void check_stiffness_by_sign() {
  constexpr int N = Family::N;
  Random random(91);
  const std::size_t count = 3 * kMaxLanes + 1;
  test::DisjointConstraintSet<N> set;
  set.count = count;
  std::vector<Real> rest(count);
  for (std::size_t c = 0; c < count; ++c) {
    const Points<N> x = Family::separated(Vector3r(Real(4 * c), 0, 0));
    rest[c] = c % 2 == 0 ? Real(2) : Real(0.5);  // even: compressed, odd: stretched
    for (int k = 0; k < N; ++k) {
      set.indices.push_back(ParticleIndex(set.positions.size()));
      set.positions.push_back(x[k]);
      set.inverse_masses.push_back(random.inverse_mass());
    }
  }
  typename Family::Input input;
  input.particles = set.indices;
  input.particle_count = set.positions.size();
  input.rest_distances = rest;
  input.compression_stiffness = 0;
  input.stretch_stiffness = 1;
  const auto constraints = Family::make(input);
  ParticleState state(set.positions, set.inverse_masses);
  Family::project(ParticleArrays::of(state), constraints, 0, count);
  for (std::size_t c = 0; c < count; ++c) {
    const bool compressed = c % 2 == 0;
    EXPECT_EQ(state.position(c * N) == set.positions[c * N], compressed) << "constraint " << c;
  }
}

TEST(ProximityBatch, EdgePointStiffnessFollowsTheSignOfC) { check_stiffness_by_sign<EdgePoint>(); }
TEST(ProximityBatch, TrianglePointStiffnessFollowsTheSignOfC) {
  check_stiffness_by_sign<TrianglePoint>();
}
TEST(ProximityBatch, EdgeEdgeStiffnessFollowsTheSignOfC) { check_stiffness_by_sign<EdgeEdge>(); }

template <class Family>
void check_reproducible_and_static() {
  test::for_each_simd_target([](const std::string&) {
    Random random(42);
    const auto set = random_set<Family>(random, 257);
    const auto constraints = build<Family>(set, random);
    ParticleState first(set.positions, set.inverse_masses), second = first;
    const ParticleState before = first;
    Family::project(ParticleArrays::of(first), constraints, 40, 40);
    EXPECT_TRUE(test::same_bits(first, before)) << "an empty range wrote particles";
    for (int iteration = 0; iteration < 5; ++iteration) {
      Family::project(ParticleArrays::of(first), constraints, 0, 257);
      Family::project(ParticleArrays::of(second), constraints, 0, 257);
    }
    EXPECT_TRUE(test::same_bits(first, second));
    EXPECT_FALSE(test::same_bits(first, before));
    for (std::size_t i = 0; i < set.positions.size(); ++i)
      if (set.inverse_masses[i] == 0) {
        EXPECT_EQ(first.position(i), before.position(i));
      }
  });
}

TEST(ProximityBatch, EdgePointReproducibleAndStaticUntouched) {
  check_reproducible_and_static<EdgePoint>();
}
TEST(ProximityBatch, TrianglePointReproducibleAndStaticUntouched) {
  check_reproducible_and_static<TrianglePoint>();
}
TEST(ProximityBatch, EdgeEdgeReproducibleAndStaticUntouched) {
  check_reproducible_and_static<EdgeEdge>();
}

/// Repeated sweeps with unit stiffness over constraints on static primitives (only the point
/// or the first edge movable) reach the rest distance, measured by the reference distance.
template <class Family>
void check_converges_to_rest_distance() {
  constexpr int N = Family::N;
  Random random(5);
  const std::size_t count = 100;
  auto set = test::make_disjoint_constraints<N>(random, count, 0, Family::random_points);
  std::vector<Real> rest(count);
  std::vector<bool> proper(count);
  for (std::size_t c = 0; c < count; ++c) {
    for (int k = 0; k < N; ++k) {
      Real& w = set.inverse_masses[set.indices[c * N + std::size_t(k)]];
      w = k < Family::kMovable ? Real(1) : Real(0);
    }
    const Real distance = Family::distance(set.points(c));
    proper[c] = distance > Real(0.05) && Family::regular(set.points(c));
    rest[c] = random.uniform(Real(0.5), Real(1.5)) * distance;
  }
  typename Family::Input input;
  input.particles = set.indices;
  input.particle_count = set.positions.size();
  input.rest_distances = rest;
  const auto constraints = Family::make(input);
  ParticleState state(set.positions, set.inverse_masses);
  for (int sweep = 0; sweep < 20; ++sweep)
    Family::project(ParticleArrays::of(state), constraints, 0, count);
  for (std::size_t c = 0; c < count; ++c) {
    if (!proper[c]) continue;
    Points<N> x;
    for (int k = 0; k < N; ++k) x[k] = state.position(set.indices[c * N + std::size_t(k)]);
    EXPECT_NEAR(Family::distance(x), rest[c], 100 * test::kRoundOff * (1 + rest[c]))
        << "constraint " << c;
  }
}

TEST(ProximityBatch, EdgePointConvergesToTheRestDistance) {
  check_converges_to_rest_distance<EdgePoint>();
}
TEST(ProximityBatch, TrianglePointConvergesToTheRestDistance) {
  check_converges_to_rest_distance<TrianglePoint>();
}
TEST(ProximityBatch, EdgeEdgeConvergesToTheRestDistance) {
  check_converges_to_rest_distance<EdgeEdge>();
}

// ------------------------------------------------------------------ validation at the door

template <class Family>
std::string error_of(const typename Family::Input& input) {
  return test::error_of([&] { Family::make(input); });
}

template <class Family>
void check_validation() {
  constexpr int N = Family::N;
  const std::string family = Family::kName;
  using Input = typename Family::Input;
  std::vector<ParticleIndex> two(2 * N);
  for (int k = 0; k < 2 * N; ++k) two[std::size_t(k)] = ParticleIndex(k);
  const std::size_t particles = 2 * N;
  const auto input = [&](std::span<const ParticleIndex> indices) {
    Input in;
    in.particles = indices;
    in.particle_count = particles;
    in.rest_distance = Real(0.1);
    return in;
  };
  EXPECT_EQ(error_of<Family>(input(two)), "");

  std::vector<ParticleIndex> bad = two;
  bad[N + 1] = 99;
  EXPECT_EQ(error_of<Family>(input(bad)), family +
                                              " constraint 1: particle index 99 is out of range (" +
                                              std::to_string(particles) + " particles)");
  bad = two;
  bad[N + 2] = bad[N];
  EXPECT_EQ(error_of<Family>(input(bad)),
            family + " constraint 1: particle " + std::to_string(N) + " appears twice");
  bad.assign(two.begin(), two.end() - 1);
  EXPECT_EQ(error_of<Family>(input(bad)), family + " constraints: " + std::to_string(2 * N - 1) +
                                              " particle indices is not a multiple of " +
                                              std::to_string(N));

  Input in = input(two);
  in.rest_distance = -1;
  EXPECT_EQ(error_of<Family>(in),
            family + " constraints: rest distance is -1, must be finite and ≥ 0");
  in.rest_distance = Real(INFINITY);
  EXPECT_EQ(error_of<Family>(in),
            family + " constraints: rest distance is inf, must be finite and ≥ 0");
  const std::vector<Real> negative = {Real(0.1), Real(-0.5)};
  in.rest_distances = negative;  // per constraint: replaces the shared (bad) value
  EXPECT_EQ(error_of<Family>(in),
            family + " constraint 1: rest distance is -0.5, must not be negative");
  const std::vector<Real> not_finite = {Real(NAN), Real(0.5)};
  in.rest_distances = not_finite;
  EXPECT_EQ(error_of<Family>(in), family + " constraint 0: rest distance is not finite");
  const std::vector<Real> one = {Real(0.5)};
  in.rest_distances = one;
  EXPECT_EQ(error_of<Family>(in), family + " constraints: 1 rest distances for 2 constraints");
  const std::vector<Real> fine = {Real(0), Real(0.5)};
  in.rest_distances = fine;
  EXPECT_EQ(error_of<Family>(in), "");
  const auto built = Family::make(in);
  EXPECT_EQ(built.rest_distance[0], Real(0));
  EXPECT_EQ(built.rest_distance[1], Real(0.5));

  in = input(two);
  in.compression_stiffness = -1;
  EXPECT_EQ(error_of<Family>(in),
            family + " constraints: compression stiffness is -1, must be finite and ≥ 0");
  in = input(two);
  in.stretch_stiffness = Real(NAN);
  EXPECT_EQ(error_of<Family>(in),
            family + " constraints: stretch stiffness is nan, must be finite and ≥ 0");
}

TEST(ProximityBatchValidation, EdgePointNamesTheConstraintAndTheProblem) {
  check_validation<EdgePoint>();
}
TEST(ProximityBatchValidation, TrianglePointNamesTheConstraintAndTheProblem) {
  check_validation<TrianglePoint>();
}
TEST(ProximityBatchValidation, EdgeEdgeNamesTheConstraintAndTheProblem) {
  check_validation<EdgeEdge>();
}

template <class Family>
void check_projection_checks() {
  constexpr int N = Family::N;
  std::vector<ParticleIndex> indices(N);
  std::vector<Vector3r> positions;
  for (int k = 0; k < N; ++k) {
    indices[std::size_t(k)] = ParticleIndex(k);
    positions.push_back(Vector3r(Real(k), Real(k * k), 1));
  }
  typename Family::Input input;
  input.particles = indices;
  input.particle_count = N;
  const auto constraints = Family::make(input);
  ParticleState state(positions, std::vector<Real>(N, Real(1)));
  EXPECT_THROW(Family::project(ParticleArrays::of(state), constraints, 0, 2), InvalidInput);
  ParticleState fewer(N - 1);
  EXPECT_THROW(Family::project(ParticleArrays::of(fewer), constraints, 0, 1), InvalidInput);
  const ParticleState before = state;
  try {
    Family::project(ParticleArrays::of(state), constraints, 0, 1,
                    {ConstraintSemantics::compliance, Real(0.01)});
    ADD_FAILURE() << "compliance semantics accepted";
  } catch (const InvalidInput& error) {
    EXPECT_EQ(std::string(error.what()),
              std::string(Family::kName) +
                  " constraints: only stiffness semantics are supported (no XPBD form)");
  }
  EXPECT_TRUE(test::same_bits(state, before));
}

TEST(ProximityBatchValidation, EdgePointRangeParticlesAndSemanticsAreChecked) {
  check_projection_checks<EdgePoint>();
}
TEST(ProximityBatchValidation, TrianglePointRangeParticlesAndSemanticsAreChecked) {
  check_projection_checks<TrianglePoint>();
}
TEST(ProximityBatchValidation, EdgeEdgeRangeParticlesAndSemanticsAreChecked) {
  check_projection_checks<EdgeEdge>();
}

}  // namespace proximity_batch_tests
}  // namespace tessera
