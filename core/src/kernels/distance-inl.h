// Distance constraint (Müller et al. 2007), the family's one formula:
//   C(p0, p1) = |p0 - p1| - l0,   ∇_{p0} C = n = (p0 - p1)/|p0 - p1|,   ∇_{p1} C = -n.
// Degenerate (invalid lane) when p0 and p1 coincide. The value keeps d = p0 − p1 and |d|, not n
// (projection-inl.h, DirectionValue: the projection then divides once).
#if defined(TESSERA_CORE_KERNELS_DISTANCE_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_DISTANCE_INL_H_
#undef TESSERA_CORE_KERNELS_DISTANCE_INL_H_
#else
#define TESSERA_CORE_KERNELS_DISTANCE_INL_H_
#endif

#include "projection-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

template <class V>
HWY_INLINE DirectionValue<V> distance_constraint(const Vec3<V>& p0, const Vec3<V>& p1,
                                                 V rest_length) {
  DirectionValue<V> value;
  value.difference = p0 - p1;
  value.length = norm(value.difference);
  value.valid = value.length > splat<V>(kDegenerateTolerance);
  value.C = value.length - rest_length;
  return value;
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_DISTANCE_INL_H_
