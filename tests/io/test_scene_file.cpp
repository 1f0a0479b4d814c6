// Scene specs, JSON scene files and build_scene: every spec form, every key, the errors a
// typo or a bad value gives, and the models built from generators and mesh files.
#include <tessera/io/scene_file.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <gtest/gtest.h>

#include <tessera/collision/collision_stage.hpp>
#include <tessera/core/error.hpp>

namespace tessera::io {
namespace scene_file_tests {

SceneDescription from_json(const std::string& text) {
  std::istringstream in(text);
  return parse_scene_json(in, "scene.json", "/scenes");
}

/// The InvalidInput message `parse` throws, or "no error".
template <class Parse>
std::string error_of(Parse&& parse) {
  try {
    parse();
  } catch (const InvalidInput& error) {
    return error.what();
  }
  return "no error";
}
std::string json_error(const std::string& text) { return error_of([&] { from_json(text); }); }
std::string spec_error(const std::string& spec) { return error_of([&] { parse_scene_spec(spec); }); }

TEST(SceneSpec, GeneratorsWithAndWithoutSizes) {
  SceneDescription cloth = parse_scene_spec("cloth");
  EXPECT_EQ(cloth.source, SceneSource::cloth);
  EXPECT_EQ(cloth.cloth_columns, 64u);
  cloth = parse_scene_spec("cloth:33");
  EXPECT_EQ(cloth.cloth_columns, 33u);
  EXPECT_EQ(cloth.cloth_rows, 33u);
  cloth = parse_scene_spec("cloth:20x7");
  EXPECT_EQ(cloth.cloth_columns, 20u);
  EXPECT_EQ(cloth.cloth_rows, 7u);
  EXPECT_EQ(cloth.name, "cloth:20x7");
  EXPECT_EQ(cloth.cloth_diagonals, DiagonalPattern::uniform);
  cloth = parse_scene_spec("cloth:20x7:alternating");
  EXPECT_EQ(cloth.cloth_columns, 20u);
  EXPECT_EQ(cloth.cloth_rows, 7u);
  EXPECT_EQ(cloth.cloth_diagonals, DiagonalPattern::alternating);
  EXPECT_EQ(parse_scene_spec("cloth:9:alternating").cloth_rows, 9u);
  // The cloth scenes take their own substeps (the accuracy the default scene is measured to
  // need); the others keep the simulation's default.
  EXPECT_EQ(cloth.simulation.substeps, kClothSubsteps);
  const SceneDescription bar = parse_scene_spec("bar:2x3x4");
  EXPECT_EQ(bar.simulation.substeps, SimulationSettings{}.substeps);
  EXPECT_EQ(bar.source, SceneSource::bar);
  EXPECT_EQ(bar.bar_cells, (std::array<std::size_t, 3>{2, 3, 4}));
  const SceneDescription mesh = parse_scene_spec("meshes/sheet.OBJ");
  EXPECT_EQ(mesh.source, SceneSource::mesh);
  EXPECT_EQ(mesh.mesh_file, "meshes/sheet.OBJ");
}

TEST(SceneSpec, BadSizesNameTheSpec) {
  EXPECT_EQ(spec_error("cloth:1x5"), "scene 'cloth:1x5': a cloth needs at least 2 vertices per side");
  EXPECT_EQ(spec_error("cloth:axb"),
            "scene 'cloth:axb': expected cloth:N or cloth:CxR with vertex counts, e.g. cloth:256x256");
  EXPECT_EQ(spec_error("cloth:5x"),
            "scene 'cloth:5x': expected cloth:N or cloth:CxR with vertex counts, e.g. cloth:256x256");
  EXPECT_EQ(spec_error("bar:0x1x1"), "scene 'bar:0x1x1': a bar needs at least 1 cell per side");
  EXPECT_EQ(spec_error("bar:2x2"),
            "scene 'bar:2x2': expected bar:XxYxZ with cell counts, e.g. bar:10x10x80");
  EXPECT_EQ(spec_error("cloth:100000x100000"), "scene 'cloth:100000x100000': more than 2^31 vertices");
  EXPECT_EQ(spec_error("bar:999999999x999999999x999999999"),
            "scene 'bar:999999999x999999999x999999999': more than 2^31 vertices");
  EXPECT_EQ(spec_error(""), "scene '': empty");
  EXPECT_EQ(spec_error("missing.json"), "missing.json: cannot open the scene file");
}

TEST(SceneFile, EveryKey) {
  const SceneDescription scene = from_json(R"({
    // comments are allowed
    "name": "sheet", "mesh": "sheet.obj", "pins": [0, 3],
    "shell": {"material": "fem_triangle", "bending": "isometric", "distance_compliance": 1e-6,
              "bending_compliance": 0.5, "youngs_modulus": 200, "poisson_ratio": 0.25, "mass": 2},
    "solid": {"material": "volume_and_distance", "youngs_modulus": 3e5, "poisson_ratio": 0,
              "volume_compliance": 1e-7, "distance_compliance": 1e-8, "mass": 4},
    "gravity": [0, 0, -1], "time_step": 0.01, "substeps": 3, "iterations": 7, "frames": 0,
    "velocity_damping": 0.5, "chebyshev": false, "chebyshev_rho": 0.75, "strategy": "dsatur",
    "mode": "hybrid", "threads": 2, "tethers": "none", "tether_compliance": 1e-5,
    "tether_attachments": 3, "sequential_order": "input", "divergence_rms": 3})");
  EXPECT_EQ(scene.name, "sheet");
  EXPECT_EQ(scene.source, SceneSource::mesh);
  EXPECT_EQ(scene.mesh_file, std::filesystem::path("/scenes/sheet.obj"));
  EXPECT_EQ(scene.pins.kind, PinRule::Kind::list);
  EXPECT_EQ(scene.pins.vertices, (std::vector<VertexIndex>{0, 3}));
  EXPECT_EQ(scene.shell.material, ShellMaterial::fem_triangle);
  EXPECT_EQ(scene.shell.bending, ShellBending::isometric);
  EXPECT_FLOAT_EQ(scene.shell.distance_compliance, 1e-6f);
  EXPECT_FLOAT_EQ(scene.shell.bending_compliance, 0.5f);
  EXPECT_FLOAT_EQ(scene.shell.youngs_modulus, 200);
  EXPECT_FLOAT_EQ(scene.shell.poisson_ratio, 0.25f);
  EXPECT_FLOAT_EQ(scene.shell.mass, 2);
  EXPECT_EQ(scene.solid.material, SolidMaterial::volume_and_distance);
  EXPECT_FLOAT_EQ(scene.solid.youngs_modulus, 3e5f);
  EXPECT_FLOAT_EQ(scene.solid.poisson_ratio, 0);
  EXPECT_FLOAT_EQ(scene.solid.volume_compliance, 1e-7f);
  EXPECT_FLOAT_EQ(scene.solid.distance_compliance, 1e-8f);
  EXPECT_FLOAT_EQ(scene.solid.mass, 4);
  EXPECT_EQ(scene.simulation.gravity, Vector3r(0, 0, -1));
  EXPECT_FLOAT_EQ(scene.simulation.time_step, 0.01f);
  EXPECT_EQ(scene.simulation.substeps, 3u);
  EXPECT_EQ(scene.simulation.iterations, 7u);
  EXPECT_EQ(scene.simulation.frames, 0u);
  EXPECT_FLOAT_EQ(scene.simulation.velocity_damping, 0.5f);
  EXPECT_EQ(scene.simulation.chebyshev, false);
  EXPECT_EQ(scene.simulation.chebyshev_rho, Real(0.75));
  EXPECT_EQ(scene.simulation.strategy, "dsatur");
  EXPECT_EQ(scene.simulation.mode, "hybrid");
  EXPECT_EQ(scene.simulation.threads, 2u);
  EXPECT_EQ(scene.tethers, TetherRule::none);
  EXPECT_FLOAT_EQ(scene.tether_compliance, 1e-5f);
  EXPECT_EQ(scene.tether_attachments, 3u);
  EXPECT_EQ(scene.simulation.sequential_order, "input");
  EXPECT_FLOAT_EQ(scene.simulation.divergence_rms, 3);
}

TEST(SceneSpec, DrapeIsAFreeClothOverASphereAndTheGroundAgainstItself) {
  const SceneDescription drape = parse_scene_spec("drape");
  EXPECT_EQ(drape.source, SceneSource::cloth);
  EXPECT_EQ(drape.cloth_columns, kDrapeVertices);
  EXPECT_EQ(drape.cloth_rows, kDrapeVertices);
  EXPECT_EQ(drape.pins.kind, PinRule::Kind::none);
  EXPECT_EQ(drape.simulation.frames, 120u);
  ASSERT_EQ(drape.collisions.colliders.size(), 2u);
  EXPECT_EQ(drape.collisions.colliders[0].shape, ColliderShape::sphere);
  EXPECT_EQ(drape.collisions.colliders[1].shape, ColliderShape::plane);
  EXPECT_TRUE(drape.collisions.self_collision);
  EXPECT_TRUE(drape.collisions.enabled());
  // Thinner than half the grid spacing, so the flat cloth touches nothing of its own.
  EXPECT_LT(drape.collisions.thickness, Real(0.5) / Real(kDrapeVertices - 1));
  const SceneDescription small = parse_scene_spec("drape:16");
  EXPECT_EQ(small.cloth_columns, 16u);
  EXPECT_LT(small.collisions.thickness, Real(0.5) / Real(15));
  EXPECT_EQ(spec_error("drape:x"), "scene 'drape:x': expected drape or drape:N with a vertex count "
                                   "per side, e.g. drape:128");
  EXPECT_EQ(spec_error("drape:1"), "scene 'drape:1': a cloth needs at least 2 vertices per side");
  EXPECT_FALSE(parse_scene_spec("cloth").collisions.enabled());
}

TEST(SceneSpec, PileIsBlocksDroppedOntoTheGroundAndOntoEachOther) {
  const SceneDescription pile = parse_scene_spec("pile");
  EXPECT_EQ(pile.source, SceneSource::pile);
  EXPECT_EQ(pile.pile_bodies, kPileBodies);
  EXPECT_EQ(pile.pins.kind, PinRule::Kind::none);
  EXPECT_EQ(pile.simulation.frames, 90u);
  ASSERT_EQ(pile.collisions.colliders.size(), 1u);
  EXPECT_EQ(pile.collisions.colliders[0].shape, ColliderShape::plane);
  EXPECT_TRUE(pile.collisions.self_collision);
  EXPECT_EQ(parse_scene_spec("pile:3").pile_bodies, 3u);
  EXPECT_EQ(spec_error("pile:x"), "scene 'pile:x': expected pile or pile:N with a number of "
                                  "blocks, e.g. pile:8");
  EXPECT_EQ(spec_error("pile:0"), "scene 'pile:0': a pile needs at least 1 block");
  EXPECT_EQ(spec_error("pile:5000"), "scene 'pile:5000': at most 4096 blocks");
  EXPECT_EQ(from_json(R"({"generator": "pile:2", "friction": 0.6})").pile_bodies, 2u);

  // Built: N separate blocks of 4 × 4 × 9 vertices, every tetrahedron positive, none
  // overlapping another block, all above the ground, each block's surface its own.
  const Scene scene = build_scene(parse_scene_spec("pile:3"));
  ASSERT_EQ(scene.mesh.positions.size(), 3u * 144u);
  EXPECT_EQ(scene.mesh.tetrahedra.size(), 3u * 3 * 3 * 8 * 6 * 4);
  EXPECT_TRUE(scene.pinned.empty());
  for (std::size_t t = 0; t < scene.mesh.tetrahedra.size(); t += 4) {
    const auto& x = scene.mesh.positions;
    const auto* v = scene.mesh.tetrahedra.data() + t;
    EXPECT_GT((x[v[1]] - x[v[0]]).dot((x[v[2]] - x[v[0]]).cross(x[v[3]] - x[v[0]])), 0);
    EXPECT_EQ(v[0] / 144, v[3] / 144) << "a tetrahedron stays in its block";
  }
  for (const Vector3r& p : scene.mesh.positions) EXPECT_GT(p.y(), Real(0.01));
  EXPECT_EQ(scene.surface_triangles.size(), 3u * 2 * 2 * (3 * 3 + 3 * 8 + 3 * 8) * 3);
}

TEST(SceneFile, TheSelfCollisionIntervalDefaultsToTheStages) {
  EXPECT_EQ(SceneDescription{}.collisions.self_collision_interval, kDefaultSelfCollisionInterval);
  EXPECT_EQ(from_json(R"({"generator": "cloth:8", "self_collision_interval": 1})")
                .collisions.self_collision_interval,
            1u);
}

TEST(SceneFile, CollidersAndContactKeys) {
  const SceneDescription scene = from_json(R"({"generator": "cloth:8",
    "colliders": [{"shape": "plane", "normal": [0, 2, 0], "offset": -1},
                  {"shape": "sphere", "centre": [1, 2, 3], "radius": 0.5},
                  {"shape": "box", "centre": [0, -1, 0], "half_extents": [1, 0.1, 2]},
                  {"shape": "capsule", "a": [0, 0, 0], "b": [1, 0, 0], "radius": 0.2},
                  {"shape": "mesh", "file": "bowl.obj"}],
    "thickness": 0.01, "friction": 0.5, "restitution": 0.25, "self_collision": true})");
  const CollisionDescription& c = scene.collisions;
  ASSERT_EQ(c.colliders.size(), 5u);
  EXPECT_EQ(c.colliders[0].normal, Vector3r(0, 2, 0));
  EXPECT_EQ(c.colliders[0].offset, Real(-1));
  EXPECT_EQ(c.colliders[1].centre, Vector3r(1, 2, 3));
  EXPECT_EQ(c.colliders[1].radius, Real(0.5));
  EXPECT_EQ(c.colliders[2].half_extents, Vector3r(1, Real(0.1), 2));
  EXPECT_EQ(c.colliders[3].b, Vector3r(1, 0, 0));
  EXPECT_EQ(c.colliders[4].mesh_file, std::filesystem::path("/scenes/bowl.obj"));
  EXPECT_EQ(c.thickness, Real(0.01));
  // "friction" sets both coefficients; "dynamic_friction" then overrides its own.
  EXPECT_EQ(c.static_friction, Real(0.5));
  EXPECT_EQ(c.dynamic_friction, Real(0.5));
  EXPECT_EQ(from_json(R"({"generator": "cloth", "friction": 0.5, "dynamic_friction": 0.2})")
                .collisions.dynamic_friction,
            Real(0.2));
  EXPECT_EQ(c.restitution, Real(0.25));
  EXPECT_TRUE(c.self_collision);

  EXPECT_EQ(json_error(R"({"generator": "cloth", "thickness": -1})"),
            "scene.json: 'thickness' must be a number in [0, inf), not -1");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "friction": -0.1})"),
            "scene.json: 'friction' must be a number in [0, inf), not -0.1");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "restitution": 2})"),
            "scene.json: 'restitution' must be a number in [0, 1], not 2");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "self_collision": true, "thickness": 0})"),
            "scene.json: 'thickness' must be positive with 'self_collision' on");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "colliders": [{"shape": "cone"}]})"),
            "scene.json: 'colliders[0].shape' must be one of plane, sphere, box, capsule, mesh, "
            "not \"cone\"");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "colliders": [{"shape": "sphere", "radius": 1}]})"),
            "scene.json: 'colliders[0]' (a sphere) needs 'centre'");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "colliders": [{"shape": "sphere", "centre": [0, 0, 0], "radius": 0}]})"),
            "scene.json: 'colliders[0].radius' must be a number in (0, inf), not 0");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "colliders": [{"shape": "plane", "normal": [0, 0, 0]}]})"),
            "scene.json: 'colliders[0].normal' must not be zero");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "colliders": [{"shape": "box", "centre": [0, 0, 0], "half_extents": [1, -1, 1]}]})"),
            "scene.json: 'colliders[0].half_extents' must be positive");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "colliders": [{"shape": "plane", "normal": [0, 1, 0], "radius": 1}]})"),
            "scene.json: unknown key 'colliders[0].radius'");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "colliders": {"shape": "plane"}})"),
            "scene.json: 'colliders' must be an array of colliders, not {\"shape\":\"plane\"}");
}

TEST(SceneFile, GeneratorAndPinRule) {
  const SceneDescription scene = from_json(R"({"generator": "bar:1x2x3", "pins": "highest-z"})");
  EXPECT_EQ(scene.source, SceneSource::bar);
  EXPECT_EQ(scene.bar_cells, (std::array<std::size_t, 3>{1, 2, 3}));
  EXPECT_EQ(scene.pins.kind, PinRule::Kind::highest);
  EXPECT_EQ(scene.pins.axis, 2u);
  EXPECT_EQ(scene.name, "bar:1x2x3");
  EXPECT_EQ(scene.simulation.substeps, SimulationSettings{}.substeps);
  EXPECT_FALSE(scene.simulation.chebyshev.has_value());  // the solver's default
  EXPECT_FALSE(scene.simulation.chebyshev_rho.has_value());
}

TEST(SceneFile, ErrorsNameTheKeyOrTheLine) {
  EXPECT_EQ(json_error(R"({"generator": "cloth", "substep": 3})"), "scene.json: unknown key 'substep'");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "shell": {"stiffness": 1}})"),
            "scene.json: unknown key 'shell.stiffness'");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "substeps": -2})"),
            "scene.json: 'substeps' must be a positive integer, not -2");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "substeps": 0})"),
            "scene.json: 'substeps' must be a positive integer up to 2^31, not 0");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "tether_attachments": 0})"),
            "scene.json: 'tether_attachments' must be a positive integer up to 2^31, not 0");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "time_step": "fast"})"),
            "scene.json: 'time_step' must be a number in (0, inf), not \"fast\"");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "chebyshev": "yes"})"),
            "scene.json: 'chebyshev' must be true or false, not \"yes\"");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "chebyshev_rho": 1})"),
            "scene.json: 'chebyshev_rho' must be a number in (0, 1), not 1");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "shell": {"poisson_ratio": 0.5}})"),
            "scene.json: 'shell.poisson_ratio' must be a number in [0, 0.5), not 0.5");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "shell": {"bending": "soft"}})"),
            "scene.json: 'shell.bending' must be one of dihedral, isometric, none, not \"soft\"");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "gravity": [0, 1e400, 0]})"),
            "scene.json: number overflow parsing '1e400'");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "time_step": 1e200})"),
            sizeof(Real) == sizeof(float)
                ? "scene.json: 'time_step' must be a number in (0, inf), not 1e+200"
                : "no error");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "gravity": [0, 1]})"),
            "scene.json: 'gravity' must be an array of 3 finite numbers, not [0,1]");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "pins": [1, -1]})"),
            "scene.json: 'pins'[1] must be a vertex number, not -1");
  EXPECT_EQ(json_error(R"({"generator": "cloth", "pins": "left"})"),
            "scene.json: 'pins': unknown pin rule 'left' (known: default, none, lowest-x, "
            "lowest-y, lowest-z, highest-x, highest-y, highest-z)");
  EXPECT_EQ(json_error(R"({"generator": "sphere"})"),
            "scene.json: 'generator' must be \"cloth\", \"cloth:CxR\", \"drape:N\", \"pile:N\", \"bar\" or \"bar:XxYxZ\", not \"sphere\"");
  EXPECT_EQ(json_error(R"({"generator": "clothes.json"})"),
            "scene.json: 'generator' must be \"cloth\", \"cloth:CxR\", \"drape:N\", \"pile:N\", \"bar\" or \"bar:XxYxZ\", not \"clothes.json\"");
  EXPECT_EQ(json_error(R"({"generator": "cloth:1"})"),
            "scene.json: 'generator': scene 'cloth:1': a cloth needs at least 2 vertices per side");
  EXPECT_EQ(json_error(R"({"frames": 3})"),
            "scene.json: the scene needs exactly one of 'generator' (e.g. \"cloth:128x128\") and 'mesh' (a file)");
  EXPECT_EQ(json_error(R"([1, 2])"), "scene.json: the scene must be an object");
  EXPECT_EQ(json_error("{\n  \"generator\": \"cloth\",\n  \"frames\": 3,,\n}"),
            "scene.json: line 3, column 15: syntax error while parsing object key - unexpected ','; "
            "expected string literal");
  EXPECT_EQ(json_error(""), "scene.json: line 1, column 1: syntax error while parsing value - "
                            "unexpected end of input; expected '[', '{', or a literal");
}

TEST(BuildScene, ClothHangsFromTwoCornersByDefault) {
  const Scene scene = build_scene(parse_scene_spec("cloth:5x4"));
  EXPECT_EQ(scene.model.particles.size(), 20u);
  EXPECT_EQ(scene.pinned, (std::vector<VertexIndex>{15, 19}));
  EXPECT_EQ(scene.surface_triangles.size(), 4u * 3u * 2u * 3u);
  EXPECT_GT(scene.model.constraints.distance.size(), 0u);
  EXPECT_GT(scene.model.constraints.dihedral.size(), 0u);
  for (std::size_t p = 0; p < 20; ++p)
    EXPECT_EQ(scene.model.particles.inverse_mass[p] == 0, p == 15 || p == 19) << p;
}

TEST(BuildScene, ClothDiagonalsAreAnOptionOfTheSpec) {
  // The same vertices and pins, the triangles of make_cloth_grid's alternating pattern.
  const Scene uniform = build_scene(parse_scene_spec("cloth:5x4"));
  const Scene alternating = build_scene(parse_scene_spec("cloth:5x4:alternating"));
  EXPECT_EQ(alternating.pinned, uniform.pinned);
  EXPECT_EQ(alternating.mesh.positions, uniform.mesh.positions);
  EXPECT_NE(alternating.mesh.triangles, uniform.mesh.triangles);
  EXPECT_EQ(alternating.mesh.triangles,
            make_cloth_grid(5, 4, Real(0.25), DiagonalPattern::alternating).triangle_indices);
  EXPECT_EQ(spec_error("cloth:5x4:diagonal"),
            "scene 'cloth:5x4:diagonal': expected cloth:N or cloth:CxR with vertex counts, e.g. cloth:256x256");
}

TEST(BuildScene, PinnedScenesGetTethersToTheirTwoNearestPins) {
  // 5 × 4 cloth hung from vertices 15 and 19: every other vertex gets two tethers, the nearer
  // corner along the grid's edges first (the middle column depends on the diagonals).
  SceneDescription description = parse_scene_spec("cloth:5x4");
  ASSERT_EQ(description.tether_attachments, 2u);
  const Scene scene = build_scene(description);
  const TetherConstraints& tethers = scene.model.constraints.tether;
  ASSERT_EQ(tethers.size(), 36u);
  for (std::size_t c = 0; c < tethers.size(); ++c) {
    const VertexIndex p = tethers.particles.particle[0][c], pin = tethers.particles.particle[1][c];
    EXPECT_EQ(p, tethers.particles.particle[0][c ^ 1]) << "two per vertex, side by side";
    const VertexIndex nearer = p % 5 < 2 ? 15u : 19u;
    if (p % 5 != 2) {
      EXPECT_EQ(pin, c % 2 == 0 ? nearer : 34u - nearer) << "vertex " << p;
    }
    EXPECT_TRUE(pin == 15 || pin == 19);
    if (c % 2 == 1) {
      EXPECT_NE(pin, tethers.particles.particle[1][c - 1]);
      EXPECT_GE(tethers.max_distance[c], tethers.max_distance[c - 1]) << "nearer first";
    }
    // Never shorter than the straight rest distance.
    EXPECT_GE(tethers.max_distance[c],
              (scene.mesh.positions[p] - scene.mesh.positions[pin]).norm() * Real(0.99999));
  }
  description.tether_attachments = 1;
  EXPECT_EQ(build_scene(description).model.constraints.tether.size(), 18u);
  description.tethers = TetherRule::none;
  EXPECT_EQ(build_scene(description).model.constraints.tether.size(), 0u);
  description.tethers = TetherRule::automatic;
  description.pins = parse_pin_rule("none");
  EXPECT_EQ(build_scene(description).model.constraints.tether.size(), 0u) << "nothing to hold";
  // A solid's tethers follow its tetrahedra's edges.
  const Scene bar = build_scene(parse_scene_spec("bar:1x1x2"));
  EXPECT_EQ(bar.model.constraints.tether.size(), 2 * (12u - bar.pinned.size()));
}

TEST(BuildScene, MeshScenesWithoutPinsHoldAPatchNotOneVertex) {
  // A 21 × 21 sheet, gently curved so one vertex is highest: the default pins are the
  // vertices within 2 % of the diagonal of it (lowest_vertices' band), not that vertex alone.
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() / "tessera_test_dome.obj";
  {
    std::ofstream out(file);
    for (int j = 0; j <= 20; ++j)
      for (int i = 0; i <= 20; ++i) {
        const double x = i / 20.0 - 0.5, z = j / 20.0 - 0.5;
        out << "v " << x << ' ' << -(x * x + z * z) << ' ' << z << '\n';
      }
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 20; ++i) {
        const int a = j * 21 + i + 1;
        out << "f " << a << ' ' << a + 1 << ' ' << a + 22 << "\nf " << a << ' ' << a + 22 << ' '
            << a + 21 << '\n';
      }
  }
  const Scene dome = build_scene(parse_scene_spec(file.string()));
  std::filesystem::remove(file);
  EXPECT_GT(dome.pinned.size(), 4u);
  EXPECT_EQ(dome.pinned.size(), 37u) << "the lattice points within 0.173 m of the centre";
  const Real diagonal = std::sqrt(Real(2) + Real(0.25));
  for (const VertexIndex v : dome.pinned)
    EXPECT_GE(dome.mesh.positions[v].y(), -Real(0.02) * diagonal - Real(1e-6)) << v;
  EXPECT_TRUE(std::find(dome.pinned.begin(), dome.pinned.end(), VertexIndex(220)) !=
              dome.pinned.end())
      << "the highest vertex, the centre";
}

TEST(BuildScene, PinRulesAndMaterials) {
  SceneDescription description = parse_scene_spec("bar:1x1x2");
  description.pins = parse_pin_rule("highest-z");
  description.solid.material = SolidMaterial::strain_tetra;
  const Scene bar = build_scene(description);
  EXPECT_EQ(bar.pinned.size(), 4u);
  for (VertexIndex v : bar.pinned) EXPECT_FLOAT_EQ(bar.mesh.positions[v].z(), Real(0.2));
  EXPECT_EQ(bar.model.constraints.strain_tetra.size(), 12u);
  EXPECT_EQ(bar.model.constraints.fem_tetra.size(), 0u);
  // 2 cells of 2 × 2 triangles on each of the 4 long sides, 2 triangles on each end.
  EXPECT_EQ(bar.surface_triangles.size() / 3, 4u * 4u + 2u * 2u);

  description.pins = parse_pin_rule("none");
  EXPECT_TRUE(build_scene(description).pinned.empty());
  description.pins.kind = PinRule::Kind::list;
  description.pins.vertices = {0, 99};
  try {
    build_scene(description);
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& error) {
    EXPECT_STREQ(error.what(), "pins: vertex 99 is out of range (the scene has 12 vertices)");
  }
}

TEST(BuildScene, MeshFilesBecomeShellsAndSolids) {
  const std::filesystem::path data = TESSERA_TEST_DATA_DIR;
  const Scene square = build_scene(parse_scene_spec((data / "square.obj").string()));
  EXPECT_EQ(square.model.constraints.distance.size(), 5u);
  EXPECT_EQ(square.pinned, (std::vector<VertexIndex>{2, 3}));  // highest y hangs the sheet
  const Scene cube = build_scene(parse_scene_spec((data / "cube.node").string()));
  EXPECT_GT(cube.model.constraints.fem_tetra.size(), 0u);
  EXPECT_TRUE(cube.mesh.triangles.empty());
  EXPECT_FALSE(cube.surface_triangles.empty());
  for (VertexIndex v : cube.pinned)  // stands on its lowest vertices
    EXPECT_FLOAT_EQ(cube.mesh.positions[v].y(), cube.mesh.positions[cube.pinned[0]].y());
  EXPECT_THROW(build_scene(parse_scene_spec((data / "missing.obj").string())), InvalidInput);
}

TEST(BoundaryTriangles, OneTetrahedronFacesOutwards) {
  const std::vector<Vector3r> x = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const std::vector<VertexIndex> tet = {0, 1, 2, 3};
  const std::vector<VertexIndex> faces = boundary_triangles(tet);
  ASSERT_EQ(faces.size(), 12u);
  const Vector3r centre = (x[0] + x[1] + x[2] + x[3]) / 4;
  for (std::size_t f = 0; f < 4; ++f) {
    const Vector3r a = x[faces[3 * f]], b = x[faces[3 * f + 1]], c = x[faces[3 * f + 2]];
    EXPECT_GT((b - a).cross(c - a).dot((a + b + c) / 3 - centre), 0) << "face " << f;
  }
  EXPECT_THROW(boundary_triangles(std::vector<VertexIndex>{0, 1, 2}), InvalidInput);
}

TEST(BoundaryTriangles, SharedFacesAreInside) {
  const TetrahedralBar bar = make_tetrahedral_bar(2, 3, 4);
  const std::vector<VertexIndex> faces = boundary_triangles(bar.tetrahedron_indices);
  // Each of the box's unit squares on its surface is split into 2 triangles.
  EXPECT_EQ(faces.size() / 3, 2u * 2u * (2 * 3 + 3 * 4 + 2 * 4));
}

/// The faces no other face shares, by counting every face's sorted vertices (the definition,
/// written the slow way), in the function's order and orientation.
std::vector<VertexIndex> boundary_by_counting(const std::vector<VertexIndex>& tetrahedra) {
  constexpr int kFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::map<std::array<VertexIndex, 3>, int> count;
  const auto key = [&](std::size_t f) {
    std::array<VertexIndex, 3> k;
    for (int i = 0; i < 3; ++i) k[std::size_t(i)] = tetrahedra[(f / 4) * 4 + kFaces[f % 4][i]];
    std::sort(k.begin(), k.end());
    return k;
  };
  for (std::size_t f = 0; f < tetrahedra.size(); ++f) ++count[key(f)];
  std::vector<VertexIndex> faces;
  for (std::size_t f = 0; f < tetrahedra.size(); ++f)
    if (count[key(f)] == 1)
      for (int i = 0; i < 3; ++i) faces.push_back(tetrahedra[(f / 4) * 4 + kFaces[f % 4][i]]);
  return faces;
}

TEST(BoundaryTriangles, AVertexInManyTetrahedraAndAnyNumberingGiveTheFacesCounted) {
  // A fan of 100 tetrahedra around the edge (0, 1000): tetrahedra k and k + 1 share a face,
  // and vertex 0's faces (300) are more than a bucket compares pair by pair.
  std::vector<VertexIndex> fan;
  for (VertexIndex k = 0; k < 100; ++k) fan.insert(fan.end(), {0, k + 1, k + 2, 1000});
  const std::vector<VertexIndex> fan_faces = boundary_triangles(fan);
  EXPECT_EQ(fan_faces, boundary_by_counting(fan));
  EXPECT_EQ(fan_faces.size() / 3, 4 * 100 - 2 * 99u);
  // A bar, and the same bar numbered from a billion (far past the face count).
  const TetrahedralBar bar = make_tetrahedral_bar(3, 4, 5);
  EXPECT_EQ(boundary_triangles(bar.tetrahedron_indices),
            boundary_by_counting(bar.tetrahedron_indices));
  std::vector<VertexIndex> shifted = bar.tetrahedron_indices;
  for (VertexIndex& v : shifted) v += 1'000'000'000;
  EXPECT_EQ(boundary_triangles(shifted), boundary_by_counting(shifted));
  // Numbered in multiples of the face count: every face in one bucket (more than a bucket
  // compares pair by pair), under many different smallest vertices.
  const TetrahedralBar small = make_tetrahedral_bar(1, 1, 2);
  std::vector<VertexIndex> one_bucket = small.tetrahedron_indices;
  for (VertexIndex& v : one_bucket) v *= VertexIndex(one_bucket.size());
  EXPECT_EQ(boundary_triangles(one_bucket), boundary_by_counting(one_bucket));
  // A face three tetrahedra share (not a manifold) is on no one's boundary, compared pair by
  // pair and, numbered into one bucket with 30 more tetrahedra, sorted.
  std::vector<VertexIndex> three = {0, 1, 2, 3, 0, 2, 1, 4, 0, 1, 2, 5};
  EXPECT_EQ(boundary_triangles(three), boundary_by_counting(three));
  for (VertexIndex k = 0; k < 30; ++k) three.insert(three.end(), {0, 10 + k, 50 + k, 90 + k});
  for (VertexIndex& v : three) v *= VertexIndex(three.size());
  EXPECT_EQ(boundary_triangles(three), boundary_by_counting(three));
}

}  // namespace scene_file_tests
}  // namespace tessera::io
