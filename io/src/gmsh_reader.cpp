// Gmsh .msh, ASCII 2.2 and 4.1 (read_gmsh, see mesh_readers.hpp): one GmshReader walks the
// sections, reads $Nodes and $Elements in the layout of the file's version, keeps triangles
// and tetrahedra (the corners of second-order ones) and skips every other section.
#include <tessera/io/mesh_readers.hpp>

#include <array>
#include <cstdint>
#include <fstream>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "line_reader.hpp"

namespace tessera::io {
using namespace detail;

namespace {

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

  /// A 4.1 section ($Nodes or $Elements) read entity block by entity block: the records its
  /// header declares, those its blocks held so far, and its names for the messages.
  struct BlockSection {
    std::string_view name;  // "Nodes"
    std::string_view singular;
    std::string_view plural;
    std::uint64_t declared = 0;
    std::uint64_t read = 0;
  };

  struct EntityBlock {
    std::uint64_t dimension;
    std::uint64_t third;  // $Nodes: the parametric flag; $Elements: the element type
    std::uint64_t count;
  };

  /// The header line of entity block `block` (of `block_count`): '<entity dimension> <entity
  /// tag> <third> <number of records>'. Checks the dimension (0 to 3), the tag, the third value
  /// (0 or 1 when `third_is_flag`) and that the block holds no more than the section has left.
  EntityBlock read_entity_block(const BlockSection& section, std::uint64_t block_count,
                                std::uint64_t block, std::string_view third_layout,
                                std::string_view third_name, bool third_is_flag) {
    next_record_in(section.name, Progress{block_count, block, "entity blocks", {}});
    const Location where = reader_.here();
    if (words_.size() != 4) {
      where.fail("expected an entity block header '<entity dimension> <entity tag> <" +
                 std::string(third_layout) + "> <number of " + std::string(section.plural) +
                 ">', found " + counted(words_.size(), "value", "values"));
    }
    EntityBlock entity{};
    entity.dimension = parse_unsigned(words_[0], "entity dimension", where);
    if (entity.dimension > 3)
      where.fail("entity dimension " + std::to_string(entity.dimension) + " is not 0, 1, 2 or 3");
    parse_signed(words_[1], "entity tag", where);
    entity.third = parse_unsigned(words_[2], third_name, where);
    if (third_is_flag && entity.third > 1)
      where.fail(std::string(third_name) + " " + std::to_string(entity.third) + " is not 0 or 1");
    entity.count = parse_unsigned(
        words_[3], "number of " + std::string(section.plural) + " in the block", where);
    const std::uint64_t left = section.declared - section.read;
    if (entity.count > left) {
      where.fail("the entity block holds " +
                 counted(entity.count, section.singular, section.plural) + ", more than the " +
                 std::to_string(left) + " left of the " + std::to_string(section.declared) +
                 " the $" + std::string(section.name) + " header declares");
    }
    return entity;
  }

  /// After the last block: the blocks held as many records as the header declared.
  void check_blocks_hold_all(const BlockSection& section) {
    if (section.read != section.declared) {
      reader_.fail("the $" + std::string(section.name) + " header declares " +
                   counted(section.declared, section.singular, section.plural) +
                   " but its blocks hold " + std::to_string(section.read));
    }
  }

  void read_nodes_v4() {
    std::uint64_t header[4] = {};
    read_section_header("Nodes", 4,
                        "<number of entity blocks> <number of nodes> <min tag> <max tag>", header);
    const std::uint64_t block_count = header[0];
    const std::uint64_t node_count = header[1];
    reserve_at_most(mesh_.positions, node_count);
    std::vector<std::uint64_t> block_tags;
    BlockSection nodes{"Nodes", "node", "nodes", node_count};
    std::uint64_t& read = nodes.read;
    for (std::uint64_t block = 0; block < block_count; ++block) {
      const EntityBlock entity =
          read_entity_block(nodes, block_count, block, "parametric", "parametric flag", true);
      const std::uint64_t dimension = entity.dimension, parametric = entity.third;
      const std::uint64_t in_block = entity.count;
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
    check_blocks_hold_all(nodes);
    expect_section_end("Nodes", counted(node_count, "node", "nodes"));
  }

  void read_elements_v4() {
    std::uint64_t header[4] = {};
    read_section_header("Elements", 4,
                        "<number of entity blocks> <number of elements> <min tag> <max tag>",
                        header);
    const std::uint64_t block_count = header[0];
    const std::uint64_t element_count = header[1];
    BlockSection elements{"Elements", "element", "elements", element_count};
    std::uint64_t& read = elements.read;
    for (std::uint64_t block = 0; block < block_count; ++block) {
      const EntityBlock entity =
          read_entity_block(elements, block_count, block, "element type", "element type", false);
      const GmshElementType* type = find_gmsh_element_type(entity.third);
      const std::uint64_t in_block = entity.count;
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
    check_blocks_hold_all(elements);
    expect_section_end("Elements", counted(element_count, "element", "elements"));
  }

  LineReader reader_;
  Version version_ = Version::v2;
  Mesh mesh_;
  std::unordered_map<std::uint64_t, VertexIndex> vertex_by_node_tag_;
  std::vector<std::string_view> words_;
};

}  // namespace

Mesh read_gmsh(std::istream& in, const std::string& name) { return GmshReader(in, name).read(); }

Mesh read_gmsh(const std::filesystem::path& file) {
  std::ifstream stream = open_for_reading(file);
  return read_gmsh(stream, file.string());
}

}  // namespace tessera::io
