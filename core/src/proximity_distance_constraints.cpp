// The three proximity families in SoA batches (point–edge, point–triangle and edge–edge
// distance; headers edge_point_/triangle_point_/edge_edge_distance_constraints.hpp):
// validation at the door, then the batched kernel (each family's lane formula in
// kernels/proximity-inl.h, run by the loop every family shares, kernels/batch_loop-inl.h, with
// the stiffness chosen by the sign of C), compiled once per SIMD target (Highway
// foreach_target) and dispatched at run time. Why one file: the families differ only in their
// formula and particle count, so their builders and entry points are one template each.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "proximity_distance_constraints.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <tessera/core/proximity_distance_constraints.hpp>

#include "kernels/batch_loop-inl.h"
#include "kernels/proximity-inl.h"
#include "kernels/residual_lanes-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

/// Projects constraints [begin, end) of a proximity batch W at a time (stiffness semantics
/// only). formula(positions, rest) returns the family's ConstraintValue<RealLanes, N>.
template <int N, class Constraints, class Formula>
HWY_INLINE void project_proximity_range(ParticleArrays particles, const Constraints& constraints,
                                        std::size_t begin, std::size_t end, Formula formula) {
  const RealTag d;
  project_constraint_lanes<N>(
      particles, constraints.particles, ProjectionParameters{nullptr, nullptr, nullptr}, begin,
      end, ProjectionSettings{},
      [&](const Vec3<RealLanes> (&x)[N], std::size_t i) {
        return formula(x, hn::LoadU(d, constraints.rest_distance.data() + i));
      },
      [&](const ConstraintValue<RealLanes, N>& value, std::size_t i) {
        return proximity_stiffness(value.C,
                                   hn::LoadU(d, constraints.compression_stiffness.data() + i),
                                   hn::LoadU(d, constraints.stretch_stiffness.data() + i));
      });
}

void ProjectEdgePointDistanceConstraints(ParticleArrays particles,
                                         const EdgePointDistanceConstraints& constraints,
                                         std::size_t begin, std::size_t end) {
  project_proximity_range<3>(particles, constraints, begin, end,
                             [](const Vec3<RealLanes> (&x)[3], RealLanes rest_distance) {
                               return edge_point_distance_constraint(x[0], x[1], x[2],
                                                                     rest_distance);
                             });
}

void ProjectTrianglePointDistanceConstraints(ParticleArrays particles,
                                             const TrianglePointDistanceConstraints& constraints,
                                             std::size_t begin, std::size_t end) {
  project_proximity_range<4>(particles, constraints, begin, end,
                             [](const Vec3<RealLanes> (&x)[4], RealLanes rest_distance) {
                               return triangle_point_distance_constraint(x[0], x[1], x[2], x[3],
                                                                         rest_distance);
                             });
}

void ProjectEdgeEdgeDistanceConstraints(ParticleArrays particles,
                                        const EdgeEdgeDistanceConstraints& constraints,
                                        std::size_t begin, std::size_t end) {
  project_proximity_range<4>(particles, constraints, begin, end,
                             [](const Vec3<RealLanes> (&x)[4], RealLanes rest_distance) {
                               return edge_edge_distance_constraint(x[0], x[1], x[2], x[3],
                                                                    rest_distance);
                             });
}

/// The part of C the constraint enforces: a side whose stiffness is 0 asks nothing (a contact
/// made compression-only by a zero stretch stiffness has no residual while it is apart).
template <class Batch>
HWY_INLINE RealLanes enforced(RealLanes C, const Batch& batch, std::size_t i) {
  const RealLanes none = zero<RealLanes>();
  const RealLanes compression = load(batch.compression_stiffness.data(), i);
  const RealLanes stretch = load(batch.stretch_stiffness.data(), i);
  return select(C < none, select(compression > none, C, none), select(stretch > none, C, none));
}

void EdgePointDistanceResiduals(const ParticleArrays& particles,
                                const EdgePointDistanceConstraints& batch, std::size_t begin,
                                std::size_t end, Real* out) {
  residual_lanes<3>(particles, batch.particles, begin, end, out,
                    [&](const Vec3<RealLanes> (&p)[3], std::size_t i) {
                      const RealLanes rest = load(batch.rest_distance.data(), i);
                      return relative(enforced(edge_point_distance_constraint(p[0], p[1], p[2], rest).C, batch, i),
                                      rest);
                    });
}

void TrianglePointDistanceResiduals(const ParticleArrays& particles,
                                    const TrianglePointDistanceConstraints& batch,
                                    std::size_t begin, std::size_t end, Real* out) {
  residual_lanes<4>(
      particles, batch.particles, begin, end, out,
      [&](const Vec3<RealLanes> (&p)[4], std::size_t i) {
        const RealLanes rest = load(batch.rest_distance.data(), i);
        return relative(enforced(triangle_point_distance_constraint(p[0], p[1], p[2], p[3], rest).C, batch, i),
                        rest);
      });
}

void EdgeEdgeDistanceResiduals(const ParticleArrays& particles,
                               const EdgeEdgeDistanceConstraints& batch, std::size_t begin,
                               std::size_t end, Real* out) {
  residual_lanes<4>(
      particles, batch.particles, begin, end, out,
      [&](const Vec3<RealLanes> (&p)[4], std::size_t i) {
        const RealLanes rest = load(batch.rest_distance.data(), i);
        return relative(enforced(edge_edge_distance_constraint(p[0], p[1], p[2], p[3], rest).C, batch, i), rest);
      });
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include <tessera/core/position_based_dynamics.hpp>

#include "sequential_loop.hpp"
#include "constraint_validation.hpp"

namespace tessera {
namespace {

/// The builder of every proximity family: its indices, a rest distance (shared or one per
/// constraint, each ≥ 0) and the compression and stretch stiffness.
template <class Constraints>
void make_proximity_constraints(const ProximityDistanceConstraintInput& input,
                                Constraints& result) {
  const detail::ConstraintValidator validator(Constraints::kFamily, input.particle_count);
  validator.check_parameter("compression stiffness", input.compression_stiffness);
  validator.check_parameter("stretch stiffness", input.stretch_stiffness);
  validator.fill_particles(result.particles, input.particles);
  const std::size_t n = result.size();
  const bool per_constraint = !input.rest_distances.empty();
  if (per_constraint && input.rest_distances.size() != n)
    validator.fail_input(std::to_string(input.rest_distances.size()) + " rest distances for " +
                         std::to_string(n) + " constraints");
  if (!per_constraint) validator.check_parameter("rest distance", input.rest_distance);
  detail::fill(result.rest_distance, n, input.rest_distance);
  if (per_constraint) {
    for (std::size_t c = 0; c < n; ++c) {
      validator.check_non_negative(c, "rest distance", input.rest_distances[c]);
      result.rest_distance[c] = input.rest_distances[c];
    }
  }
  detail::fill(result.compression_stiffness, n, input.compression_stiffness);
  detail::fill(result.stretch_stiffness, n, input.stretch_stiffness);
}

/// make_proximity_constraints into a kept batch: a rejected input leaves `out` empty, never a
/// count its arrays do not match.
template <class Constraints>
void make_proximity_constraints_into(const ProximityDistanceConstraintInput& input,
                                     Constraints& out) {
  try {
    make_proximity_constraints(input, out);
  } catch (...) {
    out = {};
    throw;
  }
}

/// The checks every proximity entry point makes before dispatching: the range and particle
/// count, and stiffness semantics (the seed has no XPBD form of these families).
template <class Constraints>
void check_proximity_projection(ParticleArrays particles, const Constraints& constraints,
                                std::size_t begin, std::size_t end,
                                const ProjectionSettings& settings) {
  check_projection_range(Constraints::kFamily, begin, end, constraints.size(),
                         constraints.particles.particle_count, particles);
  if (settings.semantics != ConstraintSemantics::stiffness)
    throw InvalidInput(std::string(Constraints::kFamily) +
                       " constraints: only stiffness semantics are supported (no XPBD form)");
}

}  // namespace

HWY_EXPORT(ProjectEdgePointDistanceConstraints);
HWY_EXPORT(ProjectTrianglePointDistanceConstraints);
HWY_EXPORT(ProjectEdgeEdgeDistanceConstraints);
HWY_EXPORT(EdgePointDistanceResiduals);
HWY_EXPORT(TrianglePointDistanceResiduals);
HWY_EXPORT(EdgeEdgeDistanceResiduals);

void make_edge_point_distance_constraints(const ProximityDistanceConstraintInput& input,
                                  EdgePointDistanceConstraints& out) {
  make_proximity_constraints_into(input, out);
}

EdgePointDistanceConstraints make_edge_point_distance_constraints(
    const ProximityDistanceConstraintInput& input) {
  EdgePointDistanceConstraints result;
  make_proximity_constraints(input, result);
  return result;
}

void make_triangle_point_distance_constraints(const ProximityDistanceConstraintInput& input,
                                  TrianglePointDistanceConstraints& out) {
  make_proximity_constraints_into(input, out);
}

TrianglePointDistanceConstraints make_triangle_point_distance_constraints(
    const ProximityDistanceConstraintInput& input) {
  TrianglePointDistanceConstraints result;
  make_proximity_constraints(input, result);
  return result;
}

void make_edge_edge_distance_constraints(const ProximityDistanceConstraintInput& input,
                                  EdgeEdgeDistanceConstraints& out) {
  make_proximity_constraints_into(input, out);
}

EdgeEdgeDistanceConstraints make_edge_edge_distance_constraints(
    const ProximityDistanceConstraintInput& input) {
  EdgeEdgeDistanceConstraints result;
  make_proximity_constraints(input, result);
  return result;
}

void project_edge_point_distance_constraints(ParticleArrays particles,
                                             const EdgePointDistanceConstraints& constraints,
                                             std::size_t begin, std::size_t end,
                                             const ProjectionSettings& settings) {
  check_proximity_projection(particles, constraints, begin, end, settings);
  HWY_DYNAMIC_DISPATCH(ProjectEdgePointDistanceConstraints)(particles, constraints, begin, end);
}

void project_triangle_point_distance_constraints(
    ParticleArrays particles, const TrianglePointDistanceConstraints& constraints,
    std::size_t begin, std::size_t end, const ProjectionSettings& settings) {
  check_proximity_projection(particles, constraints, begin, end, settings);
  HWY_DYNAMIC_DISPATCH(ProjectTrianglePointDistanceConstraints)(particles, constraints, begin,
                                                                end);
}

void project_edge_edge_distance_constraints(ParticleArrays particles,
                                            const EdgeEdgeDistanceConstraints& constraints,
                                            std::size_t begin, std::size_t end,
                                            const ProjectionSettings& settings) {
  check_proximity_projection(particles, constraints, begin, end, settings);
  HWY_DYNAMIC_DISPATCH(ProjectEdgeEdgeDistanceConstraints)(particles, constraints, begin, end);
}

void constraint_residuals(const ParticleArrays& particles,
                          const EdgePointDistanceConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(EdgePointDistanceResiduals)(particles, batch, begin, end, out);
}

void project_sequentially(ParticleArrays particles, const EdgePointDistanceConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings) {
  detail::check_proximity_call(particles, batch, begin, end, settings);
  detail::project_batch_in_order(
      particles, batch, begin, end, [&](std::size_t c, const auto& s, auto& corr) {
    detail::call_scalar_api(PositionBasedDynamics::solve_EdgePointDistanceConstraint, s, corr, batch.rest_distance[c],
                            batch.compression_stiffness[c], batch.stretch_stiffness[c]);
  });
}

void constraint_residuals(const ParticleArrays& particles,
                          const TrianglePointDistanceConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(TrianglePointDistanceResiduals)(particles, batch, begin, end, out);
}

void project_sequentially(ParticleArrays particles,
                          const TrianglePointDistanceConstraints& batch, std::size_t begin,
                          std::size_t end, const ProjectionSettings& settings) {
  detail::check_proximity_call(particles, batch, begin, end, settings);
  detail::project_batch_in_order(
      particles, batch, begin, end, [&](std::size_t c, const auto& s, auto& corr) {
    detail::call_scalar_api(PositionBasedDynamics::solve_TrianglePointDistanceConstraint, s, corr, batch.rest_distance[c],
                            batch.compression_stiffness[c], batch.stretch_stiffness[c]);
  });
}

void constraint_residuals(const ParticleArrays& particles,
                          const EdgeEdgeDistanceConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(EdgeEdgeDistanceResiduals)(particles, batch, begin, end, out);
}

void project_sequentially(ParticleArrays particles, const EdgeEdgeDistanceConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings) {
  detail::check_proximity_call(particles, batch, begin, end, settings);
  detail::project_batch_in_order(
      particles, batch, begin, end, [&](std::size_t c, const auto& s, auto& corr) {
    detail::call_scalar_api(PositionBasedDynamics::solve_EdgeEdgeDistanceConstraint, s, corr, batch.rest_distance[c],
                            batch.compression_stiffness[c], batch.stretch_stiffness[c]);
  });
}

}  // namespace tessera
#endif  // HWY_ONCE
