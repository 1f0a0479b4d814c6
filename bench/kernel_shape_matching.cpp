// kernel/shape_matching/{scalar,batch,batch_sorted}: 65,536 rigid shape-matching clusters of
// 8–27 particles each (items = clusters), every cluster on its own particles, particle
// numbers randomly permuted; the cluster's current shape is its rest shape rotated by a
// random rotation and perturbed, so every projection does real work. The scalar variant runs
// the scalar API (Eigen SVD) over AoS copies; the batch variants the CSR kernel (W clusters
// per step, branch-free polar decomposition); batch_sorted orders clusters by first particle.
#include <algorithm>
#include <numeric>
#include <random>

#include <Eigen/Geometry>

#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/shape_matching_constraints.hpp>

#include "kernel_benchmark_support.hpp"

namespace tessera::bench {
namespace {

struct ClusterScene {
  std::vector<Vector3r> rest, current;
  std::vector<Real> inverse_mass;
  std::vector<std::uint32_t> offsets;
  std::vector<ParticleIndex> particles;
};

ClusterScene cluster_scene(bool sorted) {
  std::mt19937 engine(2024);
  std::uniform_real_distribution<Real> unit(-1, 1), mass(Real(0.5), Real(2));
  std::uniform_int_distribution<int> size_of(8, 27);
  std::vector<std::size_t> sizes(kKernelBenchmarkConstraints);
  std::size_t total = 0;
  for (auto& size : sizes) total += size = std::size_t(size_of(engine));
  std::vector<ParticleIndex> permutation(total);
  std::iota(permutation.begin(), permutation.end(), ParticleIndex(0));
  std::shuffle(permutation.begin(), permutation.end(), engine);
  ClusterScene scene;
  scene.rest.resize(total);
  scene.current.resize(total);
  scene.inverse_mass.resize(total);
  std::vector<std::vector<ParticleIndex>> clusters(sizes.size());
  std::size_t next = 0;
  for (std::size_t c = 0; c < sizes.size(); ++c) {
    const Vector3r centre(unit(engine), unit(engine), unit(engine));
    const Matrix3r rotation =
        Eigen::Quaternion<Real>(unit(engine), unit(engine), unit(engine), unit(engine))
            .normalized()
            .toRotationMatrix();
    for (std::size_t k = 0; k < sizes[c]; ++k) {
      const ParticleIndex p = permutation[next++];
      const Vector3r offset(Real(0.3) * unit(engine), Real(0.3) * unit(engine),
                            Real(0.3) * unit(engine));
      scene.rest[p] = centre + offset;
      scene.current[p] = centre + rotation * offset +
                         Real(0.03) * Vector3r(unit(engine), unit(engine), unit(engine));
      scene.inverse_mass[p] = mass(engine);
      clusters[c].push_back(p);
    }
  }
  if (sorted)
    std::sort(clusters.begin(), clusters.end(),
              [](const auto& a, const auto& b) { return a.front() < b.front(); });
  scene.offsets.push_back(0);
  for (const auto& cluster : clusters) {
    scene.particles.insert(scene.particles.end(), cluster.begin(), cluster.end());
    scene.offsets.push_back(std::uint32_t(scene.particles.size()));
  }
  return scene;
}

void scalar(benchmark::State& state) {
  const ClusterScene scene = cluster_scene(false);
  const std::size_t count = scene.offsets.size() - 1;
  std::vector<Vector3r> x = scene.current;
  // The rest data of each cluster as the scalar API wants it (AoS copies, rest centre).
  std::vector<Vector3r> rest_of_entry(scene.particles.size());
  std::vector<Real> w_of_entry(scene.particles.size());
  std::vector<Vector3r> rest_cm(count);
  for (std::size_t e = 0; e < scene.particles.size(); ++e) {
    rest_of_entry[e] = scene.rest[scene.particles[e]];
    w_of_entry[e] = scene.inverse_mass[scene.particles[e]];
  }
  for (std::size_t c = 0; c < count; ++c)
    PositionBasedDynamics::init_ShapeMatchingConstraint(
        &rest_of_entry[scene.offsets[c]], &w_of_entry[scene.offsets[c]],
        int(scene.offsets[c + 1] - scene.offsets[c]), rest_cm[c]);
  std::vector<Vector3r> current(27), corr(27);
  for (auto _ : state) {
    for (std::size_t c = 0; c < count; ++c) {
      const std::size_t first = scene.offsets[c];
      const int n = int(scene.offsets[c + 1] - first);
      for (int k = 0; k < n; ++k)
        current[std::size_t(k)] = x[scene.particles[first + std::size_t(k)]];
      if (PositionBasedDynamics::solve_ShapeMatchingConstraint(
              &rest_of_entry[first], current.data(), &w_of_entry[first], n, rest_cm[c], 1, false,
              corr.data()))
        for (int k = 0; k < n; ++k)
          x[scene.particles[first + std::size_t(k)]] += corr[std::size_t(k)];
    }
    benchmark::ClobberMemory();
  }
}

void batch(benchmark::State& state, bool sorted) {
  const ClusterScene scene = cluster_scene(sorted);
  ShapeMatchingConstraints constraints = make_shape_matching_constraints(
      {scene.offsets, scene.particles, scene.rest, scene.inverse_mass});
  ParticleState particles(scene.current, scene.inverse_mass);
  for (auto _ : state) {
    project_shape_matching_constraints(ParticleArrays::of(particles), constraints, 0,
                                       constraints.size());
    benchmark::ClobberMemory();
  }
}

const bool registered = [] {
  register_kernel_benchmarks("shape_matching", scalar, batch);
  return true;
}();

}  // namespace
}  // namespace tessera::bench
