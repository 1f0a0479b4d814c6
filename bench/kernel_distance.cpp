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
  std::vector<Vector3r> x = scene.current;
  const std::vector<Real>& w = scene.inverse_mass;
  for (auto _ : state) {
    for (std::size_t c = 0; c < scene.count; ++c) {
      const ParticleIndex i = scene.indices[2 * c], j = scene.indices[2 * c + 1];
      Vector3r corr0, corr1;
      if (PositionBasedDynamics::solve_DistanceConstraint(x[i], w[i], x[j], w[j], rest_length[c],
                                                          1, corr0, corr1)) {
        x[i] += corr0;
        x[j] += corr1;
      }
    }
    benchmark::ClobberMemory();
  }
}

void batch(benchmark::State& state, bool sorted) {
  const KernelScene<2> scene = distance_scene(sorted);
  DistanceConstraints constraints = make_distance_constraints({scene.indices, scene.rest});
  ParticleState particles(scene.current, scene.inverse_mass);
  for (auto _ : state) {
    project_distance_constraints(ParticleArrays::of(particles), constraints, 0, scene.count, {});
    benchmark::ClobberMemory();
  }
}

const bool registered = [] {
  register_kernel_benchmark("distance", "scalar", scalar);
  register_kernel_benchmark("distance", "batch", [](benchmark::State& s) { batch(s, false); });
  register_kernel_benchmark("distance", "batch_sorted", [](benchmark::State& s) { batch(s, true); });
  return true;
}();

}  // namespace
}  // namespace tessera::bench
