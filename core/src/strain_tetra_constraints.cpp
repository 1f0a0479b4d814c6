// Strain tetrahedron constraints in SoA batches: validation at the door (the rest inverse comes
// from the scalar API's init), then the batched kernel — one lane formula, kernels/strain-inl.h
// — compiled once per SIMD target (Highway foreach_target) and dispatched at run time.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "strain_tetra_constraints.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/core/strain_tetra_constraints.hpp>

#include "kernels/batch-inl.h"
#include "kernels/strain-inl.h"
#include "kernels/strain_residual-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

/// How many blocks of W tetrahedra ahead the kernel asks for particles. In double precision
/// a 40×40×160 bar's particles (8.6 MB) overflow L2, and the kernel's six sub-constraints are
/// too long for the out-of-order window to reach the next block's gathers: one block ahead
/// took it from 28.9 to 36.2 M/s (medians of 5, one thread, Zen 4; two blocks, measured
/// before project_strain carried F, the same as one). In float the same prefetch cost 10 %
/// (71.6 to 64.2): half the bytes per particle, twice the lanes to prefetch per block. The
/// batch loop's families and the FEM tetrahedron were no faster with it on any scene of
/// issue 17's table, and lost up to 23 % (the float distance-only cloth).
constexpr std::size_t kPrefetchBlocks = TESSERA_DOUBLE_PRECISION ? 1 : 0;

template <bool kNormalizeStretch, bool kNormalizeShear>
HWY_NOINLINE void project_strain_tetra_lanes(ParticleArrays particles,
                                                const StrainTetraConstraints& constraints,
                                                std::size_t begin, std::size_t end) {
  const RealTag d;
  const std::size_t lanes = hn::Lanes(d);
  const ParticleIndex* slot[4];
  constraint_slots(constraints.particles, slot);
  const Real* stiffness_array[6];
  for (int s = 0; s < 3; ++s) {
    stiffness_array[s] = constraints.stretch_stiffness[std::size_t(s)].data();
    stiffness_array[s + 3] = constraints.shear_stiffness[std::size_t(s)].data();
  }
  for (std::size_t i = begin; i < end; i += lanes) {
    const LaneMask active = hn::FirstN(d, end - i);
    ParticleLanes gathered[4];
    Vec3<RealLanes> p[4];
    RealLanes w[4];
    gather_constraint_particles<4, kPrefetchBlocks>(particles, slot, i, end, gathered, p, w);
    RealLanes m[3][3];
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j)
        m[k][j] = hn::LoadU(d, constraints.rest_inverse[std::size_t(3 * k + j)].data() + i);
    RealLanes stiffness[6];
    for (int s = 0; s < 6; ++s) stiffness[s] = hn::LoadU(d, stiffness_array[s] + i);
    Vec3<RealLanes> corr[4];
    project_strain<3>(p, w, m, kStrainTetraEntries, stiffness, kNormalizeStretch,
                      kNormalizeShear, corr);
    scatter_constraint_particles(particles, slot, i, gathered, corr, active);
  }
}

void ProjectStrainTetraConstraints(ParticleArrays particles,
                                      StrainTetraConstraints& constraints, std::size_t begin,
                                      std::size_t end) {
  if (constraints.normalize_stretch) {
    if (constraints.normalize_shear)
      project_strain_tetra_lanes<true, true>(particles, constraints, begin, end);
    else
      project_strain_tetra_lanes<true, false>(particles, constraints, begin, end);
  } else {
    if (constraints.normalize_shear)
      project_strain_tetra_lanes<false, true>(particles, constraints, begin, end);
    else
      project_strain_tetra_lanes<false, false>(particles, constraints, begin, end);
  }
}

void StrainTetraResiduals(const ParticleArrays& particles, const StrainTetraConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  green_strain_residuals<4>(particles, batch, begin, end, out);
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE

#include "sequential_loop.hpp"
#include <tessera/core/position_based_dynamics.hpp>

#include "constraint_validation.hpp"

namespace tessera {

HWY_EXPORT(ProjectStrainTetraConstraints);
HWY_EXPORT(StrainTetraResiduals);

StrainTetraConstraints make_strain_tetra_constraints(const StrainTetraConstraintInput& input) {
  const detail::ConstraintValidator validator(StrainTetraConstraints::kFamily,
                                              input.rest_positions.size());
  const char* stretch_names[3] = {"xx stretch stiffness", "yy stretch stiffness",
                                  "zz stretch stiffness"};
  const char* shear_names[3] = {"xy shear stiffness", "xz shear stiffness",
                                "yz shear stiffness"};
  for (int s = 0; s < 3; ++s) {
    validator.check_parameter(stretch_names[s], input.stretch_stiffness[s]);
    validator.check_parameter(shear_names[s], input.shear_stiffness[s]);
  }
  StrainTetraConstraints result;
  result.particles = validator.particles<4>(input.particles);
  const std::size_t n = result.size();
  for (auto& entry : result.rest_inverse) entry = detail::filled(n, 0);
  for (std::size_t c = 0; c < n; ++c) {
    const auto p = validator.rest_points<4>(result.particles, input.rest_positions, c);
    Matrix3r rest_inverse;
    if (!PositionBasedDynamics::init_StrainTetraConstraint(p[0], p[1], p[2], p[3],
                                                           rest_inverse))
      validator.fail(c, "rest tetrahedron is flat (zero volume)");
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j) result.rest_inverse[std::size_t(3 * k + j)][c] = rest_inverse(k, j);
  }
  for (int s = 0; s < 3; ++s) {
    result.stretch_stiffness[std::size_t(s)] = detail::filled(n, input.stretch_stiffness[s]);
    result.shear_stiffness[std::size_t(s)] = detail::filled(n, input.shear_stiffness[s]);
  }
  result.normalize_stretch = input.normalize_stretch;
  result.normalize_shear = input.normalize_shear;
  return result;
}

void project_strain_tetra_constraints(ParticleArrays particles,
                                         StrainTetraConstraints& constraints,
                                         std::size_t begin, std::size_t end,
                                         const ProjectionSettings& /*settings*/) {
  check_projection_range(StrainTetraConstraints::kFamily, begin, end, constraints.size(),
                         constraints.particles.particle_count, particles);
  HWY_DYNAMIC_DISPATCH(ProjectStrainTetraConstraints)(particles, constraints, begin, end);
}

void constraint_residuals(const ParticleArrays& particles, const StrainTetraConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(StrainTetraResiduals)(particles, batch, begin, end, out);
}

void project_sequentially(ParticleArrays particles, const StrainTetraConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& /*settings: PBD form only*/) {
  detail::project_batch_in_order(
      particles, batch, begin, end, [&](std::size_t c, const auto& s, auto& corr) {
    const auto stiffness = [&](const std::array<AlignedVector<Real>, 3>& k) {
      return Vector3r(k[0][c], k[1][c], k[2][c]);
    };
    detail::call_scalar_api(PositionBasedDynamics::solve_StrainTetraConstraint, s, corr,
                            detail::rest_inverse_of<3>(batch.rest_inverse, c),
                            stiffness(batch.stretch_stiffness), stiffness(batch.shear_stiffness),
                            batch.normalize_stretch, batch.normalize_shear);
  });
}

}  // namespace tessera
#endif  // HWY_ONCE
