// The self-intersection count: known answers on pairs of triangles (crossing, apart, coplanar
// overlapping and apart, touching, degenerate), symmetry of the pair test under swapping and
// rotating the corners, and on meshes: a flat grid counts 0, a grid folded through itself
// counts more than 0, and the grid-culled count equals the O(n²) count on a crumpled grid.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include <tessera/collision/self_intersections.hpp>
#include <tessera/core/error.hpp>
#include <tessera/io/generators.hpp>

namespace tessera {
namespace self_intersections_tests {

using Eigen::Vector3d;

std::size_t count(const std::vector<Vector3r>& positions, const std::vector<std::uint32_t>& t) {
  return count_self_intersections(positions, t);
}

TEST(SelfIntersections, TwoCrossingTrianglesCountOne) {
  // A horizontal triangle pierced by a vertical one that shares no vertex with it.
  const std::vector<Vector3r> positions = {
      Vector3r(0, 0, 0), Vector3r(2, 0, 0), Vector3r(0, 2, 0),
      Vector3r(Real(0.5), Real(0.5), -1), Vector3r(Real(0.5), Real(0.5), 1),
      Vector3r(Real(0.6), Real(0.4), 1)};
  EXPECT_EQ(count(positions, {0, 1, 2, 3, 4, 5}), 1u);
  // Lifted above the plane, they miss.
  std::vector<Vector3r> lifted = positions;
  for (int i = 3; i < 6; ++i) lifted[std::size_t(i)].z() += 2;
  EXPECT_EQ(count(lifted, {0, 1, 2, 3, 4, 5}), 0u);
}

TEST(SelfIntersections, TrianglesSharingAVertexAreNotCounted) {
  // The same crossing, but the vertical triangle reuses vertex 0: adjacent, so skipped.
  const std::vector<Vector3r> positions = {
      Vector3r(0, 0, 0), Vector3r(2, 0, 0), Vector3r(0, 2, 0),
      Vector3r(Real(0.5), Real(0.5), -1), Vector3r(Real(0.5), Real(0.5), 1)};
  EXPECT_EQ(count(positions, {0, 1, 2, 3, 4, 0}), 0u);
}

TEST(SelfIntersections, PairTestKnownAnswers) {
  const Vector3d a0(0, 0, 0), a1(2, 0, 0), a2(0, 2, 0);
  // Coplanar, overlapping (one corner inside the other) and apart.
  EXPECT_TRUE(triangles_intersect(a0, a1, a2, {0.5, 0.5, 0}, {3, 3, 0}, {0.5, 3, 0}));
  EXPECT_FALSE(triangles_intersect(a0, a1, a2, {1.5, 1.5, 0}, {3, 3, 0}, {1.5, 3, 0}));
  // Coplanar, one inside the other with no edge crossing.
  EXPECT_TRUE(triangles_intersect(a0, a1, a2, {0.1, 0.1, 0}, {0.5, 0.1, 0}, {0.1, 0.5, 0}));
  // Coplanar, crossing edges only (a star of David).
  EXPECT_TRUE(triangles_intersect(a0, a1, a2, {-0.5, 1, 0}, {1.5, -0.5, 0}, {1.5, 1.5, 0}));
  // Touching: a corner on the face, an edge across the face's edge.
  EXPECT_TRUE(triangles_intersect(a0, a1, a2, {0.5, 0.5, 0}, {0.5, 0.5, 1}, {1, 0.5, 1}));
  EXPECT_TRUE(triangles_intersect(a0, a1, a2, {1, -1, 0}, {1, 1, 0}, {1, 0, 1}));
  // Above the plane but over the face: no.
  EXPECT_FALSE(triangles_intersect(a0, a1, a2, {0.5, 0.5, 0.1}, {0.5, 0.5, 1}, {1, 0.5, 1}));
  // Crossing the plane beside the triangle: no.
  EXPECT_FALSE(triangles_intersect(a0, a1, a2, {3, 3, -1}, {3, 3, 1}, {4, 3, 1}));
  // A degenerate triangle (a segment) through the face, and one beside it.
  EXPECT_TRUE(triangles_intersect(a0, a1, a2, {0.5, 0.5, -1}, {0.5, 0.5, 1}, {0.5, 0.5, 0.5}));
  EXPECT_FALSE(triangles_intersect(a0, a1, a2, {3, 3, -1}, {3, 3, 1}, {3, 3, 0.5}));
}

TEST(SelfIntersections, PairTestIsSymmetricAndIgnoresCornerOrder) {
  std::mt19937 random(3);
  std::uniform_real_distribution<double> coordinate(-1, 1);
  const auto point = [&] { return Vector3d(coordinate(random), coordinate(random), coordinate(random)); };
  int intersecting = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Vector3d a[3] = {point(), point(), point()};
    const Vector3d b[3] = {point(), point(), point()};
    const bool expected = triangles_intersect(a[0], a[1], a[2], b[0], b[1], b[2]);
    intersecting += expected;
    EXPECT_EQ(triangles_intersect(b[0], b[1], b[2], a[0], a[1], a[2]), expected);
    EXPECT_EQ(triangles_intersect(a[1], a[2], a[0], b[2], b[1], b[0]), expected);
  }
  EXPECT_GT(intersecting, 100);
  EXPECT_LT(intersecting, 1900);
}

TEST(SelfIntersections, AFlatGridCountsZero) {
  const io::ClothGrid grid = io::make_cloth_grid(40, 40, Real(1) / 39);
  EXPECT_EQ(count(grid.positions, grid.triangle_indices), 0u);
}

TEST(SelfIntersections, AGridFoldedThroughItselfCountsMoreThanZero) {
  // The half x > 0.5 folded back over the other half on a plane tilted through z = 0: it
  // starts below the flat half at the hinge and comes out above it.
  io::ClothGrid grid = io::make_cloth_grid(30, 30, Real(1) / 29);
  for (Vector3r& p : grid.positions)
    if (p.x() > Real(0.5)) p = Vector3r(1 - p.x(), p.y(), Real(0.4) * (p.x() - Real(0.5)) - Real(0.1));
  EXPECT_GT(count(grid.positions, grid.triangle_indices), 0u);
}

TEST(SelfIntersections, TheCulledCountEqualsTheQuadraticCount) {
  io::ClothGrid grid = io::make_cloth_grid(20, 20, Real(1) / 19);
  std::mt19937 random(9);
  std::uniform_real_distribution<Real> noise(-Real(0.06), Real(0.06));
  for (Vector3r& p : grid.positions)
    p = Vector3r(p.x() + noise(random), p.y() + noise(random), 3 * noise(random));
  const auto& t = grid.triangle_indices;
  std::size_t expected = 0;
  for (std::size_t i = 0; i < grid.triangle_count(); ++i)
    for (std::size_t j = i + 1; j < grid.triangle_count(); ++j) {
      bool adjacent = false;
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) adjacent |= t[3 * i + std::size_t(k)] == t[3 * j + std::size_t(l)];
      const auto at = [&](std::size_t v) { return grid.positions[t[v]].cast<double>().eval(); };
      if (!adjacent && triangles_intersect(at(3 * i), at(3 * i + 1), at(3 * i + 2), at(3 * j),
                                           at(3 * j + 1), at(3 * j + 2)))
        ++expected;
    }
  EXPECT_GT(expected, 10u);
  EXPECT_EQ(count(grid.positions, grid.triangle_indices), expected);
}

TEST(SelfIntersections, InvalidInputIsRefused) {
  const std::vector<Vector3r> positions(3, Vector3r::Zero());
  EXPECT_THROW(count(positions, {0, 1, 3}), InvalidInput);
  EXPECT_THROW(count(positions, {0, 1}), InvalidInput);
}

}  // namespace self_intersections_tests
}  // namespace tessera
