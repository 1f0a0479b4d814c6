// kernel/fem_triangle/{scalar,batch,batch_sorted} and kernel/fem_tetra/{scalar,batch,
// batch_sorted,scalar_xpbd,batch_xpbd,scalar_inverted,batch_inverted}: the FEM constraints' scalar API in a
// per-constraint loop against the batched kernels. The tetrahedra run with inversion handling
// on (the uninverted scene never needs the SVD, so its lanes skip it); batch_inverted starts
// with every element inverted, so every chunk pays for the lane SVD (and scalar_inverted
// for the same SVD on one lane).
#include <tessera/core/fem_tetra_constraints.hpp>
#include <tessera/core/fem_triangle_constraints.hpp>
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "kernel_benchmark_support.hpp"

namespace tessera::bench {
namespace {

constexpr Real kYoung = 1000, kPoisson = Real(0.3);

KernelScene<3> triangle_scene(bool sorted) {
  return make_kernel_scene<3>(sorted, [](std::mt19937& engine) {
    std::uniform_real_distribution<Real> unit(-1, 1);
    const Vector3r a(unit(engine), unit(engine), unit(engine));
    return std::array<Vector3r, 3>{a, a + Vector3r(Real(0.3), Real(0.05) * unit(engine), 0),
                                   a + Vector3r(Real(0.05) * unit(engine), Real(0.3),
                                                Real(0.1) * unit(engine))};
  });
}

KernelScene<4> tetra_scene(bool sorted, bool inverted = false) {
  KernelScene<4> scene = make_kernel_scene<4>(sorted, [](std::mt19937& engine) {
    std::uniform_real_distribution<Real> unit(-1, 1);
    const Vector3r a(unit(engine), unit(engine), unit(engine));
    return std::array<Vector3r, 4>{a, a + Vector3r(Real(0.3), 0, Real(0.05) * unit(engine)),
                                   a + Vector3r(0, Real(0.3), Real(0.05) * unit(engine)),
                                   a + Vector3r(Real(0.05) * unit(engine), 0, Real(0.3))};
  });
  if (inverted)  // the fourth vertex pushed through the opposite face (≈ z = 0 plane)
    for (std::size_t c = 0; c < scene.count; ++c) {
      const ParticleIndex base = scene.indices[4 * c], top = scene.indices[4 * c + 3];
      scene.current[top].z() = scene.current[base].z() - Real(0.15);
    }
  return scene;
}

void triangle_scalar(benchmark::State& state) {
  const KernelScene<3> scene = triangle_scene(false);
  std::vector<Matrix2r> rest_inverse(scene.count);
  std::vector<Real> area(scene.count);
  for (std::size_t c = 0; c < scene.count; ++c)
    PositionBasedDynamics::init_FEMTriangleConstraint(
        scene.rest[scene.indices[3 * c]], scene.rest[scene.indices[3 * c + 1]],
        scene.rest[scene.indices[3 * c + 2]], area[c], rest_inverse[c]);
  run_scalar_sweeps<3>(state, scene, [&](auto& x, const auto& w, const ParticleIndex* p,
                                         std::size_t c, Vector3r(&corr)[3]) {
    return PositionBasedDynamics::solve_FEMTriangleConstraint(
        x[p[0]], w[p[0]], x[p[1]], w[p[1]], x[p[2]], w[p[2]], area[c], rest_inverse[c], kYoung,
        kYoung, kYoung / (2 * (1 + kPoisson)), kPoisson, kPoisson, corr[0], corr[1], corr[2]);
  });
}

void triangle_batch(benchmark::State& state, bool sorted) {
  const KernelScene<3> scene = triangle_scene(sorted);
  FEMTriangleConstraintInput input;
  input.particles = scene.indices;
  input.rest_positions = scene.rest;
  input.youngs_modulus_x = input.youngs_modulus_y = kYoung;
  input.youngs_modulus_shear = kYoung / (2 * (1 + kPoisson));
  input.poisson_ratio_xy = input.poisson_ratio_yx = kPoisson;
  run_batch_sweeps(state, scene, make_fem_triangle_constraints(input),
                   project_fem_triangle_constraints);
}

void tetra_scalar(benchmark::State& state, bool xpbd, bool inverted = false) {
  const KernelScene<4> scene = tetra_scene(false, inverted);
  std::vector<Matrix3r> rest_inverse(scene.count);
  std::vector<Real> volume(scene.count), lambda(scene.count, 0);
  for (std::size_t c = 0; c < scene.count; ++c)
    PositionBasedDynamics::init_FEMTetraConstraint(
        scene.rest[scene.indices[4 * c]], scene.rest[scene.indices[4 * c + 1]],
        scene.rest[scene.indices[4 * c + 2]], scene.rest[scene.indices[4 * c + 3]], volume[c],
        rest_inverse[c]);
  std::vector<Vector3r> x = scene.current;
  const std::vector<Real>& w = scene.inverse_mass;
  for (auto _ : state) {
    if (inverted) {  // every sweep starts from the inverted state again
      state.PauseTiming();
      x = scene.current;
      state.ResumeTiming();
    }
    for (std::size_t c = 0; c < scene.count; ++c) {
      const ParticleIndex* p = &scene.indices[4 * c];
      Vector3r corr[4];
      const bool ok =
          xpbd ? XPBD::solve_FEMTetraConstraint(x[p[0]], w[p[0]], x[p[1]], w[p[1]], x[p[2]],
                                                w[p[2]], x[p[3]], w[p[3]], volume[c],
                                                rest_inverse[c], kPoisson, 1 / kYoung, true,
                                                Real(1) / 60, lambda[c], corr[0], corr[1],
                                                corr[2], corr[3])
               : PositionBasedDynamics::solve_FEMTetraConstraint(
                     x[p[0]], w[p[0]], x[p[1]], w[p[1]], x[p[2]], w[p[2]], x[p[3]], w[p[3]],
                     volume[c], rest_inverse[c], kYoung, kPoisson, true, corr[0], corr[1],
                     corr[2], corr[3]);
      if (ok)
        for (int k = 0; k < 4; ++k) x[p[k]] += corr[k];
    }
    benchmark::ClobberMemory();
  }
}

void tetra_batch(benchmark::State& state, bool sorted, bool xpbd, bool inverted) {
  const KernelScene<4> scene = tetra_scene(sorted, inverted);
  FEMTetraConstraintInput input;
  input.particles = scene.indices;
  input.rest_positions = scene.rest;
  input.youngs_modulus = kYoung;
  input.poisson_ratio = kPoisson;
  FEMTetraConstraints constraints = make_fem_tetra_constraints(input);
  const ProjectionSettings settings{
      xpbd ? ConstraintSemantics::compliance : ConstraintSemantics::stiffness, Real(1) / 60};
  ParticleState particles(scene.current, scene.inverse_mass);
  for (auto _ : state) {
    if (inverted) {  // every sweep starts from the inverted state again
      state.PauseTiming();
      particles = ParticleState(scene.current, scene.inverse_mass);
      state.ResumeTiming();
    }
    project_fem_tetra_constraints(ParticleArrays::of(particles), constraints, 0, scene.count,
                                  settings);
    benchmark::ClobberMemory();
  }
}

const bool registered = [] {
  register_kernel_benchmarks("fem_triangle", triangle_scalar, triangle_batch);
  register_kernel_benchmark("fem_tetra", "scalar",
                            [](benchmark::State& s) { tetra_scalar(s, false); });
  register_kernel_benchmark("fem_tetra", "batch",
                            [](benchmark::State& s) { tetra_batch(s, false, false, false); });
  register_kernel_benchmark("fem_tetra", "batch_sorted",
                            [](benchmark::State& s) { tetra_batch(s, true, false, false); });
  register_kernel_benchmark("fem_tetra", "scalar_xpbd",
                            [](benchmark::State& s) { tetra_scalar(s, true); });
  register_kernel_benchmark("fem_tetra", "batch_xpbd",
                            [](benchmark::State& s) { tetra_batch(s, false, true, false); });
  register_kernel_benchmark("fem_tetra", "scalar_inverted",
                            [](benchmark::State& s) { tetra_scalar(s, false, true); });
  register_kernel_benchmark("fem_tetra", "batch_inverted",
                            [](benchmark::State& s) { tetra_batch(s, false, false, true); });
  return true;
}();

}  // namespace
}  // namespace tessera::bench
