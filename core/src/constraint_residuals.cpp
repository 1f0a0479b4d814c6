// Batched residuals: constraint_residual of a whole range, W constraints at a time.
//
// Why: the solver sums every constraint's residual after a step, and one at a time that costs
// about a projection sweep. Here each family's residual runs on Highway vectors, compiled once
// per SIMD target (foreach_target) and dispatched at run time like the projection kernels.
//
// What: the same lane formulas as the one-constraint functions of constraint_residual.cpp
// (kernels/<family>-inl.h, there with V = Real), so a value differs from the scalar one only
// by rounding; only the normalisation (|C| / |reference|, sqrt(2C), the Green strain norm
// built from strain_column / deformation_gradient / green_strain_material) is spelled out
// again over V. Only positions are gathered (no inverse masses), and the results of a chunk
// are stored with store_active, so the tail of a range never writes past out[end − begin).
// Lanes past the end read padding (particle 0, zero rest data): their branch-free formulas
// compute a discarded value and never trap. Shape matching stays a loop over the scalar
// function: its clusters have any number of particles (CSR), so lanes would not line up.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "constraint_residuals.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/core/constraint_residual.hpp>

#include "kernels/batch-inl.h"
#include "kernels/dihedral-inl.h"
#include "kernels/distance-inl.h"
#include "kernels/fem-inl.h"
#include "kernels/isometric_bending-inl.h"
#include "kernels/particle_tet_contact-inl.h"
#include "kernels/proximity-inl.h"
#include "kernels/strain-inl.h"
#include "kernels/volume-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {
namespace {

/// The positions of the N slots of constraints i .. i+W (inverse masses are not needed).
template <int N>
HWY_INLINE void gather_positions(const ParticleArrays& particles,
                                 const ParticleIndex* const* slot, std::size_t i,
                                 Vec3<RealLanes> (&p)[N]) {
  const RealTag d;
  for (int k = 0; k < N; ++k) {
    const IndexLanes index = load_particle_indices(slot[k] + i);
    p[k] = {hn::GatherIndex(d, particles.x, index), hn::GatherIndex(d, particles.y, index),
            hn::GatherIndex(d, particles.z, index)};
  }
}

/// out[c − begin] = residual(positions, c) for c in [begin, end), W at a time; residual
/// returns the lanes of constraints i .. i+W from their gathered positions.
template <int N, class Residual>
HWY_INLINE void residual_lanes(const ParticleArrays& particles,
                               const ConstraintParticles<N>& indices, std::size_t begin,
                               std::size_t end, Real* out, Residual&& residual) {
  const RealTag d;
  const std::size_t lanes = hn::Lanes(d);
  const ParticleIndex* slot[N];
  constraint_slots(indices, slot);
  for (std::size_t i = begin; i < end; i += lanes) {
    Vec3<RealLanes> p[N];
    gather_positions<N>(particles, slot, i, p);
    store_active(residual(p, i), end - i, out + (i - begin));
  }
}

HWY_INLINE RealLanes load(const Real* values, std::size_t i) {
  return hn::LoadU(RealTag(), values + i);
}

/// |C| / |reference|, or |C| where the reference is zero (constraint_residual.cpp's relative).
HWY_INLINE RealLanes relative(RealLanes C, RealLanes reference) {
  const RealLanes scale = lane_abs(reference);
  return lane_abs(C) / select(scale > zero<RealLanes>(), scale, splat<RealLanes>(1.0));
}

/// The Dim×Dim inverse rest matrix of constraints i .. i+W, m[k][j] from rest_inverse[Dim k + j].
template <int Dim, std::size_t Entries>
HWY_INLINE void rest_inverse_of(const std::array<AlignedVector<Real>, Entries>& rest_inverse,
                                std::size_t i, RealLanes (&m)[Dim][Dim]) {
  static_assert(Entries == std::size_t(Dim * Dim));
  for (int k = 0; k < Dim; ++k)
    for (int j = 0; j < Dim; ++j) m[k][j] = load(rest_inverse[std::size_t(Dim * k + j)].data(), i);
}

/// ‖½ (FᵀF − I)‖_F of a triangle, F = [p1 − p0, p2 − p0] · m, as in constraint_residual.cpp.
HWY_INLINE RealLanes triangle_green_strain_norm(const Vec3<RealLanes> (&p)[3],
                                                const RealLanes (&m)[2][2]) {
  const RealLanes half = splat<RealLanes>(0.5), one = splat<RealLanes>(1.0);
  const Vec3<RealLanes> edge[2] = {p[1] - p[0], p[2] - p[0]};
  const Vec3<RealLanes> f0 = strain_column<2>(edge, m, 0);
  const Vec3<RealLanes> f1 = strain_column<2>(edge, m, 1);
  const RealLanes strain_xx = half * (dot(f0, f0) - one);
  const RealLanes strain_yy = half * (dot(f1, f1) - one);
  const RealLanes strain_xy = half * dot(f0, f1);
  return lane_sqrt(strain_xx * strain_xx + strain_yy * strain_yy +
                   splat<RealLanes>(2.0) * strain_xy * strain_xy);
}

/// ‖ε‖_F of a tetrahedron, with the FEM tetrahedron kernel's F and ε.
HWY_INLINE RealLanes tetra_green_strain_norm(const Vec3<RealLanes> (&p)[4],
                                             const RealLanes (&m)[3][3]) {
  Mat3<RealLanes> rest_inverse;
  for (int j = 0; j < 3; ++j) rest_inverse.col[j] = {m[0][j], m[1][j], m[2][j]};
  const Mat3<RealLanes> F = deformation_gradient(p, rest_inverse);
  const RealLanes z = zero<RealLanes>();
  const Mat3<RealLanes> strain = green_strain_material<RealLanes>(F, z, z, z).strain;
  return lane_sqrt(double_contraction(strain, strain));
}

template <class Batch>
HWY_INLINE void triangle_strain_lanes(const ParticleArrays& particles, const Batch& batch,
                                      std::size_t begin, std::size_t end, Real* out) {
  residual_lanes<3>(particles, batch.particles, begin, end, out,
                    [&](const Vec3<RealLanes> (&p)[3], std::size_t i) {
                      RealLanes m[2][2];
                      rest_inverse_of<2>(batch.rest_inverse, i, m);
                      return triangle_green_strain_norm(p, m);
                    });
}

template <class Batch>
HWY_INLINE void tetra_strain_lanes(const ParticleArrays& particles, const Batch& batch,
                                   std::size_t begin, std::size_t end, Real* out) {
  residual_lanes<4>(particles, batch.particles, begin, end, out,
                    [&](const Vec3<RealLanes> (&p)[4], std::size_t i) {
                      RealLanes m[3][3];
                      rest_inverse_of<3>(batch.rest_inverse, i, m);
                      return tetra_green_strain_norm(p, m);
                    });
}

}  // namespace

void DistanceResiduals(const ParticleArrays& particles, const DistanceConstraints& batch,
                       std::size_t begin, std::size_t end, Real* out) {
  residual_lanes<2>(particles, batch.particles, begin, end, out,
                    [&](const Vec3<RealLanes> (&p)[2], std::size_t i) {
                      const RealLanes rest_length = load(batch.rest_length.data(), i);
                      return relative(distance_constraint(p[0], p[1], rest_length).C,
                                      rest_length);
                    });
}

void DihedralResiduals(const ParticleArrays& particles, const DihedralConstraints& batch,
                       std::size_t begin, std::size_t end, Real* out) {
  residual_lanes<4>(particles, batch.particles, begin, end, out,
                    [&](const Vec3<RealLanes> (&p)[4], std::size_t i) {
                      return lane_abs(dihedral_constraint(p[0], p[1], p[2], p[3],
                                                          load(batch.rest_angle.data(), i))
                                          .C);
                    });
}

void VolumeResiduals(const ParticleArrays& particles, const VolumeConstraints& batch,
                     std::size_t begin, std::size_t end, Real* out) {
  residual_lanes<4>(particles, batch.particles, begin, end, out,
                    [&](const Vec3<RealLanes> (&p)[4], std::size_t i) {
                      const RealLanes rest_volume = load(batch.rest_volume.data(), i);
                      return relative(
                          volume_constraint(p[0], p[1], p[2], p[3], rest_volume).C,
                          rest_volume);
                    });
}

void IsometricBendingResiduals(const ParticleArrays& particles,
                               const IsometricBendingConstraints& batch, std::size_t begin,
                               std::size_t end, Real* out) {
  residual_lanes<4>(particles, batch.particles, begin, end, out,
                    [&](const Vec3<RealLanes> (&p)[4], std::size_t i) {
                      const RealLanes k[4] = {
                          load(batch.factor[0].data(), i), load(batch.factor[1].data(), i),
                          load(batch.factor[2].data(), i), load(batch.factor[3].data(), i)};
                      // C = ½ |u|² ≥ 0, so |u| = sqrt(2C).
                      return lane_sqrt(splat<RealLanes>(2.0) *
                                       isometric_bending_constraint(p, k).C);
                    });
}

void EdgePointDistanceResiduals(const ParticleArrays& particles,
                                const EdgePointDistanceConstraints& batch, std::size_t begin,
                                std::size_t end, Real* out) {
  residual_lanes<3>(particles, batch.particles, begin, end, out,
                    [&](const Vec3<RealLanes> (&p)[3], std::size_t i) {
                      const RealLanes rest = load(batch.rest_distance.data(), i);
                      return relative(edge_point_distance_constraint(p[0], p[1], p[2], rest).C,
                                      rest);
                    });
}

void TrianglePointDistanceResiduals(const ParticleArrays& particles,
                                    const TrianglePointDistanceConstraints& batch,
                                    std::size_t begin, std::size_t end, Real* out) {
  residual_lanes<4>(
      particles, batch.particles, begin, end, out,
      [&](const Vec3<RealLanes> (&p)[4], std::size_t i) {
        const RealLanes rest = load(batch.rest_distance.data(), i);
        return relative(triangle_point_distance_constraint(p[0], p[1], p[2], p[3], rest).C,
                        rest);
      });
}

void EdgeEdgeDistanceResiduals(const ParticleArrays& particles,
                               const EdgeEdgeDistanceConstraints& batch, std::size_t begin,
                               std::size_t end, Real* out) {
  residual_lanes<4>(
      particles, batch.particles, begin, end, out,
      [&](const Vec3<RealLanes> (&p)[4], std::size_t i) {
        const RealLanes rest = load(batch.rest_distance.data(), i);
        return relative(edge_edge_distance_constraint(p[0], p[1], p[2], p[3], rest).C, rest);
      });
}

void StrainTriangleResiduals(const ParticleArrays& particles,
                             const StrainTriangleConstraints& batch, std::size_t begin,
                             std::size_t end, Real* out) {
  triangle_strain_lanes(particles, batch, begin, end, out);
}

void StrainTetraResiduals(const ParticleArrays& particles, const StrainTetraConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  tetra_strain_lanes(particles, batch, begin, end, out);
}

void FEMTriangleResiduals(const ParticleArrays& particles, const FEMTriangleConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  triangle_strain_lanes(particles, batch, begin, end, out);
}

void FEMTetraResiduals(const ParticleArrays& particles, const FEMTetraConstraints& batch,
                       std::size_t begin, std::size_t end, Real* out) {
  tetra_strain_lanes(particles, batch, begin, end, out);
}

void ParticleTetContactResiduals(const ParticleArrays& particles,
                                 const ParticleTetContacts& batch, std::size_t begin,
                                 std::size_t end, Real* out) {
  residual_lanes<5>(
      particles, batch.particles, begin, end, out,
      [&](const Vec3<RealLanes> (&p)[5], std::size_t i) {
        const Vec3<RealLanes> tet[4] = {p[1], p[2], p[3], p[4]};
        const Vec3<RealLanes> bary = {load(batch.barycentric[0].data(), i),
                                      load(batch.barycentric[1].data(), i),
                                      load(batch.barycentric[2].data(), i)};
        const Vec3<RealLanes> normal = {load(batch.normal[0].data(), i),
                                        load(batch.normal[1].data(), i),
                                        load(batch.normal[2].data(), i)};
        // As constraint_residual: one position solve from λ = 0 with a unit effective mass
        // and no masses accumulates λ = max(0, −C), the penetration depth.
        const RealLanes z = zero<RealLanes>();
        const RealLanes no_mass[4] = {z, z, z, z};
        RealLanes penetration = z;
        contact_position_solve(z, no_mass, p[0], tet, bary, normal, splat<RealLanes>(1.0),
                               penetration);
        return penetration;
      });
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace tessera {

HWY_EXPORT(DistanceResiduals);
HWY_EXPORT(DihedralResiduals);
HWY_EXPORT(VolumeResiduals);
HWY_EXPORT(IsometricBendingResiduals);
HWY_EXPORT(EdgePointDistanceResiduals);
HWY_EXPORT(TrianglePointDistanceResiduals);
HWY_EXPORT(EdgeEdgeDistanceResiduals);
HWY_EXPORT(StrainTriangleResiduals);
HWY_EXPORT(StrainTetraResiduals);
HWY_EXPORT(FEMTriangleResiduals);
HWY_EXPORT(FEMTetraResiduals);
HWY_EXPORT(ParticleTetContactResiduals);

void constraint_residuals(const ParticleArrays& particles, const DistanceConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(DistanceResiduals)(particles, batch, begin, end, out);
}

void constraint_residuals(const ParticleArrays& particles, const DihedralConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(DihedralResiduals)(particles, batch, begin, end, out);
}

void constraint_residuals(const ParticleArrays& particles, const VolumeConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(VolumeResiduals)(particles, batch, begin, end, out);
}

void constraint_residuals(const ParticleArrays& particles,
                          const IsometricBendingConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(IsometricBendingResiduals)(particles, batch, begin, end, out);
}

void constraint_residuals(const ParticleArrays& particles,
                          const EdgePointDistanceConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(EdgePointDistanceResiduals)(particles, batch, begin, end, out);
}

void constraint_residuals(const ParticleArrays& particles,
                          const TrianglePointDistanceConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(TrianglePointDistanceResiduals)(particles, batch, begin, end, out);
}

void constraint_residuals(const ParticleArrays& particles,
                          const EdgeEdgeDistanceConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(EdgeEdgeDistanceResiduals)(particles, batch, begin, end, out);
}

void constraint_residuals(const ParticleArrays& particles,
                          const StrainTriangleConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(StrainTriangleResiduals)(particles, batch, begin, end, out);
}

void constraint_residuals(const ParticleArrays& particles, const StrainTetraConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(StrainTetraResiduals)(particles, batch, begin, end, out);
}

void constraint_residuals(const ParticleArrays& particles, const FEMTriangleConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(FEMTriangleResiduals)(particles, batch, begin, end, out);
}

void constraint_residuals(const ParticleArrays& particles, const FEMTetraConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(FEMTetraResiduals)(particles, batch, begin, end, out);
}

void constraint_residuals(const ParticleArrays& particles,
                          const ShapeMatchingConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out) {
  // Scalar on purpose: clusters of any size in CSR do not line up in lanes (see the top).
  for (std::size_t c = begin; c < end; ++c) out[c - begin] = constraint_residual(particles, batch, c);
}

void constraint_residuals(const ParticleArrays& particles, const ParticleTetContacts& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(ParticleTetContactResiduals)(particles, batch, begin, end, out);
}

}  // namespace tessera
#endif  // HWY_ONCE
