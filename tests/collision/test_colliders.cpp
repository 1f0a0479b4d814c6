// Static colliders against known answers: each analytic shape's signed distance, normal and
// closest point outside, on and inside (and at its ambiguous points); the mesh collider against
// the analytic box and sphere it approximates and against a brute-force closest triangle;
// contact generation's selection, fields, tunnelling rule and independence of the thread
// count; bad input named.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <tbb/task_arena.h>

#include <tessera/collision/colliders.hpp>
#include <tessera/core/error.hpp>
#include <tessera/io/mesh_readers.hpp>

namespace tessera {
namespace colliders_tests {

constexpr Real kTolerance = kDoublePrecision ? Real(1e-9) : Real(2e-5);

void expect_near(const Vector3r& actual, const Vector3r& expected, Real tolerance = kTolerance) {
  EXPECT_LE((actual - expected).norm(), tolerance)
      << "actual " << actual.transpose() << " expected " << expected.transpose();
}

void expect_query(const Collider& collider, const Vector3r& p, Real distance,
                  const Vector3r& normal, const Vector3r& point) {
  const SurfaceQuery q = closest_surface(collider, p);
  EXPECT_NEAR(q.distance, distance, kTolerance) << "at " << p.transpose();
  expect_near(q.normal, normal);
  expect_near(q.point, point);
}

/// Unit normal, finite everything, point = p − distance · normal.
void expect_consistent(const SurfaceQuery& q, const Vector3r& p, Real scale = 1) {
  ASSERT_TRUE(std::isfinite(q.distance)) << "at " << p.transpose();
  ASSERT_TRUE(q.normal.allFinite() && q.point.allFinite()) << "at " << p.transpose();
  EXPECT_NEAR(q.normal.norm(), 1, 10 * kTolerance) << "at " << p.transpose();
  expect_near(q.point, p - q.distance * q.normal, 10 * kTolerance * scale);
}

testing::AssertionResult contains(const std::string& message, const std::string& part) {
  if (message.find(part) != std::string::npos) return testing::AssertionSuccess();
  return testing::AssertionFailure() << "\"" << message << "\" does not contain \"" << part << "\"";
}

std::string error_of(const auto& call) {
  try {
    call();
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "(no error)";
}

// ------------------------------------------------------------------------------ meshes
struct TestMesh {
  std::vector<Vector3r> positions;
  std::vector<ParticleIndex> triangles;
};

/// The cube [-h, h]³, 12 triangles wound counter-clockwise seen from outside.
TestMesh cube_mesh(Real h) {
  TestMesh mesh;
  for (int i = 0; i < 8; ++i)
    mesh.positions.emplace_back(i & 1 ? h : -h, i & 2 ? h : -h, i & 4 ? h : -h);
  // Each face as a quad counter-clockwise from outside.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads)
    for (int t : {0, 2}) {
      mesh.triangles.push_back(ParticleIndex(q[0]));
      mesh.triangles.push_back(ParticleIndex(q[t == 0 ? 1 : 2]));
      mesh.triangles.push_back(ParticleIndex(q[t == 0 ? 2 : 3]));
    }
  return mesh;
}

/// An icosahedron subdivided `levels` times, vertices on the sphere of `radius`, outward.
TestMesh icosphere(int levels, Real radius) {
  const Real g = (1 + std::sqrt(Real(5))) / 2;
  std::vector<Vector3r> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                             {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                             {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  std::vector<std::array<ParticleIndex, 3>> faces = {
      {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<ParticleIndex, ParticleIndex>, ParticleIndex> midpoints;
    const auto midpoint = [&](ParticleIndex a, ParticleIndex b) {
      const auto key = std::minmax(a, b);
      auto [it, inserted] = midpoints.try_emplace(key, ParticleIndex(v.size()));
      if (inserted) v.push_back((v[a] + v[b]).normalized());
      return it->second;
    };
    std::vector<std::array<ParticleIndex, 3>> next;
    for (const auto& [a, b, c] : faces) {
      const ParticleIndex ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      next.push_back({a, ab, ca});
      next.push_back({b, bc, ab});
      next.push_back({c, ca, bc});
      next.push_back({ab, bc, ca});
    }
    faces = next;
  }
  TestMesh mesh;
  for (const auto& p : v) mesh.positions.push_back(radius * p);
  for (const auto& f : faces) mesh.triangles.insert(mesh.triangles.end(), f.begin(), f.end());
  return mesh;
}

/// A wavy open sheet z = 0.2 sin(x) cos(y) over [-2, 2]², normals up (+z side is outside).
TestMesh wavy_sheet(int n) {
  TestMesh mesh;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const Real x = -2 + 4 * Real(i) / n, y = -2 + 4 * Real(j) / n;
      mesh.positions.emplace_back(x, y, Real(0.2) * std::sin(x) * std::cos(y));
    }
  const auto at = [&](int i, int j) { return ParticleIndex(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      mesh.triangles.insert(mesh.triangles.end(), {at(i, j), at(i + 1, j), at(i + 1, j + 1),
                                                   at(i, j), at(i + 1, j + 1), at(i, j + 1)});
  return mesh;
}

MeshCollider collider_of(const TestMesh& mesh) {
  return MeshCollider(mesh.positions, mesh.triangles);
}

/// Closest distance to a triangle computed differently from the library (projection onto the
/// plane if it lands inside, else the nearest of the three edges): the brute-force reference.
Real reference_distance(const Vector3r& p, const Vector3r& a, const Vector3r& b,
                        const Vector3r& c) {
  const Vector3r n = (b - a).cross(c - a).normalized();
  const Vector3r projected = p - n.dot(p - a) * n;
  const auto inside_edge = [&](const Vector3r& u, const Vector3r& w) {
    return (w - u).cross(projected - u).dot(n) >= 0;
  };
  if (inside_edge(a, b) && inside_edge(b, c) && inside_edge(c, a)) return (p - projected).norm();
  const auto to_segment = [&](const Vector3r& u, const Vector3r& w) {
    const Real t = std::clamp((p - u).dot(w - u) / (w - u).squaredNorm(), Real(0), Real(1));
    return (p - (u + t * (w - u))).norm();
  };
  return std::min({to_segment(a, b), to_segment(b, c), to_segment(c, a)});
}

std::vector<Vector3r> random_points(std::size_t count, Real extent, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<Real> coordinate(-extent, extent);
  std::vector<Vector3r> points(count);
  for (auto& p : points) p = Vector3r(coordinate(rng), coordinate(rng), coordinate(rng));
  return points;
}

// ------------------------------------------------------------------------ analytic shapes
TEST(Colliders, PlaneDistanceNormalAndPoint) {
  const Vector3r n = Vector3r(1, 2, 2) / 3;
  const Collider plane = PlaneCollider{n, Real(1.5)};
  // Above, on and below, written as (surface point) + d · n.
  const Vector3r on = Vector3r(Real(0.5), Real(0.25), Real(0.25)) + Real(1.5) * n -
                      n.dot(Vector3r(Real(0.5), Real(0.25), Real(0.25))) * n;
  for (const Real d : {Real(2), Real(0), Real(-0.75)}) expect_query(plane, on + d * n, d, n, on);
}

TEST(Colliders, SphereOutsideOnInsideAndCentre) {
  const Vector3r c(1, -2, Real(0.5));
  const Collider sphere = SphereCollider{c, 2};
  expect_query(sphere, c + Vector3r(0, 0, 5), 3, Vector3r::UnitZ(), c + Vector3r(0, 0, 2));
  expect_query(sphere, c + Vector3r(-2, 0, 0), 0, -Vector3r::UnitX(), c + Vector3r(-2, 0, 0));
  expect_query(sphere, c + Vector3r(0, Real(-0.5), 0), Real(-1.5), -Vector3r::UnitY(),
               c + Vector3r(0, -2, 0));
  // The centre: the documented +y, never NaN.
  expect_query(sphere, c, -2, Vector3r::UnitY(), c + Vector3r(0, 2, 0));
}

TEST(Colliders, BoxFaceEdgeCornerInsideAndCentre) {
  // Half extents (1, 2, 3), turned 30° about z.
  const Real angle = std::numbers::pi_v<Real> / 6;
  const Matrix3r R = Eigen::AngleAxis<Real>(angle, Vector3r::UnitZ()).toRotationMatrix();
  const Vector3r c(Real(0.5), 1, -1);
  const Collider box = BoxCollider{c, Vector3r(1, 2, 3), R};
  const auto world = [&](Real x, Real y, Real z) { return Vector3r(c + R * Vector3r(x, y, z)); };
  const Vector3r ex = R.col(0), ey = R.col(1), ez = R.col(2);
  // Outside a face, an edge, a corner.
  expect_query(box, world(3, 1, 1), 2, ex, world(1, 1, 1));
  expect_query(box, world(4, 6, 0), 5, (3 * ex + 4 * ey) / 5, world(1, 2, 0));
  expect_query(box, world(-3, -4, -5), std::sqrt(Real(12)), -(ex + ey + ez).normalized(),
               world(-1, -2, -3));
  // On a face, inside near the +y face, inside near the -z face.
  expect_query(box, world(Real(0.5), 2, 1), 0, ey, world(Real(0.5), 2, 1));
  expect_query(box, world(Real(0.2), Real(1.6), 0), Real(-0.4), ey, world(Real(0.2), 2, 0));
  expect_query(box, world(0, 0, Real(-2.5)), Real(-0.5), -ez, world(0, 0, -3));
  // The centre of a cube: every face is nearest, the lowest axis's positive face is taken.
  const Collider cube = BoxCollider{Vector3r::Zero(), Vector3r::Ones(), Matrix3r::Identity()};
  expect_query(cube, Vector3r::Zero(), -1, Vector3r::UnitX(), Vector3r::UnitX());
}

TEST(Colliders, CapsuleSidesEndsAxisAndDegenerate) {
  const Collider capsule = CapsuleCollider{Vector3r(-1, 0, 0), Vector3r(1, 0, 0), Real(0.5)};
  expect_query(capsule, Vector3r(Real(0.3), 2, 0), Real(1.5), Vector3r::UnitY(),
               Vector3r(Real(0.3), Real(0.5), 0));
  expect_query(capsule, Vector3r(3, 0, 0), Real(1.5), Vector3r::UnitX(), Vector3r(Real(1.5), 0, 0));
  expect_query(capsule, Vector3r(Real(-1.3), 0, Real(-0.4)), Real(0.5) - Real(0.5),
               Vector3r(-3, 0, -4) / 5, Vector3r(Real(-1.3), 0, Real(-0.4)));
  expect_query(capsule, Vector3r(Real(0.2), 0, Real(-0.1)), Real(-0.4), -Vector3r::UnitZ(),
               Vector3r(Real(0.2), 0, Real(-0.5)));
  // On the axis: the perpendicular closest to +y; +z for an axis along y.
  expect_query(capsule, Vector3r(Real(0.7), 0, 0), Real(-0.5), Vector3r::UnitY(),
               Vector3r(Real(0.7), Real(0.5), 0));
  const Collider upright = CapsuleCollider{Vector3r(0, -1, 0), Vector3r(0, 1, 0), 1};
  expect_query(upright, Vector3r(0, Real(0.5), 0), -1, Vector3r::UnitZ(),
               Vector3r(0, Real(0.5), 1));
  // a == b is a sphere, +y at its centre.
  const Collider ball = CapsuleCollider{Vector3r(1, 1, 1), Vector3r(1, 1, 1), 2};
  expect_query(ball, Vector3r(1, 1, 1), -2, Vector3r::UnitY(), Vector3r(1, 3, 1));
  expect_query(ball, Vector3r(1, 1, 4), 1, Vector3r::UnitZ(), Vector3r(1, 1, 3));
}

TEST(Colliders, NormalIsUnitAndFiniteEverywhere) {
  const Matrix3r R =
      Eigen::AngleAxis<Real>(Real(0.7), Vector3r(1, 2, 3).normalized()).toRotationMatrix();
  const std::vector<Collider> colliders = {
      PlaneCollider{Vector3r(0, 0, 1), Real(0.3)},
      SphereCollider{Vector3r(Real(0.1), 0, 0), 1},
      BoxCollider{Vector3r::Zero(), Vector3r(1, Real(0.5), 0), R},  // a flat plate
      CapsuleCollider{Vector3r(0, -1, 0), Vector3r(0, 1, 0), Real(0.5)},
      CapsuleCollider{Vector3r::Zero(), Vector3r::Zero(), Real(0.5)},
      collider_of(cube_mesh(1)),
      collider_of(icosphere(2, 1)),
      collider_of(wavy_sheet(8))};
  std::vector<Vector3r> points = random_points(2000, 3, 7);
  // The special points: centres, axes, corners, the origin.
  for (const Vector3r& p : {Vector3r(0, 0, 0), Vector3r(Real(0.1), 0, 0), Vector3r(0, Real(0.5), 0),
                            Vector3r(1, 1, 1), Vector3r(0, 0, Real(0.3))})
    points.push_back(p);
  for (const Collider& collider : colliders)
    for (const Vector3r& p : points) expect_consistent(closest_surface(collider, p), p, 3);
}

// ------------------------------------------------------------------------------ the mesh
TEST(MeshCollider, CubeMeshMatchesTheBox) {
  const MeshCollider mesh = collider_of(cube_mesh(1));
  EXPECT_EQ(mesh.triangle_count(), 12u);
  EXPECT_TRUE(mesh.closed());
  const Collider box = BoxCollider{};
  for (const Vector3r& p : random_points(5000, 3, 11)) {
    const SurfaceQuery expected = closest_surface(box, p);
    const SurfaceQuery actual = mesh.closest_surface(p);
    ASSERT_NEAR(actual.distance, expected.distance, 4 * kTolerance) << "at " << p.transpose();
    // The normal is unique except inside where two faces are about as near.
    const Vector3r local_depth = Vector3r::Ones() - p.cwiseAbs();
    std::array<Real, 3> depths = {local_depth[0], local_depth[1], local_depth[2]};
    std::sort(depths.begin(), depths.end());
    if (expected.distance > 0 || depths[1] - depths[0] > Real(1e-3)) {
      expect_near(actual.normal, expected.normal, 1e-3);
      expect_near(actual.point, expected.point, 1e-3);
    }
  }
  // Outside near a corner and an edge, where a face normal alone would give the wrong sign.
  EXPECT_NEAR(mesh.closest_surface(Vector3r(2, 2, 2)).distance, std::sqrt(Real(3)), kTolerance);
  EXPECT_NEAR(mesh.closest_surface(Vector3r(Real(1.01), Real(1.02), 0)).distance,
              std::sqrt(Real(0.0005)), 10 * kTolerance);
  EXPECT_NEAR(mesh.closest_surface(Vector3r(Real(0.99), Real(0.98), 0)).distance, Real(-0.01),
              10 * kTolerance);
}

TEST(MeshCollider, IcosphereMatchesTheSphereWithinItsChordError) {
  const TestMesh ico = icosphere(4, 1);  // 5120 triangles
  const MeshCollider mesh = collider_of(ico);
  EXPECT_EQ(mesh.triangle_count(), 5120u);
  EXPECT_TRUE(mesh.closed());
  // The mesh lies between its inradius and the sphere: that gap is its tolerance.
  Real inradius = 1;
  for (std::size_t t = 0; t < ico.triangles.size(); t += 3) {
    const Vector3r& a = ico.positions[ico.triangles[t]];
    const Vector3r n = (ico.positions[ico.triangles[t + 1]] - a)
                           .cross(ico.positions[ico.triangles[t + 2]] - a)
                           .normalized();
    inradius = std::min(inradius, n.dot(a));
  }
  const Real tolerance = 1 - inradius + kTolerance;
  ASSERT_LT(tolerance, Real(0.01));
  const Collider sphere = SphereCollider{Vector3r::Zero(), 1};
  for (const Vector3r& p : random_points(5000, 2, 13)) {
    const SurfaceQuery expected = closest_surface(sphere, p);
    const SurfaceQuery actual = mesh.closest_surface(p);
    ASSERT_NEAR(actual.distance, expected.distance, tolerance) << "at " << p.transpose();
    if (std::abs(expected.distance) > tolerance) {
      EXPECT_EQ(actual.distance < 0, expected.distance < 0) << "at " << p.transpose();
    }
    if (p.norm() > Real(0.2)) expect_near(actual.normal, expected.normal, Real(0.2));
  }
  // Exactly on every vertex and edge midpoint, and just outside and inside them along the
  // radius, where the closest feature is a vertex or an edge: the pseudo-normals' cases.
  for (std::size_t t = 0; t < ico.triangles.size(); t += 3)
    for (int k = 0; k < 3; ++k) {
      const Vector3r& a = ico.positions[ico.triangles[t + k]];
      const Vector3r& b = ico.positions[ico.triangles[t + (k + 1) % 3]];
      for (const Vector3r& on : {a, Vector3r((a + b) / 2)}) {
        ASSERT_NEAR(mesh.closest_surface(on).distance, 0, kTolerance);
        ASSERT_NEAR(mesh.closest_surface(Real(1.001) * on).distance, Real(0.001) * on.norm(),
                    kTolerance);
        // Inside, an adjacent face is nearer than the vertex by 0.001 (1 - cos(its tilt)).
        ASSERT_NEAR(mesh.closest_surface(Real(0.999) * on).distance, Real(-0.001) * on.norm(),
                    Real(5e-6) + kTolerance);
      }
    }
}

TEST(MeshCollider, ClosestTriangleMatchesBruteForce) {
  for (const TestMesh& shape : {icosphere(3, Real(1.5)), wavy_sheet(20)}) {
    const MeshCollider mesh = collider_of(shape);
    for (const Vector3r& p : random_points(1000, 3, 17)) {
      Real nearest = std::numeric_limits<Real>::max();
      for (std::size_t t = 0; t < shape.triangles.size(); t += 3)
        nearest = std::min(nearest, reference_distance(p, shape.positions[shape.triangles[t]],
                                                       shape.positions[shape.triangles[t + 1]],
                                                       shape.positions[shape.triangles[t + 2]]));
      const SurfaceQuery q = mesh.closest_surface(p);
      ASSERT_NEAR(std::abs(q.distance), nearest, 4 * kTolerance) << "at " << p.transpose();
    }
  }
}

TEST(MeshCollider, OpenSheetSignFollowsTheWinding) {
  const MeshCollider sheet = collider_of(wavy_sheet(16));
  EXPECT_FALSE(sheet.closed());
  EXPECT_GT(sheet.closest_surface(Vector3r(Real(0.3), Real(-0.4), 1)).distance, 0);
  EXPECT_LT(sheet.closest_surface(Vector3r(Real(0.3), Real(-0.4), -1)).distance, 0);
  // Above the saddle (0, π/2, 0), where the surface is flat: distance 1, normal up (within
  // the grid's error).
  const SurfaceQuery above = sheet.closest_surface(Vector3r(0, std::numbers::pi_v<Real> / 2, 1));
  EXPECT_NEAR(above.distance, 1, 1e-2);
  expect_near(above.normal, Vector3r::UnitZ(), 5e-2);
}

TEST(MeshCollider, TakesWhatTheObjReaderGives) {
  // A unit tetrahedron, faces wound outward, as a file would hold it (quads are fanned).
  std::istringstream obj(
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
      "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  const io::Mesh file = io::read_obj(obj, "tet.obj");
  const MeshCollider tet(file.positions, file.triangles);
  EXPECT_TRUE(tet.closed());
  const SurfaceQuery inside = tet.closest_surface(Vector3r(Real(0.1), Real(0.2), Real(0.3)));
  EXPECT_NEAR(inside.distance, Real(-0.1), kTolerance);
  expect_near(inside.normal, -Vector3r::UnitX());
  // Beyond the slanted face x + y + z = 1, and beyond the corner at the origin.
  const SurfaceQuery beyond = tet.closest_surface(Vector3r(1, 1, 1));
  EXPECT_NEAR(beyond.distance, 2 / std::sqrt(Real(3)), kTolerance);
  expect_near(beyond.normal, Vector3r::Ones().normalized());
  EXPECT_NEAR(tet.closest_surface(Vector3r(-1, -1, -1)).distance, std::sqrt(Real(3)), kTolerance);
}

TEST(MeshCollider, UnevenTrianglesStayExact) {
  // 3000 triangles whose sizes shrink geometrically (by 10^4 in all) along x: uneven boxes and
  // uneven surface-area splits.
  TestMesh strip;
  Real x = 0;
  for (int t = 0; t < 3000; ++t) {
    const Real size = Real(10) * std::pow(Real(0.997), Real(t));
    const ParticleIndex first = ParticleIndex(strip.positions.size());
    strip.positions.insert(strip.positions.end(),
                           {Vector3r(x, 0, 0), Vector3r(x + size, 0, 0), Vector3r(x, size, 0)});
    strip.triangles.insert(strip.triangles.end(), {first, first + 1, first + 2});
    x += size;
  }
  const MeshCollider mesh = collider_of(strip);
  std::mt19937 rng(5);
  std::uniform_real_distribution<Real> along(0, x), up(-1, 5);
  for (int k = 0; k < 300; ++k) {
    const Vector3r p(along(rng), up(rng), up(rng));
    Real nearest = std::numeric_limits<Real>::max();
    for (std::size_t t = 0; t < strip.triangles.size(); t += 3)
      nearest = std::min(nearest, reference_distance(p, strip.positions[strip.triangles[t]],
                                                     strip.positions[strip.triangles[t + 1]],
                                                     strip.positions[strip.triangles[t + 2]]));
    ASSERT_NEAR(std::abs(mesh.closest_surface(p).distance), nearest, 1e-4 * (1 + nearest))
        << "at " << p.transpose();
  }
}

TEST(MeshCollider, FirstEntryThroughAThinWall) {
  // A slab 0.02 thick: [-1, 1] × [-0.01, 0.01] × [-1, 1], as a closed mesh.
  TestMesh slab = cube_mesh(1);
  for (auto& p : slab.positions) p.y() *= Real(0.01);
  const MeshCollider mesh = collider_of(slab);
  Vector3r point, normal;
  ASSERT_TRUE(
      mesh.first_entry(Vector3r(Real(0.2), 1, 0), Vector3r(Real(0.2), -1, 0), point, normal));
  expect_near(point, Vector3r(Real(0.2), Real(0.01), 0));
  expect_near(normal, Vector3r::UnitY());
  // Leaving through the back of a triangle is no entry; missing the slab neither.
  EXPECT_FALSE(mesh.first_entry(Vector3r(0.2, 0, 0), Vector3r(Real(0.2), 1, 0), point, normal));
  EXPECT_FALSE(mesh.first_entry(Vector3r(3, 1, 0), Vector3r(3, -1, 0), point, normal));
  EXPECT_FALSE(mesh.first_entry(Vector3r(3, 1, 0), Vector3r(3, 1, 0), point, normal));
}

// ---------------------------------------------------------------------------- contacts
ParticleState state_of(const std::vector<Vector3r>& predicted,
                       const std::vector<Vector3r>& previous,
                       const std::vector<Vector3r>& velocities,
                       const std::vector<Real>& inverse_masses) {
  ParticleState state(previous, inverse_masses);
  for (std::size_t i = 0; i < predicted.size(); ++i) {
    state.set_position(i, predicted[i]);
    state.velocity_x[i] = velocities[i].x();
    state.velocity_y[i] = velocities[i].y();
    state.velocity_z[i] = velocities[i].z();
  }
  return state;
}

TEST(ColliderContacts, HitsWithinThicknessPlusMarginOnly) {
  const Real thickness = Real(0.1), margin = Real(0.05);
  const std::vector<Collider> colliders = {PlaneCollider{Vector3r::UnitY(), 0},
                                           SphereCollider{Vector3r(0, 5, 0), 1}};
  // Heights above the floor, x spread so the sphere touches only the last two.
  const std::vector<Vector3r> predicted = {
      {0, Real(0.5), 3},  {0, Real(0.16), 3}, {0, Real(0.14), 3}, {0, Real(-0.3), 3},
      {0, Real(0.05), 3}, {0, Real(3.9), 0},  {0, Real(4.5), 0}};
  std::vector<Vector3r> previous = predicted, velocities(predicted.size());
  for (std::size_t i = 0; i < predicted.size(); ++i) {
    previous[i].y() += Real(0.1);
    velocities[i] = Vector3r(1, -Real(i), 0);
  }
  // Particle 4 is static: it makes no contact though it touches the floor.
  const std::vector<Real> inverse_masses = {1, 1, 1, 1, 0, 1, 1};
  const ParticleState state = state_of(predicted, previous, velocities, inverse_masses);
  ColliderHits hits;
  find_collider_contacts(colliders, state, thickness, margin, hits);
  ASSERT_EQ(hits.particles, (std::vector<ParticleIndex>{2, 3, 5, 6}));
  EXPECT_EQ(hits.collider, (std::vector<std::uint32_t>{0, 0, 1, 1}));
  ASSERT_EQ(hits.size(), 4u);
  for (std::size_t k = 0; k < hits.size(); ++k) {
    const std::size_t i = hits.particles[k];
    expect_near(hits.anchors[k], previous[i]);
    EXPECT_NEAR(hits.normal_speeds[k], velocities[i].dot(hits.normals[k]), kTolerance);
  }
  // The floor: normal +y, offset thickness; the sphere: below it, normal -y, offset
  // n · (0, 4, 0) + thickness = -4 + 0.1.
  expect_near(hits.normals[0], Vector3r::UnitY());
  EXPECT_NEAR(hits.offsets[0], thickness, kTolerance);
  EXPECT_NEAR(hits.offsets[1], thickness, kTolerance);
  expect_near(hits.normals[2], -Vector3r::UnitY());
  EXPECT_NEAR(hits.offsets[2], -4 + thickness, kTolerance);
  // A second call overwrites: no hits when every particle is far above.
  ParticleState far = state;
  for (std::size_t i = 0; i < far.size(); ++i) far.y[i] = 100;
  find_collider_contacts(colliders, far, thickness, margin, hits);
  EXPECT_EQ(hits.size(), 0u);
  EXPECT_EQ(hits.normals.size(), 0u);
}

TEST(ColliderContacts, MeshContactsAtRestOutsideNearAndInside) {
  const std::vector<Collider> colliders = {collider_of(cube_mesh(1))};
  const Real thickness = Real(0.05);
  // At rest (previous = predicted): just outside within the thickness, far outside, deep
  // inside (nearest face +y, 0.8 away), just inside the -x face.
  const std::vector<Vector3r> positions = {{0, Real(1.03), 0},
                                           {0, Real(1.5), 0},
                                           {Real(0.1), Real(0.2), Real(0.05)},
                                           {Real(-0.98), Real(0.5), Real(0.1)}};
  const ParticleState state =
      state_of(positions, positions, std::vector<Vector3r>(4, Vector3r::Zero()), {1, 1, 1, 1});
  ColliderHits hits;
  find_collider_contacts(colliders, state, thickness, 0, hits);
  ASSERT_EQ(hits.particles, (std::vector<ParticleIndex>{0, 2, 3}));
  expect_near(hits.normals[0], Vector3r::UnitY());
  EXPECT_NEAR(hits.offsets[0], 1 + thickness, kTolerance);
  expect_near(hits.normals[1], Vector3r::UnitY());
  EXPECT_NEAR(hits.offsets[1], 1 + thickness, kTolerance);
  expect_near(hits.normals[2], -Vector3r::UnitX());
  EXPECT_NEAR(hits.offsets[2], 1 + thickness, kTolerance);
}

TEST(ColliderContacts, MeshTunnellingUsesTheEntrySide) {
  TestMesh slab = cube_mesh(1);
  for (auto& p : slab.positions) p.y() *= Real(0.01);
  const std::vector<Collider> colliders = {collider_of(slab)};
  const Real thickness = Real(0.02);
  // 0: went right through (outside on the far side); 1: ended inside nearer the far face;
  // 2: outside, far away from the slab's bounds; 3: resting above within the thickness.
  const std::vector<Vector3r> previous = {
      {0, Real(0.5), 0}, {Real(0.5), Real(0.3), 0}, {5, 5, 5}, {0, Real(0.025), Real(0.5)}};
  const std::vector<Vector3r> predicted = {
      {0, Real(-0.5), 0}, {Real(0.5), Real(-0.008), 0}, {5, 4, 5}, {0, Real(0.025), Real(0.5)}};
  const std::vector<Vector3r> velocities(4, Vector3r(0, -1, 0));
  const ParticleState state = state_of(predicted, previous, velocities, {1, 1, 1, 1});
  ColliderHits hits;
  find_collider_contacts(colliders, state, thickness, 0, hits);
  ASSERT_EQ(hits.particles, (std::vector<ParticleIndex>{0, 1, 3}));
  for (std::size_t k = 0; k < hits.size(); ++k) {
    expect_near(hits.normals[k], Vector3r::UnitY());
    EXPECT_NEAR(hits.offsets[k], Real(0.01) + thickness, kTolerance);
    EXPECT_NEAR(hits.normal_speeds[k], -1, kTolerance);
  }
}

TEST(ColliderContacts, SameHitsForOneAndTwoThreads) {
  const std::vector<Collider> colliders = {
      PlaneCollider{Vector3r::UnitY(), -1}, SphereCollider{Vector3r(1, 0, 0), Real(0.8)},
      BoxCollider{Vector3r(-1, 0, 0), Vector3r(Real(0.5), Real(0.7), Real(0.3)),
                  Eigen::AngleAxis<Real>(Real(0.4), Vector3r::UnitX()).toRotationMatrix()},
      CapsuleCollider{Vector3r(0, 0, -1), Vector3r(0, 1, 1), Real(0.3)},
      collider_of(icosphere(3, Real(0.7)))};
  const std::vector<Vector3r> predicted = random_points(20000, 2, 23);
  std::vector<Vector3r> previous = random_points(20000, 2, 29), velocities(predicted.size());
  std::vector<Real> inverse_masses(predicted.size(), 1);
  for (std::size_t i = 0; i < predicted.size(); ++i) {
    previous[i] = predicted[i] + Real(0.05) * previous[i];
    velocities[i] = (predicted[i] - previous[i]) * 60;
    if (i % 7 == 0) inverse_masses[i] = 0;
  }
  const ParticleState state = state_of(predicted, previous, velocities, inverse_masses);
  ColliderHits one, two;
  tbb::task_arena(1).execute(
      [&] { find_collider_contacts(colliders, state, Real(0.01), Real(0.02), one); });
  tbb::task_arena(2).execute(
      [&] { find_collider_contacts(colliders, state, Real(0.01), Real(0.02), two); });
  ASSERT_GT(one.size(), 1000u);
  EXPECT_EQ(one.particles, two.particles);
  EXPECT_EQ(one.collider, two.collider);
  EXPECT_EQ(one.offsets, two.offsets);
  EXPECT_EQ(one.normal_speeds, two.normal_speeds);
  ASSERT_EQ(one.normals.size(), two.normals.size());
  for (std::size_t k = 0; k < one.size(); ++k) {
    ASSERT_EQ(one.normals[k], two.normals[k]);
    ASSERT_EQ(one.anchors[k], two.anchors[k]);
  }
  // Ordered by particle, then collider; never a static particle.
  for (std::size_t k = 0; k < one.size(); ++k) {
    EXPECT_NE(one.particles[k] % 7, 0u);
    if (k > 0) {
      EXPECT_TRUE(
          one.particles[k - 1] < one.particles[k] ||
          (one.particles[k - 1] == one.particles[k] && one.collider[k - 1] < one.collider[k]));
    }
  }
}

TEST(ColliderContacts, PenetrationDepthIsTheDeepestPoint) {
  const std::vector<Collider> colliders = {PlaneCollider{Vector3r::UnitY(), 0},
                                           SphereCollider{Vector3r(5, 0, 0), 1},
                                           collider_of(cube_mesh(Real(0.5)))};
  EXPECT_EQ(penetration_depth(colliders, std::vector<Vector3r>{{0, 1, 3}, {9, 2, 0}}), 0);
  EXPECT_NEAR(
      penetration_depth(colliders, std::vector<Vector3r>{{0, Real(-0.2), 3}, {5, Real(0.3), 0}}),
      Real(0.7), kTolerance);
  // 0.35 inside the cube mesh, 0.1 below the floor.
  EXPECT_NEAR(penetration_depth(colliders, std::vector<Vector3r>{{0, Real(-0.1), Real(0.15)}}),
              Real(0.35), kTolerance);
  EXPECT_EQ(penetration_depth({}, std::vector<Vector3r>{{0, -1, 0}}), 0);
}

// ------------------------------------------------------------------------- bad input
TEST(Colliders, BadInputIsNamed) {
  const auto validate = [](Collider c) {
    return error_of([&] { validate_colliders(std::span<const Collider>(&c, 1)); });
  };
  EXPECT_TRUE(contains(validate(PlaneCollider{Vector3r::Zero(), 0}),
                       "collider 0 (plane): normal must be a unit vector"));
  EXPECT_TRUE(
      contains(validate(PlaneCollider{Vector3r(0, 2, 0), 0}), "unit vector (its length is 2"));
  EXPECT_TRUE(
      contains(validate(SphereCollider{Vector3r::Zero(), 0}), "collider 0 (sphere): radius 0"));
  EXPECT_TRUE(contains(validate(SphereCollider{Vector3r::Zero(), NAN}),
                       "(sphere): radius nan must be finite and > 0"));
  EXPECT_TRUE(contains(validate(CapsuleCollider{Vector3r::Zero(), Vector3r::Zero(), -1}),
                       "(capsule): radius"));
  EXPECT_TRUE(
      contains(validate(BoxCollider{Vector3r::Zero(), Vector3r(1, -1, 1), Matrix3r::Identity()}),
               "(box): a half extent is negative"));
  EXPECT_TRUE(
      contains(validate(BoxCollider{Vector3r::Zero(), Vector3r::Ones(), Matrix3r::Identity() * 2}),
               "(box): rotation is not a rotation"));
  EXPECT_TRUE(
      contains(validate(BoxCollider{Vector3r::Zero(), Vector3r::Ones(), -Matrix3r::Identity()}),
               "rotation is not a rotation"));
  EXPECT_TRUE(contains(validate(SphereCollider{Vector3r(0, INFINITY, 0), 1}),
                       "(sphere): centre is not finite"));
  EXPECT_EQ(validate(CapsuleCollider{Vector3r::Ones(), Vector3r::Ones(), 1}), "(no error)");

  // The position of the bad collider in the span is named.
  const std::vector<Collider> two = {SphereCollider{}, SphereCollider{Vector3r::Zero(), -2}};
  EXPECT_TRUE(contains(error_of([&] { validate_colliders(two); }), "collider 1 (sphere)"));
  ColliderHits hits;
  const ParticleState state(std::vector<Vector3r>{{0, 0, 0}}, std::vector<Real>{1});
  EXPECT_TRUE(
      contains(error_of([&] { find_collider_contacts(two, state, 0, 0, hits); }), "collider 1"));
  EXPECT_TRUE(
      contains(error_of([&] { find_collider_contacts({}, state, -1, 0, hits); }), "thickness -1"));
  EXPECT_TRUE(
      contains(error_of([&] { find_collider_contacts({}, state, 0, NAN, hits); }), "margin nan"));

  const std::vector<Vector3r> corners = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}};
  const auto mesh_error = [&](std::vector<ParticleIndex> triangles) {
    return error_of([&] { MeshCollider(corners, triangles); });
  };
  EXPECT_EQ(mesh_error({0, 1, 2}), "(no error)");
  EXPECT_EQ(mesh_error({}), "mesh collider: no triangles");
  EXPECT_TRUE(contains(mesh_error({0, 1}), "not a multiple of 3"));
  EXPECT_TRUE(contains(mesh_error({0, 1, 2, 0, 2, 7}),
                       "mesh collider: triangle 1: vertex index 7 is out of range (4 positions)"));
  EXPECT_TRUE(
      contains(mesh_error({0, 1, 2, 2, 1, 2}), "triangle 1 is degenerate: it names vertex"));
  EXPECT_TRUE(contains(mesh_error({0, 1, 3}), "triangle 0 is degenerate: its corners"));
}

}  // namespace colliders_tests
}  // namespace tessera
