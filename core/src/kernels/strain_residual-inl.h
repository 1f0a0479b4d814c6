// The Green strain norm ‖½ (FᵀF − I)‖_F of triangles and tetrahedra on lanes: the residual
// of the strain-based and FEM families (constraint_residual.hpp), with the kernels' own F
// (p0 the reference vertex) and the FEM tetrahedron's ε.
#if defined(TESSERA_CORE_KERNELS_STRAIN_RESIDUAL_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_STRAIN_RESIDUAL_INL_H_
#undef TESSERA_CORE_KERNELS_STRAIN_RESIDUAL_INL_H_
#else
#define TESSERA_CORE_KERNELS_STRAIN_RESIDUAL_INL_H_
#endif

#include <array>
#include <cstddef>

#include <tessera/core/aligned_vector.hpp>

#include "fem-inl.h"
#include "residual_lanes-inl.h"
#include "strain-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

/// The Dim×Dim inverse rest matrix of constraints i .. i+W, m[k][j] from rest_inverse[Dim k + j].
template <int Dim, std::size_t Entries>
HWY_INLINE void rest_inverse_of(const std::array<AlignedVector<Real>, Entries>& rest_inverse,
                                std::size_t i, RealLanes (&m)[Dim][Dim]) {
  static_assert(Entries == std::size_t(Dim * Dim));
  for (int k = 0; k < Dim; ++k)
    for (int j = 0; j < Dim; ++j) m[k][j] = load(rest_inverse[std::size_t(Dim * k + j)].data(), i);
}

/// ‖½ (FᵀF − I)‖_F of a triangle, F = [p1 − p0, p2 − p0] · m (strain_column, as the kernels).
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

/// out[c − begin] = ‖E‖_F of constraints [begin, end) of a strain or FEM batch of triangles
/// (N = 3) or tetrahedra (N = 4).
template <int N, class Batch>
HWY_INLINE void green_strain_residuals(const ParticleArrays& particles, const Batch& batch,
                                       std::size_t begin, std::size_t end, Real* out) {
  residual_lanes<N>(particles, batch.particles, begin, end, out,
                    [&](const Vec3<RealLanes> (&p)[N], std::size_t i) {
                      RealLanes m[N - 1][N - 1];
                      rest_inverse_of<N - 1>(batch.rest_inverse, i, m);
                      if constexpr (N == 3)
                        return triangle_green_strain_norm(p, m);
                      else
                        return tetra_green_strain_norm(p, m);
                    });
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_STRAIN_RESIDUAL_INL_H_
