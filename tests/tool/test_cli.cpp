// The tessera tool end to end: each test runs the built program with arguments, as a shell
// user would, and checks its exit code, stdout and stderr.
#include <algorithm>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

struct Outcome {
  int exit_code = -1;
  std::string out, err;
};

std::string quote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

std::string slurp(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// A folder of its own for each test, removed afterwards.
class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    folder_ = fs::temp_directory_path() /
              ("tessera_cli_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(folder_);
    fs::create_directories(folder_);
  }
  void TearDown() override { fs::remove_all(folder_); }

  Outcome run(const std::vector<std::string>& arguments) const {
    std::string command = "cd " + quote(folder_.string()) + " && " + quote(TESSERA_TOOL);
    // Appended piece by piece: g++ 12 warns (-Wrestrict, a false positive) on " " + string.
    for (const std::string& argument : arguments) command.append(" ").append(quote(argument));
    const fs::path out = folder_ / "stdout.txt", err = folder_ / "stderr.txt";
    command.append(" >").append(quote(out.string()));
    command.append(" 2>").append(quote(err.string())).append(" </dev/null");
    const int status = std::system(command.c_str());
    Outcome outcome;
    outcome.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    outcome.out = slurp(out);
    outcome.err = slurp(err);
    return outcome;
  }

  /// Runs and parses stdout as JSON, requiring success and a quiet stderr.
  Json run_json(std::vector<std::string> arguments) const {
    arguments.push_back("--json");
    const Outcome outcome = run(arguments);
    EXPECT_EQ(outcome.exit_code, 0) << outcome.err;
    EXPECT_EQ(outcome.err, "");
    return Json::parse(outcome.out);
  }

  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path file = folder_ / name;
    std::ofstream(file, std::ios::binary) << text;
    return file;
  }

  fs::path folder_;
};

const fs::path kData = TESSERA_TEST_DATA_DIR;

TEST_F(Cli, HelpOnEverySubcommand) {
  for (const std::vector<std::string>& arguments :
       {std::vector<std::string>{"--help"}, {"run", "--help"}, {"color", "--help"}, {"info", "--help"}}) {
    const Outcome outcome = run(arguments);
    EXPECT_EQ(outcome.exit_code, 0) << arguments.front();
    EXPECT_NE(outcome.out.find("Usage: tessera"), std::string::npos) << outcome.out;
  }
  EXPECT_NE(run({"run", "--help"}).out.find("--strategy"), std::string::npos);
  EXPECT_NE(run({"color", "--help"}).out.find("--threads"), std::string::npos);
  const Outcome version = run({"--version"});
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_FALSE(version.out.empty());
}

TEST_F(Cli, InfoNamesTheBuild) {
  const Json info = run_json({"info"});
  for (const char* key : {"version", "build_type", "precision", "simd_target",
                          "simd_targets_available", "threads_available", "strategies", "modes"})
    EXPECT_TRUE(info.contains(key)) << key;
  EXPECT_TRUE(info["precision"] == "float" || info["precision"] == "double");
  EXPECT_GE(info["threads_available"].get<int>(), 1);
  const auto strategies = info["strategies"].get<std::vector<std::string>>();
  EXPECT_NE(std::find(strategies.begin(), strategies.end(), "metis"), strategies.end());
  const Outcome text = run({"info"});
  EXPECT_EQ(text.exit_code, 0);
  EXPECT_NE(text.out.find("simd_target"), std::string::npos);
}

TEST_F(Cli, ParticleLayoutChangesTheSweepsButNotTheResult) {
  const Json interleaved = run_json({"run", "cloth:12x10", "--frames", "3"});
  const Json separate =
      run_json({"run", "cloth:12x10", "--frames", "3", "--particle-layout", "separate"});
  EXPECT_EQ(interleaved["particle_layout"], "interleaved") << "the default";
  EXPECT_EQ(separate["particle_layout"], "separate");
  EXPECT_EQ(separate["state_hash"], interleaved["state_hash"]);
  const Outcome bad = run({"run", "cloth:12x10", "--frames", "1", "--particle-layout", "aos"});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("particle layout"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("aos"), std::string::npos) << bad.err;
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
}

TEST_F(Cli, PartMajorSweepsTheSameForAnyThreadCountOverAnyColouring) {
  // A part-major run of cloth:40 (1,598 movable particles) in parts of 200, on 1 and 2 threads.
  const auto on_one_and_two_threads = [&](std::vector<std::string> args) {
    args.insert(args.begin(), {"run", "cloth:40", "--frames", "3", "--particles-per-part", "200",
                               "--sweep-order", "part-major"});
    auto two = args;
    args.insert(args.end(), {"--threads", "1"});
    two.insert(two.end(), {"--threads", "2"});
    return std::pair{run_json(args), run_json(two)};
  };
  const auto [a, b] = on_one_and_two_threads({"--strategy", "metis"});
  EXPECT_EQ(a["sweep_order"], "part-major");
  EXPECT_GE(a["parts"].get<int>(), 4);
  EXPECT_EQ(a["state_hash"], b["state_hash"]);
  const Json colour_major = run_json({"run", "cloth:40", "--frames", "3", "--strategy", "metis",
                                      "--particles-per-part", "200"});
  EXPECT_EQ(colour_major["sweep_order"], "colour-major") << "auto, for 8 parts";
  EXPECT_NE(colour_major["state_hash"], a["state_hash"]) << "another Gauss-Seidel order";
  // Parts from runs of the numbering (strategy blocks): the same for any thread count, and
  // other parts than METIS's, so other bits.
  const auto [c, d] = on_one_and_two_threads({"--strategy", "blocks"});
  EXPECT_EQ(c["strategy"], "blocks");
  EXPECT_EQ(c["parts"].get<int>(), 8) << "1,598 movable particles in parts of 200 at most";
  EXPECT_EQ(c["state_hash"], d["state_hash"]);
  EXPECT_NE(c["state_hash"], a["state_hash"]);
  // The default colouring (stencil) has no parts: runs of 200 movable particles of its
  // particle order.
  const auto [e, f] = on_one_and_two_threads({});
  EXPECT_EQ(e["strategy"], "stencil");
  EXPECT_EQ(e["parts"].get<int>(), 8);
  EXPECT_GT(e["part_constraints"].get<int>(), e["constraints"].get<int>() / 2);
  EXPECT_LT(e["part_constraints"].get<int>(), e["constraints"].get<int>());
  EXPECT_EQ(e["state_hash"], f["state_hash"]);
  const Json stencil = run_json({"run", "cloth:40", "--frames", "3"});
  EXPECT_EQ(stencil["parts"].get<int>(), 0);
  EXPECT_EQ(stencil["part_constraints"].get<int>(), 0);
  EXPECT_NE(stencil["state_hash"], e["state_hash"]);
  const auto expect_clear_error = [&](const std::vector<std::string>& args, const char* words) {
    const Outcome bad = run(args);
    EXPECT_EQ(bad.exit_code, 2) << bad.err;
    EXPECT_NE(bad.err.find(words), std::string::npos) << bad.err;
    EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
  };
  expect_clear_error({"run", "cloth:12", "--frames", "1", "--sweep-order", "diagonal"},
                     "unknown sweep order 'diagonal'");
  expect_clear_error({"run", "cloth:12", "--frames", "1", "--sweep-order", "colour-major",
                      "--particles-per-part", "64"},
                     "needs a strategy with parts (metis or blocks) or --sweep-order "
                     "part-major or auto (strategy stencil has none)");
  // Auto (the default) sweeps part-major from 32 parts up, and the summary names its choice:
  // 1,598 movable particles in runs of 50 are 32 parts, in runs of 52 are 31.
  const Json chosen = run_json({"run", "cloth:40", "--frames", "3", "--particles-per-part", "50"});
  EXPECT_EQ(chosen["sweep_order"], "part-major");
  EXPECT_EQ(chosen["parts"].get<int>(), 32);
  const Json by_hand = run_json({"run", "cloth:40", "--frames", "3", "--particles-per-part", "50",
                                 "--sweep-order", "part-major"});
  EXPECT_EQ(chosen["state_hash"], by_hand["state_hash"]);
  const Json fewer = run_json({"run", "cloth:40", "--frames", "3", "--particles-per-part", "52"});
  EXPECT_EQ(fewer["sweep_order"], "colour-major");
  EXPECT_EQ(fewer["state_hash"], stencil["state_hash"]);
}

TEST_F(Cli, RunSummaryHoldsEveryKey) {
  const Json summary = run_json({"run", "cloth:12x10", "--frames", "3", "--threads", "2"});
  for (const char* key : {"scene", "particles", "constraints", "colours", "colour_lower_bound",
                          "strategy", "mode", "particle_layout", "sweep_order", "parts",
                          "part_constraints", "threads", "frames",
                          "substeps", "iterations",
                          "seconds_total", "seconds_coloring", "seconds_projection",
                          "projections_per_second", "residual_rms_initial",
                          "residual_rms_final", "state_hash"})
    EXPECT_TRUE(summary.contains(key)) << key;
  EXPECT_EQ(summary["scene"], "cloth:12x10");
  EXPECT_EQ(summary["particles"], 120);
  EXPECT_EQ(summary["frames"], 3);
  EXPECT_EQ(summary["threads"], 2);
  EXPECT_EQ(summary["mode"], "gs");
  EXPECT_EQ(summary["strategy"], "stencil");
  EXPECT_GE(summary["colours"].get<int>(), summary["colour_lower_bound"].get<int>());
  EXPECT_GT(summary["projections_per_second"].get<double>(), 0);
  EXPECT_EQ(summary["projections"].get<std::uint64_t>(),
            summary["constraints"].get<std::uint64_t>() * 3 * summary["substeps"].get<std::uint64_t>() *
                summary["iterations"].get<std::uint64_t>());
  EXPECT_GT(summary["residual_rms_initial"].get<double>(), 0);
  EXPECT_EQ(summary["state_hash"].get<std::string>().size(), 16u);
  // The text form prints the same keys.
  const Outcome text = run({"run", "cloth:12x10", "--frames", "3"});
  EXPECT_EQ(text.exit_code, 0);
  EXPECT_NE(text.out.find("state_hash"), std::string::npos);
  EXPECT_NE(text.out.find("colour_lower_bound"), std::string::npos);
  // The residual of each family the scene has, tethers included (auto for a pinned scene).
  for (const char* family : {"distance", "dihedral", "tether"})
    for (const char* measure : {"rms", "max"}) {
      const std::string key = std::string("residual_") + family + "_" + measure + "_final";
      EXPECT_TRUE(summary.contains(key)) << key;
    }
  EXPECT_FALSE(summary.contains("residual_volume_rms_final")) << "only the scene's families";
  // Where the largest residual is: a family of the scene and a constraint id it has.
  const std::string worst = summary["residual_worst"].get<std::string>();
  std::size_t id = 0;
  bool named = false;
  for (const char* family : {"distance", "dihedral", "tether"}) {
    const std::string prefix = std::string(family) + " constraint ";
    if (worst.rfind(prefix, 0) == 0) {
      named = true;
      id = std::stoul(worst.substr(prefix.size()));
    }
  }
  EXPECT_TRUE(named) << worst;
  EXPECT_LT(id, summary["constraints"].get<std::uint64_t>()) << worst;
  EXPECT_EQ(run_json({"run", "cloth:12x10", "--frames", "1", "--tethers", "none"})
                .contains("residual_tether_rms_final"),
            false);
  // Two tethers per movable particle by default (one to each of the two pins), one when asked.
  const auto constraints_with = [&](const char* attachments) {
    return run_json({"run", "cloth:12x10", "--frames", "1", "--tether-attachments", attachments})
        ["constraints"].get<std::uint64_t>();
  };
  const std::uint64_t movable = 12 * 10 - 2;
  EXPECT_EQ(summary["constraints"].get<std::uint64_t>() - constraints_with("1"), movable);
  EXPECT_EQ(constraints_with("2"), summary["constraints"].get<std::uint64_t>());
  EXPECT_EQ(constraints_with("5"), summary["constraints"].get<std::uint64_t>()) << "only 2 pins";
  EXPECT_EQ(summary["substeps"], 160) << "the cloth scenes' substeps";
}

// Divergence is a failure: the input order at 16 x 1 diverges on a 64² distance cloth; with
// a bound of 2 the run stops with one line and exit code 1, and nothing prints null.
TEST_F(Cli, DivergenceIsANumericalFailureWithExitCodeOne) {
  const std::vector<std::string> base = {"run", "cloth:64x64", "--bending", "none", "--tethers",
                                         "none", "--mode", "sequential", "--sequential-order",
                                         "input", "--substeps", "16", "--frames", "30", "--json"};
  std::vector<std::string> bounded = base;
  bounded.insert(bounded.end(), {"--divergence-rms", "2"});
  const Outcome failed = run(bounded);
  EXPECT_EQ(failed.exit_code, 1);
  EXPECT_EQ(failed.out, "");
  EXPECT_NE(failed.err.find("tessera run: solver: step "), std::string::npos) << failed.err;
  EXPECT_NE(failed.err.find(" diverged: residual RMS "), std::string::npos) << failed.err;
  EXPECT_EQ(std::count(failed.err.begin(), failed.err.end(), '\n'), 1);
  // Unbounded, the same run goes on through the divergence and ends with finite numbers: no
  // null anywhere. (Where it ends is chaotic: its RMS swings between 0.1 and 100 from frame to
  // frame, so the last frame's value says nothing; the bounded run above shows it diverged.)
  std::vector<std::string> unbounded = base;
  unbounded.insert(unbounded.end(), {"--divergence-rms", "inf"});
  const Outcome diverged = run(unbounded);
  EXPECT_EQ(diverged.exit_code, 0) << diverged.err;
  EXPECT_EQ(diverged.out.find("null"), std::string::npos) << diverged.out;
  EXPECT_TRUE(std::isfinite(Json::parse(diverged.out)["residual_rms_final"].get<double>()));
  // The groups order (the default) stays bounded under the default bound.
  std::vector<std::string> groups = base;
  groups[9] = "groups";
  EXPECT_EQ(run(groups).exit_code, 0);
}

// The drape: a free cloth falls onto a sphere and the ground, against itself too. It ends
// outside the colliders (deeper than the thickness is a failure), without a self-intersection,
// with the same state for 1 and 2 threads, and reports its contacts.
TEST_F(Cli, DrapeEndsOnTheSphereWithoutPenetrationOrSelfIntersection) {
  const std::vector<std::string> base = {"run", "drape:24", "--frames", "40", "--substeps", "16"};
  auto one = base, two = base;
  one.insert(one.end(), {"--threads", "1"});
  two.insert(two.end(), {"--threads", "2"});
  const Json a = run_json(one), b = run_json(two);
  EXPECT_EQ(a["state_hash"], b["state_hash"]);
  for (const char* key : {"contacts_mean", "contacts_max", "penetration_max", "self_intersections",
                          "seconds_collision"})
    EXPECT_TRUE(a.contains(key)) << key;
  EXPECT_GT(a["contacts_max"].get<double>(), 8) << "the cloth lies on the sphere";
  EXPECT_LE(a["penetration_max"].get<double>(), 0.005) << "at most the thickness deep";
  EXPECT_EQ(a["self_intersections"], 0);
  // Self-collision's time by what each substep did: the first substep builds, and the parts
  // add up to no more than the whole.
  const double built = a["seconds_self_collision_built"].get<double>(),
               reboxed = a["seconds_self_collision_reboxed"].get<double>(),
               refined = a["seconds_self_collision_refined"].get<double>();
  EXPECT_GT(built, 0);
  EXPECT_GE(reboxed, 0);
  EXPECT_GT(refined, 0) << "most substeps filter the last build's candidates";
  EXPECT_LE(built + reboxed + refined, a["seconds_collision"].get<double>());
  // Without colliders nothing collides and nothing is reported.
  EXPECT_FALSE(run_json({"run", "cloth:8", "--frames", "1"}).contains("contacts_mean"));
}

TEST_F(Cli, PileBlocksLandOnEachOtherWithoutPenetration) {
  const std::vector<std::string> base = {"run", "pile:3", "--frames", "30", "--substeps", "16"};
  auto one = base, two = base;
  one.insert(one.end(), {"--threads", "1"});
  two.insert(two.end(), {"--threads", "2"});
  const Json a = run_json(one), b = run_json(two);
  EXPECT_EQ(a["state_hash"], b["state_hash"]);
  EXPECT_GT(a["contacts_max"].get<double>(), 20) << "the top block lands on the lower two";
  EXPECT_LE(a["penetration_max"].get<double>(), 0.005) << "at most the thickness deep";
  EXPECT_EQ(a["self_intersections"], 0);
  EXPECT_TRUE(a.contains("residual_particle_tet_contact_max_final"));
  // --out: the frames carry each particle's contact count (point data "contacts").
  const fs::path out = folder_ / "pile";
  run_json({"run", "pile:3", "--frames", "12", "--out", out.string()});
  const std::string vtu = slurp(out / "frame_00012.vtu");
  const std::size_t name = vtu.find("Name=\"contacts\"");
  ASSERT_NE(name, std::string::npos);
  std::istringstream values(vtu.substr(vtu.find('>', name) + 1,
                                       vtu.find("</DataArray>", name) - vtu.find('>', name) - 1));
  std::size_t count = 0, touching = 0;
  for (double value; values >> value; ++count) {
    EXPECT_EQ(value, std::floor(value));
    touching += value > 0;
  }
  EXPECT_EQ(count, 3u * 144u);
  EXPECT_GT(touching, 10u) << "the blocks lie on the ground";
  run_json({"run", "cloth:6", "--frames", "1", "--out", (folder_ / "cloth").string()});
  EXPECT_EQ(slurp(folder_ / "cloth" / "frame_00001.vtu").find("contacts"), std::string::npos);

  const Json example = run_json(
      {"run", std::string(TESSERA_SOURCE_DIR) + "/examples/scenes/pile.json", "--frames", "1"});
  EXPECT_EQ(example["scene"], "pile");
  EXPECT_EQ(example["particles"], 8 * 144);
}

// The eight-block pile with its contacts swept Gauss–Seidel (coloured on top of the static
// colours, and mode sequential): the blocks come to rest on each other. Before solid contacts
// beside a face took the direction from its edge (solid_contacts.hpp, "Which normal"), both
// blew up within ten frames (863 k contacts in one substep, penetration 2 cm).
TEST_F(Cli, ThePileRestsWithItsContactsSweptGaussSeidel) {
  std::map<std::string, std::string> hashes;
  for (const std::vector<std::string>& how :
       {std::vector<std::string>{"--contact-scheduling", "coloured", "--threads", "1"},
        {"--contact-scheduling", "coloured", "--threads", "2"},
        {"--contact-scheduling", "jacobi", "--threads", "2"},
        {"--mode", "sequential"}}) {
    std::vector<std::string> arguments = {"run", "pile", "--frames", "30"};
    arguments.insert(arguments.end(), how.begin(), how.end());
    const Json summary = run_json(arguments);
    EXPECT_LT(summary["contacts_max"].get<double>(), 2000) << how[1];
    EXPECT_GT(summary["contacts_max"].get<double>(), 100) << how[1] << ": the blocks landed";
    EXPECT_LE(summary["penetration_max"].get<double>(), 0.005) << how[1];
    EXPECT_LT(summary["residual_max_final"].get<double>(), 0.1) << how[1];
    if (how[1] == "coloured") {
      EXPECT_EQ(summary["contact_scheduling"], "coloured");
      EXPECT_GT(summary["contact_colours_max"].get<double>(), 1) << "contacts sharing particles";
      EXPECT_EQ(summary["contacts_overflowed"], 0);
      if (!hashes.empty()) {
        EXPECT_EQ(summary["state_hash"], hashes.begin()->second) << "1 and 2 threads";
      }
      hashes[how.back()] = summary["state_hash"];
    }
  }
}

TEST_F(Cli, OneAndTwoThreadsGiveTheSameState) {
  std::map<std::string, std::string> hashes;
  for (const char* mode : {"gs", "jacobi", "hybrid", "sequential"}) {
    const std::vector<std::string> arguments = {"run", "cloth:20x16", "--frames", "4", "--mode", mode};
    auto one = arguments, two = arguments;
    one.insert(one.end(), {"--threads", "1"});
    two.insert(two.end(), {"--threads", "2"});
    const Json a = run_json(one), b = run_json(two);
    EXPECT_EQ(a["state_hash"], b["state_hash"]) << mode;
    EXPECT_EQ(b["mode"], mode);
    hashes[mode] = a["state_hash"].get<std::string>();
  }
  // Distinct methods reach distinct states (hybrid is jacobi here: every colour of so small a
  // cloth is below the hybrid threshold).
  EXPECT_NE(hashes["gs"], hashes["jacobi"]);
  EXPECT_NE(hashes["gs"], hashes["sequential"]);
  EXPECT_NE(hashes["jacobi"], hashes["sequential"]);
  const Json bar1 = run_json({"run", "bar:2x2x6", "--frames", "3", "--threads", "1", "--strategy", "random"});
  const Json bar2 = run_json({"run", "bar:2x2x6", "--frames", "3", "--threads", "2", "--strategy", "random"});
  EXPECT_EQ(bar1["state_hash"], bar2["state_hash"]);
}

TEST_F(Cli, RunsMeshFilesAndSceneFiles) {
  for (const char* file : {"square.obj", "pieces.obj", "cube.node", "cube_v22.msh", "cube_v41.msh"}) {
    const Json summary = run_json({"run", (kData / file).string(), "--frames", "2"});
    EXPECT_GT(summary["constraints"].get<int>(), 0) << file;
  }
  const Json strain = run_json({"run", "cloth:8", "--frames", "1", "--shell-material",
                                "strain_triangle", "--bending", "isometric", "--pins", "none"});
  EXPECT_EQ(strain["pinned"], 0);
  const fs::path scene = write("hang.json", R"({
      "name": "hanging cube", "mesh": ")" + (kData / "cube.node").string() + R"(",
      "pins": "highest-y", "solid": {"material": "volume_and_distance"},
      "frames": 2, "substeps": 3, "iterations": 5, "mode": "hybrid", "strategy": "dsatur"})");
  const Json summary = run_json({"run", scene.string()});
  EXPECT_EQ(summary["scene"], "hanging cube");
  EXPECT_EQ(summary["frames"], 2);
  EXPECT_EQ(summary["substeps"], 3);
  EXPECT_EQ(summary["mode"], "hybrid");
  EXPECT_EQ(summary["strategy"], "dsatur");
  const Json curtain = run_json({"run", std::string(TESSERA_SOURCE_DIR) + "/examples/scenes/curtain.json",
                                 "--frames", "2"});
  EXPECT_EQ(curtain["scene"], "curtain");
  EXPECT_EQ(curtain["pinned"], 3);
  // The command line overrides the file.
  EXPECT_EQ(run_json({"run", scene.string(), "--frames", "1", "--mode", "gs"})["frames"], 1);
}

TEST_F(Cli, WritesFramesWithTheColouring) {
  const fs::path out = folder_ / "frames";
  const Json summary =
      run_json({"run", "cloth:10x8", "--frames", "3", "--out", out.string(), "--obj"});
  for (int frame = 0; frame <= 3; ++frame) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d", frame);
    EXPECT_TRUE(fs::exists(out / (std::string(name) + ".vtu"))) << name;
    EXPECT_TRUE(fs::exists(out / (std::string(name) + ".obj"))) << name;
  }
  EXPECT_EQ(summary["files_written"], 8);
  const std::string pvd = slurp(out / "frames.pvd");
  EXPECT_NE(pvd.find("frame_00003.vtu"), std::string::npos);
  for (const auto& entry : fs::directory_iterator(out))
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();

  // A VTK reader (meshio, from Debian's python3-meshio) accepts the file, and its cells carry
  // a colour below the summary's colour count on every constraint cell.
  const fs::path check = write("check.py", R"(import sys
import meshio
mesh = meshio.read(sys.argv[1])
assert len(mesh.points) == 80, len(mesh.points)
colours = [int(c) for block in mesh.cell_data["colour"] for c in block]
families = [int(f) for block in mesh.cell_data["family"] for f in block]
used = {c for c, f in zip(colours, families) if f >= 0}
assert all(c >= 0 for c, f in zip(colours, families) if f >= 0)
assert all(c == -1 for c, f in zip(colours, families) if f < 0)
print(max(used) + 1, len(mesh.cells))
)");
  const std::string python = TESSERA_SYSTEM_PYTHON;
  if (std::system((python + " -c 'import meshio' 2>/dev/null").c_str()) != 0)
    GTEST_SKIP() << "python3-meshio is not installed (scripts/setup installs it)";
  const fs::path result = folder_ / "meshio.txt";
  ASSERT_EQ(std::system((python + " " + check.string() + " " + (out / "frame_00003.vtu").string() +
                         " >" + result.string() + " 2>&1").c_str()),
            0)
      << slurp(result);
  std::istringstream counts(slurp(result));
  int colours = 0, blocks = 0;
  counts >> colours >> blocks;
  EXPECT_EQ(colours, summary["colours"].get<int>());
  EXPECT_EQ(blocks, 2);  // surface triangles and constraint lines
}

TEST_F(Cli, ColorComparesEveryStrategyTheSameForAnyThreadCount) {
  const Json one = run_json({"color", "cloth:24x20", "--threads", "1"});
  const Json two = run_json({"color", "cloth:24x20", "--threads", "2"});
  ASSERT_TRUE(one.is_array());
  ASSERT_EQ(one.size(), 9u);  // every built-in strategy
  ASSERT_EQ(two.size(), one.size());
  for (std::size_t i = 0; i < one.size(); ++i) {
    for (const char* key : {"strategy", "colours", "lower_bound", "largest", "smallest",
                            "balance", "seconds", "valid"})
      EXPECT_TRUE(one[i].contains(key)) << key;
    EXPECT_TRUE(one[i]["valid"].get<bool>()) << one[i]["strategy"];
    EXPECT_GE(one[i]["colours"].get<int>(), one[i]["lower_bound"].get<int>());
    EXPECT_EQ(one[i]["colouring_hash"], two[i]["colouring_hash"]) << one[i]["strategy"];
  }
  const Json dsatur = run_json({"color", "bar:2x2x5", "--strategy", "dsatur", "--balance"});
  ASSERT_EQ(dsatur.size(), 1u);
  EXPECT_EQ(dsatur[0]["strategy"], "dsatur");
  const Outcome table = run({"color", "cloth:16"});
  EXPECT_EQ(table.exit_code, 0);
  for (const char* name : {"greedy", "stencil", "metis", "lower bound"})
    EXPECT_NE(table.out.find(name), std::string::npos) << name;
}

// Each bad input with the exact line it prints (docs/errors.md lists the same table). The
// tool runs in the test's folder, so the files are named as a user in that folder would.
TEST_F(Cli, BadInputIsOneLineAndExitCodeTwo) {
  write("truncated.msh", slurp(kData / "cube_v41.msh").substr(0, 300));
  write("binary.obj", std::string("v 0 0 0\n\x01\x02\xff\xfe\0\0f 1 2 3\n", 20));
  write("magic.msh", "$MeshFormat\n9.9 0 8\n$EndMeshFormat\n");
  write("syntax.json", "{\"generator\": \"cloth\",,}");
  write("key.json", R"({"generator": "cloth", "gravityy": [0, 0, 0]})");
  write("value.json", R"({"generator": "cloth", "iterations": 0})");
  write("empty.obj", "# nothing\n");
  write("collider_missing.json",
        R"({"generator": "cloth:8", "colliders": [{"shape": "mesh", "file": "bowl.obj"}]})");
  write("collider_bad.json",
        R"({"generator": "cloth:8", "colliders": [{"shape": "sphere", "centre": [0, 0, 0], "radius": -1}]})");
  const std::string strategies =
      "(known: greedy, largest-first, smallest-last, dsatur, stencil, iterated-greedy, random, "
      "metis, blocks)";
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{}, "tessera: a subcommand is needed: run, color or info (see tessera --help)"},
      {{"bogus"}, "tessera: unknown subcommand 'bogus' (known: run, color, info)"},
      {{"run", "--unknown"}, "tessera run: The following argument was not expected: --unknown"},
      {{"run", "--frames", "abc"}, "tessera run: --frames: must be an integer from 0 to 2147483648, not 'abc'"},
      {{"run", "--frames", "-1"}, "tessera run: --frames: must be an integer from 0 to 2147483648, not '-1'"},
      {{"run", "--substeps", "0"}, "tessera run: --substeps: must be an integer from 1 to 1048576, not '0'"},
      {{"run", "--iterations", "0"}, "tessera run: --iterations: must be an integer from 1 to 1048576, not '0'"},
      {{"run", "--threads", "0"}, "tessera run: --threads: must be an integer from 1 to 4096, not '0'"},
      {{"run", "--dt", "0"}, "tessera run: --dt: must be a finite number of seconds above 0, not '0'"},
      {{"run", "--dt", "-0.5"}, "tessera run: --dt: must be a finite number of seconds above 0, not '-0.5'"},
      {{"run", "--dt", "inf"}, "tessera run: --dt: must be a finite number of seconds above 0, not 'inf'"},
      {{"run", "--damping", "-1"}, "tessera run: --damping: must be a finite number of 1/seconds (0 or more), not '-1'"},
      {{"run", "--chebyshev", "maybe"}, "tessera run: --chebyshev: unknown value 'maybe' (known: on, off)"},
      {{"run", "--chebyshev-rho", "1"}, "tessera run: --chebyshev-rho: must be a number in (0, 1), not '1'"},
      {{"run", "--mode", "fast"}, "tessera run: unknown solver mode 'fast' (known: gs, jacobi, hybrid, sequential)"},
      {{"run", "--tethers", "some"}, "tessera run: --tethers: unknown value 'some' (known: auto, none)"},
      {{"run", "--tether-attachments", "0"}, "tessera run: --tether-attachments: must be an integer from 1 to 1048576, not '0'"},
      {{"run", "--sequential-order", "random"}, "tessera run: unknown sequential order 'random' (known: groups, input)"},
      {{"run", "--divergence-rms", "0"}, "tessera run: --divergence-rms: must be a number above 0 or inf, not '0'"},
      {{"run", "--strategy", "nope"}, "tessera run: unknown colouring strategy 'nope' " + strategies},
      {{"run", "--mode", "jacobi", "--particles-per-part", "64"}, "tessera run: --particles-per-part: sizes the runs of a part-major sweep, which mode jacobi does not run (modes gs and hybrid do; strategy stencil has no parts)"},
      {{"run", "--sweep-order", "colour-major", "--particles-per-part", "64"}, "tessera run: --particles-per-part: needs a strategy with parts (metis or blocks) or --sweep-order part-major or auto (strategy stencil has none)"},
      {{"run", "--pins", "left"}, "tessera run: --pins: unknown pin rule 'left' (known: default, none, lowest-x, lowest-y, lowest-z, highest-x, highest-y, highest-z)"},
      {{"run", "--bending", "floppy"}, "tessera run: --bending: unknown value 'floppy' (known: dihedral, isometric, none)"},
      {{"run", "--shell-material", "silk"}, "tessera run: --shell-material: unknown value 'silk' (known: distance, strain_triangle, fem_triangle)"},
      {{"run", "--solid-material", "jelly"}, "tessera run: --solid-material: unknown value 'jelly' (known: fem_tetra, strain_tetra, volume_and_distance)"},
      {{"run", "cloth:1x5"}, "tessera run: scene 'cloth:1x5': a cloth needs at least 2 vertices per side"},
      {{"run", "cloth:abc"}, "tessera run: scene 'cloth:abc': expected cloth:N or cloth:CxR with vertex counts, e.g. cloth:256x256"},
      {{"run", "bar:0x1x1"}, "tessera run: scene 'bar:0x1x1': a bar needs at least 1 cell per side"},
      {{"run", "cloth:8", "extra"}, "tessera run: The following argument was not expected: extra"},
      {{"run", "missing.obj"}, "tessera run: missing.obj: cannot open: no such file"},
      {{"run", "mesh.xyz"}, "tessera run: mesh.xyz: unsupported mesh file extension '.xyz' (expected .obj, .node, .ele, .face or .msh)"},
      {{"run", "truncated.msh"}, "tessera run: truncated.msh:26: expected 4 coordinates (x y z and 1 parametric), found 3"},
      {{"run", "binary.obj"}, "tessera run: binary.obj:2: unexpected control byte 0x01: this is not a text file"},
      {{"run", "magic.msh"}, "tessera run: magic.msh:2: unsupported .msh version 9.9 (only 2.2 and 4.1 are read)"},
      {{"run", "empty.obj"}, "tessera run: empty.obj:1: empty file (no statements, only blank lines or comments)"},
      {{"run", "syntax.json"}, "tessera run: syntax.json: line 1, column 23: syntax error while parsing object key - unexpected ','; expected string literal"},
      {{"run", "key.json"}, "tessera run: key.json: unknown key 'gravityy'"},
      {{"run", "value.json"}, "tessera run: value.json: 'iterations' must be a positive integer up to 2^31, not 0"},
      {{"run", "cloth:8", "--obj"}, "tessera run: --obj needs --out DIR"},
      {{"run", "cloth:8", "--out", "no/such/folder"}, "tessera run: --out: cannot create folder no/such/folder: No such file or directory"},
      {{"run", "cloth:8", "--out", "truncated.msh"}, "tessera run: --out: truncated.msh exists and is not a folder"},
      {{"run", "--self-collision", "maybe"}, "tessera run: --self-collision: unknown value 'maybe' (known: on, off)"},
      {{"run", "--thickness", "-1"}, "tessera run: --thickness: must be a finite number of metres (0 or more), not '-1'"},
      {{"run", "--friction", "-0.5"}, "tessera run: --friction: must be a finite number (0 or more), not '-0.5'"},
      {{"run", "cloth:8", "--self-collision", "on", "--thickness", "0"}, "tessera run: --thickness: must be positive with self-collision on"},
      {{"run", "drape:1"}, "tessera run: scene 'drape:1': a cloth needs at least 2 vertices per side"},
      {{"run", "pile:2", "--contact-scheduling", "graph"}, "tessera run: unknown contact scheduling 'graph' (known: jacobi, coloured)"},
      {{"run", "collider_missing.json"}, "tessera run: bowl.obj: cannot open: no such file"},
      {{"run", "collider_bad.json"}, "tessera run: collider_bad.json: 'colliders[0].radius' must be a number in (0, inf), not -1"},
      {{"color", "--strategy", "nope"}, "tessera color: unknown colouring strategy 'nope' " + strategies},
      {{"color", "--threads", "0"}, "tessera color: --threads: must be an integer from 1 to 4096, not '0'"},
      {{"color", "missing.node"}, "tessera color: missing.node: cannot open: no such file"},
      {{"info", "--bogus"}, "tessera info: The following argument was not expected: --bogus"},
  };
  for (const auto& [arguments, message] : cases) {
    std::string shown;
    for (const auto& argument : arguments) shown += " " + argument;
    const Outcome outcome = run(arguments);
    EXPECT_EQ(outcome.exit_code, 2) << shown;
    EXPECT_EQ(outcome.out, "") << shown;
    EXPECT_EQ(outcome.err, message + "\n") << shown;
  }
  EXPECT_FALSE(fs::exists(folder_ / "no"));
}

}  // namespace
