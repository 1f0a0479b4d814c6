// Scene descriptions: what to simulate and how, named by a short spec on a command line
// ("cloth:512x512", "bar:10x10x80", "sheet.obj") or written out in a JSON scene file, and
// turned into a Model plus the mesh to draw it with.
//
//   spec or scene file ──► SceneDescription ──► build_scene() ──► Scene { Model, mesh }
//
// A scene file is one JSON object (comments allowed). Every key is optional except the
// geometry (exactly one of "generator" and "mesh"); unknown keys are errors, so a typo is
// never silently ignored:
//
//   {
//     "name": "hanging sheet",               // shown in summaries (default: the spec/file)
//     "generator": "cloth:128x128",          // or "bar:10x10x80"; or instead:
//     "mesh": "sheet.obj",                   // a mesh file, relative to the scene file
//     "pins": "default",                     // "none", "lowest-y", "highest-x", ... or [0, 17]
//     "shell": { "material": "distance",     // or "strain_triangle", "fem_triangle"
//                "bending": "dihedral",      // or "isometric", "none"
//                "distance_compliance": 0, "bending_compliance": 1e-3,
//                "youngs_modulus": 1e4, "poisson_ratio": 0.3, "mass": 1 },
//     "solid": { "material": "fem_tetra",    // or "strain_tetra", "volume_and_distance"
//                "youngs_modulus": 1e6, "poisson_ratio": 0.3,
//                "volume_compliance": 0, "distance_compliance": 0, "mass": 1 },
//     "gravity": [0, -9.81, 0],
//     "time_step": 0.0166667, "substeps": 16, "iterations": 2, "frames": 60,
//     "velocity_damping": 0,
//     "strategy": "stencil", "mode": "gs", "threads": 0   // 0: every hardware thread
//   }
//
// Pins. "default" is each source's own choice: the generated cloth hangs from the two corners
// of its last row, the generated bar is fixed at z = 0, a tetrahedral mesh stands on its
// lowest vertices along y ("lowest-y") and a triangle mesh hangs from its highest
// ("highest-y"). "lowest-<axis>" / "highest-<axis>" pin every vertex within 1e-6 of the
// bounding-box diagonal of the extreme coordinate; an array lists vertex numbers.
//
// Errors are tessera::InvalidInput. A spec names itself ("scene 'cloth:0x5': ..."); a scene
// file names the file, and for JSON syntax errors the line and column
// ("hang.json: line 3, column 14: ..."), for a bad value the key ("hang.json: 'substeps'
// must be a positive integer, not -2").
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <istream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <tessera/core/model.hpp>
#include <tessera/core/real.hpp>
#include <tessera/io/generators.hpp>  // VertexIndex
#include <tessera/io/scenes.hpp>

namespace tessera::io {

/// Where a scene's geometry comes from.
enum class SceneSource { cloth, bar, mesh };

/// Which particles a scene pins (inverse mass 0).
struct PinRule {
  enum class Kind { scene_default, none, lowest, highest, list };
  Kind kind = Kind::scene_default;
  std::size_t axis = 1;              ///< lowest / highest: 0 = x, 1 = y, 2 = z
  std::vector<VertexIndex> vertices;  ///< list
};

/// Parses "default", "none", "lowest-x" ... "highest-z"; throws InvalidInput otherwise.
PinRule parse_pin_rule(std::string_view text);
/// The inverse of parse_pin_rule for the named kinds; "list of N vertices" for a list.
std::string describe_pin_rule(const PinRule& rule);

/// How long and how finely a scene is simulated, and with which strategy, mode and threads.
/// The tool's options override these field by field.
struct SimulationSettings {
  Vector3r gravity = Vector3r(0, Real(-9.81), 0);
  Real time_step = Real(1) / Real(60);
  /// Many substeps of few iterations: for the same number of projections, 16 × 2 leaves a
  /// 128² cloth 7× less stretched than 4 × 10 (XPBD's "small steps" observation).
  std::size_t substeps = 16;
  std::size_t iterations = 2;
  std::size_t frames = 60;
  Real velocity_damping = 0;
  std::string strategy = "stencil";
  std::string mode = "gs";
  std::size_t threads = 0;  ///< 0: every hardware thread
};

struct SceneDescription {
  /// Shown in summaries: the spec or the scene file's "name".
  std::string name;
  SceneSource source = SceneSource::cloth;
  /// cloth: vertices along x and along z; bar: cells along x, y, z.
  std::size_t cloth_columns = 64, cloth_rows = 64;
  std::array<std::size_t, 3> bar_cells{4, 4, 20};
  /// mesh: the file (any extension read_mesh knows).
  std::filesystem::path mesh_file;
  PinRule pins;
  ShellOptions shell;
  SolidOptions solid;
  SimulationSettings simulation;
};

/// A scene on the command line: "cloth" (64 × 64 vertices), "cloth:N" (N × N),
/// "cloth:CxR", "bar" (4 × 4 × 20 cells), "bar:XxYxZ", a path ending in .json (read as a
/// scene file) or any other path (a mesh file, see read_mesh). Sizes must be at least 2
/// vertices (cloth) or 1 cell (bar) per side, and at most 2^31 vertices in all. Throws
/// InvalidInput naming the spec.
SceneDescription parse_scene_spec(std::string_view spec);

/// A JSON scene file (see the top of this file); "mesh" paths are taken relative to the
/// file's folder.
SceneDescription read_scene_file(const std::filesystem::path& file);
/// The same from a stream; `name` is used in messages, `base` resolves relative mesh paths.
SceneDescription parse_scene_json(std::istream& in, const std::string& name,
                                  const std::filesystem::path& base = {});

/// A scene ready to simulate: the model and the mesh it came from (rest positions in the
/// model's particle numbering, its triangles and tetrahedra; for a tetrahedral mesh also its
/// boundary triangles, so a viewer or OBJ writer has a surface to draw).
struct Scene {
  SceneDescription description;
  Model model;
  Mesh mesh;
  std::vector<VertexIndex> surface_triangles;
  std::vector<VertexIndex> pinned;
};

/// Generates or reads the geometry, applies the pins and materials. Throws InvalidInput
/// (unreadable or bad mesh files with their own messages, a pin out of range, ...).
Scene build_scene(const SceneDescription& description);

/// The triangles on the boundary of a tetrahedral mesh: every face that belongs to exactly
/// one tetrahedron, oriented outwards when the tetrahedron is positively oriented, in the
/// order of the tetrahedra. Throws InvalidInput for an index count not a multiple of 4.
std::vector<VertexIndex> boundary_triangles(std::span<const VertexIndex> tetrahedra);

}  // namespace tessera::io
