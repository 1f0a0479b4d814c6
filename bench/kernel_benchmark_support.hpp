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
#include <utility>
#include <vector>

#include <tessera/core/constraint_batch.hpp>
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

/// Registers the three benchmarks of a family: kernel/<family>/scalar runs `scalar`,
/// kernel/<family>/batch and .../batch_sorted run `batch(state, sorted)`.
inline void register_kernel_benchmarks(const std::string& family,
                                       std::function<void(benchmark::State&)> scalar,
                                       std::function<void(benchmark::State&, bool)> batch) {
  register_kernel_benchmark(family, "scalar", std::move(scalar));
  register_kernel_benchmark(family, "batch", [batch](benchmark::State& s) { batch(s, false); });
  register_kernel_benchmark(family, "batch_sorted",
                            [batch](benchmark::State& s) { batch(s, true); });
}

/// The classic per-constraint PBD loop over an AoS copy of the scene, one sweep per
/// iteration: solve(x, w, i, c, corr) projects constraint c (particles i[0..N)) through the
/// scalar API, and its corrections are applied when it returns true.
template <int N, class Solve>
void run_scalar_sweeps(benchmark::State& state, const KernelScene<N>& scene, Solve&& solve) {
  std::vector<Vector3r> x = scene.current;
  const std::vector<Real>& w = scene.inverse_mass;
  for (auto _ : state) {
    for (std::size_t c = 0; c < scene.count; ++c) {
      const ParticleIndex* i = &scene.indices[N * c];
      Vector3r corr[N];
      if (solve(x, w, i, c, corr))
        for (int k = 0; k < N; ++k) x[i[k]] += corr[k];
    }
    benchmark::ClobberMemory();
  }
}

/// The batched kernel over the whole scene, one sweep per iteration, with default settings:
/// project(particles, constraints, begin, end, settings) is project_<family>_constraints.
template <int N, class Constraints, class Project>
void run_batch_sweeps(benchmark::State& state, const KernelScene<N>& scene,
                      Constraints constraints, Project&& project) {
  ParticleState particles(scene.current, scene.inverse_mass);
  for (auto _ : state) {
    project(ParticleArrays::of(particles), constraints, 0, scene.count, ProjectionSettings{});
    benchmark::ClobberMemory();
  }
}

}  // namespace tessera::bench
