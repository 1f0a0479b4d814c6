// Scenes: turning generated grids and read meshes into solver Models. A triangle mesh
// becomes a cloth shell (in-plane distance edges or strain/FEM triangles, plus bending across
// interior edges), a tetrahedral mesh a solid (FEM or strain tetrahedra, or volume + distance);
// the default cloth and bar scenes of the tests, benchmarks and tool are built the same way.
// build_scene (scene_description.hpp) builds a whole described scene with these.
//
// Rules every builder here follows:
//   * Particles are the mesh's vertices in the mesh's numbering (so results can be written
//     back against the same mesh). A vertex that no element references stays a particle, but
//     a static one (inverse mass 0) that nothing constrains.
//   * Masses are lumped: options.mass is the total, spread over the elements in proportion to
//     their rest area (triangles) or volume (tetrahedra), and each element hands an equal
//     share (a third, a quarter) to each of its vertices. A particle's inverse mass is
//     1 / (its mass); particles listed in `pinned` get inverse mass 0 (their share still
//     counts in the total, so the movable particles hold options.mass minus the pinned shares).
//   * Bending acts across every interior manifold edge: an edge shared by exactly two
//     triangles whose opposite vertices differ. Boundary edges (one triangle), non-manifold
//     edges (three or more triangles, e.g. a "book") and the edges of a triangle listed twice
//     get no bending.
//   * Everything is validated at the door and reported as tessera::InvalidInput whose message
//     starts with what was being built ("shell: ", "solid: ", "cloth scene: ", "bar scene: ",
//     "shell of mesh: ", "solid of mesh: "), e.g.
//       "shell: pinned vertex 12 is out of range (the mesh has 9 vertices)"
//       "solid of mesh: FEM tetra constraint 3: ..."   (core's own message, prefixed)
//     Degenerate elements are rejected: by the constraint builders (zero rest length, flat
//     tetrahedron, ...) or, where the chosen families would accept them, by the mass lumping
//     ("shell: triangle 4 has zero area").
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <string_view>
#include <vector>

#include <tessera/core/model.hpp>
#include <tessera/core/real.hpp>
#include <tessera/io/generators.hpp>    // VertexIndex
#include <tessera/io/mesh_readers.hpp>  // Mesh

namespace tessera::io {

/// Out-of-plane stiffness of a shell.
enum class ShellBending {
  dihedral,   ///< dihedral-angle constraints (any rest angle)
  isometric,  ///< isometric bending (quadratic, for nearly inextensible cloth)
  none,
};
/// The names of ShellBending's values, in order (scene files, the tool's --bending).
inline constexpr std::array<std::string_view, 3> kShellBendingNames = {"dihedral", "isometric",
                                                                      "none"};

/// In-plane material of a shell.
enum class ShellMaterial {
  distance,         ///< distance constraints on the unique edges (XPBD compliance)
  strain_triangle,  ///< strain-based triangles, material axes per triangle (x along p0 → p1)
  fem_triangle,     ///< FEM triangles, isotropic (orthotropic with equal axes)
};
/// The names of ShellMaterial's values, in order (scene files, the tool's --shell-material).
inline constexpr std::array<std::string_view, 3> kShellMaterialNames = {
    "distance", "strain_triangle", "fem_triangle"};

struct ShellOptions {
  ShellMaterial material = ShellMaterial::distance;
  ShellBending bending = ShellBending::dihedral;
  /// XPBD compliance α ≥ 0 of the distance edges.
  Real distance_compliance = 0;
  /// XPBD compliance α ≥ 0 of the dihedral or isometric bending constraints.
  Real bending_compliance = Real(1e-3);
  /// FEM triangles: Young's modulus E > 0 and Poisson ratio 0 ≤ ν < 0.5, the same along both
  /// material axes; the shear modulus is E / (2 (1 + ν)).
  Real youngs_modulus = Real(1e4);
  Real poisson_ratio = Real(0.3);
  /// Total mass > 0, lumped by area (see the top of this file).
  Real mass = 1;
};

/// Material of a solid.
enum class SolidMaterial {
  fem_tetra,            ///< FEM tetrahedra (Young's modulus, Poisson ratio; inversion-robust)
  strain_tetra,         ///< strain-based tetrahedra (unit stiffnesses)
  volume_and_distance,  ///< volume per tetrahedron plus distance per unique edge
};
/// The names of SolidMaterial's values, in order (scene files, the tool's --solid-material).
inline constexpr std::array<std::string_view, 3> kSolidMaterialNames = {
    "fem_tetra", "strain_tetra", "volume_and_distance"};

struct SolidOptions {
  SolidMaterial material = SolidMaterial::fem_tetra;
  /// FEM tetrahedra: Young's modulus E > 0 and Poisson ratio 0 ≤ ν < 0.5.
  Real youngs_modulus = Real(1e6);
  Real poisson_ratio = Real(0.3);
  /// volume_and_distance: XPBD compliances α ≥ 0 of the volumes and of the edges.
  Real volume_compliance = 0;
  Real distance_compliance = 0;
  /// Total mass > 0, lumped by volume (see the top of this file).
  Real mass = 1;
};

/// A triangle mesh (3 indices per triangle) as a cloth shell: the in-plane material of
/// `options`, bending across every interior manifold edge, the particles in `pinned` fixed.
/// Throws InvalidInput for no triangles, an index out of range or repeated within a triangle,
/// a pinned index out of range, options out of range or not finite, a degenerate triangle.
Model make_shell(std::span<const Vector3r> positions, std::span<const VertexIndex> triangles,
                 std::span<const VertexIndex> pinned, const ShellOptions& options = {});

/// A tetrahedral mesh (4 indices per tetrahedron, either orientation) as a solid, the
/// particles in `pinned` fixed. Throws InvalidInput as make_shell does (flat tetrahedra).
Model make_solid(std::span<const Vector3r> positions, std::span<const VertexIndex> tetrahedra,
                 std::span<const VertexIndex> pinned, const SolidOptions& options = {});

/// The default cloth: make_cloth_grid(columns, rows) 1 m wide (spacing 1 / (columns - 1)),
/// turned into the xz plane (grid (x, y) → (x, 0, y)), with the two corners of its last row,
/// vertices (rows - 1) * columns and rows * columns - 1, pinned.
Model make_cloth_scene(std::size_t columns, std::size_t rows, const ShellOptions& options = {});

/// The default bar: make_tetrahedral_bar(cells_x, cells_y, cells_z) with 0.1 m cells, its
/// vertices at z = 0 pinned.
Model make_bar_scene(std::size_t cells_x, std::size_t cells_y, std::size_t cells_z,
                     const SolidOptions& options = {});

/// A read mesh as a model: with tetrahedra a solid (its triangles ignored), otherwise with
/// triangles a shell; the particles in `pinned` fixed (see lowest_vertices for a common
/// choice). Throws InvalidInput when the mesh has neither triangles nor tetrahedra.
Model make_model(const Mesh& mesh, std::span<const VertexIndex> pinned,
                 const ShellOptions& shell = {}, const SolidOptions& solid = {});

/// How close to the extreme coordinate a vertex must be for the pin rules "lowest-<axis>" /
/// "highest-<axis>": a fraction of the bounding box's diagonal (rounding only).
inline constexpr Real kExtremeVertexBand = Real(1e-6);
/// The patch a mesh scene without explicit pins hangs from or stands on: the vertices within
/// 2 % of the diagonal of its lowest (solid) or highest (shell) one. One vertex would carry
/// the whole weight (a 13 k-particle sphere ended with Green strain 59 there); the patch of a
/// sphere is a cap of about a third of its radius.
inline constexpr Real kDefaultPinPatch = Real(0.02);

/// The vertices lowest along `axis` (0 = x, 1 = y, 2 = z): every vertex within
/// band × (the diagonal of the bounding box) of the minimum coordinate, in increasing order.
/// Empty for no positions. Throws InvalidInput for an axis above 2, a non-finite position or
/// a band that is negative or not finite.
std::vector<VertexIndex> lowest_vertices(std::span<const Vector3r> positions,
                                         std::size_t axis = 1, Real band = kExtremeVertexBand);

/// Bending stencils of a triangle mesh: four indices (wing0, wing1, edge0, edge1) per interior
/// manifold edge edge0–edge1 (edge0 < edge1), in the order of the edges sorted by (edge0,
/// edge1); the wings are the vertices opposite the edge in its two triangles, wing0 the one
/// whose triangle runs edge0 → edge1 when the two are consistently oriented (else the one
/// listed first). This is the layout of ClothGrid::bending_indices and of the dihedral and
/// isometric bending inputs. Throws InvalidInput for an index count not a multiple of 3, an
/// index out of [0, vertex_count) or a vertex repeated within a triangle.
std::vector<VertexIndex> bending_stencils(std::span<const VertexIndex> triangles,
                                          std::size_t vertex_count);

/// The triangles on the boundary of a tetrahedral mesh: every face that belongs to exactly
/// one tetrahedron, oriented outwards when the tetrahedron is positively oriented, in the
/// order of the tetrahedra. Throws InvalidInput for an index count not a multiple of 4.
std::vector<VertexIndex> boundary_triangles(std::span<const VertexIndex> tetrahedra);

/// Lumped vertex masses of a mesh of elements with `vertices_per_element` (3: triangles by
/// area, 4: tetrahedra by volume) vertices: `total_mass` spread over the elements in
/// proportion to their measure, each element's share split equally among its vertices;
/// vertices in no element get 0. Throws InvalidInput for another element size, an index out
/// of range, an element of zero measure or a total_mass not positive and finite.
std::vector<Real> lumped_masses(std::span<const Vector3r> positions,
                                std::span<const VertexIndex> elements,
                                std::size_t vertices_per_element, Real total_mass);

}  // namespace tessera::io
