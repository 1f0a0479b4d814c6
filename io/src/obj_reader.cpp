// Wavefront OBJ (read_obj, see mesh_readers.hpp): `v` vertices and `f` faces, fan-
// triangulated; every other statement is ignored. A statement may continue over lines ending
// in `\`, and is then reported at its first line.
#include <tessera/io/mesh_readers.hpp>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <string_view>
#include <vector>

#include "line_reader.hpp"

namespace tessera::io {
using namespace detail;

namespace {

/// The vertex one corner of an `f` statement names: the part of `i`, `i/t`, `i//n` or
/// `i/t/n` before the first slash, resolved against the vertices read so far.
VertexIndex parse_obj_face_corner(std::string_view word, std::size_t vertex_count,
                                  const Location& where) {
  const std::size_t first_slash = word.find('/');
  const std::string_view vertex_part = word.substr(0, first_slash);
  if (first_slash != std::string_view::npos) {
    const std::string_view after_vertex = word.substr(first_slash + 1);
    const std::size_t second_slash = after_vertex.find('/');
    const std::string_view texture_part = after_vertex.substr(0, second_slash);
    if (!texture_part.empty()) parse_signed(texture_part, "texture index", where);
    if (second_slash != std::string_view::npos) {
      const std::string_view normal_part = after_vertex.substr(second_slash + 1);
      if (normal_part.find('/') != std::string_view::npos || normal_part.empty()) {
        where.fail("face corner " + shown(word) + " is not of the form i, i/t, i//n or i/t/n");
      }
      parse_signed(normal_part, "normal index", where);
    }
  }
  if (vertex_part.empty()) where.fail("face corner " + shown(word) + " has no vertex index");
  const std::int64_t index = parse_signed(vertex_part, "face index", where);
  const auto count = static_cast<std::int64_t>(vertex_count);
  if (index > 0 && index <= count) return static_cast<VertexIndex>(index - 1);
  if (index < 0 && index >= -count) return static_cast<VertexIndex>(count + index);
  if (index == 0)
    where.fail("face index 0 is invalid (OBJ indices start at 1; negative ones count back)");
  where.fail("face index " + std::to_string(index) + " is out of range (the file has " +
             counted(vertex_count, "vertex", "vertices") + " so far)");
}

void read_obj_vertex(const std::vector<std::string_view>& words, Mesh& mesh,
                     const Location& where) {
  const std::size_t value_count = words.size() - 1;
  if (value_count < 3) {
    where.fail("expected 3 coordinates after 'v', found " + std::to_string(value_count));
  }
  if (value_count != 3 && value_count != 4 && value_count != 6) {
    where.fail("expected x y z [w] or x y z r g b after 'v', found " + std::to_string(value_count) +
               " values");
  }
  const Vector3r position = parse_position(words, 1, where);
  for (std::size_t i = 4; i < words.size(); ++i) parse_number(words[i], "vertex value", where);
  add_position(mesh, position, where);
}

void read_obj_face(const std::vector<std::string_view>& words, Mesh& mesh,
                   std::vector<VertexIndex>& polygon, std::vector<VertexIndex>& sorted_polygon,
                   const Location& where) {
  polygon.clear();
  for (std::size_t i = 1; i < words.size(); ++i) {
    polygon.push_back(parse_obj_face_corner(words[i], mesh.positions.size(), where));
  }
  if (polygon.size() < 3) {
    where.fail("a face needs at least 3 vertices, found " + std::to_string(polygon.size()));
  }
  sorted_polygon = polygon;
  std::sort(sorted_polygon.begin(), sorted_polygon.end());
  const auto repeated = std::adjacent_find(sorted_polygon.begin(), sorted_polygon.end());
  if (repeated != sorted_polygon.end()) {
    where.fail("the face names vertex " + std::to_string(std::uint64_t(*repeated) + 1) + " twice");
  }
  for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
    mesh.triangles.insert(mesh.triangles.end(), {polygon[0], polygon[k], polygon[k + 1]});
  }
}

bool ends_with_backslash(std::string_view text) {
  text = trim(text);
  return !text.empty() && text.back() == '\\';
}

}  // namespace

Mesh read_obj(std::istream& in, const std::string& name) {
  LineReader reader(in, name);
  Mesh mesh;
  std::string statement;
  std::vector<std::string_view> words;
  std::vector<VertexIndex> polygon;
  std::vector<VertexIndex> sorted_polygon;
  bool found_statement = false;
  while (reader.next_line()) {
    const Location where = reader.here();  // a continued statement is reported at its first line
    statement.assign(without_comment(reader.line()));
    while (ends_with_backslash(statement)) {
      statement.erase(statement.find_last_of('\\'));
      statement.push_back(' ');
      if (!reader.next_line()) break;
      statement.append(without_comment(reader.line()));
      if (statement.size() > kMaxLineLength) {
        where.fail("the statement continued with '\\' is longer than " +
                   std::to_string(kMaxLineLength) + " bytes");
      }
    }
    split_words(statement, words);
    if (words.empty()) continue;
    found_statement = true;
    if (words[0] == "v") {
      read_obj_vertex(words, mesh, where);
    } else if (words[0] == "f" || words[0] == "fo") {
      read_obj_face(words, mesh, polygon, sorted_polygon, where);
    }
    // Everything else (vt, vn, o, g, s, usemtl, mtllib, l, p, unknown statements) is ignored.
  }
  if (!found_statement) reader.fail("empty file (no statements, only blank lines or comments)");
  return mesh;
}

Mesh read_obj(const std::filesystem::path& file) {
  std::ifstream stream = open_for_reading(file);
  return read_obj(stream, file.string());
}

}  // namespace tessera::io
