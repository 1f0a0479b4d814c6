// Particle–collider contact, the family's one formula. The collision module linearises a
// static collider (plane, sphere, box, capsule, mesh) at the point closest to the particle
// into a plane each substep: unit outward normal n, offset o = n·q + thickness.
//
//   C(p) = n · p − o ≥ 0,   ∇_p C = n   (one particle; the collider never moves).
// Position solve (unilateral; a static particle, w = 0, is never corrected):
//   where C < 0:  p ← p − C n,  λ ← λ − C   (λ: the accumulated normal correction, ≥ 0),
//   then position-based friction (Macklin, Müller, Chentanez, Kim 2014, "Unified particle
//   physics for real-time applications", eq. 24) with the penetration d = −C and the
//   tangential motion since the substep's start, Δx = p − anchor, Δx_t = Δx − (Δx·n) n:
//     |Δx_t| < μs d  →  p ← p − Δx_t                           (static: it sticks)
//     otherwise      →  p ← p − Δx_t · min(μk d / |Δx_t|, 1)   (dynamic: Coulomb's bound)
// Velocity solve (restitution, Müller, Macklin, Chentanez, Jeschke, Kim 2020, "Detailed
// rigid body simulation with extended position based dynamics", eq. 34), for a contact
// that was active in the position solve (λ > 0): with v_n = v · n and ṽ_n the normal speed
// before the solve, v ← v + n (−v_n + max(−e ṽ_n, 0)).
// Every step is branch-free: an inactive lane (C ≥ 0, w = 0, a normal that is not a unit
// vector, λ = 0 for the velocity) gets a zero correction and keeps its λ.
#if defined(TESSERA_CORE_KERNELS_COLLIDER_CONTACT_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_COLLIDER_CONTACT_INL_H_
#undef TESSERA_CORE_KERNELS_COLLIDER_CONTACT_INL_H_
#else
#define TESSERA_CORE_KERNELS_COLLIDER_CONTACT_INL_H_
#endif

#include "lane_math-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

/// How far |n|² may be from 1 for a collider normal to count as a unit vector (the same
/// test make_collider_contacts applies at the door).
inline constexpr double kColliderUnitNormalTolerance = 1e-4;

/// C = n · p − offset: the particle's signed distance above the collider's tangent plane.
template <class V>
HWY_INLINE V collider_contact_distance(const Vec3<V>& p, const Vec3<V>& normal, V offset) {
  return dot(normal, p) - offset;
}

/// The penetration max(0, −C) (what the residual measures, in length units).
template <class V>
HWY_INLINE V collider_contact_penetration(const Vec3<V>& p, const Vec3<V>& normal, V offset) {
  return lane_max(zero<V>() - collider_contact_distance(p, normal, offset), zero<V>());
}

/// The particle's correction and the lanes that were corrected.
template <class V>
struct ColliderCorrection {
  Vec3<V> correction;
  Mask<V> valid;
};

/// The position solve: pushes a penetrating movable particle back onto the plane, adds the
/// penetration to λ and applies static or dynamic friction against the motion from `anchor`.
template <class V>
HWY_INLINE ColliderCorrection<V> collider_contact_position_solve(
    V w, const Vec3<V>& p, const Vec3<V>& normal, V offset, const Vec3<V>& anchor,
    V static_friction, V dynamic_friction, V& lambda) {
  const V C = collider_contact_distance(p, normal, offset);
  ColliderCorrection<V> result;
  result.valid = mask_and(
      mask_and(C < zero<V>(), w > zero<V>()),
      lane_abs(squared_norm(normal) - splat<V>(1.0)) <= splat<V>(kColliderUnitNormalTolerance));
  const V depth = select(result.valid, zero<V>() - C, zero<V>());
  const Vec3<V> push = normal * depth;
  // Friction on the position after the push: its tangential motion since the substep began.
  const Vec3<V> moved = (p + push) - anchor;
  const Vec3<V> tangential = moved - normal * dot(moved, normal);
  const V tangential_length = norm(tangential);
  const Mask<V> sticks = tangential_length < static_friction * depth;
  const V slide_limit = lane_min(
      safe_divide(dynamic_friction * depth, tangential_length, tangential_length > zero<V>()),
      splat<V>(1.0));
  const V removed = select(sticks, splat<V>(1.0), slide_limit);
  result.correction = keep_if(result.valid, push - tangential * removed);
  lambda = lambda + depth;
  return result;
}

/// The velocity solve: the normal velocity of a contact that pushed (λ > 0) becomes the
/// restitution's bounce max(−e ṽ_n, 0), whatever the position solve left.
template <class V>
HWY_INLINE ColliderCorrection<V> collider_contact_velocity_solve(V w, const Vec3<V>& v,
                                                                 const Vec3<V>& normal,
                                                                 V normal_speed, V restitution,
                                                                 V lambda) {
  ColliderCorrection<V> result;
  result.valid = mask_and(lambda > zero<V>(), w > zero<V>());
  const V bounce = lane_max(zero<V>() - restitution * normal_speed, zero<V>());
  result.correction = keep_if(result.valid, normal * (bounce - dot(v, normal)));
  return result;
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_COLLIDER_CONTACT_INL_H_
