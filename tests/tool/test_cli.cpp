// The tessera tool end to end: each test runs the built program with arguments, as a shell
// user would, and checks its exit code, stdout and stderr.
#include <sys/wait.h>

#include <array>
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
    std::string command = quote(TESSERA_TOOL);
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

TEST_F(Cli, RunSummaryHoldsEveryKey) {
  const Json summary = run_json({"run", "cloth:12x10", "--frames", "3", "--threads", "2"});
  for (const char* key : {"scene", "particles", "constraints", "colours", "colour_lower_bound",
                          "strategy", "mode", "threads", "frames", "substeps", "iterations",
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
  ASSERT_EQ(one.size(), 8u);
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

TEST_F(Cli, BadInputIsOneLineAndExitCodeTwo) {
  const fs::path truncated = write("truncated.msh", slurp(kData / "cube_v41.msh").substr(0, 300));
  const fs::path binary = write("binary.obj", std::string("v 0 0 0\n\x01\x02\xff\xfe\0\0f 1 2 3\n", 20));
  const fs::path wrong_magic = write("magic.msh", "$MeshFormat\n9.9 0 8\n$EndMeshFormat\n");
  const fs::path syntax = write("syntax.json", "{\"generator\": \"cloth\",,}");
  const fs::path unknown_key = write("key.json", R"({"generator": "cloth", "gravityy": [0, 0, 0]})");
  const fs::path bad_value = write("value.json", R"({"generator": "cloth", "iterations": 0})");
  const fs::path empty = write("empty.obj", "# nothing\n");
  const std::vector<std::vector<std::string>> cases = {
      {},
      {"bogus"},
      {"run", "--unknown"},
      {"run", "--frames", "abc"},
      {"run", "--frames", "-1"},
      {"run", "--substeps", "0"},
      {"run", "--iterations", "0"},
      {"run", "--threads", "0"},
      {"run", "--dt", "0"},
      {"run", "--dt", "-0.5"},
      {"run", "--dt", "inf"},
      {"run", "--damping", "-1"},
      {"run", "--mode", "fast"},
      {"run", "--strategy", "nope"},
      {"run", "--pins", "left"},
      {"run", "--bending", "floppy"},
      {"run", "--shell-material", "silk"},
      {"run", "--solid-material", "jelly"},
      {"run", "cloth:1x5"},
      {"run", "cloth:abc"},
      {"run", "bar:0x1x1"},
      {"run", "cloth:8", "extra"},
      {"run", (folder_ / "missing.obj").string()},
      {"run", (folder_ / "mesh.xyz").string()},
      {"run", truncated.string()},
      {"run", binary.string()},
      {"run", wrong_magic.string()},
      {"run", empty.string()},
      {"run", syntax.string()},
      {"run", unknown_key.string()},
      {"run", bad_value.string()},
      {"run", "cloth:8", "--obj"},
      {"run", "cloth:8", "--out", (folder_ / "no" / "such" / "folder").string()},
      {"run", "cloth:8", "--out", truncated.string()},
      {"color", "--strategy", "nope"},
      {"color", "--threads", "0"},
      {"color", (folder_ / "missing.node").string()},
      {"info", "--bogus"},
  };
  for (const auto& arguments : cases) {
    std::string shown;
    for (const auto& argument : arguments) shown += " " + argument;
    const Outcome outcome = run(arguments);
    EXPECT_EQ(outcome.exit_code, 2) << shown << "\n" << outcome.err;
    EXPECT_EQ(outcome.out, "") << shown;
    ASSERT_FALSE(outcome.err.empty()) << shown;
    EXPECT_EQ(std::count(outcome.err.begin(), outcome.err.end(), '\n'), 1) << shown << "\n" << outcome.err;
    EXPECT_EQ(outcome.err.rfind("tessera", 0), 0u) << shown << "\n" << outcome.err;
  }
  EXPECT_FALSE(fs::exists(folder_ / "no"));
}

TEST_F(Cli, ErrorMessagesSayWhatIsWrong) {
  EXPECT_EQ(run({"run", "--mode", "fast"}).err,
            "tessera run: unknown solver mode 'fast' (known: gs, jacobi, hybrid, sequential)\n");
  EXPECT_EQ(run({"run", "--threads", "0"}).err,
            "tessera run: --threads: must be an integer from 1 to 4096, not '0'\n");
  EXPECT_EQ(run({"run", "--dt", "0"}).err,
            "tessera run: --dt: must be a finite number of seconds above 0, not '0'\n");
  EXPECT_EQ(run({"bogus"}).err, "tessera: unknown subcommand 'bogus' (known: run, color, info)\n");
  EXPECT_EQ(run({"run", "cloth:1x5"}).err,
            "tessera run: scene 'cloth:1x5': a cloth needs at least 2 vertices per side\n");
  const fs::path key = write("key.json", R"({"generator": "cloth", "gravityy": [0, 0, 0]})");
  EXPECT_EQ(run({"run", key.string()}).err,
            "tessera run: " + key.string() + ": unknown key 'gravityy'\n");
}

}  // namespace
