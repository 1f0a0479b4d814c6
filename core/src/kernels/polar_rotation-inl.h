// The rotation factor of a polar decomposition, branch-free over lanes.
//
// Why: shape matching needs, for W clusters at once, the rotation R that maximises tr(Rᵀ A)
// over proper rotations (the R of A = R S, with reflections removed). The scalar API takes it
// from Eigen's SVD, which is a data-dependent sweep that cannot run on lanes. Here the rotation
// is found by a fixed number of rotation updates in the spirit of Müller, Bender, Chentanez,
// Macklin 2016, "A Robust Method to Extract the Rotational Part of Deformations": R is kept as
// a unit quaternion q (so it is always a proper rotation) and each update rotates it about the
// axis g = Σ_j r_j × a_j (r_j, a_j the columns of R and A), the steepest-ascent axis of
// f(R) = tr(Rᵀ A). Müller et al. step by |g| / |Σ r_j · a_j|, which converges linearly (by a
// factor 3 per update near the solution); instead, along a fixed axis n, f is exactly
//   f(θ) = const + β cos θ + γ sin θ,   γ = n · g,   β = Σ_j r_j·a_j - Σ_j (n·r_j)(n·a_j),
// so each update takes the exact maximiser θ = atan2(γ, β) along that axis. Its half-angle
// quaternion needs no trigonometry: (cos θ/2, sin θ/2 n) ∝ (ρ + β, g) with ρ = √(|g|² + β²).
// f never decreases, a pure rotation about one axis is found in one update, and the iteration
// converges like steepest ascent with exact line search (fast for the mildly stretched
// clusters of shape matching). The start is Shepperd's quaternion of the normalised A, exact
// when A is a scaled rotation; a degenerate lane (A = 0) yields the identity. Everything is
// selects, so no lane ever holds Inf or NaN.
#if defined(TESSERA_CORE_KERNELS_POLAR_ROTATION_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_POLAR_ROTATION_INL_H_
#undef TESSERA_CORE_KERNELS_POLAR_ROTATION_INL_H_
#else
#define TESSERA_CORE_KERNELS_POLAR_ROTATION_INL_H_
#endif

#include <limits>

#include "lane_math-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

/// A quaternion of lanes, w + v.
template <class V>
struct Quaternion {
  V w;
  Vec3<V> v;
};

/// a ⊗ b (Hamilton product): the rotation b followed by a.
template <class V>
HWY_INLINE Quaternion<V> multiply(const Quaternion<V>& a, const Quaternion<V>& b) {
  return {a.w * b.w - dot(a.v, b.v), b.v * a.w + a.v * b.w + cross(a.v, b.v)};
}

/// q / |q| where |q| is not tiny, `fallback` elsewhere.
template <class V>
HWY_INLINE Quaternion<V> normalized_or(const Quaternion<V>& q, const Quaternion<V>& fallback) {
  const V squared = q.w * q.w + squared_norm(q.v);
  const Mask<V> valid = squared > splat<V>(double(std::numeric_limits<Real>::min()) * 1e8);
  const V inverse = safe_divide(splat<V>(1.0), lane_sqrt(squared), valid);
  return {select(valid, q.w * inverse, fallback.w), select(valid, q.v * inverse, fallback.v)};
}

/// The rotation matrix of a unit quaternion.
template <class V>
HWY_INLINE Mat3<V> rotation_matrix(const Quaternion<V>& q) {
  const V one = splat<V>(1.0), two = splat<V>(2.0);
  const V x = q.v.x, y = q.v.y, z = q.v.z, w = q.w;
  const V xx = x * x, yy = y * y, zz = z * z;
  const V xy = x * y, xz = x * z, yz = y * z, wx = w * x, wy = w * y, wz = w * z;
  Mat3<V> r;
  r.col[0] = {one - two * (yy + zz), two * (xy + wz), two * (xz - wy)};
  r.col[1] = {two * (xy - wz), one - two * (xx + zz), two * (yz + wx)};
  r.col[2] = {two * (xz + wy), two * (yz - wx), one - two * (xx + yy)};
  return r;
}

/// A symmetric 4×4 matrix of lanes (its upper triangle, row-major: 00 01 02 03 11 12 13 22 23 33).
template <class V>
struct Symmetric4 {
  V e[10];
  static constexpr int index(int i, int j) {
    const int r = i < j ? i : j, c = i < j ? j : i;
    return r * 4 - r * (r - 1) / 2 + (c - r);
  }
  HWY_INLINE V operator()(int i, int j) const { return e[index(i, j)]; }
};

/// Horn's matrix N(a): tr(R(q)ᵀ a) = qᵀ N q for unit quaternions q = (w, x, y, z), shifted by
/// 3 I so that it is positive semi-definite when |a|_F ≤ √3 (its eigenvalues are then in
/// [0, 6]; the largest one's eigenvector is the maximiser).
template <class V>
HWY_INLINE Symmetric4<V> shifted_horn_matrix(const Mat3<V>& a) {
  const V three = splat<V>(3.0);
  const V a00 = a.col[0].x, a11 = a.col[1].y, a22 = a.col[2].z;
  const V a01 = a.col[1].x, a10 = a.col[0].y, a02 = a.col[2].x, a20 = a.col[0].z;
  const V a12 = a.col[2].y, a21 = a.col[1].z;
  return {{three + a00 + a11 + a22, a21 - a12, a02 - a20, a10 - a01,  //
           three + a00 - a11 - a22, a01 + a10, a02 + a20,             //
           three - a00 + a11 - a22, a12 + a21,                        //
           three - a00 - a11 + a22}};
}

/// p² / tr(p²): one squaring of the power method, rescaled so nothing overflows.
template <class V>
HWY_INLINE Symmetric4<V> squared_normalized(const Symmetric4<V>& p) {
  Symmetric4<V> result;
  for (int i = 0; i < 4; ++i)
    for (int j = i; j < 4; ++j) {
      V sum = p(i, 0) * p(0, j);
      for (int k = 1; k < 4; ++k) sum = sum + p(i, k) * p(k, j);
      result.e[Symmetric4<V>::index(i, j)] = sum;
    }
  const V trace = result(0, 0) + result(1, 1) + result(2, 2) + result(3, 3);
  const V inverse = safe_divide(splat<V>(1.0), trace, trace > zero<V>());
  for (V& value : result.e) value = value * inverse;
  return result;
}

/// The start of the updates: the column of P^(2^squarings) (P the shifted Horn matrix) with
/// the largest diagonal entry, i.e. 2^squarings steps of the power method towards the
/// eigenvector of the largest eigenvalue from the best coordinate axis. With no squaring this
/// is Shepperd's quaternion of a, exact when a is a rotation.
template <class V>
HWY_INLINE Quaternion<V> power_method_start(const Mat3<V>& a, int squarings) {
  Symmetric4<V> p = shifted_horn_matrix(a);
  for (int k = 0; k < squarings; ++k) p = squared_normalized(p);
  Quaternion<V> q = {p(0, 0), {p(1, 0), p(2, 0), p(3, 0)}};
  V best = p(0, 0);
  for (int c = 1; c < 4; ++c) {
    const Mask<V> better = p(c, c) > best;
    best = select(better, p(c, c), best);
    q = {select(better, p(0, c), q.w),
         select(better, Vec3<V>{p(1, c), p(2, c), p(3, c)}, q.v)};
  }
  return q;
}

/// One update of q towards the maximiser of tr(R(q)ᵀ a): the exact maximiser along the
/// Newton axis (or along g where the Newton axis is far from it).
template <class V>
HWY_INLINE Quaternion<V> polar_rotation_update(const Quaternion<V>& q, const Mat3<V>& a) {
  const Mat3<V> r = rotation_matrix(q);
  // g = Σ r_j × a_j and H = tr(M) I - sym(M) with M = Σ r_j a_jᵀ: along a unit axis n,
  // f(θ) = const + (n·g) sin θ + (nᵀ H n) cos θ.
  Vec3<V> g = cross(r.col[0], a.col[0]);
  for (int j = 1; j < 3; ++j) g += cross(r.col[j], a.col[j]);
  const Vec3<V>& r0 = r.col[0];
  const Vec3<V>& r1 = r.col[1];
  const Vec3<V>& r2 = r.col[2];
  const Vec3<V>& a0 = a.col[0];
  const Vec3<V>& a1 = a.col[1];
  const Vec3<V>& a2 = a.col[2];
  const V m00 = r0.x * a0.x + r1.x * a1.x + r2.x * a2.x;
  const V m11 = r0.y * a0.y + r1.y * a1.y + r2.y * a2.y;
  const V m22 = r0.z * a0.z + r1.z * a1.z + r2.z * a2.z;
  const V half = splat<V>(0.5);
  const V s01 = half * (r0.x * a0.y + r1.x * a1.y + r2.x * a2.y +
                        r0.y * a0.x + r1.y * a1.x + r2.y * a2.x);
  const V s02 = half * (r0.x * a0.z + r1.x * a1.z + r2.x * a2.z +
                        r0.z * a0.x + r1.z * a1.x + r2.z * a2.x);
  const V s12 = half * (r0.y * a0.z + r1.y * a1.z + r2.y * a2.z +
                        r0.z * a0.y + r1.z * a1.y + r2.z * a2.y);
  const V trace = m00 + m11 + m22;
  const V h00 = trace - m00, h11 = trace - m11, h22 = trace - m22;
  const V h01 = zero<V>() - s01, h02 = zero<V>() - s02, h12 = zero<V>() - s12;
  // Newton axis adj(H) g (its length and sign do not matter: the line search is exact).
  const Vec3<V> newton = {(h11 * h22 - h12 * h12) * g.x + (h02 * h12 - h01 * h22) * g.y +
                              (h01 * h12 - h02 * h11) * g.z,
                          (h02 * h12 - h01 * h22) * g.x + (h00 * h22 - h02 * h02) * g.y +
                              (h01 * h02 - h00 * h12) * g.z,
                          (h01 * h12 - h02 * h11) * g.x + (h01 * h02 - h00 * h12) * g.y +
                              (h00 * h11 - h01 * h01) * g.z};
  const V newton_dot_g = dot(newton, g);
  const V newton_squared = squared_norm(newton);
  const V g_squared = squared_norm(g);
  // Newton only where H is positive definite (near the maximum; elsewhere it may head for a
  // saddle of f) and its axis is within ~84° of g; else g itself (steepest ascent).
  const V minor2 = h00 * h11 - h01 * h01;
  const V det = h00 * (h11 * h22 - h12 * h12) - h01 * (h01 * h22 - h12 * h02) +
                h02 * (h01 * h12 - h11 * h02);
  const Mask<V> positive_definite =
      mask_and(mask_and(h00 > zero<V>(), minor2 > zero<V>()), det > zero<V>());
  const Mask<V> use_newton = mask_and(
      positive_definite, newton_dot_g * newton_dot_g > splat<V>(0.01) * newton_squared * g_squared);
  const Vec3<V> axis_raw = select(use_newton, newton, g);
  const V axis_squared = select(use_newton, newton_squared, g_squared);
  const Mask<V> has_axis =
      axis_squared > splat<V>(double(std::numeric_limits<Real>::min()) * 1e8);
  const Vec3<V> axis = axis_raw * safe_divide(splat<V>(1.0), lane_sqrt(axis_squared), has_axis);
  const V gamma = dot(axis, g);
  const Vec3<V> h_axis = {h00 * axis.x + h01 * axis.y + h02 * axis.z,
                          h01 * axis.x + h11 * axis.y + h12 * axis.z,
                          h02 * axis.x + h12 * axis.y + h22 * axis.z};
  const V beta = select(has_axis, dot(axis, h_axis), trace);
  // θ = atan2(γ, β) about the axis; (cos θ/2, sin θ/2 axis) ∝ (ρ + β, γ axis).
  const V rho = lane_sqrt(gamma * gamma + beta * beta);
  const Quaternion<V> step = {rho + beta, axis * gamma};
  // A zero step (a saddle: g = 0 with β ≤ 0) keeps q.
  return normalized_or(multiply(step, q), q);
}

/// The proper rotation R maximising tr(Rᵀ a): `squarings` squarings of the power method on
/// Horn's matrix for a start near the global maximiser, then `iterations` updates.
template <class V>
HWY_INLINE Mat3<V> polar_rotation(const Mat3<V>& a, int squarings, int iterations) {
  const V frobenius_squared = double_contraction(a, a);
  const Mask<V> nonzero =
      frobenius_squared > splat<V>(double(std::numeric_limits<Real>::min()) * 1e8);
  // Scaled to |a|_F = √3 (the norm of a rotation matrix): the shifted Horn matrix is then
  // positive semi-definite and the thresholds see O(1) numbers whatever the cluster's size.
  const Mat3<V> scaled =
      a * safe_divide(splat<V>(1.7320508075688772), lane_sqrt(frobenius_squared), nonzero);
  const Quaternion<V> identity = {splat<V>(1.0), Vec3<V>::zeros()};
  Quaternion<V> q = normalized_or(power_method_start(scaled, squarings), identity);
  q = {select(nonzero, q.w, identity.w), select(nonzero, q.v, identity.v)};
  for (int k = 0; k < iterations; ++k) q = polar_rotation_update(q, scaled);
  return rotation_matrix(q);
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_POLAR_ROTATION_INL_H_
