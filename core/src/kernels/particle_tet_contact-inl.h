// Particle–tetrahedron contact (the contact handling of Bender, Müller, Macklin 2015/2017,
// "Position-Based Simulation Methods in Computer Graphics", and the seed's
// init/solve/velocitySolve_ParticleTetContactConstraint), the family's one formula.
//
// Vertex order: particle p0, then the tet's x[0..3]. bary = (b1, b2, b3), b0 = 1 - b1 - b2 - b3,
// contact point c = Σ b_i x[i], unit normal n from the tet towards the particle.
//   C(p0, x0..x3) = n · (p0 - c) ≥ 0,   ∇_{p0} C = n,   ∇_{x[i]} C = -b_i n,
//   so nᵀ K n = w0 + Σ b_i² w_i = k (the inverse effective mass along any direction).
// Position solve (accumulated, clamped):  λ' = max(λ - C/k, 0),  Δλ = λ' - λ,
//   Δp0 = w0 Δλ n,  Δx[i] = -w_i b_i Δλ n.
// Velocity solve (Coulomb friction): u = v0 - Σ b_i v[i], u_t = u - (u·n) n, t = u_t/|u_t|,
//   p = min(|u_t| / k, μ λ_n),  Δv0 = -w0 p t,  Δv[i] = w_i b_i p t.
// Every step is branch-free: a lane whose contact is invalid (both sides static, non-unit
// normal, no sliding, no normal impulse) gets zero corrections and keeps its λ.
#if defined(TESSERA_CORE_KERNELS_PARTICLE_TET_CONTACT_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_PARTICLE_TET_CONTACT_INL_H_
#undef TESSERA_CORE_KERNELS_PARTICLE_TET_CONTACT_INL_H_
#else
#define TESSERA_CORE_KERNELS_PARTICLE_TET_CONTACT_INL_H_
#endif

#include "lane_math-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

/// How far |n|² may be from 1 for a normal to count as a unit vector.
inline constexpr double kContactUnitNormalTolerance = 1e-4;

/// b0..b3 from bary = (b1, b2, b3).
template <class V>
HWY_INLINE void contact_tet_weights(const Vec3<V>& bary, V (&b)[4]) {
  b[0] = splat<V>(1.0) - (bary.x + bary.y + bary.z);
  b[1] = bary.x;
  b[2] = bary.y;
  b[3] = bary.z;
}

/// k = w0 + Σ b_i² w_i.
template <class V>
HWY_INLINE V contact_inverse_mass(V w0, const V (&w)[4], const V (&b)[4]) {
  V k = w0;
  for (int i = 0; i < 4; ++i) k = k + b[i] * b[i] * w[i];
  return k;
}

/// u = v0 - Σ b_i v[i]: the particle's velocity relative to the tet's contact point.
template <class V>
HWY_INLINE Vec3<V> contact_relative_velocity(const Vec3<V>& v0, const Vec3<V> (&v)[4],
                                             const V (&b)[4]) {
  Vec3<V> u = v0;
  for (int i = 0; i < 4; ++i) u -= v[i] * b[i];
  return u;
}

/// What init_ stores per contact (the seed's constraintInfo): normal, unit tangent of the
/// sliding (0 when none), 1/k, |u_t|/k and u·n. All zero where invalid.
template <class V>
struct ContactInfo {
  Vec3<V> normal;
  Vec3<V> tangent;
  V effective_mass;
  V max_tangential_impulse;
  V normal_speed;
  Mask<V> valid;
};

template <class V>
HWY_INLINE ContactInfo<V> contact_init(V w0, const V (&w)[4], const Vec3<V>& v0,
                                       const Vec3<V> (&v)[4], const Vec3<V>& bary,
                                       const Vec3<V>& normal) {
  V b[4];
  contact_tet_weights(bary, b);
  const V k = contact_inverse_mass(w0, w, b);
  ContactInfo<V> info;
  info.valid = mask_and(
      k > splat<V>(kDegenerateTolerance),
      lane_abs(squared_norm(normal) - splat<V>(1.0)) <= splat<V>(kContactUnitNormalTolerance));
  const Vec3<V> u = contact_relative_velocity(v0, v, b);
  const V normal_speed = dot(u, normal);
  const Vec3<V> tangential = u - normal * normal_speed;
  const V tangential_speed = norm(tangential);
  const Mask<V> sliding =
      mask_and(info.valid, tangential_speed > splat<V>(kDegenerateTolerance));
  info.normal = keep_if(info.valid, normal);
  info.tangent = tangential * safe_divide(splat<V>(1.0), tangential_speed, sliding);
  info.max_tangential_impulse = safe_divide(tangential_speed, k, sliding);
  info.effective_mass = safe_divide(splat<V>(1.0), k, info.valid);
  info.normal_speed = select(info.valid, normal_speed, zero<V>());
  return info;
}

/// Corrections of the five particles (particle first) and the lanes that were solved.
template <class V>
struct ContactCorrection {
  Vec3<V> particle;
  Vec3<V> tet[4];
  Mask<V> valid;
};

/// The position solve: pushes the particle out along n with the accumulated multiplier
/// `lambda` clamped at 0. Lanes with effective_mass ≤ 0 (init_ failed) keep λ and get zero.
template <class V>
HWY_INLINE ContactCorrection<V> contact_position_solve(V w0, const V (&w)[4],
                                                       const Vec3<V>& p0,
                                                       const Vec3<V> (&x)[4],
                                                       const Vec3<V>& bary,
                                                       const Vec3<V>& normal, V effective_mass,
                                                       V& lambda) {
  V b[4];
  contact_tet_weights(bary, b);
  Vec3<V> contact_point = x[0] * b[0];
  for (int i = 1; i < 4; ++i) contact_point += x[i] * b[i];
  const V C = dot(normal, p0 - contact_point);
  ContactCorrection<V> result;
  result.valid = effective_mass > zero<V>();
  const V accumulated = lane_max(lambda - C * effective_mass, zero<V>());
  const V delta_lambda = select(result.valid, accumulated - lambda, zero<V>());
  lambda = lambda + delta_lambda;
  const Vec3<V> impulse = keep_if(result.valid, normal * delta_lambda);
  result.particle = impulse * w0;
  for (int i = 0; i < 4; ++i) result.tet[i] = impulse * (zero<V>() - w[i] * b[i]);
  return result;
}

/// The velocity solve: Coulomb friction bounded by friction · normal_impulse.
template <class V>
HWY_INLINE ContactCorrection<V> contact_velocity_solve(V w0, const V (&w)[4], const Vec3<V>& v0,
                                                       const Vec3<V> (&v)[4],
                                                       const Vec3<V>& bary,
                                                       const Vec3<V>& normal, V normal_impulse,
                                                       V friction) {
  V b[4];
  contact_tet_weights(bary, b);
  const V k = contact_inverse_mass(w0, w, b);
  const V bound = friction * normal_impulse;
  const Vec3<V> u = contact_relative_velocity(v0, v, b);
  const Vec3<V> tangential = u - normal * dot(u, normal);
  const V tangential_speed = norm(tangential);
  ContactCorrection<V> result;
  result.valid =
      mask_and(mask_and(k > splat<V>(kDegenerateTolerance), bound > zero<V>()),
               tangential_speed > splat<V>(kDegenerateTolerance));
  const Vec3<V> tangent =
      tangential * safe_divide(splat<V>(1.0), tangential_speed, result.valid);
  const V impulse = lane_min(safe_divide(tangential_speed, k, result.valid), bound);
  const Vec3<V> applied = keep_if(result.valid, tangent * impulse);
  result.particle = applied * (zero<V>() - w0);
  for (int i = 0; i < 4; ++i) result.tet[i] = applied * (w[i] * b[i]);
  return result;
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_PARTICLE_TET_CONTACT_INL_H_
