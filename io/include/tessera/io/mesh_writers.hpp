// Frame writers: a simulation state (positions, cells, per-point and per-cell data) written
// as a VTK XML UnstructuredGrid (.vtu) for ParaView, a ParaView collection (.pvd) that lists
// the frames of a run with their times, or a Wavefront OBJ of the triangles.
//
// Used by embedders that want to look at their meshes and by `tessera run --out DIR`. Only
// the standard library is used (no VTK). The writers take views (std::span) of the caller's
// arrays, so writing a frame copies nothing but the text.
//
// Every writer validates the whole frame before it touches the file system and writes
// atomically: the text goes to a temporary file beside the target
// (`<name>.tmp-<16 hex digits>`), which is flushed, closed, checked and only then renamed over
// the target. A reader (ParaView polling a folder, a crash mid-write) therefore sees either
// the old complete file or the new complete file, never a truncated one; on any failure the
// temporary is removed and the target is left as it was. The rename makes the replacement
// atomic, not durable: nothing is fsync'ed (the standard library cannot), so a power loss may
// lose the newest frame.
//
// Directories are never created: writing into a folder that does not exist is an error (a
// mistyped --out should not scatter folders). Create the folder first.
//
// All errors are tessera::InvalidInput with the message "cannot write <file>: <problem>".
// The library never prints. The free functions may run concurrently (each call has its own
// temporary, so concurrent writers of one file leave one writer's complete frame); a
// PvdSeries, like a std::vector, is not to be used by two threads at once.
//
// If the target is a symbolic link, the rename replaces the link, not the file it points to.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <tessera/core/real.hpp>
#include <tessera/io/generators.hpp>  // VertexIndex

namespace tessera::io {

/// The kind of every cell of a CellBlock.
enum class CellType {
  line,         ///< 2 vertices, VTK_LINE (3): distance constraints, edges
  triangle,     ///< 3 vertices, VTK_TRIANGLE (5): cloth, FEM/strain triangles
  tetrahedron,  ///< 4 vertices, VTK_TETRA (10): volume, FEM/strain tetrahedra
};

/// Vertices per cell of a type: 2, 3 or 4.
constexpr std::size_t vertices_per_cell(CellType type) {
  switch (type) {
    case CellType::line: return 2;
    case CellType::triangle: return 3;
    case CellType::tetrahedron: return 4;
  }
  return 0;
}

/// The VTK cell type number of a type (VTK_LINE 3, VTK_TRIANGLE 5, VTK_TETRA 10).
constexpr std::uint8_t vtk_cell_type(CellType type) {
  switch (type) {
    case CellType::line: return 3;
    case CellType::triangle: return 5;
    case CellType::tetrahedron: return 10;
  }
  return 0;
}

/// One block of cells of one type, plus named integer cell data: one value per cell of this
/// block (e.g. "colour": each constraint's colour, so a user sees the colouring on the mesh).
struct CellBlock {
  CellType type = CellType::triangle;
  /// vertices_per_cell(type) indices per cell, cells back to back (the generators' layout).
  std::span<const VertexIndex> vertices;
  /// (name, values) pairs; names are unique within a block. The same name in several blocks
  /// is one array of the written mesh.
  std::vector<std::pair<std::string, std::span<const std::int32_t>>> cell_data;
};

/// One state of a mesh: points, cells in blocks, optional scalar point data.
struct Frame {
  std::span<const Vector3r> positions;
  /// Cells in block order: the written cells are block 0's, then block 1's, and so on.
  std::vector<CellBlock> blocks;
  /// (name, one value per point) pairs, e.g. inverse mass; names are unique.
  std::vector<std::pair<std::string, std::span<const Real>>> point_data;
};

/// Writes `frame` as a VTK XML UnstructuredGrid (.vtu), ASCII, one Piece. Points are
/// Float32 when Real is float and Float64 when it is double (printed with the shortest
/// digits that read back to the same value), connectivity and offsets are Int64, types UInt8.
///
/// Cell data: VTK needs one value per cell of the whole mesh, so every cell-data name of any
/// block becomes one Int32 array over all cells (in order of first appearance), and the cells
/// of blocks that do not have that array get -1.
///
/// Throws tessera::InvalidInput ("cannot write <file>: <problem>") before creating anything
/// when: a block's index count is not a multiple of its vertices per cell; an index is not
/// below positions.size(); a cell-data array has not one value per cell of its block; a
/// point-data array has not one value per point; a name is empty, repeated (within a block,
/// or among the point data) or contains one of < > & " ' or a control character; a position
/// or point-data value is not finite (the message names the point). Also throws when the
/// folder does not exist or the file cannot be written or renamed into place; then neither
/// the target nor a temporary is left changed or behind.
void write_vtu(const std::filesystem::path& file, const Frame& frame);

/// Wavefront OBJ of the positions ("v x y z", every point, in order) and the triangle blocks
/// ("f a b c", 1-based); line and tetrahedron blocks and all point and cell data are skipped.
/// The frame is validated and the file written exactly as by write_vtu (same errors, same
/// atomic write).
void write_obj(const std::filesystem::path& file, const Frame& frame);

/// A ParaView collection (.pvd) listing the frames written so far as (time, file) pairs,
/// in the order they were added. Typical use: write_vtu(frame_i), add(t_i, frame_i),
/// write(), so the .pvd on disk is complete and valid after every frame.
class PvdSeries {
 public:
  /// The collection file, e.g. out/frames.pvd. Nothing is written until write().
  explicit PvdSeries(std::filesystem::path file);

  /// Appends a frame at `time` (must be finite). `vtu_file` is a path as the caller would
  /// open it (absolute, or relative to the current folder); it is stored relative to the
  /// .pvd's folder (e.g. "frame_0003.vtu" or "frames/frame_0003.vtu"), with '/' separators,
  /// so the output folder can be moved as a whole. The .vtu need not exist yet.
  void add(double time, const std::filesystem::path& vtu_file);

  /// Rewrites the whole .pvd atomically (same scheme and errors as write_vtu).
  void write() const;

  const std::filesystem::path& file() const { return file_; }
  /// The frames added so far: (time, path relative to the .pvd's folder).
  const std::vector<std::pair<double, std::string>>& frames() const { return frames_; }

 private:
  std::filesystem::path file_;
  std::vector<std::pair<double, std::string>> frames_;
};

}  // namespace tessera::io
