// The frame writers: the numbers in a written .vtu (counts, connectivity, offsets, types, cell
// data with its -1 fill, points), a .pvd that stays valid after every frame, an OBJ round
// trip, validation errors that leave nothing behind, and atomic replacement of a file.
// Each test writes into a fresh folder under the system's temporary folder and removes it.
#include <gtest/gtest.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <tessera/core/error.hpp>
#include <tessera/io/generators.hpp>
#include <tessera/io/mesh_writers.hpp>

namespace tessera::io {
namespace mesh_writers_tests {

namespace fs = std::filesystem;

// ---- helpers -------------------------------------------------------------------------------

class MeshWriters : public ::testing::Test {
 protected:
  void SetUp() override {
    std::random_device device;
    const auto token = (std::uint64_t(device()) << 32) ^ device();
    folder_ = fs::temp_directory_path() / ("tessera_mesh_writers_" + std::to_string(token));
    ASSERT_TRUE(fs::create_directory(folder_));
  }
  void TearDown() override {
    std::error_code ignored;
    fs::permissions(folder_, fs::perms::owner_all, fs::perm_options::add, ignored);
    fs::remove_all(folder_, ignored);
  }
  const fs::path& folder() const { return folder_; }

 private:
  fs::path folder_;
};

std::string read_text(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The names in a folder (recursively, relative to it), sorted.
std::vector<std::string> listing(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::recursive_directory_iterator(folder))
    names.push_back(entry.path().lexically_relative(folder).generic_string());
  std::sort(names.begin(), names.end());
  return names;
}

/// The message of the InvalidInput `action` throws, or a marker when it throws nothing or
/// something else.
std::string invalid_input_message(const std::function<void()>& action) {
  try {
    action();
  } catch (const InvalidInput& error) {
    return error.what();
  } catch (const std::exception& error) {
    return std::string("<not InvalidInput: ") + error.what() + ">";
  }
  return "<no exception>";
}

/// The value of attribute `name` in the first tag that starts with `<tag` (empty if none).
std::string attribute(const std::string& xml, const std::string& tag, const std::string& name) {
  const std::size_t tag_start = xml.find("<" + tag);
  if (tag_start == std::string::npos) return {};
  const std::size_t tag_end = xml.find('>', tag_start);
  const std::size_t at = xml.find(" " + name + "=\"", tag_start);
  if (at == std::string::npos || at > tag_end) return {};
  const std::size_t value_start = at + name.size() + 3;
  return xml.substr(value_start, xml.find('"', value_start) - value_start);
}

/// The DataArray tag whose Name is `name` (empty if none).
std::string data_array_tag(const std::string& xml, const std::string& name) {
  const std::size_t at = xml.find("Name=\"" + name + "\"");
  if (at == std::string::npos) return {};
  const std::size_t start = xml.rfind("<DataArray", at);
  return xml.substr(start, xml.find('>', at) - start + 1);
}

/// The whitespace-separated values of the DataArray whose Name is `name`.
std::vector<std::string> data_array_values(const std::string& xml, const std::string& name) {
  const std::size_t at = xml.find("Name=\"" + name + "\"");
  if (at == std::string::npos) return {};
  const std::size_t content_start = xml.find('>', at) + 1;
  const std::size_t content_end = xml.find("</DataArray>", content_start);
  std::istringstream content(xml.substr(content_start, content_end - content_start));
  std::vector<std::string> values;
  for (std::string value; content >> value;) values.push_back(value);
  return values;
}

std::vector<std::string> strings(std::initializer_list<long long> numbers) {
  std::vector<std::string> text;
  for (const long long n : numbers) text.push_back(std::to_string(n));
  return text;
}

Real parse_real(const std::string& text) {
  Real value = std::numeric_limits<Real>::quiet_NaN();
  std::from_chars(text.data(), text.data() + text.size(), value);
  return value;
}

/// Empty when every opened tag is closed in order (<?...?> and <!--...--> are skipped,
/// <.../> closes itself); otherwise what is wrong.
std::string tag_balance_problem(const std::string& xml) {
  std::vector<std::string> open;
  for (std::size_t at = xml.find('<'); at != std::string::npos; at = xml.find('<', at + 1)) {
    const std::size_t end = xml.find('>', at);
    if (end == std::string::npos) return "unterminated tag at " + std::to_string(at);
    const std::string tag = xml.substr(at + 1, end - at - 1);
    if (tag.starts_with("?") || tag.starts_with("!--")) continue;
    const std::string name = tag.substr(tag.starts_with("/") ? 1 : 0,
                                        tag.find_first_of(" \t\n/", 1) - (tag.starts_with("/") ? 1 : 0));
    if (tag.starts_with("/")) {
      if (open.empty() || open.back() != name) return "</" + name + "> does not close the open tag";
      open.pop_back();
    } else if (!tag.ends_with("/")) {
      open.push_back(name);
    }
  }
  return open.empty() ? std::string() : "<" + open.back() + "> is never closed";
}

/// A small mesh: two lines, two triangles, one tetrahedron. "colour" exists on the lines and
/// the tetrahedron, "family" only on the triangles.
struct SmallMesh {
  std::vector<Vector3r> positions{{0, 0, 0}, {Real(0.1), 0, 0}, {0, Real(1.5), 0},
                                  {0, 0, Real(-2.25)}, {Real(1) / 3, 1, 1}};
  std::vector<Real> inverse_mass{0, 1, 1, Real(0.5), 2};
  std::vector<VertexIndex> lines{0, 1, 1, 2};
  std::vector<std::int32_t> line_colours{0, 1};
  std::vector<VertexIndex> triangles{0, 1, 2, 1, 2, 3};
  std::vector<std::int32_t> triangle_families{7, 8};
  std::vector<VertexIndex> tetrahedra{0, 1, 2, 4};
  std::vector<std::int32_t> tetrahedron_colours{2};

  Frame frame() const {
    Frame frame;
    frame.positions = positions;
    frame.blocks.push_back({CellType::line, lines, {{"colour", line_colours}}});
    frame.blocks.push_back({CellType::triangle, triangles, {{"family", triangle_families}}});
    frame.blocks.push_back({CellType::tetrahedron, tetrahedra, {{"colour", tetrahedron_colours}}});
    frame.point_data.push_back({"inverse_mass", inverse_mass});
    return frame;
  }
};

// ---- .vtu ----------------------------------------------------------------------------------

TEST_F(MeshWriters, VtuHoldsTheNumbers) {
  const SmallMesh mesh;
  const fs::path file = folder() / "frame.vtu";
  write_vtu(file, mesh.frame());
  EXPECT_EQ(listing(folder()), std::vector<std::string>{"frame.vtu"});
  const std::string xml = read_text(file);

  EXPECT_EQ(tag_balance_problem(xml), "");
  EXPECT_EQ(attribute(xml, "VTKFile", "type"), "UnstructuredGrid");
  EXPECT_EQ(attribute(xml, "Piece", "NumberOfPoints"), "5");
  EXPECT_EQ(attribute(xml, "Piece", "NumberOfCells"), "5");

  EXPECT_EQ(data_array_values(xml, "connectivity"),
            strings({0, 1, 1, 2, 0, 1, 2, 1, 2, 3, 0, 1, 2, 4}));
  EXPECT_EQ(data_array_values(xml, "offsets"), strings({2, 4, 7, 10, 14}));
  EXPECT_EQ(data_array_values(xml, "types"), strings({3, 3, 5, 5, 10}));
  // Arrays missing from a block are filled with -1 on its cells.
  EXPECT_EQ(data_array_values(xml, "colour"), strings({0, 1, -1, -1, 2}));
  EXPECT_EQ(data_array_values(xml, "family"), strings({-1, -1, 7, 8, -1}));
  EXPECT_NE(data_array_tag(xml, "colour").find("type=\"Int32\""), std::string::npos);
  // Cell data sits inside <CellData>, point data inside <PointData>.
  EXPECT_LT(xml.find("<CellData"), xml.find("Name=\"colour\""));
  EXPECT_GT(xml.find("</CellData>"), xml.find("Name=\"family\""));
  EXPECT_LT(xml.find("<PointData"), xml.find("Name=\"inverse_mass\""));
  EXPECT_GT(xml.find("</PointData>"), xml.find("Name=\"inverse_mass\""));

  const std::string real_type = kDoublePrecision ? "type=\"Float64\"" : "type=\"Float32\"";
  EXPECT_NE(data_array_tag(xml, "Points").find(real_type), std::string::npos);
  EXPECT_NE(data_array_tag(xml, "Points").find("NumberOfComponents=\"3\""), std::string::npos);
  const std::vector<std::string> points = data_array_values(xml, "Points");
  ASSERT_EQ(points.size(), 3 * mesh.positions.size());
  for (std::size_t p = 0; p < mesh.positions.size(); ++p)
    for (int k = 0; k < 3; ++k)  // shortest round-trip digits: bitwise the same value
      EXPECT_EQ(parse_real(points[3 * p + k]), mesh.positions[p][k]) << "point " << p;

  EXPECT_NE(data_array_tag(xml, "inverse_mass").find(real_type), std::string::npos);
  const std::vector<std::string> masses = data_array_values(xml, "inverse_mass");
  ASSERT_EQ(masses.size(), mesh.inverse_mass.size());
  for (std::size_t p = 0; p < masses.size(); ++p)
    EXPECT_EQ(parse_real(masses[p]), mesh.inverse_mass[p]);
}

TEST_F(MeshWriters, VtuOfAnEmptyFrameAndOfPositionsOnly) {
  write_vtu(folder() / "empty.vtu", Frame{});
  const std::string empty = read_text(folder() / "empty.vtu");
  EXPECT_EQ(tag_balance_problem(empty), "");
  EXPECT_EQ(attribute(empty, "Piece", "NumberOfPoints"), "0");
  EXPECT_EQ(attribute(empty, "Piece", "NumberOfCells"), "0");
  EXPECT_TRUE(data_array_values(empty, "connectivity").empty());

  const std::vector<Vector3r> positions{{1, 2, 3}};
  Frame points_only;
  points_only.positions = positions;
  points_only.blocks.push_back({CellType::triangle, {}, {}});  // an empty block is fine
  write_vtu(folder() / "points.vtu", points_only);
  const std::string xml = read_text(folder() / "points.vtu");
  EXPECT_EQ(tag_balance_problem(xml), "");
  EXPECT_EQ(attribute(xml, "Piece", "NumberOfPoints"), "1");
  EXPECT_EQ(data_array_values(xml, "Points"), strings({1, 2, 3}));
  EXPECT_EQ(xml.find("<CellData"), std::string::npos);
  EXPECT_EQ(xml.find("<PointData"), std::string::npos);
}

TEST_F(MeshWriters, VtuOfALargeClothIsComplete) {
  // Larger than the writer's 64 KiB chunks, so the text reaches the file in several pieces.
  const ClothGrid cloth = make_cloth_grid(120, 90, Real(0.01));
  std::vector<std::int32_t> edge_colours(cloth.edge_count());
  for (std::size_t e = 0; e < edge_colours.size(); ++e) edge_colours[e] = std::int32_t(e % 6);
  Frame frame;
  frame.positions = cloth.positions;
  frame.blocks.push_back({CellType::triangle, cloth.triangle_indices, {}});
  frame.blocks.push_back({CellType::line, cloth.edge_indices, {{"colour", edge_colours}}});
  const fs::path file = folder() / "cloth.vtu";
  write_vtu(file, frame);
  const std::string xml = read_text(file);
  ASSERT_GT(xml.size(), std::size_t(4) << 16);
  EXPECT_EQ(tag_balance_problem(xml), "");
  const std::size_t cells = cloth.triangle_count() + cloth.edge_count();
  EXPECT_EQ(attribute(xml, "Piece", "NumberOfPoints"), std::to_string(cloth.vertex_count()));
  EXPECT_EQ(attribute(xml, "Piece", "NumberOfCells"), std::to_string(cells));
  EXPECT_EQ(data_array_values(xml, "Points").size(), 3 * cloth.vertex_count());
  EXPECT_EQ(data_array_values(xml, "connectivity").size(),
            cloth.triangle_indices.size() + cloth.edge_indices.size());
  const std::vector<std::string> offsets = data_array_values(xml, "offsets");
  ASSERT_EQ(offsets.size(), cells);
  EXPECT_EQ(offsets.back(), std::to_string(3 * cloth.triangle_count() + 2 * cloth.edge_count()));
  const std::vector<std::string> colours = data_array_values(xml, "colour");
  ASSERT_EQ(colours.size(), cells);
  EXPECT_EQ(colours.front(), "-1");
  EXPECT_EQ(colours.back(), std::to_string((cloth.edge_count() - 1) % 6));
}

TEST_F(MeshWriters, VtuIsParseableXmlWhenPython3IsAvailable) {
  if (std::system("python3 -c 'import xml.etree.ElementTree' >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "python3 with xml.etree is not available";
  const SmallMesh mesh;
  const fs::path vtu = folder() / "frame.vtu";
  write_vtu(vtu, mesh.frame());
  PvdSeries series(folder() / "frames.pvd");
  series.add(0.25, vtu);
  series.write();
  for (const fs::path& file : {vtu, series.file()}) {
    const std::string command =
        "python3 -c 'import sys, xml.etree.ElementTree as E; E.parse(sys.argv[1])' '" +
        file.string() + "' >/dev/null 2>&1";
    EXPECT_EQ(std::system(command.c_str()), 0) << file;
  }
}

// ---- .pvd ----------------------------------------------------------------------------------

struct DataSetEntry {
  std::string timestep, file;
  bool operator==(const DataSetEntry&) const = default;
};

std::vector<DataSetEntry> pvd_entries(const std::string& xml) {
  std::vector<DataSetEntry> entries;
  for (std::size_t at = xml.find("<DataSet"); at != std::string::npos;
       at = xml.find("<DataSet", at + 1)) {
    const std::string tag = xml.substr(at, xml.find('>', at) - at + 1);
    entries.push_back({attribute(tag, "DataSet", "timestep"), attribute(tag, "DataSet", "file")});
  }
  return entries;
}

TEST_F(MeshWriters, PvdListsTheFramesInOrderAfterEveryWrite) {
  const SmallMesh mesh;
  fs::create_directory(folder() / "frames");
  PvdSeries series(folder() / "frames.pvd");
  EXPECT_EQ(series.file(), folder() / "frames.pvd");
  const std::vector<double> times{0, 0.5, 1.25};
  std::vector<DataSetEntry> expected;
  for (std::size_t i = 0; i < times.size(); ++i) {
    const std::string name = "frame_" + std::to_string(i) + ".vtu";
    write_vtu(folder() / "frames" / name, mesh.frame());
    series.add(times[i], folder() / "frames" / name);
    series.write();
    expected.push_back({i == 0 ? "0" : i == 1 ? "0.5" : "1.25", "frames/" + name});

    const std::string xml = read_text(series.file());
    EXPECT_EQ(tag_balance_problem(xml), "") << "after frame " << i;
    EXPECT_EQ(attribute(xml, "VTKFile", "type"), "Collection");
    EXPECT_EQ(pvd_entries(xml), expected) << "after frame " << i;
    for (const DataSetEntry& entry : pvd_entries(xml))
      EXPECT_TRUE(fs::exists(folder() / entry.file)) << entry.file;
  }
  EXPECT_EQ(series.frames().size(), times.size());
  EXPECT_EQ(listing(folder()), (std::vector<std::string>{"frames", "frames.pvd", "frames/frame_0.vtu",
                                                         "frames/frame_1.vtu", "frames/frame_2.vtu"}));
}

TEST_F(MeshWriters, PvdStoresPathsRelativeToItsFolderAndEscapesThem) {
  PvdSeries series(folder() / "out" / "run.pvd");
  series.add(0, folder() / "out" / "a.vtu");
  series.add(1, folder() / "out" / "." / "sub" / "b.vtu");
  series.add(2, folder() / "elsewhere" / "c.vtu");
  series.add(3, folder() / "out" / "x&y\"z.vtu");
  ASSERT_EQ(series.frames().size(), 4u);
  EXPECT_EQ(series.frames()[0].second, "a.vtu");
  EXPECT_EQ(series.frames()[1].second, "sub/b.vtu");
  EXPECT_EQ(series.frames()[2].second, "../elsewhere/c.vtu");
  EXPECT_EQ(series.frames()[3].second, "x&y\"z.vtu");

  fs::create_directory(folder() / "out");
  series.write();
  const std::string xml = read_text(series.file());
  EXPECT_EQ(tag_balance_problem(xml), "");
  EXPECT_NE(xml.find("file=\"x&amp;y&quot;z.vtu\""), std::string::npos);
}

TEST_F(MeshWriters, PvdRejectsANonFiniteTime) {
  PvdSeries series(folder() / "run.pvd");
  const std::string message = invalid_input_message(
      [&] { series.add(std::numeric_limits<double>::quiet_NaN(), folder() / "a.vtu"); });
  EXPECT_NE(message.find("run.pvd"), std::string::npos) << message;
  EXPECT_NE(message.find("not finite"), std::string::npos) << message;
  EXPECT_TRUE(series.frames().empty());
}

// ---- .obj ----------------------------------------------------------------------------------

TEST_F(MeshWriters, ObjRoundTripsPositionsAndTriangles) {
  const SmallMesh mesh;
  Frame frame = mesh.frame();
  const std::vector<VertexIndex> more_triangles{4, 3, 2};
  frame.blocks.push_back({CellType::triangle, more_triangles, {}});
  const fs::path file = folder() / "mesh.obj";
  write_obj(file, frame);
  EXPECT_EQ(listing(folder()), std::vector<std::string>{"mesh.obj"});

  std::vector<Vector3r> positions;
  std::vector<VertexIndex> triangles;
  std::istringstream lines(read_text(file));
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::string kind;
    words >> kind;
    if (kind == "v") {
      std::string x, y, z;
      words >> x >> y >> z;
      positions.emplace_back(parse_real(x), parse_real(y), parse_real(z));
    } else if (kind == "f") {
      for (long index; words >> index;) {
        ASSERT_GE(index, 1) << "OBJ indices are 1-based";
        triangles.push_back(VertexIndex(index - 1));
      }
    } else {
      EXPECT_TRUE(kind.empty() || kind.starts_with("#")) << line;
    }
  }
  ASSERT_EQ(positions.size(), mesh.positions.size());
  for (std::size_t p = 0; p < positions.size(); ++p)
    EXPECT_EQ(positions[p], mesh.positions[p]) << "point " << p;
  std::vector<VertexIndex> expected = mesh.triangles;  // lines and tetrahedra are skipped
  expected.insert(expected.end(), more_triangles.begin(), more_triangles.end());
  EXPECT_EQ(triangles, expected);
}

// ---- validation ----------------------------------------------------------------------------

TEST_F(MeshWriters, InvalidFramesThrowAndLeaveNothing) {
  const SmallMesh mesh;
  const Real nan = std::numeric_limits<Real>::quiet_NaN();
  const Real infinity = std::numeric_limits<Real>::infinity();
  std::vector<Vector3r> nan_positions = mesh.positions;
  nan_positions[3].y() = nan;
  std::vector<Vector3r> infinite_positions = mesh.positions;
  infinite_positions[4].z() = -infinity;
  const std::vector<VertexIndex> seven_indices{0, 1, 2, 3, 4, 0, 1};
  const std::vector<VertexIndex> out_of_range{0, 1, 5};
  const std::vector<std::int32_t> three_colours{0, 1, 2};
  const std::vector<Real> four_masses{1, 1, 1, 1};
  std::vector<Real> infinite_masses = mesh.inverse_mass;
  infinite_masses[2] = infinity;

  struct Case {
    std::string what;
    std::function<void(Frame&)> break_frame;
    std::string expected_in_message;
  };
  const std::vector<Case> cases{
      {"NaN position", [&](Frame& f) { f.positions = nan_positions; }, "point 3 is not finite"},
      {"infinite position", [&](Frame& f) { f.positions = infinite_positions; },
       "point 4 is not finite"},
      {"index count not a multiple", [&](Frame& f) { f.blocks[1].vertices = seven_indices; },
       "block 1 (triangle) has 7 vertex indices, not a multiple of 3"},
      {"index count for tetrahedra", [&](Frame& f) { f.blocks[2].vertices = mesh.triangles; },
       "block 2 (tetrahedron) has 6 vertex indices, not a multiple of 4"},
      {"index out of range",
       [&](Frame& f) {
         f.blocks[1].vertices = out_of_range;
         f.blocks[1].cell_data.clear();
       },
       "block 1 (triangle): vertex index 5 of cell 0 is out of range (5 points)"},
      {"cell data size", [&](Frame& f) { f.blocks[0].cell_data[0].second = three_colours; },
       "cell data \"colour\" has 3 values for 2 cells"},
      {"empty cell data name", [&](Frame& f) { f.blocks[0].cell_data[0].first = ""; },
       "is empty"},
      {"cell data name with <", [&](Frame& f) { f.blocks[0].cell_data[0].first = "a<b"; },
       "not allowed in a name"},
      {"cell data name with &", [&](Frame& f) { f.blocks[1].cell_data[0].first = "a&b"; },
       "not allowed in a name"},
      {"cell data name with a quote", [&](Frame& f) { f.blocks[2].cell_data[0].first = "a\"b"; },
       "not allowed in a name"},
      {"cell data name with a newline", [&](Frame& f) { f.blocks[2].cell_data[0].first = "a\nb"; },
       "not allowed in a name"},
      {"cell data twice in a block",
       [&](Frame& f) { f.blocks[0].cell_data.push_back(f.blocks[0].cell_data[0]); },
       "block 0 (line): cell data \"colour\" is given twice"},
      {"empty point data name", [&](Frame& f) { f.point_data[0].first = ""; }, "is empty"},
      {"point data name with >", [&](Frame& f) { f.point_data[0].first = "m>"; },
       "not allowed in a name"},
      {"point data twice", [&](Frame& f) { f.point_data.push_back(f.point_data[0]); },
       "point data \"inverse_mass\" is given twice"},
      {"point data size", [&](Frame& f) { f.point_data[0].second = four_masses; },
       "point data \"inverse_mass\" has 4 values for 5 points"},
      {"infinite point data", [&](Frame& f) { f.point_data[0].second = infinite_masses; },
       "point data \"inverse_mass\" is not finite at point 2"},
  };

  for (const Case& broken : cases) {
    Frame frame = mesh.frame();
    broken.break_frame(frame);
    for (const char* name : {"frame.vtu", "frame.obj"}) {
      const fs::path file = folder() / name;
      const std::string message = invalid_input_message([&] {
        if (file.extension() == ".vtu")
          write_vtu(file, frame);
        else
          write_obj(file, frame);
      });
      EXPECT_EQ(message.find("cannot write " + file.string() + ": "), 0u)
          << broken.what << ": " << message;
      EXPECT_NE(message.find(broken.expected_in_message), std::string::npos)
          << broken.what << ": " << message;
      EXPECT_TRUE(listing(folder()).empty()) << broken.what;
    }
  }
}

TEST_F(MeshWriters, MissingFolderThrowsAndCreatesNothing) {
  const SmallMesh mesh;
  const fs::path missing = folder() / "missing";
  for (const fs::path& file : {missing / "frame.vtu", missing / "frame.obj", missing / "run.pvd",
                               missing / "deeper" / "frame.vtu"}) {
    const std::string message = invalid_input_message([&] {
      if (file.extension() == ".vtu")
        write_vtu(file, mesh.frame());
      else if (file.extension() == ".obj")
        write_obj(file, mesh.frame());
      else
        PvdSeries(file).write();
    });
    EXPECT_EQ(message.find("cannot write " + file.string() + ": "), 0u) << message;
    EXPECT_NE(message.find("does not exist"), std::string::npos) << message;
  }
  EXPECT_TRUE(listing(folder()).empty());
}

TEST_F(MeshWriters, UnwritablePathsThrowAndLeaveNothing) {
  const SmallMesh mesh;
  // The "folder" is a regular file.
  std::ofstream(folder() / "plain.txt") << "not a folder\n";
  const std::string under_a_file =
      invalid_input_message([&] { write_vtu(folder() / "plain.txt" / "frame.vtu", mesh.frame()); });
  EXPECT_NE(under_a_file.find("is not a folder"), std::string::npos) << under_a_file;

  // The target is a folder: everything is written, then the rename fails and the temporary
  // must go.
  fs::create_directory(folder() / "frame.vtu");
  std::ofstream(folder() / "frame.vtu" / "keep.txt") << "kept\n";
  const std::string onto_a_folder =
      invalid_input_message([&] { write_vtu(folder() / "frame.vtu", mesh.frame()); });
  EXPECT_EQ(onto_a_folder.find("cannot write " + (folder() / "frame.vtu").string() + ": "), 0u)
      << onto_a_folder;
  EXPECT_NE(onto_a_folder.find("rename"), std::string::npos) << onto_a_folder;

  // A path that names no file.
  const std::string no_name =
      invalid_input_message([&] { write_obj(folder() / "sub" / "", mesh.frame()); });
  EXPECT_NE(no_name.find("names no file"), std::string::npos) << no_name;

  EXPECT_EQ(listing(folder()),
            (std::vector<std::string>{"frame.vtu", "frame.vtu/keep.txt", "plain.txt"}));
  EXPECT_EQ(read_text(folder() / "frame.vtu" / "keep.txt"), "kept\n");
}

TEST_F(MeshWriters, ReadOnlyFolderThrowsAndLeavesNothing) {
  const fs::path locked = folder() / "locked";
  fs::create_directory(locked);
  fs::permissions(locked, fs::perms::owner_read | fs::perms::owner_exec);
  if (std::ofstream(locked / "probe").is_open()) {  // root ignores permissions
    fs::remove(locked / "probe");
    GTEST_SKIP() << "this user can write into a read-only folder (root)";
  }
  const SmallMesh mesh;
  const std::string message =
      invalid_input_message([&] { write_vtu(locked / "frame.vtu", mesh.frame()); });
  EXPECT_NE(message.find("cannot create the temporary file"), std::string::npos) << message;
  fs::permissions(locked, fs::perms::owner_all);
  EXPECT_EQ(listing(folder()), std::vector<std::string>{"locked"});
}

// ---- atomic replacement --------------------------------------------------------------------

TEST_F(MeshWriters, RewritingAFrameReplacesItAtomically) {
  const SmallMesh mesh;
  const fs::path file = folder() / "frame.vtu";
  write_vtu(file, mesh.frame());
  const std::string old_content = read_text(file);

  // A reader that opened the old frame keeps reading the old, complete frame: the new one is
  // a different file renamed over the name, not the old file truncated and rewritten.
  std::ifstream old_reader(file, std::ios::binary);
  ASSERT_TRUE(old_reader.is_open());
  std::vector<Vector3r> moved = mesh.positions;
  for (Vector3r& x : moved) x += Vector3r(10, 20, 30);
  Frame moved_frame = mesh.frame();
  moved_frame.positions = moved;
  write_vtu(file, moved_frame);
  std::ostringstream seen_by_old_reader;
  seen_by_old_reader << old_reader.rdbuf();
  EXPECT_EQ(seen_by_old_reader.str(), old_content);
  const std::string new_content = read_text(file);
  EXPECT_NE(new_content, old_content);
  EXPECT_EQ(tag_balance_problem(new_content), "");
  EXPECT_EQ(parse_real(data_array_values(new_content, "Points")[0]), Real(10));

  // A rewrite that fails leaves the previous frame as it was.
  Frame broken = moved_frame;
  broken.blocks[0].cell_data[0].first = "";
  EXPECT_THROW(write_vtu(file, broken), InvalidInput);
  EXPECT_EQ(read_text(file), new_content);
  EXPECT_EQ(listing(folder()), std::vector<std::string>{"frame.vtu"});
}

TEST_F(MeshWriters, ConcurrentWritersOfOneFileLeaveOneCompleteFrame) {
  // Each writer has its own temporary, so the file always holds one writer's whole frame.
  const SmallMesh mesh;
  const fs::path file = folder() / "frame.vtu";
  constexpr int kWriters = 4, kRounds = 20;
  std::vector<std::vector<Vector3r>> positions(kWriters, mesh.positions);
  std::set<std::string> complete_contents;
  for (int w = 0; w < kWriters; ++w) {
    for (Vector3r& x : positions[w]) x.x() += Real(w);
    Frame frame = mesh.frame();
    frame.positions = positions[w];
    const fs::path reference = folder() / ("reference_" + std::to_string(w) + ".vtu");
    write_vtu(reference, frame);
    complete_contents.insert(read_text(reference));
    fs::remove(reference);
  }
  std::vector<std::thread> writers;
  std::vector<std::string> failures(kWriters);
  for (int w = 0; w < kWriters; ++w)
    writers.emplace_back([&, w] {
      Frame frame = mesh.frame();
      frame.positions = positions[w];
      try {
        for (int round = 0; round < kRounds; ++round) write_vtu(file, frame);
      } catch (const std::exception& error) {
        failures[w] = error.what();
      }
    });
  for (std::thread& writer : writers) writer.join();
  for (const std::string& failure : failures) EXPECT_EQ(failure, "");
  EXPECT_EQ(complete_contents.count(read_text(file)), 1u);
  EXPECT_EQ(listing(folder()), std::vector<std::string>{"frame.vtu"});
}

}  // namespace mesh_writers_tests
}  // namespace tessera::io
