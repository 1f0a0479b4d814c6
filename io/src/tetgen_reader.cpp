// TetGen .node/.ele/.face (read_tetgen, see mesh_readers.hpp): the points of the .node file
// fix the numbering (first index 0 or 1, then consecutive) that the tetrahedra of the .ele
// file and the triangles of an optional .face file refer to.
#include <tessera/io/mesh_readers.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <fstream>
#include <initializer_list>
#include <string_view>
#include <system_error>
#include <vector>

#include "line_reader.hpp"

namespace tessera::io {
using namespace detail;

namespace {

/// Moves to the next line holding data (skipping blank lines and `#` comments) and splits
/// it into `words`; false at the end of the input.
bool next_tetgen_record(LineReader& reader, std::vector<std::string_view>& words) {
  while (reader.next_line()) {
    split_words(without_comment(reader.line()), words);
    if (!words.empty()) return true;
  }
  return false;
}

/// Reads the first data line of a TetGen file, its header, into `words`: at least one and at
/// most `max_values` values laid out as `layout` (for the messages). Returns where it is.
Location read_tetgen_header(LineReader& reader, std::vector<std::string_view>& words,
                            std::size_t max_values, std::string_view layout) {
  if (!next_tetgen_record(reader, words)) {
    reader.fail("empty file (expected the header '" + std::string(layout) + "')");
  }
  if (words.size() > max_values) {
    reader.fail("the header has " + std::to_string(words.size()) + " values (expected " +
                std::string(layout) + ")");
  }
  return reader.here();
}

/// A per-line count from a header (attributes, markers): a line could never hold more.
std::uint64_t parse_column_count(std::string_view word, std::string_view what,
                                 const Location& where) {
  const std::uint64_t count = parse_unsigned(word, what, where);
  if (count > kMaxLineLength)
    where.fail(std::string(what) + " " + std::to_string(count) + " is too large");
  return count;
}

std::uint64_t parse_marker_count(std::string_view word, const Location& where) {
  const std::uint64_t count = parse_unsigned(word, "boundary marker count", where);
  if (count > 1) where.fail("boundary marker count " + std::to_string(count) + " is not 0 or 1");
  return count;
}

/// How the .node file numbers its points, which .ele and .face refer to.
struct TetgenNumbering {
  std::uint64_t first_index = 0;
  std::uint64_t point_count = 0;
  const std::string* node_name = nullptr;
};

TetgenNumbering read_tetgen_points(LineReader& reader, const std::string& node_name, Mesh& mesh) {
  std::vector<std::string_view> words;
  const Location header = read_tetgen_header(
      reader, words, 4, "<#points> <dimension> <#attributes> <#boundary markers>");
  const std::uint64_t point_count = parse_unsigned(words[0], "point count", header);
  const std::uint64_t dimension =
      words.size() > 1 ? parse_unsigned(words[1], "dimension", header) : 3;
  if (dimension != 3)
    header.fail("dimension " + std::to_string(dimension) + " is not supported (only 3)");
  const std::uint64_t attribute_count =
      words.size() > 2 ? parse_column_count(words[2], "attribute count", header) : 0;
  const std::uint64_t marker_count = words.size() > 3 ? parse_marker_count(words[3], header) : 0;
  const std::uint64_t values_per_point = 4 + attribute_count + marker_count;

  reserve_at_most(mesh.positions, point_count);
  TetgenNumbering numbering{0, point_count, &node_name};
  for (std::uint64_t point = 0; point < point_count; ++point) {
    if (!next_tetgen_record(reader, words)) {
      reader.fail("truncated: the file ends after " + std::to_string(point) + " of the " +
                  counted(point_count, "point", "points") + " its header declares");
    }
    const Location where = reader.here();
    if (words.size() < 4) {
      where.fail("expected a point index and 3 coordinates, found " +
                 counted(words.size(), "value", "values"));
    }
    if (words.size() != values_per_point) {
      where.fail("expected " + std::to_string(values_per_point) + " values (index, x y z, " +
                 counted(attribute_count, "attribute", "attributes") + ", " +
                 counted(marker_count, "boundary marker", "boundary markers") + "), found " +
                 std::to_string(words.size()));
    }
    const std::uint64_t index = parse_unsigned(words[0], "point index", where);
    if (point == 0) {
      if (index > 1)
        where.fail("the first point index is " + std::to_string(index) + " (expected 0 or 1)");
      numbering.first_index = index;
    } else if (index != numbering.first_index + point) {
      where.fail("point index " + std::to_string(index) + " is out of sequence (expected " +
                 std::to_string(numbering.first_index + point) + ")");
    }
    const Vector3r position = parse_position(words, 1, where);
    for (std::uint64_t a = 0; a < attribute_count; ++a)
      parse_number(words[4 + a], "attribute", where);
    if (marker_count == 1) parse_signed(words.back(), "boundary marker", where);
    add_position(mesh, position, where);
  }
  if (next_tetgen_record(reader, words)) {
    reader.fail("unexpected data after the " + counted(point_count, "point", "points") +
                " the header declares");
  }
  return numbering;
}

/// The 0-based vertex a corner of a .ele or .face line names.
VertexIndex parse_tetgen_corner(std::string_view word, const TetgenNumbering& numbering,
                                const Location& where) {
  const std::int64_t number = parse_signed(word, "point index", where);
  const auto first = static_cast<std::int64_t>(numbering.first_index);
  const auto count = static_cast<std::int64_t>(numbering.point_count);
  if (number < first || number - first >= count) {
    where.fail("point " + std::to_string(number) + " is out of range (" + *numbering.node_name +
               (count == 0 ? " has no points)"
                           : " numbers its points " + std::to_string(first) + " to " +
                                 std::to_string(first + count - 1) + ")"));
  }
  return static_cast<VertexIndex>(number - first);
}

/// Reads the element lines shared by .ele and .face: `index corner... [extra values]`,
/// keeping the first `kept_corners` corners of each. `extra_counts` are the accepted
/// numbers of values after the corners.
void read_tetgen_elements(LineReader& reader, const TetgenNumbering& numbering,
                          std::uint64_t element_count, std::size_t corner_count,
                          std::size_t kept_corners,
                          std::initializer_list<std::uint64_t> extra_counts,
                          std::string_view extras_description, std::string_view element_name,
                          std::string_view element_plural, std::vector<VertexIndex>& elements) {
  std::vector<std::string_view> words;
  std::array<VertexIndex, 10> corners{};
  for (std::uint64_t element = 0; element < element_count; ++element) {
    if (!next_tetgen_record(reader, words)) {
      reader.fail("truncated: the file ends after " + std::to_string(element) + " of the " +
                  counted(element_count, element_name, element_plural) + " its header declares");
    }
    const Location where = reader.here();
    const std::uint64_t extra =
        words.size() - 1 - std::min<std::size_t>(words.size() - 1, corner_count);
    if (words.size() < 1 + corner_count ||
        std::find(extra_counts.begin(), extra_counts.end(), extra) == extra_counts.end()) {
      where.fail("expected an index, " + std::to_string(corner_count) + " point indices and " +
                 std::string(extras_description) + ", found " +
                 counted(words.size(), "value", "values"));
    }
    parse_signed(words[0], std::string(element_name) + " index", where);
    for (std::size_t k = 0; k < corner_count; ++k)
      corners[k] = parse_tetgen_corner(words[1 + k], numbering, where);
    const std::size_t repeated = first_repeated(corners.data(), corner_count);
    if (repeated != corner_count) {
      where.fail("the " + std::string(element_name) + " names point " +
                 std::to_string(std::uint64_t(corners[repeated]) + numbering.first_index) +
                 " twice");
    }
    for (std::size_t v = 1 + corner_count; v < words.size(); ++v)
      parse_number(words[v], "value", where);
    elements.insert(elements.end(), corners.begin(),
                    corners.begin() + static_cast<std::ptrdiff_t>(kept_corners));
  }
  if (next_tetgen_record(reader, words)) {
    reader.fail("unexpected data after the " +
                counted(element_count, element_name, element_plural) + " the header declares");
  }
}

void read_tetgen_tetrahedra(LineReader& reader, const TetgenNumbering& numbering, Mesh& mesh) {
  std::vector<std::string_view> words;
  const Location header = read_tetgen_header(
      reader, words, 3, "<#tetrahedra> <nodes per tetrahedron> <#attributes>");
  const std::uint64_t count = parse_unsigned(words[0], "tetrahedron count", header);
  const std::uint64_t nodes_per_tetrahedron =
      words.size() > 1 ? parse_unsigned(words[1], "nodes per tetrahedron", header) : 4;
  if (nodes_per_tetrahedron != 4 && nodes_per_tetrahedron != 10) {
    header.fail("nodes per tetrahedron " + std::to_string(nodes_per_tetrahedron) +
                " is not 4 or 10");
  }
  const std::uint64_t attribute_count =
      words.size() > 2 ? parse_column_count(words[2], "attribute count", header) : 0;
  mesh.tetrahedra.reserve(4 * static_cast<std::size_t>(std::min(count, kReserveLimit)));
  read_tetgen_elements(reader, numbering, count, static_cast<std::size_t>(nodes_per_tetrahedron), 4,
                       {attribute_count}, counted(attribute_count, "attribute", "attributes"),
                       "tetrahedron", "tetrahedra", mesh.tetrahedra);
}

void read_tetgen_triangles(LineReader& reader, const TetgenNumbering& numbering, Mesh& mesh) {
  std::vector<std::string_view> words;
  const Location header = read_tetgen_header(reader, words, 2, "<#faces> <#boundary markers>");
  const std::uint64_t count = parse_unsigned(words[0], "face count", header);
  const std::uint64_t marker_count = words.size() > 1 ? parse_marker_count(words[1], header) : 0;
  mesh.triangles.reserve(3 * static_cast<std::size_t>(std::min(count, kReserveLimit)));
  // After the corners: the marker, then (with tetgen -nn) the two adjacent tetrahedra.
  read_tetgen_elements(reader, numbering, count, 3, 3, {marker_count, marker_count + 2},
                       counted(marker_count, "boundary marker", "boundary markers") +
                           " (then optionally 2 adjacent tetrahedra)",
                       "face", "faces", mesh.triangles);
}

Mesh read_tetgen_streams(std::istream& node, std::istream& ele, std::istream* face,
                         const std::string& node_name, const std::string& ele_name,
                         const std::string& face_name) {
  Mesh mesh;
  LineReader node_reader(node, node_name);
  const TetgenNumbering numbering = read_tetgen_points(node_reader, node_name, mesh);
  LineReader ele_reader(ele, ele_name);
  read_tetgen_tetrahedra(ele_reader, numbering, mesh);
  if (face != nullptr) {
    LineReader face_reader(*face, face_name);
    read_tetgen_triangles(face_reader, numbering, mesh);
  }
  return mesh;
}

}  // namespace

Mesh read_tetgen(std::istream& node, std::istream& ele, const std::string& node_name,
                 const std::string& ele_name) {
  return read_tetgen_streams(node, ele, nullptr, node_name, ele_name, std::string());
}

Mesh read_tetgen(std::istream& node, std::istream& ele, std::istream& face,
                 const std::string& node_name, const std::string& ele_name,
                 const std::string& face_name) {
  return read_tetgen_streams(node, ele, &face, node_name, ele_name, face_name);
}

Mesh read_tetgen(const std::filesystem::path& file) {
  std::filesystem::path base = file;
  const std::string extension = lowercase_extension(file);
  if (extension == ".node" || extension == ".ele" || extension == ".face") base.replace_extension();
  std::filesystem::path node_path = base, ele_path = base, face_path = base;
  node_path += ".node";
  ele_path += ".ele";
  face_path += ".face";
  std::ifstream node_stream = open_for_reading(node_path);
  std::ifstream ele_stream = open_for_reading(ele_path);
  std::error_code error;
  if (std::filesystem::is_regular_file(face_path, error)) {
    std::ifstream face_stream = open_for_reading(face_path);
    return read_tetgen_streams(node_stream, ele_stream, &face_stream, node_path.string(),
                               ele_path.string(), face_path.string());
  }
  return read_tetgen_streams(node_stream, ele_stream, nullptr, node_path.string(),
                             ele_path.string(), std::string());
}

}  // namespace tessera::io
