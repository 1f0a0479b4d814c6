// Tetrahedron volume constraint (Müller et al. 2007, "Position Based Dynamics"): the family's
// one formula, run on one lane by the scalar API (volume.cpp) and on W lanes by the batched
// kernel (volume_constraints.cpp).
//
// Vertex order p0, p1, p2, p3 with p0 the reference vertex; the signed volume and C:
//   V = (1/6) ((p1 - p0) × (p2 - p0)) · (p3 - p0)   (positive when p3 lies on the side the
//   right-handed normal of (p0, p1, p2) points to),   C = V - V0,
//   ∇_{p1} C = (p2 - p0) × (p3 - p0) / 6,   ∇_{p2} C = (p3 - p0) × (p1 - p0) / 6,
//   ∇_{p3} C = (p1 - p0) × (p2 - p0) / 6,   ∇_{p0} C = -(∇_{p1} C + ∇_{p2} C + ∇_{p3} C).
// Every lane is valid: a degenerate tetrahedron (all points on one line) shows up as a
// vanishing Σ w_i |∇_i C|², which the projection rejects; a flat one with a proper face is
// projected (inflated back to V0).
#if defined(TESSERA_CORE_KERNELS_VOLUME_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_VOLUME_INL_H_
#undef TESSERA_CORE_KERNELS_VOLUME_INL_H_
#else
#define TESSERA_CORE_KERNELS_VOLUME_INL_H_
#endif

#include "projection-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

template <class V>
HWY_INLINE ConstraintValue<V, 4> volume_constraint(const Vec3<V>& p0, const Vec3<V>& p1,
                                                   const Vec3<V>& p2, const Vec3<V>& p3,
                                                   V rest_volume) {
  ConstraintValue<V, 4> value;
  const Vec3<V> e1 = p1 - p0;
  const Vec3<V> e2 = p2 - p0;
  const Vec3<V> e3 = p3 - p0;
  const V sixth = splat<V>(1.0 / 6.0);
  value.gradient[1] = cross(e2, e3) * sixth;
  value.gradient[2] = cross(e3, e1) * sixth;
  value.gradient[3] = cross(e1, e2) * sixth;
  value.gradient[0] = -(value.gradient[1] + value.gradient[2] + value.gradient[3]);
  value.C = dot(value.gradient[3], e3) - rest_volume;
  value.valid = all_lanes<V>();
  return value;
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_VOLUME_INL_H_
