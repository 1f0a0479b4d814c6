// A scene description: the plain settings a scene is made from (where its geometry comes
// from, which particles are pinned, the shell and solid materials, how it is simulated), and
// build_scene, which turns one into a Model plus the mesh to draw it with.
//
//   parse (scene_file.hpp) ──► SceneDescription ──► build_scene() ──► Scene { Model, mesh }
//
// The description is data only: it is filled by the parsers of scene_file.hpp, by a program
// directly, or by the tool's options, and build_scene reads nothing but it (and the mesh file
// it names). The simulation settings are io's own plain struct: io depends on core only, so
// the tool maps them to the solver's SolverSettings (apps/solver_settings.hpp).
//
// Pins. "default" is each source's own choice: the generated cloth hangs from the two corners
// of its last row, the generated bar is fixed at z = 0, a tetrahedral mesh stands on a patch
// around its lowest vertex along y and a triangle mesh hangs from a patch around its highest
// (the vertices within kDefaultPinPatch of the bounding-box diagonal, scenes.hpp).
// "lowest-<axis>" / "highest-<axis>" pin every vertex within 1e-6 of the diagonal of the
// extreme coordinate; a list names vertex numbers.
//
// Tethers. "auto" (the default) adds long-range attachments (long_range_attachments.hpp) to
// any scene with pins: every movable particle tethered to its tether_attachments nearest
// pinned ones along the mesh's edges (two by default). "none" leaves them out.
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <tessera/core/model.hpp>
#include <tessera/core/real.hpp>
#include <tessera/io/generators.hpp>    // VertexIndex
#include <tessera/io/mesh_readers.hpp>  // Mesh
#include <tessera/io/scenes.hpp>        // ShellOptions, SolidOptions, the builders

namespace tessera::io {

/// Where a scene's geometry comes from.
enum class SceneSource { cloth, bar, mesh, pile };

/// Which particles a scene pins (inverse mass 0); see the top of this file.
struct PinRule {
  enum class Kind { scene_default, none, lowest, highest, list };
  Kind kind = Kind::scene_default;
  std::size_t axis = 1;              ///< lowest / highest: 0 = x, 1 = y, 2 = z
  std::vector<VertexIndex> vertices;  ///< list
};

/// The reach of a scene's tethers over the rest path length: 1, the paper's. Measured on the
/// default cloth (60 frames of 32 × 1): 1.02 and 1.05 leave the same RMS residual (0.036 →
/// 0.038, 0.042) and move the largest from the top edge's middle to a fold; no gain to buy.
inline constexpr Real kDefaultTetherReachScale = Real(1);
/// Attachments each movable particle is tethered to, nearest first
/// (LongRangeAttachmentOptions::attachments). On the default cloth (60 frames of 32 × 1) one
/// leaves the top edge between the two pins free to sag, its middle edge 58 % long; two hold
/// that span straight: distance max 0.58 → 0.17, for 12 % more stepping time
/// (docs/performance.md, "Accuracy per second").
inline constexpr std::size_t kDefaultTetherAttachments = 2;
/// Substeps per frame of the cloth scenes (cloth, cloth:N, cloth:CxR): the fewest measured to
/// end the default scene (256², 60 frames, gs, two tethers per particle) within the accuracy
/// its users ask for, residual RMS ≤ 0.01 and max ≤ 0.10: 128 × 1 leaves 0.011 / 0.12,
/// 160 × 1 leaves 0.0088 / 0.085 (64 × 2 leaves 0.015 / 0.24: substeps beat iterations).
/// Smaller cloths end lower at the same setting (64²: 0.0093 / 0.068 from 64 substeps).
/// Other scenes keep SimulationSettings' 32.
inline constexpr std::size_t kClothSubsteps = 160;

/// Whether a scene gets long-range attachments (see the top of this file).
enum class TetherRule { automatic, none };
/// The names of TetherRule's values, in order (scene files, the tool's --tethers).
inline constexpr std::array<std::string_view, 2> kTetherRuleNames = {"auto", "none"};

/// A static collider of a scene: io's own plain description (io depends on core only); the
/// tool turns it into the collision module's collider (apps/solver_settings.hpp).
enum class ColliderShape { plane, sphere, box, capsule, mesh };
/// The names of ColliderShape's values, in order (scene files' "shape").
inline constexpr std::array<std::string_view, 5> kColliderShapeNames = {"plane", "sphere", "box",
                                                                        "capsule", "mesh"};
struct ColliderDescription {
  ColliderShape shape = ColliderShape::plane;
  /// plane: the surface n·x = offset, free on the side n points to (n need not be unit).
  Vector3r normal = Vector3r(0, 1, 0);
  Real offset = 0;
  /// sphere: centre and radius; box: centre and half extents (axis-aligned); capsule: the
  /// segment a–b and the radius.
  Vector3r centre = Vector3r::Zero();
  Real radius = 0;
  Vector3r half_extents = Vector3r::Zero();
  Vector3r a = Vector3r::Zero(), b = Vector3r::Zero();
  /// mesh: a triangle mesh file (OBJ, or any format read_mesh knows with triangles), read by
  /// build_scene into Scene::collider_meshes.
  std::filesystem::path mesh_file;
};

/// Contacts of a scene (the collision module's CollisionSettings, see
/// collision/include/tessera/collision/collision_stage.hpp for what each means): on when
/// there is a collider or self-collision.
struct CollisionDescription {
  std::vector<ColliderDescription> colliders;
  Real thickness = Real(0.005);
  Real static_friction = Real(0.4);
  Real dynamic_friction = Real(0.3);
  Real restitution = 0;
  bool self_collision = false;
  /// The most substeps between self-collision grid builds, each other substep refining their
  /// candidates (CollisionSettings::self_collision_interval; its default, kDefaultSelfCollisionInterval).
  std::size_t self_collision_interval = 16;

  bool enabled() const { return self_collision || !colliders.empty(); }
};

/// How long and how finely a scene is simulated, and with which strategy, mode and threads.
/// The tool's options override these field by field.
struct SimulationSettings {
  Vector3r gravity = Vector3r(0, Real(-9.81), 0);
  Real time_step = Real(1) / Real(60);
  /// Many substeps of one iteration (XPBD's "small steps"): for the same number of sweeps,
  /// substeps beat iterations. On the 256² cloth with one tether per particle (60 frames)
  /// 32 × 1 costs what 16 × 2 does and ends with the residual RMS 0.036 instead of 0.056 and
  /// the largest 0.58 instead of 3.5 (16 × 4: 0.032 / 0.59 for 1.6× the time). The cloth
  /// scenes take kClothSubsteps.
  std::size_t substeps = 32;
  std::size_t iterations = 1;
  std::size_t frames = 60;
  Real velocity_damping = 0;
  /// Chebyshev acceleration of mode jacobi and its ρ (SolverSettings::chebyshev,
  /// chebyshev_rho); unset keeps the solver's default.
  std::optional<bool> chebyshev;
  std::optional<Real> chebyshev_rho;
  std::string strategy = "stencil";
  std::string mode = "gs";
  /// Mode sequential's order: "groups" (the reference library's) or "input".
  std::string sequential_order = "groups";
  /// How contacts are scheduled in modes gs and hybrid: "jacobi" or "coloured"
  /// (SolverSettings::contact_scheduling); unset keeps the solver's default.
  std::optional<std::string> contact_scheduling;
  /// The RMS residual past which a step counts as diverged (SolverSettings::divergence_rms).
  Real divergence_rms = 10;
  /// 0: every hardware thread (the solver's meaning, tessera::worker_threads).
  std::size_t threads = 0;
};

struct SceneDescription {
  /// Shown in summaries: the spec or the scene file's "name".
  std::string name;
  SceneSource source = SceneSource::cloth;
  /// cloth: vertices along x and along z; bar: cells along x, y, z.
  std::size_t cloth_columns = 64, cloth_rows = 64;
  /// cloth: how each grid square is split (spec suffix ":alternating"; uniform by default,
  /// which the pinned state hashes of cloth scenes assume).
  DiagonalPattern cloth_diagonals = DiagonalPattern::uniform;
  std::array<std::size_t, 3> bar_cells{4, 4, 20};
  /// pile: the number of tetrahedral blocks (generators.hpp, make_pile).
  std::size_t pile_bodies = 8;
  /// mesh: the file (any extension read_mesh knows).
  std::filesystem::path mesh_file;
  PinRule pins;
  TetherRule tethers = TetherRule::automatic;
  /// XPBD compliance α ≥ 0 of the tethers (0: inextensible), and their reach as a multiple
  /// of the rest path length (LongRangeAttachmentOptions::reach_scale, ≥ 1).
  Real tether_compliance = 0;
  Real tether_reach_scale = kDefaultTetherReachScale;
  std::size_t tether_attachments = kDefaultTetherAttachments;
  ShellOptions shell;
  SolidOptions solid;
  CollisionDescription collisions;
  SimulationSettings simulation;
};

/// A scene ready to simulate: the model and the mesh it came from (rest positions in the
/// model's particle numbering, its triangles and tetrahedra; for a tetrahedral mesh also its
/// boundary triangles, so a viewer or OBJ writer has a surface to draw).
struct Scene {
  SceneDescription description;
  Model model;
  Mesh mesh;
  std::vector<VertexIndex> surface_triangles;
  std::vector<VertexIndex> pinned;
  /// The mesh of each mesh collider of description.collisions, in order.
  std::vector<Mesh> collider_meshes;
};

/// Generates or reads the geometry, applies the pins and materials. Throws InvalidInput
/// (unreadable or bad mesh files with their own messages, a pin out of range, ...).
Scene build_scene(const SceneDescription& description);

}  // namespace tessera::io
