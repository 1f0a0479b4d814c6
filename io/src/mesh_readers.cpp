// Mesh readers for Wavefront OBJ, TetGen .node/.ele/.face and Gmsh .msh (ASCII 2.2, 4.1).
//
// All three formats are line-oriented text, so they share one LineReader (bounded line
// length, control bytes rejected, a line number for every message) and one set of number
// parsers (std::from_chars: locale-independent, no silent prefixes, finite values only).
// Counts declared in headers are never trusted for allocation: vectors reserve at most
// kReserveLimit entries and grow as records are actually read, and every loop consumes a
// line per step, so a lying header costs no more than the file's own size.
#include <tessera/io/mesh_readers.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string_view>
#include <system_error>
#include <unordered_map>

#include <tessera/core/error.hpp>

namespace tessera::io {
namespace {

/// Longest line (or OBJ statement joined with `\`) a reader accepts: far beyond any real
/// mesh line, and a bound on memory when the input is an endless stream of non-newlines.
constexpr std::size_t kMaxLineLength = std::size_t(1) << 20;

/// Most entries reserved up front from a count a header declares; beyond it vectors grow.
constexpr std::uint64_t kReserveLimit = std::uint64_t(1) << 16;

constexpr std::uint64_t kMaxVertexCount = std::numeric_limits<VertexIndex>::max();

/// A word of the input as it may appear in a message: quoted, cut after 40 characters,
/// bytes that are not printable ASCII written as \xNN.
std::string shown(std::string_view text) {
  constexpr std::size_t kShownCharacters = 40;
  std::string result = "'";
  for (std::size_t i = 0; i < std::min(text.size(), kShownCharacters); ++i) {
    const auto byte = static_cast<unsigned char>(text[i]);
    if (byte >= 0x20 && byte < 0x7f) {
      result.push_back(static_cast<char>(byte));
    } else {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\x%02X", static_cast<unsigned>(byte));
      result += escaped;
    }
  }
  if (text.size() > kShownCharacters) result += "...";
  result += "'";
  return result;
}

/// "1 vertex", "8 vertices".
std::string counted(std::uint64_t count, std::string_view singular, std::string_view plural) {
  return std::to_string(count) + " " + std::string(count == 1 ? singular : plural);
}

/// Where a problem is: the file's name and a 1-based line number.
struct Location {
  const std::string* file_name;
  std::size_t line;

  [[noreturn]] void fail(const std::string& message) const {
    throw InvalidInput(*file_name + ":" + std::to_string(std::max<std::size_t>(line, 1)) + ": " +
                       message);
  }
};

bool is_blank(char character) {
  return character == ' ' || character == '\t' || character == '\r' || character == '\v' ||
         character == '\f';
}

std::string_view trim(std::string_view text) {
  while (!text.empty() && is_blank(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_blank(text.back())) text.remove_suffix(1);
  return text;
}

/// The blank-separated words of `text`, into `words` (cleared first).
void split_words(std::string_view text, std::vector<std::string_view>& words) {
  words.clear();
  std::size_t position = 0;
  while (position < text.size()) {
    while (position < text.size() && is_blank(text[position])) ++position;
    const std::size_t start = position;
    while (position < text.size() && !is_blank(text[position])) ++position;
    if (position > start) words.push_back(text.substr(start, position - start));
  }
}

/// `text` up to its first `#` (OBJ and TetGen comments).
std::string_view without_comment(std::string_view text) {
  const std::size_t hash = text.find('#');
  return hash == std::string_view::npos ? text : text.substr(0, hash);
}

/// Reads a stream line by line (LF, CRLF or CR endings), counting lines. Rejects lines
/// longer than kMaxLineLength and control bytes (binary data), drops a UTF-8 byte order
/// mark at the start. Reads through the stream buffer, so the stream's state flags are
/// not consulted beyond the constructor.
class LineReader {
 public:
  LineReader(std::istream& in, const std::string& file_name)
      : buffer_(in.rdbuf()), file_name_(file_name) {
    if (!in || buffer_ == nullptr) {
      Location{&file_name_, 1}.fail("cannot read: the stream is in a failed state");
    }
  }

  /// Moves to the next line; false at the end of the input.
  bool next_line() {
    if (at_end_) return false;
    text_.clear();
    bool read_anything = false;
    for (;;) {
      const int character = buffer_->sbumpc();
      if (character == std::char_traits<char>::eof()) {
        at_end_ = true;
        break;
      }
      read_anything = true;
      if (character == '\n') break;
      if (character == '\r') {
        if (buffer_->sgetc() == '\n') buffer_->sbumpc();
        break;
      }
      if (text_.size() == kMaxLineLength) {
        ++line_number_;
        fail("the line is longer than " + std::to_string(kMaxLineLength) + " bytes");
      }
      text_.push_back(static_cast<char>(character));
    }
    if (!read_anything) return false;
    ++line_number_;
    for (const char character : text_) {
      const auto byte = static_cast<unsigned char>(character);
      if ((byte < 0x20 && !is_blank(character)) || byte == 0x7f) {
        char hex[8];
        std::snprintf(hex, sizeof hex, "0x%02X", static_cast<unsigned>(byte));
        fail(std::string("unexpected control byte ") + hex + ": this is not a text file");
      }
    }
    std::string_view line = text_;
    if (line_number_ == 1 && line.substr(0, 3) == "\xEF\xBB\xBF") line.remove_prefix(3);
    line_ = line;
    return true;
  }

  std::string_view line() const { return line_; }
  std::size_t line_number() const { return line_number_; }
  Location here() const { return {&file_name_, line_number_}; }
  [[noreturn]] void fail(const std::string& message) const { here().fail(message); }

 private:
  std::streambuf* buffer_;
  const std::string& file_name_;
  std::string text_;
  std::string_view line_;
  std::size_t line_number_ = 0;
  bool at_end_ = false;
};

// ---- numbers -------------------------------------------------------------------------

/// `word` without one leading '+' (from_chars does not take it; the formats allow it).
std::string_view without_plus(std::string_view word) {
  if (word.size() > 1 && word[0] == '+' && word[1] != '-' && word[1] != '+') word.remove_prefix(1);
  return word;
}

template <typename Integer>
bool parse_whole(std::string_view word, Integer& value, std::errc& error) {
  const char* const end = word.data() + word.size();
  const auto result = std::from_chars(word.data(), end, value);
  error = result.ec;
  return result.ec == std::errc() && result.ptr == end;
}

/// A non-negative integer: a count, a tag, an index.
std::uint64_t parse_unsigned(std::string_view word, std::string_view what, const Location& where) {
  std::uint64_t value = 0;
  std::errc error{};
  if (parse_whole(without_plus(word), value, error)) return value;
  if (error == std::errc::result_out_of_range) {
    where.fail(std::string(what) + " " + shown(word) + " is too large");
  }
  std::int64_t negative = 0;
  if (parse_whole(word, negative, error) && negative < 0) {
    where.fail(std::string(what) + " " + std::string(word) + " is negative");
  }
  where.fail(std::string(what) + " " + shown(word) + " is not an integer");
}

std::int64_t parse_signed(std::string_view word, std::string_view what, const Location& where) {
  std::int64_t value = 0;
  std::errc error{};
  if (parse_whole(without_plus(word), value, error)) return value;
  if (error == std::errc::result_out_of_range) {
    where.fail(std::string(what) + " " + shown(word) + " is out of range");
  }
  where.fail(std::string(what) + " " + shown(word) + " is not an integer");
}

/// Any number (nan and inf included); for values that are checked and then ignored.
double parse_number(std::string_view word, std::string_view what, const Location& where) {
  double value = 0;
  std::errc error{};
  if (parse_whole(without_plus(word), value, error)) return value;
  if (error == std::errc::result_out_of_range) {
    where.fail(std::string(what) + " " + shown(word) + " is out of range for a double");
  }
  where.fail(std::string(what) + " " + shown(word) + " is not a number");
}

/// A finite coordinate that fits Real.
Real parse_coordinate(std::string_view word, std::string_view what, const Location& where) {
  const double value = parse_number(word, what, where);
  if (!std::isfinite(value)) where.fail(std::string(what) + " " + shown(word) + " is not finite");
  if (std::abs(value) > static_cast<double>(std::numeric_limits<Real>::max())) {
    where.fail(std::string(what) + " " + shown(word) + " is too large for Real (" +
               (kDoublePrecision ? "double" : "float") + ")");
  }
  return static_cast<Real>(value);
}

/// x y z from three consecutive words.
Vector3r parse_position(const std::vector<std::string_view>& words, std::size_t first,
                        const Location& where) {
  return Vector3r(parse_coordinate(words[first], "x coordinate", where),
                  parse_coordinate(words[first + 1], "y coordinate", where),
                  parse_coordinate(words[first + 2], "z coordinate", where));
}

void add_position(Mesh& mesh, const Vector3r& position, const Location& where) {
  if (mesh.positions.size() >= kMaxVertexCount) {
    where.fail("too many vertices: VertexIndex holds at most " + std::to_string(kMaxVertexCount));
  }
  mesh.positions.push_back(position);
}

void reserve_at_most(std::vector<Vector3r>& positions, std::uint64_t declared) {
  positions.reserve(positions.size() + static_cast<std::size_t>(std::min(declared, kReserveLimit)));
}

/// Position of the first of `count` corners that appears again later, or `count` if none does.
template <typename Value>
std::size_t first_repeated(const Value* corners, std::size_t count) {
  for (std::size_t a = 0; a < count; ++a)
    for (std::size_t b = a + 1; b < count; ++b)
      if (corners[a] == corners[b]) return a;
  return count;
}

std::string lowercase_extension(const std::filesystem::path& file) {
  std::string extension = file.extension().string();
  for (char& character : extension) {
    if (character >= 'A' && character <= 'Z') character = static_cast<char>(character - 'A' + 'a');
  }
  return extension;
}

std::ifstream open_for_reading(const std::filesystem::path& file) {
  std::error_code error;
  if (std::filesystem::is_directory(file, error)) {
    throw InvalidInput(file.string() + ": cannot open: it is a directory");
  }
  std::ifstream stream(file, std::ios::binary);
  if (!stream) {
    const bool exists = std::filesystem::exists(file, error);
    throw InvalidInput(file.string() + ": cannot open" + (exists ? "" : ": no such file"));
  }
  return stream;
}

// ---- Wavefront OBJ -------------------------------------------------------------------

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

// ---- TetGen --------------------------------------------------------------------------

/// Moves to the next line holding data (skipping blank lines and `#` comments) and splits
/// it into `words`; false at the end of the input.
bool next_tetgen_record(LineReader& reader, std::vector<std::string_view>& words) {
  while (reader.next_line()) {
    split_words(without_comment(reader.line()), words);
    if (!words.empty()) return true;
  }
  return false;
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
  if (!next_tetgen_record(reader, words)) {
    reader.fail(
        "empty file (expected the header '<#points> <dimension> <#attributes> <#boundary "
        "markers>')");
  }
  if (words.size() > 4) {
    reader.fail("the header has " + std::to_string(words.size()) +
                " values (expected <#points> <dimension> <#attributes> <#boundary markers>)");
  }
  const Location header = reader.here();
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
  if (!next_tetgen_record(reader, words)) {
    reader.fail(
        "empty file (expected the header '<#tetrahedra> <nodes per tetrahedron> <#attributes>')");
  }
  if (words.size() > 3) {
    reader.fail("the header has " + std::to_string(words.size()) +
                " values (expected <#tetrahedra> <nodes per tetrahedron> <#attributes>)");
  }
  const Location header = reader.here();
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
  if (!next_tetgen_record(reader, words)) {
    reader.fail("empty file (expected the header '<#faces> <#boundary markers>')");
  }
  if (words.size() > 2) {
    reader.fail("the header has " + std::to_string(words.size()) +
                " values (expected <#faces> <#boundary markers>)");
  }
  const Location header = reader.here();
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

// ---- Gmsh ----------------------------------------------------------------------------

/// An element type the reader keeps, with the corners it takes.
struct GmshElementType {
  std::uint64_t type;
  std::size_t node_count;
  std::size_t corner_count;  // 3: a triangle, 4: a tetrahedron
  const char* description;
};

constexpr std::array<GmshElementType, 4> kGmshElementTypes{{
    {2, 3, 3, "3-node triangle"},
    {4, 4, 4, "4-node tetrahedron"},
    {9, 6, 3, "6-node triangle"},
    {11, 10, 4, "10-node tetrahedron"},
}};

const GmshElementType* find_gmsh_element_type(std::uint64_t type) {
  for (const GmshElementType& known : kGmshElementTypes) {
    if (known.type == type) return &known;
  }
  return nullptr;
}

class GmshReader {
 public:
  GmshReader(std::istream& in, const std::string& name) : reader_(in, name) {}

  Mesh read() {
    if (!next_record()) reader_.fail("empty file");
    const std::string_view first = trim(reader_.line());
    if (first != "$MeshFormat") {
      if (first == "$NOD" || first == "$NOE") {
        reader_.fail("unsupported .msh version 1 (the file starts with " + std::string(first) +
                     "; only 2.2 and 4.1 are read)");
      }
      reader_.fail("not a Gmsh .msh file: expected $MeshFormat, found " + shown(first));
    }
    read_format();
    while (next_record()) {
      const std::string_view marker = trim(reader_.line());
      if (marker.front() != '$') {
        reader_.fail("expected a section such as $Nodes or $Elements, found " + shown(marker));
      }
      if (marker == "$Nodes") {
        version_ == Version::v2 ? read_nodes_v2() : read_nodes_v4();
      } else if (marker == "$Elements") {
        version_ == Version::v2 ? read_elements_v2() : read_elements_v4();
      } else if (marker.substr(0, 4) == "$End") {
        reader_.fail("unexpected " + shown(marker) + " outside any section");
      } else {
        skip_section(marker.substr(1));
      }
    }
    return std::move(mesh_);
  }

 private:
  enum class Version { v2, v4 };

  /// Moves to the next non-blank line and splits it into words_; false at the end.
  bool next_record() {
    while (reader_.next_line()) {
      split_words(reader_.line(), words_);
      if (!words_.empty()) return true;
    }
    return false;
  }

  /// How far a section got, for the message when it ends early. Built for every record, so
  /// it holds numbers and views only; the text is made on failure.
  struct Progress {
    std::uint64_t expected = 0;
    std::uint64_t read = 0;
    std::string_view plural;         // "nodes", "elements", "entity blocks"
    std::string_view header_layout;  // set instead while the section's header line is awaited

    std::string describe() const {
      if (!header_layout.empty()) return "expected the header '" + std::string(header_layout) + "'";
      return "expected " + std::to_string(expected) + " " + std::string(plural) + ", read " +
             std::to_string(read);
    }
  };

  /// The next record inside $<section>: fails at the end of the file or on a `$` line.
  void next_record_in(std::string_view section, const Progress& progress) {
    if (!next_record()) {
      reader_.fail("truncated: the file ends inside $" + std::string(section) + " (" +
                   progress.describe() + ")");
    }
    if (words_.front().front() == '$') {
      reader_.fail("unexpected " + shown(trim(reader_.line())) + " inside $" +
                   std::string(section) + " (" + progress.describe() + ")");
    }
  }

  void expect_section_end(std::string_view section, const std::string& after) {
    const std::string end_marker = "$End" + std::string(section);
    if (!next_record()) reader_.fail("truncated: the file ends before " + end_marker);
    if (trim(reader_.line()) != end_marker) {
      reader_.fail("expected " + end_marker + " after " + after + ", found " +
                   shown(trim(reader_.line())));
    }
  }

  void skip_section(std::string_view marker_name) {
    const std::string name(marker_name);  // a copy: the line buffer changes as lines are read
    const std::string end_marker = "$End" + name;
    while (reader_.next_line()) {
      if (trim(reader_.line()) == end_marker) return;
    }
    reader_.fail("truncated: the file ends inside $" + name + " (no " + end_marker + ")");
  }

  void read_format() {
    if (!next_record()) reader_.fail("truncated: the file ends inside $MeshFormat");
    const Location where = reader_.here();
    if (words_.size() != 3) {
      where.fail("expected '<version> <file type> <data size>' in $MeshFormat, found " +
                 counted(words_.size(), "value", "values"));
    }
    const double version = parse_number(words_[0], "version", where);
    if (version == 4.1) {
      version_ = Version::v4;
    } else if (version == 2.0 || version == 2.1 || version == 2.2) {
      version_ = Version::v2;
    } else {
      where.fail("unsupported .msh version " + std::string(words_[0]) +
                 " (only 2.2 and 4.1 are read)");
    }
    const std::uint64_t file_type = parse_unsigned(words_[1], "file type", where);
    if (file_type == 1)
      where.fail("binary .msh not supported (file type 1); save the mesh as ASCII");
    if (file_type != 0)
      where.fail("file type " + std::to_string(file_type) + " is not 0 (ASCII) or 1 (binary)");
    parse_unsigned(words_[2], "data size", where);
    expect_section_end("MeshFormat", "the format line");
  }

  /// Parses `count` header words (all non-negative integers) of a section's first line.
  void read_section_header(std::string_view section, std::size_t count, std::string_view layout,
                           std::uint64_t* values) {
    next_record_in(section, Progress{0, 0, {}, layout});
    const Location where = reader_.here();
    if (words_.size() != count) {
      where.fail("expected the $" + std::string(section) + " header '" + std::string(layout) +
                 "', found " + counted(words_.size(), "value", "values"));
    }
    for (std::size_t i = 0; i < count; ++i)
      values[i] = parse_unsigned(words_[i], "header value", where);
  }

  void add_node(std::uint64_t tag, const Vector3r& position, const Location& where) {
    if (tag == 0) where.fail("node tag 0 is not positive");
    if (mesh_.positions.size() >= kMaxVertexCount) {
      where.fail("too many vertices: VertexIndex holds at most " + std::to_string(kMaxVertexCount));
    }
    const auto [entry, inserted] =
        vertex_by_node_tag_.try_emplace(tag, static_cast<VertexIndex>(mesh_.positions.size()));
    if (!inserted) where.fail("node tag " + std::to_string(tag) + " appears twice");
    mesh_.positions.push_back(position);
  }

  /// Adds the element whose node tags are words_[first_node...]; `tag` is for messages.
  void add_element(const GmshElementType& type, std::size_t first_node, std::uint64_t tag,
                   const Location& where) {
    std::array<std::uint64_t, 10> node_tags{};
    std::array<VertexIndex, 10> vertices{};
    for (std::size_t k = 0; k < type.node_count; ++k) {
      node_tags[k] = parse_unsigned(words_[first_node + k], "node tag", where);
      const auto found = vertex_by_node_tag_.find(node_tags[k]);
      if (found == vertex_by_node_tag_.end()) {
        where.fail("element " + std::to_string(tag) + " names node tag " +
                   std::to_string(node_tags[k]) + ", which is not in $Nodes");
      }
      vertices[k] = found->second;
    }
    const std::size_t repeated = first_repeated(node_tags.data(), type.node_count);
    if (repeated != type.node_count) {
      where.fail("element " + std::to_string(tag) + " names node tag " +
                 std::to_string(node_tags[repeated]) + " twice");
    }
    std::vector<VertexIndex>& elements =
        type.corner_count == 3 ? mesh_.triangles : mesh_.tetrahedra;
    elements.insert(elements.end(), vertices.begin(),
                    vertices.begin() + static_cast<std::ptrdiff_t>(type.corner_count));
  }

  void read_nodes_v2() {
    std::uint64_t node_count = 0;
    read_section_header("Nodes", 1, "<number of nodes>", &node_count);
    reserve_at_most(mesh_.positions, node_count);
    for (std::uint64_t read = 0; read < node_count; ++read) {
      next_record_in("Nodes", Progress{node_count, read, "nodes", {}});
      const Location where = reader_.here();
      if (words_.size() != 4) {
        where.fail("expected a node tag and 3 coordinates, found " +
                   counted(words_.size(), "value", "values"));
      }
      const std::uint64_t tag = parse_unsigned(words_[0], "node tag", where);
      add_node(tag, parse_position(words_, 1, where), where);
    }
    expect_section_end("Nodes", counted(node_count, "node", "nodes"));
  }

  void read_elements_v2() {
    std::uint64_t element_count = 0;
    read_section_header("Elements", 1, "<number of elements>", &element_count);
    for (std::uint64_t read = 0; read < element_count; ++read) {
      next_record_in("Elements", Progress{element_count, read, "elements", {}});
      const Location where = reader_.here();
      if (words_.size() < 3) {
        where.fail("expected '<tag> <type> <number of tags> <tags...> <node tags...>', found " +
                   counted(words_.size(), "value", "values"));
      }
      const std::uint64_t tag = parse_unsigned(words_[0], "element tag", where);
      const GmshElementType* type =
          find_gmsh_element_type(parse_unsigned(words_[1], "element type", where));
      if (type == nullptr) continue;  // points, lines, quadrangles, hexahedra...: skipped
      const std::uint64_t tag_count = parse_unsigned(words_[2], "number of tags", where);
      if (tag_count > words_.size() - 3 || words_.size() - 3 - tag_count != type->node_count) {
        where.fail("element " + std::to_string(tag) + " (" + type->description + ") should have " +
                   std::to_string(type->node_count) + " node tags after its " +
                   counted(tag_count, "tag", "tags") + ", found " +
                   counted(words_.size(), "value", "values") + " in all");
      }
      for (std::size_t i = 0; i < tag_count; ++i)
        parse_signed(words_[3 + i], "element tag value", where);
      add_element(*type, 3 + static_cast<std::size_t>(tag_count), tag, where);
    }
    expect_section_end("Elements", counted(element_count, "element", "elements"));
  }

  void read_nodes_v4() {
    std::uint64_t header[4] = {};
    read_section_header("Nodes", 4,
                        "<number of entity blocks> <number of nodes> <min tag> <max tag>", header);
    const std::uint64_t block_count = header[0];
    const std::uint64_t node_count = header[1];
    reserve_at_most(mesh_.positions, node_count);
    std::vector<std::uint64_t> block_tags;
    std::uint64_t read = 0;
    for (std::uint64_t block = 0; block < block_count; ++block) {
      next_record_in("Nodes", Progress{block_count, block, "entity blocks", {}});
      const Location block_header = reader_.here();
      if (words_.size() != 4) {
        block_header.fail(
            "expected an entity block header '<entity dimension> <entity tag> <parametric> "
            "<number of nodes>', found " +
            counted(words_.size(), "value", "values"));
      }
      const std::uint64_t dimension = parse_unsigned(words_[0], "entity dimension", block_header);
      if (dimension > 3)
        block_header.fail("entity dimension " + std::to_string(dimension) + " is not 0, 1, 2 or 3");
      parse_signed(words_[1], "entity tag", block_header);
      const std::uint64_t parametric = parse_unsigned(words_[2], "parametric flag", block_header);
      if (parametric > 1)
        block_header.fail("parametric flag " + std::to_string(parametric) + " is not 0 or 1");
      const std::uint64_t in_block =
          parse_unsigned(words_[3], "number of nodes in the block", block_header);
      if (in_block > node_count - read) {
        block_header.fail("the entity block holds " + counted(in_block, "node", "nodes") +
                          ", more than the " + std::to_string(node_count - read) + " left of the " +
                          std::to_string(node_count) + " the $Nodes header declares");
      }
      block_tags.clear();
      block_tags.reserve(static_cast<std::size_t>(std::min(in_block, kReserveLimit)));
      for (std::uint64_t k = 0; k < in_block; ++k) {
        next_record_in("Nodes", Progress{node_count, read, "nodes", {}});
        if (words_.size() != 1) {
          reader_.fail("expected one node tag, found " + counted(words_.size(), "value", "values"));
        }
        block_tags.push_back(parse_unsigned(words_[0], "node tag", reader_.here()));
      }
      const std::size_t value_count = 3 + static_cast<std::size_t>(parametric == 1 ? dimension : 0);
      for (std::uint64_t k = 0; k < in_block; ++k) {
        next_record_in("Nodes", Progress{node_count, read, "nodes", {}});
        const Location where = reader_.here();
        if (words_.size() != value_count) {
          where.fail("expected " + std::to_string(value_count) + " coordinates (x y z" +
                     (value_count > 3 ? " and " + std::to_string(value_count - 3) + " parametric"
                                      : std::string()) +
                     "), found " + std::to_string(words_.size()));
        }
        const Vector3r position = parse_position(words_, 0, where);
        for (std::size_t i = 3; i < value_count; ++i)
          parse_number(words_[i], "parametric coordinate", where);
        add_node(block_tags[static_cast<std::size_t>(k)], position, where);
        ++read;
      }
    }
    if (read != node_count) {
      reader_.fail("the $Nodes header declares " + counted(node_count, "node", "nodes") +
                   " but its blocks hold " + std::to_string(read));
    }
    expect_section_end("Nodes", counted(node_count, "node", "nodes"));
  }

  void read_elements_v4() {
    std::uint64_t header[4] = {};
    read_section_header("Elements", 4,
                        "<number of entity blocks> <number of elements> <min tag> <max tag>",
                        header);
    const std::uint64_t block_count = header[0];
    const std::uint64_t element_count = header[1];
    std::uint64_t read = 0;
    for (std::uint64_t block = 0; block < block_count; ++block) {
      next_record_in("Elements", Progress{block_count, block, "entity blocks", {}});
      const Location block_header = reader_.here();
      if (words_.size() != 4) {
        block_header.fail(
            "expected an entity block header '<entity dimension> <entity tag> <element type> "
            "<number of elements>', found " +
            counted(words_.size(), "value", "values"));
      }
      const std::uint64_t dimension = parse_unsigned(words_[0], "entity dimension", block_header);
      if (dimension > 3)
        block_header.fail("entity dimension " + std::to_string(dimension) + " is not 0, 1, 2 or 3");
      parse_signed(words_[1], "entity tag", block_header);
      const GmshElementType* type =
          find_gmsh_element_type(parse_unsigned(words_[2], "element type", block_header));
      const std::uint64_t in_block =
          parse_unsigned(words_[3], "number of elements in the block", block_header);
      if (in_block > element_count - read) {
        block_header.fail("the entity block holds " + counted(in_block, "element", "elements") +
                          ", more than the " + std::to_string(element_count - read) +
                          " left of the " + std::to_string(element_count) +
                          " the $Elements header declares");
      }
      for (std::uint64_t k = 0; k < in_block; ++k) {
        next_record_in("Elements", Progress{element_count, read, "elements", {}});
        ++read;
        if (type == nullptr) continue;  // points, lines, quadrangles, hexahedra...: skipped
        const Location where = reader_.here();
        if (words_.size() != 1 + type->node_count) {
          where.fail("expected an element tag and " + std::to_string(type->node_count) +
                     " node tags (" + type->description + "), found " +
                     counted(words_.size(), "value", "values"));
        }
        add_element(*type, 1, parse_unsigned(words_[0], "element tag", where), where);
      }
    }
    if (read != element_count) {
      reader_.fail("the $Elements header declares " +
                   counted(element_count, "element", "elements") + " but its blocks hold " +
                   std::to_string(read));
    }
    expect_section_end("Elements", counted(element_count, "element", "elements"));
  }

  LineReader reader_;
  Version version_ = Version::v2;
  Mesh mesh_;
  std::unordered_map<std::uint64_t, VertexIndex> vertex_by_node_tag_;
  std::vector<std::string_view> words_;
};

}  // namespace

// ---- public API ----------------------------------------------------------------------

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

Mesh read_gmsh(std::istream& in, const std::string& name) { return GmshReader(in, name).read(); }

Mesh read_gmsh(const std::filesystem::path& file) {
  std::ifstream stream = open_for_reading(file);
  return read_gmsh(stream, file.string());
}

Mesh read_mesh(const std::filesystem::path& file) {
  const std::string extension = lowercase_extension(file);
  if (extension == ".obj") return read_obj(file);
  if (extension == ".node" || extension == ".ele" || extension == ".face") return read_tetgen(file);
  if (extension == ".msh") return read_gmsh(file);
  throw InvalidInput(file.string() + ": unsupported mesh file extension " +
                     (extension.empty() ? std::string("(none)") : shown(extension)) +
                     " (expected .obj, .node, .ele, .face or .msh)");
}

}  // namespace tessera::io
