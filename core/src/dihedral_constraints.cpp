// Dihedral constraints in SoA batches: validation at the door (rest angles measured with the
// family's own formula), then the batched kernel, compiled once per SIMD target (Highway
// foreach_target) and dispatched at run time.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "dihedral_constraints.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/core/dihedral_constraints.hpp>

#include "kernels/batch_loop-inl.h"
#include "kernels/dihedral-inl.h"
#include "kernels/residual_lanes-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

void ProjectDihedralConstraints(ParticleArrays particles, DihedralConstraints& constraints,
                                std::size_t begin, std::size_t end,
                                ProjectionSettings settings) {
  const RealTag d;
  const Real* rest_angle = constraints.rest_angle.data();
  project_constraint_lanes<4>(
      particles, constraints.particles,
      {constraints.stiffness.data(), constraints.compliance.data(), constraints.lambda.data()},
      begin, end, settings, [&](const Vec3<RealLanes> (&p)[4], std::size_t i) {
        return dihedral_constraint(p[0], p[1], p[2], p[3], hn::LoadU(d, rest_angle + i));
      });
}

void DihedralResiduals(const ParticleArrays& particles, const DihedralConstraints& batch,
                       std::size_t begin, std::size_t end, Real inverse_dt2, Real* out) {
  residual_lanes<4>(particles, batch.particles, begin, end, out,
                    [&](const Vec3<RealLanes> (&p)[4], std::size_t i) {
                      const RealLanes C = dihedral_constraint(p[0], p[1], p[2], p[3],
                                                              load(batch.rest_angle.data(), i))
                                              .C;
                      return lane_abs(xpbd_residual(C, batch.compliance.data(),
                                                    batch.lambda.data(), i, inverse_dt2));
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
#include "degenerate_shape.hpp"

namespace tessera {

HWY_EXPORT(ProjectDihedralConstraints);
HWY_EXPORT(DihedralResiduals);

DihedralConstraints make_dihedral_constraints(const DihedralConstraintInput& input) {
  namespace lanes = HWY_NAMESPACE;
  const detail::ConstraintValidator validator(DihedralConstraints::kFamily,
                                              input.rest_positions.size());
  validator.check_parameter("stiffness", input.stiffness);
  validator.check_parameter("compliance", input.compliance);
  DihedralConstraints result;
  result.particles = validator.particles<4>(input.particles);
  const std::size_t n = result.size();
  result.rest_angle = detail::filled(n, 0);
  const Real tolerance_squared = kDegenerateTolerance * kDegenerateTolerance;
  for (std::size_t c = 0; c < n; ++c) {
    const auto p = validator.rest_points<4>(result.particles, input.rest_positions, c);
    // The constraint's own degenerate cases, named.
    if (!((p[3] - p[2]).squaredNorm() > tolerance_squared))
      validator.fail(c, "degenerate rest stencil: shared edge p2-p3 has zero length");
    if (detail::flat_triangle((p[2] - p[0]).cross(p[3] - p[0]).norm(),
                              detail::longest_edge({p[0], p[2], p[3]})))
      validator.fail(c, "degenerate rest stencil: triangle (p0, p2, p3) has zero area");
    if (detail::flat_triangle((p[3] - p[1]).cross(p[2] - p[1]).norm(),
                              detail::longest_edge({p[1], p[3], p[2]})))
      validator.fail(c, "degenerate rest stencil: triangle (p1, p3, p2) has zero area");
    // φ0 is C at rest for φ0 = 0, evaluated by the formula every projection uses.
    const auto at_rest = lanes::dihedral_constraint<Real>(
        lanes::from_eigen(p[0]), lanes::from_eigen(p[1]), lanes::from_eigen(p[2]),
        lanes::from_eigen(p[3]), Real(0));
    if (!at_rest.valid || !std::isfinite(at_rest.C))
      validator.fail(c, "degenerate rest stencil: the rest angle is undefined");
    result.rest_angle[c] = at_rest.C;
  }
  result.stiffness = detail::filled(n, input.stiffness);
  result.compliance = detail::filled(n, input.compliance);
  result.lambda = detail::filled(n, 0);
  return result;
}

void project_dihedral_constraints(ParticleArrays particles, DihedralConstraints& constraints,
                                  std::size_t begin, std::size_t end,
                                  const ProjectionSettings& settings) {
  check_projection_range(DihedralConstraints::kFamily, begin, end, constraints.size(),
                         constraints.particles.particle_count, particles);
  HWY_DYNAMIC_DISPATCH(ProjectDihedralConstraints)(particles, constraints, begin, end, settings);
}

void constraint_residuals(const ParticleArrays& particles, const DihedralConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(DihedralResiduals)(particles, batch, begin, end, Real(0), out);
}

void xpbd_residuals(const ParticleArrays& particles, const DihedralConstraints& batch,
                    std::size_t begin, std::size_t end, Real dt, Real* out) {
  HWY_DYNAMIC_DISPATCH(DihedralResiduals)(particles, batch, begin, end, detail::inverse_squared(dt), out);
}

void project_sequentially(ParticleArrays particles, DihedralConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings) {
  detail::project_stiffness_or_compliance(
      particles, batch, begin, end, settings, PositionBasedDynamics::solve_DihedralConstraint,
      XPBD::solve_DihedralConstraint, [&](std::size_t c) { return batch.rest_angle[c]; });
}

}  // namespace tessera
#endif  // HWY_ONCE
