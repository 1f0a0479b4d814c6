// Scenes: shells, solids, the default cloth and bar, and read meshes as Models; and
// build_scene, which builds a SceneDescription (scene_description.hpp) with them: geometry
// generated or read, pins picked by the description's rule, the shell or solid made.
//
// Each builder validates what core does not see (options, pins, element lists as a whole),
// then lets core's make_<family>_constraints validate the constraints themselves, re-throwing
// their InvalidInput with the name of what was being built in front. Strain triangles take
// their rest shape in the xy plane, which a mesh in space does not have: each triangle is
// laid into its own plane (x along p0 → p1) in a scratch array of 3 points per triangle, the
// batch is built against that array, and its particle indices are then pointed back at the
// mesh's vertices (validated here beforehand, as core would have).
#include <tessera/io/scenes.hpp>
#include <tessera/io/scene_description.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>

#include <tessera/core/error.hpp>
#include <tessera/core/long_range_attachments.hpp>

namespace tessera::io {
namespace {

/// A value as the messages print it ("-1", "0.5", "nan", "inf").
std::string number(Real value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

void require_vertex_count_fits(const std::string& context, std::size_t vertex_count) {
  if (vertex_count > std::numeric_limits<VertexIndex>::max())
    throw InvalidInput(context + ": " + std::to_string(vertex_count) +
                       " vertices do not fit a 32-bit vertex index");
}

/// Checks an element list: a whole number of elements, indices in range, none repeated
/// within an element. `element` names one element in messages ("triangle", "tetrahedron").
void check_elements(const std::string& context, std::span<const VertexIndex> elements,
                    std::size_t vertices_per_element, std::size_t vertex_count,
                    const char* element) {
  if (elements.size() % vertices_per_element != 0)
    throw InvalidInput(context + ": " + std::to_string(elements.size()) +
                       " indices are not a whole number of " + element + "s (" +
                       std::to_string(vertices_per_element) + " indices each)");
  for (std::size_t e = 0; e < elements.size() / vertices_per_element; ++e) {
    const VertexIndex* vertices = elements.data() + e * vertices_per_element;
    for (std::size_t k = 0; k < vertices_per_element; ++k) {
      if (vertices[k] >= vertex_count)
        throw InvalidInput(context + ": " + element + " " + std::to_string(e) + ": vertex " +
                           std::to_string(vertices[k]) + " is out of range (the mesh has " +
                           std::to_string(vertex_count) + " vertices)");
      for (std::size_t j = 0; j < k; ++j)
        if (vertices[j] == vertices[k])
          throw InvalidInput(context + ": " + element + " " + std::to_string(e) + ": vertex " +
                             std::to_string(vertices[k]) + " appears twice");
    }
  }
}

void check_pins(const std::string& context, std::span<const VertexIndex> pinned,
                std::size_t vertex_count) {
  for (const VertexIndex vertex : pinned)
    if (vertex >= vertex_count)
      throw InvalidInput(context + ": pinned vertex " + std::to_string(vertex) +
                         " is out of range (the mesh has " + std::to_string(vertex_count) +
                         " vertices)");
}

void require_positive(const std::string& context, const char* name, Real value) {
  if (!(value > 0) || !std::isfinite(value))
    throw InvalidInput(context + ": " + name + " is " + number(value) +
                       ", expected a positive finite number");
}

void require_non_negative(const std::string& context, const char* name, Real value) {
  if (!(value >= 0) || !std::isfinite(value))
    throw InvalidInput(context + ": " + name + " is " + number(value) +
                       ", expected a finite number >= 0");
}

void require_poisson_ratio(const std::string& context, Real value) {
  if (!(value >= 0 && value < Real(0.5)))
    throw InvalidInput(context + ": poisson_ratio is " + number(value) +
                       ", expected 0 <= poisson_ratio < 0.5");
}

void check_options(const std::string& context, const ShellOptions& options) {
  require_non_negative(context, "distance_compliance", options.distance_compliance);
  require_non_negative(context, "bending_compliance", options.bending_compliance);
  require_positive(context, "youngs_modulus", options.youngs_modulus);
  require_poisson_ratio(context, options.poisson_ratio);
  require_positive(context, "mass", options.mass);
}

void check_options(const std::string& context, const SolidOptions& options) {
  require_positive(context, "youngs_modulus", options.youngs_modulus);
  require_poisson_ratio(context, options.poisson_ratio);
  require_non_negative(context, "volume_compliance", options.volume_compliance);
  require_non_negative(context, "distance_compliance", options.distance_compliance);
  require_positive(context, "mass", options.mass);
}

/// Runs build(); an InvalidInput it throws (core's constraint or particle validation) comes
/// back with "<context>: " in front.
template <class Build>
auto with_context(const std::string& context, Build&& build) {
  try {
    return build();
  } catch (const InvalidInput& error) {
    throw InvalidInput(context + ": " + error.what());
  }
}

/// One side of a triangle: the edge as (lower, higher), the direction the triangle runs
/// along it, the vertex opposite it, and the triangle (for a deterministic tie order).
struct TriangleSide {
  VertexIndex lower;
  VertexIndex higher;
  VertexIndex from;
  VertexIndex opposite;
  std::size_t triangle;
};

/// All sides of (already validated) triangles, sorted by edge, then by triangle.
std::vector<TriangleSide> sorted_sides(std::span<const VertexIndex> triangles) {
  std::vector<TriangleSide> sides;
  sides.reserve(triangles.size());
  for (std::size_t t = 0; t < triangles.size() / 3; ++t) {
    for (std::size_t k = 0; k < 3; ++k) {
      const VertexIndex from = triangles[3 * t + k];
      const VertexIndex to = triangles[3 * t + (k + 1) % 3];
      const VertexIndex opposite = triangles[3 * t + (k + 2) % 3];
      sides.push_back({std::min(from, to), std::max(from, to), from, opposite, t});
    }
  }
  std::sort(sides.begin(), sides.end(), [](const TriangleSide& a, const TriangleSide& b) {
    return std::tie(a.lower, a.higher, a.triangle) < std::tie(b.lower, b.higher, b.triangle);
  });
  return sides;
}

/// The unique edges and the bending stencils of (already validated) triangles.
struct TriangleTopology {
  std::vector<VertexIndex> edges;     // (lower, higher) per edge, sorted
  std::vector<VertexIndex> stencils;  // (wing0, wing1, edge0, edge1) per interior manifold edge
};

TriangleTopology triangle_topology(std::span<const VertexIndex> triangles) {
  const std::vector<TriangleSide> sides = sorted_sides(triangles);
  TriangleTopology topology;
  for (std::size_t first = 0; first < sides.size();) {
    std::size_t end = first + 1;
    while (end < sides.size() && sides[end].lower == sides[first].lower &&
           sides[end].higher == sides[first].higher)
      ++end;
    const VertexIndex lower = sides[first].lower, higher = sides[first].higher;
    topology.edges.insert(topology.edges.end(), {lower, higher});
    // Exactly two triangles with different opposite vertices (a triangle listed twice has
    // the same one: no bending there).
    if (end - first == 2 && sides[first].opposite != sides[first + 1].opposite) {
      const bool second_runs_up = sides[first + 1].from == lower && sides[first].from != lower;
      const TriangleSide& wing0 = second_runs_up ? sides[first + 1] : sides[first];
      const TriangleSide& wing1 = second_runs_up ? sides[first] : sides[first + 1];
      topology.stencils.insert(topology.stencils.end(),
                               {wing0.opposite, wing1.opposite, lower, higher});
    }
    first = end;
  }
  return topology;
}

double element_measure(std::span<const Vector3r> positions, const VertexIndex* vertices,
                       std::size_t vertices_per_element) {
  const Eigen::Vector3d a = positions[vertices[0]].cast<double>();
  const Eigen::Vector3d b = positions[vertices[1]].cast<double>();
  const Eigen::Vector3d c = positions[vertices[2]].cast<double>();
  if (vertices_per_element == 3) return (b - a).cross(c - a).norm() / 2;
  const Eigen::Vector3d d = positions[vertices[3]].cast<double>();
  return std::abs((b - a).dot((c - a).cross(d - a))) / 6;
}

std::vector<Real> lumped_masses_in(const std::string& context,
                                   std::span<const Vector3r> positions,
                                   std::span<const VertexIndex> elements,
                                   std::size_t vertices_per_element, Real total_mass) {
  const char* element = vertices_per_element == 3 ? "triangle" : "tetrahedron";
  const std::size_t element_count = elements.size() / vertices_per_element;
  std::vector<double> measures(element_count);
  double total_measure = 0;
  for (std::size_t e = 0; e < element_count; ++e) {
    const VertexIndex* vertices = elements.data() + e * vertices_per_element;
    for (std::size_t k = 0; k < vertices_per_element; ++k)
      if (!positions[vertices[k]].allFinite())
        throw InvalidInput(context + ": position of vertex " + std::to_string(vertices[k]) +
                           " is not finite");
    measures[e] = element_measure(positions, vertices, vertices_per_element);
    if (!(measures[e] > 0))
      throw InvalidInput(context + ": " + element + " " + std::to_string(e) + " has zero " +
                         (vertices_per_element == 3 ? "area" : "volume"));
    total_measure += measures[e];
  }
  std::vector<double> masses(positions.size(), 0);
  const double mass_per_measure = double(total_mass) / total_measure;
  for (std::size_t e = 0; e < element_count; ++e) {
    const double share = measures[e] * mass_per_measure / double(vertices_per_element);
    for (std::size_t k = 0; k < vertices_per_element; ++k)
      masses[elements[e * vertices_per_element + k]] += share;
  }
  std::vector<Real> result(masses.size());
  std::transform(masses.begin(), masses.end(), result.begin(),
                 [](double mass) { return static_cast<Real>(mass); });
  return result;
}

/// The particles: inverse mass 1 / mass, 0 where the mass is 0 (no element) or pinned.
ParticleState particles_of(const std::string& context, std::span<const Vector3r> positions,
                           const std::vector<Real>& masses, std::span<const VertexIndex> pinned) {
  std::vector<Real> inverse_masses(masses.size(), 0);
  for (std::size_t v = 0; v < masses.size(); ++v)
    if (masses[v] > 0) inverse_masses[v] = Real(1) / masses[v];
  for (const VertexIndex vertex : pinned) inverse_masses[vertex] = 0;
  return with_context(context, [&] { return ParticleState(positions, inverse_masses); });
}

/// Strain triangles of a mesh in space: each triangle laid into its own plane (p0 at the
/// origin, x along p0 → p1, y toward p2), built there, then indexed into the mesh.
StrainTriangleConstraints strain_triangles(std::span<const Vector3r> positions,
                                           std::span<const VertexIndex> triangles) {
  const std::size_t triangle_count = triangles.size() / 3;
  std::vector<Vector3r> planar(triangles.size(), Vector3r::Zero());
  std::vector<ParticleIndex> planar_indices(triangles.size());
  for (std::size_t t = 0; t < triangle_count; ++t) {
    for (std::size_t k = 0; k < 3; ++k) planar_indices[3 * t + k] = ParticleIndex(3 * t + k);
    const Vector3r p0 = positions[triangles[3 * t]];
    const Vector3r e1 = positions[triangles[3 * t + 1]] - p0;
    const Vector3r e2 = positions[triangles[3 * t + 2]] - p0;
    const Vector3r normal = e1.cross(e2);
    const Real length = e1.norm();
    // A degenerate triangle stays all at the origin: core reports its zero area.
    if (!(length > 0) || !(normal.norm() > 0) || !normal.allFinite()) continue;
    const Vector3r x_axis = e1 / length;
    const Vector3r y_axis = normal.normalized().cross(x_axis);
    planar[3 * t + 1] = Vector3r(length, 0, 0);
    planar[3 * t + 2] = Vector3r(e2.dot(x_axis), e2.dot(y_axis), 0);
  }
  StrainTriangleConstraints result =
      make_strain_triangle_constraints({planar_indices, planar});
  for (std::size_t t = 0; t < triangle_count; ++t)
    for (std::size_t k = 0; k < 3; ++k) result.particles.particle[k][t] = triangles[3 * t + k];
  result.particles.particle_count = positions.size();
  return result;
}

/// What make_shell and make_solid check at the door, in this order: the vertex count, the
/// options, then the elements (`element` names one: "triangle", "tetrahedron") and the pins.
template <class Options>
void check_input(const std::string& context, std::span<const Vector3r> positions,
                 std::span<const VertexIndex> elements, std::size_t vertices_per_element,
                 const char* element, std::span<const VertexIndex> pinned, const Options& options) {
  require_vertex_count_fits(context, positions.size());
  check_options(context, options);
  if (elements.empty())
    throw InvalidInput(context + ": the mesh has no " +
                       (vertices_per_element == 3 ? "triangles" : "tetrahedra"));
  check_elements(context, elements, vertices_per_element, positions.size(), element);
  check_pins(context, pinned, positions.size());
}

Model shell_in(const std::string& context, std::span<const Vector3r> positions,
               std::span<const VertexIndex> triangles, std::span<const VertexIndex> pinned,
               const ShellOptions& options) {
  check_input(context, positions, triangles, 3, "triangle", pinned, options);

  const TriangleTopology topology = triangle_topology(triangles);
  Model model;
  ConstraintSets& sets = model.constraints;
  with_context(context, [&] {
    switch (options.material) {
      case ShellMaterial::distance:
        sets.distance = make_distance_constraints(
            {topology.edges, positions, Real(1), options.distance_compliance});
        break;
      case ShellMaterial::strain_triangle:
        sets.strain_triangle = strain_triangles(positions, triangles);
        break;
      case ShellMaterial::fem_triangle: {
        const Real shear_modulus = options.youngs_modulus / (2 * (1 + options.poisson_ratio));
        sets.fem_triangle = make_fem_triangle_constraints(
            {triangles, positions, options.youngs_modulus, options.youngs_modulus,
             shear_modulus, options.poisson_ratio, options.poisson_ratio});
        break;
      }
    }
    switch (options.bending) {
      case ShellBending::dihedral:
        sets.dihedral = make_dihedral_constraints(
            {topology.stencils, positions, Real(1), options.bending_compliance});
        break;
      case ShellBending::isometric:
        sets.isometric_bending = make_isometric_bending_constraints(
            {topology.stencils, positions, Real(1), options.bending_compliance});
        break;
      case ShellBending::none:
        break;
    }
    return 0;
  });
  const std::vector<Real> masses = lumped_masses_in(context, positions, triangles, 3, options.mass);
  model.particles = particles_of(context, positions, masses, pinned);
  return model;
}

Model solid_in(const std::string& context, std::span<const Vector3r> positions,
               std::span<const VertexIndex> tetrahedra, std::span<const VertexIndex> pinned,
               const SolidOptions& options) {
  check_input(context, positions, tetrahedra, 4, "tetrahedron", pinned, options);

  Model model;
  ConstraintSets& sets = model.constraints;
  with_context(context, [&] {
    switch (options.material) {
      case SolidMaterial::fem_tetra:
        sets.fem_tetra = make_fem_tetra_constraints(
            {tetrahedra, positions, options.youngs_modulus, options.poisson_ratio, true});
        break;
      case SolidMaterial::strain_tetra:
        sets.strain_tetra = make_strain_tetra_constraints({tetrahedra, positions});
        break;
      case SolidMaterial::volume_and_distance: {
        sets.volume = make_volume_constraints(
            {tetrahedra, positions, Real(1), options.volume_compliance});
        const std::vector<VertexIndex> edges = unique_edges(
            std::vector<VertexIndex>(tetrahedra.begin(), tetrahedra.end()), 4, positions.size());
        sets.distance = make_distance_constraints(
            {edges, positions, Real(1), options.distance_compliance});
        break;
      }
    }
    return 0;
  });
  const std::vector<Real> masses =
      lumped_masses_in(context, positions, tetrahedra, 4, options.mass);
  model.particles = particles_of(context, positions, masses, pinned);
  return model;
}

/// A generated scene's mesh with the particles its source pins by default.
struct PinnedMesh {
  Mesh mesh;
  std::vector<VertexIndex> pinned;
};

/// The default cloth (make_cloth_scene): 1 m wide in the xz plane, hung from the two corners
/// of its last row.
PinnedMesh cloth_mesh(std::size_t columns, std::size_t rows, DiagonalPattern diagonals) {
  ClothGrid grid = columns < 2 ? make_cloth_grid(columns, rows)  // reports the size
                               : make_cloth_grid(columns, rows, Real(1) / Real(columns - 1),
                                                 diagonals);
  for (Vector3r& p : grid.positions) p = Vector3r(p.x(), 0, p.y());
  PinnedMesh cloth;
  cloth.mesh.positions = std::move(grid.positions);
  cloth.mesh.triangles = std::move(grid.triangle_indices);
  cloth.pinned = {VertexIndex((rows - 1) * columns), VertexIndex(rows * columns - 1)};
  return cloth;
}

/// The pile scene's blocks: 3 × 3 × 8 cells of 4 cm (12 × 12 × 32 cm), two per layer, the
/// layers crosswise (long along z, then along x) 20 cm apart from 10 cm above the ground,
/// each block tilted 7° about its long axis (the two of a layer opposite ways) so they land
/// on edges; no pins.
PinnedMesh pile_mesh(std::size_t bodies) {
  constexpr Real kSpacing = Real(0.04);
  const TetrahedralBar block = make_tetrahedral_bar(3, 3, 8, kSpacing);
  const Vector3r centre(Real(1.5) * kSpacing, Real(1.5) * kSpacing, 4 * kSpacing);
  PinnedMesh pile;
  Mesh& mesh = pile.mesh;
  mesh.positions.reserve(bodies * block.vertex_count());
  mesh.tetrahedra.reserve(bodies * block.tetrahedron_indices.size());
  for (std::size_t body = 0; body < bodies; ++body) {
    const std::size_t layer = body / 2;
    const Real side = body % 2 == 0 ? Real(-1) : Real(1);
    const bool crosswise = layer % 2 == 1;
    const Real tilt = side * Real(0.08);  // radians, about the block's long axis (z)
    const Real c = std::cos(tilt), s = std::sin(tilt);
    // The last block of an odd count sits alone in the middle of its layer.
    const Real offset = (body + 1 == bodies && bodies % 2 == 1) ? 0 : side * Real(0.09);
    const Vector3r at = crosswise ? Vector3r(0, Real(0.08) + Real(0.15) * Real(layer), offset)
                                  : Vector3r(offset, Real(0.08) + Real(0.15) * Real(layer), 0);
    const VertexIndex first = VertexIndex(mesh.positions.size());
    for (const Vector3r& rest : block.positions) {
      const Vector3r local = rest - centre;
      Vector3r tilted(c * local.x() - s * local.y(), s * local.x() + c * local.y(), local.z());
      // Crosswise: a quarter turn about y, (x, y, z) -> (z, y, -x) (a rotation, so the
      // tetrahedra keep their positive orientation).
      if (crosswise) tilted = Vector3r(tilted.z(), tilted.y(), -tilted.x());
      mesh.positions.push_back(tilted + at);
    }
    for (const VertexIndex v : block.tetrahedron_indices) mesh.tetrahedra.push_back(first + v);
  }
  return pile;
}

/// The default bar (make_bar_scene): 0.1 m cells, fixed at z = 0.
PinnedMesh bar_mesh(const std::array<std::size_t, 3>& cells) {
  TetrahedralBar bar = make_tetrahedral_bar(cells[0], cells[1], cells[2], Real(0.1));
  PinnedMesh pinned_bar;
  for (std::size_t v = 0; v < bar.vertex_count(); ++v)
    if (bar.positions[v].z() == 0) pinned_bar.pinned.push_back(VertexIndex(v));
  pinned_bar.mesh.positions = std::move(bar.positions);
  pinned_bar.mesh.tetrahedra = std::move(bar.tetrahedron_indices);
  return pinned_bar;
}

/// The pins a rule picks among `positions`, or `defaults` for scene_default.
std::vector<VertexIndex> pins_of(const PinRule& rule, std::span<const Vector3r> positions,
                                 std::vector<VertexIndex> defaults,
                                 Real band = kExtremeVertexBand) {
  switch (rule.kind) {
    case PinRule::Kind::scene_default: return defaults;
    case PinRule::Kind::none: return {};
    case PinRule::Kind::lowest: return lowest_vertices(positions, rule.axis, band);
    case PinRule::Kind::highest: {
      std::vector<Vector3r> mirrored(positions.begin(), positions.end());
      for (Vector3r& p : mirrored) p = -p;
      return lowest_vertices(mirrored, rule.axis, band);
    }
    case PinRule::Kind::list:
      for (const VertexIndex v : rule.vertices)
        if (v >= positions.size())
          throw InvalidInput("pins: vertex " + std::to_string(v) + " is out of range (the scene has " +
                             std::to_string(positions.size()) + " vertices)");
      return rule.vertices;
  }
  return {};
}

}  // namespace

Model make_shell(std::span<const Vector3r> positions, std::span<const VertexIndex> triangles,
                 std::span<const VertexIndex> pinned, const ShellOptions& options) {
  return shell_in("shell", positions, triangles, pinned, options);
}

Model make_solid(std::span<const Vector3r> positions, std::span<const VertexIndex> tetrahedra,
                 std::span<const VertexIndex> pinned, const SolidOptions& options) {
  return solid_in("solid", positions, tetrahedra, pinned, options);
}

Model make_cloth_scene(std::size_t columns, std::size_t rows, const ShellOptions& options) {
  const std::string context = "cloth scene";
  const PinnedMesh cloth = with_context(context, [&] { return cloth_mesh(columns, rows, DiagonalPattern::uniform); });
  return shell_in(context, cloth.mesh.positions, cloth.mesh.triangles, cloth.pinned, options);
}

Model make_bar_scene(std::size_t cells_x, std::size_t cells_y, std::size_t cells_z,
                     const SolidOptions& options) {
  const std::string context = "bar scene";
  const PinnedMesh bar =
      with_context(context, [&] { return bar_mesh({cells_x, cells_y, cells_z}); });
  return solid_in(context, bar.mesh.positions, bar.mesh.tetrahedra, bar.pinned, options);
}

Model make_model(const Mesh& mesh, std::span<const VertexIndex> pinned, const ShellOptions& shell,
                 const SolidOptions& solid) {
  if (!mesh.tetrahedra.empty())
    return solid_in("solid of mesh", mesh.positions, mesh.tetrahedra, pinned, solid);
  if (!mesh.triangles.empty())
    return shell_in("shell of mesh", mesh.positions, mesh.triangles, pinned, shell);
  throw InvalidInput("make_model: the mesh has no triangles and no tetrahedra (" +
                     std::to_string(mesh.vertex_count()) + " vertices)");
}

std::vector<VertexIndex> lowest_vertices(std::span<const Vector3r> positions, std::size_t axis,
                                         Real band) {
  if (axis > 2)
    throw InvalidInput("lowest_vertices: axis " + std::to_string(axis) +
                       " is not 0 (x), 1 (y) or 2 (z)");
  require_vertex_count_fits("lowest_vertices", positions.size());
  if (positions.empty()) return {};
  Vector3r low = positions[0], high = positions[0];
  for (std::size_t v = 0; v < positions.size(); ++v) {
    if (!positions[v].allFinite())
      throw InvalidInput("lowest_vertices: position of vertex " + std::to_string(v) +
                         " is not finite");
    low = low.cwiseMin(positions[v]);
    high = high.cwiseMax(positions[v]);
  }
  if (!(std::isfinite(band) && band >= 0))
    throw InvalidInput("lowest_vertices: band must be >= 0 and finite");
  const Real tolerance = band * (high - low).norm();
  const auto axis_index = static_cast<Eigen::Index>(axis);
  std::vector<VertexIndex> lowest;
  for (std::size_t v = 0; v < positions.size(); ++v)
    if (positions[v][axis_index] <= low[axis_index] + tolerance)
      lowest.push_back(VertexIndex(v));
  return lowest;
}

std::vector<VertexIndex> bending_stencils(std::span<const VertexIndex> triangles,
                                          std::size_t vertex_count) {
  check_elements("bending_stencils", triangles, 3, vertex_count, "triangle");
  return triangle_topology(triangles).stencils;
}

std::vector<Real> lumped_masses(std::span<const Vector3r> positions,
                                std::span<const VertexIndex> elements,
                                std::size_t vertices_per_element, Real total_mass) {
  const std::string context = "lumped_masses";
  if (vertices_per_element != 3 && vertices_per_element != 4)
    throw InvalidInput(context + ": elements of " + std::to_string(vertices_per_element) +
                       " vertices, expected 3 (triangles) or 4 (tetrahedra)");
  require_positive(context, "total_mass", total_mass);
  check_elements(context, elements, vertices_per_element, positions.size(),
                 vertices_per_element == 3 ? "triangle" : "tetrahedron");
  return lumped_masses_in(context, positions, elements, vertices_per_element, total_mass);
}

std::vector<VertexIndex> boundary_triangles(std::span<const VertexIndex> tetrahedra) {
  if (tetrahedra.size() % 4 != 0)
    throw InvalidInput("boundary_triangles: " + std::to_string(tetrahedra.size()) +
                       " indices are not a whole number of tetrahedra");
  // Faces opposite vertex d, c, b, a, each oriented outwards for a positive tetrahedron.
  constexpr int kFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  const std::size_t face_count = tetrahedra.size();  // 4 per tetrahedron
  // A face is on the boundary when no other face has its three vertices. Faces are bucketed
  // by their smallest vertex (modulo the face count, so any numbering fits) with a counting
  // sort, and compared within their bucket only: linear in the faces, where a sort of all of
  // them took 0.4 s of a 40x40x160 bar's start-up.
  if (face_count > std::numeric_limits<std::uint32_t>::max())
    throw InvalidInput("boundary_triangles: " + std::to_string(face_count / 4) +
                       " tetrahedra have more faces than 32-bit face numbers hold");
  std::vector<std::array<VertexIndex, 3>> keys(face_count);
  // bucket_start[b]: first the size of bucket b, then its end, then its start.
  std::vector<std::uint32_t> bucket_start(face_count + 1, 0);
  const auto bucket_of = [&](const std::array<VertexIndex, 3>& key) {
    return std::size_t(key[0]) % face_count;
  };
  for (std::size_t f = 0; f < face_count; ++f) {
    const VertexIndex* tet = tetrahedra.data() + (f / 4) * 4;
    std::array<VertexIndex, 3> key = {tet[kFaces[f % 4][0]], tet[kFaces[f % 4][1]],
                                      tet[kFaces[f % 4][2]]};
    std::sort(key.begin(), key.end());
    keys[f] = key;
    ++bucket_start[bucket_of(key)];
  }
  for (std::size_t b = 1; b < face_count; ++b) bucket_start[b] += bucket_start[b - 1];
  bucket_start[face_count] = std::uint32_t(face_count);
  std::vector<std::uint32_t> bucketed(face_count);  // each bucket's faces in ascending order
  for (std::size_t f = face_count; f-- > 0;)
    bucketed[--bucket_start[bucket_of(keys[f])]] = std::uint32_t(f);
  // Entry by entry: std::array's == calls memcmp, which is slow for 12 bytes.
  const auto same_key = [](const std::array<VertexIndex, 3>& a,
                           const std::array<VertexIndex, 3>& b) {
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
  };
  // A bucket of a few faces is compared pair by pair; a large one (a vertex in very many
  // tetrahedra) is sorted by key first, so no mesh makes this quadratic.
  constexpr std::size_t kPairwiseBucket = 32;
  std::vector<bool> on_boundary(face_count, false);
  for (std::size_t b = 0; b < face_count; ++b) {
    const auto first = bucketed.begin() + std::ptrdiff_t(bucket_start[b]);
    const auto last = bucketed.begin() + std::ptrdiff_t(bucket_start[b + 1]);
    if (std::size_t(last - first) > kPairwiseBucket) {
      std::sort(first, last, [&](std::uint32_t x, std::uint32_t y) {
        return std::tie(keys[x][0], keys[x][1], keys[x][2]) <
               std::tie(keys[y][0], keys[y][1], keys[y][2]);
      });
      for (auto i = first; i != last;) {
        auto j = i + 1;
        while (j != last && same_key(keys[*j], keys[*i])) ++j;
        on_boundary[*i] = j == i + 1;
        i = j;
      }
      continue;
    }
    for (auto i = first; i != last; ++i) {
      bool shared = false;
      for (auto j = first; j != last && !shared; ++j)
        shared = j != i && same_key(keys[*j], keys[*i]);
      on_boundary[*i] = !shared;
    }
  }
  std::vector<VertexIndex> triangles;
  for (std::size_t f = 0; f < face_count; ++f)
    if (on_boundary[f]) {
      const VertexIndex* tet = tetrahedra.data() + (f / 4) * 4;
      for (int k = 0; k < 3; ++k) triangles.push_back(tet[kFaces[f % 4][k]]);
    }
  return triangles;
}

Scene build_scene(const SceneDescription& description) {
  Scene scene;
  scene.description = description;
  Mesh& mesh = scene.mesh;
  std::vector<VertexIndex> default_pins;
  switch (description.source) {
    case SceneSource::cloth: {
      PinnedMesh cloth = cloth_mesh(description.cloth_columns, description.cloth_rows,
                                    description.cloth_diagonals);
      mesh = std::move(cloth.mesh);
      default_pins = std::move(cloth.pinned);
      break;
    }
    case SceneSource::bar: {
      PinnedMesh bar = bar_mesh(description.bar_cells);
      mesh = std::move(bar.mesh);
      default_pins = std::move(bar.pinned);
      break;
    }
    case SceneSource::pile: {
      mesh = pile_mesh(description.pile_bodies).mesh;
      break;
    }
    case SceneSource::mesh: {
      mesh = read_mesh(description.mesh_file);
      if (mesh.tetrahedra.empty() && mesh.triangles.empty())
        throw InvalidInput(description.mesh_file.string() + ": the mesh has no triangles and no tetrahedra");
      PinRule rule;
      rule.kind = mesh.tetrahedra.empty() ? PinRule::Kind::highest : PinRule::Kind::lowest;
      default_pins = pins_of(rule, mesh.positions, {}, kDefaultPinPatch);
      break;
    }
  }
  scene.pinned = pins_of(description.pins, mesh.positions, std::move(default_pins));
  if (!mesh.tetrahedra.empty()) {
    mesh.triangles.clear();  // a solid's own triangles (TetGen .face, Gmsh surfaces) are not simulated
    scene.model = make_solid(mesh.positions, mesh.tetrahedra, scene.pinned, description.solid);
    scene.surface_triangles = boundary_triangles(mesh.tetrahedra);
  } else {
    scene.model = make_shell(mesh.positions, mesh.triangles, scene.pinned, description.shell);
    scene.surface_triangles = mesh.triangles;
  }
  if (description.tethers == TetherRule::automatic && !scene.pinned.empty()) {
    const bool solid = !mesh.tetrahedra.empty();
    const std::vector<VertexIndex> edges =
        unique_edges(solid ? mesh.tetrahedra : mesh.triangles, solid ? 4 : 3, mesh.vertex_count());
    const ParticleState& particles = scene.model.particles;
    scene.model.constraints.tether = make_long_range_attachments(
        mesh.positions,
        std::span(particles.inverse_mass.data(), particles.size()), edges,
        {.reach_scale = description.tether_reach_scale,
         .attachments = description.tether_attachments,
         .compliance = description.tether_compliance});
  }
  for (const ColliderDescription& collider : description.collisions.colliders) {
    if (collider.shape != ColliderShape::mesh) continue;
    Mesh collider_mesh = read_mesh(collider.mesh_file);
    if (collider_mesh.triangles.empty())
      throw InvalidInput(collider.mesh_file.string() + ": a mesh collider needs triangles, the file has none");
    scene.collider_meshes.push_back(std::move(collider_mesh));
  }
  return scene;
}

}  // namespace tessera::io
