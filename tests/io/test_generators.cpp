// The procedural meshes: element and edge counts, orientation, conformity, stencil layout.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <map>
#include <set>

#include <tessera/core/error.hpp>
#include <tessera/io/generators.hpp>

namespace tessera::io {
namespace generators_tests {

Real signed_volume(const TetrahedralBar& bar, std::size_t t) {
  const VertexIndex* v = bar.tetrahedron_indices.data() + 4 * t;
  const Vector3r a = bar.positions[v[0]], b = bar.positions[v[1]];
  const Vector3r c = bar.positions[v[2]], d = bar.positions[v[3]];
  return (b - a).dot((c - a).cross(d - a)) / 6;
}

Real signed_area_z(const ClothGrid& cloth, std::size_t t) {
  const VertexIndex* v = cloth.triangle_indices.data() + 3 * t;
  const Vector3r a = cloth.positions[v[0]], b = cloth.positions[v[1]], c = cloth.positions[v[2]];
  return (b - a).cross(c - a).z() / 2;
}

/// Edges of a cloth by brute force: every pair of every triangle, deduplicated.
std::set<std::pair<VertexIndex, VertexIndex>> brute_force_edges(const std::vector<VertexIndex>& elements,
                                                                std::size_t per_element) {
  std::set<std::pair<VertexIndex, VertexIndex>> edges;
  for (std::size_t e = 0; e < elements.size() / per_element; ++e)
    for (std::size_t a = 0; a < per_element; ++a)
      for (std::size_t b = a + 1; b < per_element; ++b) {
        const VertexIndex u = elements[e * per_element + a], v = elements[e * per_element + b];
        edges.insert({std::min(u, v), std::max(u, v)});
      }
  return edges;
}

class ClothPatterns : public ::testing::TestWithParam<DiagonalPattern> {};

TEST_P(ClothPatterns, CountsOrientationAndEdges) {
  const std::size_t columns = 7, rows = 5;
  const ClothGrid cloth = make_cloth_grid(columns, rows, Real(0.5), GetParam());
  EXPECT_EQ(cloth.vertex_count(), columns * rows);
  EXPECT_EQ(cloth.triangle_count(), 2 * (columns - 1) * (rows - 1));
  // Horizontal + vertical + one diagonal per square.
  const std::size_t edges = (columns - 1) * rows + columns * (rows - 1) + (columns - 1) * (rows - 1);
  EXPECT_EQ(cloth.edge_count(), edges);
  // Boundary edges bend nothing.
  const std::size_t boundary = 2 * (columns - 1) + 2 * (rows - 1);
  EXPECT_EQ(cloth.bending_count(), edges - boundary);
  EXPECT_FLOAT_EQ(cloth.positions[columns * rows - 1].x(), Real(0.5) * (columns - 1));
  EXPECT_FLOAT_EQ(cloth.positions[columns * rows - 1].y(), Real(0.5) * (rows - 1));

  for (std::size_t t = 0; t < cloth.triangle_count(); ++t)
    EXPECT_NEAR(signed_area_z(cloth, t), Real(0.125), Real(1e-6)) << "triangle " << t;

  const auto expected = brute_force_edges(cloth.triangle_indices, 3);
  std::vector<std::pair<VertexIndex, VertexIndex>> listed;
  for (std::size_t e = 0; e < cloth.edge_count(); ++e) {
    ASSERT_LT(cloth.edge_indices[2 * e], cloth.edge_indices[2 * e + 1]);
    listed.emplace_back(cloth.edge_indices[2 * e], cloth.edge_indices[2 * e + 1]);
  }
  EXPECT_TRUE(std::is_sorted(listed.begin(), listed.end()));
  EXPECT_EQ(std::set(listed.begin(), listed.end()), expected);
}

TEST_P(ClothPatterns, BendingStencilsAreTwoTrianglesSharingAnEdge) {
  const ClothGrid cloth = make_cloth_grid(6, 6, Real(1), GetParam());
  std::set<std::array<VertexIndex, 3>> triangles;  // rotated so the smallest index is first
  for (std::size_t t = 0; t < cloth.triangle_count(); ++t) {
    std::array<VertexIndex, 3> v = {cloth.triangle_indices[3 * t], cloth.triangle_indices[3 * t + 1],
                                    cloth.triangle_indices[3 * t + 2]};
    std::rotate(v.begin(), std::min_element(v.begin(), v.end()), v.end());
    triangles.insert(v);
  }
  auto has_ccw = [&](VertexIndex a, VertexIndex b, VertexIndex c) {
    std::array<VertexIndex, 3> v = {a, b, c};
    std::rotate(v.begin(), std::min_element(v.begin(), v.end()), v.end());
    return triangles.count(v) == 1;
  };
  std::set<std::pair<VertexIndex, VertexIndex>> bent_edges;
  for (std::size_t s = 0; s < cloth.bending_count(); ++s) {
    const VertexIndex* v = cloth.bending_indices.data() + 4 * s;
    EXPECT_TRUE(has_ccw(v[0], v[2], v[3])) << "stencil " << s << ": (wing0, edge0, edge1)";
    EXPECT_TRUE(has_ccw(v[1], v[3], v[2])) << "stencil " << s << ": (wing1, edge1, edge0)";
    EXPECT_TRUE(bent_edges.insert({std::min(v[2], v[3]), std::max(v[2], v[3])}).second)
        << "edge bent twice, stencil " << s;
  }
}

INSTANTIATE_TEST_SUITE_P(Generators, ClothPatterns,
                         ::testing::Values(DiagonalPattern::uniform, DiagonalPattern::alternating));

TEST(ClothGrid, UniformDiagonalsGiveSixEdgesAtInteriorVertices) {
  const ClothGrid uniform = make_cloth_grid(5, 5);
  const ClothGrid alternating = make_cloth_grid(5, 5, Real(1), DiagonalPattern::alternating);
  auto degrees = [](const ClothGrid& cloth) {
    std::vector<int> degree(cloth.vertex_count(), 0);
    for (VertexIndex v : cloth.edge_indices) ++degree[v];
    return degree;
  };
  const std::vector<int> u = degrees(uniform), a = degrees(alternating);
  EXPECT_EQ(*std::max_element(u.begin(), u.end()), 6);
  EXPECT_EQ(u[2 * 5 + 2], 6);
  EXPECT_EQ(*std::max_element(a.begin(), a.end()), 8);
}

TEST(TetrahedralBar, CountsOrientationAndConformity) {
  const std::size_t cx = 4, cy = 3, cz = 2;
  const Real spacing = Real(0.25);
  const TetrahedralBar bar = make_tetrahedral_bar(cx, cy, cz, spacing);
  EXPECT_EQ(bar.vertex_count(), (cx + 1) * (cy + 1) * (cz + 1));
  EXPECT_EQ(bar.tetrahedron_count(), 6 * cx * cy * cz);

  Real volume = 0;
  for (std::size_t t = 0; t < bar.tetrahedron_count(); ++t) {
    const Real v = signed_volume(bar, t);
    EXPECT_GT(v, 0) << "tetrahedron " << t;
    volume += v;
  }
  EXPECT_NEAR(volume, cx * cy * cz * spacing * spacing * spacing, Real(1e-5));

  // Each face shared by exactly two tets (interior) or lying on the box surface (one tet).
  std::map<std::array<VertexIndex, 3>, int> faces;
  for (std::size_t t = 0; t < bar.tetrahedron_count(); ++t) {
    const VertexIndex* v = bar.tetrahedron_indices.data() + 4 * t;
    for (int skip = 0; skip < 4; ++skip) {
      std::array<VertexIndex, 3> face;
      int n = 0;
      for (int k = 0; k < 4; ++k)
        if (k != skip) face[n++] = v[k];
      std::sort(face.begin(), face.end());
      ++faces[face];
    }
  }
  std::size_t boundary_faces = 0;
  for (const auto& [face, count] : faces) {
    ASSERT_LE(count, 2);
    if (count == 2) continue;
    ++boundary_faces;
    // A face seen once must lie on the surface: all three vertices on one box side.
    bool on_surface = false;
    for (int axis = 0; axis < 3; ++axis) {
      const Real extent = spacing * Real(axis == 0 ? cx : axis == 1 ? cy : cz);
      for (Real side : {Real(0), extent}) {
        bool all = true;
        for (VertexIndex v : face) all = all && std::abs(bar.positions[v][axis] - side) < Real(1e-6);
        on_surface = on_surface || all;
      }
    }
    EXPECT_TRUE(on_surface) << "unmatched interior face " << face[0] << " " << face[1] << " " << face[2];
  }
  // Each unit square of the surface is split into two triangles.
  EXPECT_EQ(boundary_faces, 4 * (cx * cy + cy * cz + cx * cz));

  const auto expected = brute_force_edges(bar.tetrahedron_indices, 4);
  EXPECT_EQ(bar.edge_count(), expected.size());
  std::set<std::pair<VertexIndex, VertexIndex>> listed;
  for (std::size_t e = 0; e < bar.edge_count(); ++e)
    listed.insert({bar.edge_indices[2 * e], bar.edge_indices[2 * e + 1]});
  EXPECT_EQ(listed, expected);
}

TEST(Generators, RejectBadSizes) {
  EXPECT_THROW(make_cloth_grid(1, 5), InvalidInput);
  EXPECT_THROW(make_cloth_grid(5, 5, Real(0)), InvalidInput);
  EXPECT_THROW(make_tetrahedral_bar(0, 2, 2), InvalidInput);
  EXPECT_THROW(make_tetrahedral_bar(2, 2, 2, Real(-1)), InvalidInput);
  EXPECT_THROW(unique_edges({0, 1, 7}, 3, 5), InvalidInput);
  EXPECT_THROW(unique_edges({0, 1, 1}, 3, 5), InvalidInput);
  EXPECT_THROW(unique_edges({0, 1, 2, 3}, 3, 5), InvalidInput);
}

}  // namespace generators_tests
}  // namespace tessera::io
