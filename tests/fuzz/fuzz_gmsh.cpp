// Fuzzes read_gmsh (stream overload) with arbitrary bytes: InvalidInput is the expected answer
// to bad input; a crash, a sanitizer report, a hang, an oversized allocation or a mesh that
// breaks check_mesh's invariants is a finding.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include <tessera/core/error.hpp>
#include <tessera/io/mesh_readers.hpp>

#include "mesh_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    tessera::fuzz::check_mesh(tessera::io::read_gmsh(in, "fuzz.msh"));
  } catch (const tessera::InvalidInput&) {
  }
  return 0;
}
