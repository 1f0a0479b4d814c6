// Isometric bending (Bergou, Wardetzky, Harmon, Zorin, Grinspun 2006, "A Quadratic Bending
// Model for Inextensible Surfaces"): the family's one formula, run on one lane by the scalar
// API (isometric_bending.cpp) and on W lanes by the batched kernel
// (isometric_bending_constraints.cpp).
//
// Vertex order of a bending stencil: p2-p3 is the shared edge, the triangles are
// (p0, p2, p3) and (p1, p3, p2). Q (4×4, from the rest shape, indexed p0..p3) is constant and
// of rank one, Q = k kᵀ (k = √(3/(A0+A1)) · K, K the cotangent Laplacian row), so with the
// discrete mean-curvature vector u = Σ_j k_j p_j
//   C = ½ Σ_ij Q_ij p_i · p_j = ½ |u|²,   ∇_{pi} C = Σ_j Q_ij p_j = k_i u.
// Evaluating through u matters: the PBD step C ∇_i C / Σ w|∇C|² = ½ k_i u / Σ_j w_j k_j² is
// then proportional to u, well conditioned for a nearly flat stencil. Written with Q directly
// (C = ½ p·Qp), C of a stencil that is flat up to rounding is rounding noise times the
// stencil's size while ∇C is rounding noise, and the step jumps by the size of the stencil.
// k sums to zero, so the positions are taken relative to their centroid first (the same
// value, without cancellation far from the origin).
// Invalid lane (zero corrections): Σ_i |∇_i C|² ≤ tol², a stencil that is flat for its Q;
// such a lane *satisfies* the constraint, which bending_is_flat reports to the scalar API.
#if defined(TESSERA_CORE_KERNELS_ISOMETRIC_BENDING_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_ISOMETRIC_BENDING_INL_H_
#undef TESSERA_CORE_KERNELS_ISOMETRIC_BENDING_INL_H_
#else
#define TESSERA_CORE_KERNELS_ISOMETRIC_BENDING_INL_H_
#endif

#include "projection-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

/// C and ∇C for the stencil (p0, p1; shared edge p2-p3) and the factor k of its Q = k kᵀ.
template <class V>
HWY_INLINE ConstraintValue<V, 4> isometric_bending_constraint(const Vec3<V> (&p)[4],
                                                              const V (&k)[4]) {
  ConstraintValue<V, 4> value;
  const Vec3<V> centroid = (p[0] + p[1] + p[2] + p[3]) * splat<V>(0.25);
  Vec3<V> u = (p[0] - centroid) * k[0];
  for (int j = 1; j < 4; ++j) u += (p[j] - centroid) * k[j];
  V gradient_squared = zero<V>();
  for (int i = 0; i < 4; ++i) {
    value.gradient[i] = u * k[i];
    gradient_squared = gradient_squared + squared_norm(value.gradient[i]);
  }
  value.C = squared_norm(u) * splat<V>(0.5);
  value.valid = gradient_squared > degenerate_denominator<V>();
  return value;
}

/// Lanes whose stencil is flat for its Q (∇C vanishes): satisfied, nothing to project.
template <class V>
HWY_INLINE Mask<V> bending_is_flat(const ConstraintValue<V, 4>& value) {
  return mask_not(value.valid);
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_ISOMETRIC_BENDING_INL_H_
