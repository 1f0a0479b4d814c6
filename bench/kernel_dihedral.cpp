// kernel/dihedral/{scalar,batch,batch_sorted}: the dihedral bending constraint through the
// scalar API in a per-constraint loop, and through the batched kernel over SoA data.
#include <numbers>

#include <tessera/core/dihedral_constraints.hpp>
#include <tessera/core/position_based_dynamics.hpp>

#include "kernel_benchmark_support.hpp"

namespace tessera::bench {
namespace {

/// A hinge with a random opening angle and shape, randomly placed: edge p2-p3, wings p0, p1.
KernelScene<4> dihedral_scene(bool sorted) {
  return make_kernel_scene<4>(sorted, [](std::mt19937& engine) {
    std::uniform_real_distribution<Real> unit(-1, 1), angle(Real(0.3), Real(2.8));
    const Real a = angle(engine);
    const Vector3r shift(unit(engine), unit(engine), unit(engine));
    return std::array<Vector3r, 4>{
        shift + Vector3r(Real(0.5) + Real(0.2) * unit(engine), 1, 0),
        shift + Vector3r(Real(0.5) + Real(0.2) * unit(engine), -std::cos(a), std::sin(a)),
        shift, shift + Vector3r(1, Real(0.1) * unit(engine), 0)};
  });
}

void scalar(benchmark::State& state) {
  const KernelScene<4> scene = dihedral_scene(false);
  const DihedralConstraints constraints =
      make_dihedral_constraints({scene.indices, scene.rest});
  std::vector<Real> rest_angle(constraints.rest_angle.begin(),
                               constraints.rest_angle.begin() + long(scene.count));
  run_scalar_sweeps<4>(state, scene, [&](auto& x, const auto& w, const ParticleIndex* i,
                                         std::size_t c, Vector3r(&corr)[4]) {
    return PositionBasedDynamics::solve_DihedralConstraint(
        x[i[0]], w[i[0]], x[i[1]], w[i[1]], x[i[2]], w[i[2]], x[i[3]], w[i[3]], rest_angle[c], 1,
        corr[0], corr[1], corr[2], corr[3]);
  });
}

void batch(benchmark::State& state, bool sorted) {
  const KernelScene<4> scene = dihedral_scene(sorted);
  run_batch_sweeps(state, scene, make_dihedral_constraints({scene.indices, scene.rest}),
                   project_dihedral_constraints);
}

const bool registered = [] {
  register_kernel_benchmarks("dihedral", scalar, batch);
  return true;
}();

}  // namespace
}  // namespace tessera::bench
