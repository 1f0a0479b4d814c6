// Tethers in SoA batches: validation at the door, then the batched kernel, compiled once per
// SIMD target (Highway foreach_target) and dispatched at run time.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "tether_constraints.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/core/tether_constraints.hpp>

#include "kernels/batch_loop-inl.h"
#include "kernels/residual_lanes-inl.h"
#include "kernels/tether-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

void ProjectTetherConstraints(ParticleArrays particles, TetherConstraints& constraints,
                              std::size_t begin, std::size_t end, ProjectionSettings settings) {
  const RealTag d;
  const Real* max_distance = constraints.max_distance.data();
  project_constraint_lanes<2>(
      particles, constraints.particles,
      {constraints.stiffness.data(), constraints.compliance.data(), constraints.lambda.data()},
      begin, end, settings, [&](const Vec3<RealLanes> (&p)[2], std::size_t i) {
        return tether_constraint(p[0], p[1], hn::LoadU(d, max_distance + i));
      });
}

void TetherResiduals(const ParticleArrays& particles, const TetherConstraints& batch,
                     std::size_t begin, std::size_t end, Real inverse_dt2, Real* out) {
  residual_lanes<2>(particles, batch.particles, begin, end, out,
                    [&](const Vec3<RealLanes> (&p)[2], std::size_t i) {
                      const RealLanes reach = load(batch.max_distance.data(), i);
                      const RealLanes C = norm(p[0] - p[1]) - reach;
                      const RealLanes h = xpbd_residual(C, batch.compliance.data(),
                                                        batch.lambda.data(), i, inverse_dt2);
                      return relative(lane_max(h, zero<RealLanes>()), reach);
                    });
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include <tessera/core/position_based_dynamics_extensions.hpp>

#include "constraint_validation.hpp"
#include "sequential_loop.hpp"

namespace tessera {

HWY_EXPORT(ProjectTetherConstraints);
HWY_EXPORT(TetherResiduals);

TetherConstraints make_tether_constraints(const TetherConstraintInput& input) {
  const detail::ConstraintValidator validator(TetherConstraints::kFamily,
                                              input.rest_positions.size());
  validator.check_parameter("stiffness", input.stiffness);
  validator.check_parameter("compliance", input.compliance);
  TetherConstraints result;
  result.particles = validator.particles<2>(input.particles);
  const std::size_t n = result.size();
  const bool given = !input.max_distances.empty();
  if (given && input.max_distances.size() != n)
    validator.fail_input(std::to_string(input.max_distances.size()) + " reaches for " +
                         std::to_string(n) + " tethers");
  result.max_distance = detail::filled(n, 0);
  for (std::size_t c = 0; c < n; ++c) {
    const auto [p0, p1] = validator.rest_points<2>(result.particles, input.rest_positions, c);
    const Real reach = given                    ? input.max_distances[c]
                       : input.max_distance != 0 ? input.max_distance
                                                 : (p0 - p1).norm();
    validator.check_positive(c, "reach", reach);
    result.max_distance[c] = reach;
  }
  result.stiffness = detail::filled(n, input.stiffness);
  result.compliance = detail::filled(n, input.compliance);
  result.lambda = detail::filled(n, 0);
  return result;
}

void project_tether_constraints(ParticleArrays particles, TetherConstraints& constraints,
                                std::size_t begin, std::size_t end,
                                const ProjectionSettings& settings) {
  check_projection_range(TetherConstraints::kFamily, begin, end, constraints.size(),
                         constraints.particles.particle_count, particles);
  HWY_DYNAMIC_DISPATCH(ProjectTetherConstraints)(particles, constraints, begin, end, settings);
}

void constraint_residuals(const ParticleArrays& particles, const TetherConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(TetherResiduals)(particles, batch, begin, end, Real(0), out);
}

void xpbd_residuals(const ParticleArrays& particles, const TetherConstraints& batch,
                    std::size_t begin, std::size_t end, Real dt, Real* out) {
  HWY_DYNAMIC_DISPATCH(TetherResiduals)(particles, batch, begin, end, detail::inverse_squared(dt), out);
}

void project_sequentially(ParticleArrays particles, TetherConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings) {
  detail::project_stiffness_or_compliance(
      particles, batch, begin, end, settings,
      PositionBasedDynamicsExtensions::solve_TetherConstraint,
      XPBDExtensions::solve_TetherConstraint, [&](std::size_t c) { return batch.max_distance[c]; });
}

}  // namespace tessera
#endif  // HWY_ONCE
