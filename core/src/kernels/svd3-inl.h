// A branch-free 3×3 singular value decomposition over lanes, for the inversion-robust FEM
// material (Irving et al. 2004) in the batched kernels.
//
// Why not Eigen: JacobiSVD branches on every element's data and runs one matrix at a time;
// the batch kernels need the same instruction stream for W tetrahedra at once. The method is
// in the spirit of McAdams et al. 2011 ("Computing the Singular Value Decomposition of 3×3
// matrices with minimal branching and elementary floating point operations"), with exact
// (not quaternion-approximated) Jacobi rotations:
//   1. F is scaled by its largest |entry| (so FᵀF neither overflows nor underflows),
//   2. kSvdJacobiSweeps cyclic Jacobi sweeps over the pairs (0,1), (0,2), (1,2) diagonalise
//      the symmetric A = FᵀF; the product of the rotations is V (a proper rotation),
//   3. V's columns are sorted by decreasing eigenvalue (each swap negates one column, so V
//      stays a rotation),
//   4. B = F V is factored B = U R by Gram–Schmidt: u0 = b0/|b0|, u1 = the part of b1
//      orthogonal to u0, normalised (any unit vector orthogonal to u0 when that part
//      vanishes), u2 = u0 × u1; the singular values are the diagonal of R,
//      σ0 = |b0|, σ1 = u1·b1, σ2 = u2·b2.
// U and V are rotations by construction, so the sign of det F lands on σ2, the smallest:
// exactly the convention of PositionBasedDynamics::computeGreenStrainAndPiolaStressInversion.
// The off-diagonal of R is dropped; it is of the order of the Jacobi residual.
#if defined(TESSERA_CORE_KERNELS_SVD3_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_SVD3_INL_H_
#undef TESSERA_CORE_KERNELS_SVD3_INL_H_
#else
#define TESSERA_CORE_KERNELS_SVD3_INL_H_
#endif

#include "lane_math-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

/// Cyclic Jacobi sweeps (3 rotations each). Convergence is quadratic: over 10⁵ random,
/// rank-deficient and nearly repeated-column matrices the worst off-diagonal / trace of FᵀF
/// was 0.34, 0.04, 7e-6 and 2e-21 after 1, 2, 3 and 4 sweeps, so four reach round-off in
/// float and in double.
inline constexpr int kSvdJacobiSweeps = 4;

/// True when any lane of the mask is set. Formulas use it only to skip work whose result
/// every lane would discard (a lane's value never depends on its neighbours).
template <class V>
HWY_INLINE bool any_lane(const Mask<V>& mask) {
  if constexpr (kScalarLane<V>) {
    return mask;
  } else {
    return !hn::AllFalse(hn::DFromV<V>(), mask);
  }
}

/// F = U diag(sigma) Vᵀ with U, V rotations, sigma[0] ≥ sigma[1] ≥ |sigma[2]|.
template <class V>
struct Svd3 {
  Mat3<V> u;
  Vec3<V> sigma;
  Mat3<V> v;
};

namespace svd3_detail {

/// One Jacobi rotation in the (p, q) plane: A ← Gᵀ A G with a_pq → 0, V ← V G, where
/// G_pp = G_qq = c, G_pq = s, G_qp = -s and t = s/c is the smaller root of
/// t² + 2θt - 1 = 0, θ = (a_qq - a_pp) / (2 a_pq), written overflow-free as
/// t = 2 a_pq sign(τ) / (|τ| + sqrt(τ² + 4 a_pq²)), τ = a_qq - a_pp (t = 0 when a_pq = 0).
template <int P, int Q, class V>
HWY_INLINE void jacobi_rotation(V (&a)[3][3], Mat3<V>& v) {
  constexpr int R = 3 - P - Q;
  const V apq = a[P][Q];
  const V tau = a[Q][Q] - a[P][P];
  const V denominator =
      lane_abs(tau) + lane_sqrt(tau * tau + splat<V>(4.0) * apq * apq);
  const V t = safe_divide(splat<V>(2.0) * apq * sign_or_one(tau), denominator,
                          denominator > zero<V>());
  const V c = splat<V>(1.0) / lane_sqrt(splat<V>(1.0) + t * t);
  const V s = t * c;
  a[P][P] = a[P][P] - t * apq;
  a[Q][Q] = a[Q][Q] + t * apq;
  a[P][Q] = a[Q][P] = zero<V>();
  const V arp = a[R][P], arq = a[R][Q];
  a[R][P] = a[P][R] = c * arp - s * arq;
  a[R][Q] = a[Q][R] = s * arp + c * arq;
  const Vec3<V> vp = v.col[P], vq = v.col[Q];
  v.col[P] = vp * c - vq * s;
  v.col[Q] = vp * s + vq * c;
}

/// Orders eigenvalue i before j when it is larger; the swap negates one column of V so V
/// stays a rotation.
template <int I, int J, class V>
HWY_INLINE void sort_pair(V (&d)[3], Mat3<V>& v) {
  const Mask<V> swap = d[I] < d[J];
  const V di = d[I], dj = d[J];
  d[I] = select(swap, dj, di);
  d[J] = select(swap, di, dj);
  const Vec3<V> vi = v.col[I], vj = v.col[J];
  v.col[I] = select(swap, vj, vi);
  v.col[J] = select(swap, -vi, vj);
}

}  // namespace svd3_detail

template <class V>
HWY_INLINE Svd3<V> svd3(const Mat3<V>& F) {
  using namespace svd3_detail;
  // 1. Scale to the largest entry (1 when F = 0, so nothing divides by zero).
  V largest = zero<V>();
  for (int j = 0; j < 3; ++j)
    largest = lane_max(largest, lane_max(lane_abs(F.col[j].x),
                                         lane_max(lane_abs(F.col[j].y), lane_abs(F.col[j].z))));
  const Mask<V> nonzero = largest > zero<V>();
  const V scale = select(nonzero, largest, splat<V>(1.0));
  const Mat3<V> f = F * (splat<V>(1.0) / scale);

  // 2. Jacobi on A = fᵀf.
  V a[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) a[i][j] = a[j][i] = dot(f.col[i], f.col[j]);
  Svd3<V> result;
  result.v = Mat3<V>::identity();
  for (int sweep = 0; sweep < kSvdJacobiSweeps; ++sweep) {
    jacobi_rotation<0, 1>(a, result.v);
    jacobi_rotation<0, 2>(a, result.v);
    jacobi_rotation<1, 2>(a, result.v);
  }

  // 3. Sort by decreasing eigenvalue.
  V d[3] = {a[0][0], a[1][1], a[2][2]};
  sort_pair<0, 1>(d, result.v);
  sort_pair<0, 2>(d, result.v);
  sort_pair<1, 2>(d, result.v);

  // 4. B = f V = U R.
  const Vec3<V> b0 = f * result.v.col[0];
  const Vec3<V> b1 = f * result.v.col[1];
  const Vec3<V> b2 = f * result.v.col[2];
  const V one = splat<V>(1.0);
  const V tiny = splat<V>(double(kDegenerateTolerance) * double(kDegenerateTolerance));

  const V length0_squared = squared_norm(b0);
  const Mask<V> has_u0 = length0_squared > tiny;
  const Vec3<V> u0 =
      select(has_u0, b0 * safe_divide(one, lane_sqrt(length0_squared), has_u0),
             Vec3<V>{one, zero<V>(), zero<V>()});

  const Vec3<V> rest1 = b1 - u0 * dot(u0, b1);
  const V length1_squared = squared_norm(rest1);
  const Mask<V> has_u1 = length1_squared > tiny;
  // Fallback: u0 × e_x or u0 × e_y, whichever is longer (at least 1/√2 for a unit u0).
  const Vec3<V> cross_x{zero<V>(), u0.z, zero<V>() - u0.y};
  const Vec3<V> cross_y{zero<V>() - u0.z, zero<V>(), u0.x};
  const V cross_x_squared = squared_norm(cross_x), cross_y_squared = squared_norm(cross_y);
  const Mask<V> use_x = cross_x_squared >= cross_y_squared;
  const Vec3<V> fallback = select(use_x, cross_x, cross_y);
  const V fallback_squared = select(use_x, cross_x_squared, cross_y_squared);
  const Vec3<V> direction1 = select(has_u1, rest1, fallback);
  const V direction1_squared = select(has_u1, length1_squared, fallback_squared);
  const Vec3<V> u1 =
      direction1 * safe_divide(one, lane_sqrt(direction1_squared), direction1_squared > zero<V>());
  const Vec3<V> u2 = cross(u0, u1);

  result.u = Mat3<V>{{u0, u1, u2}};
  result.sigma = Vec3<V>{dot(u0, b0), dot(u1, b1), dot(u2, b2)} * scale;
  return result;
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_SVD3_INL_H_
