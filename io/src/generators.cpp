// Cloth grid and tetrahedral bar generators.
//
// Edges and bending stencils are derived from the elements, not written out per pattern, so
// the two diagonal patterns and the tetrahedra share one code path. Both derivations bucket
// element edges by their lower vertex (a counting sort, linear in the element count) and sort
// each small bucket, which yields the edges sorted by (lower, higher) vertex: a deterministic,
// row-major "natural" order.
#include <tessera/io/generators.hpp>

#include <algorithm>
#include <cmath>
#include <array>
#include <limits>
#include <string>

#include <tessera/core/error.hpp>

namespace tessera::io {
namespace {

void require_vertex_count_fits(std::size_t vertex_count, const char* what) {
  if (vertex_count > std::numeric_limits<VertexIndex>::max())
    throw InvalidInput(std::string(what) + ": " + std::to_string(vertex_count) +
                       " vertices do not fit a 32-bit vertex index");
}

void require_positive_spacing(Real spacing, const char* what) {
  if (!(spacing > 0) || !std::isfinite(spacing))
    throw InvalidInput(std::string(what) + ": spacing " + std::to_string(spacing) +
                       " is not a positive finite number");
}

/// One directed edge u→v of an element, and the element vertex opposite it (triangles only).
struct EdgeRecord {
  VertexIndex lower;
  VertexIndex higher;
  VertexIndex from;
  VertexIndex opposite;
};

/// Counting sort of the records by lower vertex, then each bucket sorted by higher vertex
/// (ties keep element order, so the result depends on the input only).
std::vector<EdgeRecord> sort_edge_records(const std::vector<EdgeRecord>& records,
                                          std::size_t vertex_count) {
  std::vector<std::size_t> bucket_start(vertex_count + 1, 0);
  for (const EdgeRecord& r : records) ++bucket_start[r.lower + 1];
  for (std::size_t v = 0; v < vertex_count; ++v) bucket_start[v + 1] += bucket_start[v];
  std::vector<EdgeRecord> sorted(records.size());
  std::vector<std::size_t> cursor(bucket_start.begin(), bucket_start.end() - 1);
  for (const EdgeRecord& r : records) sorted[cursor[r.lower]++] = r;
  for (std::size_t v = 0; v < vertex_count; ++v)
    std::stable_sort(sorted.begin() + static_cast<std::ptrdiff_t>(bucket_start[v]),
                     sorted.begin() + static_cast<std::ptrdiff_t>(bucket_start[v + 1]),
                     [](const EdgeRecord& a, const EdgeRecord& b) { return a.higher < b.higher; });
  return sorted;
}

std::vector<EdgeRecord> element_edge_records(const std::vector<VertexIndex>& element_indices,
                                             std::size_t vertices_per_element,
                                             std::size_t vertex_count) {
  if (vertices_per_element < 2)
    throw InvalidInput("unique_edges: elements need at least 2 vertices, got " +
                       std::to_string(vertices_per_element));
  if (element_indices.size() % vertices_per_element != 0)
    throw InvalidInput("unique_edges: " + std::to_string(element_indices.size()) +
                       " indices are not a whole number of " +
                       std::to_string(vertices_per_element) + "-vertex elements");
  const std::size_t element_count = element_indices.size() / vertices_per_element;
  std::vector<EdgeRecord> records;
  records.reserve(element_count * vertices_per_element * (vertices_per_element - 1) / 2);
  for (std::size_t e = 0; e < element_count; ++e) {
    const VertexIndex* element = element_indices.data() + e * vertices_per_element;
    for (std::size_t a = 0; a < vertices_per_element; ++a) {
      if (element[a] >= vertex_count)
        throw InvalidInput("element " + std::to_string(e) + ": vertex index " +
                           std::to_string(element[a]) + " out of range [0, " +
                           std::to_string(vertex_count) + ")");
      for (std::size_t b = a + 1; b < vertices_per_element; ++b) {
        const VertexIndex u = element[a], v = element[b];
        if (u == v)
          throw InvalidInput("element " + std::to_string(e) + ": vertex " + std::to_string(u) +
                             " appears twice");
        // For a triangle (a, b) = (0, 1), (0, 2), (1, 2); the directed edge in cyclic order
        // and its opposite vertex are needed for bending stencils.
        VertexIndex from = u, opposite = 0;
        if (vertices_per_element == 3) {
          const std::size_t third = 3 - a - b;
          from = (b == a + 1) ? u : v;  // (0,1) and (1,2) run u→v; (0,2) runs 2→0
          opposite = element[third];
        }
        records.push_back({std::min(u, v), std::max(u, v), from, opposite});
      }
    }
  }
  return records;
}

}  // namespace

std::vector<VertexIndex> unique_edges(const std::vector<VertexIndex>& element_indices,
                                      std::size_t vertices_per_element,
                                      std::size_t vertex_count) {
  const std::vector<EdgeRecord> sorted = sort_edge_records(
      element_edge_records(element_indices, vertices_per_element, vertex_count), vertex_count);
  std::vector<VertexIndex> edges;
  edges.reserve(sorted.size());  // at most one edge per record, two indices per edge
  for (std::size_t i = 0; i < sorted.size(); ++i) {
    if (i > 0 && sorted[i].lower == sorted[i - 1].lower && sorted[i].higher == sorted[i - 1].higher)
      continue;
    edges.push_back(sorted[i].lower);
    edges.push_back(sorted[i].higher);
  }
  return edges;
}

ClothGrid make_cloth_grid(std::size_t columns, std::size_t rows, Real spacing,
                          DiagonalPattern pattern) {
  if (columns < 2 || rows < 2)
    throw InvalidInput("make_cloth_grid: needs at least 2 x 2 vertices, got " +
                       std::to_string(columns) + " x " + std::to_string(rows));
  require_positive_spacing(spacing, "make_cloth_grid");
  if (rows > std::numeric_limits<VertexIndex>::max() / columns)
    throw InvalidInput("make_cloth_grid: " + std::to_string(columns) + " x " +
                       std::to_string(rows) + " vertices do not fit a 32-bit vertex index");
  require_vertex_count_fits(columns * rows, "make_cloth_grid");

  ClothGrid cloth;
  cloth.columns = columns;
  cloth.rows = rows;
  cloth.positions.reserve(columns * rows);
  for (std::size_t j = 0; j < rows; ++j)
    for (std::size_t i = 0; i < columns; ++i)
      cloth.positions.emplace_back(static_cast<Real>(i) * spacing,
                                   static_cast<Real>(j) * spacing, Real(0));

  auto vertex = [columns](std::size_t i, std::size_t j) {
    return static_cast<VertexIndex>(j * columns + i);
  };
  cloth.triangle_indices.reserve((columns - 1) * (rows - 1) * 6);
  for (std::size_t j = 0; j + 1 < rows; ++j) {
    for (std::size_t i = 0; i + 1 < columns; ++i) {
      const VertexIndex a = vertex(i, j), b = vertex(i + 1, j);
      const VertexIndex c = vertex(i, j + 1), d = vertex(i + 1, j + 1);
      const bool rising = pattern == DiagonalPattern::uniform || (i + j) % 2 == 0;
      // Square a b / c d (a bottom left, d top right), both triangles counter-clockwise.
      const std::array<VertexIndex, 6> split =
          rising ? std::array<VertexIndex, 6>{a, b, d, a, d, c}
                 : std::array<VertexIndex, 6>{a, b, c, b, d, c};
      cloth.triangle_indices.insert(cloth.triangle_indices.end(), split.begin(), split.end());
    }
  }

  const std::vector<EdgeRecord> sorted = sort_edge_records(
      element_edge_records(cloth.triangle_indices, 3, cloth.vertex_count()), cloth.vertex_count());
  for (std::size_t i = 0; i < sorted.size();) {
    std::size_t end = i + 1;
    while (end < sorted.size() && sorted[end].lower == sorted[i].lower &&
           sorted[end].higher == sorted[i].higher)
      ++end;
    const VertexIndex lower = sorted[i].lower, higher = sorted[i].higher;
    cloth.edge_indices.push_back(lower);
    cloth.edge_indices.push_back(higher);
    if (end - i == 2) {
      // wing0 is the triangle that runs lower→higher, so (wing0, edge0, edge1) and
      // (wing1, edge1, edge0) are both counter-clockwise.
      const EdgeRecord& first = sorted[i].from == lower ? sorted[i] : sorted[i + 1];
      const EdgeRecord& second = sorted[i].from == lower ? sorted[i + 1] : sorted[i];
      cloth.bending_indices.insert(cloth.bending_indices.end(),
                                   {first.opposite, second.opposite, lower, higher});
    }
    i = end;
  }
  return cloth;
}

TetrahedralBar make_tetrahedral_bar(std::size_t cells_x, std::size_t cells_y,
                                    std::size_t cells_z, Real spacing) {
  if (cells_x == 0 || cells_y == 0 || cells_z == 0)
    throw InvalidInput("make_tetrahedral_bar: needs at least 1 x 1 x 1 cells, got " +
                       std::to_string(cells_x) + " x " + std::to_string(cells_y) + " x " +
                       std::to_string(cells_z));
  require_positive_spacing(spacing, "make_tetrahedral_bar");
  const std::size_t nx = cells_x + 1, ny = cells_y + 1, nz = cells_z + 1;
  const std::size_t limit = std::numeric_limits<VertexIndex>::max();
  if (ny > limit / nx || nz > limit / (nx * ny))
    throw InvalidInput("make_tetrahedral_bar: " + std::to_string(nx) + " x " +
                       std::to_string(ny) + " x " + std::to_string(nz) +
                       " vertices do not fit a 32-bit vertex index");

  TetrahedralBar bar;
  bar.cells_x = cells_x;
  bar.cells_y = cells_y;
  bar.cells_z = cells_z;
  bar.positions.reserve(nx * ny * nz);
  for (std::size_t k = 0; k < nz; ++k)
    for (std::size_t j = 0; j < ny; ++j)
      for (std::size_t i = 0; i < nx; ++i)
        bar.positions.emplace_back(static_cast<Real>(i) * spacing, static_cast<Real>(j) * spacing,
                                   static_cast<Real>(k) * spacing);

  // Kuhn subdivision: one tetrahedron per permutation (p, q, r) of the axes, walking from the
  // lowest corner along p, then q, then r to the highest corner. Its orientation is the sign
  // of the permutation, so odd permutations swap their last two vertices.
  struct Walk {
    std::array<int, 3> axes;
    bool odd;
  };
  constexpr std::array<Walk, 6> walks = {{{{0, 1, 2}, false},
                                          {{1, 2, 0}, false},
                                          {{2, 0, 1}, false},
                                          {{0, 2, 1}, true},
                                          {{1, 0, 2}, true},
                                          {{2, 1, 0}, true}}};
  bar.tetrahedron_indices.reserve(cells_x * cells_y * cells_z * 24);
  for (std::size_t k = 0; k < cells_z; ++k) {
    for (std::size_t j = 0; j < cells_y; ++j) {
      for (std::size_t i = 0; i < cells_x; ++i) {
        for (const Walk& walk : walks) {
          std::array<std::size_t, 3> corner = {i, j, k};
          std::array<VertexIndex, 4> tet;
          for (std::size_t step = 0; step < 4; ++step) {
            if (step > 0) ++corner[static_cast<std::size_t>(walk.axes[step - 1])];
            tet[step] = static_cast<VertexIndex>((corner[2] * ny + corner[1]) * nx + corner[0]);
          }
          if (walk.odd) std::swap(tet[2], tet[3]);
          bar.tetrahedron_indices.insert(bar.tetrahedron_indices.end(), tet.begin(), tet.end());
        }
      }
    }
  }
  bar.edge_indices = unique_edges(bar.tetrahedron_indices, 4, bar.vertex_count());
  return bar;
}

}  // namespace tessera::io
