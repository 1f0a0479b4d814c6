// Dihedral bending constraint (Müller et al. 2007, appendix; gradients of the dihedral angle
// from Bridson, Marino, Fedkiw 2003, "Simulation of Clothing with Folds and Wrinkles"): the
// family's one formula, run on one lane by the scalar API (dihedral.cpp) and on W lanes by
// the batched kernel (dihedral_constraints.cpp).
//
// Vertex order: p2-p3 is the shared edge e = p3 - p2, p0 and p1 are the wings; the triangles
// are (p0, p2, p3) and (p1, p3, p2) with (unnormalised) normals
//   N1 = (p2 - p0) × (p3 - p0),   N2 = (p3 - p1) × (p2 - p1).
// The signed angle about the edge and the constraint:
//   ψ = atan2((N1 × N2) · ê, N1 · N2),   φ = |ψ| = acos(n̂1 · n̂2) ∈ [0, π],   C = φ - φ0.
// atan2 keeps φ accurate near 0 and π, where acos of a rounded dot product does not. The
// gradient of ψ has no 1/sin φ factor, so flat and fully folded stencils stay finite:
//   ∇_{p0} ψ = -|e| N1 / |N1|²,   ∇_{p1} ψ = -|e| N2 / |N2|²,
//   ∇_{p2} ψ = -(1 - s0) ∇_{p0} ψ - (1 - s1) ∇_{p1} ψ,
//   ∇_{p3} ψ = -s0 ∇_{p0} ψ - s1 ∇_{p1} ψ,      s_k = (p_k - p2) · e / |e|²,
// and ∇C = sign(ψ) ∇ψ with sign(ψ) = +1 at ψ = 0 (a flat stencil with φ0 > 0 buckles towards
// positive ψ, deterministically).
// Invalid lane (zero corrections): |e|² ≤ tol² (zero-length edge) or |N_k|² ≤ tol² |e|⁴ (a
// wing triangle whose height over the edge is below tol |e|: flat at any scale), with
// tol = kDegenerateTolerance.
#if defined(TESSERA_CORE_KERNELS_DIHEDRAL_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_DIHEDRAL_INL_H_
#undef TESSERA_CORE_KERNELS_DIHEDRAL_INL_H_
#else
#define TESSERA_CORE_KERNELS_DIHEDRAL_INL_H_
#endif

#include <numbers>

#include "projection-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

/// The unsigned angle |atan2(y, x)| ∈ [0, π] of the point (x, y), branch-free.
/// One lane uses std::atan2. W lanes reduce to an argument in [0, 1] for Highway's atan
/// polynomial:
///   a = min(|y|, |x|) / max(|y|, |x|),  t = atan(a),  t ← π/2 - t where |y| > |x|,
///   t ← π - t where x < 0  (so atan2(0, negative) = π, as std::atan2(+0, x < 0)).
/// (0, 0) gives 0. hn::Atan takes any argument, so it divides 1/a on every lane (kept only
/// where a > 1): a division on the path to C that a ∈ [0, 1] never needs. Its polynomial is
/// called directly, the same t for every a ∈ [0, 1].
template <class V>
HWY_INLINE V lane_unsigned_atan2(V y, V x) {
  if constexpr (kScalarLane<V>) {
    return std::abs(std::atan2(y, x));
  } else {
    const V ay = lane_abs(y), ax = lane_abs(x);
    const V largest = lane_max(ay, ax), smallest = lane_min(ay, ax);
    const V ratio = safe_divide(smallest, largest, largest > zero<V>());
    // Highway's own polynomial, from its internal namespace (Highway 1.0.3, Debian 12); were it
    // to move, hn::Atan(d, ratio) gives the same bits with the division back.
    V t = hn::impl::AtanImpl<hn::TFromV<V>>().AtanPoly(hn::DFromV<V>(), ratio);
    t = select(ay > ax, splat<V>(std::numbers::pi / 2) - t, t);
    return select(x < zero<V>(), splat<V>(std::numbers::pi) - t, t);
  }
}

/// C = φ - φ0 and ∇C of the dihedral constraint on stencil (p0, p1; shared edge p2-p3).
template <class V>
HWY_INLINE ConstraintValue<V, 4> dihedral_constraint(const Vec3<V>& p0, const Vec3<V>& p1,
                                                     const Vec3<V>& p2, const Vec3<V>& p3,
                                                     V rest_angle) {
  ConstraintValue<V, 4> value;
  const Vec3<V> edge = p3 - p2;
  const Vec3<V> normal0 = cross(p2 - p0, p3 - p0);  // N1, twice the area of (p0, p2, p3)
  const Vec3<V> normal1 = cross(p3 - p1, p2 - p1);  // N2, twice the area of (p1, p3, p2)
  const V edge_squared = squared_norm(edge);
  const V normal0_squared = squared_norm(normal0);
  const V normal1_squared = squared_norm(normal1);
  const V tolerance_squared =
      splat<V>(double(kDegenerateTolerance) * double(kDegenerateTolerance));
  const V flat_below = tolerance_squared * edge_squared * edge_squared;
  value.valid = mask_and(edge_squared > tolerance_squared,
                         mask_and(normal0_squared > flat_below, normal1_squared > flat_below));

  // atan2 depends on the ratio of its arguments alone, so both are scaled by |e| rather than
  // the first divided by it: one division fewer on the path to C. An invalid lane reads
  // atan2(0, N1 · N2) (its |e| may be 0, and 0 · a negative dot would be -0, which the lane
  // atan2 and std::atan2 read differently).
  const V edge_length = lane_sqrt(edge_squared);
  const V sine_part =  // |N1||N2||e| sin ψ
      select(value.valid, dot(cross(normal0, normal1), edge), zero<V>());
  const V normals_dot = dot(normal0, normal1);
  const V cosine_part =  // |N1||N2||e| cos ψ
      select(value.valid, normals_dot * edge_length, normals_dot);
  value.C = lane_unsigned_atan2(sine_part, cosine_part) - rest_angle;

  const V signed_edge_length = zero<V>() - sign_or_one(sine_part) * edge_length;
  const Vec3<V> grad_wing0 =
      normal0 * safe_divide(signed_edge_length, normal0_squared, value.valid);
  const Vec3<V> grad_wing1 =
      normal1 * safe_divide(signed_edge_length, normal1_squared, value.valid);
  // s0 and s1 share 1/|e|²: one division for both.
  const V inverse_edge_squared = safe_divide(splat<V>(1.0), edge_squared, value.valid);
  const V s0 = dot(p0 - p2, edge) * inverse_edge_squared;
  const V s1 = dot(p1 - p2, edge) * inverse_edge_squared;
  const V one = splat<V>(1.0);
  value.gradient[0] = grad_wing0;
  value.gradient[1] = grad_wing1;
  value.gradient[2] = -(grad_wing0 * (one - s0) + grad_wing1 * (one - s1));
  value.gradient[3] = -(grad_wing0 * s0 + grad_wing1 * s1);
  return value;
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_DIHEDRAL_INL_H_
