// Self-collision detection: known answers on one triangle and a vertex, on two edges, the
// topology and static filters, a vertex that crosses a triangle within the substep, and on a
// folded cloth the exact set a brute-force O(n²) loop finds with the same rule, listed the
// same on 1 and 2 threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <random>
#include <numbers>
#include <vector>

#include <tbb/task_arena.h>

#include <tessera/collision/self_collision.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/simd.hpp>
#include <tessera/io/generators.hpp>

#include "closest_distance.hpp"
#include "leaf_scan.hpp"
#include "segment_distances.hpp"
#include "triangle_distances.hpp"

namespace tessera {
namespace self_collision_tests {

using Contacts = SelfCollision::Contacts;

constexpr Real kThickness = Real(0.1);
const SelfCollisionSettings kSettings{kThickness, Real(0.02), Real(0.8)};

/// One triangle (0, 1, 2) in the plane z = 0 and a particle 3 at `p` (all at rest).
ParticleState triangle_and_point(const Vector3r& p, Real point_inverse_mass = 1) {
  const std::vector<Vector3r> positions = {Vector3r(0, 0, 0), Vector3r(1, 0, 0),
                                           Vector3r(0, 1, 0), p};
  const std::vector<Real> inverse_masses = {1, 1, 1, point_inverse_mass};
  return ParticleState(positions, inverse_masses);
}

/// The mesh of triangle_and_point: one triangle; particle 3 belongs to no triangle.
const std::vector<std::uint32_t> kTriangleAndPoint = {0, 1, 2};

Contacts detect(const std::vector<std::uint32_t>& triangles, const ParticleState& state,
                const SelfCollisionSettings& settings = kSettings) {
  SelfCollision collision(triangles, state.size());
  Contacts contacts;
  collision.detect(state, settings, contacts);
  return contacts;
}

TEST(SelfCollision, AVertexJustAboveATriangleIsOneContact) {
  const Contacts contacts =
      detect(kTriangleAndPoint, triangle_and_point(Vector3r(Real(0.2), Real(0.2), Real(0.05))));
  EXPECT_EQ(contacts.triangle_point, (std::vector<ParticleIndex>{3, 0, 1, 2}));
  EXPECT_TRUE(contacts.edge_edge.empty());
}

TEST(SelfCollision, AVertexWithinTheMarginIsAContactOneBeyondItIsNot) {
  // thickness + margin = 0.12.
  EXPECT_EQ(detect(kTriangleAndPoint, triangle_and_point(Vector3r(Real(0.2), Real(0.2), Real(0.115))))
                .triangle_point_count(),
            1u);
  EXPECT_EQ(detect(kTriangleAndPoint, triangle_and_point(Vector3r(Real(0.2), Real(0.2), Real(0.125))))
                .triangle_point_count(),
            0u);
  // Beside the triangle, past its edge: the distance is to the edge, not to the plane.
  EXPECT_EQ(detect(kTriangleAndPoint, triangle_and_point(Vector3r(Real(0.6), Real(0.6), Real(0))))
                .triangle_point_count(),
            0u);
}

TEST(SelfCollision, AFarVertexIsNoContact) {
  EXPECT_EQ(detect(kTriangleAndPoint, triangle_and_point(Vector3r(3, 2, 1))).triangle_point_count(),
            0u);
}

TEST(SelfCollision, ATriangleNeverTouchesItsOwnVerticesOrEdges) {
  // With a thickness larger than the triangle, every vertex is "near" the triangle and every
  // edge near the others: none of them is a contact.
  const Contacts contacts = detect(kTriangleAndPoint, triangle_and_point(Vector3r(5, 5, 5)),
                                   SelfCollisionSettings{Real(2), Real(0)});
  EXPECT_TRUE(contacts.triangle_point.empty());
  EXPECT_TRUE(contacts.edge_edge.empty());
}

TEST(SelfCollision, AdjacentEdgesAreNoContactCrossingEdgesAre) {
  // Triangle (0, 1, 2) in z = 0 and a thin triangle (0, 3, 4) along the diagonal x = y,
  // 0.05 above it at 3 and 4:
  //
  //    2                 edges, sorted: (0,1) (0,2) (0,3) (0,4) (1,2) (3,4)
  //    |`.   3           the four through 0 meet there (distance 0) but are adjacent;
  //    |  `.╱            (0,3) crosses (1,2) 0.025 above it, (3,4) crosses it 0.05 above;
  //    | 4╱`.            (3,4) passes 0.2 from (0,1) and (0,2): out of reach (0.12).
  //    0╱─────1
  const std::vector<Vector3r> positions = {Vector3r(0, 0, 0), Vector3r(1, 0, 0),
                                           Vector3r(0, 1, 0), Vector3r(1, 1, Real(0.05)),
                                           Vector3r(Real(0.2), Real(0.2), Real(0.05))};
  const std::vector<std::uint32_t> triangles = {0, 1, 2, 0, 3, 4};
  const ParticleState state(positions, std::vector<Real>(5, 1));
  const Contacts contacts = detect(triangles, state);
  EXPECT_EQ(contacts.edge_edge, (std::vector<ParticleIndex>{0, 3, 1, 2, 1, 2, 3, 4}));
  // Switched off, the edge–edge list is empty and the vertex–triangle one unchanged.
  SelfCollisionSettings vertex_triangle_only = kSettings;
  vertex_triangle_only.edge_edge = false;
  const Contacts without = detect(triangles, state, vertex_triangle_only);
  EXPECT_TRUE(without.edge_edge.empty());
  EXPECT_EQ(without.triangle_point, contacts.triangle_point);
  // Vertex 4 hovers 0.05 over triangle (0, 1, 2), whose corner it is not; vertex 3 is 0.7
  // past its hypotenuse, and 1 and 2 are far from the thin triangle.
  EXPECT_EQ(contacts.triangle_point, (std::vector<ParticleIndex>{4, 0, 1, 2}));
}

TEST(SelfCollision, StaticParticlesAloneMakeNoContact) {
  ParticleState state = triangle_and_point(Vector3r(Real(0.2), Real(0.2), Real(0.05)), 0);
  for (std::size_t i = 0; i < 3; ++i) state.inverse_mass[i] = 0;
  EXPECT_EQ(detect(kTriangleAndPoint, state).triangle_point_count(), 0u);
  // One movable particle is enough.
  state.inverse_mass[1] = 1;
  EXPECT_EQ(detect(kTriangleAndPoint, state).triangle_point_count(), 1u);
}

TEST(SelfCollision, AVertexCrossingATriangleWithinTheSubstepIsAContact) {
  // From 0.3 above to 0.3 below in one substep: at neither end within reach (0.12), but the
  // straight motion passes through the triangle.
  ParticleState state = triangle_and_point(Vector3r(Real(0.2), Real(0.2), Real(-0.3)));
  state.previous_z[3] = Real(0.3);
  EXPECT_EQ(detect(kTriangleAndPoint, state).triangle_point, (std::vector<ParticleIndex>{3, 0, 1, 2}));
  // The same motion far beside the triangle is no contact.
  state.x[3] = state.previous_x[3] = 5;
  EXPECT_EQ(detect(kTriangleAndPoint, state).triangle_point_count(), 0u);
}

TEST(SelfCollision, ContactsBecomeCompressionOnlyConstraintsAtTheThickness) {
  const ParticleState state = triangle_and_point(Vector3r(Real(0.2), Real(0.2), Real(0.05)));
  const Contacts contacts = detect(kTriangleAndPoint, state);
  const SelfCollisionConstraints constraints =
      make_self_collision_constraints(contacts, state.size(), kSettings);
  ASSERT_EQ(constraints.triangle_point.size(), 1u);
  EXPECT_EQ(constraints.edge_edge.size(), 0u);
  EXPECT_EQ(constraints.triangle_point.particles.particle[0][0], 3u);
  EXPECT_EQ(constraints.triangle_point.particles.particle[3][0], 2u);
  EXPECT_EQ(constraints.triangle_point.rest_distance[0], kThickness);
  EXPECT_EQ(constraints.triangle_point.compression_stiffness[0], kSettings.stiffness);
  EXPECT_EQ(constraints.triangle_point.stretch_stiffness[0], Real(0));
}

TEST(SelfCollision, AMeshWithoutTrianglesHasNoContact) {
  SelfCollision collision({}, 4);
  Contacts contacts{{1, 2, 3, 4}, {5, 6, 7, 8}, {9}};  // stale lists are overwritten
  collision.detect(triangle_and_point(Vector3r(0, 0, 0)), kSettings, contacts);
  EXPECT_TRUE(contacts.triangle_point.empty());
  EXPECT_TRUE(contacts.edge_edge.empty());
}

TEST(SelfCollision, InvalidInputIsRefused) {
  const std::vector<std::uint32_t> out_of_range = {0, 1, 7};
  EXPECT_THROW(SelfCollision(out_of_range, 4), InvalidInput);
  const std::vector<std::uint32_t> repeated = {0, 1, 1};
  EXPECT_THROW(SelfCollision(repeated, 4), InvalidInput);
  const std::vector<std::uint32_t> ragged = {0, 1};
  EXPECT_THROW(SelfCollision(ragged, 4), InvalidInput);
  SelfCollision collision(kTriangleAndPoint, 4);
  Contacts contacts;
  const ParticleState state = triangle_and_point(Vector3r(0, 0, 1));
  EXPECT_THROW(collision.detect(state, SelfCollisionSettings{0, 0}, contacts), InvalidInput);
  EXPECT_THROW(collision.detect(state, SelfCollisionSettings{1, -1}, contacts), InvalidInput);
  SelfCollisionSettings negative_skin = kSettings;
  negative_skin.skin = -1;
  EXPECT_THROW(collision.update(state, negative_skin, contacts), InvalidInput);
  SelfCollisionSettings small_scale = kSettings;
  small_scale.motion_scale = Real(0.5);
  EXPECT_THROW(collision.detect(state, small_scale, contacts), InvalidInput);
  EXPECT_THROW(collision.detect(ParticleState(3), kSettings, contacts), InvalidInput);
}

// ------------------------------------------------------------------ a folded cloth

/// An n × n cloth of spacing h folded in half over a cylinder of radius 0.4 h (layers 0.8 h
/// apart), the top layer rippled by ±0.3 h so it comes within reach of the bottom in places,
/// moving down by 0.05 h over the substep; two corners static.
struct FoldedCloth {
  io::ClothGrid grid;
  ParticleState state;

  explicit FoldedCloth(std::size_t n) : grid(io::make_cloth_grid(n, n, Real(1) / Real(n - 1))) {
    const Real h = Real(1) / Real(n - 1), radius = Real(0.4) * h;
    std::vector<Vector3r> positions;
    for (const Vector3r& p : grid.positions) {
      const Real along = p.x() - Real(0.5);
      if (along <= 0) {
        positions.emplace_back(p.x(), 0, p.y());
        continue;
      }
      const Real angle = along / radius;
      if (angle <= std::numbers::pi_v<Real>) {
        positions.emplace_back(Real(0.5) + radius * std::sin(angle),
                               radius - radius * std::cos(angle), p.y());
        continue;
      }
      const Real x = Real(0.5) - (along - std::numbers::pi_v<Real> * radius);
      const Real ripple = Real(0.3) * h * std::sin(Real(37) * x) * std::cos(Real(23) * p.y());
      positions.emplace_back(x, 2 * radius + ripple, p.y());
    }
    std::vector<Real> inverse_masses(positions.size(), 1);
    inverse_masses[0] = inverse_masses[n - 1] = 0;
    state = ParticleState(positions, inverse_masses);
    // The upper half (the fold's top and the upper layer) comes down by 0.2 h in the substep,
    // the lower layer stays: only relative motion makes contacts (self_collision.hpp).
    for (std::size_t i = 0; i < state.size(); ++i)
      if (state.y[i] > radius) state.previous_y[i] += Real(0.2) * h;
  }
  Real spacing() const { return Real(1) / Real(grid.columns - 1); }
};

/// The contact rule of self_collision.hpp over every pair, O(n²).
Contacts brute_force(const FoldedCloth& cloth, const SelfCollision& collision, Real reach) {
  const ParticleState& s = cloth.state;
  const auto start = [&](std::uint32_t i) {
    return Vector3r(s.previous_x[i], s.previous_y[i], s.previous_z[i]);
  };
  const auto motion = [&](std::uint32_t i) { return Vector3r(s.position(i) - start(i)); };
  // The most two primitives' points approach each other: max |Δi − Δj| over their corners.
  const auto approach = [&](std::initializer_list<std::uint32_t> a,
                            std::initializer_list<std::uint32_t> b) {
    Real most = 0;
    for (const std::uint32_t i : a)
      for (const std::uint32_t j : b) most = std::max(most, (motion(i) - motion(j)).norm());
    return most;
  };
  const auto movable = [&](std::initializer_list<std::uint32_t> ids) {
    for (const std::uint32_t i : ids)
      if (s.inverse_mass[i] != 0) return true;
    return false;
  };
  Contacts contacts;
  const auto triangles = collision.triangles();
  for (std::uint32_t p = 0; p < s.size(); ++p)
    for (std::size_t t = 0; t < triangles.size() / 3; ++t) {
      const std::uint32_t a = triangles[3 * t], b = triangles[3 * t + 1], c = triangles[3 * t + 2];
      if (p == a || p == b || p == c || !movable({p, a, b, c})) continue;
      const Real within = reach + approach({p}, {a, b, c});
      if (detail::squared_point_triangle_distance(start(p), start(a), start(b), start(c)) <
          within * within)
        contacts.triangle_point.insert(contacts.triangle_point.end(), {p, a, b, c});
    }
  const auto edges = collision.edges();
  for (std::size_t e = 0; e < edges.size() / 2; ++e)
    for (std::size_t f = e + 1; f < edges.size() / 2; ++f) {
      const std::uint32_t p0 = edges[2 * e], p1 = edges[2 * e + 1], p2 = edges[2 * f],
                          p3 = edges[2 * f + 1];
      if (p0 == p2 || p0 == p3 || p1 == p2 || p1 == p3 || !movable({p0, p1, p2, p3})) continue;
      const Real within = reach + approach({p0, p1}, {p2, p3});
      if (detail::squared_segment_distance(start(p0), start(p1), start(p2), start(p3)) <
          within * within)
        contacts.edge_edge.insert(contacts.edge_edge.end(), {p0, p1, p2, p3});
    }
  return contacts;
}

TEST(SelfCollision, BatchedSegmentDistancesAreTheScalarOnesBitForBitOnEveryTarget) {
  // The build measures its edge pairs a vector at a time (segment_distances.cpp); a candidate
  // is a candidate by the scalar rule's bits, so each lane must give exactly
  // squared_segment_distance: random pairs, nearly parallel ones (where the closest points
  // hinge on the sign of a e − b², and a fused multiply–add had moved them by 5·10⁻⁴ of the
  // length), point-like second segments, shared lines; on every target the machine runs.
  std::mt19937 random(7);
  std::uniform_real_distribution<Real> coordinate(-1, 1), small(-1e-3f, 1e-3f);
  const auto point = [&] { return Vector3r(coordinate(random), coordinate(random), coordinate(random)); };
  struct Case {
    Vector3r p1, q1;
    std::vector<Vector3r> p, q;
  };
  std::vector<Case> cases;
  for (int k = 0; k < 40; ++k) {
    Case c{point(), point(), {}, {}};
    const Vector3r direction = c.q1 - c.p1;
    for (int j = 0; j < 37; ++j) {
      Vector3r p = point(), q = point();
      if (j % 4 == 1) {  // nearly parallel, a little apart
        p = c.p1 + Vector3r(small(random), small(random), small(random)) * 50;
        q = p + direction + Vector3r(small(random), small(random), small(random));
      } else if (j % 4 == 2) {  // point-like
        q = p;
      } else if (j % 4 == 3) {  // on the same line, shifted
        p = c.p1 + Real(0.5) * direction, q = c.q1 + Real(0.7) * direction;
      }
      c.p.push_back(p), c.q.push_back(q);
    }
    cases.push_back(std::move(c));
  }
  // The case the review found: scalar 0.0495352, an FMA lane 0.0500000.
  cases.push_back({Vector3r(-0.35835135f, -0.441194177f, -0.233575344f),
                   Vector3r(0.590032995f, -0.611597002f, -0.501026332f),
                   {Vector3r(-0.349473983f, -0.391988546f, -0.233585238f)},
                   {Vector3r(0.598803699f, -0.562844515f, -0.501125336f)}});
  std::size_t compared = 0, within_tested = 0, within_found = 0;
  for (const std::string& target : available_simd_targets()) {
    force_simd_target(target);
    for (const Case& c : cases) {
      const std::size_t n = c.p.size();
      const std::size_t padded = detail::padded_to_lanes(n);
      std::vector<Real> px(padded), py(padded), pz(padded), qx(padded), qy(padded), qz(padded),
          squared(padded);
      for (std::size_t j = 0; j < n; ++j)
        px[j] = c.p[j].x(), py[j] = c.p[j].y(), pz[j] = c.p[j].z(), qx[j] = c.q[j].x(),
        qy[j] = c.q[j].y(), qz[j] = c.q[j].z();
      detail::squared_segment_distances(c.p1, c.q1,
                                        {px.data(), py.data(), pz.data(), qx.data(), qy.data(),
                                         qz.data(), n},
                                        squared.data());
      for (std::size_t j = 0; j < n; ++j) {
        const Real expected = detail::squared_segment_distance(c.p1, c.q1, c.p[j], c.q[j]);
        EXPECT_EQ(std::memcmp(&squared[j], &expected, sizeof(Real)), 0)
            << target << ": pair " << j << " gives " << squared[j] << ", the scalar rule "
            << expected;
        ++compared;
      }
      // segments_within: the pairs closer than own + budget[j], by the scalar comparison
      // (within = own + budget, squared < within²), in order; budgets around each pair's own
      // distance, some exactly at it.
      const Real own = Real(0.05);
      std::vector<Real> budget(padded, Real(0)), within_squared(padded);
      std::vector<std::uint32_t> within(padded);
      std::vector<std::uint32_t> expected_within;
      for (std::size_t j = 0; j < n; ++j) {
        const Real distance = std::sqrt(squared[j]);
        budget[j] = std::max(Real(0), distance - own + Real(j % 3) * Real(0.01) - Real(0.01));
        const Real reach = own + budget[j];
        if (squared[j] < reach * reach) expected_within.push_back(std::uint32_t(j));
      }
      const std::size_t found = detail::segments_within(
          c.p1, c.q1, own,
          {px.data(), py.data(), pz.data(), qx.data(), qy.data(), qz.data(), n}, budget.data(),
          within_squared.data(), within.data());
      EXPECT_EQ(std::vector<std::uint32_t>(within.begin(), within.begin() + std::ptrdiff_t(found)),
                expected_within)
          << target;
      EXPECT_EQ(std::memcmp(within_squared.data(), squared.data(), n * sizeof(Real)), 0) << target;
      within_tested += n;
      within_found += found;
      // segment_pairs_within: pair j of two batches (the first segments other pairs' second
      // ones, point-like ones replaced), against the scalar rule at limits around each
      // pair's distance.
      std::vector<Real> fx(padded), fy(padded), fz(padded), gx(padded), gy(padded), gz(padded),
          limit(padded, Real(0));
      std::vector<std::uint32_t> pair_passing(padded);
      std::vector<std::uint32_t> expected_pairs;
      for (std::size_t j = 0; j < n; ++j) {
        Vector3r p = c.p[(j + 1) % n], q = c.q[(j + 1) % n];
        if (detail::dot3(q - p, q - p) <= kDegenerateTolerance * kDegenerateTolerance)
          p = c.p1, q = c.q1;
        fx[j] = p.x(), fy[j] = p.y(), fz[j] = p.z(), gx[j] = q.x(), gy[j] = q.y(), gz[j] = q.z();
        const Real distance = detail::squared_segment_distance(p, q, c.p[j], c.q[j]);
        limit[j] = std::sqrt(distance) + Real(int(j % 3) - 1) * Real(1e-3);
        if (distance < limit[j] * limit[j]) expected_pairs.push_back(std::uint32_t(j));
      }
      const std::size_t pairs_found = detail::segment_pairs_within(
          {fx.data(), fy.data(), fz.data(), gx.data(), gy.data(), gz.data(), n},
          {px.data(), py.data(), pz.data(), qx.data(), qy.data(), qz.data(), n}, limit.data(),
          pair_passing.data());
      EXPECT_EQ(std::vector<std::uint32_t>(pair_passing.begin(),
                                           pair_passing.begin() + std::ptrdiff_t(pairs_found)),
                expected_pairs)
          << target;
    }
  }
  force_simd_target("");
  EXPECT_GT(compared, 1000u);
  // Both answers occur.
  EXPECT_GT(within_found, within_tested / 5);
  EXPECT_LT(within_found, 4 * within_tested / 5);
}

TEST(SelfCollision, BatchedTriangleDistancesAreTheScalarOnesBitForBitOnEveryTarget) {
  // The build measures its vertex–triangle pairs a vector at a time (triangle_distances.cpp):
  // each lane must give squared_point_triangle_distance's bits and the same answer to
  // "closer than own + budget", whichever Voronoi region holds the closest point: points
  // over the face and beyond each vertex and edge, on the region borders (the point level
  // with a corner or an edge), near-degenerate and degenerate (collinear, point-like)
  // triangles; on every target the machine runs.
  std::mt19937 random(11);
  std::uniform_real_distribution<Real> coordinate(-1, 1), unit(0, 1);
  const auto point = [&] { return Vector3r(coordinate(random), coordinate(random), coordinate(random)); };
  struct Case {
    Vector3r p;
    std::vector<Vector3r> a, b, c;
  };
  std::vector<Case> cases;
  for (int k = 0; k < 40; ++k) {
    Case c{point(), {}, {}, {}};
    for (int j = 0; j < 45; ++j) {
      Vector3r a = point(), b = point(), t = point();
      if (j % 5 == 1) {  // collinear corners
        t = a + unit(random) * (b - a);
      } else if (j % 5 == 2) {  // a point-like triangle
        b = a, t = a;
      } else if (j % 5 == 3) {  // p level with a corner or on an edge's line: region borders
        const Vector3r corners[3] = {a, b, t};
        const Vector3r& from = corners[j % 3];
        const Vector3r& to = corners[(j + 1) % 3];
        c.a.push_back(a), c.b.push_back(b), c.c.push_back(t);
        a = c.p + (from - to);  // p − a parallel to an edge
        b = c.p, t = point();  // p on a corner
      } else if (j % 5 == 4) {  // a thin sliver
        t = Real(0.5) * (a + b) + Real(1e-4) * point();
      }
      c.a.push_back(a), c.b.push_back(b), c.c.push_back(t);
    }
    cases.push_back(std::move(c));
  }
  std::size_t compared = 0, found_total = 0;
  for (const std::string& target : available_simd_targets()) {
    force_simd_target(target);
    for (const Case& c : cases) {
      const std::size_t n = c.a.size();
      const std::size_t padded = detail::padded_to_lanes(n);
      std::vector<Real> xyz[9], budget(padded, Real(0)), squared(padded);
      for (std::vector<Real>& v : xyz) v.assign(padded, Real(0));
      std::vector<std::uint32_t> within(padded), expected_within;
      const Real own = Real(0.1);
      for (std::size_t j = 0; j < n; ++j) {
        const Vector3r* corners[3] = {&c.a[j], &c.b[j], &c.c[j]};
        for (int v = 0; v < 9; ++v) xyz[v][j] = (*corners[v / 3])[v % 3];
        const Real expected = detail::squared_point_triangle_distance(c.p, c.a[j], c.b[j], c.c[j]);
        // Budgets around each pair's distance, some exactly at it.
        budget[j] = std::max(Real(0), std::sqrt(expected) - own + Real(int(j % 3) - 1) * Real(0.01));
        const Real limit = own + budget[j];
        if (expected < limit * limit) expected_within.push_back(std::uint32_t(j));
      }
      const std::size_t found = detail::triangles_within(
          c.p, own,
          {xyz[0].data(), xyz[1].data(), xyz[2].data(), xyz[3].data(), xyz[4].data(),
           xyz[5].data(), xyz[6].data(), xyz[7].data(), xyz[8].data(), budget.data(), n},
          squared.data(), within.data());
      for (std::size_t j = 0; j < n; ++j) {
        const Real expected = detail::squared_point_triangle_distance(c.p, c.a[j], c.b[j], c.c[j]);
        EXPECT_EQ(std::memcmp(&squared[j], &expected, sizeof(Real)), 0)
            << target << ": triangle " << j << " gives " << squared[j] << ", the scalar rule "
            << expected;
        ++compared;
      }
      EXPECT_EQ(std::vector<std::uint32_t>(within.begin(), within.begin() + std::ptrdiff_t(found)),
                expected_within)
          << target;
      found_total += found;
    }
  }
  force_simd_target("");
  EXPECT_GT(compared, 1000u);
  EXPECT_GT(found_total, compared / 5);
  EXPECT_LT(found_total, 4 * compared / 5);
}

TEST(SelfCollision, LeafKernelsPassExactlyTheScalarRulesPairsOnEveryTarget) {
  // The build measures each primitive against the members of the leaves its leaf meets, read
  // in place (triangles_within_leaves, segments_within_leaves): a member passes when its box
  // overlaps the query's, it shares no particle with it, it is not all static with it, and
  // its distance is below own + (budget + allowed), allowed the balls' closing over `steps`.
  // Each lane must give the scalar rule's bits and answer, on every target.
  std::mt19937 random(5);
  std::uniform_real_distribution<Real> coordinate(-1, 1), unit(0, 1);
  const auto point = [&] { return Vector3r(coordinate(random), coordinate(random), coordinate(random)); };
  constexpr std::size_t kLeaves = 6, kLanes = detail::kBlockLanes;
  for (const std::size_t coordinates : {std::size_t(6), std::size_t(9)}) {
    const std::size_t fields = coordinates + detail::kLeafTailFields;
    std::vector<Real> data(kLeaves * fields * kLanes);
    const auto at = [&](std::size_t leaf, std::size_t field, std::size_t lane) -> Real& {
      return data[(leaf * fields + field) * kLanes + lane];
    };
    std::size_t compared = 0, passed = 0, ruled_out = 0;
    for (int round = 0; round < 30; ++round) {
      for (std::size_t leaf = 0; leaf < kLeaves; ++leaf)
        for (std::size_t lane = 0; lane < kLanes; ++lane) {
          Vector3r corner[3] = {point(), point(), point()};
          for (std::size_t c = 0; c < coordinates / 3; ++c)
            for (int axis = 0; axis < 3; ++axis) at(leaf, 3 * c + std::size_t(axis), lane) = corner[c][axis];
          const std::size_t tail = coordinates;
          at(leaf, tail + detail::kLeafBudget, lane) = Real(0.2) * unit(random);
          for (int axis = 0; axis < 3; ++axis)
            at(leaf, tail + detail::kLeafCentre + std::size_t(axis), lane) = Real(0.1) * coordinate(random);
          at(leaf, tail + detail::kLeafRadius, lane) = Real(0.05) * unit(random);
          for (int axis = 0; axis < 3; ++axis) {
            const Real lo = coordinate(random);
            at(leaf, tail + detail::kLeafLo + std::size_t(axis), lane) = lo;
            at(leaf, tail + detail::kLeafHi + std::size_t(axis), lane) = lo + unit(random);
          }
          for (std::size_t k = 0; k < 3; ++k)
            at(leaf, tail + detail::kLeafIds + k, lane) = detail::id_lane(std::uint32_t(random() % 40));
          at(leaf, tail + detail::kLeafStatic, lane) = random() % 4 == 0 ? Real(1) : Real(0);
        }
      const std::vector<std::uint32_t> met = {4, 1, 5, 2};
      const Vector3r p1 = point(), q1 = p1 + Real(0.5) * point();
      detail::BlockQuery query{{Real(0.1) * coordinate(random), Real(0.1) * coordinate(random),
                                Real(0.1) * coordinate(random)},
                               Real(0.05) * unit(random), Real(3), {}, {}, round % 3 == 0};
      for (int axis = 0; axis < 3; ++axis)
        query.box.lo[axis] = coordinate(random) - Real(0.5), query.box.hi[axis] = query.box.lo[axis] + Real(1.5);
      query.id[0] = detail::id_lane(std::uint32_t(random() % 40));
      query.id[1] = coordinates == 6 ? detail::id_lane(std::uint32_t(random() % 40)) : query.id[0];
      const Real own = Real(0.3) * unit(random);
      for (const std::string& target : available_simd_targets()) {
        force_simd_target(target);
        const std::size_t room = met.size() * kLanes + detail::kSegmentBatchLanes;
        std::vector<Real> squared(room), allowed(room);
        std::vector<std::uint32_t> within(room), expected;
        const std::size_t found =
            coordinates == 6
                ? detail::segments_within_leaves(p1, q1, own, query, data.data(), met.data(),
                                                 met.size(), squared.data(), allowed.data(), within.data())
                : detail::triangles_within_leaves(p1, own, query, data.data(), met.data(), met.size(),
                                                  squared.data(), allowed.data(), within.data());
        for (std::size_t b = 0; b < met.size(); ++b)
          for (std::size_t lane = 0; lane < kLanes; ++lane) {
            const std::size_t leaf = met[b], tail = coordinates, k = b * kLanes + lane;
            const auto v = [&](std::size_t field) {
              return Vector3r(at(leaf, field, lane), at(leaf, field + 1, lane), at(leaf, field + 2, lane));
            };
            bool may = true;
            for (int axis = 0; axis < 3; ++axis)
              may = may && at(leaf, tail + detail::kLeafLo + std::size_t(axis), lane) <= query.box.hi[axis] &&
                    query.box.lo[axis] <= at(leaf, tail + detail::kLeafHi + std::size_t(axis), lane);
            for (std::size_t id = 0; id < 3; ++id)
              for (const Real mine : query.id)
                may = may && std::memcmp(&at(leaf, tail + detail::kLeafIds + id, lane), &mine, sizeof(Real)) != 0;
            may = may && !(query.all_static && at(leaf, tail + detail::kLeafStatic, lane) != 0);
            if (!may) {
              ++ruled_out;
              continue;
            }
            const Real dx = query.centre[0] - at(leaf, tail + detail::kLeafCentre, lane),
                       dy = query.centre[1] - at(leaf, tail + detail::kLeafCentre + 1, lane),
                       dz = query.centre[2] - at(leaf, tail + detail::kLeafCentre + 2, lane);
            const Real closing = query.steps * (query.radius + at(leaf, tail + detail::kLeafRadius, lane) +
                                                std::sqrt(dx * dx + dy * dy + dz * dz));
            const Real distance =
                coordinates == 6 ? detail::squared_segment_distance(p1, q1, v(0), v(3))
                                 : detail::squared_point_triangle_distance(p1, v(0), v(3), v(6));
            EXPECT_EQ(std::memcmp(&allowed[k], &closing, sizeof(Real)), 0) << target;
            EXPECT_EQ(std::memcmp(&squared[k], &distance, sizeof(Real)), 0) << target;
            const Real limit = own + (at(leaf, tail + detail::kLeafBudget, lane) + closing);
            if (distance < limit * limit) expected.push_back(std::uint32_t(k));
            ++compared;
          }
        EXPECT_EQ(std::vector<std::uint32_t>(within.begin(), within.begin() + std::ptrdiff_t(found)),
                  expected)
            << target << (coordinates == 6 ? " segments" : " triangles");
        passed += found;
      }
    }
    force_simd_target("");
    EXPECT_GT(compared, 200u);
    EXPECT_GT(ruled_out, 200u);
    EXPECT_GT(passed, compared / 10);
    EXPECT_LT(passed, compared);
  }
}

TEST(SelfCollision, TheLeafScanFindsExactlyTheMembersWhoseBoxMeetsOnEveryTarget) {
  // A re-box queries the build's leaves by box (lanes_meeting_box, leaf_scan.cpp): of the
  // met leaves' members, those whose box overlaps the query's, as positions
  // b · kBlockLanes + lane in order, on every target. Boxes touching the query's at a face
  // meet (≤ both ways); an empty box (a padding lane's) meets nothing. (The re-box path
  // that calls it, padding members included, is covered by the contact and hash tests.)
  std::mt19937 random(11);
  std::uniform_real_distribution<Real> coordinate(-1, 1), unit(0, 1);
  constexpr std::size_t kLeaves = 7, kLanes = detail::kBlockLanes, kCoordinates = 6;
  constexpr std::size_t kFields = kCoordinates + detail::kLeafTailFields;
  std::vector<Real> data(kLeaves * kFields * kLanes, Real(0));
  const auto at = [&](std::size_t leaf, std::size_t field, std::size_t lane) -> Real& {
    return data[(leaf * kFields + kCoordinates + field) * kLanes + lane];
  };
  std::size_t compared = 0, met_total = 0;
  for (int round = 0; round < 40; ++round) {
    Aabb query;
    for (int axis = 0; axis < 3; ++axis)
      query.lo[axis] = coordinate(random) - Real(0.3), query.hi[axis] = query.lo[axis] + Real(0.8);
    for (std::size_t leaf = 0; leaf < kLeaves; ++leaf)
      for (std::size_t lane = 0; lane < kLanes; ++lane)
        for (std::size_t axis = 0; axis < 3; ++axis) {
          Real lo = coordinate(random), hi = lo + Real(0.5) * unit(random);
          if (random() % 16 == 0) hi = query.lo[axis];  // touching at a face: meets
          if (random() % 16 == 0) lo = query.hi[axis], hi = lo + Real(0.1);
          if (leaf == 3 && lane % 5 == 0)  // empty, as a padding lane's
            lo = std::numeric_limits<Real>::max(), hi = std::numeric_limits<Real>::lowest();
          at(leaf, detail::kLeafLo + axis, lane) = lo;
          at(leaf, detail::kLeafHi + axis, lane) = hi;
        }
    const std::vector<std::uint32_t> met = {5, 0, 3, 6, 2};
    std::vector<std::uint32_t> expected;
    for (std::size_t b = 0; b < met.size(); ++b)
      for (std::size_t lane = 0; lane < kLanes; ++lane) {
        bool meets = true;
        for (std::size_t axis = 0; axis < 3; ++axis)
          meets = meets && at(met[b], detail::kLeafLo + axis, lane) <= query.hi[axis] &&
                  query.lo[axis] <= at(met[b], detail::kLeafHi + axis, lane);
        if (meets) expected.push_back(std::uint32_t(b * kLanes + lane));
        ++compared;
      }
    met_total += expected.size();
    for (const std::string& target : available_simd_targets()) {
      force_simd_target(target);
      std::vector<std::uint32_t> meeting(met.size() * kLanes + detail::kSegmentBatchLanes);
      const std::size_t found =
          detail::lanes_meeting_box(query, data.data(), kFields, kCoordinates + detail::kLeafLo,
                                    met.data(), met.size(), meeting.data());
      EXPECT_EQ(std::vector<std::uint32_t>(meeting.begin(), meeting.begin() + std::ptrdiff_t(found)),
                expected)
          << target;
    }
  }
  force_simd_target("");
  EXPECT_GT(met_total, compared / 20);
  EXPECT_LT(met_total, compared / 2);
}

TEST(SelfCollision, AFoldedClothHasExactlyTheBruteForceContacts) {
  const FoldedCloth cloth(24);
  SelfCollision collision(cloth.grid.triangle_indices, cloth.state.size());
  const SelfCollisionSettings settings{Real(0.4) * cloth.spacing(), Real(0.1) * cloth.spacing()};
  Contacts contacts;
  collision.detect(cloth.state, settings, contacts);
  const Contacts expected = brute_force(cloth, collision, settings.thickness + settings.margin);
  EXPECT_GT(expected.triangle_point_count(), 20u);
  EXPECT_GT(expected.edge_edge_count(), 20u);
  EXPECT_EQ(contacts.triangle_point, expected.triangle_point);
  EXPECT_EQ(contacts.edge_edge, expected.edge_edge);
}

TEST(SelfCollision, APointLikeEdgeHasExactlyTheBruteForceContacts) {
  // A triangle with two corners at one place has a point-like edge (0, 1), which a build
  // measures by the scalar rule; it lies 0.05 under the edge (3, 4) of another triangle,
  // within the reach 0.1.
  FoldedCloth cloth(2);  // for brute_force: its state is replaced
  const std::vector<Vector3r> positions = {{0, 0, 0},     {0, 0, 0},    {0, 0, 1},
                                           {-1, Real(0.05), 0}, {1, Real(0.05), 0}, {0, Real(0.05), 2}};
  cloth.state = ParticleState(positions, std::vector<Real>(positions.size(), Real(1)));
  const std::vector<std::uint32_t> triangles = {0, 1, 2, 3, 4, 5};
  SelfCollision collision(triangles, positions.size());
  const SelfCollisionSettings settings{Real(0.08), Real(0.02)};
  Contacts contacts;
  collision.detect(cloth.state, settings, contacts);
  const Contacts expected = brute_force(cloth, collision, settings.thickness + settings.margin);
  const std::vector<ParticleIndex> point_like_pair = {0, 1, 3, 4};
  EXPECT_NE(std::search(expected.edge_edge.begin(), expected.edge_edge.end(),
                        point_like_pair.begin(), point_like_pair.end()),
            expected.edge_edge.end());
  EXPECT_EQ(contacts.triangle_point, expected.triangle_point);
  EXPECT_EQ(contacts.edge_edge, expected.edge_edge);
}

/// The folded cloth's top layer moving down at a constant 0.05 h per substep, a skin of
/// 0.01 h for rounding and a horizon of 4 (at that speed the paths close 3/4 of the reach in
/// 7 substeps).
struct ApproachingLayers {
  FoldedCloth cloth{24};
  ParticleState& s = cloth.state;
  SelfCollisionSettings settings{Real(0.4) * cloth.spacing(), Real(0.1) * cloth.spacing()};

  ApproachingLayers() {
    for (std::size_t i = 0; i < s.size(); ++i) s.previous_y[i] = s.y[i] + (s.previous_y[i] - s.y[i]) / 4;
    settings.skin = Real(0.01) * cloth.spacing();
    settings.horizon = 4;
  }
  SelfCollision collision() const { return SelfCollision(cloth.grid.triangle_indices, s.size()); }
  /// One more substep of the same motion.
  void next_substep() {
    for (std::size_t i = 0; i < s.size(); ++i) {
      const Real step = s.y[i] - s.previous_y[i];
      s.previous_y[i] = s.y[i];
      s.y[i] += step;
    }
  }
};

TEST(SelfCollision, RefiningADetectionOverFourSubstepsGivesEachSubstepsOwnContacts) {
  // The approaching layers: a detection puts each particle on the path of its motion, so it
  // still covers each of the next four substeps of the same motion, and refined there lists
  // what a detection at that substep finds (and no more).
  ApproachingLayers layers;
  ParticleState& s = layers.s;
  const SelfCollisionSettings& settings = layers.settings;
  SelfCollision once = layers.collision(), every = layers.collision();
  Contacts first, refined, direct;
  EXPECT_FALSE(once.covers(s)) << "no detection yet";
  once.detect(s, settings, first);
  std::size_t changes = 0;
  std::vector<ParticleIndex> previous_list = first.triangle_point;
  for (int substep = 1; substep <= 4; ++substep) {
    layers.next_substep();
    EXPECT_TRUE(once.covers(s)) << substep;
    once.refine(s, settings, refined);
    every.detect(s, settings, direct);
    EXPECT_EQ(refined.triangle_point, direct.triangle_point) << substep;
    EXPECT_EQ(refined.triangle_point_triangle, direct.triangle_point_triangle) << substep;
    EXPECT_EQ(refined.edge_edge, direct.edge_edge) << substep;
    EXPECT_LE(refined.triangle_point_count() + refined.edge_edge_count(), once.candidate_count());
    changes += refined.triangle_point != previous_list;
    previous_list = refined.triangle_point;
  }
  EXPECT_GE(changes, 2u) << "the contacts change as the layers approach";
  EXPECT_GT(once.candidate_count(), direct.triangle_point_count() + direct.edge_edge_count());
  layers.next_substep();
  EXPECT_FALSE(once.covers(s)) << "past the horizon";
}

TEST(SelfCollision, TheFilterCreditsTheMotionTheHorizonHasLeft) {
  // The approaching layers: a candidate's bound at substep τ is its least over the horizon
  // plus the (T − τ) ρ of relative motion still to come, so early in the horizon their pairs
  // are ruled out unmeasured, later they are measured. Each substep still lists exactly a
  // detection's contacts.
  ApproachingLayers layers;
  ParticleState& s = layers.s;
  const SelfCollisionSettings& settings = layers.settings;
  SelfCollision once = layers.collision(), every = layers.collision();
  Contacts refined, direct;
  once.detect(s, settings, refined);
  std::vector<std::size_t> measured;
  for (int substep = 1; substep <= 4; ++substep) {
    layers.next_substep();
    ASSERT_TRUE(once.covers(s)) << substep;
    once.refine(s, settings, refined);
    every.detect(s, settings, direct);
    EXPECT_EQ(refined.triangle_point, direct.triangle_point) << substep;
    EXPECT_EQ(refined.edge_edge, direct.edge_edge) << substep;
    measured.push_back(once.measured_candidate_count());
  }
  // Measured (float and double alike): 166, 744, 1,962, 3,497; with the horizon's end bound
  // on every substep, 3,497 each time.
  for (std::size_t k = 1; k < measured.size(); ++k)
    EXPECT_GE(measured[k], measured[k - 1]) << "substep " << k + 1;
  EXPECT_LT(2 * measured.front(), measured.back()) << "the first substep credits 3 ρ more";
}

TEST(SelfCollision, TheHorizonShortensForFastPathsAndUpdatesStayExact) {
  // The top layer moving down at a constant speed, horizon at most 8. At 0.02 h per substep
  // the paths close 3/4 of the reach (0.5 h) in 18 substeps: a build serves all 8 substeps
  // after it. At 0.2 h per substep they close it in 1.9: a build every second substep, the
  // substep between refined. Every update lists exactly a detection's contacts.
  for (const Real speed : {Real(0.02), Real(0.2)}) {
    FoldedCloth cloth(24);
    ParticleState& s = cloth.state;
    const Real h = cloth.spacing();
    for (std::size_t i = 0; i < s.size(); ++i)
      if (s.previous_y[i] != s.y[i]) s.previous_y[i] = s.y[i] + speed * h;
    SelfCollision updated(cloth.grid.triangle_indices, s.size()), every(cloth.grid.triangle_indices, s.size());
    SelfCollisionSettings settings{Real(0.4) * h, Real(0.1) * h};
    settings.skin = Real(0.01) * h;
    settings.horizon = 8;
    Contacts by_update, direct;
    std::vector<SelfCollision::Update> done;
    for (int substep = 0; substep < 10; ++substep) {
      done.push_back(updated.update(s, settings, by_update));
      every.detect(s, settings, direct);
      EXPECT_EQ(by_update.triangle_point, direct.triangle_point) << speed << " " << substep;
      EXPECT_EQ(by_update.edge_edge, direct.edge_edge) << speed << " " << substep;
      for (std::size_t i = 0; i < s.size(); ++i) {
        const Real step = s.y[i] - s.previous_y[i];
        s.previous_y[i] = s.y[i];
        s.y[i] += step;
      }
    }
    using U = SelfCollision::Update;
    const std::vector<U> expected =
        speed < Real(0.1) ? std::vector<U>{U::built, U::refined, U::refined, U::refined, U::refined,
                                           U::refined, U::refined, U::refined, U::refined, U::built}
                          : std::vector<U>{U::built, U::refined, U::built, U::refined, U::built,
                                           U::refined, U::built, U::refined, U::built, U::refined};
    EXPECT_EQ(done, expected) << speed;
  }
}

TEST(SelfCollision, AHorizonSetPastAnyUseIsCappedAndDetectionStaysExact) {
  // 90 % of the cloth at rest, so a build keeps the horizon setting (its fast particles'
  // speed is 0), and a patch of the upper layer diving at 0.2 h per substep. Whatever the
  // setting, up to the largest size_t, a detection lists what the brute-force loop lists.
  // (Before the cap, horizon + 1 wrapped to 0 at the largest: no allowance for the paths,
  // contacts lost.)
  for (const std::size_t horizon :
       {std::size_t(16), std::size_t(1) << 20, std::numeric_limits<std::size_t>::max()}) {
    FoldedCloth cloth(24);
    ParticleState& s = cloth.state;
    const Real h = cloth.spacing();
    for (std::size_t i = 0; i < s.size(); ++i) {
      const bool patch = s.y[i] > Real(0.5) * h && s.x[i] < Real(0.3) && s.z[i] > Real(0.4) &&
                         s.z[i] < Real(0.6);
      s.previous_y[i] = patch ? s.y[i] + Real(0.2) * h : s.y[i];
    }
    SelfCollision collision(cloth.grid.triangle_indices, s.size());
    SelfCollisionSettings settings{Real(0.4) * h, Real(0.1) * h};
    settings.skin = Real(0.01) * h;
    settings.horizon = horizon;
    Contacts contacts;
    collision.detect(s, settings, contacts);
    const Contacts expected = brute_force(cloth, collision, settings.thickness + settings.margin);
    EXPECT_GT(expected.triangle_point_count(), 0u) << horizon;
    EXPECT_EQ(contacts.triangle_point, expected.triangle_point) << horizon;
    EXPECT_EQ(contacts.edge_edge, expected.edge_edge) << horizon;
  }
}

TEST(SelfCollision, UpdateBuildsAgainWhenTheReachGrows) {
  // The folded cloth at rest; the margin grows from 0.05 h to 0.2 h between two updates. The
  // first build's candidates were chosen for the shorter reach: the second update builds
  // and lists a detection's contacts (before: 0 + 9 where a detection finds 3 + 36).
  FoldedCloth cloth(24);
  ParticleState& s = cloth.state;
  const Real h = cloth.spacing();
  for (std::size_t i = 0; i < s.size(); ++i) s.previous_y[i] = s.y[i];
  SelfCollision updated(cloth.grid.triangle_indices, s.size()), fresh(cloth.grid.triangle_indices, s.size());
  SelfCollisionSettings settings{Real(0.3) * h, Real(0.05) * h};
  settings.skin = Real(0.01) * h;
  Contacts by_update, direct;
  EXPECT_EQ(updated.update(s, settings, by_update), SelfCollision::Update::built);
  EXPECT_EQ(updated.update(s, settings, by_update), SelfCollision::Update::refined);
  settings.margin = Real(0.2) * h;
  EXPECT_EQ(updated.update(s, settings, by_update), SelfCollision::Update::built);
  fresh.detect(s, settings, direct);
  EXPECT_GT(direct.triangle_point_count(), 0u);
  EXPECT_EQ(by_update.triangle_point, direct.triangle_point);
  EXPECT_EQ(by_update.edge_edge, direct.edge_edge);
  settings.margin = Real(0.1) * h;  // a shorter reach keeps the candidates: a superset
  EXPECT_EQ(updated.update(s, settings, by_update), SelfCollision::Update::refined);
  fresh.detect(s, settings, direct);
  EXPECT_EQ(by_update.triangle_point, direct.triangle_point);
  EXPECT_EQ(by_update.edge_edge, direct.edge_edge);
}

/// The folded cloth's particles on prescribed trajectories: the bulk drifting and falling,
/// the lower layer still, and two patches of the upper layer (three with `third_patch`)
/// whose particles go straight, curve, stop, reverse or speed up, by a hash of the particle
/// (kind 0) or all alike (kind 1: curving). Substep k's start is the trajectory at k, its
/// prediction the trajectory at k + 1 plus a little noise (3·10⁻⁴ h), and with `kicks` one
/// particle in about 97 kicked by up to 0.15 h.
struct PrescribedPaths {
  FoldedCloth cloth;
  std::vector<Vector3r> rest;
  Real h;
  explicit PrescribedPaths(std::size_t n) : cloth(n), h(cloth.spacing()) {
    for (std::size_t i = 0; i < cloth.state.size(); ++i) rest.push_back(cloth.state.position(i));
  }
  Vector3r at(std::size_t i, Real k, int kind, bool third_patch) const {
    const Vector3r& p = rest[i];
    const Vector3r bulk(Real(0.05) * h * k, Real(-0.002) * h * k * k, Real(0.01) * h * k);
    const auto near = [&](Real cx, Real cz, Real size) {
      return std::abs(p.x() - cx) < size && std::abs(p.z() - cz) < size;
    };
    const bool upper = p.y() > Real(0.4) * h;
    const bool patch = near(Real(0.2), Real(0.3), Real(0.12)) || near(Real(0.35), Real(0.75), Real(0.1)) ||
                       (third_patch && near(Real(0.1), Real(0.55), Real(0.1)));
    if (!upper || !patch) return p + bulk;
    const Real phase = Real(7) * p.x() + Real(5) * p.z();
    const std::uint32_t hash = std::uint32_t(i) * 2654435761u;
    const Real speed = Real(0.04) * h * (1 + Real(0.5) * std::sin(phase));
    const Real turn = Real(3) + Real((hash >> 8) % 7);  // when it stops or reverses
    Vector3r own = Vector3r::Zero();
    switch (kind == 0 ? int((hash >> 16) % 5) : 1) {
      case 0: own.y() = -speed * k; break;
      case 1: {
        const Real w = Real(0.4) + Real(0.3) * std::sin(phase);
        own = Real(0.3) * h * Vector3r(std::cos(w * k + phase) - std::cos(phase), Real(-0.1) * k,
                                       std::sin(w * k + phase) - std::sin(phase));
        break;
      }
      case 2: own.y() = -speed * std::min(k, turn); break;
      case 3: own.y() = k < turn ? -speed * k : -speed * turn + Real(1.5) * speed * (k - turn); break;
      case 4: own.y() = Real(-0.004) * h * k * k; break;
    }
    return p + bulk + own;
  }
  void set_substep(int k, int kind, bool third_patch, std::uint32_t seed, bool kicks) {
    ParticleState& s = cloth.state;
    std::mt19937 random(seed * 7919u + std::uint32_t(k));
    std::uniform_real_distribution<Real> unit(-1, 1);
    for (std::size_t i = 0; i < s.size(); ++i) {
      const Vector3r start = at(i, Real(k), kind, third_patch);
      Vector3r noise(unit(random), unit(random), unit(random));
      noise *= Real(0.0003) * h * (kicks && random() % 97 == 0 ? 500 : 1);
      const Vector3r end = at(i, Real(k + 1), kind, third_patch) + noise;
      s.previous_x[i] = start.x(), s.previous_y[i] = start.y(), s.previous_z[i] = start.z();
      s.x[i] = end.x(), s.y[i] = end.y(), s.z[i] = end.z();
    }
  }
};

TEST(SelfCollision, UpdatesAndRefinesMatchADetectionOnPathsThatCurveStopReverseAndJump) {
  // Every substep of 40, update() and a refine() loop (while covers() holds, else a
  // detection) list exactly what a detection of that substep lists, on trajectories that
  // leave any straight path: horizons 2 and 5, rooms of 1 and 2 substeps, with and without
  // edge–edge contacts. (Written from an independent review: a re-anchoring that forgot the
  // substep, or a re-box that skipped triangles re-boxed before, passed every other test.)
  std::size_t contacts = 0, by_kind[3] = {0, 0, 0};
  std::uint32_t seed = 1;
  for (const int motion : {0, 1, 10})
    for (const std::size_t horizon : {std::size_t(2), std::size_t(5)})
      for (const Real scale : {Real(1), Real(2)}) {
        PrescribedPaths paths(20);
        SelfCollisionSettings settings{Real(0.4) * paths.h, Real(0.1) * paths.h};
        settings.skin = Real(0.01) * paths.h;
        settings.motion_scale = scale;
        settings.horizon = horizon;
        settings.edge_edge = seed % 5 != 0;
        const std::vector<std::uint32_t>& mesh = paths.cloth.grid.triangle_indices;
        const std::size_t n = paths.cloth.state.size();
        SelfCollision updated(mesh, n), refined(mesh, n), every(mesh, n);
        Contacts by_update, by_refine, direct;
        for (int k = 0; k < 40; ++k) {
          paths.set_substep(k, motion % 10, motion >= 10, seed, seed % 3 == 0);
          ++by_kind[int(updated.update(paths.cloth.state, settings, by_update))];
          if (k > 0 && refined.covers(paths.cloth.state))
            refined.refine(paths.cloth.state, settings, by_refine);
          else
            refined.detect(paths.cloth.state, settings, by_refine);
          every.detect(paths.cloth.state, settings, direct);
          contacts += direct.triangle_point_count() + direct.edge_edge_count();
          const std::string where = "motion " + std::to_string(motion) + " horizon " +
                                    std::to_string(horizon) + " scale " + std::to_string(scale) +
                                    " substep " + std::to_string(k);
          ASSERT_EQ(by_update.triangle_point, direct.triangle_point) << where;
          ASSERT_EQ(by_update.edge_edge, direct.edge_edge) << where;
          ASSERT_EQ(by_refine.triangle_point, direct.triangle_point) << where;
          ASSERT_EQ(by_refine.edge_edge, direct.edge_edge) << where;
        }
        ++seed;
      }
  EXPECT_GT(contacts, 1000u);
  EXPECT_GT(by_kind[int(SelfCollision::Update::refined)], 50u);
  EXPECT_GT(by_kind[int(SelfCollision::Update::reboxed)], 50u);
  EXPECT_GT(by_kind[int(SelfCollision::Update::built)], 50u);
}

TEST(SelfCollision, AParticleOffItsPathIsNotCoveredThoughItMovesLikeTheBulk) {
  // The top layer moves down at 0.2 h per substep and the detection puts it on that path.
  // One particle of it that stops dead (its motion now the bottom layer's, which is the
  // bulk's) has left its path though it moves like the bulk: not covered, and update()
  // re-boxes it and lists exactly a detection's contacts.
  FoldedCloth cloth(24);
  ParticleState& s = cloth.state;
  const Real h = cloth.spacing();
  SelfCollision updated(cloth.grid.triangle_indices, s.size()), every(cloth.grid.triangle_indices, s.size());
  SelfCollisionSettings settings{Real(0.4) * h, Real(0.1) * h};
  settings.skin = Real(0.05) * h;
  Contacts by_update, direct;
  ASSERT_EQ(updated.update(s, settings, by_update), SelfCollision::Update::built);
  std::size_t stopped = s.size();
  for (std::size_t i = 0; i < s.size() && stopped == s.size(); ++i)
    if (s.y[i] != s.previous_y[i] && s.inverse_mass[i] != 0) stopped = i;
  ASSERT_LT(stopped, s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    const Real step = i == stopped ? Real(0) : s.y[i] - s.previous_y[i];
    s.previous_y[i] = s.y[i];
    s.y[i] += step;
  }
  EXPECT_FALSE(updated.covers(s)) << "particle " << stopped << " stopped off its path";
  EXPECT_EQ(updated.update(s, settings, by_update), SelfCollision::Update::reboxed);
  every.detect(s, settings, direct);
  EXPECT_EQ(by_update.triangle_point, direct.triangle_point);
  EXPECT_EQ(by_update.edge_edge, direct.edge_edge);
}

TEST(SelfCollision, ADetectionStopsCoveringWhenAParticleOutrunsItsBudget) {
  // Budgets for one substep of motion and a skin of 0.1 h: the cloth drifting as a whole by
  // 5 h stays covered, one particle moving 0.1 h against the rest does not, and neither does
  // a substep in which it moves that much.
  FoldedCloth cloth(16);
  ParticleState& s = cloth.state;
  const Real h = cloth.spacing();
  for (std::size_t i = 0; i < s.size(); ++i) s.previous_y[i] = s.y[i];  // at rest
  SelfCollision collision(cloth.grid.triangle_indices, s.size());
  SelfCollisionSettings settings{Real(0.4) * h, Real(0.1) * h};
  settings.skin = Real(0.1) * h;
  Contacts contacts;
  collision.detect(s, settings, contacts);
  EXPECT_TRUE(collision.covers(s));
  ParticleState drifted = s;
  for (std::size_t i = 0; i < s.size(); ++i) drifted.x[i] += 5 * h, drifted.previous_x[i] += 5 * h;
  EXPECT_TRUE(collision.covers(drifted)) << "a drift of the whole cloth is no way";
  ParticleState moved = s;
  moved.previous_z[40] += Real(0.1) * h, moved.z[40] += Real(0.1) * h;
  EXPECT_FALSE(collision.covers(moved)) << "particle 40 went twice its half budget";
  ParticleState fast = s;
  fast.z[40] += Real(0.1) * h;
  EXPECT_FALSE(collision.covers(fast)) << "particle 40 moves 0.1 h in this substep";
}

TEST(SelfCollision, SwitchingEdgeEdgeContactsBetweenUpdatesBuildsAgain) {
  // A flat 20 × 20 sheet (spacing 1) and two loose triangles. The last build's edge grid,
  // records and candidates belong to its edge_edge setting: an update with the other one
  // builds, and every update gives the contacts of a detection of its own. (Before, a
  // re-box with edge–edge on after a build without it wrote past the edges' records, and
  // switching off and on again left re-boxed edges' records stale: 0 edge–edge contacts
  // where a detection finds 4.)
  struct Sheet {
    std::vector<std::uint32_t> triangles;
    std::vector<Real> x, y, z, w;
    std::size_t count = 0, first_probe = 0, second_probe = 0;
    void add(Real a, Real b, Real c) { x.push_back(a), y.push_back(b), z.push_back(c), w.push_back(1), ++count; }
    void place(std::size_t i, Real a, Real b, Real c) { x[i] = a, y[i] = b, z[i] = c; }
    // At rest: the start of the substep is where it ends.
    SelfCollisionPositions positions() const {
      return {x.data(), y.data(), z.data(), x.data(), y.data(), z.data(), w.data(), count};
    }
  } sheet;
  const int n = 20;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) sheet.add(Real(i), Real(j), 0);
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const std::uint32_t a = std::uint32_t(j * n + i), b = a + 1, c = a + n, d = c + 1;
      sheet.triangles.insert(sheet.triangles.end(), {a, b, d, a, d, c});
    }
  for (std::size_t* probe : {&sheet.first_probe, &sheet.second_probe}) {
    *probe = sheet.count;
    const Real at = Real(100 * (probe == &sheet.first_probe ? 1 : 2));
    sheet.add(at, at, 50), sheet.add(at + 1, at, 50), sheet.add(at, at + 1, 50);
    const std::uint32_t p = std::uint32_t(*probe);
    sheet.triangles.insert(sheet.triangles.end(), {p, p + 1, p + 2});
  }
  const auto settings = [](bool edge_edge) {
    SelfCollisionSettings s{Real(0.1), 0};
    s.skin = Real(0.02), s.edge_edge = edge_edge;
    return s;
  };
  const auto detected = [&](bool edge_edge) {
    SelfCollision fresh(sheet.triangles, sheet.count);
    Contacts contacts;
    fresh.detect(sheet.positions(), settings(edge_edge), contacts);
    return contacts;
  };
  const std::size_t a = sheet.first_probe, b = sheet.second_probe;
  {
    SelfCollision collision(sheet.triangles, sheet.count);
    Contacts contacts;
    EXPECT_EQ(collision.update(sheet.positions(), settings(true), contacts), SelfCollision::Update::built);
    // The first probe moves with edge–edge off, then the second crosses its edge (a, a + 1)
    // 0.05 below it with edge–edge on.
    sheet.place(a, 300, 300, 10), sheet.place(a + 1, 302, 300, 10), sheet.place(a + 2, 300, 302, 10);
    EXPECT_EQ(collision.update(sheet.positions(), settings(false), contacts), SelfCollision::Update::built);
    EXPECT_EQ(contacts.edge_edge, detected(false).edge_edge);
    sheet.place(b, 301, 299, Real(9.95)), sheet.place(b + 1, 301, 301, Real(9.95)),
        sheet.place(b + 2, 303, 299, Real(9.95));
    EXPECT_EQ(collision.update(sheet.positions(), settings(true), contacts), SelfCollision::Update::built);
    const Contacts expected = detected(true);
    EXPECT_GT(expected.edge_edge_count(), 0u);
    EXPECT_EQ(contacts.edge_edge, expected.edge_edge);
    EXPECT_EQ(contacts.triangle_point, expected.triangle_point);
  }
  {
    // Edge–edge off at the build, on at the next update (a re-box before): a build, exact.
    SelfCollision collision(sheet.triangles, sheet.count);
    Contacts contacts;
    EXPECT_EQ(collision.update(sheet.positions(), settings(false), contacts), SelfCollision::Update::built);
    sheet.place(a + 2, 300, Real(300.5), Real(9.9));
    EXPECT_EQ(collision.update(sheet.positions(), settings(true), contacts), SelfCollision::Update::built);
    EXPECT_EQ(contacts.edge_edge, detected(true).edge_edge);
    EXPECT_EQ(contacts.triangle_point, detected(true).triangle_point);
  }
}

// The folded cloth of `size` at rest but for a patch of its upper layer that dives onto the
// lower one, speeding up each substep: those particles outrun the room a build gave them, so
// update() re-boxes their primitives (the rest keep their candidates), and every substep
// lists exactly what a detection of its own lists. Returns the longest candidate list a
// re-box merged its found pairs into.
std::size_t expect_updates_match_detections(std::size_t size) {
  FoldedCloth cloth(size);
  ParticleState& s = cloth.state;
  const Real h = cloth.spacing();
  for (std::size_t i = 0; i < s.size(); ++i) s.previous_y[i] = s.y[i];
  std::vector<std::size_t> patch;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (s.y[i] > Real(0.5) * h && s.x[i] < Real(0.3) && s.z[i] > Real(0.4) && s.z[i] < Real(0.6))
      patch.push_back(i);
  EXPECT_GT(patch.size(), 5u);
  SelfCollision updated(cloth.grid.triangle_indices, s.size()), every(cloth.grid.triangle_indices, s.size());
  SelfCollisionSettings settings{Real(0.4) * h, Real(0.1) * h};
  settings.motion_scale = 2;
  settings.skin = Real(0.05) * h;
  Contacts by_update, direct;
  std::size_t reboxed = 0, built = 0, longest_merged = 0;
  for (int substep = 0; substep < 6; ++substep) {
    const std::size_t longest = std::max(updated.triangle_point_candidate_count(),
                                         updated.edge_edge_candidate_count());
    const SelfCollision::Update done = updated.update(s, settings, by_update);
    reboxed += done == SelfCollision::Update::reboxed;
    built += done == SelfCollision::Update::built;
    if (done == SelfCollision::Update::reboxed) longest_merged = std::max(longest_merged, longest);
    every.detect(s, settings, direct);
    EXPECT_EQ(by_update.triangle_point, direct.triangle_point) << substep;
    EXPECT_EQ(by_update.triangle_point_triangle, direct.triangle_point_triangle) << substep;
    EXPECT_EQ(by_update.edge_edge, direct.edge_edge) << substep;
    // Next substep: the patch comes down faster, the rest stays.
    for (std::size_t i = 0; i < s.size(); ++i) s.previous_y[i] = s.y[i];
    for (const std::size_t i : patch) s.y[i] -= Real(0.03) * h * Real(substep + 1);
  }
  EXPECT_EQ(built, 1u) << "the first update builds; the patch is re-boxed after";
  EXPECT_GE(reboxed, 2u);
  EXPECT_GT(direct.triangle_point_count() + direct.edge_edge_count(), 0u);
  return longest_merged;
}

TEST(SelfCollision, UpdatesRebuildOnlyWhatOutranItsRoomAndMatchADetectionEachSubstep) {
  expect_updates_match_detections(24);
}

TEST(SelfCollision, UpdatesMatchADetectionEachSubstepWhenTheirListsAreMergedInBlocks) {
  // A re-box merges its found pairs into the candidate lists in blocks of at least 4096
  // pairs (kLeastBlock, self_collision.cpp), in parallel: on two threads, a cloth with a
  // list of at least two blocks.
  tbb::task_arena(2).execute([] { EXPECT_GE(expect_updates_match_detections(64), 2u * 4096); });
}

TEST(SelfCollision, TheFilterMeasuresOnlyWhatTheAnchorDistancesCannotRuleOut) {
  // The folded cloth at rest with a skin of 0.3 h: the layers' nearby pairs and many in-plane
  // neighbours are candidates. At rest the anchor distances rule most of them out unmeasured;
  // with every particle jittered about its room (start and motion, each up to half its
  // budget) the bound rules out fewer and the list is still exactly a detection's own.
  FoldedCloth cloth(24);
  ParticleState& s = cloth.state;
  const Real h = cloth.spacing();
  for (std::size_t i = 0; i < s.size(); ++i) s.previous_y[i] = s.y[i];
  SelfCollision reused(cloth.grid.triangle_indices, s.size()),
      fresh(cloth.grid.triangle_indices, s.size());
  SelfCollisionSettings settings{Real(0.4) * h, Real(0.1) * h};
  settings.skin = Real(0.3) * h;
  Contacts refined, direct;
  reused.detect(s, settings, refined);
  const std::size_t candidates = reused.candidate_count();
  ASSERT_GT(candidates, 1000u);
  EXPECT_LT(reused.measured_candidate_count(), candidates / 2) << "at rest: most ruled out";
  std::uint32_t seed = 12345;
  const auto jitter = [&] {  // in [-0.07 h, 0.07 h]: |3 axes| < 0.15 h, half the skin
    seed = seed * 1664525u + 1013904223u;
    return Real(0.07) * h * (Real(seed >> 8) / Real(1 << 24) * 2 - 1);
  };
  for (int round = 0; round < 3; ++round) {
    ParticleState moved = s;
    for (std::size_t i = 0; i < s.size(); ++i) {
      if (s.inverse_mass[i] == 0) continue;
      moved.previous_x[i] += jitter(), moved.previous_y[i] += jitter(), moved.previous_z[i] += jitter();
      moved.x[i] = moved.previous_x[i] + jitter();
      moved.y[i] = moved.previous_y[i] + jitter();
      moved.z[i] = moved.previous_z[i] + jitter();
    }
    ASSERT_TRUE(reused.covers(moved)) << round;
    reused.refine(moved, settings, refined);
    fresh.detect(moved, settings, direct);
    EXPECT_GT(direct.triangle_point_count() + direct.edge_edge_count(), 20u) << round;
    EXPECT_EQ(refined.triangle_point, direct.triangle_point) << round;
    EXPECT_EQ(refined.edge_edge, direct.edge_edge) << round;
    EXPECT_LT(reused.measured_candidate_count(), candidates) << round;
    EXPECT_GT(reused.measured_candidate_count(), direct.triangle_point_count() + direct.edge_edge_count())
        << round;
  }
}

TEST(SelfCollision, AFlatClothAtRestHasNoContact) {
  const io::ClothGrid grid = io::make_cloth_grid(32, 32, Real(1) / 31);
  const ParticleState state(grid.positions, std::vector<Real>(grid.vertex_count(), 1));
  const Contacts contacts = detect(grid.triangle_indices, state,
                                   SelfCollisionSettings{Real(0.4) / 31, Real(0.1) / 31});
  EXPECT_EQ(contacts.triangle_point_count(), 0u);
  EXPECT_EQ(contacts.edge_edge_count(), 0u);
}

TEST(SelfCollision, AFoldedClothFallingAsAWholeHasOnlyItsRestingContacts) {
  // Every particle moves by the same 3 h in the substep (a fall, seen by a substep): the
  // pairs cannot approach each other, so the contacts are those of the cloth at rest. A rule
  // counting each particle's own motion would put every pair within 6 h in contact.
  FoldedCloth resting(24), falling(24);
  const Real h = resting.spacing();
  for (FoldedCloth* cloth : {&resting, &falling})
    for (std::size_t i = 0; i < cloth->state.size(); ++i)
      cloth->state.previous_y[i] = cloth->state.y[i] + (cloth == &falling ? 3 * h : 0);
  const SelfCollisionSettings settings{Real(0.4) * h, Real(0.1) * h};
  const Contacts at_rest = detect(resting.grid.triangle_indices, resting.state, settings);
  const Contacts fall = detect(falling.grid.triangle_indices, falling.state, settings);
  EXPECT_EQ(fall.triangle_point, at_rest.triangle_point);
  EXPECT_EQ(fall.edge_edge, at_rest.edge_edge);
  EXPECT_LT(fall.triangle_point_count(), 100u);
}

TEST(SelfCollision, TheSameContactsOnOneAndTwoThreads) {
  const FoldedCloth cloth(64);
  const SelfCollisionSettings settings{Real(0.4) * cloth.spacing(), Real(0.1) * cloth.spacing()};
  const auto contacts_on = [&](int threads) {
    Contacts contacts;
    tbb::task_arena(threads).execute([&] {
      SelfCollision collision(cloth.grid.triangle_indices, cloth.state.size());
      collision.detect(cloth.state, settings, contacts);
      collision.detect(cloth.state, settings, contacts);  // buffers reused: same answer
    });
    return contacts;
  };
  const Contacts one = contacts_on(1), two = contacts_on(2);
  EXPECT_GT(one.triangle_point_count(), 50u);
  EXPECT_EQ(one.triangle_point, two.triangle_point);
  EXPECT_EQ(one.edge_edge, two.edge_edge);
}

}  // namespace self_collision_tests
}  // namespace tessera
