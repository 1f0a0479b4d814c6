// What the three mesh readers (obj_reader.cpp, tetgen_reader.cpp, gmsh_reader.cpp) share:
// every format is line-oriented text, so they read it through one LineReader (bounded line
// length, control bytes rejected, a line number for every message), split lines into words
// the same way and parse numbers with one set of parsers (std::from_chars: locale-independent,
// no silent prefixes, finite coordinates only). Internal to tessera::io: not installed.
//
// Counts declared in headers are never trusted for allocation: vectors reserve at most
// kReserveLimit entries and grow as records are actually read, and every loop consumes a line
// per step, so a lying header costs no more than the file's own size.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <istream>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include <tessera/core/real.hpp>
#include <tessera/io/mesh_readers.hpp>

namespace tessera::io::detail {

// ---- limits ----------------------------------------------------------------------------

/// Longest line (or OBJ statement joined with `\`) a reader accepts: far beyond any real
/// mesh line, and a bound on memory when the input is an endless stream of non-newlines.
inline constexpr std::size_t kMaxLineLength = std::size_t(1) << 20;

/// Most entries reserved up front from a count a header declares; beyond it vectors grow.
inline constexpr std::uint64_t kReserveLimit = std::uint64_t(1) << 16;

inline constexpr std::uint64_t kMaxVertexCount = std::numeric_limits<VertexIndex>::max();

// ---- messages --------------------------------------------------------------------------

/// A word of the input as it may appear in a message: quoted, cut after 40 characters,
/// bytes that are not printable ASCII written as \xNN.
std::string shown(std::string_view text);

/// "1 vertex", "8 vertices".
std::string counted(std::uint64_t count, std::string_view singular, std::string_view plural);

/// Where a problem is: the file's name and a 1-based line number.
struct Location {
  const std::string* file_name;
  std::size_t line;

  /// Throws InvalidInput "<file>:<line>: <message>".
  [[noreturn]] void fail(const std::string& message) const;
};

// ---- lines and words -------------------------------------------------------------------

inline bool is_blank(char character) {
  return character == ' ' || character == '\t' || character == '\r' || character == '\v' ||
         character == '\f';
}

std::string_view trim(std::string_view text);

/// The blank-separated words of `text`, into `words` (cleared first).
void split_words(std::string_view text, std::vector<std::string_view>& words);

/// `text` up to its first `#` (OBJ and TetGen comments).
std::string_view without_comment(std::string_view text);

/// Reads a stream line by line (LF, CRLF or CR endings), counting lines. Rejects lines
/// longer than kMaxLineLength and control bytes (binary data), drops a UTF-8 byte order
/// mark at the start. Reads through the stream buffer, so the stream's state flags are
/// not consulted beyond the constructor.
class LineReader {
 public:
  LineReader(std::istream& in, const std::string& file_name);

  /// Moves to the next line; false at the end of the input.
  bool next_line();

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

// ---- numbers ---------------------------------------------------------------------------
// `what` names the value in the message ("point index", "x coordinate").

/// A non-negative integer: a count, a tag, an index.
std::uint64_t parse_unsigned(std::string_view word, std::string_view what, const Location& where);

std::int64_t parse_signed(std::string_view word, std::string_view what, const Location& where);

/// Any number (nan and inf included); for values that are checked and then ignored.
double parse_number(std::string_view word, std::string_view what, const Location& where);

/// A finite coordinate that fits Real.
Real parse_coordinate(std::string_view word, std::string_view what, const Location& where);

/// x y z from three consecutive words.
Vector3r parse_position(const std::vector<std::string_view>& words, std::size_t first,
                        const Location& where);

// ---- building the Mesh -----------------------------------------------------------------

/// Appends a vertex; fails beyond kMaxVertexCount vertices.
void add_position(Mesh& mesh, const Vector3r& position, const Location& where);

/// Reserves room for `declared` more positions, but never more than kReserveLimit.
void reserve_at_most(std::vector<Vector3r>& positions, std::uint64_t declared);

/// Position of the first of `count` corners that appears again later, or `count` if none does.
template <typename Value>
std::size_t first_repeated(const Value* corners, std::size_t count) {
  for (std::size_t a = 0; a < count; ++a)
    for (std::size_t b = a + 1; b < count; ++b)
      if (corners[a] == corners[b]) return a;
  return count;
}

// ---- files -----------------------------------------------------------------------------

/// The extension of `file` in lower case (".obj" for "CUBE.OBJ").
std::string lowercase_extension(const std::filesystem::path& file);

/// Opens `file` in binary mode; throws InvalidInput "<file>: cannot open..." (a directory,
/// no such file, no permission).
std::ifstream open_for_reading(const std::filesystem::path& file);

}  // namespace tessera::io::detail
