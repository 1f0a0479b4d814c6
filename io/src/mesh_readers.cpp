// read_mesh: the reader for a file picked by its extension. The readers themselves are one
// file per format (obj_reader.cpp, tetgen_reader.cpp, gmsh_reader.cpp) over the shared line
// reader and number parsers of line_reader.hpp.
#include <tessera/io/mesh_readers.hpp>

#include <string>

#include <tessera/core/error.hpp>

#include "line_reader.hpp"

namespace tessera::io {
using namespace detail;

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
