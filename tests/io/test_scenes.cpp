// Scenes: shells, solids, the default cloth and bar and read meshes as Models — particle and
// constraint counts per family, pins, lumped masses, bending stencils on general meshes, and
// the validation messages.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numeric>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <tessera/core/error.hpp>
#include <tessera/io/generators.hpp>
#include <tessera/io/mesh_readers.hpp>
#include <tessera/io/scenes.hpp>

namespace tessera::io {
namespace scenes_tests {

const std::filesystem::path kDataDir = TESSERA_TEST_DATA_DIR;

std::size_t family_size(const Model& model, ConstraintFamily family) {
  return model.constraints.sizes()[static_cast<std::size_t>(family)];
}

/// The families of a model that hold constraints.
std::set<ConstraintFamily> non_empty_families(const Model& model) {
  std::set<ConstraintFamily> families;
  model.constraints.for_each([&](ConstraintFamily family, const auto& batch) {
    if (batch.size() > 0) families.insert(family);
  });
  return families;
}

std::vector<VertexIndex> static_particles(const Model& model) {
  std::vector<VertexIndex> fixed;
  for (std::size_t i = 0; i < model.particles.size(); ++i)
    if (model.particles.inverse_mass[i] == 0) fixed.push_back(VertexIndex(i));
  return fixed;
}

std::vector<Vector3r> positions_of(const Model& model) {
  std::vector<Vector3r> positions;
  for (std::size_t i = 0; i < model.particles.size(); ++i)
    positions.push_back(model.particles.position(i));
  return positions;
}

/// The model's movable particles hold the lumped masses, and the lumped masses add up to
/// `total` (pinned shares included).
void expect_lumped_masses(const Model& model, std::span<const VertexIndex> elements,
                          std::size_t vertices_per_element, Real total) {
  const std::vector<Vector3r> positions = positions_of(model);
  const std::vector<Real> masses = lumped_masses(positions, elements, vertices_per_element, total);
  double sum = 0;
  for (std::size_t i = 0; i < masses.size(); ++i) {
    sum += masses[i];
    if (model.particles.inverse_mass[i] != 0) {
      EXPECT_NEAR(model.particles.inverse_mass[i] * masses[i], 1, 1e-5) << "particle " << i;
    }
  }
  EXPECT_NEAR(sum, total, 1e-5 * total);
}

/// A bending stencil as a set element: (lower edge, higher edge, lower wing, higher wing).
using StencilKey = std::array<VertexIndex, 4>;
std::set<StencilKey> stencil_set(const std::vector<VertexIndex>& stencils) {
  std::set<StencilKey> keys;
  for (std::size_t s = 0; s < stencils.size() / 4; ++s) {
    const VertexIndex* v = stencils.data() + 4 * s;
    keys.insert({std::min(v[2], v[3]), std::max(v[2], v[3]), std::min(v[0], v[1]),
                 std::max(v[0], v[1])});
  }
  return keys;
}

template <class Build>
std::string invalid_input_message(Build&& build) {
  try {
    build();
  } catch (const InvalidInput& error) {
    return error.what();
  }
  ADD_FAILURE() << "no InvalidInput thrown";
  return {};
}

// A unit square split along its diagonal 0–3 into two triangles, in the xy plane.
const std::vector<Vector3r> kSquare = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0),
                                       Vector3r(1, 1, 0)};
const std::vector<VertexIndex> kSquareTriangles = {0, 1, 3, 0, 3, 2};

// A tetrahedron with positive orientation, and its four outward triangles.
const std::vector<Vector3r> kTetrahedron = {Vector3r(0, 0, 0), Vector3r(1, 0, 0),
                                            Vector3r(0, 1, 0), Vector3r(0, 0, 1)};
const std::vector<VertexIndex> kTetrahedronIndices = {0, 1, 2, 3};
const std::vector<VertexIndex> kTetrahedronSurface = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};

TEST(ClothScene, MatchesTheGridTurnedIntoTheXzPlane) {
  const std::size_t columns = 16, rows = 12;
  const ClothGrid grid = make_cloth_grid(columns, rows, Real(1) / Real(columns - 1));
  const Model model = make_cloth_scene(columns, rows);

  ASSERT_EQ(model.particles.size(), columns * rows);
  EXPECT_EQ(family_size(model, ConstraintFamily::distance), grid.edge_count());
  EXPECT_EQ(family_size(model, ConstraintFamily::dihedral), grid.bending_count());
  EXPECT_EQ(non_empty_families(model),
            (std::set{ConstraintFamily::distance, ConstraintFamily::dihedral}));

  EXPECT_EQ(static_particles(model),
            (std::vector<VertexIndex>{VertexIndex((rows - 1) * columns),
                                      VertexIndex(rows * columns - 1)}));
  Real min_x = 1e9, max_x = -1e9;
  for (std::size_t i = 0; i < model.particles.size(); ++i) {
    EXPECT_EQ(model.particles.y[i], 0) << "particle " << i;
    min_x = std::min(min_x, model.particles.x[i]);
    max_x = std::max(max_x, model.particles.x[i]);
    EXPECT_NEAR(model.particles.z[i], grid.positions[i].y(), 1e-6);
  }
  EXPECT_EQ(min_x, 0);
  EXPECT_NEAR(max_x, 1, 1e-6);
  // The pinned corners are the last row's: z at its maximum, x at 0 and 1.
  EXPECT_EQ(model.particles.position((rows - 1) * columns).x(), 0);
  EXPECT_NEAR(model.particles.position(rows * columns - 1).x(), 1, 1e-6);
  EXPECT_NEAR(model.particles.position(rows * columns - 1).z(), Real(rows - 1) / Real(columns - 1),
              1e-6);

  expect_lumped_masses(model, grid.triangle_indices, 3, 1);
  ShellOptions heavy;
  heavy.mass = 7;
  expect_lumped_masses(make_cloth_scene(columns, rows, heavy), grid.triangle_indices, 3, 7);
}

TEST(ClothScene, EveryMaterialAndBendingBuildsItsFamiliesOnly) {
  const ClothGrid grid = make_cloth_grid(6, 5, Real(0.2));
  const std::array<std::pair<ShellMaterial, ConstraintFamily>, 3> materials = {{
      {ShellMaterial::distance, ConstraintFamily::distance},
      {ShellMaterial::strain_triangle, ConstraintFamily::strain_triangle},
      {ShellMaterial::fem_triangle, ConstraintFamily::fem_triangle},
  }};
  const std::array<std::pair<ShellBending, std::size_t>, 3> bendings = {{
      {ShellBending::dihedral, static_cast<std::size_t>(ConstraintFamily::dihedral)},
      {ShellBending::isometric, static_cast<std::size_t>(ConstraintFamily::isometric_bending)},
      {ShellBending::none, kConstraintFamilyCount},
  }};
  for (const auto& [material, material_family] : materials) {
    for (const auto& [bending, bending_family] : bendings) {
      ShellOptions options;
      options.material = material;
      options.bending = bending;
      const Model model = make_cloth_scene(6, 5, options);
      std::set<ConstraintFamily> expected = {material_family};
      if (bending_family < kConstraintFamilyCount)
        expected.insert(static_cast<ConstraintFamily>(bending_family));
      EXPECT_EQ(non_empty_families(model), expected)
          << "material " << int(material) << ", bending " << int(bending);
      const std::size_t in_plane = family_size(model, material_family);
      EXPECT_EQ(in_plane, material == ShellMaterial::distance ? grid.edge_count()
                                                              : grid.triangle_count());
      if (bending_family < kConstraintFamilyCount) {
        EXPECT_EQ(model.constraints.sizes()[bending_family], grid.bending_count());
      }
      EXPECT_EQ(static_particles(model).size(), 2u);
    }
  }
}

TEST(Shell, StrainTrianglesMeasureEachTriangleInItsOwnPlane) {
  // The cloth lies in the xz plane, where the xy projection of every triangle is flat: the
  // rest matrices must come from the triangles' own planes, so F = I at rest.
  ShellOptions options;
  options.material = ShellMaterial::strain_triangle;
  const Model model = make_cloth_scene(4, 3, options);
  const StrainTriangleConstraints& strain = model.constraints.strain_triangle;
  ASSERT_EQ(strain.size(), 12u);
  EXPECT_EQ(strain.particles.particle_count, model.particles.size());
  for (std::size_t c = 0; c < strain.size(); ++c) {
    const Vector3r p0 = model.particles.position(strain.particles.particle[0][c]);
    const Vector3r p1 = model.particles.position(strain.particles.particle[1][c]);
    const Vector3r p2 = model.particles.position(strain.particles.particle[2][c]);
    Eigen::Matrix<Real, 3, 2> edges;
    edges << p1 - p0, p2 - p0;
    Matrix2r rest_inverse;
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j) rest_inverse(k, j) = strain.rest_inverse[std::size_t(2 * k + j)][c];
    const Matrix2r metric = (edges * rest_inverse).transpose() * (edges * rest_inverse);
    EXPECT_TRUE(metric.isApprox(Matrix2r::Identity(), Real(1e-4))) << "triangle " << c << "\n"
                                                                   << metric;
  }
}

TEST(BarScene, CountsFixedEndAndMass) {
  const TetrahedralBar bar = make_tetrahedral_bar(2, 3, 4, Real(0.1));
  const Model model = make_bar_scene(2, 3, 4);
  ASSERT_EQ(model.particles.size(), 3u * 4u * 5u);
  EXPECT_EQ(non_empty_families(model), std::set{ConstraintFamily::fem_tetra});
  EXPECT_EQ(family_size(model, ConstraintFamily::fem_tetra), 2u * 3u * 4u * 6u);
  std::vector<VertexIndex> at_z0;
  for (std::size_t v = 0; v < bar.vertex_count(); ++v)
    if (bar.positions[v].z() == 0) at_z0.push_back(VertexIndex(v));
  EXPECT_EQ(at_z0.size(), 12u);
  EXPECT_EQ(static_particles(model), at_z0);
  EXPECT_NEAR(model.particles.position(model.particles.size() - 1).z(), Real(0.4), 1e-6);
  expect_lumped_masses(model, bar.tetrahedron_indices, 4, 1);
  EXPECT_NEAR(model.constraints.fem_tetra.youngs_modulus[0], Real(1e6), 1);
}

TEST(BarScene, SolidMaterials) {
  const TetrahedralBar bar = make_tetrahedral_bar(1, 2, 3, Real(0.1));
  SolidOptions options;
  options.material = SolidMaterial::strain_tetra;
  Model model = make_bar_scene(1, 2, 3, options);
  EXPECT_EQ(non_empty_families(model), std::set{ConstraintFamily::strain_tetra});
  EXPECT_EQ(family_size(model, ConstraintFamily::strain_tetra), bar.tetrahedron_count());

  options.material = SolidMaterial::volume_and_distance;
  options.volume_compliance = Real(1e-4);
  options.distance_compliance = Real(2e-4);
  model = make_bar_scene(1, 2, 3, options);
  EXPECT_EQ(non_empty_families(model),
            (std::set{ConstraintFamily::distance, ConstraintFamily::volume}));
  EXPECT_EQ(family_size(model, ConstraintFamily::volume), bar.tetrahedron_count());
  EXPECT_EQ(family_size(model, ConstraintFamily::distance), bar.edge_count());
  EXPECT_EQ(model.constraints.volume.compliance[0], Real(1e-4));
  EXPECT_EQ(model.constraints.distance.compliance[0], Real(2e-4));

  options.material = SolidMaterial::fem_tetra;
  options.youngs_modulus = Real(5e4);
  options.poisson_ratio = Real(0.45);
  model = make_bar_scene(1, 2, 3, options);
  EXPECT_EQ(model.constraints.fem_tetra.youngs_modulus[0], Real(5e4));
  EXPECT_EQ(model.constraints.fem_tetra.poisson_ratio[0], Real(0.45));
}

TEST(BendingStencils, MatchTheClothGrid) {
  for (const DiagonalPattern pattern : {DiagonalPattern::uniform, DiagonalPattern::alternating}) {
    const ClothGrid grid = make_cloth_grid(9, 7, Real(1), pattern);
    const std::vector<VertexIndex> stencils =
        bending_stencils(grid.triangle_indices, grid.vertex_count());
    EXPECT_EQ(stencil_set(stencils), stencil_set(grid.bending_indices));
    // Same order and wing convention, too.
    EXPECT_EQ(stencils, grid.bending_indices);
  }
}

TEST(BendingStencils, TetrahedronSurfaceHasOnePerEdge) {
  const std::vector<VertexIndex> stencils = bending_stencils(kTetrahedronSurface, 4);
  ASSERT_EQ(stencils.size(), 6u * 4u);
  std::set<std::pair<VertexIndex, VertexIndex>> edges;
  for (std::size_t s = 0; s < 6; ++s) {
    const VertexIndex* v = stencils.data() + 4 * s;
    EXPECT_LT(v[2], v[3]);
    // The wings are the two vertices not on the edge.
    EXPECT_EQ(std::set<VertexIndex>(v, v + 4), (std::set<VertexIndex>{0, 1, 2, 3}));
    edges.insert({v[2], v[3]});
  }
  EXPECT_EQ(edges.size(), 6u);
  // Sorted by edge.
  EXPECT_TRUE(std::is_sorted(edges.begin(), edges.end()));
  EXPECT_EQ(std::vector<VertexIndex>(stencils.begin() + 2, stencils.begin() + 4),
            (std::vector<VertexIndex>{0, 1}));
}

TEST(BendingStencils, NonManifoldBookEdgeGetsNone) {
  // Three pages sharing the spine 0–1.
  const std::vector<VertexIndex> book = {0, 1, 2, 1, 0, 3, 0, 1, 4};
  EXPECT_TRUE(bending_stencils(book, 5).empty());
  // A fourth triangle on page 2's edge 1–2 makes that edge (only) interior.
  std::vector<VertexIndex> book_and_more = book;
  book_and_more.insert(book_and_more.end(), {2, 1, 5});
  EXPECT_EQ(bending_stencils(book_and_more, 6), (std::vector<VertexIndex>{0, 5, 1, 2}));
  // A triangle listed twice bends nowhere.
  EXPECT_TRUE(bending_stencils(std::vector<VertexIndex>{0, 1, 2, 0, 2, 1}, 3).empty());
}

TEST(BendingStencils, RejectsBadTriangles) {
  EXPECT_EQ(invalid_input_message([] { bending_stencils(std::vector<VertexIndex>{0, 1}, 3); }),
            "bending_stencils: 2 indices are not a whole number of triangles (3 indices each)");
  EXPECT_EQ(invalid_input_message([] { bending_stencils(std::vector<VertexIndex>{0, 1, 3}, 3); }),
            "bending_stencils: triangle 0: vertex 3 is out of range (the mesh has 3 vertices)");
  EXPECT_EQ(invalid_input_message([] { bending_stencils(std::vector<VertexIndex>{0, 1, 1}, 3); }),
            "bending_stencils: triangle 0: vertex 1 appears twice");
}

TEST(Shell, BookBuildsWithoutBendingOnItsSpine) {
  const std::vector<Vector3r> positions = {Vector3r(0, 0, 0), Vector3r(0, 0, 1),
                                           Vector3r(1, 0, 0), Vector3r(-1, 0, 0),
                                           Vector3r(0, 1, 0)};
  const Model model = make_shell(positions, std::vector<VertexIndex>{0, 1, 2, 1, 0, 3, 0, 1, 4}, {});
  EXPECT_EQ(family_size(model, ConstraintFamily::distance), 7u);
  EXPECT_EQ(family_size(model, ConstraintFamily::dihedral), 0u);
  EXPECT_TRUE(static_particles(model).empty());
}

TEST(Shell, TwoPiecesAndAnUnusedVertex) {
  // Two unit squares 5 m apart, and vertex 8 used by nothing.
  std::vector<Vector3r> positions = kSquare;
  for (const Vector3r& p : kSquare) positions.push_back(p + Vector3r(5, 0, 0));
  positions.push_back(Vector3r(9, 9, 9));
  std::vector<VertexIndex> triangles = kSquareTriangles;
  for (const VertexIndex v : kSquareTriangles) triangles.push_back(v + 4);
  const std::vector<VertexIndex> pinned = {1};
  ShellOptions options;
  options.mass = 2;
  const Model model = make_shell(positions, triangles, pinned, options);
  ASSERT_EQ(model.particles.size(), 9u);
  EXPECT_EQ(family_size(model, ConstraintFamily::distance), 10u);
  EXPECT_EQ(family_size(model, ConstraintFamily::dihedral), 2u);
  EXPECT_EQ(model.constraints.dihedral.particles.particle[2][1], 4u);
  EXPECT_EQ(model.constraints.dihedral.particles.particle[3][1], 7u);
  EXPECT_EQ(static_particles(model), (std::vector<VertexIndex>{1, 8}));
  // Each square holds half the mass: 1/3 at its diagonal's ends, 1/6 at the other corners.
  EXPECT_NEAR(model.particles.inverse_mass[0], 3, 1e-5);
  EXPECT_NEAR(model.particles.inverse_mass[2], 6, 1e-5);
  EXPECT_NEAR(model.particles.inverse_mass[7], 3, 1e-5);
  expect_lumped_masses(model, triangles, 3, 2);
}

TEST(LumpedMasses, SplitByAreaAndVolume) {
  EXPECT_EQ(lumped_masses(kSquare, kSquareTriangles, 3, 6),
            (std::vector<Real>{2, 1, 1, 2}));
  const std::vector<Real> tetrahedron = lumped_masses(kTetrahedron, kTetrahedronIndices, 4, 2);
  for (const Real mass : tetrahedron) EXPECT_NEAR(mass, Real(0.5), 1e-6);
  EXPECT_EQ(invalid_input_message([] { lumped_masses(kSquare, kSquareTriangles, 2, 1); }),
            "lumped_masses: elements of 2 vertices, expected 3 (triangles) or 4 (tetrahedra)");
}

TEST(MakeModel, TetrahedraMakeASolid) {
  Mesh mesh;
  mesh.positions = kTetrahedron;
  mesh.tetrahedra = kTetrahedronIndices;
  mesh.triangles = kTetrahedronSurface;  // ignored
  const Model model = make_model(mesh, std::vector<VertexIndex>{0});
  EXPECT_EQ(non_empty_families(model), std::set{ConstraintFamily::fem_tetra});
  EXPECT_EQ(static_particles(model), std::vector<VertexIndex>{0});
  EXPECT_NEAR(model.particles.inverse_mass[3], 4, 1e-5);
}

TEST(MakeModel, TrianglesMakeAShell) {
  Mesh mesh;
  mesh.positions = kSquare;
  mesh.triangles = kSquareTriangles;
  const Model model = make_model(mesh, {});
  EXPECT_EQ(non_empty_families(model),
            (std::set{ConstraintFamily::distance, ConstraintFamily::dihedral}));
  EXPECT_EQ(family_size(model, ConstraintFamily::distance), 5u);
  EXPECT_EQ(family_size(model, ConstraintFamily::dihedral), 1u);
  EXPECT_TRUE(static_particles(model).empty());
}

TEST(MakeModel, EmptyMeshIsInvalid) {
  Mesh mesh;
  mesh.positions = kSquare;
  EXPECT_EQ(invalid_input_message([&] { make_model(mesh, {}); }),
            "make_model: the mesh has no triangles and no tetrahedra (4 vertices)");
  EXPECT_EQ(invalid_input_message([] { make_model(Mesh{}, {}); }),
            "make_model: the mesh has no triangles and no tetrahedra (0 vertices)");
}

TEST(MakeModel, ReadsTheCubeWithItsLowestLayerPinned) {
  const Mesh mesh = read_mesh(kDataDir / "cube.node");
  ASSERT_EQ(mesh.tetrahedron_count(), 7u);
  const std::vector<VertexIndex> pinned = lowest_vertices(mesh.positions);
  EXPECT_EQ(pinned, (std::vector<VertexIndex>{0, 1, 4, 5, 8, 9, 11}));
  const Model model = make_model(mesh, pinned);
  ASSERT_EQ(model.particles.size(), 12u);
  EXPECT_EQ(family_size(model, ConstraintFamily::fem_tetra), 7u);
  EXPECT_EQ(static_particles(model), pinned);
  expect_lumped_masses(model, mesh.tetrahedra, 4, 1);

  // The same file's boundary triangles as a shell (three triangles, no shared edge of two).
  Mesh surface = mesh;
  surface.tetrahedra.clear();
  const Model shell = make_model(surface, {});
  EXPECT_EQ(family_size(shell, ConstraintFamily::distance), 8u);
  EXPECT_EQ(family_size(shell, ConstraintFamily::dihedral), 1u);  // the bottom's diagonal 0–3
  // Vertices on no triangle stay static.
  EXPECT_EQ(static_particles(shell), (std::vector<VertexIndex>{4, 5, 6, 7, 11}));
}

TEST(LowestVertices, WithinToleranceAlongTheAxis) {
  const std::vector<Vector3r> positions = {Vector3r(0, Real(1e-8), 0), Vector3r(1, 1, 1),
                                           Vector3r(2, 0, 5), Vector3r(3, Real(0.01), 0)};
  EXPECT_EQ(lowest_vertices(positions), (std::vector<VertexIndex>{0, 2}));
  EXPECT_EQ(lowest_vertices(positions, 0), std::vector<VertexIndex>{0});
  EXPECT_EQ(lowest_vertices(positions, 2), (std::vector<VertexIndex>{0, 3}));
  EXPECT_TRUE(lowest_vertices({}).empty());
  EXPECT_EQ(invalid_input_message([&] { lowest_vertices(positions, 3); }),
            "lowest_vertices: axis 3 is not 0 (x), 1 (y) or 2 (z)");
}

TEST(Validation, BadPinsAndElements) {
  EXPECT_EQ(invalid_input_message(
                [] { make_shell(kSquare, kSquareTriangles, std::vector<VertexIndex>{2, 99}); }),
            "shell: pinned vertex 99 is out of range (the mesh has 4 vertices)");
  EXPECT_EQ(invalid_input_message([] {
              make_solid(kTetrahedron, kTetrahedronIndices, std::vector<VertexIndex>{4});
            }),
            "solid: pinned vertex 4 is out of range (the mesh has 4 vertices)");
  Mesh mesh;
  mesh.positions = kSquare;
  mesh.triangles = {0, 1, 7};
  EXPECT_EQ(invalid_input_message([&] { make_model(mesh, {}); }),
            "shell of mesh: triangle 0: vertex 7 is out of range (the mesh has 4 vertices)");
  EXPECT_EQ(invalid_input_message([] {
              make_solid(kTetrahedron, std::vector<VertexIndex>{0, 1, 2, 2}, {});
            }),
            "solid: tetrahedron 0: vertex 2 appears twice");
  EXPECT_EQ(invalid_input_message([] { make_shell(kSquare, {}, {}); }),
            "shell: the mesh has no triangles");
  EXPECT_EQ(invalid_input_message([] { make_cloth_scene(1, 5); }),
            "cloth scene: make_cloth_grid: needs at least 2 x 2 vertices, got 1 x 5");
  EXPECT_EQ(invalid_input_message([] { make_bar_scene(1, 0, 1); }),
            "bar scene: make_tetrahedral_bar: needs at least 1 x 1 x 1 cells, got 1 x 0 x 1");
}

TEST(Validation, DegenerateElementsNameWhatWasBeingBuilt) {
  // Coincident points: core's distance constraint reports it, prefixed.
  const std::vector<Vector3r> coincident = {Vector3r(0, 0, 0), Vector3r(0, 0, 0),
                                            Vector3r(1, 0, 0)};
  const std::string distance = invalid_input_message(
      [&] { make_shell(coincident, std::vector<VertexIndex>{0, 1, 2}, {}); });
  EXPECT_EQ(distance.rfind("shell: distance constraint 0: ", 0), 0u) << distance;
  // Collinear points pass the distance constraints; the mass lumping rejects the triangle.
  const std::vector<Vector3r> collinear = {Vector3r(0, 0, 0), Vector3r(1, 0, 0),
                                           Vector3r(2, 0, 0)};
  ShellOptions flat;
  flat.bending = ShellBending::none;
  EXPECT_EQ(invalid_input_message(
                [&] { make_shell(collinear, std::vector<VertexIndex>{0, 1, 2}, {}, flat); }),
            "shell: triangle 0 has zero area");
  flat.material = ShellMaterial::strain_triangle;
  const std::string strain = invalid_input_message(
      [&] { make_shell(collinear, std::vector<VertexIndex>{0, 1, 2}, {}, flat); });
  EXPECT_EQ(strain.rfind("shell: strain triangle constraint 0: ", 0), 0u) << strain;
  // A flat tetrahedron: core's FEM tetra constraint reports it, prefixed.
  Mesh mesh;
  mesh.positions = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0), Vector3r(1, 1, 0)};
  mesh.tetrahedra = {0, 1, 2, 3};
  const std::string tetra = invalid_input_message([&] { make_model(mesh, {}); });
  EXPECT_EQ(tetra.rfind("solid of mesh: FEM tetra constraint 0: ", 0), 0u) << tetra;
}

TEST(Validation, OptionsOutOfRange) {
  const auto shell_message = [](auto change) {
    ShellOptions options;
    change(options);
    return invalid_input_message([&] { make_shell(kSquare, kSquareTriangles, {}, options); });
  };
  EXPECT_EQ(shell_message([](ShellOptions& o) { o.mass = 0; }),
            "shell: mass is 0, expected a positive finite number");
  EXPECT_EQ(shell_message([](ShellOptions& o) { o.mass = std::numeric_limits<Real>::quiet_NaN(); }),
            "shell: mass is nan, expected a positive finite number");
  EXPECT_EQ(shell_message([](ShellOptions& o) { o.youngs_modulus = -1; }),
            "shell: youngs_modulus is -1, expected a positive finite number");
  EXPECT_EQ(shell_message([](ShellOptions& o) { o.poisson_ratio = Real(0.5); }),
            "shell: poisson_ratio is 0.5, expected 0 <= poisson_ratio < 0.5");
  EXPECT_EQ(shell_message([](ShellOptions& o) { o.distance_compliance = -1; }),
            "shell: distance_compliance is -1, expected a finite number >= 0");
  EXPECT_EQ(shell_message([](ShellOptions& o) {
              o.bending_compliance = std::numeric_limits<Real>::infinity();
            }),
            "shell: bending_compliance is inf, expected a finite number >= 0");

  const auto solid_message = [](auto change) {
    SolidOptions options;
    change(options);
    return invalid_input_message([&] { make_bar_scene(1, 1, 1, options); });
  };
  EXPECT_EQ(solid_message([](SolidOptions& o) { o.mass = -2; }),
            "bar scene: mass is -2, expected a positive finite number");
  EXPECT_EQ(solid_message([](SolidOptions& o) { o.youngs_modulus = 0; }),
            "bar scene: youngs_modulus is 0, expected a positive finite number");
  EXPECT_EQ(solid_message([](SolidOptions& o) { o.poisson_ratio = Real(-0.1); }),
            "bar scene: poisson_ratio is -0.1, expected 0 <= poisson_ratio < 0.5");
  EXPECT_EQ(solid_message([](SolidOptions& o) { o.volume_compliance = -1; }),
            "bar scene: volume_compliance is -1, expected a finite number >= 0");
  EXPECT_EQ(solid_message([](SolidOptions& o) { o.distance_compliance = -1; }),
            "bar scene: distance_compliance is -1, expected a finite number >= 0");
}

}  // namespace scenes_tests
}  // namespace tessera::io
