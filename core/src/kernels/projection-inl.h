// The two projection rules every constraint formula ends with, written once over lanes.
//
// A family's formula evaluates its constraint C, the gradients ∇_i C of its N particles and a
// mask of the lanes whose configuration is valid (not degenerate); then
//   project_pbd:  Δp_i = -k · C / (Σ_j w_j |∇_j C|²) · w_i ∇_i C      (Müller et al. 2007)
//   project_xpbd: α̃ = α/dt², Δλ = (-C - α̃ λ) / (Σ_j w_j |∇_j C|² + α̃), λ += Δλ,
//                 Δp_i = w_i Δλ ∇_i C                                   (Macklin et al. 2016)
// Both return the mask of lanes that were projected; every other lane gets zero corrections
// (and an unchanged λ). A static particle (w = 0) always gets exactly zero.
//
// α̃ is α · (1/dt²): the reciprocal is the same for every lane and batch, so a loop computes
// it once and each lane multiplies (a division per lane sat on the projection's path).
//
// A two-particle family whose gradients are a unit direction and its opposite (distance,
// tether: ∇_{p0} C = n = d/|d|, ∇_{p1} C = −n) returns a DirectionValue instead: d and |d|,
// not n. With |n|² = 1 the rules above become, for the one division they need,
//   project_pbd:  s = k · C / ((w0 + w1) |d|),               Δp0 = −s w0 d,  Δp1 = s w1 d
//   project_xpbd: t = (−C − α̃ λ) / ((w0 + w1 + α̃) |d|),   Δλ = t |d|,  Δp0 = t w0 d,  Δp1 = −t w1 d
// (t = Δλ/|d|): the normalisation n = d/|d| and the sum Σ w |∇C|² leave the path from the
// positions to the corrections, which in the distance kernel was three divisions long.
#if defined(TESSERA_CORE_KERNELS_PROJECTION_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_PROJECTION_INL_H_
#undef TESSERA_CORE_KERNELS_PROJECTION_INL_H_
#else
#define TESSERA_CORE_KERNELS_PROJECTION_INL_H_
#endif

#include "lane_math-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

/// C, its gradients and the lanes where they are defined.
template <class V, int N>
struct ConstraintValue {
  V C;
  Vec3<V> gradient[N];
  Mask<V> valid;
};

/// C of a two-particle constraint whose gradients are ±d/|d| (see the top of this file), and
/// the lanes where they are defined (|d| not degenerate).
template <class V>
struct DirectionValue {
  V C;
  Vec3<V> difference;  // d = p0 − p1
  V length;            // |d|
  Mask<V> valid;
};

/// Lanes whose value is finite (x - x is 0 only for finite x).
template <class V>
HWY_INLINE Mask<V> is_finite(V x) {
  return (x - x) == zero<V>();
}

template <class V, int N>
HWY_INLINE V weighted_gradient_norm(const ConstraintValue<V, N>& value, const V (&w)[N]) {
  V sum = w[0] * squared_norm(value.gradient[0]);
  for (int i = 1; i < N; ++i) sum = sum + w[i] * squared_norm(value.gradient[i]);
  return sum;
}

template <class V>
HWY_INLINE V degenerate_denominator() {
  return splat<V>(double(kDegenerateTolerance) * double(kDegenerateTolerance));
}

/// α̃ = α · (1/dt²) where valid, 0 elsewhere (1/dt² is invariant in a loop over lanes).
template <class V>
HWY_INLINE V scaled_compliance(V compliance, V dt, const Mask<V>& valid) {
  const V inverse_dt2 = splat<V>(1.0) / select(dt > zero<V>(), dt * dt, splat<V>(1.0));
  return select(valid, compliance * inverse_dt2, zero<V>());
}

template <class V, int N>
HWY_INLINE Mask<V> project_pbd(const ConstraintValue<V, N>& value, const V (&w)[N],
                               V stiffness, Vec3<V> (&corr)[N]) {
  const V denominator = weighted_gradient_norm(value, w);
  const Mask<V> valid = mask_and(mask_and(value.valid, is_finite(value.C)),
                                 denominator > degenerate_denominator<V>());
  const V s = safe_divide(stiffness * value.C, denominator, valid);
  for (int i = 0; i < N; ++i) corr[i] = keep_if(valid, value.gradient[i] * (zero<V>() - s * w[i]));
  return valid;
}

template <class V, int N>
HWY_INLINE Mask<V> project_xpbd(const ConstraintValue<V, N>& value, const V (&w)[N],
                                V compliance, V dt, V& lambda, Vec3<V> (&corr)[N]) {
  const V weighted = weighted_gradient_norm(value, w);
  const Mask<V> valid = mask_and(
      mask_and(mask_and(value.valid, is_finite(value.C)), weighted > degenerate_denominator<V>()),
      mask_and(dt > zero<V>(), compliance >= zero<V>()));
  const V alpha_tilde = scaled_compliance(compliance, dt, valid);
  const V delta_lambda =
      safe_divide(zero<V>() - value.C - alpha_tilde * lambda, weighted + alpha_tilde, valid);
  lambda = lambda + delta_lambda;
  for (int i = 0; i < N; ++i) corr[i] = keep_if(valid, value.gradient[i] * (delta_lambda * w[i]));
  return valid;
}

template <class V>
HWY_INLINE Mask<V> project_pbd(const DirectionValue<V>& value, const V (&w)[2], V stiffness,
                               Vec3<V> (&corr)[2]) {
  const V weighted = w[0] + w[1];
  const Mask<V> valid = mask_and(mask_and(value.valid, is_finite(value.C)),
                                 weighted > degenerate_denominator<V>());
  const V s = safe_divide(stiffness * value.C, weighted * value.length, valid);
  corr[0] = keep_if(valid, value.difference * (zero<V>() - s * w[0]));
  corr[1] = keep_if(valid, value.difference * (s * w[1]));
  return valid;
}

template <class V>
HWY_INLINE Mask<V> project_xpbd(const DirectionValue<V>& value, const V (&w)[2], V compliance,
                                V dt, V& lambda, Vec3<V> (&corr)[2]) {
  const V weighted = w[0] + w[1];
  const Mask<V> valid = mask_and(
      mask_and(mask_and(value.valid, is_finite(value.C)), weighted > degenerate_denominator<V>()),
      mask_and(dt > zero<V>(), compliance >= zero<V>()));
  const V alpha_tilde = scaled_compliance(compliance, dt, valid);
  const V t = safe_divide(zero<V>() - value.C - alpha_tilde * lambda,
                          (weighted + alpha_tilde) * value.length, valid);
  lambda = lambda + select(valid, t * value.length, zero<V>());
  corr[0] = keep_if(valid, value.difference * (t * w[0]));
  corr[1] = keep_if(valid, value.difference * (zero<V>() - t * w[1]));
  return valid;
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_PROJECTION_INL_H_
