// Shape matching (Müller, Heidelberger, Teschner, Gross 2005, "Meshless Deformations Based on
// Shape Matching") over lanes, one cluster per lane. With cluster masses m_i, rest offsets
// q_i = x0_i - c0 (c0 the mass-weighted rest centre) and the current centre c = Σ m_i x_i / Σ m_i:
//   A_pq = Σ m_i (x_i - c) q_iᵀ,
//   T = R, the rotation of the polar decomposition A_pq = R S (det R = +1)     (rigid), or
//   T = A_pq A_qq⁻¹ with A_qq = Σ m_i q_i q_iᵀ (precomputed at build)         (allowStretch),
//   goal g_i = T q_i + c,   corr_i = k (g_i - x_i)  for movable particles.
// C = Σ m_i |g_i - x_i|² / 2 is the matching energy; corr_i = -k ∇_i C / m_i at fixed T, c.
// Vertex order is the cluster's entry order. A rigid lane is invalid (zero corrections) when
// A_pq has rank < 2 (every point on one line or all at one point), judged by the cofactor
// matrix relative to |A_pq|²; the rotation comes from kernels/polar_rotation-inl.h (a
// branch-free iteration), where the scalar API uses Eigen's SVD: the batch is tested against it.
#if defined(TESSERA_CORE_KERNELS_SHAPE_MATCHING_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_SHAPE_MATCHING_INL_H_
#undef TESSERA_CORE_KERNELS_SHAPE_MATCHING_INL_H_
#else
#define TESSERA_CORE_KERNELS_SHAPE_MATCHING_INL_H_
#endif

#include <limits>

#include "polar_rotation-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

/// Power-method squarings and rotation updates of the polar decomposition: measured against
/// Eigen's SVD on random stretched, planar and reflected matrices, 4 + 4 reach round-off in
/// float and double (well-conditioned clusters need 1–2 updates; the rest is margin).
inline constexpr int kShapeMatchingPolarSquarings = 4;
inline constexpr int kShapeMatchingPolarUpdates = 4;

/// Relative size below which the second singular value of A_pq counts as zero (the scalar
/// API's kRankTolerance: a few hundred round-off units).
inline constexpr double kShapeMatchingRankTolerance =
    256 * double(std::numeric_limits<Real>::epsilon());

/// The 2×2 minors of a (the entries of its cofactor matrix), squared and summed: between
/// σ0²σ1² and 3 σ0²σ1² for singular values σ0 ≥ σ1 ≥ σ2.
template <class V>
HWY_INLINE V squared_cofactor_norm(const Mat3<V>& a) {
  const Vec3<V> c0 = cross(a.col[1], a.col[2]);
  const Vec3<V> c1 = cross(a.col[2], a.col[0]);
  const Vec3<V> c2 = cross(a.col[0], a.col[1]);
  return squared_norm(c0) + squared_norm(c1) + squared_norm(c2);
}

/// The goal transform T of one cluster per lane and the lanes where it is determined.
template <class V>
struct ShapeMatchingTransform {
  Mat3<V> T;
  Mask<V> valid;
};

/// Rigid: T = R of A_pq = R S; valid where rank A_pq ≥ 2 (σ1 > tol · σ0, σ0 > tol_deg²).
template <class V>
HWY_INLINE ShapeMatchingTransform<V> shape_matching_rotation(const Mat3<V>& a_pq) {
  const V frobenius_squared = double_contraction(a_pq, a_pq);
  const double tiny = double(kDegenerateTolerance) * double(kDegenerateTolerance);
  const double rank = kShapeMatchingRankTolerance;
  ShapeMatchingTransform<V> result;
  result.valid =
      mask_and(frobenius_squared > splat<V>(tiny * tiny),
               squared_cofactor_norm(a_pq) >
                   splat<V>(rank * rank) * frobenius_squared * frobenius_squared);
  result.T = polar_rotation(a_pq, kShapeMatchingPolarSquarings, kShapeMatchingPolarUpdates);
  return result;
}

/// With stretch: T = A_pq A_qq⁻¹ (A_qq⁻¹ validated at build, so every lane is valid).
template <class V>
HWY_INLINE ShapeMatchingTransform<V> shape_matching_linear(const Mat3<V>& a_pq,
                                                           const Mat3<V>& inverse_a_qq) {
  return {a_pq * inverse_a_qq, all_lanes<V>()};
}

/// corr_i = k (T q_i + c - x_i).
template <class V>
HWY_INLINE Vec3<V> shape_matching_correction(const Mat3<V>& T, const Vec3<V>& q,
                                             const Vec3<V>& centre, const Vec3<V>& x,
                                             V stiffness) {
  return (T * q + centre - x) * stiffness;
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_SHAPE_MATCHING_INL_H_
