// Scene files and specs: parsing only. A short spec on a command line ("cloth:512x512",
// "bar:10x10x80", "sheet.obj") or a JSON scene file becomes a SceneDescription, the plain
// settings struct of scene_description.hpp; build_scene (there) turns that into a model.
// Nothing here opens a mesh or builds anything, and building never looks back at the text:
//
//   spec or scene file ──► parse_scene_spec / read_scene_file ──► SceneDescription
//                                                  ──► build_scene() ──► Scene { Model, mesh }
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
//     "tethers": "auto", "tether_compliance": 0,  // or "none": no long-range attachments
//     "tether_attachments": 2,               // pins each particle is tethered to, nearest first
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
//     "chebyshev": true, "chebyshev_rho": 0.9,  // mode jacobi's acceleration (solver.hpp)
//     "strategy": "stencil", "mode": "gs", "threads": 0,  // 0: every hardware thread
//     "sequential_order": "groups",          // mode sequential: or "input"
//     "contact_scheduling": "coloured",      // modes gs, hybrid: or "jacobi" (contacts)
//     "divergence_rms": 10,                  // a step above this RMS residual is a failure
//     "colliders": [                         // static colliders (ColliderDescription)
//       { "shape": "plane", "normal": [0, 1, 0], "offset": -0.6 },
//       { "shape": "sphere", "centre": [0.5, -0.35, 0.5], "radius": 0.25 },
//       { "shape": "box", "centre": [0, 0, 0], "half_extents": [1, 0.1, 1] },
//       { "shape": "capsule", "a": [0, 0, 0], "b": [1, 0, 0], "radius": 0.1 },
//       { "shape": "mesh", "file": "bowl.obj" } ],  // relative to the scene file
//     "thickness": 0.005,                    // contact distance (m)
//     "friction": 0.4, "dynamic_friction": 0.3,  // "friction" sets both, then the other wins
//     "restitution": 0, "self_collision": false,
//     "self_collision_interval": 16          // most substeps between self-collision grid builds
//   }
//
// What the pin rules pick is said with PinRule (scene_description.hpp).
//
// Errors are tessera::InvalidInput. A spec names itself ("scene 'cloth:0x5': ..."); a scene
// file names the file, and for JSON syntax errors the line and column
// ("hang.json: line 3, column 14: ..."), for a bad value the key ("hang.json: 'substeps'
// must be a positive integer, not -2").
#pragma once

#include <filesystem>
#include <istream>
#include <string>
#include <string_view>

#include <tessera/io/scene_description.hpp>

namespace tessera::io {

/// Parses "default", "none", "lowest-x" ... "highest-z"; throws InvalidInput otherwise.
PinRule parse_pin_rule(std::string_view text);
/// The inverse of parse_pin_rule for the named kinds; "list of N vertices" for a list.
std::string describe_pin_rule(const PinRule& rule);

/// Vertices per side of the "drape" scene.
inline constexpr std::size_t kDrapeVertices = 128;
/// Blocks of the "pile" scene, by default and at most.
inline constexpr std::size_t kPileBodies = 8;
inline constexpr std::size_t kMaxPileBodies = 4096;

/// A scene on the command line: "cloth" (64 × 64 vertices), "cloth:N" (N × N),
/// "cloth:CxR" (either followed by ":alternating" for chequerboard diagonals,
/// DiagonalPattern::alternating), "drape" / "drape:N" (a free N × N cloth, 128 by default,
/// falling onto a sphere and the ground with self-collision, 120 frames), "pile" / "pile:N"
/// (N FEM blocks, 8 by default, dropped crosswise onto the ground and onto each other, 90
/// frames), "bar" (4 × 4 × 20
/// cells), "bar:XxYxZ", a path ending in .json (read as a
/// scene file) or any other path (a mesh file, see read_mesh; not opened here). Sizes must be
/// at least 2 vertices (cloth) or 1 cell (bar) per side, and at most 2^31 vertices in all.
/// Throws InvalidInput naming the spec.
SceneDescription parse_scene_spec(std::string_view spec);

/// A JSON scene file (see the top of this file); "mesh" paths are taken relative to the
/// file's folder.
SceneDescription read_scene_file(const std::filesystem::path& file);
/// The same from a stream; `name` is used in messages, `base` resolves relative mesh paths.
SceneDescription parse_scene_json(std::istream& in, const std::string& name,
                                  const std::filesystem::path& base = {});

}  // namespace tessera::io
