// Volume constraints in SoA batches: validation at the door (signed rest volumes, flat rest
// tetrahedra rejected), then the batched kernel, compiled once per SIMD target (Highway
// foreach_target) and dispatched at run time.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "volume_constraints.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/core/volume_constraints.hpp>

#include "kernels/batch_loop-inl.h"
#include "kernels/volume-inl.h"
#include "kernels/residual_lanes-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

void ProjectVolumeConstraints(ParticleArrays particles, VolumeConstraints& constraints,
                              std::size_t begin, std::size_t end, ProjectionSettings settings) {
  const RealTag d;
  const Real* rest_volume = constraints.rest_volume.data();
  project_constraint_lanes<4>(
      particles, constraints.particles,
      {constraints.stiffness.data(), constraints.compliance.data(), constraints.lambda.data()},
      begin, end, settings, [&](const Vec3<RealLanes> (&p)[4], std::size_t i) {
        return volume_constraint(p[0], p[1], p[2], p[3], hn::LoadU(d, rest_volume + i));
      });
}

void VolumeResiduals(const ParticleArrays& particles, const VolumeConstraints& batch,
                     std::size_t begin, std::size_t end, Real inverse_dt2, Real* out) {
  residual_lanes<4>(particles, batch.particles, begin, end, out,
                    [&](const Vec3<RealLanes> (&p)[4], std::size_t i) {
                      const RealLanes rest_volume = load(batch.rest_volume.data(), i);
                      const RealLanes C = volume_constraint(p[0], p[1], p[2], p[3], rest_volume).C;
                      return relative(xpbd_residual(C, batch.compliance.data(),
                                                    batch.lambda.data(), i, inverse_dt2),
                                      rest_volume);
                    });
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "sequential_loop.hpp"
#include <algorithm>
#include <cmath>
#include <sstream>

#include "constraint_validation.hpp"

namespace tessera {

HWY_EXPORT(ProjectVolumeConstraints);
HWY_EXPORT(VolumeResiduals);

VolumeConstraints make_volume_constraints(const VolumeConstraintInput& input) {
  namespace lanes = HWY_NAMESPACE;
  const detail::ConstraintValidator validator(VolumeConstraints::kFamily,
                                              input.rest_positions.size());
  validator.check_parameter("stiffness", input.stiffness);
  validator.check_parameter("compliance", input.compliance);
  VolumeConstraints result;
  result.particles = validator.particles<4>(input.particles);
  const std::size_t n = result.size();
  result.rest_volume = detail::filled(n, 0);
  for (std::size_t c = 0; c < n; ++c) {
    const auto p = validator.rest_points<4>(result.particles, input.rest_positions, c);
    // V0 is C at rest for V0 = 0, evaluated by the formula every projection uses.
    const Real volume = lanes::volume_constraint<Real>(
                            lanes::from_eigen(p[0]), lanes::from_eigen(p[1]),
                            lanes::from_eigen(p[2]), lanes::from_eigen(p[3]), Real(0))
                            .C;
    // Flat is judged relative to the tetrahedron's size, so it means the same at any scale.
    Real longest_edge = 0;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) longest_edge = std::max(longest_edge, (p[a] - p[b]).norm());
    if (!std::isfinite(volume) ||
        !(6 * std::abs(volume) >
          kDegenerateTolerance * longest_edge * longest_edge * longest_edge)) {
      std::ostringstream problem;
      problem << "rest volume is " << volume << " (flat tetrahedron)";
      validator.fail(c, problem.str());
    }
    result.rest_volume[c] = volume;
  }
  result.stiffness = detail::filled(n, input.stiffness);
  result.compliance = detail::filled(n, input.compliance);
  result.lambda = detail::filled(n, 0);
  return result;
}

void project_volume_constraints(ParticleArrays particles, VolumeConstraints& constraints,
                                std::size_t begin, std::size_t end,
                                const ProjectionSettings& settings) {
  check_projection_range(VolumeConstraints::kFamily, begin, end, constraints.size(),
                         constraints.particles.particle_count, particles);
  HWY_DYNAMIC_DISPATCH(ProjectVolumeConstraints)(particles, constraints, begin, end, settings);
}

void constraint_residuals(const ParticleArrays& particles, const VolumeConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(VolumeResiduals)(particles, batch, begin, end, Real(0), out);
}

void xpbd_residuals(const ParticleArrays& particles, const VolumeConstraints& batch,
                    std::size_t begin, std::size_t end, Real dt, Real* out) {
  HWY_DYNAMIC_DISPATCH(VolumeResiduals)(particles, batch, begin, end, detail::inverse_squared(dt), out);
}

void project_sequentially(ParticleArrays particles, VolumeConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings) {
  detail::project_stiffness_or_compliance(
      particles, batch, begin, end, settings, PositionBasedDynamics::solve_VolumeConstraint,
      XPBD::solve_VolumeConstraint, [&](std::size_t c) { return batch.rest_volume[c]; });
}

}  // namespace tessera
#endif  // HWY_ONCE
