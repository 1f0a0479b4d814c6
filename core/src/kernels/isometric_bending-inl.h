// Isometric bending (Bergou, Wardetzky, Harmon, Zorin, Grinspun 2006, "A Quadratic Bending
// Model for Inextensible Surfaces"): the family's one formula, run on one lane by the scalar
// API (isometric_bending.cpp) and on W lanes by the batched kernel
// (isometric_bending_constraints.cpp).
//
// Vertex order as for the dihedral constraint: p2-p3 is the shared edge, the triangles are
// (p0, p2, p3) and (p1, p3, p2). Q (4×4, from the rest shape, indexed p0..p3) is constant, so
//   C = ½ Σ_ij Q_ij p_i · p_j,   ∇_{pi} C = Σ_j Q_ij p_j.
// Q's rows sum to zero, so the positions are taken relative to their centroid first (the same
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

/// C and ∇C for the stencil (p0, p1; shared edge p2-p3) and its matrix Q (Q[i][j] = Q_ij).
template <class V>
HWY_INLINE ConstraintValue<V, 4> isometric_bending_constraint(const Vec3<V> (&p)[4],
                                                              const V (&Q)[4][4]) {
  ConstraintValue<V, 4> value;
  const Vec3<V> centroid = (p[0] + p[1] + p[2] + p[3]) * splat<V>(0.25);
  Vec3<V> relative[4];
  for (int i = 0; i < 4; ++i) relative[i] = p[i] - centroid;
  V C = zero<V>();
  V gradient_squared = zero<V>();
  for (int i = 0; i < 4; ++i) {
    Vec3<V> g = relative[0] * Q[i][0];
    for (int j = 1; j < 4; ++j) g += relative[j] * Q[i][j];
    value.gradient[i] = g;
    C = C + dot(relative[i], g);
    gradient_squared = gradient_squared + squared_norm(g);
  }
  value.C = C * splat<V>(0.5);
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
