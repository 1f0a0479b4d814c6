// Fuzzes read_tetgen (stream overloads) with arbitrary bytes split into the .node, .ele and
// (optional) .face files at the first and second NUL byte: "node\0ele" or "node\0ele\0face".
// The seeds are real file triples joined that way. InvalidInput is the expected answer to
// bad input; a crash, a sanitizer report, a hang, an oversized allocation or a mesh that
// breaks check_mesh's invariants is a finding.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>
#include <string_view>

#include <tessera/core/error.hpp>
#include <tessera/io/mesh_readers.hpp>

#include "mesh_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const std::size_t first = bytes.find('\0');
  const std::string_view node = bytes.substr(0, first);
  const std::string_view rest =
      first == std::string_view::npos ? std::string_view() : bytes.substr(first + 1);
  const std::size_t second = rest.find('\0');
  const std::string_view ele = rest.substr(0, second);
  try {
    std::istringstream node_in{std::string(node)}, ele_in{std::string(ele)};
    if (second == std::string_view::npos) {
      tessera::fuzz::check_mesh(
          tessera::io::read_tetgen(node_in, ele_in, "fuzz.node", "fuzz.ele"));
    } else {
      std::istringstream face_in{std::string(rest.substr(second + 1))};
      tessera::fuzz::check_mesh(tessera::io::read_tetgen(node_in, ele_in, face_in, "fuzz.node",
                                                         "fuzz.ele", "fuzz.face"));
    }
  } catch (const tessera::InvalidInput&) {
  }
  return 0;
}
