// Models of the solver tests and benchmarks: a cloth lying in the xz plane with two corners
// pinned (distance + dihedral bending), and a tetrahedral bar along z with its z = 0 end
// fixed (FEM tetra, or volume + distance). Unit inverse mass per movable particle.
#pragma once

#include <cstddef>
#include <cstring>
#include <string>
#include <vector>

#include <tessera/coloring/colouring_statistics.hpp>
#include <tessera/coloring/run_colouring.hpp>
#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/io/generators.hpp>
#include <tessera/coloring/model_graph.hpp>
#include <tessera/core/model.hpp>
#include <tessera/parallel/solver.hpp>

namespace tessera::test {

enum class ClothBending { none, dihedral, isometric };

inline Model cloth_model(std::size_t columns, std::size_t rows,
                         ClothBending bending = ClothBending::dihedral,
                         Real bending_compliance = Real(1e-3),
                         Real distance_compliance = 0) {
  io::ClothGrid grid = io::make_cloth_grid(columns, rows, Real(1) / Real(columns - 1));
  for (Vector3r& p : grid.positions) p = Vector3r(p.x(), 0, p.y());
  std::vector<Real> inverse_masses(grid.vertex_count(), Real(1));
  inverse_masses[(rows - 1) * columns] = 0;
  inverse_masses[rows * columns - 1] = 0;
  Model model;
  model.particles = ParticleState(grid.positions, inverse_masses);
  model.constraints.distance = make_distance_constraints(
      {grid.edge_indices, grid.positions, Real(1), distance_compliance});
  if (bending == ClothBending::dihedral)
    model.constraints.dihedral = make_dihedral_constraints(
        {grid.bending_indices, grid.positions, Real(1), bending_compliance});
  if (bending == ClothBending::isometric)
    model.constraints.isometric_bending = make_isometric_bending_constraints(
        {grid.bending_indices, grid.positions, Real(1), bending_compliance});
  return model;
}

enum class BarMaterial { fem_tetra, volume_and_distance };

inline Model tet_bar_model(std::size_t x, std::size_t y, std::size_t z,
                           BarMaterial material = BarMaterial::fem_tetra,
                           Real youngs_modulus = Real(2e4)) {
  const io::TetrahedralBar bar = io::make_tetrahedral_bar(x, y, z, Real(0.1));
  std::vector<Real> inverse_masses(bar.vertex_count(), Real(1));
  for (std::size_t v = 0; v < bar.vertex_count(); ++v)
    if (bar.positions[v].z() == 0) inverse_masses[v] = 0;
  Model model;
  model.particles = ParticleState(bar.positions, inverse_masses);
  if (material == BarMaterial::fem_tetra) {
    model.constraints.fem_tetra = make_fem_tetra_constraints(
        {bar.tetrahedron_indices, bar.positions, youngs_modulus, Real(0.3), true});
  } else {
    model.constraints.volume =
        make_volume_constraints({bar.tetrahedron_indices, bar.positions});
    model.constraints.distance = make_distance_constraints({bar.edge_indices, bar.positions});
  }
  return model;
}

/// The colouring of a model by a built-in strategy.
inline Colouring colour_model(const Model& model, const char* strategy = "greedy",
                              ColouringOptions options = {}) {
  const ConstraintGraph graph = constraint_graph(model);
  return ColouringRegistry::with_builtin_strategies().get(strategy).colour(graph, options);
}

/// Every solver mode, for the tests that run each.
inline constexpr SolverMode kSolverModes[] = {SolverMode::gs, SolverMode::jacobi,
                                              SolverMode::hybrid, SolverMode::sequential};

inline std::string mode_name(SolverMode mode) { return std::string(solver_mode_name(mode)); }

/// A solver of the model: coloured by a built-in strategy (with the options' post-passes), or
/// without a colouring in sequential mode, which needs none.
inline Solver make_solver(const Model& model, SolverSettings settings, const char* strategy = "greedy",
                          ColouringOptions options = {}) {
  if (settings.mode == SolverMode::sequential) return Solver(model, settings);
  const ConstraintGraph graph = constraint_graph(model);
  return Solver(model,
                run_colouring(ColouringRegistry::with_builtin_strategies().get(strategy), graph,
                              options)
                    .colouring,
                settings);
}

/// Bitwise equality of two position arrays (determinism and "nothing changed" checks).
inline bool same_bits(const std::vector<Vector3r>& a, const std::vector<Vector3r>& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), a.size() * sizeof(Vector3r)) == 0;
}

}  // namespace tessera::test
