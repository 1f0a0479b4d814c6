// What every successfully read mesh must satisfy, whatever bytes it came from: finite
// positions, whole elements, every index in range. A violation aborts (a fuzz finding).
#pragma once

#include <cstdio>
#include <cstdlib>

#include <tessera/io/mesh_readers.hpp>

namespace tessera::fuzz {

inline void require(bool condition, const char* what) {
  if (!condition) {
    std::fprintf(stderr, "fuzz: mesh invariant violated: %s\n", what);
    std::abort();
  }
}

inline void check_mesh(const io::Mesh& mesh) {
  for (const Vector3r& p : mesh.positions) require(p.allFinite(), "a position is not finite");
  require(mesh.triangles.size() % 3 == 0, "triangle indices are not a multiple of 3");
  require(mesh.tetrahedra.size() % 4 == 0, "tetrahedron indices are not a multiple of 4");
  for (const io::VertexIndex v : mesh.triangles)
    require(v < mesh.vertex_count(), "a triangle index is out of range");
  for (const io::VertexIndex v : mesh.tetrahedra)
    require(v < mesh.vertex_count(), "a tetrahedron index is out of range");
}

}  // namespace tessera::fuzz
