// kernel/strain_triangle/{scalar,batch,batch_sorted} and kernel/strain_tetra/{...}: strain
// based dynamics (every sub-constraint active, unnormalised stretch, normalised shear), the
// scalar API in a per-constraint loop against the batched kernel.
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/strain_tetra_constraints.hpp>
#include <tessera/core/strain_triangle_constraints.hpp>

#include "kernel_benchmark_support.hpp"

namespace tessera::bench {
namespace {

constexpr bool kNormalizeStretch = false;
constexpr bool kNormalizeShear = true;

KernelScene<3> triangle_scene(bool sorted) {
  return make_kernel_scene<3>(sorted, [](std::mt19937& engine) {
    std::uniform_real_distribution<Real> unit(-1, 1);
    const Vector3r a(unit(engine), unit(engine), unit(engine));
    return std::array<Vector3r, 3>{a, a + Vector3r(Real(0.3), Real(0.05) * unit(engine), 0),
                                   a + Vector3r(Real(0.05) * unit(engine), Real(0.3), 0)};
  });
}

KernelScene<4> tetra_scene(bool sorted) {
  return make_kernel_scene<4>(sorted, [](std::mt19937& engine) {
    std::uniform_real_distribution<Real> unit(-1, 1);
    const Vector3r a(unit(engine), unit(engine), unit(engine));
    return std::array<Vector3r, 4>{a, a + Vector3r(Real(0.3), 0, Real(0.05) * unit(engine)),
                                   a + Vector3r(0, Real(0.3), Real(0.05) * unit(engine)),
                                   a + Vector3r(Real(0.05) * unit(engine), 0, Real(0.3))};
  });
}

void triangle_scalar(benchmark::State& state) {
  const KernelScene<3> scene = triangle_scene(false);
  std::vector<Matrix2r> rest_inverse(scene.count);
  for (std::size_t c = 0; c < scene.count; ++c)
    PositionBasedDynamics::init_StrainTriangleConstraint(
        scene.rest[scene.indices[3 * c]], scene.rest[scene.indices[3 * c + 1]],
        scene.rest[scene.indices[3 * c + 2]], rest_inverse[c]);
  run_scalar_sweeps<3>(state, scene, [&](auto& x, const auto& w, const ParticleIndex* p,
                                         std::size_t c, Vector3r(&corr)[3]) {
    return PositionBasedDynamics::solve_StrainTriangleConstraint(
        x[p[0]], w[p[0]], x[p[1]], w[p[1]], x[p[2]], w[p[2]], rest_inverse[c], 1, 1, 1,
        kNormalizeStretch, kNormalizeShear, corr[0], corr[1], corr[2]);
  });
}

void triangle_batch(benchmark::State& state, bool sorted) {
  const KernelScene<3> scene = triangle_scene(sorted);
  StrainTriangleConstraintInput input;
  input.particles = scene.indices;
  input.rest_positions = scene.rest;
  input.normalize_stretch = kNormalizeStretch;
  input.normalize_shear = kNormalizeShear;
  run_batch_sweeps(state, scene, make_strain_triangle_constraints(input),
                   project_strain_triangle_constraints);
}

void tetra_scalar(benchmark::State& state) {
  const KernelScene<4> scene = tetra_scene(false);
  std::vector<Matrix3r> rest_inverse(scene.count);
  for (std::size_t c = 0; c < scene.count; ++c)
    PositionBasedDynamics::init_StrainTetraConstraint(
        scene.rest[scene.indices[4 * c]], scene.rest[scene.indices[4 * c + 1]],
        scene.rest[scene.indices[4 * c + 2]], scene.rest[scene.indices[4 * c + 3]],
        rest_inverse[c]);
  const Vector3r ones = Vector3r::Ones();
  run_scalar_sweeps<4>(state, scene, [&](auto& x, const auto& w, const ParticleIndex* p,
                                         std::size_t c, Vector3r(&corr)[4]) {
    return PositionBasedDynamics::solve_StrainTetraConstraint(
        x[p[0]], w[p[0]], x[p[1]], w[p[1]], x[p[2]], w[p[2]], x[p[3]], w[p[3]], rest_inverse[c],
        ones, ones, kNormalizeStretch, kNormalizeShear, corr[0], corr[1], corr[2], corr[3]);
  });
}

void tetra_batch(benchmark::State& state, bool sorted) {
  const KernelScene<4> scene = tetra_scene(sorted);
  StrainTetraConstraintInput input;
  input.particles = scene.indices;
  input.rest_positions = scene.rest;
  input.normalize_stretch = kNormalizeStretch;
  input.normalize_shear = kNormalizeShear;
  run_batch_sweeps(state, scene, make_strain_tetra_constraints(input),
                   project_strain_tetra_constraints);
}

const bool registered = [] {
  register_kernel_benchmarks("strain_triangle", triangle_scalar, triangle_batch);
  register_kernel_benchmarks("strain_tetra", tetra_scalar, tetra_batch);
  return true;
}();

}  // namespace
}  // namespace tessera::bench
