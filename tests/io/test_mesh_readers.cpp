// The mesh readers: known meshes from the hand-written files in tests/io/data (OBJ, TetGen,
// Gmsh 2.2 and 4.1 of one geometry), one test per error message with its "file:line: "
// prefix, and robustness: every prefix of every valid file, random bytes, random edits of
// valid files and endless input all end in a mesh or tessera::InvalidInput, never a crash.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <streambuf>
#include <string>
#include <vector>

#include <tessera/core/error.hpp>
#include <tessera/io/mesh_readers.hpp>

namespace tessera::io {
namespace mesh_readers_tests {

const std::filesystem::path kDataDir = TESSERA_TEST_DATA_DIR;

std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

using Point = std::array<double, 3>;

std::vector<Point> positions_of(const Mesh& mesh) {
  std::vector<Point> points;
  for (const Vector3r& p : mesh.positions)
    points.push_back({double(p.x()), double(p.y()), double(p.z())});
  return points;
}

/// The cube of tests/io/data/cube.*: 8 corners, then a separate tetrahedron at x = 3.
const std::vector<Point> kCubePositions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0},
                                           {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1},
                                           {3, 0, 0}, {4, 0, 0}, {3, 1, 0}, {3, 0, 1}};
const std::vector<VertexIndex> kCubeTetrahedra = {0, 1, 3, 7, 0, 1, 7, 5, 0, 2, 7, 3, 0,  2,
                                                  6, 7, 0, 4, 5, 7, 0, 4, 7, 6, 8, 9, 10, 11};
const std::vector<VertexIndex> kCubeTriangles = {0, 3, 1, 0, 2, 3, 8, 10, 9};

// ---- error helpers: the message a reader throws for in-memory input -----------------

std::string obj_error(const std::string& text) {
  std::istringstream in(text);
  try {
    read_obj(in, "bad.obj");
  } catch (const InvalidInput& error) {
    return error.what();
  }
  return "(no error)";
}

std::string gmsh_error(const std::string& text) {
  std::istringstream in(text);
  try {
    read_gmsh(in, "bad.msh");
  } catch (const InvalidInput& error) {
    return error.what();
  }
  return "(no error)";
}

std::string tetgen_error(const std::string& node, const std::string& ele,
                         const std::string* face = nullptr) {
  std::istringstream node_in(node), ele_in(ele), face_in(face ? *face : std::string());
  try {
    if (face)
      read_tetgen(node_in, ele_in, face_in, "bad.node", "bad.ele", "bad.face");
    else
      read_tetgen(node_in, ele_in, "bad.node", "bad.ele");
  } catch (const InvalidInput& error) {
    return error.what();
  }
  return "(no error)";
}

std::string path_error(Mesh (*reader)(const std::filesystem::path&),
                       const std::filesystem::path& file) {
  try {
    reader(file);
  } catch (const InvalidInput& error) {
    return error.what();
  }
  return "(no error)";
}

const std::string kGmsh22Header = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
const std::string kGmsh41Header = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
const std::string kGmsh22Nodes = "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n";
const std::string kTetgenNodes = "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";
const std::string kTetgenOneTet = "1 4 0\n1 1 2 3 4\n";

// ---- valid files ----------------------------------------------------------------------

TEST(ReadObj, SquareQuadWithNegativeIndicesIsFanTriangulated) {
  const Mesh mesh = read_obj(kDataDir / "square.obj");
  EXPECT_EQ(positions_of(mesh), (std::vector<Point>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}));
  EXPECT_EQ(mesh.triangles, (std::vector<VertexIndex>{0, 1, 2, 0, 2, 3}));
  EXPECT_TRUE(mesh.tetrahedra.empty());
}

TEST(ReadObj, TwoPiecesWithCrlfEveryCornerFormPentagonAndContinuation) {
  const Mesh mesh = read_obj(kDataDir / "pieces.obj");
  EXPECT_EQ(positions_of(mesh), (std::vector<Point>{{0, 0, 0},
                                                    {2, 0, 0},
                                                    {2, 1, 0},
                                                    {1, 2, 0},
                                                    {0, 1, 0},
                                                    {5, 0, 0.5},
                                                    {6, 0, 0.5},
                                                    {5, 1, 0.5}}));
  EXPECT_EQ(mesh.triangles,
            (std::vector<VertexIndex>{0, 1, 2, 0, 2, 3, 0, 3, 4, 5, 6, 7, 5, 7, 6}));
}

TEST(ReadObj, StreamOverloadAcceptsCornerFormsAndIgnoresOtherStatements) {
  std::istringstream in(
      "\xEF\xBB\xBFv 0 0 0\nv +1 0 0 1\nv 0 1 0 0.5 0.5 0.5\nvt 0 0\nvn 0 0 1\nvp 0.5\n"
      "mystery statement 42\n\n   # indented comment\nf 1/1 2/1/1 3//1\nl 1 2 3\nfo 3 2 1\n");
  const Mesh mesh = read_obj(in, "memory.obj");
  EXPECT_EQ(positions_of(mesh), (std::vector<Point>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}));
  EXPECT_EQ(mesh.triangles, (std::vector<VertexIndex>{0, 1, 2, 2, 1, 0}));
}

TEST(ReadObj, OldMacLineEndsAreLineEnds) {
  std::istringstream in("v 0 0 0\rv 1 0 0\rv 0 1 0\rf 1 2 3\r");
  const Mesh mesh = read_obj(in, "mac.obj");
  EXPECT_EQ(mesh.vertex_count(), 3u);
  EXPECT_EQ(mesh.triangles, (std::vector<VertexIndex>{0, 1, 2}));
}

TEST(ReadObj, VerticesWithoutFacesAreNotAnError) {
  std::istringstream in("v 0 0 0\nv 1 0 0\n");
  const Mesh mesh = read_obj(in, "points.obj");
  EXPECT_EQ(mesh.vertex_count(), 2u);
  EXPECT_TRUE(mesh.triangles.empty());
}

void expect_cube(const Mesh& mesh, bool with_faces) {
  EXPECT_EQ(positions_of(mesh), kCubePositions);
  EXPECT_EQ(mesh.tetrahedra, kCubeTetrahedra);
  EXPECT_EQ(mesh.triangles, with_faces ? kCubeTriangles : std::vector<VertexIndex>{});
}

TEST(ReadTetgen, OneBasedCubeWithFacesFromBaseNodeEleAndFacePaths) {
  expect_cube(read_tetgen(kDataDir / "cube"), true);
  expect_cube(read_tetgen(kDataDir / "cube.node"), true);
  expect_cube(read_tetgen(kDataDir / "cube.ele"), true);
  expect_cube(read_tetgen(kDataDir / "cube.face"), true);
}

TEST(ReadTetgen, ZeroBasedCubeGivesTheSameMeshWithoutFaceFile) {
  expect_cube(read_tetgen(kDataDir / "cube0.node"), false);
}

TEST(ReadTetgen, StreamOverloadsWithAndWithoutFaces) {
  std::istringstream node(read_text(kDataDir / "cube.node")), ele(read_text(kDataDir / "cube.ele"));
  expect_cube(read_tetgen(node, ele, "cube.node", "cube.ele"), false);
  std::istringstream node2(read_text(kDataDir / "cube.node")),
      ele2(read_text(kDataDir / "cube.ele"));
  std::istringstream face(read_text(kDataDir / "cube.face"));
  expect_cube(read_tetgen(node2, ele2, face, "cube.node", "cube.ele", "cube.face"), true);
}

TEST(ReadTetgen, TenNodeTetrahedraKeepTheirCorners) {
  std::istringstream node(
      "# corners, then six mid-edge points\n10 3\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n"
      "4 .5 0 0\n5 .5 .5 0\n6 0 .5 0\n7 0 0 .5\n8 .5 0 .5\n9 0 .5 .5\n");
  std::istringstream ele("1 10\n0 0 1 2 3 4 5 6 7 8 9\n");
  const Mesh mesh = read_tetgen(node, ele, "quadratic.node", "quadratic.ele");
  EXPECT_EQ(mesh.vertex_count(), 10u);
  EXPECT_EQ(mesh.tetrahedra, (std::vector<VertexIndex>{0, 1, 2, 3}));
}

TEST(ReadTetgen, FaceFileWithAdjacentTetrahedraColumns) {
  std::istringstream node(kTetgenNodes), ele(kTetgenOneTet),
      face("2 1\n1 1 2 3 -1 1 -1\n2 1 2 4 -1 1 -1\n");
  const Mesh mesh = read_tetgen(node, ele, face, "a.node", "a.ele", "a.face");
  EXPECT_EQ(mesh.triangles, (std::vector<VertexIndex>{0, 1, 2, 0, 1, 3}));
}

TEST(ReadGmsh, Version22GivesTheTetgenMesh) {
  expect_cube(read_gmsh(kDataDir / "cube_v22.msh"), true);
}

TEST(ReadGmsh, Version41GivesTheTetgenMesh) {
  expect_cube(read_gmsh(kDataDir / "cube_v41.msh"), true);
}

TEST(ReadGmsh, SecondOrderElementsKeepTheirCorners) {
  std::istringstream in(
      kGmsh22Header +
      "$Nodes\n10\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 .5 0 0\n6 .5 .5 0\n7 0 .5 0\n"
      "8 0 0 .5\n9 .5 0 .5\n10 0 .5 .5\n$EndNodes\n"
      "$Elements\n2\n1 9 2 0 0 1 2 3 5 6 7\n2 11 2 0 0 1 2 3 4 5 6 7 8 10 9\n$EndElements\n");
  const Mesh mesh = read_gmsh(in, "quadratic.msh");
  EXPECT_EQ(mesh.vertex_count(), 10u);
  EXPECT_EQ(mesh.triangles, (std::vector<VertexIndex>{0, 1, 2}));
  EXPECT_EQ(mesh.tetrahedra, (std::vector<VertexIndex>{0, 1, 2, 3}));
}

TEST(ReadGmsh, Version41ParametricNodesAndEmptyBlocks) {
  std::istringstream in(kGmsh41Header +
                        "$Nodes\n4 3 5 9\n0 1 0 0\n2 1 1 2\n9\n5\n0 1 0 0.25 0.75\n1 0 0 0.5 0.5\n"
                        "1 3 1 1\n7\n0 0 1 0.125\n3 1 0 0\n$EndNodes\n"
                        "$Elements\n1 1 1 1\n2 1 2 1\n1 9 5 7\n$EndElements\n");
  const Mesh mesh = read_gmsh(in, "parametric.msh");
  EXPECT_EQ(positions_of(mesh), (std::vector<Point>{{0, 1, 0}, {1, 0, 0}, {0, 0, 1}}));
  EXPECT_EQ(mesh.triangles, (std::vector<VertexIndex>{0, 1, 2}));
}

TEST(ReadGmsh, NodesWithoutElementsAreNotAnError) {
  std::istringstream in(kGmsh22Header + kGmsh22Nodes);
  const Mesh mesh = read_gmsh(in, "nodes.msh");
  EXPECT_EQ(mesh.vertex_count(), 4u);
  EXPECT_TRUE(mesh.triangles.empty());
  EXPECT_TRUE(mesh.tetrahedra.empty());
}

TEST(ReadMesh, PicksTheReaderByExtensionIgnoringCase) {
  EXPECT_EQ(read_mesh(kDataDir / "square.obj").triangles,
            (std::vector<VertexIndex>{0, 1, 2, 0, 2, 3}));
  expect_cube(read_mesh(kDataDir / "cube.node"), true);
  expect_cube(read_mesh(kDataDir / "cube0.ele"), false);
  expect_cube(read_mesh(kDataDir / "cube_v22.msh"), true);
  expect_cube(read_mesh(kDataDir / "cube_v41.msh"), true);
  const std::filesystem::path upper =
      std::filesystem::temp_directory_path() / "tessera_readers_SQUARE.OBJ";
  std::filesystem::copy_file(kDataDir / "square.obj", upper,
                             std::filesystem::copy_options::overwrite_existing);
  EXPECT_EQ(read_mesh(upper).vertex_count(), 4u);
  std::filesystem::remove(upper);
}

// ---- file-level errors ----------------------------------------------------------------

TEST(ReadMeshErrors, UnsupportedExtensionMissingFileAndDirectory) {
  EXPECT_EQ(path_error(read_mesh, "model.stl"),
            "model.stl: unsupported mesh file extension '.stl' (expected .obj, .node, .ele, .face "
            "or .msh)");
  EXPECT_EQ(
      path_error(read_mesh, "model"),
      "model: unsupported mesh file extension (none) (expected .obj, .node, .ele, .face or .msh)");
  const std::filesystem::path missing = kDataDir / "missing.obj";
  EXPECT_EQ(path_error(read_obj, missing), missing.string() + ": cannot open: no such file");
  EXPECT_EQ(path_error(read_gmsh, kDataDir),
            kDataDir.string() + ": cannot open: it is a directory");
  const std::filesystem::path missing_ele = kDataDir / "missing.ele";
  const std::filesystem::path lonely_node =
      std::filesystem::temp_directory_path() / "tessera_readers_lonely.node";
  std::ofstream(lonely_node) << kTetgenNodes;
  EXPECT_EQ(path_error(read_tetgen, lonely_node),
            (std::filesystem::temp_directory_path() / "tessera_readers_lonely.ele").string() +
                ": cannot open: no such file");
  std::filesystem::remove(lonely_node);
}

TEST(ReadMeshErrors, EmptyFileOnDisk) {
  const std::filesystem::path empty =
      std::filesystem::temp_directory_path() / "tessera_readers_empty.msh";
  std::ofstream{empty};
  EXPECT_EQ(path_error(read_mesh, empty), empty.string() + ":1: empty file");
  std::filesystem::remove(empty);
}

// ---- OBJ errors -----------------------------------------------------------------------

TEST(ReadObjErrors, EveryMessageWithFileAndLine) {
  EXPECT_EQ(obj_error(""), "bad.obj:1: empty file (no statements, only blank lines or comments)");
  EXPECT_EQ(obj_error("# only\n\n# comments\n"),
            "bad.obj:3: empty file (no statements, only blank lines or comments)");
  EXPECT_EQ(obj_error("v 0 0\n"), "bad.obj:1: expected 3 coordinates after 'v', found 2");
  EXPECT_EQ(obj_error("v 0 0 0 1 2 3 4 5\n"),
            "bad.obj:1: expected x y z [w] or x y z r g b after 'v', found 8 values");
  EXPECT_EQ(obj_error("v 0 0 0 1 2\n"),
            "bad.obj:1: expected x y z [w] or x y z r g b after 'v', found 5 values");
  EXPECT_EQ(obj_error("v 0 zero 0\n"), "bad.obj:1: y coordinate 'zero' is not a number");
  EXPECT_EQ(obj_error("v 0 0 1.5x\n"), "bad.obj:1: z coordinate '1.5x' is not a number");
  EXPECT_EQ(obj_error("v 0,5 0 0\n"), "bad.obj:1: x coordinate '0,5' is not a number");
  EXPECT_EQ(obj_error("\nv nan 0 0\n"), "bad.obj:2: x coordinate 'nan' is not finite");
  EXPECT_EQ(obj_error("v 0 -inf 0\n"), "bad.obj:1: y coordinate '-inf' is not finite");
  EXPECT_EQ(obj_error("v 0 0 1e400\n"),
            "bad.obj:1: z coordinate '1e400' is out of range for a double");
  if (!kDoublePrecision) {
    EXPECT_EQ(obj_error("v 1e39 0 0\n"),
              "bad.obj:1: x coordinate '1e39' is too large for Real (float)");
  }
  EXPECT_EQ(obj_error("v 0 0 0 w\n"), "bad.obj:1: vertex value 'w' is not a number");

  const std::string eight =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 1 1 0\nv 1 0 1\nv 0 1 1\n# c\nv 1 1 1\n";
  EXPECT_EQ(obj_error(eight + "f 1 2 12\n"),
            "bad.obj:10: face index 12 is out of range (the file has 8 vertices so far)");
  EXPECT_EQ(obj_error("v 0 0 0\nf 1 2 3\nv 1 0 0\nv 0 1 0\n"),
            "bad.obj:2: face index 2 is out of range (the file has 1 vertex so far)");
  EXPECT_EQ(obj_error(eight + "f -1 -2 -9\n"),
            "bad.obj:10: face index -9 is out of range (the file has 8 vertices so far)");
  EXPECT_EQ(
      obj_error(eight + "f 0 1 2\n"),
      "bad.obj:10: face index 0 is invalid (OBJ indices start at 1; negative ones count back)");
  EXPECT_EQ(obj_error(eight + "f 1 2\n"), "bad.obj:10: a face needs at least 3 vertices, found 2");
  EXPECT_EQ(obj_error(eight + "f 1 2 3 2\n"), "bad.obj:10: the face names vertex 2 twice");
  EXPECT_EQ(obj_error(eight + "f 1 2 -8\n"), "bad.obj:10: the face names vertex 1 twice");
  EXPECT_EQ(obj_error(eight + "f 1 x 3\n"), "bad.obj:10: face index 'x' is not an integer");
  EXPECT_EQ(obj_error(eight + "f 1 2 99999999999999999999\n"),
            "bad.obj:10: face index '99999999999999999999' is out of range");
  EXPECT_EQ(obj_error(eight + "f 1/a 2 3\n"), "bad.obj:10: texture index 'a' is not an integer");
  EXPECT_EQ(obj_error(eight + "f 1//b 2 3\n"), "bad.obj:10: normal index 'b' is not an integer");
  EXPECT_EQ(obj_error(eight + "f 1/1/1/1 2 3\n"),
            "bad.obj:10: face corner '1/1/1/1' is not of the form i, i/t, i//n or i/t/n");
  EXPECT_EQ(obj_error(eight + "f 1/2/ 2 3\n"),
            "bad.obj:10: face corner '1/2/' is not of the form i, i/t, i//n or i/t/n");
  EXPECT_EQ(obj_error(eight + "f /1 2 3\n"), "bad.obj:10: face corner '/1' has no vertex index");
  // A continued statement is reported at its first line.
  EXPECT_EQ(obj_error(eight + "f 1 2 \\\n 3 \\\n 44\n"),
            "bad.obj:10: face index 44 is out of range (the file has 8 vertices so far)");
}

TEST(ReadObjErrors, BinaryDataAndOverlongLines) {
  EXPECT_EQ(obj_error("v 0 0 0\nv 1\x01\x02"),
            "bad.obj:2: unexpected control byte 0x01: this is not a text file");
  EXPECT_EQ(obj_error(std::string("v 0 0 0\0", 8)),
            "bad.obj:1: unexpected control byte 0x00: this is not a text file");
  EXPECT_EQ(obj_error("# " + std::string(2u << 20, 'a')),
            "bad.obj:1: the line is longer than 1048576 bytes");
  std::string long_statement = "v 0 0 0\nf";
  for (int i = 0; i < 300000; ++i) long_statement += " 1 \\\n";
  EXPECT_EQ(obj_error(long_statement),
            "bad.obj:2: the statement continued with '\\' is longer than 1048576 bytes");
}

/// An endless stream of one character: the readers must stop with an error, not hang or
/// fill memory.
class EndlessBuffer : public std::streambuf {
 public:
  explicit EndlessBuffer(char fill) {
    block_.fill(fill);
    setg(block_.data(), block_.data(), block_.data() + block_.size());
  }

 protected:
  int_type underflow() override {
    setg(block_.data(), block_.data(), block_.data() + block_.size());
    return traits_type::to_int_type(block_[0]);
  }

 private:
  std::array<char, 4096> block_{};
};

TEST(ReadMeshErrors, EndlessInputWithoutLineEndsStops) {
  EndlessBuffer endless('7');
  std::istream in(&endless);
  EXPECT_THROW(read_obj(in, "endless.obj"), InvalidInput);
  EXPECT_THROW(read_gmsh(in, "endless.msh"), InvalidInput);
}

TEST(ReadMeshErrors, FailedStreamIsReported) {
  std::istringstream in("v 0 0 0\n");
  in.setstate(std::ios::failbit);
  EXPECT_EQ(
      [&] {
        try {
          read_obj(in, "failed.obj");
        } catch (const InvalidInput& error) {
          return std::string(error.what());
        }
        return std::string("(no error)");
      }(),
      "failed.obj:1: cannot read: the stream is in a failed state");
}

// ---- TetGen errors --------------------------------------------------------------------

TEST(ReadTetgenErrors, NodeFile) {
  EXPECT_EQ(tetgen_error("", kTetgenOneTet),
            "bad.node:1: empty file (expected the header '<#points> <dimension> <#attributes> "
            "<#boundary markers>')");
  EXPECT_EQ(tetgen_error("# nothing\n", kTetgenOneTet),
            "bad.node:1: empty file (expected the header '<#points> <dimension> <#attributes> "
            "<#boundary markers>')");
  EXPECT_EQ(tetgen_error("4 3 0 0 9\n", kTetgenOneTet),
            "bad.node:1: the header has 5 values (expected <#points> <dimension> <#attributes> "
            "<#boundary markers>)");
  EXPECT_EQ(tetgen_error("four 3 0 0\n", kTetgenOneTet),
            "bad.node:1: point count 'four' is not an integer");
  EXPECT_EQ(tetgen_error("-4 3 0 0\n", kTetgenOneTet), "bad.node:1: point count -4 is negative");
  EXPECT_EQ(tetgen_error("4 2 0 0\n", kTetgenOneTet),
            "bad.node:1: dimension 2 is not supported (only 3)");
  EXPECT_EQ(tetgen_error("4 3 0 2\n", kTetgenOneTet),
            "bad.node:1: boundary marker count 2 is not 0 or 1");
  EXPECT_EQ(tetgen_error("4 3 99999999999 0\n", kTetgenOneTet),
            "bad.node:1: attribute count 99999999999 is too large");
  EXPECT_EQ(tetgen_error("4 3 0 0\n1 0 0 0\n2 1 0 0\n", kTetgenOneTet),
            "bad.node:3: truncated: the file ends after 2 of the 4 points its header declares");
  EXPECT_EQ(tetgen_error("1000000000000 3 0 0\n1 0 0 0\n", kTetgenOneTet),
            "bad.node:2: truncated: the file ends after 1 of the 1000000000000 points its header "
            "declares");
  EXPECT_EQ(tetgen_error("4 3 0 0\n1 0 0\n", kTetgenOneTet),
            "bad.node:2: expected a point index and 3 coordinates, found 3 values");
  EXPECT_EQ(
      tetgen_error("4 3 1 1\n1 0 0 0 0.5\n", kTetgenOneTet),
      "bad.node:2: expected 6 values (index, x y z, 1 attribute, 1 boundary marker), found 5");
  EXPECT_EQ(tetgen_error("4 3 0 0\n5 0 0 0\n", kTetgenOneTet),
            "bad.node:2: the first point index is 5 (expected 0 or 1)");
  EXPECT_EQ(tetgen_error("4 3 0 0\n1 0 0 0\n2 1 0 0\n# gap\n4 0 1 0\n", kTetgenOneTet),
            "bad.node:5: point index 4 is out of sequence (expected 3)");
  EXPECT_EQ(tetgen_error("4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 nan\n", kTetgenOneTet),
            "bad.node:5: z coordinate 'nan' is not finite");
  EXPECT_EQ(tetgen_error("4 3 1 1\n1 0 0 0 a 1\n", kTetgenOneTet),
            "bad.node:2: attribute 'a' is not a number");
  EXPECT_EQ(tetgen_error("4 3 0 1\n1 0 0 0 1.5\n", kTetgenOneTet),
            "bad.node:2: boundary marker '1.5' is not an integer");
  EXPECT_EQ(tetgen_error(kTetgenNodes + "5 1 1 1\n", kTetgenOneTet),
            "bad.node:6: unexpected data after the 4 points the header declares");
}

TEST(ReadTetgenErrors, EleAndFaceFiles) {
  EXPECT_EQ(tetgen_error(kTetgenNodes, ""),
            "bad.ele:1: empty file (expected the header '<#tetrahedra> <nodes per tetrahedron> "
            "<#attributes>')");
  EXPECT_EQ(tetgen_error(kTetgenNodes, "1 4 0 0\n"),
            "bad.ele:1: the header has 4 values (expected <#tetrahedra> <nodes per tetrahedron> "
            "<#attributes>)");
  EXPECT_EQ(tetgen_error(kTetgenNodes, "1 8 0\n"),
            "bad.ele:1: nodes per tetrahedron 8 is not 4 or 10");
  EXPECT_EQ(tetgen_error(kTetgenNodes, "2 4 0\n1 1 2 3 4\n"),
            "bad.ele:2: truncated: the file ends after 1 of the 2 tetrahedra its header declares");
  EXPECT_EQ(tetgen_error(kTetgenNodes, "1 4 0\n1 1 2 3\n"),
            "bad.ele:2: expected an index, 4 point indices and 0 attributes, found 4 values");
  EXPECT_EQ(tetgen_error(kTetgenNodes, "1 4 1\n1 1 2 3 4\n"),
            "bad.ele:2: expected an index, 4 point indices and 1 attribute, found 5 values");
  EXPECT_EQ(tetgen_error(kTetgenNodes, "1 4 0\n1 1 2 3 5\n"),
            "bad.ele:2: point 5 is out of range (bad.node numbers its points 1 to 4)");
  EXPECT_EQ(tetgen_error(kTetgenNodes, "1 4 0\n1 0 1 2 3\n"),
            "bad.ele:2: point 0 is out of range (bad.node numbers its points 1 to 4)");
  EXPECT_EQ(tetgen_error("0 3 0 0\n", "1 4 0\n1 1 2 3 4\n"),
            "bad.ele:2: point 1 is out of range (bad.node has no points)");
  EXPECT_EQ(tetgen_error(kTetgenNodes, "1 4 0\n1 1 2 2 3\n"),
            "bad.ele:2: the tetrahedron names point 2 twice");
  EXPECT_EQ(tetgen_error(kTetgenNodes, "1 4 0\n1 1 2 x 3\n"),
            "bad.ele:2: point index 'x' is not an integer");
  EXPECT_EQ(tetgen_error(kTetgenNodes, kTetgenOneTet + "2 1 2 3 4\n"),
            "bad.ele:3: unexpected data after the 1 tetrahedron the header declares");

  const std::string no_face;
  EXPECT_EQ(tetgen_error(kTetgenNodes, kTetgenOneTet, &no_face),
            "bad.face:1: empty file (expected the header '<#faces> <#boundary markers>')");
  const std::string bad_markers = "1 3\n";
  EXPECT_EQ(tetgen_error(kTetgenNodes, kTetgenOneTet, &bad_markers),
            "bad.face:1: boundary marker count 3 is not 0 or 1");
  const std::string short_face = "1 1\n1 1 2 3\n";
  EXPECT_EQ(tetgen_error(kTetgenNodes, kTetgenOneTet, &short_face),
            "bad.face:2: expected an index, 3 point indices and 1 boundary marker (then optionally "
            "2 adjacent "
            "tetrahedra), found 4 values");
  const std::string repeated = "1 0\n1 1 3 3\n";
  EXPECT_EQ(tetgen_error(kTetgenNodes, kTetgenOneTet, &repeated),
            "bad.face:2: the face names point 3 twice");
  const std::string outside = "1 0\n1 1 2 7\n";
  EXPECT_EQ(tetgen_error(kTetgenNodes, kTetgenOneTet, &outside),
            "bad.face:2: point 7 is out of range (bad.node numbers its points 1 to 4)");
}

// ---- Gmsh errors ----------------------------------------------------------------------

TEST(ReadGmshErrors, HeaderAndSections) {
  EXPECT_EQ(gmsh_error(""), "bad.msh:1: empty file");
  EXPECT_EQ(gmsh_error("\n  \n"), "bad.msh:2: empty file");
  EXPECT_EQ(gmsh_error("solid cube\n"),
            "bad.msh:1: not a Gmsh .msh file: expected $MeshFormat, found 'solid cube'");
  EXPECT_EQ(gmsh_error("$NOD\n1\n1 0 0 0\n$ENDNOD\n"),
            "bad.msh:1: unsupported .msh version 1 (the file starts with $NOD; only 2.2 and 4.1 "
            "are read)");
  EXPECT_EQ(gmsh_error("$MeshFormat\n"), "bad.msh:1: truncated: the file ends inside $MeshFormat");
  EXPECT_EQ(gmsh_error("$MeshFormat\n3.0 0 8\n$EndMeshFormat\n"),
            "bad.msh:2: unsupported .msh version 3.0 (only 2.2 and 4.1 are read)");
  EXPECT_EQ(gmsh_error("$MeshFormat\n4 0 8\n$EndMeshFormat\n"),
            "bad.msh:2: unsupported .msh version 4 (only 2.2 and 4.1 are read)");
  EXPECT_EQ(gmsh_error("$MeshFormat\n2.2 1 8\n\x01\x00\x00\x00\n$EndMeshFormat\n"),
            "bad.msh:2: binary .msh not supported (file type 1); save the mesh as ASCII");
  EXPECT_EQ(gmsh_error("$MeshFormat\n2.2 7 8\n$EndMeshFormat\n"),
            "bad.msh:2: file type 7 is not 0 (ASCII) or 1 (binary)");
  EXPECT_EQ(
      gmsh_error("$MeshFormat\n2.2 0\n$EndMeshFormat\n"),
      "bad.msh:2: expected '<version> <file type> <data size>' in $MeshFormat, found 2 values");
  EXPECT_EQ(gmsh_error("$MeshFormat\n2.2 0 8\n$Nodes\n"),
            "bad.msh:3: expected $EndMeshFormat after the format line, found '$Nodes'");
  EXPECT_EQ(gmsh_error(kGmsh22Header + "1 0 0 0\n"),
            "bad.msh:4: expected a section such as $Nodes or $Elements, found '1 0 0 0'");
  EXPECT_EQ(gmsh_error(kGmsh22Header + "$EndNodes\n"),
            "bad.msh:4: unexpected '$EndNodes' outside any section");
  EXPECT_EQ(gmsh_error(kGmsh22Header + "$PhysicalNames\n1\n2 1 \"top\"\n"),
            "bad.msh:6: truncated: the file ends inside $PhysicalNames (no $EndPhysicalNames)");
  EXPECT_EQ(gmsh_error(kGmsh22Header + kGmsh22Nodes + "$Elements\n1\n1 4 0 1 2 3 4\n"),
            "bad.msh:13: truncated: the file ends before $EndElements");
  EXPECT_EQ(
      gmsh_error(kGmsh22Header + kGmsh22Nodes + "$Elements\n1\n1 4 0 1 2 3 4\n2 4 0 1 2 3 4\n"),
      "bad.msh:14: expected $EndElements after 1 element, found '2 4 0 1 2 3 4'");
}

TEST(ReadGmshErrors, Version22NodesAndElements) {
  EXPECT_EQ(gmsh_error(kGmsh22Header + "$Nodes\n"),
            "bad.msh:4: truncated: the file ends inside $Nodes (expected the header '<number of "
            "nodes>')");
  EXPECT_EQ(gmsh_error(kGmsh22Header + "$Nodes\n120\n1 0 0 0\n2 1 0 0\n"),
            "bad.msh:7: truncated: the file ends inside $Nodes (expected 120 nodes, read 2)");
  EXPECT_EQ(
      gmsh_error(kGmsh22Header + "$Nodes\n1000000000000\n1 0 0 0\n$EndNodes\n"),
      "bad.msh:7: unexpected '$EndNodes' inside $Nodes (expected 1000000000000 nodes, read 1)");
  EXPECT_EQ(gmsh_error(kGmsh22Header + "$Nodes\n1 2\n"),
            "bad.msh:5: expected the $Nodes header '<number of nodes>', found 2 values");
  EXPECT_EQ(gmsh_error(kGmsh22Header + "$Nodes\nmany\n"),
            "bad.msh:5: header value 'many' is not an integer");
  EXPECT_EQ(gmsh_error(kGmsh22Header + "$Nodes\n1\n1 0 0\n$EndNodes\n"),
            "bad.msh:6: expected a node tag and 3 coordinates, found 3 values");
  EXPECT_EQ(gmsh_error(kGmsh22Header + "$Nodes\n1\n1 0 0 inf\n$EndNodes\n"),
            "bad.msh:6: z coordinate 'inf' is not finite");
  EXPECT_EQ(gmsh_error(kGmsh22Header + "$Nodes\n1\n0 0 0 0\n$EndNodes\n"),
            "bad.msh:6: node tag 0 is not positive");
  EXPECT_EQ(gmsh_error(kGmsh22Header + "$Nodes\n1\n-3 0 0 0\n$EndNodes\n"),
            "bad.msh:6: node tag -3 is negative");
  EXPECT_EQ(gmsh_error(kGmsh22Header + "$Nodes\n2\n7 0 0 0\n7 1 0 0\n$EndNodes\n"),
            "bad.msh:7: node tag 7 appears twice");

  const std::string elements =
      kGmsh22Header + kGmsh22Nodes + "$Elements\n";  // "$Elements" is line 11
  EXPECT_EQ(gmsh_error(elements + "2\n1 4 0 1 2 3 4\n"),
            "bad.msh:13: truncated: the file ends inside $Elements (expected 2 elements, read 1)");
  EXPECT_EQ(gmsh_error(elements + "1\n1 4\n"),
            "bad.msh:13: expected '<tag> <type> <number of tags> <tags...> <node tags...>', found "
            "2 values");
  EXPECT_EQ(gmsh_error(elements + "1\n1 4 2 0 1 2 3\n"),
            "bad.msh:13: element 1 (4-node tetrahedron) should have 4 node tags after its 2 tags, "
            "found 7 values in all");
  EXPECT_EQ(gmsh_error(elements + "1\n1 4 99 0 1 2 3\n"),
            "bad.msh:13: element 1 (4-node tetrahedron) should have 4 node tags after its 99 tags, "
            "found 7 values in all");
  EXPECT_EQ(gmsh_error(elements + "1\n5 4 0 1 2 3 9\n"),
            "bad.msh:13: element 5 names node tag 9, which is not in $Nodes");
  EXPECT_EQ(gmsh_error(elements + "1\n5 2 0 1 3 3\n"),
            "bad.msh:13: element 5 names node tag 3 twice");
  EXPECT_EQ(gmsh_error(elements + "1\n5 2 1 x 1 2 3\n"),
            "bad.msh:13: element tag value 'x' is not an integer");
  EXPECT_EQ(gmsh_error(elements + "1\n5 two 0 1 2 3\n"),
            "bad.msh:13: element type 'two' is not an integer");
  // Elements before nodes name tags that are not (yet) in $Nodes.
  EXPECT_EQ(gmsh_error(kGmsh22Header + "$Elements\n1\n1 2 0 1 2 3\n$EndElements\n" + kGmsh22Nodes),
            "bad.msh:6: element 1 names node tag 1, which is not in $Nodes");
}

TEST(ReadGmshErrors, Version41NodesAndElements) {
  EXPECT_EQ(gmsh_error(kGmsh41Header + "$Nodes\n1 3 1 3\n"),
            "bad.msh:5: truncated: the file ends inside $Nodes (expected 1 entity blocks, read 0)");
  EXPECT_EQ(gmsh_error(kGmsh41Header + "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n"),
            "bad.msh:11: truncated: the file ends inside $Nodes (expected 3 nodes, read 2)");
  EXPECT_EQ(gmsh_error(kGmsh41Header + "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n$EndNodes\n"),
            "bad.msh:9: unexpected '$EndNodes' inside $Nodes (expected 3 nodes, read 0)");
  EXPECT_EQ(gmsh_error(kGmsh41Header + "$Nodes\n1 3 1\n"),
            "bad.msh:5: expected the $Nodes header '<number of entity blocks> <number of nodes> "
            "<min tag> <max tag>', "
            "found 3 values");
  EXPECT_EQ(gmsh_error(kGmsh41Header + "$Nodes\n1 3 1 3\n2 1 0\n"),
            "bad.msh:6: expected an entity block header '<entity dimension> <entity tag> "
            "<parametric> <number of "
            "nodes>', found 3 values");
  EXPECT_EQ(gmsh_error(kGmsh41Header + "$Nodes\n1 3 1 3\n4 1 0 3\n"),
            "bad.msh:6: entity dimension 4 is not 0, 1, 2 or 3");
  EXPECT_EQ(gmsh_error(kGmsh41Header + "$Nodes\n1 3 1 3\n2 1 2 3\n"),
            "bad.msh:6: parametric flag 2 is not 0 or 1");
  EXPECT_EQ(gmsh_error(kGmsh41Header + "$Nodes\n1 3 1 3\n2 1 0 1000000000000\n"),
            "bad.msh:6: the entity block holds 1000000000000 nodes, more than the 3 left of the 3 "
            "the $Nodes header "
            "declares");
  EXPECT_EQ(gmsh_error(kGmsh41Header + "$Nodes\n1 3 1 3\n2 1 0 2\n1\n2\n0 0 0\n1 0 0\n$EndNodes\n"),
            "bad.msh:10: the $Nodes header declares 3 nodes but its blocks hold 2");
  EXPECT_EQ(gmsh_error(kGmsh41Header + "$Nodes\n1 2 1 2\n2 1 0 2\n1 2\n"),
            "bad.msh:7: expected one node tag, found 2 values");
  EXPECT_EQ(gmsh_error(kGmsh41Header + "$Nodes\n1 1 1 1\n2 1 1 1\n1\n0 0 0 0.5\n$EndNodes\n"),
            "bad.msh:8: expected 5 coordinates (x y z and 2 parametric), found 4");
  EXPECT_EQ(gmsh_error(kGmsh41Header + "$Nodes\n1 1 1 1\n2 1 0 1\n1\n0 0 0 0.5\n$EndNodes\n"),
            "bad.msh:8: expected 3 coordinates (x y z), found 4");
  EXPECT_EQ(gmsh_error(kGmsh41Header + "$Nodes\n1 2 1 2\n2 1 0 2\n5\n5\n0 0 0\n1 0 0\n$EndNodes\n"),
            "bad.msh:10: node tag 5 appears twice");

  const std::string nodes =
      kGmsh41Header +
      "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n$Elements\n";
  // "$Elements" is line 16, its header line 17.
  EXPECT_EQ(
      gmsh_error(nodes + "1 1 1 1\n3 1 4 1\n1 1 2 3\n$EndElements\n"),
      "bad.msh:19: expected an element tag and 4 node tags (4-node tetrahedron), found 4 values");
  EXPECT_EQ(gmsh_error(nodes + "1 1 1 1\n3 1 4 1\n1 1 2 3 8\n$EndElements\n"),
            "bad.msh:19: element 1 names node tag 8, which is not in $Nodes");
  EXPECT_EQ(gmsh_error(nodes + "1 1 1 1\n3 1 4 1\n1 1 2 1 3\n$EndElements\n"),
            "bad.msh:19: element 1 names node tag 1 twice");
  EXPECT_EQ(gmsh_error(nodes + "1 1 1 1\n3 1 4 5\n"),
            "bad.msh:18: the entity block holds 5 elements, more than the 1 left of the 1 the "
            "$Elements header declares");
  EXPECT_EQ(gmsh_error(nodes + "1 3 1 3\n3 1 4 1\n1 1 2 3 4\n$EndElements\n"),
            "bad.msh:19: the $Elements header declares 3 elements but its blocks hold 1");
  EXPECT_EQ(gmsh_error(nodes + "1 2 1 2\n3 1 4 2\n1 1 2 3 4\n"),
            "bad.msh:19: truncated: the file ends inside $Elements (expected 2 elements, read 1)");
  EXPECT_EQ(
      gmsh_error(nodes + "2 1 1 1\n3 1 4 1\n1 1 2 3 4\n"),
      "bad.msh:19: truncated: the file ends inside $Elements (expected 2 entity blocks, read 1)");
  EXPECT_EQ(gmsh_error(nodes + "1 1 1 1\n3 1 4 1 0\n"),
            "bad.msh:18: expected an entity block header '<entity dimension> <entity tag> <element "
            "type> <number of "
            "elements>', found 5 values");
}

// ---- robustness -----------------------------------------------------------------------

/// What every mesh a reader returns must satisfy, whatever the input.
void expect_well_formed(const Mesh& mesh) {
  ASSERT_EQ(mesh.triangles.size() % 3, 0u);
  ASSERT_EQ(mesh.tetrahedra.size() % 4, 0u);
  for (const Vector3r& p : mesh.positions)
    ASSERT_TRUE(std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z()));
  for (VertexIndex v : mesh.triangles) ASSERT_LT(v, mesh.positions.size());
  for (VertexIndex v : mesh.tetrahedra) ASSERT_LT(v, mesh.positions.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3) {
    const VertexIndex* v = &mesh.triangles[t];
    ASSERT_TRUE(v[0] != v[1] && v[0] != v[2] && v[1] != v[2]);
  }
  for (std::size_t t = 0; t < mesh.tetrahedra.size(); t += 4) {
    std::array<VertexIndex, 4> v{};
    std::copy_n(&mesh.tetrahedra[t], 4, v.begin());
    std::sort(v.begin(), v.end());
    ASSERT_TRUE(std::adjacent_find(v.begin(), v.end()) == v.end());
  }
}

enum class Format { obj, gmsh };

/// Runs one reader on `text`: a mesh or InvalidInput with a "name:line: " prefix, nothing else.
void expect_mesh_or_invalid_input(Format format, const std::string& text) {
  std::istringstream in(text);
  const std::string name = format == Format::obj ? "fuzz.obj" : "fuzz.msh";
  try {
    expect_well_formed(format == Format::obj ? read_obj(in, name) : read_gmsh(in, name));
  } catch (const InvalidInput& error) {
    const std::string message = error.what();
    ASSERT_EQ(message.rfind(name + ":", 0), 0u) << message;
    ASSERT_TRUE(std::isdigit(static_cast<unsigned char>(message[name.size() + 1]))) << message;
  }
}

void expect_tetgen_mesh_or_invalid_input(const std::string& node, const std::string& ele,
                                         const std::string& face) {
  std::istringstream node_in(node), ele_in(ele), face_in(face);
  try {
    expect_well_formed(read_tetgen(node_in, ele_in, face_in, "fuzz.node", "fuzz.ele", "fuzz.face"));
  } catch (const InvalidInput& error) {
    const std::string message = error.what();
    ASSERT_TRUE(message.rfind("fuzz.node:", 0) == 0 || message.rfind("fuzz.ele:", 0) == 0 ||
                message.rfind("fuzz.face:", 0) == 0)
        << message;
  }
}

TEST(ReadMeshRobustness, EveryPrefixOfEveryValidFile) {
  for (const char* file : {"square.obj", "pieces.obj"}) {
    const std::string text = read_text(kDataDir / file);
    for (std::size_t cut = 0; cut <= text.size(); ++cut)
      expect_mesh_or_invalid_input(Format::obj, text.substr(0, cut));
  }
  for (const char* file : {"cube_v22.msh", "cube_v41.msh"}) {
    const std::string text = read_text(kDataDir / file);
    std::size_t parsed = 0;
    for (std::size_t cut = 0; cut <= text.size(); ++cut) {
      std::istringstream in(text.substr(0, cut));
      try {
        read_gmsh(in, "cut.msh");
        ++parsed;
      } catch (const InvalidInput&) {
      }
    }
    // Only cuts at the section boundaries (before or after a blank line) parse.
    EXPECT_LE(parsed, 20u) << file;
  }
  for (const char* base : {"cube", "cube0"}) {
    const std::string node = read_text(kDataDir / (std::string(base) + ".node"));
    const std::string ele = read_text(kDataDir / (std::string(base) + ".ele"));
    const std::string face = read_text(kDataDir / "cube.face");
    for (std::size_t cut = 0; cut <= node.size(); ++cut)
      expect_tetgen_mesh_or_invalid_input(node.substr(0, cut), ele, face);
    for (std::size_t cut = 0; cut <= ele.size(); ++cut)
      expect_tetgen_mesh_or_invalid_input(node, ele.substr(0, cut), face);
    for (std::size_t cut = 0; cut <= face.size(); ++cut)
      expect_tetgen_mesh_or_invalid_input(node, ele, face.substr(0, cut));
  }
}

TEST(ReadMeshRobustness, TruncatedGmshNamesTheSectionItEndsIn) {
  const std::string text = read_text(kDataDir / "cube_v22.msh");
  const std::size_t inside_nodes = text.find("99 1 0 1");
  std::istringstream in(text.substr(0, inside_nodes));
  try {
    read_gmsh(in, "cut.msh");
    FAIL() << "a file cut inside $Nodes parsed";
  } catch (const InvalidInput& error) {
    EXPECT_STREQ(error.what(),
                 "cut.msh:16: truncated: the file ends inside $Nodes (expected 12 nodes, read 5)");
  }
}

TEST(ReadMeshRobustness, RandomBytes) {
  std::mt19937 random(20240611u);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<std::size_t> length(0, 400);
  for (int round = 0; round < 3000; ++round) {
    std::string bytes(length(random), '\0');
    for (char& b : bytes) b = static_cast<char>(byte(random));
    expect_mesh_or_invalid_input(Format::obj, bytes);
    expect_mesh_or_invalid_input(Format::gmsh, bytes);
    expect_tetgen_mesh_or_invalid_input(bytes, bytes, bytes);
    expect_mesh_or_invalid_input(Format::gmsh, kGmsh22Header + bytes);
    expect_mesh_or_invalid_input(Format::gmsh, kGmsh41Header + bytes);
  }
}

/// Random words drawn from each format's own vocabulary, so the fuzzing gets past the
/// first line and into the section and record parsers.
TEST(ReadMeshRobustness, RandomWordsFromTheFormatsVocabulary) {
  const std::vector<std::string> words = {"v",
                                          "f",
                                          "vt",
                                          "#",
                                          "\\",
                                          "/",
                                          "//",
                                          "1/2/3",
                                          "-1",
                                          "-2",
                                          "0",
                                          "1",
                                          "2",
                                          "3",
                                          "4",
                                          "5",
                                          "10",
                                          "1e9",
                                          "nan",
                                          "0.5",
                                          "-0.0",
                                          "$Nodes",
                                          "$EndNodes",
                                          "$Elements",
                                          "$EndElements",
                                          "$MeshFormat",
                                          "$EndMeshFormat",
                                          "2.2",
                                          "4.1",
                                          "$Entities",
                                          "$EndEntities",
                                          "18446744073709551615",
                                          "9223372036854775808",
                                          "-9223372036854775808",
                                          "\n",
                                          "\n",
                                          "\n",
                                          "\r\n",
                                          " ",
                                          "\t"};
  std::mt19937 random(7u);
  std::uniform_int_distribution<std::size_t> pick(0, words.size() - 1);
  std::uniform_int_distribution<int> length(0, 120);
  for (int round = 0; round < 4000; ++round) {
    std::string text;
    for (int w = length(random); w > 0; --w) text += words[pick(random)] + " ";
    expect_mesh_or_invalid_input(Format::obj, text);
    expect_mesh_or_invalid_input(Format::gmsh, kGmsh22Header + text);
    expect_mesh_or_invalid_input(Format::gmsh, kGmsh41Header + text);
    expect_tetgen_mesh_or_invalid_input(text, text, text);
    expect_tetgen_mesh_or_invalid_input(kTetgenNodes, text, text);
  }
}

TEST(ReadMeshRobustness, RandomEditsOfValidFiles) {
  const std::string obj = read_text(kDataDir / "pieces.obj");
  const std::string v22 = read_text(kDataDir / "cube_v22.msh");
  const std::string v41 = read_text(kDataDir / "cube_v41.msh");
  const std::string node = read_text(kDataDir / "cube.node");
  const std::string ele = read_text(kDataDir / "cube.ele");
  const std::string face = read_text(kDataDir / "cube.face");
  const std::string replacements = "0123456789 \n-+.e$/#x";
  std::mt19937 random(99u);
  auto edit = [&](std::string text) {
    std::uniform_int_distribution<int> edit_count(1, 4);
    for (int e = edit_count(random); e > 0 && !text.empty(); --e) {
      const std::size_t at = std::uniform_int_distribution<std::size_t>(0, text.size() - 1)(random);
      const char replacement = replacements[std::uniform_int_distribution<std::size_t>(
          0, replacements.size() - 1)(random)];
      switch (std::uniform_int_distribution<int>(0, 2)(random)) {
        case 0:
          text[at] = replacement;
          break;
        case 1:
          text.insert(text.begin() + static_cast<std::ptrdiff_t>(at), replacement);
          break;
        default:
          text.erase(at, 1);
          break;
      }
    }
    return text;
  };
  for (int round = 0; round < 2000; ++round) {
    expect_mesh_or_invalid_input(Format::obj, edit(obj));
    expect_mesh_or_invalid_input(Format::gmsh, edit(v22));
    expect_mesh_or_invalid_input(Format::gmsh, edit(v41));
    expect_tetgen_mesh_or_invalid_input(edit(node), ele, face);
    expect_tetgen_mesh_or_invalid_input(node, edit(ele), face);
    expect_tetgen_mesh_or_invalid_input(node, ele, edit(face));
  }
}

}  // namespace mesh_readers_tests
}  // namespace tessera::io
