// Procedural meshes for tests, benchmarks and demos: a triangulated cloth grid and a
// tetrahedral bar. Each generator returns rest positions plus flat index arrays (a fixed
// number of particle indices per element, elements back to back), which is the form the
// colouring stage and the constraint families take without copying.
//
// Orders are deterministic and "natural" (row-major over the grid, edges sorted by their
// lower then higher vertex), so benchmarks that compare natural against shuffled input
// order start from a well-defined baseline.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <tessera/core/indices.hpp>
#include <tessera/core/real.hpp>

namespace tessera::io {

/// Particle (vertex) index as stored in the generated index arrays: a mesh vertex is a
/// particle, so this is core's ParticleIndex under the mesh's name.
using VertexIndex = tessera::ParticleIndex;

/// How each grid square of a cloth is split into two triangles.
enum class DiagonalPattern {
  /// Every square split along the same diagonal: interior vertices have 6 edges, so the
  /// edge graph is the triangular lattice (its distance constraints need exactly 6 colours).
  uniform,
  /// The diagonal alternates like a chequerboard ("union jack"): vertices have 4 or 8 edges.
  alternating,
};

/// A cloth of columns × rows vertices in the z = 0 plane.
struct ClothGrid {
  std::size_t columns = 0;
  std::size_t rows = 0;
  /// Rest position of each vertex; vertex (i, j) (column i, row j) is j * columns + i.
  std::vector<Vector3r> positions;
  /// Three vertices per triangle, counter-clockwise seen from +z.
  std::vector<VertexIndex> triangle_indices;
  /// Two vertices per unique edge (lower index first), sorted: distance constraints.
  std::vector<VertexIndex> edge_indices;
  /// Four vertices per interior edge in the order (wing0, wing1, edge0, edge1), where
  /// edge0–edge1 is the shared edge and the wings are the opposite vertices of its two
  /// triangles: dihedral and isometric bending stencils. Same order as the edges they bend.
  std::vector<VertexIndex> bending_indices;

  std::size_t vertex_count() const { return positions.size(); }
  std::size_t triangle_count() const { return triangle_indices.size() / 3; }
  std::size_t edge_count() const { return edge_indices.size() / 2; }
  std::size_t bending_count() const { return bending_indices.size() / 4; }
};

/// A triangulated cloth grid of columns × rows vertices (each at least 2) spaced `spacing`
/// apart. Throws tessera::InvalidInput for fewer than 2 vertices along a side, a
/// non-positive spacing or a vertex count that does not fit VertexIndex.
ClothGrid make_cloth_grid(std::size_t columns, std::size_t rows, Real spacing = Real(1),
                          DiagonalPattern pattern = DiagonalPattern::uniform);

/// A box of cells_x × cells_y × cells_z cubic cells, each split into 6 tetrahedra.
struct TetrahedralBar {
  std::size_t cells_x = 0;
  std::size_t cells_y = 0;
  std::size_t cells_z = 0;
  /// Rest position of each vertex; vertex (i, j, k) is (k * (cells_y + 1) + j) * (cells_x + 1) + i.
  std::vector<Vector3r> positions;
  /// Four vertices per tetrahedron (a, b, c, d) with positive orientation:
  /// (b - a) · ((c - a) × (d - a)) > 0.
  std::vector<VertexIndex> tetrahedron_indices;
  /// Two vertices per unique edge (lower index first), sorted: distance constraints.
  std::vector<VertexIndex> edge_indices;

  std::size_t vertex_count() const { return positions.size(); }
  std::size_t tetrahedron_count() const { return tetrahedron_indices.size() / 4; }
  std::size_t edge_count() const { return edge_indices.size() / 2; }
};

/// A tetrahedral bar of cells_x × cells_y × cells_z cubes of side `spacing` (each count at
/// least 1). Every cube is cut into 6 tetrahedra around its diagonal from the lowest to the
/// highest corner (the Kuhn subdivision); since every cube face is then cut along the same
/// diagonal from both sides, the mesh is conforming: each interior triangle is shared by
/// exactly two tetrahedra. Throws tessera::InvalidInput for a zero count, a non-positive
/// spacing or a vertex count that does not fit VertexIndex.
TetrahedralBar make_tetrahedral_bar(std::size_t cells_x, std::size_t cells_y,
                                    std::size_t cells_z, Real spacing = Real(1));

/// The unique edges of elements with `vertices_per_element` vertices each (every pair of an
/// element's vertices is an edge: triangles give 3, tetrahedra 6), two indices per edge, lower
/// index first, sorted. Linear time: a counting sort by lower vertex. `vertex_count` bounds
/// the indices; an index out of range throws tessera::InvalidInput.
std::vector<VertexIndex> unique_edges(const std::vector<VertexIndex>& element_indices,
                                      std::size_t vertices_per_element,
                                      std::size_t vertex_count);

}  // namespace tessera::io
