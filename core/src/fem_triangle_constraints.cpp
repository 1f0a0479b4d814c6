// FEM triangle constraints in SoA batches: validation at the door (rest frame and area from
// the scalar API's init, the material checked positive definite once), then the batched
// kernel — one lane formula, kernels/fem-inl.h — compiled once per SIMD target (Highway
// foreach_target) and dispatched at run time.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "fem_triangle_constraints.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/core/fem_triangle_constraints.hpp>

#include "kernels/batch-inl.h"
#include "kernels/fem-inl.h"
#include "kernels/strain_residual-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

void ProjectFEMTriangleConstraints(ParticleArrays particles,
                                   FEMTriangleConstraints& constraints, std::size_t begin,
                                   std::size_t end) {
  const RealTag d;
  const std::size_t lanes = hn::Lanes(d);
  const ParticleIndex* slot[3];
  constraint_slots(constraints.particles, slot);
  for (std::size_t i = begin; i < end; i += lanes) {
    const LaneMask active = hn::FirstN(d, end - i);
    ParticleLanes gathered[3];
    Vec3<RealLanes> p[3];
    RealLanes w[3];
    gather_constraint_particles(particles, slot, i, end, gathered, p, w);
    RealLanes m[2][2];
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j)
        m[k][j] = hn::LoadU(d, constraints.rest_inverse[std::size_t(2 * k + j)].data() + i);
    Vec3<RealLanes> corr[3];
    fem_triangle_pbd(p, w, hn::LoadU(d, constraints.area.data() + i), m,
                     hn::LoadU(d, constraints.youngs_modulus_x.data() + i),
                     hn::LoadU(d, constraints.youngs_modulus_y.data() + i),
                     hn::LoadU(d, constraints.youngs_modulus_shear.data() + i),
                     hn::LoadU(d, constraints.poisson_ratio_xy.data() + i),
                     hn::LoadU(d, constraints.poisson_ratio_yx.data() + i), corr);
    scatter_constraint_particles(particles, slot, i, gathered, corr, active);
  }
}

void FEMTriangleResiduals(const ParticleArrays& particles, const FEMTriangleConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  green_strain_residuals<3>(particles, batch, begin, end, out);
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE

#include "sequential_loop.hpp"
#include <cmath>
#include <string>

#include <tessera/core/position_based_dynamics.hpp>

#include "constraint_validation.hpp"

namespace tessera {

HWY_EXPORT(ProjectFEMTriangleConstraints);
HWY_EXPORT(FEMTriangleResiduals);

FEMTriangleConstraints make_fem_triangle_constraints(const FEMTriangleConstraintInput& input) {
  const detail::ConstraintValidator validator(FEMTriangleConstraints::kFamily,
                                              input.rest_positions.size());
  const Real ex = input.youngs_modulus_x, ey = input.youngs_modulus_y,
             g = input.youngs_modulus_shear, nxy = input.poisson_ratio_xy,
             nyx = input.poisson_ratio_yx;
  const Real material[5] = {ex, ey, g, nxy, nyx};
  const char* names[5] = {"Young's modulus x", "Young's modulus y", "shear modulus",
                          "Poisson ratio xy", "Poisson ratio yx"};
  for (int k = 0; k < 5; ++k)
    if (!std::isfinite(material[k])) validator.fail_input(std::string(names[k]) + " is not finite");
  // The same positive-definiteness test as the kernel (solve_FEMTriangleConstraint).
  const Real one_minus_product = 1 - nxy * nyx;
  const Real c_xy = Real(0.5) * (nyx * ex + nxy * ey) / one_minus_product;
  if (!(ex > 0) || !(ey > 0) || !(g > 0) || !(one_minus_product > 0) ||
      !((ex / one_minus_product) * (ey / one_minus_product) - c_xy * c_xy > 0))
    validator.fail_input("material is not positive definite (E_x, E_y, G > 0, ν_xy ν_yx < 1 "
                         "and a positive normal-stress determinant are required)");

  FEMTriangleConstraints result;
  result.particles = validator.particles<3>(input.particles);
  const std::size_t n = result.size();
  result.area = detail::filled(n, 0);
  for (auto& entry : result.rest_inverse) entry = detail::filled(n, 0);
  for (std::size_t c = 0; c < n; ++c) {
    const auto p = validator.rest_points<3>(result.particles, input.rest_positions, c);
    Real area;
    Matrix2r rest_inverse;
    if (!PositionBasedDynamics::init_FEMTriangleConstraint(p[0], p[1], p[2], area, rest_inverse))
      validator.fail(c, "rest triangle has zero area");
    result.area[c] = area;
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j) result.rest_inverse[std::size_t(2 * k + j)][c] = rest_inverse(k, j);
  }
  result.youngs_modulus_x = detail::filled(n, ex);
  result.youngs_modulus_y = detail::filled(n, ey);
  result.youngs_modulus_shear = detail::filled(n, g);
  result.poisson_ratio_xy = detail::filled(n, nxy);
  result.poisson_ratio_yx = detail::filled(n, nyx);
  return result;
}

void project_fem_triangle_constraints(ParticleArrays particles,
                                      FEMTriangleConstraints& constraints, std::size_t begin,
                                      std::size_t end, const ProjectionSettings& /*settings*/) {
  check_projection_range(FEMTriangleConstraints::kFamily, begin, end, constraints.size(),
                         constraints.particles.particle_count, particles);
  HWY_DYNAMIC_DISPATCH(ProjectFEMTriangleConstraints)(particles, constraints, begin, end);
}

void constraint_residuals(const ParticleArrays& particles, const FEMTriangleConstraints& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(FEMTriangleResiduals)(particles, batch, begin, end, out);
}

void project_sequentially(ParticleArrays particles, const FEMTriangleConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& /*settings: PBD form only*/) {
  detail::project_batch_in_order(
      particles, batch, begin, end, [&](std::size_t c, const auto& s, auto& corr) {
    detail::call_scalar_api(PositionBasedDynamics::solve_FEMTriangleConstraint, s, corr, batch.area[c],
                            detail::rest_inverse_of<2>(batch.rest_inverse, c),
                            batch.youngs_modulus_x[c], batch.youngs_modulus_y[c],
                            batch.youngs_modulus_shear[c], batch.poisson_ratio_xy[c],
                            batch.poisson_ratio_yx[c]);
  });
}

}  // namespace tessera
#endif  // HWY_ONCE
