// Isometric bending constraints in SoA batches: validation at the door (each stencil's Q built
// by init_IsometricBendingConstraint, the scalar API's own set-up, and stored as its rank-one
// factor k, Q = k kᵀ, recovered as the scalar API does), then the batched kernel, compiled
// once per SIMD target (Highway foreach_target) and dispatched at run time.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "isometric_bending_constraints.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/core/isometric_bending_constraints.hpp>

#include "kernels/batch_loop-inl.h"
#include "kernels/isometric_bending-inl.h"
#include "kernels/residual_lanes-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

void ProjectIsometricBendingConstraints(ParticleArrays particles,
                                        IsometricBendingConstraints& constraints,
                                        std::size_t begin, std::size_t end,
                                        ProjectionSettings settings) {
  const RealTag d;
  const Real* factor[4];
  for (std::size_t j = 0; j < 4; ++j) factor[j] = constraints.factor[j].data();
  project_constraint_lanes<4>(
      particles, constraints.particles,
      {constraints.stiffness.data(), constraints.compliance.data(), constraints.lambda.data()},
      begin, end, settings, [&](const Vec3<RealLanes> (&p)[4], std::size_t i) {
        const RealLanes k[4] = {hn::LoadU(d, factor[0] + i), hn::LoadU(d, factor[1] + i),
                                hn::LoadU(d, factor[2] + i), hn::LoadU(d, factor[3] + i)};
        return isometric_bending_constraint(p, k);
      });
}

void IsometricBendingResiduals(const ParticleArrays& particles,
                               const IsometricBendingConstraints& batch, std::size_t begin,
                               std::size_t end, Real inverse_dt2, Real* out) {
  residual_lanes<4>(particles, batch.particles, begin, end, out,
                    [&](const Vec3<RealLanes> (&p)[4], std::size_t i) {
                      const RealLanes k[4] = {
                          load(batch.factor[0].data(), i), load(batch.factor[1].data(), i),
                          load(batch.factor[2].data(), i), load(batch.factor[3].data(), i)};
                      // C = ½ |u|² ≥ 0, so |u| = sqrt(2C); the XPBD residual in the same
                      // units is sqrt(2 |C + α̃λ|).
                      const RealLanes h =
                          xpbd_residual(isometric_bending_constraint(p, k).C,
                                        batch.compliance.data(), batch.lambda.data(), i,
                                        inverse_dt2);
                      return lane_sqrt(splat<RealLanes>(2.0) * lane_abs(h));
                    });
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include <tessera/core/xpbd.hpp>

#include "sequential_loop.hpp"
#include <tessera/core/position_based_dynamics.hpp>

#include "constraint_validation.hpp"
#include "degenerate_shape.hpp"
#include "isometric_bending_factor.hpp"

namespace tessera {

HWY_EXPORT(ProjectIsometricBendingConstraints);
HWY_EXPORT(IsometricBendingResiduals);

Matrix4r IsometricBendingConstraints::matrix(std::size_t c) const {
  const Vector4r k(factor[0][c], factor[1][c], factor[2][c], factor[3][c]);
  return k * k.transpose();
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
  for (auto& entries : result.factor) entries = detail::filled(n, 0);
  for (std::size_t c = 0; c < n; ++c) {
    const auto p = validator.rest_points<4>(result.particles, input.rest_positions, c);
    // init_IsometricBendingConstraint's degenerate cases, named.
    if (!((p[3] - p[2]).norm() > kDegenerateTolerance))
      validator.fail(c, "degenerate rest stencil: shared edge p2-p3 has zero length");
    if (detail::flat_triangle((p[2] - p[0]).cross(p[3] - p[0]).norm(),
                              detail::longest_edge({p[0], p[2], p[3]})))
      validator.fail(c, "degenerate rest stencil: triangle (p0, p2, p3) has zero area");
    if (detail::flat_triangle((p[3] - p[1]).cross(p[2] - p[1]).norm(),
                              detail::longest_edge({p[1], p[3], p[2]})))
      validator.fail(c, "degenerate rest stencil: triangle (p1, p3, p2) has zero area");
    Matrix4r Q;
    if (!PositionBasedDynamics::init_IsometricBendingConstraint(p[0], p[1], p[2], p[3], Q) ||
        !Q.allFinite())
      validator.fail(c, "degenerate rest stencil: the bending matrix Q is undefined");
    const Vector4r k = detail::isometric_bending_factor(Q);
    for (std::size_t j = 0; j < 4; ++j) result.factor[j][c] = k[int(j)];
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

void constraint_residuals(const ParticleArrays& particles,
                          const IsometricBendingConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(IsometricBendingResiduals)(particles, batch, begin, end, Real(0), out);
}

void xpbd_residuals(const ParticleArrays& particles, const IsometricBendingConstraints& batch,
                    std::size_t begin, std::size_t end, Real dt, Real* out) {
  HWY_DYNAMIC_DISPATCH(IsometricBendingResiduals)(particles, batch, begin, end,
                                                  detail::inverse_squared(dt), out);
}

void project_sequentially(ParticleArrays particles, IsometricBendingConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings) {
  detail::project_stiffness_or_compliance(
      particles, batch, begin, end, settings, PositionBasedDynamics::solve_IsometricBendingConstraint,
      XPBD::solve_IsometricBendingConstraint, [&](std::size_t c) { return batch.matrix(c); });
}

}  // namespace tessera
#endif  // HWY_ONCE
