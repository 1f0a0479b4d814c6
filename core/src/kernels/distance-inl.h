// Distance constraint (Müller et al. 2007), the family's one formula:
//   C(p0, p1) = |p0 - p1| - l0,   ∇_{p0} C = n = (p0 - p1)/|p0 - p1|,   ∇_{p1} C = -n.
// Degenerate (invalid lane) when p0 and p1 coincide.
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
HWY_INLINE ConstraintValue<V, 2> distance_constraint(const Vec3<V>& p0, const Vec3<V>& p1,
                                                     V rest_length) {
  ConstraintValue<V, 2> value;
  const Vec3<V> difference = p0 - p1;
  const V length = norm(difference);
  value.valid = length > splat<V>(kDegenerateTolerance);
  const V inverse_length = safe_divide(splat<V>(1.0), length, value.valid);
  const Vec3<V> direction = difference * inverse_length;
  value.C = length - rest_length;
  value.gradient[0] = direction;
  value.gradient[1] = -direction;
  return value;
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_DISTANCE_INL_H_
