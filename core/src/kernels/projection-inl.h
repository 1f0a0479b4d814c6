// The two projection rules every constraint formula ends with, written once over lanes.
//
// A family's formula evaluates its constraint C, the gradients ∇_i C of its N particles and a
// mask of the lanes whose configuration is valid (not degenerate); then
//   project_pbd:  Δp_i = -k · C / (Σ_j w_j |∇_j C|²) · w_i ∇_i C      (Müller et al. 2007)
//   project_xpbd: α̃ = α/dt² (0 for α = 0), Δλ = (-C - α̃ λ) / (Σ_j w_j |∇_j C|² + α̃), λ += Δλ,
//                 Δp_i = w_i Δλ ∇_i C                                   (Macklin et al. 2016)
// Both return the mask of lanes that were projected; every other lane gets zero corrections
// (and an unchanged λ). A static particle (w = 0) always gets exactly zero.
//
// Two other forms, equal in exact arithmetic and with the same contract, take a division or a
// sum of squares off a family's path to its corrections:
// - a constraint C = sqrt(2E) of an energy E (the XPBD FEM tetrahedron) returns an EnergyValue:
//   ∇E and C² = 2E, not ∇C = ∇E / C (see project_xpbd for it below);
// - the strain sub-constraints give Σ w|∇C|² as a quadratic form in ∂C/∂f (strain-inl.h) and
//   take the PBD multiplier and mask from pbd_multiplier.
//
// α̃ is α · (1/dt²): the reciprocal is the same for every lane and batch, so the batch loop
// makes it once (TimeStep) and each batch multiplies, where it divided per batch before (the
// scalar API makes it per call).
//
// A two-particle family whose gradients are a unit direction and its opposite (distance,
// tether: ∇_{p0} C = n = d/|d|, ∇_{p1} C = −n) returns a DirectionValue instead: d and |d|,
// not n. With |n|² = 1 the rules above become, for the one division they need,
//   project_pbd:  s = k · C / ((w0 + w1) |d|),             Δp0 = −s w0 d,  Δp1 = s w1 d
//   project_xpbd: t = (−C − α̃ λ) / ((w0 + w1 + α̃) |d|),   Δp0 = t w0 d,   Δp1 = −t w1 d,
//                 Δλ = t |d|
// (t = Δλ/|d|): the normalisation n = d/|d| and the sum Σ w |∇C|² leave the path from the
// positions to the corrections, which in the distance kernel was a square root and two
// divisions long (α/dt² was a third division per batch).
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
/// the lanes where they are defined (|d| not degenerate; a family may narrow them, as the
/// tether does to C > 0).
template <class V>
struct DirectionValue {
  V C;
  Vec3<V> difference;  // d = p0 − p1
  V length;            // |d|
  Mask<V> valid;
};

/// C = sqrt(2E) of an energy E, given by C² = 2E and ∇E rather than C and ∇C = ∇E / C (see
/// project_xpbd for it), and the lanes where the formula is defined.
template <class V, int N>
struct EnergyValue {
  V squared_C;                  // 2E
  Vec3<V> energy_gradient[N];   // ∇_i E = C ∇_i C
  Mask<V> valid;
};

/// Lanes whose value is finite (x - x is 0 only for finite x).
template <class V>
HWY_INLINE Mask<V> is_finite(V x) {
  return (x - x) == zero<V>();
}

/// Σ_i w_i |g_i|².
template <class V, int N>
HWY_INLINE V weighted_squared_norm(const Vec3<V> (&g)[N], const V (&w)[N]) {
  V sum = w[0] * squared_norm(g[0]);
  for (int i = 1; i < N; ++i) sum = sum + w[i] * squared_norm(g[i]);
  return sum;
}

template <class V, int N>
HWY_INLINE V weighted_gradient_norm(const ConstraintValue<V, N>& value, const V (&w)[N]) {
  return weighted_squared_norm(value.gradient, w);
}

template <class V>
HWY_INLINE V degenerate_denominator() {
  return splat<V>(double(kDegenerateTolerance) * double(kDegenerateTolerance));
}

/// An XPBD projection's time step and 1/dt² (0 where dt is not positive; Inf where dt is so
/// small that 1/dt² overflows), made once per loop over batches.
template <class V>
struct TimeStep {
  V dt;
  V inverse_squared;

  static HWY_INLINE TimeStep of(V dt) {
    const Mask<V> positive = dt > zero<V>();
    return {dt, select(positive, splat<V>(1.0) / select(positive, dt * dt, splat<V>(1.0)),
                       zero<V>())};
  }
};

/// α̃ = α · (1/dt²), 0 for α = 0 whatever dt (1/dt² may be Inf); the projections leave
/// lanes whose α̃ is not finite.
template <class V>
HWY_INLINE V scaled_compliance(V compliance, const TimeStep<V>& step) {
  return select(compliance == zero<V>(), zero<V>(), compliance * step.inverse_squared);
}

/// The lanes whose time step and compliance an XPBD projection accepts: dt > 0 and α ≥ 0
/// with a finite α̃ (also what a family reports for a lane it leaves satisfied).
template <class V>
HWY_INLINE Mask<V> xpbd_inputs_valid(const TimeStep<V>& step, V compliance, V alpha_tilde) {
  return mask_and(mask_and(step.dt > zero<V>(), compliance >= zero<V>()), is_finite(alpha_tilde));
}
template <class V>
HWY_INLINE Mask<V> xpbd_inputs_valid(const TimeStep<V>& step, V compliance) {
  return xpbd_inputs_valid(step, compliance, scaled_compliance(compliance, step));
}

/// The lanes a PBD projection may project: the formula's valid lanes with a finite C and a
/// non-degenerate Σ w|∇C|².
template <class V>
HWY_INLINE Mask<V> pbd_valid(const Mask<V>& formula_valid, V C, V weighted) {
  return mask_and(mask_and(formula_valid, is_finite(C)), weighted > degenerate_denominator<V>());
}

/// The lanes an XPBD projection may project: those of a PBD projection, with the time step
/// and compliance accepted.
template <class V>
HWY_INLINE Mask<V> xpbd_valid(const Mask<V>& formula_valid, V C, V weighted,
                              const TimeStep<V>& step, V compliance, V alpha_tilde) {
  return mask_and(pbd_valid(formula_valid, C, weighted),
                  xpbd_inputs_valid(step, compliance, alpha_tilde));
}

/// The PBD rule's multiplier s = k C / Σ w|∇C|² on the lanes it may project (`valid`, from
/// pbd_valid and whatever the family adds), 0 elsewhere; Δp_i = -s w_i ∇_i C.
template <class V>
HWY_INLINE V pbd_multiplier(V stiffness, V C, V weighted, const Mask<V>& valid) {
  return safe_divide(stiffness * C, weighted, valid);
}

template <class V, int N>
HWY_INLINE Mask<V> project_pbd(const ConstraintValue<V, N>& value, const V (&w)[N],
                               V stiffness, Vec3<V> (&corr)[N]) {
  const V denominator = weighted_gradient_norm(value, w);
  const Mask<V> valid = pbd_valid(value.valid, value.C, denominator);
  const V s = pbd_multiplier(stiffness, value.C, denominator, valid);
  for (int i = 0; i < N; ++i) corr[i] = keep_if(valid, value.gradient[i] * (zero<V>() - s * w[i]));
  return valid;
}

template <class V, int N>
HWY_INLINE Mask<V> project_xpbd(const ConstraintValue<V, N>& value, const V (&w)[N],
                                V compliance, const TimeStep<V>& step, V& lambda,
                                Vec3<V> (&corr)[N]) {
  const V weighted = weighted_gradient_norm(value, w);
  const V alpha_tilde = scaled_compliance(compliance, step);
  const Mask<V> valid = xpbd_valid(value.valid, value.C, weighted, step, compliance, alpha_tilde);
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
  const Mask<V> valid = pbd_valid(value.valid, value.C, weighted);
  const V s = safe_divide(stiffness * value.C, weighted * value.length, valid);
  corr[0] = keep_if(valid, value.difference * (zero<V>() - s * w[0]));
  corr[1] = keep_if(valid, value.difference * (s * w[1]));
  return valid;
}

template <class V>
HWY_INLINE Mask<V> project_xpbd(const DirectionValue<V>& value, const V (&w)[2], V compliance,
                                const TimeStep<V>& step, V& lambda, Vec3<V> (&corr)[2]) {
  const V weighted = w[0] + w[1];
  const V alpha_tilde = scaled_compliance(compliance, step);
  const Mask<V> valid = xpbd_valid(value.valid, value.C, weighted, step, compliance, alpha_tilde);
  const V t = safe_divide(zero<V>() - value.C - alpha_tilde * lambda,
                          (weighted + alpha_tilde) * value.length, valid);
  lambda = lambda + select(valid, t * value.length, zero<V>());
  corr[0] = keep_if(valid, value.difference * (t * w[0]));
  corr[1] = keep_if(valid, value.difference * (zero<V>() - t * w[1]));
  return valid;
}

/// The XPBD rule for C = sqrt(2E) with ∇C = ∇E / C, written with ∇E and C² = 2E so that 1/C
/// leaves the path from E to the corrections:
///   t = (−C − α̃ λ) C / (Σ_i w_i |∇_i E|² + α̃ C²),   Δλ = t C,   Δp_i = t w_i ∇_i E,
/// the same Δλ and Δp as the rule at the top of this file; the lanes it may project are those
/// where Σ_i w_i |∇_i C|² = Σ_i w_i |∇_i E|² / C² would pass. |∇E|² grows as C³: a
/// lane whose denominator or step overflowed (a float element stretched about a million
/// times) is left alone rather than stepped by 0 or NaN.
template <class V, int N>
HWY_INLINE Mask<V> project_xpbd(const EnergyValue<V, N>& value, const V (&w)[N], V compliance,
                                const TimeStep<V>& step, V& lambda, Vec3<V> (&corr)[N]) {
  const V C = lane_sqrt(value.squared_C);
  const V weighted_energy = weighted_squared_norm(value.energy_gradient, w);
  const V alpha_tilde = scaled_compliance(compliance, step);
  const Mask<V> valid = mask_and(
      mask_and(mask_and(value.valid, is_finite(C)),
               weighted_energy > degenerate_denominator<V>() * value.squared_C),
      xpbd_inputs_valid(step, compliance, alpha_tilde));
  const V denominator = weighted_energy + alpha_tilde * value.squared_C;
  const V t = safe_divide((zero<V>() - C - alpha_tilde * lambda) * C, denominator, valid);
  const Mask<V> projected = mask_and(valid, mask_and(is_finite(denominator), is_finite(t)));
  lambda = lambda + select(projected, t * C, zero<V>());
  for (int i = 0; i < N; ++i) corr[i] = keep_if(projected, value.energy_gradient[i] * (t * w[i]));
  return projected;
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_PROJECTION_INL_H_
