// The catalogue of bad inputs (docs/errors.md): each test feeds one kind of bad input to the
// API and checks the exact message of the InvalidInput (or NumericalFailure) it produces, so
// the document and the library cannot drift apart. Where the answer is "not an error" (an
// inverted rest tetrahedron, threads = 0) the test checks what happens instead.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <oneapi/tbb/info.h>

#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/long_range_attachments.hpp>
#include <tessera/io/mesh_readers.hpp>
#include <tessera/parallel/solver.hpp>

#include "scenes.hpp"

namespace tessera {
namespace errors_tests {

const std::filesystem::path kDataDir = TESSERA_TEST_DATA_DIR;
constexpr Real kNaN = std::numeric_limits<Real>::quiet_NaN();
constexpr Real kInf = std::numeric_limits<Real>::infinity();

/// The message of the InvalidInput `action` throws ("" and a test failure if none).
std::string invalid_input(const std::function<void()>& action) {
  try {
    action();
  } catch (const InvalidInput& error) {
    return error.what();
  }
  ADD_FAILURE() << "no InvalidInput was thrown";
  return {};
}

std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Unit tetrahedron 0-1-2-3 and a fifth particle.
const std::vector<Vector3r> kRest = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};

// ---- indices ------------------------------------------------------------------------------

TEST(ErrorCatalogue, IndexOutOfRange) {
  const std::vector<ParticleIndex> edges = {0, 1, 2, 5};
  EXPECT_EQ(invalid_input([&] { make_distance_constraints({edges, kRest}); }),
            "distance constraint 1: particle index 5 is out of range (5 particles)");
  const std::vector<ParticleIndex> tet = {0, 1, 2, 4294967295u};
  EXPECT_EQ(invalid_input([&] { make_fem_tetra_constraints({tet, kRest}); }),
            "FEM tetra constraint 0: particle index 4294967295 is out of range (5 particles)");
}

TEST(ErrorCatalogue, RepeatedIndex) {
  const std::vector<ParticleIndex> tets = {0, 1, 2, 3, 0, 1, 1, 2};
  EXPECT_EQ(invalid_input([&] { make_volume_constraints({tets, kRest}); }),
            "volume constraint 1: particle 1 appears twice");
  const std::vector<ParticleIndex> stencil = {0, 3, 1, 3};
  EXPECT_EQ(invalid_input([&] { make_dihedral_constraints({stencil, kRest}); }),
            "dihedral constraint 0: particle 3 appears twice");
}

TEST(ErrorCatalogue, IndexCountNotAMultipleOfTheArity) {
  const std::vector<ParticleIndex> three = {0, 1, 2};
  EXPECT_EQ(invalid_input([&] { make_distance_constraints({three, kRest}); }),
            "distance constraints: 3 particle indices is not a multiple of 2");
}

// ---- particles ----------------------------------------------------------------------------

TEST(ErrorCatalogue, NonFinitePositions) {
  std::vector<Vector3r> positions = kRest;
  const std::vector<Real> masses(positions.size(), Real(1));
  positions[2].y() = kNaN;
  EXPECT_EQ(invalid_input([&] { ParticleState(positions, masses); }),
            "particle 2: position is not finite");
  positions[2].y() = 0;
  positions[4].z() = -kInf;
  EXPECT_EQ(invalid_input([&] { ParticleState(positions, masses); }),
            "particle 4: position is not finite");
}

TEST(ErrorCatalogue, NonFiniteOrNegativeInverseMasses) {
  std::vector<Real> masses(kRest.size(), Real(1));
  masses[3] = kNaN;
  EXPECT_EQ(invalid_input([&] { ParticleState(kRest, masses); }),
            "particle 3: inverse mass nan must be finite and ≥ 0");
  masses[3] = kInf;
  EXPECT_EQ(invalid_input([&] { ParticleState(kRest, masses); }),
            "particle 3: inverse mass inf must be finite and ≥ 0");
  masses[3] = Real(-1);
  EXPECT_EQ(invalid_input([&] { ParticleState(kRest, masses); }),
            "particle 3: inverse mass -1.000000 must be finite and ≥ 0");
}

TEST(ErrorCatalogue, PositionAndMassCountsDiffer) {
  const std::vector<Real> masses(3, Real(1));
  EXPECT_EQ(invalid_input([&] { ParticleState(kRest, masses); }),
            "particles: 5 positions but 3 inverse masses");
}

TEST(ErrorCatalogue, NonFiniteRestPositionOfAConstraint) {
  std::vector<Vector3r> rest = kRest;
  rest[1].x() = kInf;
  const std::vector<ParticleIndex> edge = {0, 1};
  EXPECT_EQ(invalid_input([&] { make_distance_constraints({edge, rest}); }),
            "distance constraint 0: rest position is not finite");
}

TEST(ErrorCatalogue, SetPositionRejectsNonFiniteAndUnknownParticles) {
  const Model model = test::cloth_model(3, 3);
  Solver solver(model, test::colour_model(model), SolverSettings{});
  EXPECT_EQ(invalid_input([&] { solver.set_position(4, Vector3r(0, kNaN, 0)); }),
            "particle 4: position is not finite");
  EXPECT_EQ(invalid_input([&] { solver.set_position(9, Vector3r::Zero()); }),
            "particle 9 does not exist (the model has 9)");
}

// ---- parameters ---------------------------------------------------------------------------

TEST(ErrorCatalogue, NegativeOrNonFiniteStiffnessAndCompliance) {
  const std::vector<ParticleIndex> edge = {0, 1};
  EXPECT_EQ(invalid_input([&] { make_distance_constraints({edge, kRest, Real(-0.5)}); }),
            "distance constraints: stiffness is -0.5, must be finite and ≥ 0");
  EXPECT_EQ(invalid_input([&] { make_distance_constraints({edge, kRest, 1, kNaN}); }),
            "distance constraints: compliance is nan, must be finite and ≥ 0");
  const std::vector<ParticleIndex> tet = {0, 1, 2, 3};
  EXPECT_EQ(invalid_input([&] { make_fem_tetra_constraints({tet, kRest, Real(0)}); }),
            "FEM tetra constraints: Young's modulus is 0, must be finite and > 0");
  EXPECT_EQ(invalid_input([&] { make_fem_tetra_constraints({tet, kRest, 1, Real(0.5)}); }),
            "FEM tetra constraints: Poisson ratio is 0.5, must lie in (-1, 0.5)");
}

// ---- degenerate rest shapes ---------------------------------------------------------------

TEST(ErrorCatalogue, ZeroRestLength) {
  std::vector<Vector3r> rest = kRest;
  rest[4] = rest[1];
  const std::vector<ParticleIndex> edges = {0, 1, 1, 4};
  EXPECT_EQ(invalid_input([&] { make_distance_constraints({edges, rest}); }),
            "distance constraint 1: rest length is 0 (particles 1 and 4 coincide at rest)");
}

TEST(ErrorCatalogue, ZeroRestArea) {
  // 0, 1 and 4' on one line.
  std::vector<Vector3r> rest = kRest;
  rest[4] = Vector3r(2, 0, 0);
  const std::vector<ParticleIndex> triangle = {0, 1, 4};
  EXPECT_EQ(invalid_input([&] { make_fem_triangle_constraints({triangle, rest}); }),
            "FEM triangle constraint 0: rest triangle has zero area");
  EXPECT_EQ(invalid_input([&] { make_strain_triangle_constraints({triangle, rest}); }),
            "strain triangle constraint 0: rest triangle has zero area in the xy plane");
  const std::vector<ParticleIndex> flat_wing = {3, 4, 0, 1};
  EXPECT_EQ(invalid_input([&] { make_dihedral_constraints({flat_wing, rest}); }),
            "dihedral constraint 0: degenerate rest stencil: triangle (p1, p3, p2) has zero area");
}

TEST(ErrorCatalogue, ZeroRestVolume) {
  // 0, 1, 2 and 4' in the plane z = 0.
  std::vector<Vector3r> rest = kRest;
  rest[4] = Vector3r(1, 1, 0);
  const std::vector<ParticleIndex> tet = {0, 1, 2, 4};
  EXPECT_EQ(invalid_input([&] { make_volume_constraints({tet, rest}); }),
            "volume constraint 0: rest volume is 0 (flat tetrahedron)");
  EXPECT_EQ(invalid_input([&] { make_fem_tetra_constraints({tet, rest}); }),
            "FEM tetra constraint 0: rest tetrahedron is flat (zero volume)");
}

TEST(ErrorCatalogue, InvertedRestTetrahedronIsAcceptedAndKeptAsItsRestShape) {
  // Listed with negative orientation (1 and 2 swapped): not an error. The volume constraint
  // keeps the signed (negative) rest volume and the FEM element measures F relative to its
  // rest shape, so at rest both are satisfied and a step moves nothing but gravity's sag.
  const std::vector<ParticleIndex> inverted = {0, 2, 1, 3};
  const VolumeConstraints volume = make_volume_constraints({inverted, kRest});
  EXPECT_NEAR(volume.rest_volume[0], Real(-1) / Real(6), 1e-6);
  Model model;
  std::vector<Real> masses(kRest.size(), Real(1));
  masses[0] = masses[1] = masses[2] = 0;
  model.particles = ParticleState(kRest, masses);
  model.constraints.fem_tetra = make_fem_tetra_constraints({inverted, kRest, Real(1e4)});
  SolverSettings settings;
  settings.gravity = Vector3r::Zero();
  Solver solver(model, test::colour_model(model), settings);
  for (int step = 0; step < 10; ++step) solver.step();
  EXPECT_NEAR((solver.position(3) - kRest[3]).norm(), 0, 1e-5);
}

// ---- empty input --------------------------------------------------------------------------

TEST(ErrorCatalogue, EmptyMeshFiles) {
  std::istringstream obj(""), msh("\n"), node(""), ele("");
  EXPECT_EQ(invalid_input([&] { io::read_obj(obj, "empty.obj"); }),
            "empty.obj:1: empty file (no statements, only blank lines or comments)");
  EXPECT_EQ(invalid_input([&] { io::read_gmsh(msh, "empty.msh"); }), "empty.msh:1: empty file");
  EXPECT_EQ(invalid_input([&] { io::read_tetgen(node, ele, "empty.node", "empty.ele"); }),
            "empty.node:1: empty file (expected the header '<#points> <dimension> <#attributes> "
            "<#boundary markers>')");
}

TEST(ErrorCatalogue, EmptyModelIsNotAnError) {
  // No particles and no constraints: a solver that steps nothing, in every mode.
  for (const SolverMode mode :
       {SolverMode::gs, SolverMode::jacobi, SolverMode::hybrid, SolverMode::sequential}) {
    const Model model;
    SolverSettings settings;
    settings.mode = mode;
    Solver solver(model, test::colour_model(model), settings);
    solver.step();
    EXPECT_EQ(solver.particle_count(), 0u);
  }
}

// ---- colourings made by hand or by a user's strategy ----------------------------------------

TEST(ErrorCatalogue, ColouringWithAGapOrAnOutOfRangeColour) {
  EXPECT_EQ(invalid_input([] { Colouring::from_colours({0, 2, 0}); }),
            "colouring: colour 1 of 3 is empty (colours must be dense)");
  // A colour no dense colouring can reach (a strategy's "uncoloured" marker, say) is refused
  // before it sizes anything.
  EXPECT_EQ(invalid_input([] { Colouring::from_colours({0, 1, 0xFFFFFFFFu}); }),
            "colouring: constraint 2 has colour 4294967295, but 3 constraints need at most "
            "that many colours (colours must be dense)");
}

// ---- names --------------------------------------------------------------------------------

TEST(ErrorCatalogue, UnknownStrategyName) {
  const ColouringRegistry registry = ColouringRegistry::with_builtin_strategies();
  EXPECT_EQ(invalid_input([&] { registry.get("fastest"); }),
            "unknown colouring strategy 'fastest' (known: greedy, largest-first, smallest-last, "
            "dsatur, stencil, iterated-greedy, random, metis, blocks)");
}

TEST(ErrorCatalogue, UnknownModeName) {
  EXPECT_EQ(invalid_input([&] { parse_solver_mode("gauss-seidel"); }),
            "unknown solver mode 'gauss-seidel' (known: gs, jacobi, hybrid, sequential)");
  const Model model = test::cloth_model(3, 3);
  SolverSettings settings;
  settings.mode = SolverMode::jacobi;
  EXPECT_EQ(invalid_input([&] { Solver(model, settings); }),
            "solver: mode jacobi needs a colouring");
}

// ---- solver settings ----------------------------------------------------------------------

TEST(ErrorCatalogue, ThreadCountZeroMeansEveryHardwareThread) {
  const Model model = test::cloth_model(3, 3);
  SolverSettings settings;
  settings.threads = 0;
  Solver solver(model, test::colour_model(model), settings);
  EXPECT_EQ(solver.statistics().threads, std::size_t(tbb::info::default_concurrency()));
  EXPECT_GE(solver.statistics().threads, 1u);
  solver.step();
}

TEST(ErrorCatalogue, NonPositiveOrNonFiniteTimeStep) {
  const Model model = test::cloth_model(3, 3);
  const Colouring colouring = test::colour_model(model);
  SolverSettings settings;
  settings.time_step = 0;
  EXPECT_EQ(invalid_input([&] { Solver(model, colouring, settings); }),
            "solver settings: time step must be positive and finite (got 0.000000)");
  settings.time_step = Real(-0.01);
  EXPECT_EQ(invalid_input([&] { Solver(model, colouring, settings); }),
            "solver settings: time step must be positive and finite (got -0.010000)");
  settings.time_step = kInf;
  EXPECT_EQ(invalid_input([&] { Solver(model, colouring, settings); }),
            "solver settings: time step must be positive and finite (got inf)");
  settings = SolverSettings{};
  Solver solver(model, colouring, settings);
  EXPECT_EQ(invalid_input([&] { solver.project(1, 0); }),
            "solver: projection time step must be positive and finite (got 0.000000)");
}

TEST(ErrorCatalogue, OtherSolverSettings) {
  const Model model = test::cloth_model(3, 3);
  const Colouring colouring = test::colour_model(model);
  SolverSettings settings;
  settings.substeps = 0;
  EXPECT_EQ(invalid_input([&] { Solver(model, colouring, settings); }),
            "solver settings: substeps must be at least 1");
  settings = SolverSettings{};
  settings.jacobi_relaxation = 2;
  EXPECT_EQ(invalid_input([&] { Solver(model, colouring, settings); }),
            "solver settings: Jacobi relaxation must be in (0, 2) (got 2.000000)");
  settings = SolverSettings{};
  settings.chebyshev_rho = 1;
  EXPECT_EQ(invalid_input([&] { Solver(model, colouring, settings); }),
            "solver settings: chebyshev_rho (the Chebyshev spectral radius estimate) must be in "
            "(0, 1) (got 1.000000)");
  settings = SolverSettings{};
  settings.chebyshev_delay = 0;
  EXPECT_EQ(invalid_input([&] { Solver(model, colouring, settings); }),
            "solver settings: chebyshev_delay must be at least 1");
  settings = SolverSettings{};
  settings.velocity_damping = -1;
  EXPECT_EQ(invalid_input([&] { Solver(model, colouring, settings); }),
            "solver settings: velocity damping must be >= 0 and finite (got -1.000000)");
  settings = SolverSettings{};
  settings.block_size = 0;
  EXPECT_EQ(invalid_input([&] { Solver(model, colouring, settings); }),
            "solver settings: block size must be at least 1");
  settings = SolverSettings{};
  settings.gravity.y() = kNaN;
  EXPECT_EQ(invalid_input([&] { Solver(model, colouring, settings); }),
            "solver settings: gravity is not finite");
}

TEST(ErrorCatalogue, PartSizeThatSizesNothing) {
  // SolverSettings::particles_per_part sizes only the runs of a part-major sweep of a
  // colouring without parts.
  const Model model = test::cloth_model(3, 3);
  SolverSettings settings;
  settings.sweep_order = SweepOrder::colour_major;
  settings.particles_per_part = 4;
  EXPECT_EQ(invalid_input([&] { Solver(model, test::colour_model(model), settings); }),
            "schedule: particles per part sizes the runs a part-major sweep makes of a "
            "colouring without parts; this sweep is colour-major");
  settings.sweep_order = SweepOrder::part_major;
  EXPECT_EQ(invalid_input([&] { Solver(model, test::colour_model(model, "blocks"), settings); }),
            "schedule: particles per part sizes the runs a part-major sweep makes of a "
            "colouring without parts; this colouring has its own parts (its strategy's "
            "particles per part sizes them)");
  // A mode without colour phases, whatever the sweep order (input order has no colouring).
  settings = SolverSettings{};
  settings.mode = SolverMode::sequential;
  settings.sequential_order = SequentialOrder::input;
  settings.particles_per_part = 4;
  EXPECT_EQ(invalid_input([&] { Solver(model, test::colour_model(model), settings); }),
            "schedule: particles per part sizes the runs of a part-major sweep, which mode "
            "sequential does not run (modes gs and hybrid do)");
}

TEST(ErrorCatalogue, BatchBuiltForAnotherModel) {
  Model model = test::cloth_model(3, 3);
  std::vector<Vector3r> more(12, Vector3r::Zero());
  more[11] = Vector3r(1, 0, 0);
  const std::vector<ParticleIndex> edge = {0, 11};
  model.constraints.distance = make_distance_constraints({edge, more});
  EXPECT_EQ(invalid_input([&] { constraint_graph(model); }),
            "distance constraints were built for 12 particles, the model has 9");
}

// ---- a step that leaves the finite numbers ------------------------------------------------

TEST(ErrorCatalogue, OverflowingStepIsNumericalFailure) {
  const Model model = test::cloth_model(3, 3);
  SolverSettings settings;
  settings.time_step = std::numeric_limits<Real>::max() / 4;  // h·g overflows
  Solver solver(model, test::colour_model(model), settings);
  try {
    solver.step();
    FAIL() << "no NumericalFailure";
  } catch (const NumericalFailure& failure) {
    EXPECT_EQ(std::string(failure.what()),
              "solver: step 1 made particle 0 non-finite; positions and velocities are restored "
              "to before it (check the time step, compliance and velocities)");
  }
}

TEST(ErrorCatalogue, TetherAndLongRangeAttachmentInput) {
  const std::vector<Vector3r> rest = {Vector3r(0, 0, 0), Vector3r(1, 0, 0)};
  const std::vector<ParticleIndex> pair = {0, 1};
  const std::vector<Real> negative = {-1}, two = {1, 1};
  EXPECT_EQ(invalid_input([&] { make_tether_constraints({pair, rest, negative}); }),
            "tether constraint 0: reach is -1, must be positive");
  EXPECT_EQ(invalid_input([&] { make_tether_constraints({pair, rest, two}); }),
            "tether constraints: 2 reaches for 1 tethers");
  const std::vector<Real> masses = {0, 1};
  const std::vector<ParticleIndex> odd = {0, 1, 1};
  EXPECT_EQ(invalid_input([&] { make_long_range_attachments(rest, masses, odd); }),
            "long-range attachments: 3 edge indices is not a whole number of edges (2 each)");
}

TEST(ErrorCatalogue, ColliderContactInput) {
  const std::vector<ParticleIndex> two = {0, 1};
  const std::vector<Vector3r> normals = {Vector3r(0, 0, 1), Vector3r(0, 0, 2)};
  const std::vector<Vector3r> anchors(2, Vector3r::Zero());
  const std::vector<Real> offsets = {0, 0}, speeds = {0, 0}, one = {0};
  EXPECT_EQ(invalid_input([&] {
              make_collider_contacts({two, 2, normals, offsets, anchors, speeds});
            }),
            "collider contact constraint 1: normal is not a unit vector");
  EXPECT_EQ(invalid_input([&] {
              make_collider_contacts({two, 2, normals, one, anchors, speeds});
            }),
            "collider contact constraints: 2 contacts but 2 normals, 1 offsets, 2 anchors and "
            "2 normal speeds");
  const std::vector<Vector3r> up(2, Vector3r(0, 0, 1));
  EXPECT_EQ(invalid_input([&] {
              make_collider_contacts({two, 2, up, offsets, anchors, speeds, 0, 0, Real(1.5)});
            }),
            "collider contact constraints: restitution is 1.5, must lie in [0, 1]");
}

TEST(ErrorCatalogue, DivergenceBoundAndADivergedStep) {
  const Model small = test::cloth_model(3, 3);
  SolverSettings settings;
  settings.divergence_rms = 0;
  EXPECT_EQ(invalid_input([&] { Solver(small, test::colour_model(small), settings); }),
            "solver settings: divergence bound must be positive (got 0.000000; infinity turns "
            "the check off)");
  // A 64² distance cloth swept in input order at 16 × 1 diverges (parallel.SequentialOrder).
  settings = SolverSettings{};
  settings.mode = SolverMode::sequential;
  settings.sequential_order = SequentialOrder::input;
  settings.substeps = 16;
  settings.iterations = 1;
  settings.divergence_rms = 2;
  Solver solver(test::cloth_model(64, 64, test::ClothBending::none), settings);
  std::string message;
  for (int frame = 0; frame < 60 && message.empty(); ++frame) {
    try {
      solver.step();
    } catch (const NumericalFailure& failure) {
      message = failure.what();
    }
  }
  const std::string tail =
      "; positions and velocities are restored to before it (more substeps or iterations, a "
      "smaller time step, or SolverSettings::divergence_rms)";
  ASSERT_GT(message.size(), tail.size()) << message;
  EXPECT_EQ(message.rfind("solver: step ", 0), 0u) << message;
  EXPECT_NE(message.find(" diverged: residual RMS "), std::string::npos) << message;
  EXPECT_NE(message.find(" exceeds the bound 2; the largest, "), std::string::npos) << message;
  EXPECT_NE(message.find(", is distance constraint "), std::string::npos) << message;
  EXPECT_EQ(message.substr(message.size() - tail.size()), tail);
}

// ---- files --------------------------------------------------------------------------------

TEST(ErrorCatalogue, UnreadableFiles) {
  const std::filesystem::path missing = kDataDir / "missing.msh";
  EXPECT_EQ(invalid_input([&] { io::read_mesh(missing); }),
            missing.string() + ": cannot open: no such file");
  EXPECT_EQ(invalid_input([&] { io::read_obj(kDataDir); }),
            kDataDir.string() + ": cannot open: it is a directory");
  EXPECT_EQ(invalid_input([&] { io::read_mesh("mesh.stl"); }),
            "mesh.stl: unsupported mesh file extension '.stl' (expected .obj, .node, .ele, .face "
            "or .msh)");
}

TEST(ErrorCatalogue, TruncatedFiles) {
  const std::string msh = read_text(kDataDir / "cube_v41.msh");
  std::istringstream cut_msh(msh.substr(0, msh.find("$EndElements")));
  EXPECT_EQ(invalid_input([&] { io::read_gmsh(cut_msh, "cut.msh"); }),
            "cut.msh:74: truncated: the file ends before $EndElements");
  // The comment lines, the header and 3 of its 12 points.
  const std::string node = read_text(kDataDir / "cube.node");
  std::size_t end = 0;
  for (int line = 0; line < 6; ++line) end = node.find('\n', end) + 1;
  std::istringstream cut_node(node.substr(0, end)), ele(read_text(kDataDir / "cube.ele"));
  EXPECT_EQ(invalid_input([&] { io::read_tetgen(cut_node, ele, "cut.node", "cube.ele"); }),
            "cut.node:6: truncated: the file ends after 3 of the 12 points its header declares");
}

TEST(ErrorCatalogue, WrongMagic) {
  // An STL file under a .msh name, and a binary .msh.
  std::istringstream stl("solid cube\n  facet normal 0 0 1\n");
  EXPECT_EQ(invalid_input([&] { io::read_gmsh(stl, "cube.msh"); }),
            "cube.msh:1: not a Gmsh .msh file: expected $MeshFormat, found 'solid cube'");
  std::istringstream binary(std::string("$MeshFormat\n4.1 1 8\n\x01\x00\x00\x00\n", 25));
  EXPECT_EQ(invalid_input([&] { io::read_gmsh(binary, "cube.msh"); }),
            "cube.msh:2: binary .msh not supported (file type 1); save the mesh as ASCII");
  // A .node file that is an OBJ.
  std::istringstream obj_as_node("v 0 0 0\n"), ele("1 4 0\n1 1 2 3 4\n");
  EXPECT_EQ(invalid_input([&] { io::read_tetgen(obj_as_node, ele, "cube.node", "cube.ele"); }),
            "cube.node:1: point count 'v' is not an integer");
}

}  // namespace errors_tests
}  // namespace tessera
