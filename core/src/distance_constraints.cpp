// Distance constraints in SoA batches: validation at the door, then the batched kernel,
// compiled once per SIMD target (Highway foreach_target) and dispatched at run time.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "distance_constraints.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/core/distance_constraints.hpp>

#include "kernels/batch-inl.h"
#include "kernels/distance-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

void ProjectDistanceConstraints(ParticleArrays particles, DistanceConstraints& constraints,
                                std::size_t begin, std::size_t end,
                                ProjectionSettings settings) {
  const RealTag d;
  const std::size_t lanes = hn::Lanes(d);
  const ParticleIndex* slot0 = constraints.particles.particle[0].data();
  const ParticleIndex* slot1 = constraints.particles.particle[1].data();
  const bool compliance = settings.semantics == ConstraintSemantics::compliance;
  const RealLanes dt = hn::Set(d, settings.dt);
  for (std::size_t i = begin; i < end; i += lanes) {
    const std::size_t active_count = end - i;
    const LaneMask active = hn::FirstN(d, active_count);
    const ParticleLanes a = gather_particles(particles, slot0 + i);
    const ParticleLanes b = gather_particles(particles, slot1 + i);
    const auto value = distance_constraint(a.position, b.position,
                                           hn::LoadU(d, constraints.rest_length.data() + i));
    const RealLanes w[2] = {a.inverse_mass, b.inverse_mass};
    Vec3<RealLanes> corr[2];
    if (compliance) {
      RealLanes lambda = hn::LoadU(d, constraints.lambda.data() + i);
      project_xpbd(value, w, hn::LoadU(d, constraints.compliance.data() + i), dt, lambda, corr);
      store_active(lambda, active_count, constraints.lambda.data() + i);
    } else {
      project_pbd(value, w, hn::LoadU(d, constraints.stiffness.data() + i), corr);
    }
    scatter_corrected(particles, slot0 + i, a, corr[0], active);
    scatter_corrected(particles, slot1 + i, b, corr[1], active);
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include "constraint_validation.hpp"

namespace tessera {

HWY_EXPORT(ProjectDistanceConstraints);

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
    const Vector3r& p0 = input.rest_positions[result.particles.particle[0][c]];
    const Vector3r& p1 = input.rest_positions[result.particles.particle[1][c]];
    if (!p0.allFinite() || !p1.allFinite()) validator.fail(c, "rest position is not finite");
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

}  // namespace tessera
#endif  // HWY_ONCE
