// `tessera run --out DIR`: every frame as a VTK .vtu (listed in DIR/frames.pvd for ParaView)
// and, with --obj, as a Wavefront .obj of the surface.
//
// What a .vtu holds, so a user sees the colouring on the mesh:
//   points      the particles (user numbering), point data "inverse_mass" (0 = pinned) and,
//               when the run has a collision stage, "contacts": how many contacts of the
//               frame's last substep hold the particle (collider, self and solid contacts)
//   cells       block 1: the surface triangles (of a shell, or the boundary of a solid)
//               block 2: one line per distance constraint, and per bending constraint its
//                        hinge edge (dihedral, isometric bending)
//               block 3: one triangle per strain or FEM triangle constraint
//               block 4: one tetrahedron per volume, strain or FEM tetra constraint
//   cell data   "colour"      the constraint's colour (-1 for surface cells, and in mode
//                             sequential, which colours nothing)
//               "family"      the constraint's ConstraintFamily number (-1: surface)
//               "constraint"  its global constraint id (-1: surface)
// In ParaView: colour by "colour", and threshold "family" to see one family at a time.
// Shape matching and the proximity families have no cell of their own.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

#include <tessera/coloring/colouring.hpp>
#include <tessera/io/mesh_writers.hpp>
#include <tessera/io/scene_file.hpp>
#include <tessera/parallel/solver.hpp>

namespace tessera::cli {

class FrameOutput {
 public:
  /// Creates `folder` if it does not exist (its parent must). `colouring` may be null (mode
  /// sequential). Throws InvalidInput naming the folder if it cannot be used.
  FrameOutput(std::filesystem::path folder, const io::Scene& scene, const Colouring* colouring,
              bool write_obj);

  /// Writes frame `frame` at `time` and rewrites the .pvd so it lists it. `contacts` (one
  /// per particle, or empty for none) becomes the point data "contacts".
  void write(std::size_t frame, double time, std::span<const Vector3r> positions,
             std::span<const Real> contacts = {});

  std::size_t files_written() const { return files_written_; }
  const std::filesystem::path& folder() const { return folder_; }

 private:
  /// One block's cells and its three cell-data arrays.
  struct Cells {
    io::CellType type;
    std::vector<io::VertexIndex> vertices;
    std::vector<std::int32_t> colour, family, constraint;
  };
  void add_constraint_cells(const Model& model, const Colouring* colouring);

  std::filesystem::path folder_;
  io::PvdSeries series_;
  bool write_obj_;
  std::vector<Real> inverse_mass_;
  std::size_t particle_count_ = 0;
  std::vector<Cells> cells_;
  std::size_t files_written_ = 0;
};

/// How many contacts of the solver's last substep hold each particle, in the user's
/// numbering (a contact counts once for every particle it moves, static sides included).
std::vector<Real> contacts_per_particle(const Solver& solver);

}  // namespace tessera::cli
