// kernel/particle_tet_contact/{scalar,batch,batch_sorted}: the position solve (accumulated,
// clamped λ) of 65,536 contacts, each a particle just inside the top of its own tetrahedron.
// The contacts are initialised once outside the timed loop (init_ / make_); the timed sweep is
// the per-iteration work of a contact solver.
#include <tessera/core/particle_tet_contact_constraints.hpp>
#include <tessera/core/position_based_dynamics.hpp>

#include "kernel_benchmark_support.hpp"

namespace tessera::bench {
namespace {

using Info = Eigen::Matrix<Real, 3, 3, Eigen::DontAlign>;

const Vector3r kBarycentric(Real(0.2), Real(0.25), Real(0.3));

KernelScene<5> contact_scene(bool sorted) {
  return make_kernel_scene<5>(sorted, [](std::mt19937& engine) {
    std::uniform_real_distribution<Real> unit(-1, 1);
    const Vector3r origin(unit(engine), unit(engine), unit(engine));
    std::array<Vector3r, 5> p = {origin, origin, origin + Vector3r(Real(0.3), 0, 0),
                                 origin + Vector3r(0, Real(0.3), 0),
                                 origin + Vector3r(0, 0, Real(0.3))};
    // The particle sits just below the contact point (normal +z).
    p[0] = Real(0.25) * p[1] + Real(0.2) * p[2] + Real(0.25) * p[3] + Real(0.3) * p[4] -
           Vector3r(0, 0, Real(0.02));
    return p;
  });
}

void scalar(benchmark::State& state) {
  const KernelScene<5> scene = contact_scene(false);
  const Vector3r normal(0, 0, 1), zero = Vector3r::Zero();
  const std::array<Vector3r, 4> still = {zero, zero, zero, zero};
  std::vector<Vector3r> x = scene.current;
  const std::vector<Real>& w = scene.inverse_mass;
  std::vector<Info> info(scene.count);
  std::vector<Real> lambda(scene.count, 0);
  for (std::size_t c = 0; c < scene.count; ++c) {
    const ParticleIndex* p = &scene.indices[5 * c];
    const std::array<Real, 4> wt = {w[p[1]], w[p[2]], w[p[3]], w[p[4]]};
    const std::array<Vector3r, 4> xt = {x[p[1]], x[p[2]], x[p[3]], x[p[4]]};
    PositionBasedDynamics::init_ParticleTetContactConstraint(w[p[0]], x[p[0]], zero, wt.data(),
                                                             xt.data(), still.data(),
                                                             kBarycentric, normal, info[c]);
  }
  for (auto _ : state) {
    for (std::size_t c = 0; c < scene.count; ++c) {
      const ParticleIndex* p = &scene.indices[5 * c];
      const std::array<Real, 4> wt = {w[p[1]], w[p[2]], w[p[3]], w[p[4]]};
      const std::array<Vector3r, 4> xt = {x[p[1]], x[p[2]], x[p[3]], x[p[4]]};
      Vector3r corr0;
      std::array<Vector3r, 4> corr;
      if (PositionBasedDynamics::solve_ParticleTetContactConstraint(
              w[p[0]], x[p[0]], wt.data(), xt.data(), kBarycentric, info[c], lambda[c], corr0,
              corr.data())) {
        x[p[0]] += corr0;
        for (int k = 0; k < 4; ++k) x[p[k + 1]] += corr[std::size_t(k)];
      }
    }
    benchmark::ClobberMemory();
  }
}

void batch(benchmark::State& state, bool sorted) {
  const KernelScene<5> scene = contact_scene(sorted);
  ParticleState particles(scene.current, scene.inverse_mass);
  const std::vector<Vector3r> barycentric(scene.count, kBarycentric);
  const std::vector<Vector3r> normals(scene.count, Vector3r(0, 0, 1));
  ParticleTetContacts contacts =
      make_particle_tet_contacts({scene.indices, barycentric, normals}, particles);
  for (auto _ : state) {
    project_particle_tet_contacts(ParticleArrays::of(particles), contacts, 0, scene.count);
    benchmark::ClobberMemory();
  }
}

const bool registered = [] {
  register_kernel_benchmarks("particle_tet_contact", scalar, batch);
  return true;
}();

}  // namespace
}  // namespace tessera::bench
