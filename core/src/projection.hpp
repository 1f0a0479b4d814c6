// The two projection rules every scalar kernel ends with, written once.
//
// A family's source evaluates its constraint C and the gradients ∇_i C of its N particles,
// then hands them to project_pbd (stiffness semantics, Müller et al. 2007) or project_xpbd
// (compliance semantics, Macklin et al. 2016). Both write every correction, zero it on a
// degenerate denominator, and never write a non-zero correction to a static particle.
#pragma once

#include <array>
#include <cmath>

#include <tessera/core/real.hpp>

namespace tessera::detail {

template <int N>
using Gradients = std::array<Vector3r, N>;

template <int N>
inline void zero_corrections(Vector3r* const (&corr)[N]) {
  for (int i = 0; i < N; ++i) corr[i]->setZero();
}

/// Σ_i w_i |∇_i C|²: the constraint's inverse effective mass along its gradient.
template <int N>
inline Real weighted_gradient_norm(const Gradients<N>& grad, const std::array<Real, N>& w) {
  Real sum = 0;
  for (int i = 0; i < N; ++i) sum += w[i] * grad[i].squaredNorm();
  return sum;
}

/// Δp_i = -k · C / (Σ_j w_j |∇_j C|²) · w_i ∇_i C. Returns false (zero corrections) when the
/// denominator is degenerate.
template <int N>
inline bool project_pbd(Real C, const Gradients<N>& grad, const std::array<Real, N>& w,
                        Real stiffness, Vector3r* const (&corr)[N]) {
  const Real denominator = weighted_gradient_norm<N>(grad, w);
  if (!(denominator > kDegenerateTolerance * kDegenerateTolerance) || !std::isfinite(C)) {
    zero_corrections<N>(corr);
    return false;
  }
  const Real s = stiffness * C / denominator;
  for (int i = 0; i < N; ++i) *corr[i] = (-s * w[i]) * grad[i];
  return true;
}

/// α̃ = compliance / dt²; Δλ = (-C - α̃ λ) / (Σ w |∇C|² + α̃); λ += Δλ; Δp_i = w_i Δλ ∇_i C.
/// Returns false (zero corrections, λ unchanged) for dt ≤ 0, negative compliance or a
/// degenerate denominator.
template <int N>
inline bool project_xpbd(Real C, const Gradients<N>& grad, const std::array<Real, N>& w,
                         Real compliance, Real dt, Real& lambda, Vector3r* const (&corr)[N]) {
  if (!(dt > 0) || !(compliance >= 0) || !std::isfinite(C)) {
    zero_corrections<N>(corr);
    return false;
  }
  const Real alpha_tilde = compliance / (dt * dt);
  const Real weighted = weighted_gradient_norm<N>(grad, w);
  if (!(weighted > kDegenerateTolerance * kDegenerateTolerance)) {
    zero_corrections<N>(corr);
    return false;
  }
  const Real delta_lambda = (-C - alpha_tilde * lambda) / (weighted + alpha_tilde);
  lambda += delta_lambda;
  for (int i = 0; i < N; ++i) *corr[i] = (delta_lambda * w[i]) * grad[i];
  return true;
}

}  // namespace tessera::detail
