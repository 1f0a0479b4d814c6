// What the schedule and the solver need to know of each constraint family, in one place:
//
//   per_constraint_arrays(batch)  every array indexed by constraint (rest data, parameters, λ),
//                                 as a tuple of references, so a batch can be reordered
//                                 without naming its fields;
//   project_batch(...)            the family's batched SIMD kernel over [begin, end);
//   lambda_of(batch)              its XPBD multipliers (nullptr for families without them).
//
// Shape matching is the one family whose particles are not one slot array per particle
// (clusters are CSR), so the reordering code treats it separately (schedule.cpp).
#pragma once

#include <array>
#include <cstddef>
#include <tuple>
#include <type_traits>

#include <tessera/parallel/model.hpp>

namespace tessera::detail {

inline auto per_constraint_arrays(DistanceConstraints& b) {
  return std::tie(b.rest_length, b.stiffness, b.compliance, b.lambda);
}
inline auto per_constraint_arrays(DihedralConstraints& b) {
  return std::tie(b.rest_angle, b.stiffness, b.compliance, b.lambda);
}
inline auto per_constraint_arrays(IsometricBendingConstraints& b) {
  return std::tie(b.factor, b.stiffness, b.compliance, b.lambda);
}
inline auto per_constraint_arrays(VolumeConstraints& b) {
  return std::tie(b.rest_volume, b.stiffness, b.compliance, b.lambda);
}
template <ProximityKind Kind>
auto per_constraint_arrays(ProximityDistanceConstraints<Kind>& b) {
  return std::tie(b.rest_distance, b.compression_stiffness, b.stretch_stiffness);
}
inline auto per_constraint_arrays(StrainTriangleConstraints& b) {
  return std::tie(b.rest_inverse, b.xx_stiffness, b.yy_stiffness, b.xy_stiffness);
}
inline auto per_constraint_arrays(StrainTetraConstraints& b) {
  return std::tie(b.rest_inverse, b.stretch_stiffness, b.shear_stiffness);
}
inline auto per_constraint_arrays(FEMTriangleConstraints& b) {
  return std::tie(b.area, b.rest_inverse, b.youngs_modulus_x, b.youngs_modulus_y,
                  b.youngs_modulus_shear, b.poisson_ratio_xy, b.poisson_ratio_yx);
}
inline auto per_constraint_arrays(FEMTetraConstraints& b) {
  return std::tie(b.volume, b.rest_inverse, b.youngs_modulus, b.poisson_ratio, b.compliance,
                  b.lambda);
}
/// Shape matching: the per-cluster arrays (its per-entry arrays are handled with the CSR).
inline auto per_constraint_arrays(ShapeMatchingConstraints& b) {
  return std::tie(b.rest_centre, b.inverse_rest_moment, b.stiffness);
}

inline Real* lambda_of(DistanceConstraints& b) { return b.lambda.data(); }
inline Real* lambda_of(DihedralConstraints& b) { return b.lambda.data(); }
inline Real* lambda_of(IsometricBendingConstraints& b) { return b.lambda.data(); }
inline Real* lambda_of(VolumeConstraints& b) { return b.lambda.data(); }
inline Real* lambda_of(FEMTetraConstraints& b) { return b.lambda.data(); }
template <class Batch>
Real* lambda_of(Batch&) {
  return nullptr;
}

/// The settings a family is projected with: the proximity families have no XPBD form, so the
/// solver projects them with their PBD stiffness under either semantics (as the strain, FEM
/// triangle and shape-matching kernels do by themselves); the others as given.
template <class Batch>
ProjectionSettings settings_for(const Batch&, const ProjectionSettings& settings) {
  if constexpr (requires(Batch b) { b.compression_stiffness; })
    return {ConstraintSemantics::stiffness, settings.dt};
  else
    return settings;
}

inline void project_batch(ParticleArrays p, DistanceConstraints& b, std::size_t begin,
                          std::size_t end, const ProjectionSettings& s) {
  project_distance_constraints(p, b, begin, end, s);
}
inline void project_batch(ParticleArrays p, DihedralConstraints& b, std::size_t begin,
                          std::size_t end, const ProjectionSettings& s) {
  project_dihedral_constraints(p, b, begin, end, s);
}
inline void project_batch(ParticleArrays p, IsometricBendingConstraints& b, std::size_t begin,
                          std::size_t end, const ProjectionSettings& s) {
  project_isometric_bending_constraints(p, b, begin, end, s);
}
inline void project_batch(ParticleArrays p, VolumeConstraints& b, std::size_t begin,
                          std::size_t end, const ProjectionSettings& s) {
  project_volume_constraints(p, b, begin, end, s);
}
inline void project_batch(ParticleArrays p, EdgePointDistanceConstraints& b, std::size_t begin,
                          std::size_t end, const ProjectionSettings& s) {
  project_edge_point_distance_constraints(p, b, begin, end, settings_for(b, s));
}
inline void project_batch(ParticleArrays p, TrianglePointDistanceConstraints& b,
                          std::size_t begin, std::size_t end, const ProjectionSettings& s) {
  project_triangle_point_distance_constraints(p, b, begin, end, settings_for(b, s));
}
inline void project_batch(ParticleArrays p, EdgeEdgeDistanceConstraints& b, std::size_t begin,
                          std::size_t end, const ProjectionSettings& s) {
  project_edge_edge_distance_constraints(p, b, begin, end, settings_for(b, s));
}
inline void project_batch(ParticleArrays p, StrainTriangleConstraints& b, std::size_t begin,
                          std::size_t end, const ProjectionSettings& s) {
  project_strain_triangle_constraints(p, b, begin, end, s);
}
inline void project_batch(ParticleArrays p, StrainTetraConstraints& b, std::size_t begin,
                          std::size_t end, const ProjectionSettings& s) {
  project_strain_tetra_constraints(p, b, begin, end, s);
}
inline void project_batch(ParticleArrays p, FEMTriangleConstraints& b, std::size_t begin,
                          std::size_t end, const ProjectionSettings& s) {
  project_fem_triangle_constraints(p, b, begin, end, s);
}
inline void project_batch(ParticleArrays p, FEMTetraConstraints& b, std::size_t begin,
                          std::size_t end, const ProjectionSettings& s) {
  project_fem_tetra_constraints(p, b, begin, end, s);
}
inline void project_batch(ParticleArrays p, ShapeMatchingConstraints& b, std::size_t begin,
                          std::size_t end, const ProjectionSettings&) {
  project_shape_matching_constraints(p, b, begin, end);
}

/// Particles per constraint of a fixed-arity family (0 for shape matching).
template <class Batch>
constexpr std::size_t arity_of() {
  if constexpr (std::is_same_v<Batch, ShapeMatchingConstraints>)
    return 0;
  else
    return decltype(Batch::particles)::kParticlesPerConstraint;
}

/// The batch of `sets` of the same family (type) as `like`.
template <class Batch>
const Batch& same_family(const ConstraintSets& sets, const Batch& /*like*/) {
  const Batch* found = nullptr;
  sets.for_each([&](ConstraintFamily, const auto& batch) {
    if constexpr (std::is_same_v<std::decay_t<decltype(batch)>, Batch>) found = &batch;
  });
  return *found;
}

}  // namespace tessera::detail
