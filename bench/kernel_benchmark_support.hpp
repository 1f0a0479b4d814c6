// The common scene of the kernel benchmarks: kKernelBenchmarkConstraints constraints of one
// family, each on its own particles (as inside one colour), particle numbers randomly
// permuted so every gather misses the neighbouring constraint's cache lines; in the
// `batch_sorted` variant the constraints are sorted by their first particle, to show what
// gathers cost when locality is good. Positions start perturbed from rest so every
// projection does real work.
//
// Every family registers three benchmarks, named kernel/<family>/{scalar,batch,batch_sorted}:
// the scalar API in a loop over an AoS copy (the classic per-constraint PBD loop), and the
// batched kernel over SoA data. items_per_second = constraint projections per second.
#pragma once

#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <functional>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include <tessera/core/particle_state.hpp>

namespace tessera::bench {

inline constexpr std::size_t kKernelBenchmarkConstraints = 65536;

template <int N>
struct KernelScene {
  std::vector<Vector3r> rest;      // rest position of every particle
  std::vector<Vector3r> current;   // start position of every particle (perturbed rest)
  std::vector<Real> inverse_mass;  // all movable, in [0.5, 2]
  std::vector<ParticleIndex> indices;  // N per constraint
  std::size_t count = 0;
};

/// make_points(engine) returns the N rest points of one well-conditioned constraint.
template <int N, class MakePoints>
KernelScene<N> make_kernel_scene(bool sorted, MakePoints&& make_points,
                                 std::size_t count = kKernelBenchmarkConstraints) {
  std::mt19937 engine(2024);
  std::uniform_real_distribution<Real> unit(-1, 1), mass(Real(0.5), Real(2));
  KernelScene<N> scene;
  scene.count = count;
  const std::size_t particles = count * N;
  std::vector<ParticleIndex> permutation(particles);
  std::iota(permutation.begin(), permutation.end(), ParticleIndex(0));
  std::shuffle(permutation.begin(), permutation.end(), engine);
  scene.rest.resize(particles);
  scene.current.resize(particles);
  scene.inverse_mass.resize(particles);
  std::vector<std::array<ParticleIndex, N>> constraints(count);
  for (std::size_t c = 0; c < count; ++c) {
    const std::array<Vector3r, N> points = make_points(engine);
    for (int k = 0; k < N; ++k) {
      const ParticleIndex p = permutation[c * N + std::size_t(k)];
      constraints[c][std::size_t(k)] = p;
      scene.rest[p] = points[std::size_t(k)];
      scene.current[p] =
          points[std::size_t(k)] + Real(0.05) * Vector3r(unit(engine), unit(engine), unit(engine));
      scene.inverse_mass[p] = mass(engine);
    }
  }
  if (sorted)
    std::sort(constraints.begin(), constraints.end(),
              [](const auto& a, const auto& b) { return a[0] < b[0]; });
  for (const auto& constraint : constraints)
    scene.indices.insert(scene.indices.end(), constraint.begin(), constraint.end());
  return scene;
}

/// Registers kernel/<family>/<variant> with items_per_second = constraints per second.
/// `run(state)` performs one sweep over all constraints per benchmark iteration.
inline void register_kernel_benchmark(const std::string& family, const std::string& variant,
                                      std::function<void(benchmark::State&)> run) {
  benchmark::RegisterBenchmark(("kernel/" + family + "/" + variant).c_str(),
                               [run](benchmark::State& state) {
                                 run(state);
                                 state.SetItemsProcessed(
                                     std::int64_t(state.iterations()) *
                                     std::int64_t(kKernelBenchmarkConstraints));
                               })
      ->Unit(benchmark::kMicrosecond);
}

}  // namespace tessera::bench
