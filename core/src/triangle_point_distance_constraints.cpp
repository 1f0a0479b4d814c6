// Point–triangle distance constraints in SoA batches: validation at the door, then the batched
// kernel (the family's lane formula in kernels/proximity-inl.h, the loop shared by the
// proximity families in kernels/proximity_batch-inl.h), compiled once per SIMD target
// (Highway foreach_target) and dispatched at run time.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "triangle_point_distance_constraints.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <tessera/core/triangle_point_distance_constraints.hpp>

#include "kernels/proximity_batch-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

struct TrianglePointDistanceFormula {
  static HWY_INLINE ConstraintValue<RealLanes, 4> evaluate(const Vec3<RealLanes> (&x)[4],
                                                           RealLanes rest_distance) {
    return triangle_point_distance_constraint(x[0], x[1], x[2], x[3], rest_distance);
  }
};

void ProjectTrianglePointDistanceConstraints(ParticleArrays particles,
                                             const TrianglePointDistanceConstraints& constraints,
                                             std::size_t begin, std::size_t end) {
  project_proximity_range<4, TrianglePointDistanceFormula>(
      particles,
      {constraints.particles, constraints.rest_distance.data(),
       constraints.compression_stiffness.data(), constraints.stretch_stiffness.data()},
      begin, end);
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include "constraint_validation.hpp"

namespace tessera {

HWY_EXPORT(ProjectTrianglePointDistanceConstraints);

TrianglePointDistanceConstraints make_triangle_point_distance_constraints(
    const TrianglePointDistanceConstraintInput& input) {
  using Constraints = TrianglePointDistanceConstraints;
  const detail::ConstraintValidator validator(Constraints::kFamily, input.particle_count);
  validator.check_parameter("compression stiffness", input.compression_stiffness);
  validator.check_parameter("stretch stiffness", input.stretch_stiffness);
  Constraints result;
  result.particles = validator.particles<4>(input.particles);
  const std::size_t n = result.size();
  const bool per_constraint = !input.rest_distances.empty();
  if (per_constraint && input.rest_distances.size() != n)
    validator.fail_input(std::to_string(input.rest_distances.size()) + " rest distances for " +
                         std::to_string(n) + " constraints");
  if (!per_constraint) validator.check_parameter("rest distance", input.rest_distance);
  result.rest_distance = detail::filled(n, input.rest_distance);
  if (per_constraint) {
    for (std::size_t c = 0; c < n; ++c) {
      validator.check_non_negative(c, "rest distance", input.rest_distances[c]);
      result.rest_distance[c] = input.rest_distances[c];
    }
  }
  result.compression_stiffness = detail::filled(n, input.compression_stiffness);
  result.stretch_stiffness = detail::filled(n, input.stretch_stiffness);
  return result;
}

void project_triangle_point_distance_constraints(
    ParticleArrays particles, const TrianglePointDistanceConstraints& constraints,
    std::size_t begin, std::size_t end, const ProjectionSettings& settings) {
  check_projection_range(TrianglePointDistanceConstraints::kFamily, begin, end, constraints.size(),
                         constraints.particles.particle_count, particles);
  if (settings.semantics != ConstraintSemantics::stiffness)
    throw InvalidInput(std::string(TrianglePointDistanceConstraints::kFamily) +
                       " constraints: only stiffness semantics are supported (no XPBD form)");
  HWY_DYNAMIC_DISPATCH(ProjectTrianglePointDistanceConstraints)(particles, constraints, begin, end);
}

}  // namespace tessera
#endif  // HWY_ONCE
