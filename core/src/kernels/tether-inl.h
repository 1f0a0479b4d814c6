// Tether (long-range attachment, Kim, Chentanez, Müller 2012, "Long Range Attachments — A
// Method to Simulate Inextensible Clothing in Computer Games"), the family's one formula:
//   C(p0, p1) = |p0 - p1| - d ≤ 0   (unilateral: only a stretched tether acts)
//   ∇_{p0} C = n = (p0 - p1)/|p0 - p1|,   ∇_{p1} C = -n.
// Vertex order: p0 is the tethered particle, p1 its attachment (usually static). The lane is
// valid (projected) only where C > 0; a tether within its reach is inactive: no correction,
// λ unchanged. Degenerate when p0 and p1 coincide (then C = -d ≤ 0 anyway).
#if defined(TESSERA_CORE_KERNELS_TETHER_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_TETHER_INL_H_
#undef TESSERA_CORE_KERNELS_TETHER_INL_H_
#else
#define TESSERA_CORE_KERNELS_TETHER_INL_H_
#endif

#include "distance-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

template <class V>
HWY_INLINE DirectionValue<V> tether_constraint(const Vec3<V>& p0, const Vec3<V>& p1,
                                               V max_distance) {
  DirectionValue<V> value = distance_constraint(p0, p1, max_distance);
  value.valid = mask_and(value.valid, value.C > zero<V>());
  return value;
}

/// The tether's overshoot max(0, C) (what its residual measures, relative to d).
template <class V>
HWY_INLINE V tether_overshoot(const Vec3<V>& p0, const Vec3<V>& p1, V max_distance) {
  const V C = norm(p0 - p1) - max_distance;
  return lane_max(C, zero<V>());
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_TETHER_INL_H_
