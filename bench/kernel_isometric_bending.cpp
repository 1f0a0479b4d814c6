// kernel/isometric_bending/{scalar,batch,batch_sorted}: the isometric bending constraint
// through the scalar API in a per-constraint loop (one Matrix4r per constraint, as an AoS
// simulator keeps it), and through the batched kernel over SoA data.
#include <tessera/core/isometric_bending_constraints.hpp>
#include <tessera/core/position_based_dynamics.hpp>

#include "kernel_benchmark_support.hpp"

namespace tessera::bench {
namespace {

/// A planar stencil (edge p2-p3, wings on either side), randomly placed; the perturbation
/// of make_kernel_scene bends it.
KernelScene<4> bending_scene(bool sorted) {
  return make_kernel_scene<4>(sorted, [](std::mt19937& engine) {
    std::uniform_real_distribution<Real> unit(-1, 1);
    const Vector3r shift(unit(engine), unit(engine), unit(engine));
    return std::array<Vector3r, 4>{
        shift + Vector3r(Real(0.5) + Real(0.3) * unit(engine), Real(0.5), 0),
        shift + Vector3r(Real(0.5) + Real(0.3) * unit(engine), Real(-0.5), 0), shift,
        shift + Vector3r(1, 0, 0)};
  });
}

void scalar(benchmark::State& state) {
  const KernelScene<4> scene = bending_scene(false);
  const IsometricBendingConstraints constraints =
      make_isometric_bending_constraints({scene.indices, scene.rest});
  std::vector<Matrix4r> Q(scene.count);
  for (std::size_t c = 0; c < scene.count; ++c) Q[c] = constraints.matrix(c);
  run_scalar_sweeps<4>(state, scene, [&](auto& x, const auto& w, const ParticleIndex* i,
                                         std::size_t c, Vector3r(&corr)[4]) {
    return PositionBasedDynamics::solve_IsometricBendingConstraint(
        x[i[0]], w[i[0]], x[i[1]], w[i[1]], x[i[2]], w[i[2]], x[i[3]], w[i[3]], Q[c], 1,
        corr[0], corr[1], corr[2], corr[3]);
  });
}

void batch(benchmark::State& state, bool sorted) {
  const KernelScene<4> scene = bending_scene(sorted);
  run_batch_sweeps(state, scene,
                   make_isometric_bending_constraints({scene.indices, scene.rest}),
                   project_isometric_bending_constraints);
}

const bool registered = [] {
  register_kernel_benchmarks("isometric_bending", scalar, batch);
  return true;
}();

}  // namespace
}  // namespace tessera::bench
