// FrameOutput (see frame_output.hpp): the cells of a scene are gathered once, at
// construction (the surface, then one cell per constraint of the families that have a cell
// type, with its colour, family and id), and every write() pairs them with the frame's
// positions and writes frame_NNNNN.vtu (and .obj), then rewrites frames.pvd.
#include "frame_output.hpp"

#include <cstdio>
#include <stdexcept>
#include <string>
#include <system_error>

#include <tessera/core/error.hpp>

namespace tessera::cli {
namespace {

std::filesystem::path frame_file(const std::filesystem::path& folder, std::size_t frame,
                                 const char* extension) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05zu.%s", frame, extension);
  return folder / name;
}

}  // namespace

FrameOutput::FrameOutput(std::filesystem::path folder, const io::Scene& scene,
                         const Colouring* colouring, bool write_obj)
    : folder_(std::move(folder)), series_(folder_ / "frames.pvd"), write_obj_(write_obj) {
  std::error_code error;
  if (!std::filesystem::exists(folder_, error)) {
    if (!std::filesystem::create_directory(folder_, error) || error)
      throw InvalidInput("--out: cannot create folder " + folder_.string() + ": " +
                         (error ? error.message() : std::string("unknown error")));
  } else if (!std::filesystem::is_directory(folder_, error)) {
    throw InvalidInput("--out: " + folder_.string() + " exists and is not a folder");
  }

  const ParticleState& particles = scene.model.particles;
  particle_count_ = particles.size();
  inverse_mass_.resize(particles.size());
  for (std::size_t p = 0; p < particles.size(); ++p) inverse_mass_[p] = particles.inverse_mass[p];

  Cells surface{io::CellType::triangle, scene.surface_triangles, {}, {}, {}};
  const std::size_t surface_cells = surface.vertices.size() / 3;
  surface.colour.assign(surface_cells, -1);
  surface.family.assign(surface_cells, -1);
  surface.constraint.assign(surface_cells, -1);
  cells_.push_back(std::move(surface));
  add_constraint_cells(scene.model, colouring);
}

void FrameOutput::add_constraint_cells(const Model& model, const Colouring* colouring) {
  Cells lines{io::CellType::line, {}, {}, {}, {}};
  Cells triangles{io::CellType::triangle, {}, {}, {}, {}};
  Cells tetrahedra{io::CellType::tetrahedron, {}, {}, {}, {}};
  const auto add = [&](Cells& cells, ConstraintFamily family, std::size_t index,
                       std::initializer_list<io::VertexIndex> vertices) {
    const ConstraintIndex id = model.constraint_id(family, index);
    cells.vertices.insert(cells.vertices.end(), vertices);
    cells.colour.push_back(colouring ? std::int32_t(colouring->colour_of(id)) : -1);
    cells.family.push_back(std::int32_t(family));
    cells.constraint.push_back(std::int32_t(id));
  };
  // Each family says how it is drawn (kTraits.cell, constraint_families.hpp).
  model.constraints.for_each([&](ConstraintFamily family, const auto& batch) {
    using Batch = std::decay_t<decltype(batch)>;
    constexpr CellShape shape = Batch::kTraits.cell;
    if constexpr (shape != CellShape::none) {
      const auto& p = batch.particles.particle;
      for (std::size_t c = 0; c < batch.size(); ++c) {
        if constexpr (shape == CellShape::segment)
          add(lines, family, c, {p[0][c], p[1][c]});
        else if constexpr (shape == CellShape::hinge)
          add(lines, family, c, {p[2][c], p[3][c]});
        else if constexpr (shape == CellShape::triangle)
          add(triangles, family, c, {p[0][c], p[1][c], p[2][c]});
        else
          add(tetrahedra, family, c, {p[0][c], p[1][c], p[2][c], p[3][c]});
      }
    }
  });
  for (Cells* cells : {&lines, &triangles, &tetrahedra})
    if (!cells->colour.empty()) cells_.push_back(std::move(*cells));
}

void FrameOutput::write(std::size_t frame, double time, std::span<const Vector3r> positions,
                        std::span<const Real> contacts) {
  io::Frame data;
  data.positions = positions;
  data.point_data.emplace_back("inverse_mass", inverse_mass_);
  if (!contacts.empty()) {
    if (contacts.size() != particle_count_)
      throw std::logic_error("FrameOutput: contact counts for " + std::to_string(contacts.size()) +
                             " particles, the scene has " + std::to_string(particle_count_));
    data.point_data.emplace_back("contacts", contacts);
  }
  for (const Cells& cells : cells_) {
    io::CellBlock block{cells.type, cells.vertices, {}};
    block.cell_data.emplace_back("colour", cells.colour);
    block.cell_data.emplace_back("family", cells.family);
    block.cell_data.emplace_back("constraint", cells.constraint);
    data.blocks.push_back(std::move(block));
  }
  const std::filesystem::path vtu = frame_file(folder_, frame, "vtu");
  io::write_vtu(vtu, data);
  ++files_written_;
  series_.add(time, vtu);
  series_.write();
  if (write_obj_) {
    data.blocks.resize(1);  // the surface
    io::write_obj(frame_file(folder_, frame, "obj"), data);
    ++files_written_;
  }
}

std::vector<Real> contacts_per_particle(const Solver& solver) {
  const std::vector<std::uint32_t> counts = solver.contact_counts();
  return std::vector<Real>(counts.begin(), counts.end());
}

}  // namespace tessera::cli
