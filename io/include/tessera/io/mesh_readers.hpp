// Mesh readers: load the rest positions and the triangles and tetrahedra of a mesh from
// the file formats simulators are usually fed with (Wavefront OBJ, TetGen .node/.ele/.face,
// Gmsh .msh ASCII 2.2 and 4.1), into the flat index arrays the rest of Tessera takes.
//
// The readers are meant for input an embedder does not control: every malformed, truncated
// or hostile file ends in a tessera::InvalidInput naming the file and the line, never in a
// crash, a hang or an allocation the file's size does not justify. They never print.
//
// Error messages. Every problem found in the content of a file throws tessera::InvalidInput
// whose message starts with "<name>:<line>: " (the name is the path as given, or the name
// passed to a stream overload; lines count from 1) and then says what is wrong, e.g.
//   "cube.obj:7: face index 12 is out of range (the file has 8 vertices so far)"
//   "cube.msh:41: truncated: the file ends inside $Nodes (expected 120 nodes, read 37)"
// A file that cannot be opened at all gives "<name>: cannot open ..." (there is no line).
#pragma once

#include <filesystem>
#include <istream>
#include <string>
#include <vector>

#include <tessera/core/real.hpp>
#include <tessera/io/generators.hpp>  // VertexIndex

namespace tessera::io {

/// A mesh as read from a file: positions, and the elements it holds (3 indices per triangle,
/// 4 per tetrahedron, 0-based into positions). Either element list may be empty: a file
/// with no elements of a kind is not an error, the caller decides what it needs. Positions
/// are every vertex of the file in file order, including vertices no element uses (the
/// mid-edge nodes of second-order elements, nodes of skipped element types).
struct Mesh {
  std::vector<Vector3r> positions;
  std::vector<VertexIndex> triangles;
  std::vector<VertexIndex> tetrahedra;

  std::size_t vertex_count() const { return positions.size(); }
  std::size_t triangle_count() const { return triangles.size() / 3; }
  std::size_t tetrahedron_count() const { return tetrahedra.size() / 4; }
};

/// Wavefront OBJ. Reads `v x y z [w]` vertices (w ignored; the common `v x y z r g b`
/// vertex-colour extension is accepted and the colour ignored) and `f` faces whose vertices
/// are written `i`, `i/t`, `i//n` or `i/t/n`; indices are 1-based, negative indices count
/// back from the last vertex read so far. Faces with more than 3 vertices are
/// fan-triangulated (v0 v1 v2, v0 v2 v3, ...). Texture and normal indices are checked to be
/// integers and otherwise ignored. Every other statement (vt, vn, vp, o, g, s, usemtl,
/// mtllib, l, p, curves, surfaces, anything unknown) is ignored, as are `#` comments, blank
/// lines, `\r` line ends and a UTF-8 byte order mark; a line ending in `\` continues on the
/// next. A face may only name vertices defined above it.
Mesh read_obj(const std::filesystem::path& file);
Mesh read_obj(std::istream& in, const std::string& name);

/// TetGen. `file` is `foo.node`, `foo.ele`, `foo.face` or the base `foo`; reads `foo.node`
/// (points) and `foo.ele` (tetrahedra, both required) and, when it exists, `foo.face`
/// (triangles). Point numbering starts at the first point's index (0 or 1) and must then
/// be consecutive; .ele and .face use the same numbering. 10-node (second-order)
/// tetrahedra contribute their 4 corners. Attributes, boundary markers and the adjacent-
/// tetrahedron columns of a `-nn` .face file are checked to be numbers and ignored. `#`
/// starts a comment anywhere on a line.
Mesh read_tetgen(const std::filesystem::path& file);
Mesh read_tetgen(std::istream& node, std::istream& ele, const std::string& node_name,
                 const std::string& ele_name);
/// The same with a .face stream for the triangles.
Mesh read_tetgen(std::istream& node, std::istream& ele, std::istream& face,
                 const std::string& node_name, const std::string& ele_name,
                 const std::string& face_name);

/// Gmsh .msh, ASCII, versions 2.2 (also 2.0 and 2.1, which share its layout) and 4.1.
/// Reads $Nodes and $Elements and skips every other section ($PhysicalNames, $Entities,
/// $Periodic, $NodeData, ...). Node tags are arbitrary distinct positive integers; vertices
/// are numbered 0, 1, 2... in the order the nodes appear. Element types read: 2 (3-node
/// triangle), 4 (4-node tetrahedron), and the corners of 9 (6-node triangle) and 11
/// (10-node tetrahedron). Every other type (points, lines, quadrangles, hexahedra, prisms,
/// pyramids, other high-order types) is skipped. Binary files, version 4.0 and older
/// formats throw InvalidInput. Each record (a node, a node tag, an element) is expected on
/// its own line, as Gmsh writes them.
Mesh read_gmsh(const std::filesystem::path& file);
Mesh read_gmsh(std::istream& in, const std::string& name);

/// Picks the reader by extension, ignoring case: .obj → read_obj; .node, .ele, .face →
/// read_tetgen; .msh → read_gmsh. Any other extension throws InvalidInput.
Mesh read_mesh(const std::filesystem::path& file);

}  // namespace tessera::io
