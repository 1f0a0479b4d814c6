// Distance constraints in SoA batches: validation at the door, then the batched kernel,
// compiled once per SIMD target (Highway foreach_target) and dispatched at run time.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "distance_constraints.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/core/distance_constraints.hpp>

#include "kernels/batch_loop-inl.h"
#include "kernels/distance-inl.h"
#include "kernels/residual_lanes-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

void ProjectDistanceConstraints(ParticleArrays particles, DistanceConstraints& constraints,
                                std::size_t begin, std::size_t end,
                                ProjectionSettings settings) {
  const RealTag d;
  const Real* rest_length = constraints.rest_length.data();
  project_constraint_lanes<2>(
      particles, constraints.particles,
      {constraints.stiffness.data(), constraints.compliance.data(), constraints.lambda.data()},
      begin, end, settings, [&](const Vec3<RealLanes> (&p)[2], std::size_t i) {
        return distance_constraint(p[0], p[1], hn::LoadU(d, rest_length + i));
      });
}

void DistanceResiduals(const ParticleArrays& particles, const DistanceConstraints& batch,
                       std::size_t begin, std::size_t end, Real inverse_dt2, Real* out) {
  residual_lanes<2>(particles, batch.particles, begin, end, out,
                    [&](const Vec3<RealLanes> (&p)[2], std::size_t i) {
                      const RealLanes rest_length = load(batch.rest_length.data(), i);
                      const RealLanes C = distance_constraint(p[0], p[1], rest_length).C;
                      return relative(xpbd_residual(C, batch.compliance.data(),
                                                    batch.lambda.data(), i, inverse_dt2),
                                      rest_length);
                    });
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "sequential_loop.hpp"
#include "constraint_validation.hpp"

namespace tessera {

HWY_EXPORT(ProjectDistanceConstraints);
HWY_EXPORT(DistanceResiduals);

DistanceConstraints make_distance_constraints(const DistanceConstraintInput& input) {
  const detail::ConstraintValidator validator(DistanceConstraints::kFamily,
                                              input.rest_positions.size());
  validator.check_parameter("stiffness", input.stiffness);
  validator.check_parameter("compliance", input.compliance);
  DistanceConstraints result;
  result.particles = validator.particles<2>(input.particles);
  const std::size_t n = result.size();
  result.rest_length = detail::filled(n, 0);
  for (std::size_t c = 0; c < n; ++c) {
    const auto [p0, p1] = validator.rest_points<2>(result.particles, input.rest_positions, c);
    const Real length = (p0 - p1).norm();
    if (!(length > kDegenerateTolerance))
      validator.fail(c, "rest length is 0 (particles " +
                            std::to_string(result.particles.particle[0][c]) + " and " +
                            std::to_string(result.particles.particle[1][c]) +
                            " coincide at rest)");
    result.rest_length[c] = length;
  }
  result.stiffness = detail::filled(n, input.stiffness);
  result.compliance = detail::filled(n, input.compliance);
  result.lambda = detail::filled(n, 0);
  return result;
}

void project_distance_constraints(ParticleArrays particles, DistanceConstraints& constraints,
                                  std::size_t begin, std::size_t end,
                                  const ProjectionSettings& settings) {
  check_projection_range(DistanceConstraints::kFamily, begin, end, constraints.size(),
                         constraints.particles.particle_count, particles);
  HWY_DYNAMIC_DISPATCH(ProjectDistanceConstraints)(particles, constraints, begin, end, settings);
}

void constraint_residuals(const ParticleArrays& particles, const DistanceConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(DistanceResiduals)(particles, batch, begin, end, Real(0), out);
}

void xpbd_residuals(const ParticleArrays& particles, const DistanceConstraints& batch,
                    std::size_t begin, std::size_t end, Real dt, Real* out) {
  HWY_DYNAMIC_DISPATCH(DistanceResiduals)(particles, batch, begin, end, detail::inverse_squared(dt), out);
}

void project_sequentially(ParticleArrays particles, DistanceConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings) {
  detail::project_stiffness_or_compliance(
      particles, batch, begin, end, settings, PositionBasedDynamics::solve_DistanceConstraint,
      XPBD::solve_DistanceConstraint, [&](std::size_t c) { return batch.rest_length[c]; });
}

}  // namespace tessera
#endif  // HWY_ONCE
