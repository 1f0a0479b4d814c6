// A model: what the solver simulates. Particles (SoA, the user's numbering) and one batch per
// constraint family, each built and validated by make_<family>_constraints. Core types only,
// so scene generators and mesh readers (io) can build models without the solver.
//
//   Model ──► constraint_graph(model) ──► a ColouringStrategy ──► Colouring
//         ──► Solver(model, colouring)                      (coloring/ and parallel/)
//
// Constraints have a global id: the families' constraints concatenated in the fixed order
// of ConstraintFamily (all distance constraints first, then dihedral, ...). The constraint
// graph, the colouring and the solver's lookups (lambda, residuals) all speak of that id.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <utility>

#include <tessera/core/dihedral_constraints.hpp>
#include <tessera/core/distance_constraints.hpp>
#include <tessera/core/fem_tetra_constraints.hpp>
#include <tessera/core/indices.hpp>
#include <tessera/core/fem_triangle_constraints.hpp>
#include <tessera/core/isometric_bending_constraints.hpp>
#include <tessera/core/particle_state.hpp>
#include <tessera/core/proximity_distance_constraints.hpp>
#include <tessera/core/shape_matching_constraints.hpp>
#include <tessera/core/strain_tetra_constraints.hpp>
#include <tessera/core/strain_triangle_constraints.hpp>
#include <tessera/core/volume_constraints.hpp>

namespace tessera {

/// The constraint families a model holds, in global-id order.
enum class ConstraintFamily : std::uint8_t {
  distance,
  dihedral,
  isometric_bending,
  volume,
  edge_point_distance,
  triangle_point_distance,
  edge_edge_distance,
  strain_triangle,
  strain_tetra,
  fem_triangle,
  fem_tetra,
  shape_matching,
};
inline constexpr std::size_t kConstraintFamilyCount = 12;

/// "distance", "dihedral", "isometric_bending", ... (the names the tool and reports use).
std::string_view family_name(ConstraintFamily family);

/// One batch per family; an empty batch (the default) holds no constraints.
struct ConstraintSets {
  DistanceConstraints distance;
  DihedralConstraints dihedral;
  IsometricBendingConstraints isometric_bending;
  VolumeConstraints volume;
  EdgePointDistanceConstraints edge_point_distance;
  TrianglePointDistanceConstraints triangle_point_distance;
  EdgeEdgeDistanceConstraints edge_edge_distance;
  StrainTriangleConstraints strain_triangle;
  StrainTetraConstraints strain_tetra;
  FEMTriangleConstraints fem_triangle;
  FEMTetraConstraints fem_tetra;
  ShapeMatchingConstraints shape_matching;

  /// Calls visit(family, batch) for every family, in ConstraintFamily order.
  template <class Visit>
  void for_each(Visit&& visit) {
    visit(ConstraintFamily::distance, distance);
    visit(ConstraintFamily::dihedral, dihedral);
    visit(ConstraintFamily::isometric_bending, isometric_bending);
    visit(ConstraintFamily::volume, volume);
    visit(ConstraintFamily::edge_point_distance, edge_point_distance);
    visit(ConstraintFamily::triangle_point_distance, triangle_point_distance);
    visit(ConstraintFamily::edge_edge_distance, edge_edge_distance);
    visit(ConstraintFamily::strain_triangle, strain_triangle);
    visit(ConstraintFamily::strain_tetra, strain_tetra);
    visit(ConstraintFamily::fem_triangle, fem_triangle);
    visit(ConstraintFamily::fem_tetra, fem_tetra);
    visit(ConstraintFamily::shape_matching, shape_matching);
  }
  template <class Visit>
  void for_each(Visit&& visit) const {
    const_cast<ConstraintSets&>(*this).for_each(
        [&](ConstraintFamily family, auto& batch) { visit(family, std::as_const(batch)); });
  }

  /// Constraints per family, in ConstraintFamily order.
  std::array<std::size_t, kConstraintFamilyCount> sizes() const;
  std::size_t size() const;
};

struct Model {
  ParticleState particles;
  ConstraintSets constraints;

  /// The global id of constraint `index` of `family`.
  ConstraintIndex constraint_id(ConstraintFamily family, std::size_t index) const;
};

}  // namespace tessera
