// The lane vocabulary every constraint formula is written in.
//
// Why: DESIGN.md asks for one formula per constraint family, run on one lane by the scalar
// API and on W lanes by the batched kernels. A formula here is a function template over a
// lane type V, which is either
//     Real                          (one constraint: the scalar API), or
//     hn::Vec<hn::ScalableTag<Real>> (W constraints side by side: the batched kernels),
// and uses only what this file defines for both: + - * / on V, comparisons giving a Mask<V>,
// and the free functions below (splat, sqrt, select, min, max, abs, acos, ...), plus Vec3 and
// Mat3 built from them. No formula branches on data: a degenerate lane is marked in a mask
// and its corrections are selected to zero, so all lanes run the same instructions and a
// lane rounds the same way whatever its neighbours hold.
//
// Like every Highway "-inl.h" file this one is included once per compiled SIMD target
// (foreach_target re-includes the translation unit), so its code lives in
// tessera::HWY_NAMESPACE and the include guard toggles with HWY_TARGET_TOGGLE.
#if defined(TESSERA_CORE_KERNELS_LANE_MATH_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_LANE_MATH_INL_H_
#undef TESSERA_CORE_KERNELS_LANE_MATH_INL_H_
#else
#define TESSERA_CORE_KERNELS_LANE_MATH_INL_H_
#endif

#include <algorithm>
#include <cmath>
#include <type_traits>

#include <hwy/highway.h>
#include <hwy/contrib/math/math-inl.h>

#include <tessera/core/real.hpp>

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

/// True for the one-lane instantiation (V = Real).
template <class V>
inline constexpr bool kScalarLane = std::is_floating_point_v<V>;

/// The mask type of V: bool for one lane, a Highway mask for W lanes.
template <class V>
using Mask = decltype(std::declval<V>() < std::declval<V>());

/// V with every lane equal to value.
template <class V>
HWY_INLINE V splat(double value) {
  if constexpr (kScalarLane<V>) {
    return static_cast<V>(value);
  } else {
    return hn::Set(hn::DFromV<V>(), static_cast<hn::TFromV<V>>(value));
  }
}

template <class V>
HWY_INLINE V zero() {
  return splat<V>(0.0);
}

/// condition ? when_true : when_false, lane by lane.
template <class V, class M>
HWY_INLINE V select(const M& condition, V when_true, V when_false) {
  if constexpr (kScalarLane<V>) {
    return condition ? when_true : when_false;
  } else {
    return hn::IfThenElse(condition, when_true, when_false);
  }
}

template <class M>
HWY_INLINE M mask_and(const M& a, const M& b) {
  if constexpr (std::is_same_v<M, bool>) {
    return a && b;
  } else {
    return hn::And(a, b);
  }
}

template <class M>
HWY_INLINE M mask_or(const M& a, const M& b) {
  if constexpr (std::is_same_v<M, bool>) {
    return a || b;
  } else {
    return hn::Or(a, b);
  }
}

template <class M>
HWY_INLINE M mask_not(const M& a) {
  if constexpr (std::is_same_v<M, bool>) {
    return !a;
  } else {
    return hn::Not(a);
  }
}

/// True in every lane.
template <class V>
HWY_INLINE Mask<V> all_lanes() {
  return splat<V>(0.0) == splat<V>(0.0);
}

template <class V>
HWY_INLINE V lane_sqrt(V x) {
  if constexpr (kScalarLane<V>) {
    return std::sqrt(x);
  } else {
    return hn::Sqrt(x);
  }
}

template <class V>
HWY_INLINE V lane_min(V a, V b) {
  if constexpr (kScalarLane<V>) {
    return std::min(a, b);
  } else {
    return hn::Min(a, b);
  }
}

template <class V>
HWY_INLINE V lane_max(V a, V b) {
  if constexpr (kScalarLane<V>) {
    return std::max(a, b);
  } else {
    return hn::Max(a, b);
  }
}

template <class V>
HWY_INLINE V lane_abs(V x) {
  if constexpr (kScalarLane<V>) {
    return std::abs(x);
  } else {
    return hn::Abs(x);
  }
}

template <class V>
HWY_INLINE V clamp(V x, V lo, V hi) {
  return lane_min(lane_max(x, lo), hi);
}

/// acos of x ∈ [-1, 1] (callers clamp first).
template <class V>
HWY_INLINE V lane_acos(V x) {
  if constexpr (kScalarLane<V>) {
    return std::acos(x);
  } else {
    return hn::Acos(hn::DFromV<V>(), x);
  }
}

/// +1 where x ≥ 0, -1 elsewhere.
template <class V>
HWY_INLINE V sign_or_one(V x) {
  return select(x < zero<V>(), splat<V>(-1.0), splat<V>(1.0));
}

/// numerator / denominator where valid, 0 elsewhere (the division runs on a safe denominator,
/// so no lane ever holds Inf or NaN).
template <class V>
HWY_INLINE V safe_divide(V numerator, V denominator, const Mask<V>& valid) {
  const V safe = select(valid, denominator, splat<V>(1.0));
  return select(valid, numerator / safe, zero<V>());
}

// ---------------------------------------------------------------------------------------
/// A 3-vector of lanes: lane i of x, y, z is the vector of constraint i.
template <class V>
struct Vec3 {
  V x, y, z;

  static HWY_INLINE Vec3 zeros() { return {zero<V>(), zero<V>(), zero<V>()}; }
  HWY_INLINE Vec3 operator+(const Vec3& b) const { return {x + b.x, y + b.y, z + b.z}; }
  HWY_INLINE Vec3 operator-(const Vec3& b) const { return {x - b.x, y - b.y, z - b.z}; }
  HWY_INLINE Vec3 operator-() const { return {zero<V>() - x, zero<V>() - y, zero<V>() - z}; }
  HWY_INLINE Vec3 operator*(V s) const { return {x * s, y * s, z * s}; }
  HWY_INLINE Vec3& operator+=(const Vec3& b) { return *this = *this + b; }
  HWY_INLINE Vec3& operator-=(const Vec3& b) { return *this = *this - b; }
};

template <class V>
HWY_INLINE Vec3<V> operator*(V s, const Vec3<V>& a) {
  return a * s;
}

template <class V>
HWY_INLINE V dot(const Vec3<V>& a, const Vec3<V>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

template <class V>
HWY_INLINE Vec3<V> cross(const Vec3<V>& a, const Vec3<V>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

template <class V>
HWY_INLINE V squared_norm(const Vec3<V>& a) {
  return dot(a, a);
}

template <class V>
HWY_INLINE V norm(const Vec3<V>& a) {
  return lane_sqrt(squared_norm(a));
}

template <class V, class M>
HWY_INLINE Vec3<V> select(const M& condition, const Vec3<V>& a, const Vec3<V>& b) {
  return {select(condition, a.x, b.x), select(condition, a.y, b.y),
          select(condition, a.z, b.z)};
}

/// a where valid, zero elsewhere.
template <class V, class M>
HWY_INLINE Vec3<V> keep_if(const M& valid, const Vec3<V>& a) {
  return select(valid, a, Vec3<V>::zeros());
}

// ---------------------------------------------------------------------------------------
/// A 3×3 matrix of lanes, stored by columns (col[j] is column j).
template <class V>
struct Mat3 {
  Vec3<V> col[3];

  static HWY_INLINE Mat3 identity() {
    const V o = splat<V>(1.0), z = zero<V>();
    return {{{o, z, z}, {z, o, z}, {z, z, o}}};
  }
  static HWY_INLINE Mat3 zeros() {
    return {{Vec3<V>::zeros(), Vec3<V>::zeros(), Vec3<V>::zeros()}};
  }
  HWY_INLINE V operator()(int row, int column) const {
    const Vec3<V>& c = col[column];
    return row == 0 ? c.x : (row == 1 ? c.y : c.z);
  }
  HWY_INLINE Vec3<V> row(int r) const { return {(*this)(r, 0), (*this)(r, 1), (*this)(r, 2)}; }
  HWY_INLINE Vec3<V> operator*(const Vec3<V>& v) const {
    return col[0] * v.x + col[1] * v.y + col[2] * v.z;
  }
  HWY_INLINE Mat3 operator*(const Mat3& b) const {
    return {{(*this) * b.col[0], (*this) * b.col[1], (*this) * b.col[2]}};
  }
  HWY_INLINE Mat3 operator+(const Mat3& b) const {
    return {{col[0] + b.col[0], col[1] + b.col[1], col[2] + b.col[2]}};
  }
  HWY_INLINE Mat3 operator-(const Mat3& b) const {
    return {{col[0] - b.col[0], col[1] - b.col[1], col[2] - b.col[2]}};
  }
  HWY_INLINE Mat3 operator*(V s) const { return {{col[0] * s, col[1] * s, col[2] * s}}; }
  HWY_INLINE Mat3 transposed() const { return {{row(0), row(1), row(2)}}; }
  HWY_INLINE V trace() const { return col[0].x + col[1].y + col[2].z; }
  HWY_INLINE V determinant() const { return dot(col[0], cross(col[1], col[2])); }
};

/// Σ_ij a_ij b_ij.
template <class V>
HWY_INLINE V double_contraction(const Mat3<V>& a, const Mat3<V>& b) {
  return dot(a.col[0], b.col[0]) + dot(a.col[1], b.col[1]) + dot(a.col[2], b.col[2]);
}

// ---------------------------------------------------------------------------------------
// Conversions at the edge of the scalar API (one lane, Eigen types).

HWY_INLINE Vec3<Real> from_eigen(const Vector3r& v) { return {v.x(), v.y(), v.z()}; }
HWY_INLINE Vector3r to_eigen(const Vec3<Real>& v) { return Vector3r(v.x, v.y, v.z); }
HWY_INLINE Mat3<Real> from_eigen(const Matrix3r& m) {
  return {{from_eigen(Vector3r(m.col(0))), from_eigen(Vector3r(m.col(1))),
           from_eigen(Vector3r(m.col(2)))}};
}
HWY_INLINE Matrix3r to_eigen(const Mat3<Real>& m) {
  Matrix3r result;
  for (int j = 0; j < 3; ++j) result.col(j) = to_eigen(m.col[j]);
  return result;
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_LANE_MATH_INL_H_
