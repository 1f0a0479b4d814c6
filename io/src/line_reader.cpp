// The shared text machinery of the mesh readers (see line_reader.hpp): messages, the line
// reader, words, number parsers and the file opening all three formats do the same way.
#include "line_reader.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <system_error>

#include <tessera/core/error.hpp>

namespace tessera::io::detail {
namespace {

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

/// The failure of a parse_whole: "<what> '<word>' <out_of_range>" when from_chars said the
/// value does not fit, "<what> '<word>' <not_parsed>" otherwise.
[[noreturn]] void fail_parse(std::string_view word, std::string_view what, const Location& where,
                             std::errc error, const char* out_of_range, const char* not_parsed) {
  where.fail(std::string(what) + " " + shown(word) + " " +
             (error == std::errc::result_out_of_range ? out_of_range : not_parsed));
}

}  // namespace

// ---- messages --------------------------------------------------------------------------

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

std::string counted(std::uint64_t count, std::string_view singular, std::string_view plural) {
  return std::to_string(count) + " " + std::string(count == 1 ? singular : plural);
}

void Location::fail(const std::string& message) const {
  throw InvalidInput(*file_name + ":" + std::to_string(std::max<std::size_t>(line, 1)) + ": " +
                     message);
}

// ---- lines and words -------------------------------------------------------------------

std::string_view trim(std::string_view text) {
  while (!text.empty() && is_blank(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_blank(text.back())) text.remove_suffix(1);
  return text;
}

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

std::string_view without_comment(std::string_view text) {
  const std::size_t hash = text.find('#');
  return hash == std::string_view::npos ? text : text.substr(0, hash);
}

LineReader::LineReader(std::istream& in, const std::string& file_name)
    : buffer_(in.rdbuf()), file_name_(file_name) {
  if (!in || buffer_ == nullptr) {
    Location{&file_name_, 1}.fail("cannot read: the stream is in a failed state");
  }
}

bool LineReader::next_line() {
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

// ---- numbers ---------------------------------------------------------------------------

std::uint64_t parse_unsigned(std::string_view word, std::string_view what, const Location& where) {
  std::uint64_t value = 0;
  std::errc error{};
  if (parse_whole(without_plus(word), value, error)) return value;
  std::int64_t negative = 0;
  std::errc ignored{};
  if (parse_whole(word, negative, ignored) && negative < 0) {
    where.fail(std::string(what) + " " + std::string(word) + " is negative");
  }
  fail_parse(word, what, where, error, "is too large", "is not an integer");
}

std::int64_t parse_signed(std::string_view word, std::string_view what, const Location& where) {
  std::int64_t value = 0;
  std::errc error{};
  if (parse_whole(without_plus(word), value, error)) return value;
  fail_parse(word, what, where, error, "is out of range", "is not an integer");
}

double parse_number(std::string_view word, std::string_view what, const Location& where) {
  double value = 0;
  std::errc error{};
  if (parse_whole(without_plus(word), value, error)) return value;
  fail_parse(word, what, where, error, "is out of range for a double", "is not a number");
}

Real parse_coordinate(std::string_view word, std::string_view what, const Location& where) {
  const double value = parse_number(word, what, where);
  if (!std::isfinite(value)) where.fail(std::string(what) + " " + shown(word) + " is not finite");
  if (std::abs(value) > static_cast<double>(std::numeric_limits<Real>::max())) {
    where.fail(std::string(what) + " " + shown(word) + " is too large for Real (" +
               (kDoublePrecision ? "double" : "float") + ")");
  }
  return static_cast<Real>(value);
}

Vector3r parse_position(const std::vector<std::string_view>& words, std::size_t first,
                        const Location& where) {
  return Vector3r(parse_coordinate(words[first], "x coordinate", where),
                  parse_coordinate(words[first + 1], "y coordinate", where),
                  parse_coordinate(words[first + 2], "z coordinate", where));
}

// ---- building the Mesh -----------------------------------------------------------------

void add_position(Mesh& mesh, const Vector3r& position, const Location& where) {
  if (mesh.positions.size() >= kMaxVertexCount) {
    where.fail("too many vertices: VertexIndex holds at most " + std::to_string(kMaxVertexCount));
  }
  mesh.positions.push_back(position);
}

void reserve_at_most(std::vector<Vector3r>& positions, std::uint64_t declared) {
  positions.reserve(positions.size() + static_cast<std::size_t>(std::min(declared, kReserveLimit)));
}

// ---- files -----------------------------------------------------------------------------

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

}  // namespace tessera::io::detail
