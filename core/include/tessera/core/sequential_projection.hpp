// The classic sequential PBD loop over a constraint batch: the reference the parallel solver
// modes are compared against, for results and for speed.
//
// One thread, the constraints of [begin, end) in input order, each projected by the scalar
// API (tessera::PositionBasedDynamics, tessera::XPBD) on the positions as they are at that
// moment, and its corrections added to its movable particles before the next constraint is
// evaluated (Gauss–Seidel in input order), as the classic PBD library's solver loop does.
// Unlike the batched kernels (project_<family>_constraints), the constraints of a range may
// share particles freely: no colouring is needed.
//
// Every overload reads the batch's stored rest data and parameters exactly as the family's
// batched kernel interprets them, so on constraints that share no movable particle it gives
// the batched kernel's result up to rounding (the two evaluate the same formula, with
// different instruction sequences). Particles with inverse mass 0 are never written.
// Each overload checks the range and the particle count once (check_projection_range) and
// throws InvalidInput when they are wrong.
#pragma once

#include <cstddef>

#include <tessera/core/constraint_batch.hpp>
#include <tessera/core/dihedral_constraints.hpp>
#include <tessera/core/distance_constraints.hpp>
#include <tessera/core/fem_tetra_constraints.hpp>
#include <tessera/core/fem_triangle_constraints.hpp>
#include <tessera/core/isometric_bending_constraints.hpp>
#include <tessera/core/particle_state.hpp>
#include <tessera/core/particle_tet_contact_constraints.hpp>
#include <tessera/core/proximity_distance_constraints.hpp>
#include <tessera/core/shape_matching_constraints.hpp>
#include <tessera/core/strain_tetra_constraints.hpp>
#include <tessera/core/strain_triangle_constraints.hpp>
#include <tessera/core/volume_constraints.hpp>

namespace tessera {

/// Distance: stiffness semantics → PositionBasedDynamics::solve_DistanceConstraint with
/// (rest_length, stiffness); compliance semantics → XPBD::solve_DistanceConstraint with
/// (rest_length, compliance, settings.dt, lambda).
void project_sequentially(ParticleArrays particles, DistanceConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings);

/// Dihedral: PositionBasedDynamics::solve_DihedralConstraint with (rest_angle, stiffness), or
/// XPBD::solve_DihedralConstraint with (rest_angle, compliance, settings.dt, lambda).
void project_sequentially(ParticleArrays particles, DihedralConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings);

/// Volume: PositionBasedDynamics::solve_VolumeConstraint with (rest_volume, stiffness), or
/// XPBD::solve_VolumeConstraint with (rest_volume, compliance, settings.dt, lambda).
void project_sequentially(ParticleArrays particles, VolumeConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings);

/// Isometric bending: PositionBasedDynamics::solve_IsometricBendingConstraint with
/// (Q = batch.matrix(c), stiffness), or XPBD::solve_IsometricBendingConstraint with
/// (Q, compliance, settings.dt, lambda). Q = k kᵀ is rebuilt from the stored factor k.
void project_sequentially(ParticleArrays particles, IsometricBendingConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings);

/// Point–edge distance: PositionBasedDynamics::solve_EdgePointDistanceConstraint with
/// (rest_distance, compression_stiffness, stretch_stiffness). Stiffness semantics only, like
/// project_edge_point_distance_constraints: compliance semantics throw InvalidInput (the
/// family has no XPBD form).
void project_sequentially(ParticleArrays particles, const EdgePointDistanceConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings = {});

/// Point–triangle distance: PositionBasedDynamics::solve_TrianglePointDistanceConstraint with
/// (rest_distance, compression_stiffness, stretch_stiffness). Stiffness semantics only
/// (compliance throws InvalidInput, as in the batched kernel).
void project_sequentially(ParticleArrays particles,
                          const TrianglePointDistanceConstraints& batch, std::size_t begin,
                          std::size_t end, const ProjectionSettings& settings = {});

/// Edge–edge distance: PositionBasedDynamics::solve_EdgeEdgeDistanceConstraint with
/// (rest_distance, compression_stiffness, stretch_stiffness). Stiffness semantics only
/// (compliance throws InvalidInput, as in the batched kernel).
void project_sequentially(ParticleArrays particles, const EdgeEdgeDistanceConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings = {});

/// Strain triangle: PositionBasedDynamics::solve_StrainTriangleConstraint with
/// (invRestMat from rest_inverse, xx/yy/xy_stiffness, normalize_stretch, normalize_shear).
/// No XPBD form: the PBD form under either semantics (settings are not used).
void project_sequentially(ParticleArrays particles, const StrainTriangleConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings);

/// Strain tetrahedron: PositionBasedDynamics::solve_StrainTetraConstraint with
/// (invRestMat from rest_inverse, stretch_stiffness[0..2], shear_stiffness[0..2] = xy, xz, yz,
/// normalize_stretch, normalize_shear). No XPBD form: the PBD form under either semantics.
void project_sequentially(ParticleArrays particles, const StrainTetraConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings);

/// FEM triangle: PositionBasedDynamics::solve_FEMTriangleConstraint with (area, invRestMat,
/// youngs_modulus_x/y/shear, poisson_ratio_xy/yx). No XPBD form: the PBD form under either
/// semantics.
void project_sequentially(ParticleArrays particles, const FEMTriangleConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings);

/// FEM tetrahedron: PositionBasedDynamics::solve_FEMTetraConstraint with (volume, invRestMat,
/// youngs_modulus, poisson_ratio, handle_inversion), or XPBD::solve_FEMTetraConstraint with
/// (volume, invRestMat, poisson_ratio, compliance, handle_inversion, settings.dt, lambda).
void project_sequentially(ParticleArrays particles, FEMTetraConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings);

/// Shape matching, one cluster after another: PositionBasedDynamics::
/// solve_ShapeMatchingConstraint with the cluster's rest shape in centre-of-mass coordinates
/// (x0 = the stored rest offsets q, restCm = 0, so x0 - restCm is q exactly), the current
/// positions and inverse masses of its particles, stiffness and allow_stretch. PBD only, like
/// project_shape_matching_constraints: settings are not used. The scalar API weighs the
/// particles by their current inverse masses, the batch by the masses it was built with: the
/// two agree as long as the masses have not changed since the batch was built.
void project_sequentially(ParticleArrays particles, const ShapeMatchingConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings = {});

/// Particle–tet contacts, position solve only (friction stays with
/// solve_particle_tet_contact_velocities): PositionBasedDynamics::
/// solve_ParticleTetContactConstraint with the barycentric coordinates and a constraintInfo
/// rebuilt from the batch (col 0 normal, col 1 tangent, (0,2) effective_mass,
/// (1,2) max_tangential_impulse, (2,2) normal_speed), accumulating the batch's lambda. The
/// contact's multiplier rule is its own (clamped at 0): settings are not used.
void project_sequentially(ParticleArrays particles, ParticleTetContacts& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings = {});

}  // namespace tessera
