// Frame writers (.vtu, .pvd, .obj): validate the whole frame first, then format it as text in
// chunks and write it atomically (temporary file beside the target, flushed, closed, checked,
// renamed over the target; the temporary is removed on any failure). See mesh_writers.hpp.
#include <tessera/io/mesh_writers.hpp>

#include <array>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <fstream>
#include <random>
#include <string_view>
#include <system_error>
#include <type_traits>

#include <tessera/core/error.hpp>

namespace tessera::io {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void fail(const fs::path& file, const std::string& problem) {
  throw InvalidInput("cannot write " + file.string() + ": " + problem);
}

const char* cell_type_name(CellType type) {
  switch (type) {
    case CellType::line: return "line";
    case CellType::triangle: return "triangle";
    case CellType::tetrahedron: return "tetrahedron";
  }
  return "unknown";
}

std::string block_label(std::size_t block_index, CellType type) {
  return "block " + std::to_string(block_index) + " (" + cell_type_name(type) + ")";
}

// ---- number and text formatting ----------------------------------------------------------

/// Appends a value with std::to_chars: the shortest text that reads back to the same value
/// for floating point, independent of the locale.
template <class Number>
void append_number(std::string& text, Number value) {
  std::array<char, 64> digits;
  const auto [end, error] = std::to_chars(digits.data(), digits.data() + digits.size(), value);
  (void)error;  // 64 characters hold any float, double or 64-bit integer
  text.append(digits.data(), end);
}

/// The characters a name may not contain: XML markup and quotes (names are written inside
/// attribute values unescaped) and control characters.
bool is_unsafe_name_character(char c) {
  const auto code = static_cast<unsigned char>(c);
  return code < 0x20 || code == 0x7f || c == '<' || c == '>' || c == '&' || c == '"' || c == '\'';
}

/// Why `name` cannot be written as an array name, or empty when it can.
std::string name_problem(const std::string& name) {
  if (name.empty()) return "is empty";
  for (const char c : name)
    if (is_unsafe_name_character(c))
      return "contains a character that is not allowed in a name (< > & \" ' or a control "
             "character)";
  return {};
}

/// `text` escaped for an XML attribute value in double quotes.
std::string xml_escaped(std::string_view text) {
  std::string escaped;
  escaped.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&': escaped += "&amp;"; break;
      case '<': escaped += "&lt;"; break;
      case '>': escaped += "&gt;"; break;
      case '"': escaped += "&quot;"; break;
      case '\'': escaped += "&apos;"; break;
      default: escaped += c;
    }
  }
  return escaped;
}

/// Collects text and hands it to the stream in chunks of about 64 KiB, so a large frame
/// neither goes through the stream number by number nor is held in memory whole.
class ChunkedText {
 public:
  explicit ChunkedText(std::ostream& out) : out_(out) { text_.reserve(kChunk + 256); }
  std::string& text() { return text_; }
  /// Call after each short piece (a line): passes the text on once a chunk is full.
  void maybe_flush() {
    if (text_.size() >= kChunk) flush();
  }
  void flush() {
    out_.write(text_.data(), static_cast<std::streamsize>(text_.size()));
    text_.clear();
  }

 private:
  static constexpr std::size_t kChunk = std::size_t(1) << 16;
  std::ostream& out_;
  std::string text_;
};

/// One line per position, `prefix` then "x y z" (VTU points, OBJ `v` lines).
void append_positions(ChunkedText& chunks, const char* prefix,
                      std::span<const Vector3r> positions) {
  std::string& text = chunks.text();
  for (const Vector3r& x : positions) {
    text += prefix;
    append_number(text, x.x());
    text += ' ';
    append_number(text, x.y());
    text += ' ';
    append_number(text, x.z());
    text += '\n';
    chunks.maybe_flush();
  }
}

// ---- atomic file writing -------------------------------------------------------------------

std::uint64_t mix_bits(std::uint64_t x) {  // splitmix64's finaliser
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

/// A token unique to this process and call: a random per-process seed (so two processes
/// writing into one folder do not collide) mixed with a call counter (so two threads do not).
std::uint64_t unique_token() {
  static const std::uint64_t process_seed = [] {
    std::uint64_t seed = static_cast<std::uint64_t>(
        std::chrono::steady_clock::now().time_since_epoch().count());
    try {
      std::random_device device;
      seed ^= (std::uint64_t(device()) << 32) ^ std::uint64_t(device());
    } catch (...) {  // no entropy source: the clock alone still differs between processes
    }
    return seed;
  }();
  static std::atomic<std::uint64_t> calls{0};
  return mix_bits(process_seed ^ mix_bits(calls.fetch_add(1, std::memory_order_relaxed)));
}

std::string errno_text(int error_number) {
  return error_number != 0 ? std::generic_category().message(error_number) : "unknown error";
}

/// A temporary path beside `file` that does not exist yet: "<name>.tmp-<16 hex digits>".
fs::path temporary_path_for(const fs::path& file) {
  static constexpr char kHex[] = "0123456789abcdef";
  for (int attempt = 0; attempt < 16; ++attempt) {
    std::uint64_t token = unique_token();
    std::string suffix = ".tmp-";
    for (int digit = 0; digit < 16; ++digit, token >>= 4) suffix += kHex[token & 0xf];
    fs::path candidate = file;
    candidate += suffix;
    std::error_code error;
    if (!fs::exists(fs::symlink_status(candidate, error))) return candidate;
  }
  fail(file, "cannot find an unused temporary file name beside it");
}

/// Writes `file` through `write_body(std::ostream&)` atomically: into a temporary beside it,
/// flushed, closed and checked, then renamed over `file`. On any failure the temporary is
/// removed and InvalidInput thrown (an exception from write_body is passed on after the
/// cleanup); `file` keeps its old content until the rename.
template <class WriteBody>
void write_atomically(const fs::path& file, WriteBody&& write_body) {
  if (!file.has_filename()) fail(file, "the path names no file");
  const fs::path folder = file.has_parent_path() ? file.parent_path() : fs::path(".");
  std::error_code folder_error;
  const fs::file_status folder_status = fs::status(folder, folder_error);
  if (!fs::exists(folder_status))
    fail(file, "the folder " + folder.string() + " does not exist (folders are not created)");
  if (!fs::is_directory(folder_status))
    fail(file, folder.string() + " is not a folder");

  const fs::path temporary = temporary_path_for(file);
  auto remove_temporary = [&temporary] {
    std::error_code ignored;
    fs::remove(temporary, ignored);
  };

  errno = 0;
  std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
  if (!out.is_open()) {
    const int open_errno = errno;
    remove_temporary();  // in case it was created but not opened for writing
    fail(file, "cannot create the temporary file " + temporary.string() + ": " +
                   errno_text(open_errno));
  }
  try {
    write_body(static_cast<std::ostream&>(out));
    errno = 0;
    out.flush();
    if (!out) {
      const int write_errno = errno;
      out.close();
      remove_temporary();
      fail(file, "writing the temporary file failed: " + errno_text(write_errno));
    }
    errno = 0;
    out.close();
    if (out.fail()) {
      const int close_errno = errno;
      remove_temporary();
      fail(file, "closing the temporary file failed: " + errno_text(close_errno));
    }
  } catch (...) {
    if (out.is_open()) out.close();
    remove_temporary();
    throw;
  }

  std::error_code rename_error;
  fs::rename(temporary, file, rename_error);
  if (rename_error) {
    remove_temporary();
    fail(file, "cannot rename the temporary file into place: " + rename_error.message());
  }
}

// ---- frame validation ------------------------------------------------------------------------

/// One cell-data array of the whole mesh: its name and, per block, the values (or none).
struct MergedCellData {
  std::string name;
  std::vector<const std::span<const std::int32_t>*> per_block;  // nullptr: fill with -1
};

/// Checks everything write_vtu and write_obj document, before any file is touched.
void validate_frame(const fs::path& file, const Frame& frame) {
  const std::size_t point_count = frame.positions.size();
  for (std::size_t p = 0; p < point_count; ++p) {
    const Vector3r& x = frame.positions[p];
    if (!std::isfinite(x.x()) || !std::isfinite(x.y()) || !std::isfinite(x.z()))
      fail(file, "the position of point " + std::to_string(p) + " is not finite");
  }

  for (std::size_t a = 0; a < frame.point_data.size(); ++a) {
    const auto& [name, values] = frame.point_data[a];
    if (const std::string problem = name_problem(name); !problem.empty())
      fail(file, "the name of point data array " + std::to_string(a) + " (\"" + name + "\") " +
                     problem);
    for (std::size_t b = 0; b < a; ++b)
      if (frame.point_data[b].first == name)
        fail(file, "point data \"" + name + "\" is given twice");
    if (values.size() != point_count)
      fail(file, "point data \"" + name + "\" has " + std::to_string(values.size()) +
                     " values for " + std::to_string(point_count) + " points");
    for (std::size_t p = 0; p < values.size(); ++p)
      if (!std::isfinite(values[p]))
        fail(file, "point data \"" + name + "\" is not finite at point " + std::to_string(p));
  }

  for (std::size_t b = 0; b < frame.blocks.size(); ++b) {
    const CellBlock& block = frame.blocks[b];
    const std::string label = block_label(b, block.type);
    const std::size_t per_cell = vertices_per_cell(block.type);
    if (per_cell == 0) fail(file, label + " has an unknown cell type");
    if (block.vertices.size() % per_cell != 0)
      fail(file, label + " has " + std::to_string(block.vertices.size()) +
                     " vertex indices, not a multiple of " + std::to_string(per_cell) +
                     " per cell");
    const std::size_t cell_count = block.vertices.size() / per_cell;
    for (std::size_t i = 0; i < block.vertices.size(); ++i)
      if (block.vertices[i] >= point_count)
        fail(file, label + ": vertex index " + std::to_string(block.vertices[i]) + " of cell " +
                       std::to_string(i / per_cell) + " is out of range (" +
                       std::to_string(point_count) + " points)");
    for (std::size_t a = 0; a < block.cell_data.size(); ++a) {
      const auto& [name, values] = block.cell_data[a];
      if (const std::string problem = name_problem(name); !problem.empty())
        fail(file, label + ": the name of cell data array " + std::to_string(a) + " (\"" + name +
                       "\") " + problem);
      for (std::size_t earlier = 0; earlier < a; ++earlier)
        if (block.cell_data[earlier].first == name)
          fail(file, label + ": cell data \"" + name + "\" is given twice");
      if (values.size() != cell_count)
        fail(file, label + ": cell data \"" + name + "\" has " + std::to_string(values.size()) +
                       " values for " + std::to_string(cell_count) + " cells");
    }
  }
}

/// The cell-data arrays of the whole mesh, in order of first appearance over the blocks.
std::vector<MergedCellData> merge_cell_data(const Frame& frame) {
  std::vector<MergedCellData> merged;
  for (std::size_t b = 0; b < frame.blocks.size(); ++b)
    for (const auto& entry : frame.blocks[b].cell_data) {
      MergedCellData* array = nullptr;
      for (MergedCellData& candidate : merged)
        if (candidate.name == entry.first) array = &candidate;
      if (array == nullptr) {
        merged.push_back({entry.first, std::vector<const std::span<const std::int32_t>*>(
                                           frame.blocks.size(), nullptr)});
        array = &merged.back();
      }
      array->per_block[b] = &entry.second;
    }
  return merged;
}

std::size_t cell_count_of(const CellBlock& block) {
  return block.vertices.size() / vertices_per_cell(block.type);
}

// ---- the formats -----------------------------------------------------------------------------

constexpr const char* kRealVtkType = kDoublePrecision ? "Float64" : "Float32";
constexpr std::size_t kScalarsPerLine = 12;

/// The values of one DataArray, kScalarsPerLine to an indented line; `count` is the array's
/// length, so the last line is ended wherever it stops.
class ScalarLines {
 public:
  ScalarLines(ChunkedText& chunks, std::size_t count) : chunks_(chunks), count_(count) {}
  template <class Number>
  void add(Number value) {
    std::string& text = chunks_.text();
    text += (written_ % kScalarsPerLine == 0) ? "          " : " ";
    append_number(text, value);
    if (written_ % kScalarsPerLine == kScalarsPerLine - 1 || written_ + 1 == count_) {
      text += '\n';
      chunks_.maybe_flush();
    }
    ++written_;
  }

 private:
  ChunkedText& chunks_;
  std::size_t count_;
  std::size_t written_ = 0;
};

void write_vtu_body(std::ostream& out, const Frame& frame,
                    const std::vector<MergedCellData>& cell_data) {
  std::size_t total_cells = 0;
  for (const CellBlock& block : frame.blocks) total_cells += cell_count_of(block);

  ChunkedText chunks(out);
  std::string& text = chunks.text();
  text += "<?xml version=\"1.0\"?>\n";
  text += "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n";
  text += "  <UnstructuredGrid>\n";
  text += "    <Piece NumberOfPoints=\"";
  append_number(text, frame.positions.size());
  text += "\" NumberOfCells=\"";
  append_number(text, total_cells);
  text += "\">\n";

  if (!frame.point_data.empty()) {
    text += "      <PointData Scalars=\"" + frame.point_data.front().first + "\">\n";
    for (const auto& [name, values] : frame.point_data) {
      text += "        <DataArray type=\"";
      text += kRealVtkType;
      text += "\" Name=\"" + name + "\" format=\"ascii\">\n";
      ScalarLines lines(chunks, values.size());
      for (const Real value : values) lines.add(value);
      text += "        </DataArray>\n";
    }
    text += "      </PointData>\n";
  }

  if (!cell_data.empty()) {
    text += "      <CellData Scalars=\"" + cell_data.front().name + "\">\n";
    for (const MergedCellData& array : cell_data) {
      text += "        <DataArray type=\"Int32\" Name=\"" + array.name + "\" format=\"ascii\">\n";
      ScalarLines lines(chunks, total_cells);
      for (std::size_t b = 0; b < frame.blocks.size(); ++b) {
        const std::span<const std::int32_t>* values = array.per_block[b];
        const std::size_t cells = cell_count_of(frame.blocks[b]);
        for (std::size_t c = 0; c < cells; ++c)
          lines.add(values != nullptr ? (*values)[c] : std::int32_t(-1));
      }
      text += "        </DataArray>\n";
    }
    text += "      </CellData>\n";
  }

  text += "      <Points>\n";
  text += "        <DataArray type=\"";
  text += kRealVtkType;
  text += "\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  append_positions(chunks, "          ", frame.positions);
  text += "        </DataArray>\n";
  text += "      </Points>\n";

  text += "      <Cells>\n";
  text += "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (const CellBlock& block : frame.blocks) {
    const std::size_t per_cell = vertices_per_cell(block.type);
    for (std::size_t i = 0; i < block.vertices.size(); ++i) {
      text += (i % per_cell == 0) ? "          " : " ";
      append_number(text, block.vertices[i]);
      if (i % per_cell == per_cell - 1) {
        text += '\n';
        chunks.maybe_flush();
      }
    }
  }
  text += "        </DataArray>\n";
  // offsets: the end of each cell in connectivity (VTK XML's convention, no leading 0).
  text += "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  std::uint64_t offset = 0;
  ScalarLines offsets(chunks, total_cells);
  for (const CellBlock& block : frame.blocks) {
    const std::size_t per_cell = vertices_per_cell(block.type);
    for (std::size_t c = 0; c < cell_count_of(block); ++c) {
      offset += per_cell;
      offsets.add(offset);
    }
  }
  text += "        </DataArray>\n";
  text += "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  ScalarLines types(chunks, total_cells);
  for (const CellBlock& block : frame.blocks) {
    const unsigned vtk_type = vtk_cell_type(block.type);
    for (std::size_t c = 0; c < cell_count_of(block); ++c) types.add(vtk_type);
  }
  text += "        </DataArray>\n";
  text += "      </Cells>\n";
  text += "    </Piece>\n";
  text += "  </UnstructuredGrid>\n";
  text += "</VTKFile>\n";
  chunks.flush();
}

void write_obj_body(std::ostream& out, const Frame& frame) {
  std::size_t triangle_count = 0;
  for (const CellBlock& block : frame.blocks)
    if (block.type == CellType::triangle) triangle_count += cell_count_of(block);

  ChunkedText chunks(out);
  std::string& text = chunks.text();
  text += "# Wavefront OBJ written by Tessera: ";
  append_number(text, frame.positions.size());
  text += " vertices, ";
  append_number(text, triangle_count);
  text += " triangles\n";
  append_positions(chunks, "v ", frame.positions);
  for (const CellBlock& block : frame.blocks) {
    if (block.type != CellType::triangle) continue;
    for (std::size_t i = 0; i < block.vertices.size(); i += 3) {
      text += 'f';
      for (std::size_t k = 0; k < 3; ++k) {
        text += ' ';
        append_number(text, std::uint64_t(block.vertices[i + k]) + 1);  // OBJ is 1-based
      }
      text += '\n';
      chunks.maybe_flush();
    }
  }
  chunks.flush();
}

}  // namespace

void write_vtu(const std::filesystem::path& file, const Frame& frame) {
  validate_frame(file, frame);
  const std::vector<MergedCellData> cell_data = merge_cell_data(frame);
  write_atomically(file, [&](std::ostream& out) { write_vtu_body(out, frame, cell_data); });
}

void write_obj(const std::filesystem::path& file, const Frame& frame) {
  validate_frame(file, frame);
  write_atomically(file, [&](std::ostream& out) { write_obj_body(out, frame); });
}

PvdSeries::PvdSeries(std::filesystem::path file) : file_(std::move(file)) {}

void PvdSeries::add(double time, const std::filesystem::path& vtu_file) {
  const auto refuse = [&](const std::string& problem) {
    throw InvalidInput("cannot add " + vtu_file.string() + " to " + file_.string() + ": " +
                       problem);
  };
  if (!std::isfinite(time)) refuse("its time is not finite");
  if (vtu_file.empty()) refuse("the frame's path is empty");
  std::error_code error;
  const fs::path absolute_pvd = fs::absolute(file_, error);
  if (error) refuse("cannot make the .pvd's path absolute: " + error.message());
  const fs::path absolute_vtu = fs::absolute(vtu_file, error);
  if (error) refuse("cannot make the frame's path absolute: " + error.message());
  const fs::path pvd_folder = absolute_pvd.parent_path().lexically_normal();
  const fs::path vtu = absolute_vtu.lexically_normal();
  fs::path relative = vtu.lexically_relative(pvd_folder);
  if (relative.empty()) relative = vtu;  // no relative path (another root): keep it absolute
  frames_.emplace_back(time, relative.generic_string());
}

void PvdSeries::write() const {
  write_atomically(file_, [&](std::ostream& out) {
    ChunkedText chunks(out);
    std::string& text = chunks.text();
    text += "<?xml version=\"1.0\"?>\n";
    text += "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n";
    text += "  <Collection>\n";
    for (const auto& [time, relative_file] : frames_) {
      text += "    <DataSet timestep=\"";
      append_number(text, time);
      text += "\" group=\"\" part=\"0\" file=\"" + xml_escaped(relative_file) + "\"/>\n";
      chunks.maybe_flush();
    }
    text += "  </Collection>\n";
    text += "</VTKFile>\n";
    chunks.flush();
  });
}

}  // namespace tessera::io
