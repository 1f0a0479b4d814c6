// Isometric bending constraints in SoA batches: validation at the door (each stencil's Q built
// by init_IsometricBendingConstraint, the scalar API's own set-up, and stored as its 10
// distinct entries), then the batched kernel, compiled once per SIMD target (Highway
// foreach_target) and dispatched at run time.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "isometric_bending_constraints.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/core/isometric_bending_constraints.hpp>

#include "kernels/batch_loop-inl.h"
#include "kernels/isometric_bending-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

void ProjectIsometricBendingConstraints(ParticleArrays particles,
                                        IsometricBendingConstraints& constraints,
                                        std::size_t begin, std::size_t end,
                                        ProjectionSettings settings) {
  using Constraints = IsometricBendingConstraints;
  const RealTag d;
  const Real* q[Constraints::kMatrixEntries];
  for (int e = 0; e < Constraints::kMatrixEntries; ++e)
    q[e] = constraints.q[std::size_t(e)].data();
  project_constraint_lanes<4>(
      particles, constraints.particles,
      {constraints.stiffness.data(), constraints.compliance.data(), constraints.lambda.data()},
      begin, end, settings, [&](const Vec3<RealLanes> (&p)[4], std::size_t i) {
        RealLanes Q[4][4];
        for (int r = 0; r < 4; ++r)
          for (int c = r; c < 4; ++c)
            Q[r][c] = Q[c][r] = hn::LoadU(d, q[Constraints::entry(r, c)] + i);
        return isometric_bending_constraint(p, Q);
      });
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include <tessera/core/position_based_dynamics.hpp>

#include "constraint_validation.hpp"

namespace tessera {

HWY_EXPORT(ProjectIsometricBendingConstraints);

Matrix4r IsometricBendingConstraints::matrix(std::size_t c) const {
  Matrix4r Q;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) Q(i, j) = q[std::size_t(entry(i, j))][c];
  return Q;
}

IsometricBendingConstraints make_isometric_bending_constraints(
    const IsometricBendingConstraintInput& input) {
  const detail::ConstraintValidator validator(IsometricBendingConstraints::kFamily,
                                              input.rest_positions.size());
  validator.check_parameter("stiffness", input.stiffness);
  validator.check_parameter("compliance", input.compliance);
  IsometricBendingConstraints result;
  result.particles = validator.particles<4>(input.particles);
  const std::size_t n = result.size();
  for (auto& entries : result.q) entries = detail::filled(n, 0);
  for (std::size_t c = 0; c < n; ++c) {
    Vector3r p[4];
    for (std::size_t k = 0; k < 4; ++k) {
      p[k] = input.rest_positions[result.particles.particle[k][c]];
      if (!p[k].allFinite()) validator.fail(c, "rest position is not finite");
    }
    // init_IsometricBendingConstraint's degenerate cases, named.
    if (!((p[3] - p[2]).norm() > kDegenerateTolerance))
      validator.fail(c, "degenerate rest stencil: shared edge p2-p3 has zero length");
    if (!((p[2] - p[0]).cross(p[3] - p[0]).norm() > kDegenerateTolerance))
      validator.fail(c, "degenerate rest stencil: triangle (p0, p2, p3) has zero area");
    if (!((p[3] - p[1]).cross(p[2] - p[1]).norm() > kDegenerateTolerance))
      validator.fail(c, "degenerate rest stencil: triangle (p1, p3, p2) has zero area");
    Matrix4r Q;
    if (!PositionBasedDynamics::init_IsometricBendingConstraint(p[0], p[1], p[2], p[3], Q) ||
        !Q.allFinite())
      validator.fail(c, "degenerate rest stencil: the bending matrix Q is undefined");
    for (int i = 0; i < 4; ++i)
      for (int j = i; j < 4; ++j)
        result.q[std::size_t(IsometricBendingConstraints::entry(i, j))][c] = Q(i, j);
  }
  result.stiffness = detail::filled(n, input.stiffness);
  result.compliance = detail::filled(n, input.compliance);
  result.lambda = detail::filled(n, 0);
  return result;
}

void project_isometric_bending_constraints(ParticleArrays particles,
                                           IsometricBendingConstraints& constraints,
                                           std::size_t begin, std::size_t end,
                                           const ProjectionSettings& settings) {
  check_projection_range(IsometricBendingConstraints::kFamily, begin, end, constraints.size(),
                         constraints.particles.particle_count, particles);
  HWY_DYNAMIC_DISPATCH(ProjectIsometricBendingConstraints)(particles, constraints, begin, end,
                                                           settings);
}

}  // namespace tessera
#endif  // HWY_ONCE
