// kernel/volume/{scalar,batch,batch_sorted}: the tetrahedron volume constraint through the
// scalar API in a per-constraint loop, and through the batched kernel over SoA data.
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/volume_constraints.hpp>

#include "kernel_benchmark_support.hpp"

namespace tessera::bench {
namespace {

/// A positively oriented tetrahedron of edge about 0.5, randomly placed and shaped.
KernelScene<4> volume_scene(bool sorted) {
  return make_kernel_scene<4>(sorted, [](std::mt19937& engine) {
    std::uniform_real_distribution<Real> unit(-1, 1);
    const Vector3r shift(unit(engine), unit(engine), unit(engine));
    const auto jitter = [&] {
      Vector3r j;
      for (int k = 0; k < 3; ++k) j[k] = Real(0.1) * unit(engine);
      return j;
    };
    return std::array<Vector3r, 4>{shift + jitter(),
                                   shift + Vector3r(Real(0.5), 0, 0) + jitter(),
                                   shift + Vector3r(0, Real(0.5), 0) + jitter(),
                                   shift + Vector3r(0, 0, Real(0.5)) + jitter()};
  });
}

void scalar(benchmark::State& state) {
  const KernelScene<4> scene = volume_scene(false);
  const VolumeConstraints constraints = make_volume_constraints({scene.indices, scene.rest});
  std::vector<Real> rest_volume(constraints.rest_volume.begin(),
                                constraints.rest_volume.begin() + long(scene.count));
  run_scalar_sweeps<4>(state, scene, [&](auto& x, const auto& w, const ParticleIndex* i,
                                         std::size_t c, Vector3r(&corr)[4]) {
    return PositionBasedDynamics::solve_VolumeConstraint(
        x[i[0]], w[i[0]], x[i[1]], w[i[1]], x[i[2]], w[i[2]], x[i[3]], w[i[3]], rest_volume[c],
        1, corr[0], corr[1], corr[2], corr[3]);
  });
}

void batch(benchmark::State& state, bool sorted) {
  const KernelScene<4> scene = volume_scene(sorted);
  run_batch_sweeps(state, scene, make_volume_constraints({scene.indices, scene.rest}),
                   project_volume_constraints);
}

const bool registered = [] {
  register_kernel_benchmarks("volume", scalar, batch);
  return true;
}();

}  // namespace
}  // namespace tessera::bench
