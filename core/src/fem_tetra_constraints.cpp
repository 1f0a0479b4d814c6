// FEM tetrahedron constraints in SoA batches: validation at the door (rest volume and inverse
// from the scalar API's init, the material checked once), then the batched PBD and XPBD
// kernels — one lane formula, kernels/fem-inl.h, with the branch-free SVD of svd3-inl.h for
// the inversion-robust material — compiled once per SIMD target (Highway foreach_target) and
// dispatched at run time.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "fem_tetra_constraints.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/core/fem_tetra_constraints.hpp>

#include "kernels/batch-inl.h"
#include "kernels/fem-inl.h"
#include "kernels/strain_residual-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

template <bool kCompliance, bool kHandleInversion>
HWY_NOINLINE void project_fem_tetra_lanes(ParticleArrays particles,
                                          FEMTetraConstraints& constraints, std::size_t begin,
                                          std::size_t end, const ProjectionSettings& settings) {
  const RealTag d;
  const std::size_t lanes = hn::Lanes(d);
  const ParticleIndex* slot[4];
  constraint_slots(constraints.particles, slot);
  const auto step = TimeStep<RealLanes>::of(hn::Set(d, settings.dt));
  const bool lambda_starts_at_zero = settings.lambda_starts_at_zero;
  // The arrays' addresses, read once: the scatter's vector stores may alias anything, so
  // through `constraints` each batch would reload them.
  const Real* rest_inverse_entry[9];
  for (int k = 0; k < 9; ++k)
    rest_inverse_entry[k] = constraints.rest_inverse[std::size_t(k)].data();
  const Real* volume_of = constraints.volume.data();
  const Real* poisson_of = constraints.poisson_ratio.data();
  const Real* compliance_of = constraints.compliance.data();
  const Real* youngs_modulus_of = constraints.youngs_modulus.data();
  Real* lambda_of = constraints.lambda.data();
  for (std::size_t i = begin; i < end; i += lanes) {
    const std::size_t active_count = end - i;
    const LaneMask active = hn::FirstN(d, active_count);
    ParticleLanes gathered[4];
    Vec3<RealLanes> p[4];
    RealLanes w[4];
    gather_constraint_particles(particles, slot, i, end, gathered, p, w);
    Mat3<RealLanes> rest_inverse;
    for (int j = 0; j < 3; ++j)
      rest_inverse.col[j] = {hn::LoadU(d, rest_inverse_entry[j] + i),
                             hn::LoadU(d, rest_inverse_entry[3 + j] + i),
                             hn::LoadU(d, rest_inverse_entry[6 + j] + i)};
    const RealLanes volume = hn::LoadU(d, volume_of + i);
    const RealLanes poisson = hn::LoadU(d, poisson_of + i);
    Vec3<RealLanes> corr[4];
    if constexpr (kCompliance) {
      RealLanes lambda = lambda_starts_at_zero ? hn::Zero(d) : hn::LoadU(d, lambda_of + i);
      fem_tetra_xpbd(p, w, volume, rest_inverse, poisson, hn::LoadU(d, compliance_of + i), step,
                     kHandleInversion, lambda, corr);
      store_active(lambda, active_count, lambda_of + i);
    } else {
      fem_tetra_pbd(p, w, volume, rest_inverse, hn::LoadU(d, youngs_modulus_of + i), poisson,
                    kHandleInversion, corr);
    }
    scatter_constraint_particles(particles, slot, i, gathered, corr, active);
  }
}

void ProjectFEMTetraConstraints(ParticleArrays particles, FEMTetraConstraints& constraints,
                                std::size_t begin, std::size_t end,
                                ProjectionSettings settings) {
  const bool compliance = settings.semantics == ConstraintSemantics::compliance;
  if (compliance) {
    if (constraints.handle_inversion)
      project_fem_tetra_lanes<true, true>(particles, constraints, begin, end, settings);
    else
      project_fem_tetra_lanes<true, false>(particles, constraints, begin, end, settings);
  } else {
    if (constraints.handle_inversion)
      project_fem_tetra_lanes<false, true>(particles, constraints, begin, end, settings);
    else
      project_fem_tetra_lanes<false, false>(particles, constraints, begin, end, settings);
  }
}

void FEMTetraResiduals(const ParticleArrays& particles, const FEMTetraConstraints& batch,
                       std::size_t begin, std::size_t end, Real* out) {
  green_strain_residuals<4>(particles, batch, begin, end, out);
}

/// |C + α̃λ| / sqrt(V) with the XPBD form's C = sqrt(2 V ψ₁(F)) (xpbd.hpp): sqrt(2 ψ₁) is a
/// strain-sized number (ψ₁ ≈ ½ ε² for a small strain ε), so the residual reads like the
/// Green strain it replaces.
void FEMTetraXpbdResiduals(const ParticleArrays& particles, const FEMTetraConstraints& batch,
                           std::size_t begin, std::size_t end, Real inverse_dt2, Real* out) {
  const RealTag d;
  residual_lanes<4>(particles, batch.particles, begin, end, out,
                    [&](const Vec3<RealLanes> (&p)[4], std::size_t i) {
                      RealLanes m[3][3];
                      rest_inverse_of<3>(batch.rest_inverse, i, m);
                      Mat3<RealLanes> rest_inverse;
                      for (int j = 0; j < 3; ++j)
                        rest_inverse.col[j] = {m[0][j], m[1][j], m[2][j]};
                      const RealLanes volume = load(batch.volume.data(), i);
                      const RealLanes nu = load(batch.poisson_ratio.data(), i);
                      const Mask<RealLanes> valid =
                          mask_and(valid_poisson_ratio(nu), volume > zero<RealLanes>());
                      RealLanes mu, lame;
                      lame_parameters(hn::Set(d, Real(1)), nu, valid, mu, lame);
                      const TetraEnergy<RealLanes> element = fem_tetra_energy(
                          p, volume, rest_inverse, mu, lame, batch.handle_inversion);
                      const RealLanes C = lane_sqrt(splat<RealLanes>(2.0) *
                                                    lane_max(element.energy, zero<RealLanes>()));
                      const RealLanes h = xpbd_residual(C, batch.compliance.data(),
                                                        batch.lambda.data(), i, inverse_dt2);
                      return safe_divide(lane_abs(h), lane_sqrt(volume), valid);
                    });
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include <tessera/core/xpbd.hpp>

#include "sequential_loop.hpp"
#include <cmath>
#include <string>

#include <tessera/core/position_based_dynamics.hpp>

#include "constraint_validation.hpp"

namespace tessera {
HWY_EXPORT(ProjectFEMTetraConstraints);
HWY_EXPORT(FEMTetraResiduals);
HWY_EXPORT(FEMTetraXpbdResiduals);

FEMTetraConstraints make_fem_tetra_constraints(const FEMTetraConstraintInput& input) {
  const detail::ConstraintValidator validator(FEMTetraConstraints::kFamily,
                                              input.rest_positions.size());
  if (!std::isfinite(input.youngs_modulus) || !(input.youngs_modulus > 0))
    validator.fail_input("Young's modulus is " + detail::describe(input.youngs_modulus) +
                         ", must be finite and > 0");
  if (!(input.poisson_ratio > -1 && input.poisson_ratio < Real(0.5)))
    validator.fail_input("Poisson ratio is " + detail::describe(input.poisson_ratio) +
                         ", must lie in (-1, 0.5)");
  FEMTetraConstraints result;
  result.particles = validator.particles<4>(input.particles);
  const std::size_t n = result.size();
  result.volume = detail::filled(n, 0);
  for (auto& entry : result.rest_inverse) entry = detail::filled(n, 0);
  for (std::size_t c = 0; c < n; ++c) {
    const auto p = validator.rest_points<4>(result.particles, input.rest_positions, c);
    Real volume;
    Matrix3r rest_inverse;
    if (!PositionBasedDynamics::init_FEMTetraConstraint(p[0], p[1], p[2], p[3], volume,
                                                        rest_inverse))
      validator.fail(c, "rest tetrahedron is flat (zero volume)");
    result.volume[c] = volume;
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j) result.rest_inverse[std::size_t(3 * k + j)][c] = rest_inverse(k, j);
  }
  result.youngs_modulus = detail::filled(n, input.youngs_modulus);
  result.poisson_ratio = detail::filled(n, input.poisson_ratio);
  result.compliance = detail::filled(n, 1 / input.youngs_modulus);
  result.lambda = detail::filled(n, 0);
  result.handle_inversion = input.handle_inversion;
  return result;
}

void project_fem_tetra_constraints(ParticleArrays particles, FEMTetraConstraints& constraints,
                                   std::size_t begin, std::size_t end,
                                   const ProjectionSettings& settings) {
  check_projection_range(FEMTetraConstraints::kFamily, begin, end, constraints.size(),
                         constraints.particles.particle_count, particles);
  HWY_DYNAMIC_DISPATCH(ProjectFEMTetraConstraints)(particles, constraints, begin, end, settings);
}

void constraint_residuals(const ParticleArrays& particles, const FEMTetraConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(FEMTetraResiduals)(particles, batch, begin, end, out);
}

void xpbd_residuals(const ParticleArrays& particles, const FEMTetraConstraints& batch,
                    std::size_t begin, std::size_t end, Real dt, Real* out) {
  HWY_DYNAMIC_DISPATCH(FEMTetraXpbdResiduals)(particles, batch, begin, end,
                                              detail::inverse_squared(dt), out);
}

void project_sequentially(ParticleArrays particles, FEMTetraConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings) {
  detail::project_batch_in_order(
      particles, batch, begin, end, [&](std::size_t c, const auto& s, auto& corr) {
    const auto rest_inverse = detail::rest_inverse_of<3>(batch.rest_inverse, c);
    if (detail::uses_compliance(settings))
      detail::call_scalar_api(XPBD::solve_FEMTetraConstraint, s, corr, batch.volume[c], rest_inverse,
                              batch.poisson_ratio[c], batch.compliance[c], batch.handle_inversion,
                              settings.dt, batch.lambda[c]);
    else
      detail::call_scalar_api(PositionBasedDynamics::solve_FEMTetraConstraint, s, corr, batch.volume[c], rest_inverse,
                              batch.youngs_modulus[c], batch.poisson_ratio[c],
                              batch.handle_inversion);
  });
}

}  // namespace tessera
#endif  // HWY_ONCE
