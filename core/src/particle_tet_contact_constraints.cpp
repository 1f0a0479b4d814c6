// Particle–tetrahedron contacts in SoA batches: validation and init_ at the door, then the
// batched position solve and velocity (friction) solve, each compiled once per SIMD target
// (Highway foreach_target) and dispatched at run time. All three run the family's one formula
// (kernels/particle_tet_contact-inl.h) on W contacts at a time.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "particle_tet_contact_constraints.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/core/particle_tet_contact_constraints.hpp>

#include "kernels/batch-inl.h"
#include "kernels/particle_tet_contact-inl.h"
#include "kernels/residual_lanes-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {
namespace {

HWY_INLINE Vec3<RealLanes> load_vec3(const std::array<AlignedVector<Real>, 3>& arrays,
                                     std::size_t i) {
  const RealTag d;
  return {hn::LoadU(d, arrays[0].data() + i), hn::LoadU(d, arrays[1].data() + i),
          hn::LoadU(d, arrays[2].data() + i)};
}

HWY_INLINE void store_vec3(const Vec3<RealLanes>& value, std::size_t active_count,
                           std::array<AlignedVector<Real>, 3>& arrays, std::size_t i) {
  store_active(value.x, active_count, arrays[0].data() + i);
  store_active(value.y, active_count, arrays[1].data() + i);
  store_active(value.z, active_count, arrays[2].data() + i);
}

/// The five particles of W contacts (slot 0 the particle, 1..4 the tet).
struct ContactLanes {
  ParticleLanes particle;
  ParticleLanes tet[4];
  RealLanes w[4];
  Vec3<RealLanes> x[4];
};

HWY_INLINE ContactLanes gather_contact(const ParticleArrays& arrays,
                                       const ParticleTetContacts& contacts, std::size_t i,
                                       std::size_t end) {
  ContactLanes lanes;
  lanes.particle = gather_particles(arrays, contacts.particles.particle[0].data() + i, end - i);
  HWY_UNROLL(4)  // the slots' lanes stay in registers (see gather_constraint_particles)
  for (int k = 0; k < 4; ++k) {
    lanes.tet[k] = gather_particles(arrays, contacts.particles.particle[k + 1].data() + i, end - i);
    lanes.w[k] = lanes.tet[k].inverse_mass;
    lanes.x[k] = lanes.tet[k].position;
  }
  return lanes;
}

HWY_INLINE void scatter_contact(ParticleArrays& arrays, const ParticleTetContacts& contacts,
                                std::size_t i, const ContactLanes& lanes,
                                const ContactCorrection<RealLanes>& correction,
                                const LaneMask& active) {
  if (arrays.corrected_x != nullptr) {  // redirected output (see ParticleArrays)
    store_corrected(arrays, 0, i, lanes.particle, correction.particle, active);
    for (std::size_t k = 0; k < 4; ++k)
      store_corrected(arrays, k + 1, i, lanes.tet[k], correction.tet[k], active);
    return;
  }
  scatter_corrected(arrays, contacts.particles.particle[0].data() + i, lanes.particle,
                    correction.particle, active);
  HWY_UNROLL(4)
  for (int k = 0; k < 4; ++k)
    scatter_corrected(arrays, contacts.particles.particle[k + 1].data() + i, lanes.tet[k],
                      correction.tet[k], active);
}

}  // namespace

void InitParticleTetContacts(ParticleArrays velocities, ParticleTetContacts& contacts) {
  const RealTag d;
  const std::size_t n = contacts.size();
  for (std::size_t i = 0; i < n; i += hn::Lanes(d)) {
    const std::size_t active_count = n - i;
    const ContactLanes v = gather_contact(velocities, contacts, i, n);
    const auto info = contact_init(v.particle.inverse_mass, v.w, v.particle.position, v.x,
                                   load_vec3(contacts.barycentric, i),
                                   load_vec3(contacts.normal, i));
    store_vec3(info.normal, active_count, contacts.normal, i);
    store_vec3(info.tangent, active_count, contacts.tangent, i);
    store_active(info.effective_mass, active_count, contacts.effective_mass.data() + i);
    store_active(info.max_tangential_impulse, active_count,
                 contacts.max_tangential_impulse.data() + i);
    store_active(info.normal_speed, active_count, contacts.normal_speed.data() + i);
  }
}

void ProjectParticleTetContacts(ParticleArrays particles, ParticleTetContacts& contacts,
                                std::size_t begin, std::size_t end,
                                bool lambda_starts_at_zero) {
  const RealTag d;
  for (std::size_t i = begin; i < end; i += hn::Lanes(d)) {
    const std::size_t active_count = end - i;
    const LaneMask active = hn::FirstN(d, active_count);
    const ContactLanes p = gather_contact(particles, contacts, i, end);
    RealLanes lambda =
        lambda_starts_at_zero ? hn::Zero(d) : hn::LoadU(d, contacts.lambda.data() + i);
    const auto correction = contact_position_solve(
        p.particle.inverse_mass, p.w, p.particle.position, p.x,
        load_vec3(contacts.barycentric, i), load_vec3(contacts.normal, i),
        hn::LoadU(d, contacts.effective_mass.data() + i), lambda);
    store_active(lambda, active_count, contacts.lambda.data() + i);
    scatter_contact(particles, contacts, i, p, correction, active);
  }
}

void SolveParticleTetContactVelocities(ParticleArrays velocities,
                                       const ParticleTetContacts& contacts, std::size_t begin,
                                       std::size_t end, Real dt) {
  const RealTag d;
  const RealLanes inverse_dt = hn::Set(d, Real(1) / dt);
  for (std::size_t i = begin; i < end; i += hn::Lanes(d)) {
    const LaneMask active = hn::FirstN(d, end - i);
    const ContactLanes v = gather_contact(velocities, contacts, i, end);
    const auto correction = contact_velocity_solve(
        v.particle.inverse_mass, v.w, v.particle.position, v.x,
        load_vec3(contacts.barycentric, i), load_vec3(contacts.normal, i),
        hn::LoadU(d, contacts.lambda.data() + i) * inverse_dt,
        hn::LoadU(d, contacts.friction.data() + i));
    scatter_contact(velocities, contacts, i, v, correction, active);
  }
}

void ParticleTetContactResiduals(const ParticleArrays& particles,
                                 const ParticleTetContacts& batch, std::size_t begin,
                                 std::size_t end, Real* out) {
  residual_lanes<5>(
      particles, batch.particles, begin, end, out,
      [&](const Vec3<RealLanes> (&p)[5], std::size_t i) {
        const Vec3<RealLanes> tet[4] = {p[1], p[2], p[3], p[4]};
        const Vec3<RealLanes> bary = {load(batch.barycentric[0].data(), i),
                                      load(batch.barycentric[1].data(), i),
                                      load(batch.barycentric[2].data(), i)};
        const Vec3<RealLanes> normal = {load(batch.normal[0].data(), i),
                                        load(batch.normal[1].data(), i),
                                        load(batch.normal[2].data(), i)};
        // As constraint_residual: one position solve from λ = 0 with a unit effective mass
        // and no masses accumulates λ = max(0, −C), the penetration depth.
        const RealLanes z = zero<RealLanes>();
        const RealLanes no_mass[4] = {z, z, z, z};
        RealLanes penetration = z;
        contact_position_solve(z, no_mass, p[0], tet, bary, normal, splat<RealLanes>(1.0),
                               penetration);
        return penetration;
      });
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include <tessera/core/position_based_dynamics.hpp>

#include "sequential_loop.hpp"
#include <cmath>
#include <string>

#include "constraint_validation.hpp"

namespace tessera {

HWY_EXPORT(InitParticleTetContacts);
HWY_EXPORT(ProjectParticleTetContacts);
HWY_EXPORT(SolveParticleTetContactVelocities);
HWY_EXPORT(ParticleTetContactResiduals);

namespace {

/// The same test as the scalar init_ (kernels/particle_tet_contact-inl.h).
bool is_unit(const Vector3r& n) {
  return std::abs(n.squaredNorm() - 1) <= Real(1e-4);
}

}  // namespace

namespace {

void build_particle_tet_contacts(const ParticleTetContactInput& input, const ParticleState& state,
                                 ParticleTetContacts& result) {
  const detail::ConstraintValidator validator(ParticleTetContacts::kFamily, state.size());
  validator.check_parameter("friction", input.friction);
  validator.fill_particles(result.particles, input.particles);
  const std::size_t n = result.size();
  if (input.barycentric.size() != n || input.normals.size() != n)
    validator.fail_input(std::to_string(n) + " contacts but " +
                         std::to_string(input.barycentric.size()) +
                         " barycentric coordinates and " + std::to_string(input.normals.size()) +
                         " normals");
  for (auto& a : result.barycentric) detail::fill(a, n, 0);
  for (auto& a : result.normal) detail::fill(a, n, 0);
  for (auto& a : result.tangent) detail::fill(a, n, 0);
  for (std::size_t c = 0; c < n; ++c) {
    const Vector3r& bary = input.barycentric[c];
    const Vector3r& normal = input.normals[c];
    if (!bary.allFinite()) validator.fail(c, "barycentric coordinates are not finite");
    if (!normal.allFinite()) validator.fail(c, "normal is not finite");
    if (!is_unit(normal)) validator.fail(c, "normal is not a unit vector");
    for (int slot = 0; slot < 5; ++slot) {
      const ParticleIndex p = result.particles.particle[std::size_t(slot)][c];
      if (!std::isfinite(state.velocity_x[p]) || !std::isfinite(state.velocity_y[p]) ||
          !std::isfinite(state.velocity_z[p]))
        validator.fail(c, "velocity of particle " + std::to_string(p) + " is not finite");
    }
    for (int k = 0; k < 3; ++k) {
      result.barycentric[std::size_t(k)][c] = bary[k];
      result.normal[std::size_t(k)][c] = normal[k];
    }
  }
  detail::fill(result.effective_mass, n, 0);
  detail::fill(result.max_tangential_impulse, n, 0);
  detail::fill(result.normal_speed, n, 0);
  detail::fill(result.friction, n, input.friction);
  detail::fill(result.lambda, n, 0);
  if (n > 0) {
    ParticleState& velocities = const_cast<ParticleState&>(state);  // only read by init
    HWY_DYNAMIC_DISPATCH(InitParticleTetContacts)(velocity_arrays_of(velocities), result);
  }
}

}  // namespace

void make_particle_tet_contacts(const ParticleTetContactInput& input, const ParticleState& state,
                                ParticleTetContacts& out) {
  // A rejected input leaves `out` empty, never a count its arrays do not match.
  try {
    build_particle_tet_contacts(input, state, out);
  } catch (...) {
    out = {};
    throw;
  }
}

ParticleTetContacts make_particle_tet_contacts(const ParticleTetContactInput& input,
                                               const ParticleState& state) {
  ParticleTetContacts result;
  make_particle_tet_contacts(input, state, result);
  return result;
}

void project_particle_tet_contacts(ParticleArrays particles, ParticleTetContacts& contacts,
                                   std::size_t begin, std::size_t end,
                                   const ProjectionSettings& settings) {
  check_projection_range(ParticleTetContacts::kFamily, begin, end, contacts.size(),
                         contacts.particles.particle_count, particles);
  HWY_DYNAMIC_DISPATCH(ProjectParticleTetContacts)(particles, contacts, begin, end,
                                                   settings.lambda_starts_at_zero);
}

void solve_particle_tet_contact_velocities(ParticleArrays velocities,
                                           const ParticleTetContacts& contacts,
                                           std::size_t begin, std::size_t end, Real dt) {
  check_projection_range(ParticleTetContacts::kFamily, begin, end, contacts.size(),
                         contacts.particles.particle_count, velocities);
  if (!(dt > 0) || !std::isfinite(dt))
    throw InvalidInput(std::string(ParticleTetContacts::kFamily) +
                       " constraints: time step must be finite and positive");
  HWY_DYNAMIC_DISPATCH(SolveParticleTetContactVelocities)(velocities, contacts, begin, end, dt);
}

void constraint_residuals(const ParticleArrays& particles, const ParticleTetContacts& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(ParticleTetContactResiduals)(particles, batch, begin, end, out);
}

void project_sequentially(ParticleArrays particles, ParticleTetContacts& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& /*settings: the contact's own rule*/) {
  check_projection_range(ParticleTetContacts::kFamily, begin, end, batch.size(),
                         batch.particles.particle_count, particles);
  // Slot 0 is the particle, slots 1..4 the tet's x[0..3].
  detail::project_in_order<5>(
      particles, batch.particles, begin, end,
      [&](std::size_t c, const detail::ConstraintStencil<5>& s, Vector3r(&corr)[5]) {
        Matrix3r constraint_info = Matrix3r::Zero();
        for (int k = 0; k < 3; ++k) {
          constraint_info(k, 0) = batch.normal[std::size_t(k)][c];
          constraint_info(k, 1) = batch.tangent[std::size_t(k)][c];
        }
        constraint_info(0, 2) = batch.effective_mass[c];
        constraint_info(1, 2) = batch.max_tangential_impulse[c];
        constraint_info(2, 2) = batch.normal_speed[c];
        const Vector3r barycentric(batch.barycentric[0][c], batch.barycentric[1][c],
                                   batch.barycentric[2][c]);
        PositionBasedDynamics::solve_ParticleTetContactConstraint(s.inverse_mass[0], s.position[0],
                                                s.inverse_mass + 1, s.position + 1, barycentric,
                                                constraint_info, batch.lambda[c], corr[0],
                                                corr + 1);
      });
}

}  // namespace tessera
#endif  // HWY_ONCE
