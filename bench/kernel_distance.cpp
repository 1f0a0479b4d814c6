// kernel/distance/{scalar,batch,batch_sorted}
#include <tessera/core/distance_constraints.hpp>
#include <tessera/core/position_based_dynamics.hpp>

#include "kernel_benchmark_support.hpp"

namespace tessera::bench {
namespace {

KernelScene<2> distance_scene(bool sorted) {
  return make_kernel_scene<2>(sorted, [](std::mt19937& engine) {
    std::uniform_real_distribution<Real> unit(-1, 1);
    const Vector3r a(unit(engine), unit(engine), unit(engine));
    return std::array<Vector3r, 2>{a, a + Vector3r(Real(0.3), unit(engine), unit(engine))};
  });
}

void scalar(benchmark::State& state) {
  const KernelScene<2> scene = distance_scene(false);
  std::vector<Real> rest_length(scene.count);
  for (std::size_t c = 0; c < scene.count; ++c)
    rest_length[c] = (scene.rest[scene.indices[2 * c]] - scene.rest[scene.indices[2 * c + 1]]).norm();
  run_scalar_sweeps<2>(state, scene, [&](auto& x, const auto& w, const ParticleIndex* i,
                                         std::size_t c, Vector3r(&corr)[2]) {
    return PositionBasedDynamics::solve_DistanceConstraint(x[i[0]], w[i[0]], x[i[1]], w[i[1]],
                                                           rest_length[c], 1, corr[0], corr[1]);
  });
}

void batch(benchmark::State& state, bool sorted) {
  const KernelScene<2> scene = distance_scene(sorted);
  run_batch_sweeps(state, scene, make_distance_constraints({scene.indices, scene.rest}),
                   project_distance_constraints);
}

const bool registered = [] {
  register_kernel_benchmarks("distance", scalar, batch);
  return true;
}();

}  // namespace
}  // namespace tessera::bench
