// Particle–collider contacts in SoA batches: validation at the door, then the batched position
// solve, velocity (restitution) solve and residual, each compiled once per SIMD target
// (Highway foreach_target) and dispatched at run time. All run the family's one formula
// (kernels/collider_contact-inl.h) on W contacts at a time.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "collider_contact_constraints.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/core/collider_contact_constraints.hpp>

#include "kernels/batch-inl.h"
#include "kernels/collider_contact-inl.h"
#include "kernels/residual_lanes-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {
namespace {

HWY_INLINE Vec3<RealLanes> load_vec3(const std::array<AlignedVector<Real>, 3>& arrays,
                                     std::size_t i) {
  return {load(arrays[0].data(), i), load(arrays[1].data(), i), load(arrays[2].data(), i)};
}

}  // namespace

void ProjectColliderContacts(ParticleArrays particles, ColliderContacts& contacts,
                             std::size_t begin, std::size_t end,
                             bool lambda_starts_at_zero) {
  const RealTag d;
  const ParticleIndex* slot[1];
  constraint_slots(contacts.particles, slot);
  for (std::size_t i = begin; i < end; i += hn::Lanes(d)) {
    const std::size_t active_count = end - i;
    ParticleLanes gathered[1];
    Vec3<RealLanes> p[1];
    RealLanes w[1];
    gather_constraint_particles<1>(particles, slot, i, end, gathered, p, w);
    RealLanes lambda = lambda_starts_at_zero ? hn::Zero(d) : load(contacts.lambda.data(), i);
    const auto solved = collider_contact_position_solve(
        w[0], p[0], load_vec3(contacts.normal, i), load(contacts.offset.data(), i),
        load_vec3(contacts.anchor, i), load(contacts.static_friction.data(), i),
        load(contacts.dynamic_friction.data(), i), lambda);
    store_active(lambda, active_count, contacts.lambda.data() + i);
    const Vec3<RealLanes> correction[1] = {solved.correction};
    scatter_constraint_particles<1>(particles, slot, i, gathered, correction,
                                    hn::FirstN(d, active_count));
  }
}

void SolveColliderContactVelocities(ParticleArrays velocities, const ColliderContacts& contacts,
                                    std::size_t begin, std::size_t end) {
  const RealTag d;
  const ParticleIndex* slot[1];
  constraint_slots(contacts.particles, slot);
  for (std::size_t i = begin; i < end; i += hn::Lanes(d)) {
    ParticleLanes gathered[1];
    Vec3<RealLanes> v[1];
    RealLanes w[1];
    gather_constraint_particles<1>(velocities, slot, i, end, gathered, v, w);
    const auto solved = collider_contact_velocity_solve(
        w[0], v[0], load_vec3(contacts.normal, i), load(contacts.normal_speed.data(), i),
        load(contacts.restitution.data(), i), load(contacts.lambda.data(), i));
    const Vec3<RealLanes> correction[1] = {solved.correction};
    scatter_constraint_particles<1>(velocities, slot, i, gathered, correction,
                                    hn::FirstN(d, end - i));
  }
}

void ColliderContactResiduals(const ParticleArrays& particles, const ColliderContacts& batch,
                              std::size_t begin, std::size_t end, Real* out) {
  residual_lanes<1>(particles, batch.particles, begin, end, out,
                    [&](const Vec3<RealLanes> (&p)[1], std::size_t i) {
                      return collider_contact_penetration(p[0], load_vec3(batch.normal, i),
                                                          load(batch.offset.data(), i));
                    });
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include <tessera/core/position_based_dynamics_extensions.hpp>

#include <cmath>
#include <string>

#include "constraint_validation.hpp"
#include "sequential_loop.hpp"

namespace tessera {

HWY_EXPORT(ProjectColliderContacts);
HWY_EXPORT(SolveColliderContactVelocities);
HWY_EXPORT(ColliderContactResiduals);

namespace {

/// The same test as the lane formula's (kernels/collider_contact-inl.h).
bool is_unit(const Vector3r& n) {
  return std::abs(n.squaredNorm() - 1) <= Real(1e-4);
}

void set_vec3(std::array<AlignedVector<Real>, 3>& arrays, std::size_t c, const Vector3r& v) {
  for (std::size_t k = 0; k < 3; ++k) arrays[k][c] = v[int(k)];
}

Vector3r vec3_of(const std::array<AlignedVector<Real>, 3>& arrays, std::size_t c) {
  return Vector3r(arrays[0][c], arrays[1][c], arrays[2][c]);
}

}  // namespace

namespace {

void build_collider_contacts(const ColliderContactInput& input, ColliderContacts& result) {
  const detail::ConstraintValidator validator(ColliderContacts::kFamily, input.particle_count);
  validator.check_parameter("static friction", input.static_friction);
  validator.check_parameter("dynamic friction", input.dynamic_friction);
  if (!(input.restitution >= 0 && input.restitution <= 1))
    validator.fail_input("restitution is " + detail::describe(input.restitution) +
                         ", must lie in [0, 1]");
  validator.fill_particles(result.particles, input.particles);
  const std::size_t n = result.size();
  if (input.normals.size() != n || input.offsets.size() != n || input.anchors.size() != n ||
      input.normal_speeds.size() != n)
    validator.fail_input(std::to_string(n) + " contacts but " +
                         std::to_string(input.normals.size()) + " normals, " +
                         std::to_string(input.offsets.size()) + " offsets, " +
                         std::to_string(input.anchors.size()) + " anchors and " +
                         std::to_string(input.normal_speeds.size()) + " normal speeds");
  for (auto& a : result.normal) detail::fill(a, n, 0);
  for (auto& a : result.anchor) detail::fill(a, n, 0);
  detail::fill(result.offset, n, 0);
  detail::fill(result.normal_speed, n, 0);
  for (std::size_t c = 0; c < n; ++c) {
    const Vector3r& normal = input.normals[c];
    if (!normal.allFinite()) validator.fail(c, "normal is not finite");
    if (!is_unit(normal)) validator.fail(c, "normal is not a unit vector");
    validator.check_finite(c, "offset", input.offsets[c]);
    if (!input.anchors[c].allFinite()) validator.fail(c, "anchor is not finite");
    validator.check_finite(c, "normal speed", input.normal_speeds[c]);
    set_vec3(result.normal, c, normal);
    set_vec3(result.anchor, c, input.anchors[c]);
    result.offset[c] = input.offsets[c];
    result.normal_speed[c] = input.normal_speeds[c];
  }
  detail::fill(result.static_friction, n, input.static_friction);
  detail::fill(result.dynamic_friction, n, input.dynamic_friction);
  detail::fill(result.restitution, n, input.restitution);
  detail::fill(result.lambda, n, 0);
}

}  // namespace

void make_collider_contacts(const ColliderContactInput& input, ColliderContacts& out) {
  // A rejected input leaves `out` empty, never a count its arrays do not match.
  try {
    build_collider_contacts(input, out);
  } catch (...) {
    out = {};
    throw;
  }
}

ColliderContacts make_collider_contacts(const ColliderContactInput& input) {
  ColliderContacts result;
  make_collider_contacts(input, result);
  return result;
}

void project_collider_contacts(ParticleArrays particles, ColliderContacts& contacts,
                               std::size_t begin, std::size_t end,
                               const ProjectionSettings& settings) {
  check_projection_range(ColliderContacts::kFamily, begin, end, contacts.size(),
                         contacts.particles.particle_count, particles);
  HWY_DYNAMIC_DISPATCH(ProjectColliderContacts)(particles, contacts, begin, end,
                                                settings.lambda_starts_at_zero);
}

void solve_collider_contact_velocities(ParticleArrays velocities,
                                       const ColliderContacts& contacts, std::size_t begin,
                                       std::size_t end) {
  check_projection_range(ColliderContacts::kFamily, begin, end, contacts.size(),
                         contacts.particles.particle_count, velocities);
  HWY_DYNAMIC_DISPATCH(SolveColliderContactVelocities)(velocities, contacts, begin, end);
}

void constraint_residuals(const ParticleArrays& particles, const ColliderContacts& batch,
                          std::size_t begin, std::size_t end, Real* out) {
  HWY_DYNAMIC_DISPATCH(ColliderContactResiduals)(particles, batch, begin, end, out);
}

void project_sequentially(ParticleArrays particles, ColliderContacts& batch, std::size_t begin,
                          std::size_t end,
                          const ProjectionSettings& /*settings: the contact's own rule*/) {
  detail::project_batch_in_order(
      particles, batch, begin, end,
      [&](std::size_t c, const detail::ConstraintStencil<1>& s, Vector3r(&corr)[1]) {
        PositionBasedDynamicsExtensions::solve_ColliderContactConstraint(
            s.position[0], s.inverse_mass[0], vec3_of(batch.normal, c), batch.offset[c],
            vec3_of(batch.anchor, c), batch.static_friction[c], batch.dynamic_friction[c],
            batch.lambda[c], corr[0]);
      });
}

}  // namespace tessera
#endif  // HWY_ONCE
