// kernel/{edge_point_distance,triangle_point_distance,edge_edge_distance}/
// {scalar,batch,batch_sorted}: the three proximity families on the common kernel scene.
// Why these shapes: each constraint is a thickness constraint (rest distance 0.1) between
// primitives about 0.05–0.5 apart whose closest points fall in every Voronoi region (vertex,
// edge, face; interior and endpoint pairs), as in cloth self-collision, so the batch pays for
// evaluating all regions and the scalar loop for mispredicting among them.
#include <string>
#include <utility>

#include <tessera/core/proximity_distance_constraints.hpp>
#include <tessera/core/position_based_dynamics.hpp>

#include "kernel_benchmark_support.hpp"

namespace tessera::bench {
namespace {

constexpr Real kRestDistance = Real(0.1);

Vector3r random_vector(std::mt19937& engine) {
  std::uniform_real_distribution<Real> unit(-1, 1);
  return Vector3r(unit(engine), unit(engine), unit(engine));
}

std::array<Vector3r, 3> edge_point_points(std::mt19937& engine) {
  std::uniform_real_distribution<Real> along(Real(-0.3), Real(1.3));
  const Vector3r a = random_vector(engine);
  const Vector3r b = a + Vector3r(Real(0.4), 0, 0) + Real(0.2) * random_vector(engine);
  const Vector3r p = a + along(engine) * (b - a) + Real(0.25) * random_vector(engine);
  return {p, a, b};
}

std::array<Vector3r, 4> triangle_point_points(std::mt19937& engine) {
  const Vector3r a = random_vector(engine);
  const Vector3r b = a + Vector3r(Real(0.4), 0, 0) + Real(0.1) * random_vector(engine);
  const Vector3r c = a + Vector3r(0, Real(0.4), 0) + Real(0.1) * random_vector(engine);
  const Vector3r p = (a + b + c) / 3 + Real(0.35) * random_vector(engine);
  return {p, a, b, c};
}

std::array<Vector3r, 4> edge_edge_points(std::mt19937& engine) {
  const Vector3r p0 = random_vector(engine);
  const Vector3r p1 = p0 + Vector3r(Real(0.4), 0, 0) + Real(0.2) * random_vector(engine);
  const Vector3r p2 = (p0 + p1) / 2 + Real(0.3) * random_vector(engine);
  const Vector3r p3 = p2 + Vector3r(0, Real(0.4), 0) + Real(0.2) * random_vector(engine);
  return {p0, p1, p2, p3};
}

/// The classic per-constraint loop over an AoS copy; solve(x, w, indices of c, corr) calls
/// the scalar API of the family.
template <int N, class Solve>
void scalar(benchmark::State& state, const KernelScene<N>& scene, Solve solve) {
  std::vector<Vector3r> x = scene.current;
  const std::vector<Real>& w = scene.inverse_mass;
  for (auto _ : state) {
    for (std::size_t c = 0; c < scene.count; ++c) {
      const ParticleIndex* index = scene.indices.data() + N * c;
      std::array<Vector3r, N> corr;
      if (solve(x, w, index, corr))
        for (int k = 0; k < N; ++k) x[index[k]] += corr[std::size_t(k)];
    }
    benchmark::ClobberMemory();
  }
}

template <int N, class Constraints, class Project>
void batch(benchmark::State& state, const KernelScene<N>& scene, const Constraints& constraints,
           Project project) {
  ParticleState particles(scene.current, scene.inverse_mass);
  for (auto _ : state) {
    project(ParticleArrays::of(particles), constraints, 0, scene.count, ProjectionSettings{});
    benchmark::ClobberMemory();
  }
}

void edge_point(benchmark::State& state, const std::string& variant) {
  const auto scene = make_kernel_scene<3>(variant == "batch_sorted", edge_point_points);
  if (variant == "scalar") {
    scalar<3>(state, scene,
              [](const std::vector<Vector3r>& x, const std::vector<Real>& w, const ParticleIndex* i,
                 std::array<Vector3r, 3>& corr) {
                return PositionBasedDynamics::solve_EdgePointDistanceConstraint(
                    x[i[0]], w[i[0]], x[i[1]], w[i[1]], x[i[2]], w[i[2]], kRestDistance, 1, 1,
                    corr[0], corr[1], corr[2]);
              });
    return;
  }
  EdgePointDistanceConstraintInput input;
  input.particles = scene.indices;
  input.particle_count = scene.rest.size();
  input.rest_distance = kRestDistance;
  batch<3>(state, scene, make_edge_point_distance_constraints(input),
           project_edge_point_distance_constraints);
}

void triangle_point(benchmark::State& state, const std::string& variant) {
  const auto scene = make_kernel_scene<4>(variant == "batch_sorted", triangle_point_points);
  if (variant == "scalar") {
    scalar<4>(state, scene,
              [](const std::vector<Vector3r>& x, const std::vector<Real>& w, const ParticleIndex* i,
                 std::array<Vector3r, 4>& corr) {
                return PositionBasedDynamics::solve_TrianglePointDistanceConstraint(
                    x[i[0]], w[i[0]], x[i[1]], w[i[1]], x[i[2]], w[i[2]], x[i[3]], w[i[3]],
                    kRestDistance, 1, 1, corr[0], corr[1], corr[2], corr[3]);
              });
    return;
  }
  TrianglePointDistanceConstraintInput input;
  input.particles = scene.indices;
  input.particle_count = scene.rest.size();
  input.rest_distance = kRestDistance;
  batch<4>(state, scene, make_triangle_point_distance_constraints(input),
           project_triangle_point_distance_constraints);
}

void edge_edge(benchmark::State& state, const std::string& variant) {
  const auto scene = make_kernel_scene<4>(variant == "batch_sorted", edge_edge_points);
  if (variant == "scalar") {
    scalar<4>(state, scene,
              [](const std::vector<Vector3r>& x, const std::vector<Real>& w, const ParticleIndex* i,
                 std::array<Vector3r, 4>& corr) {
                return PositionBasedDynamics::solve_EdgeEdgeDistanceConstraint(
                    x[i[0]], w[i[0]], x[i[1]], w[i[1]], x[i[2]], w[i[2]], x[i[3]], w[i[3]],
                    kRestDistance, 1, 1, corr[0], corr[1], corr[2], corr[3]);
              });
    return;
  }
  EdgeEdgeDistanceConstraintInput input;
  input.particles = scene.indices;
  input.particle_count = scene.rest.size();
  input.rest_distance = kRestDistance;
  batch<4>(state, scene, make_edge_edge_distance_constraints(input),
           project_edge_edge_distance_constraints);
}

const bool registered = [] {
  using Run = void (*)(benchmark::State&, const std::string&);
  const std::pair<const char*, Run> families[] = {{"edge_point_distance", edge_point},
                                                  {"triangle_point_distance", triangle_point},
                                                  {"edge_edge_distance", edge_edge}};
  for (const auto& [family, run] : families)
    for (const std::string variant : {"scalar", "batch", "batch_sorted"})
      register_kernel_benchmark(family, variant,
                                [run, variant](benchmark::State& s) { run(s, variant); });
  return true;
}();

}  // namespace
}  // namespace tessera::bench
