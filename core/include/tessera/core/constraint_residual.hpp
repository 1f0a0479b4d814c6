// How far one constraint is from being satisfied, per family: the numbers the solver reports
// as the residual (RMS and max per family, before and after a run).
//
// Why one function per family: each family's raw C has its own units (metres, cubic metres,
// radians, energy), and a family's RMS must be comparable from one iteration to the next and
// between scenes of different size. So every overload returns a normalised violation ≥ 0 at
// the current positions, dimensionless wherever the family has a natural reference (rest
// length, rest volume, rest distance, the identity strain, the rest cluster size); the header
// comment of each overload names its measure and its units. Where the family's lane formula
// (core/src/kernels/<family>-inl.h) gives C, the residual is evaluated through it on one lane,
// so it is the violation the kernel itself sees.
//
// Every function is finite for finite positions, also for degenerate configurations (all
// particles at one point, a zero-length edge...): each comment says what such a configuration
// reads. Preconditions (not checked, as in every hot loop): c < batch.size(), and `particles`
// holds the particles the batch was built for.
#pragma once

#include <cstddef>

#include <tessera/core/dihedral_constraints.hpp>
#include <tessera/core/distance_constraints.hpp>
#include <tessera/core/fem_tetra_constraints.hpp>
#include <tessera/core/fem_triangle_constraints.hpp>
#include <tessera/core/isometric_bending_constraints.hpp>
#include <tessera/core/particle_state.hpp>
#include <tessera/core/particle_tet_contact_constraints.hpp>
#include <tessera/core/proximity_distance_constraints.hpp>
#include <tessera/core/real.hpp>
#include <tessera/core/shape_matching_constraints.hpp>
#include <tessera/core/strain_tetra_constraints.hpp>
#include <tessera/core/strain_triangle_constraints.hpp>
#include <tessera/core/volume_constraints.hpp>

namespace tessera {

/// Distance: relative stretch |‖p0 − p1‖ − l0| / l0 (dimensionless). Coincident particles
/// read 1. (A zero l0, which the builder rejects, would read |‖p0 − p1‖|.)
Real constraint_residual(const ParticleArrays& particles, const DistanceConstraints& batch,
                         std::size_t c);

/// Dihedral: |φ − φ0| in radians, φ ∈ [0, π] the angle between the wing normals exactly as
/// the dihedral formula computes it. A degenerate stencil (zero-length shared edge or a
/// zero-area wing) has no defined angle; it reads the formula's value there, φ = 0 for a
/// stencil collapsed to one point (so the residual is φ0), always finite and ≤ π.
Real constraint_residual(const ParticleArrays& particles, const DihedralConstraints& batch,
                         std::size_t c);

/// Volume: relative volume change |V − V0| / |V0| (dimensionless), V the signed volume
/// (1/6) ((p1 − p0) × (p2 − p0)) · (p3 − p0) with p0 the reference vertex, as in the
/// kernel; an inverted tetrahedron counts its full signed change (inverting a unit tet reads
/// 2). A flat or collapsed tetrahedron reads 1. (A zero V0, which the builder rejects,
/// would read |V|.)
Real constraint_residual(const ParticleArrays& particles, const VolumeConstraints& batch,
                         std::size_t c);

/// Isometric bending: |u| = |Σ_j k_j p_j| = sqrt(2C), the discrete mean-curvature vector of
/// the kernel's C = ½ |u|² (Q = k kᵀ). Dimensionless: k scales as 1/length (Q as 1/area), so
/// scaling a stencil leaves |u| unchanged, like the bending energy. The model assumes a flat
/// rest shape: a rigid motion of a flat rest stencil reads 0, while a curved rest stencil
/// reads its own rest curvature (the kernel's C is not 0 there either). A stencil collapsed
/// to one point reads 0.
Real constraint_residual(const ParticleArrays& particles,
                         const IsometricBendingConstraints& batch, std::size_t c);

/// Edge–point distance: |d − d0| / d0 with d the current point–segment distance (closest
/// point as in the kernel) and d0 the rest distance; |d| where d0 = 0. Dimensionless for
/// d0 > 0, a length for d0 = 0.
Real constraint_residual(const ParticleArrays& particles,
                         const EdgePointDistanceConstraints& batch, std::size_t c);

/// Triangle–point distance: |d − d0| / d0 (|d| where d0 = 0), d the current point–triangle
/// distance (a zero-area triangle is measured to its longest edge, as in the kernel).
Real constraint_residual(const ParticleArrays& particles,
                         const TrianglePointDistanceConstraints& batch, std::size_t c);

/// Edge–edge distance: |d − d0| / d0 (|d| where d0 = 0), d the current segment–segment
/// distance (closest pair as in the kernel).
Real constraint_residual(const ParticleArrays& particles,
                         const EdgeEdgeDistanceConstraints& batch, std::size_t c);

/// Strain triangle: ‖E‖_F, the Frobenius norm of the 2×2 Green strain E = ½ (FᵀF − I) with
/// F = [p1 − p0, p2 − p0] · invRestMat (3×2, p0 the reference vertex, as in the kernel).
/// Dimensionless; 0 for a rigid motion of the rest triangle. Note the family's convention:
/// the rest triangle is taken in the xy plane (init_StrainTriangleConstraint), so the rest
/// positions a batch was built from read 0 only when they lie in that plane. A triangle
/// collapsed to one point reads √2 / 2.
Real constraint_residual(const ParticleArrays& particles,
                         const StrainTriangleConstraints& batch, std::size_t c);

/// Strain tetrahedron: ‖E‖_F of the 3×3 Green strain E = ½ (FᵀF − I), F = [p1 − p0,
/// p2 − p0, p3 − p0] · invRestMat (p0 the reference vertex). Dimensionless; 0 at any rigid
/// motion of the rest shape (also of a mirrored one: Green strain does not see inversion).
/// A tetrahedron collapsed to one point reads √3 / 2.
Real constraint_residual(const ParticleArrays& particles, const StrainTetraConstraints& batch,
                         std::size_t c);

/// FEM triangle: ‖E‖_F of the 2×2 Green strain E = ½ (FᵀF − I), F = [p1 − p0, p2 − p0] ·
/// invRestMat in the triangle's own rest frame (any orientation in space), as in the kernel.
/// Dimensionless and independent of the material; collapsed to one point: √2 / 2.
Real constraint_residual(const ParticleArrays& particles, const FEMTriangleConstraints& batch,
                         std::size_t c);

/// FEM tetrahedron: ‖E‖_F of the 3×3 Green strain E = ½ (FᵀF − I), F = [p1 − p0, p2 − p0,
/// p3 − p0] · invRestMat (the kernel's F and ε; the plain strain even where the kernel's
/// inversion handling evaluates a clamped one, so a mirrored element reads 0). Dimensionless
/// and independent of the material; collapsed to one point: √3 / 2.
Real constraint_residual(const ParticleArrays& particles, const FEMTetraConstraints& batch,
                         std::size_t c);

/// Shape matching, c = the cluster: RMS_i |x_i − g_i| / RMS_i |q_i| (dimensionless), with
/// q_i the cluster's rest offsets, g_i = T q_i + centre the kernel's goal positions (centre
/// mass-weighted; T the kernel's rotation of A_pq, or A_pq A_qq⁻¹ when the batch allows
/// stretch) and both RMS plain averages over the cluster's particles. Rigid clusters: a
/// uniform scaling by s reads |s − 1|; where the kernel finds no rotation (A_pq of rank < 2,
/// e.g. the cluster collapsed to a point) the rotation its iteration still returns is used,
/// and since |R q_i| = |q_i| a cluster collapsed to one point reads 1. With stretch allowed,
/// any affine image of the rest cluster reads 0, a collapse to one point included (the zero
/// map matches it, and the kernel would not move it either). An empty cluster, or one whose
/// rest offsets are all zero, reads 0.
Real constraint_residual(const ParticleArrays& particles, const ShapeMatchingConstraints& batch,
                         std::size_t c);

/// Particle–tet contact: the penetration depth max(0, −C) in length units, C = n · (p0 −
/// Σ b_i x_i) the kernel's signed distance of the particle above the contact plane (stored
/// normal n and barycentric b). 0 while the particle is on the outer side.
Real constraint_residual(const ParticleArrays& particles, const ParticleTetContacts& batch,
                         std::size_t c);

// ------------------------------------------------------------------------------ batched
// constraint_residuals(particles, batch, begin, end, out): constraint_residual of constraints
// [begin, end), W at a time on the active SIMD target (the family's lane formula instantiated
// on Highway vectors, as the batched projection kernels run it), written to out[c − begin]
// for each c. Same values as the one-constraint function up to rounding (FMA contraction and
// the vector math functions round differently). Nothing outside out[0, end − begin) is
// written. Shape matching (clusters of any size) evaluates its clusters one at a time.
// Preconditions (not checked): begin ≤ end ≤ batch.size(), as for constraint_residual.

void constraint_residuals(const ParticleArrays& particles, const DistanceConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out);
void constraint_residuals(const ParticleArrays& particles, const DihedralConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out);
void constraint_residuals(const ParticleArrays& particles, const VolumeConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out);
void constraint_residuals(const ParticleArrays& particles,
                          const IsometricBendingConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out);
void constraint_residuals(const ParticleArrays& particles,
                          const EdgePointDistanceConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out);
void constraint_residuals(const ParticleArrays& particles,
                          const TrianglePointDistanceConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out);
void constraint_residuals(const ParticleArrays& particles,
                          const EdgeEdgeDistanceConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out);
void constraint_residuals(const ParticleArrays& particles,
                          const StrainTriangleConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out);
void constraint_residuals(const ParticleArrays& particles, const StrainTetraConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out);
void constraint_residuals(const ParticleArrays& particles, const FEMTriangleConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out);
void constraint_residuals(const ParticleArrays& particles, const FEMTetraConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out);
void constraint_residuals(const ParticleArrays& particles,
                          const ShapeMatchingConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out);
void constraint_residuals(const ParticleArrays& particles, const ParticleTetContacts& batch,
                          std::size_t begin, std::size_t end, Real* out);

}  // namespace tessera
