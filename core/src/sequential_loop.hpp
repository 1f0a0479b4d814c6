// The sequential reference loop (sequential_projection.hpp), written once for every family:
// for each constraint of [begin, end) in order, copy its particles out of the SoA arrays,
// call the family's scalar-API mapping (its `solve`, in <family>_constraints.cpp), add the
// corrections to the movable particles, go on. Each family's project_sequentially is then
// only its mapping from batch arrays to scalar-API arguments, the part that has to match the
// batched kernel. No heap allocation per constraint.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <tuple>
#include <utility>

#include <tessera/core/constraint_batch.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/particle_state.hpp>
#include <tessera/core/real.hpp>

namespace tessera::detail {

/// The particles of one constraint, copied out of the SoA arrays.
template <int N>
struct ConstraintStencil {
  ParticleIndex index[N];
  Vector3r position[N];
  Real inverse_mass[N];
};

inline Vector3r position_of(const ParticleArrays& particles, ParticleIndex i) {
  const std::size_t at = i * particles.stride;
  return Vector3r(particles.x[at], particles.y[at], particles.z[at]);
}

/// Adds a correction to particle i when it is movable; a static particle is never written.
inline void add_correction(const ParticleArrays& particles, ParticleIndex i, Real inverse_mass,
                    const Vector3r& correction) {
  if (!(inverse_mass > 0)) return;
  const std::size_t at = i * particles.stride;
  particles.x[at] += correction.x();
  particles.y[at] += correction.y();
  particles.z[at] += correction.z();
}

template <int N>
ConstraintStencil<N> gather_stencil(const ParticleArrays& particles,
                                    const ConstraintParticles<N>& slots, std::size_t c) {
  ConstraintStencil<N> stencil;
  for (int k = 0; k < N; ++k) {
    const ParticleIndex i = slots.particle[std::size_t(k)][c];
    stencil.index[k] = i;
    stencil.position[k] = position_of(particles, i);
    stencil.inverse_mass[k] = particles.inverse_mass[i * particles.stride];
  }
  return stencil;
}

/// The loop itself: solve(c, stencil, corr) calls the scalar API on constraint c and writes
/// its N corrections, which are applied before constraint c + 1 is gathered.
template <int N, class Solve>
void project_in_order(const ParticleArrays& particles, const ConstraintParticles<N>& slots,
                      std::size_t begin, std::size_t end, Solve&& solve) {
  for (std::size_t c = begin; c < end; ++c) {
    const ConstraintStencil<N> s = gather_stencil<N>(particles, slots, c);
    Vector3r corr[N];
    solve(c, s, corr);
    for (int k = 0; k < N; ++k) add_correction(particles, s.index[k], s.inverse_mass[k], corr[k]);
  }
}

/// The same over a fixed-arity batch, after its range and particle checks.
template <class Batch, class Solve>
void project_batch_in_order(const ParticleArrays& particles, const Batch& batch,
                            std::size_t begin, std::size_t end, Solve&& solve) {
  check_projection_range(Batch::kFamily, begin, end, batch.size(),
                         batch.particles.particle_count, particles);
  project_in_order<Batch::kTraits.arity>(particles, batch.particles, begin, end, solve);
}

/// Calls a scalar-API function in the seed's argument order: solve(p0, w0, ..., p(N-1),
/// w(N-1), parameters..., corr[0], ..., corr[N-1]).
template <int N, class Function, class... Parameters>
void call_scalar_api(Function&& solve, const ConstraintStencil<N>& s, Vector3r (&corr)[N],
                     Parameters&&... parameters) {
  [&]<std::size_t... K>(std::index_sequence<K...>) {
    std::apply(solve, std::tuple_cat(std::tie(s.position[K], s.inverse_mass[K])...,
                                     std::forward_as_tuple(parameters...),
                                     std::tie(corr[K])...));
  }(std::make_index_sequence<std::size_t(N)>());
}

inline bool uses_compliance(const ProjectionSettings& settings) {
  return settings.semantics == ConstraintSemantics::compliance;
}

/// The mapping of a family whose scalar API is solve(particles, rest, stiffness, corr) in PBD
/// and solve(particles, rest, compliance, dt, λ, corr) in XPBD: rest(c) is constraint c's rest
/// value, stiffness, compliance and λ its arrays of those names.
template <class Batch, class Pbd, class Xpbd, class Rest>
void project_stiffness_or_compliance(const ParticleArrays& particles, Batch& batch,
                                     std::size_t begin, std::size_t end,
                                     const ProjectionSettings& settings, Pbd&& pbd, Xpbd&& xpbd,
                                     Rest&& rest) {
  project_batch_in_order(particles, batch, begin, end,
                         [&](std::size_t c, const auto& s, auto& corr) {
                           if (uses_compliance(settings))
                             call_scalar_api(xpbd, s, corr, rest(c), batch.compliance[c],
                                             settings.dt, batch.lambda[c]);
                           else
                             call_scalar_api(pbd, s, corr, rest(c), batch.stiffness[c]);
                         });
}

/// invRestMat(k, j) from rest_inverse[Dim k + j] (the layout of the strain and FEM batches).
template <int Dim, std::size_t Entries>
Eigen::Matrix<Real, Dim, Dim, Eigen::DontAlign> rest_inverse_of(
    const std::array<AlignedVector<Real>, Entries>& rest_inverse, std::size_t c) {
  static_assert(Entries == std::size_t(Dim * Dim));
  Eigen::Matrix<Real, Dim, Dim, Eigen::DontAlign> m;
  for (int k = 0; k < Dim; ++k)
    for (int j = 0; j < Dim; ++j) m(k, j) = rest_inverse[std::size_t(Dim * k + j)][c];
  return m;
}

/// The checks of the proximity entry points: range, particle count, stiffness semantics.
template <class Constraints>
void check_proximity_call(const ParticleArrays& particles, const Constraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings) {
  check_projection_range(Constraints::kFamily, begin, end, batch.size(),
                         batch.particles.particle_count, particles);
  if (uses_compliance(settings))
    throw InvalidInput(std::string(Constraints::kFamily) +
                       " constraints: only stiffness semantics are supported (no XPBD form)");
}

}  // namespace tessera::detail
