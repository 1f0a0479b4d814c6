// Strain triangle constraints in SoA batches: validation at the door (the rest inverse comes
// from the scalar API's init), then the batched kernel — one lane formula, kernels/strain-inl.h
// — compiled once per SIMD target (Highway foreach_target) and dispatched at run time.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "strain_triangle_constraints.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/core/strain_triangle_constraints.hpp>

#include "kernels/batch-inl.h"
#include "kernels/strain-inl.h"
#include "kernels/strain_residual-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

template <bool kNormalizeStretch, bool kNormalizeShear>
HWY_NOINLINE void project_strain_triangle_lanes(ParticleArrays particles,
                                                const StrainTriangleConstraints& constraints,
                                                std::size_t begin, std::size_t end) {
  const RealTag d;
  const std::size_t lanes = hn::Lanes(d);
  const ParticleIndex* slot[3];
  constraint_slots(constraints.particles, slot);
  const Real* stiffness_array[3] = {constraints.xx_stiffness.data(),
                                    constraints.yy_stiffness.data(),
                                    constraints.xy_stiffness.data()};
  for (std::size_t i = begin; i < end; i += lanes) {
    const LaneMask active = hn::FirstN(d, end - i);
    ParticleLanes gathered[3];
    Vec3<RealLanes> p[3];
    RealLanes w[3];
    gather_constraint_particles(particles, slot, i, end, gathered, p, w);
    RealLanes m[2][2];
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j)
        m[k][j] = hn::LoadU(d, constraints.rest_inverse[std::size_t(2 * k + j)].data() + i);
    RealLanes stiffness[3];
    for (int s = 0; s < 3; ++s) stiffness[s] = hn::LoadU(d, stiffness_array[s] + i);
    Vec3<RealLanes> corr[3];
    project_strain<2>(p, w, m, kStrainTriangleEntries, stiffness, kNormalizeStretch,
                      kNormalizeShear, corr);
    scatter_constraint_particles(particles, slot, i, gathered, corr, active);
  }
}

void ProjectStrainTriangleConstraints(ParticleArrays particles,
                                      StrainTriangleConstraints& constraints, std::size_t begin,
                                      std::size_t end) {
  if (constraints.normalize_stretch) {
    if (constraints.normalize_shear)
      project_strain_triangle_lanes<true, true>(particles, constraints, begin, end);
    else
      project_strain_triangle_lanes<true, false>(particles, constraints, begin, end);
  } else {
    if (constraints.normalize_shear)
      project_strain_triangle_lanes<false, true>(particles, constraints, begin, end);
    else
      project_strain_triangle_lanes<false, false>(particles, constraints, begin, end);
  }
}

void StrainTriangleResiduals(const ParticleArrays& particles,
                             const StrainTriangleConstraints& batch, std::size_t begin,
                             std::size_t end, Real* out) {
  green_strain_residuals<3>(particles, batch, begin, end, out);
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE

#include "sequential_loop.hpp"
#include <tessera/core/position_based_dynamics.hpp>

#include "constraint_validation.hpp"

namespace tessera {

HWY_EXPORT(ProjectStrainTriangleConstraints);
HWY_EXPORT(StrainTriangleResiduals);

StrainTriangleConstraints make_strain_triangle_constraints(
    const StrainTriangleConstraintInput& input) {
  const detail::ConstraintValidator validator(StrainTriangleConstraints::kFamily,
                                              input.rest_positions.size());
  validator.check_parameter("xx stiffness", input.xx_stiffness);
  validator.check_parameter("yy stiffness", input.yy_stiffness);
  validator.check_parameter("xy stiffness", input.xy_stiffness);
  StrainTriangleConstraints result;
  result.particles = validator.particles<3>(input.particles);
  const std::size_t n = result.size();
  for (auto& entry : result.rest_inverse) entry = detail::filled(n, 0);
  for (std::size_t c = 0; c < n; ++c) {
    const auto p = validator.rest_points<3>(result.particles, input.rest_positions, c);
    Matrix2r rest_inverse;
    if (!PositionBasedDynamics::init_StrainTriangleConstraint(p[0], p[1], p[2], rest_inverse))
      validator.fail(c, "rest triangle has zero area in the xy plane");
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j) result.rest_inverse[std::size_t(2 * k + j)][c] = rest_inverse(k, j);
  }
  result.xx_stiffness = detail::filled(n, input.xx_stiffness);
  result.yy_stiffness = detail::filled(n, input.yy_stiffness);
  result.xy_stiffness = detail::filled(n, input.xy_stiffness);
  result.normalize_stretch = input.normalize_stretch;
  result.normalize_shear = input.normalize_shear;
  return result;
}

void project_strain_triangle_constraints(ParticleArrays particles,
                                         StrainTriangleConstraints& constraints,
                                         std::size_t begin, std::size_t end,
                                         const ProjectionSettings& /*settings*/) {
  check_projection_range(StrainTriangleConstraints::kFamily, begin, end, constraints.size(),
                         constraints.particles.particle_count, particles);
  HWY_DYNAMIC_DISPATCH(ProjectStrainTriangleConstraints)(particles, constraints, begin, end);
}

void constraint_residuals(const ParticleArrays& particles,
                          const StrainTriangleConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(StrainTriangleResiduals)(particles, batch, begin, end, out);
}

void project_sequentially(ParticleArrays particles, const StrainTriangleConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& /*settings: PBD form only*/) {
  detail::project_batch_in_order(
      particles, batch, begin, end, [&](std::size_t c, const auto& s, auto& corr) {
    detail::call_scalar_api(PositionBasedDynamics::solve_StrainTriangleConstraint, s, corr,
                            detail::rest_inverse_of<2>(batch.rest_inverse, c), batch.xx_stiffness[c],
                            batch.yy_stiffness[c], batch.xy_stiffness[c], batch.normalize_stretch,
                            batch.normalize_shear);
  });
}

}  // namespace tessera
#endif  // HWY_ONCE
