// Constraint graphs of the test meshes shared by the colouring tests: cloth (distance only;
// distance + bending; pinned top row), a tetrahedral bar (volume + distance), isolated
// constraints, constraints meeting only at a pinned particle, clusters (a variable-size
// group), an empty set and a single constraint.
#pragma once

#include <string>
#include <vector>

#include <tessera/coloring/constraint_graph.hpp>
#include <tessera/io/generators.hpp>

namespace tessera::test {

struct TestMesh {
  std::string name;
  ConstraintGraph graph;
};

inline ConstraintGraph cloth_graph(std::size_t columns, std::size_t rows, bool bending,
                                   bool pin_top_row = false) {
  const io::ClothGrid cloth = io::make_cloth_grid(columns, rows);
  std::vector<Real> inverse_masses(cloth.vertex_count(), Real(1));
  if (pin_top_row)
    for (std::size_t i = 0; i < columns; ++i) inverse_masses[(rows - 1) * columns + i] = 0;
  std::vector<ConstraintGroup> groups = {
      ConstraintGroup::fixed_arity("distance", 2, cloth.edge_indices)};
  if (bending) groups.push_back(ConstraintGroup::fixed_arity("bending", 4, cloth.bending_indices));
  return ConstraintGraph(inverse_masses, groups);
}

inline ConstraintGraph tet_bar_graph(std::size_t x, std::size_t y, std::size_t z) {
  const io::TetrahedralBar bar = io::make_tetrahedral_bar(x, y, z);
  const std::vector<Real> inverse_masses(bar.vertex_count(), Real(1));
  const std::vector<ConstraintGroup> groups = {
      ConstraintGroup::fixed_arity("volume", 4, bar.tetrahedron_indices),
      ConstraintGroup::fixed_arity("distance", 2, bar.edge_indices)};
  return ConstraintGraph(inverse_masses, groups);
}

/// `count` distance constraints on disjoint particle pairs, plus one between two static
/// particles: nothing conflicts.
inline ConstraintGraph isolated_graph(std::size_t count) {
  std::vector<Real> inverse_masses(2 * count + 2, Real(1));
  inverse_masses[2 * count] = inverse_masses[2 * count + 1] = 0;
  std::vector<ParticleIndex> indices(2 * count + 2);
  for (std::size_t i = 0; i < indices.size(); ++i) indices[i] = static_cast<ParticleIndex>(i);
  const std::vector<ConstraintGroup> groups = {ConstraintGroup::fixed_arity("distance", 2, indices)};
  return ConstraintGraph(inverse_masses, groups);
}

/// A star: `arms` distance constraints from a pinned hub (particle 0) to movable particles,
/// and `arms` bending-like 3-particle constraints (hub, arm end, another pinned particle).
/// All constraints of a group share only static particles.
inline ConstraintGraph pinned_star_graph(std::size_t arms) {
  std::vector<Real> inverse_masses(arms + 2, Real(2));
  inverse_masses[0] = 0;
  inverse_masses[arms + 1] = 0;
  std::vector<ParticleIndex> spokes;
  for (std::size_t i = 1; i <= arms; ++i) spokes.insert(spokes.end(), {0, static_cast<ParticleIndex>(i)});
  const std::vector<ConstraintGroup> groups = {ConstraintGroup::fixed_arity("spoke", 2, spokes)};
  return ConstraintGraph(inverse_masses, groups);
}

/// Shape-matching style clusters (a variable-size group: 3×3 blocks of a grid overlapping by
/// one row/column) plus the grid's distance constraints.
inline ConstraintGraph cluster_graph() {
  const io::ClothGrid cloth = io::make_cloth_grid(9, 9);
  std::vector<ParticleIndex> offsets = {0}, members;
  for (std::size_t j = 0; j + 2 < 9; j += 2)
    for (std::size_t i = 0; i + 2 < 9; i += 2) {
      for (std::size_t b = 0; b < 3; ++b)
        for (std::size_t a = 0; a < 3; ++a) members.push_back(static_cast<ParticleIndex>((j + b) * 9 + i + a));
      offsets.push_back(static_cast<ParticleIndex>(members.size()));
    }
  const std::vector<Real> inverse_masses(cloth.vertex_count(), Real(1));
  const std::vector<ConstraintGroup> groups = {
      ConstraintGroup::fixed_arity("distance", 2, cloth.edge_indices),
      ConstraintGroup::variable_size("shape matching", offsets, members)};
  return ConstraintGraph(inverse_masses, groups);
}

inline ConstraintGraph single_constraint_graph() {
  const std::vector<Real> inverse_masses = {1, 1, 1, 1};
  const std::vector<ParticleIndex> tet = {0, 1, 2, 3};
  const std::vector<ConstraintGroup> groups = {ConstraintGroup::fixed_arity("volume", 4, tet)};
  return ConstraintGraph(inverse_masses, groups);
}

inline ConstraintGraph empty_graph() {
  const std::vector<Real> inverse_masses = {1, 1, 1};
  const std::vector<ParticleIndex> none;
  const std::vector<ConstraintGroup> groups = {ConstraintGroup::fixed_arity("distance", 2, none)};
  return ConstraintGraph(inverse_masses, groups);
}

inline std::vector<TestMesh> all_test_meshes() {
  std::vector<TestMesh> meshes;
  meshes.push_back({"cloth_distance", cloth_graph(16, 12, false)});
  meshes.push_back({"cloth_distance_bending", cloth_graph(16, 12, true)});
  meshes.push_back({"cloth_pinned", cloth_graph(12, 12, true, true)});
  meshes.push_back({"tet_bar", tet_bar_graph(8, 3, 3)});
  meshes.push_back({"isolated", isolated_graph(20)});
  meshes.push_back({"pinned_star", pinned_star_graph(12)});
  meshes.push_back({"clusters", cluster_graph()});
  meshes.push_back({"single", single_constraint_graph()});
  meshes.push_back({"empty", empty_graph()});
  return meshes;
}

}  // namespace tessera::test
