// Particle–collider contacts as an SoA batch: a particle touching a static collider (plane,
// sphere, box, capsule, static mesh). The collision module linearises the collider at the
// point closest to the particle into a plane every substep and builds one contact per
// touching particle: C = n · p − offset ≥ 0 with the plane's unit outward normal n. The
// position solve pushes a penetrating particle back onto the plane and applies
// position-based static and dynamic friction against its motion since the substep began
// (Macklin et al. 2014, eq. 24); the velocity pass then sets the normal velocity of every
// contact that pushed to its restitution bounce (Müller et al. 2020, eq. 34). The formula is
// in kernels/collider_contact-inl.h; its scalar form is
// PositionBasedDynamicsExtensions::solve_ColliderContactConstraint and
// velocitySolve_ColliderContactConstraint (position_based_dynamics_extensions.hpp).
#pragma once

#include <array>
#include <cstddef>
#include <span>

#include <tessera/core/constraint_batch.hpp>

namespace tessera {

struct ColliderContactInput {
  /// One particle index per contact.
  std::span<const ParticleIndex> particles;
  /// The number of particles; every index must be below it.
  std::size_t particle_count = 0;
  /// The unit outward normal of the collider's tangent plane, per contact.
  std::span<const Vector3r> normals;
  /// The admissible side is n · p ≥ offset (offset = n · q + thickness, q the closest point
  /// on the collider), per contact.
  std::span<const Real> offsets;
  /// The particle's position at the start of the substep, per contact: friction measures the
  /// tangential motion from it.
  std::span<const Vector3r> anchors;
  /// v · n before the solve (negative: approaching), per contact: what restitution reverses.
  std::span<const Real> normal_speeds;
  /// Static and dynamic friction coefficients μs, μk ≥ 0 and restitution e ∈ [0, 1] of every
  /// contact (per-contact arrays of the batch, changeable afterwards).
  Real static_friction = 0;
  Real dynamic_friction = 0;
  Real restitution = 0;
};

struct ColliderContacts {
  static constexpr const char* kFamily = "collider contact";
  static constexpr FamilyTraits kTraits = {
      .arity = 1, .xpbd = false, .multiplier = true, .velocity_pass = true,
      .cell = CellShape::none};
  /// Its arrays by constraint and its batch-wide fields (see constraint_families.hpp).
  template <class Self>
  static auto per_constraint_arrays(Self& b) {
    return std::tie(b.normal, b.offset, b.anchor, b.normal_speed, b.static_friction,
                    b.dynamic_friction, b.restitution, b.lambda);
  }
  template <class Self>
  static auto batch_wide_fields(Self&) {
    return std::tie();
  }
  ConstraintParticles<1> particles;
  /// Unit outward normal of the collider's tangent plane.
  std::array<AlignedVector<Real>, 3> normal;
  /// The plane's offset: the admissible side is n · p ≥ offset.
  AlignedVector<Real> offset;
  /// The particle's position at the start of the substep (friction's reference).
  std::array<AlignedVector<Real>, 3> anchor;
  /// v · n before the solve (restitution's reference).
  AlignedVector<Real> normal_speed;
  AlignedVector<Real> static_friction;
  AlignedVector<Real> dynamic_friction;
  AlignedVector<Real> restitution;
  /// The accumulated normal correction of the position solve (0 after make, ≥ 0 always; the
  /// solver resets it every substep): the velocity pass acts where it is positive.
  AlignedVector<Real> lambda;

  std::size_t size() const { return particles.count; }
};

/// Validates and builds the batch with λ = 0. Throws InvalidInput naming the contact for: an
/// index out of range, a normal that is not finite or not a unit vector (| |n|² − 1 | >
/// 1e-4), a non-finite offset, anchor or normal speed; and about the input as a whole for a
/// count of normals, offsets, anchors or normal speeds that differs from the number of
/// contacts, a friction coefficient that is negative or not finite, and a restitution outside
/// [0, 1]. A particle may have several contacts (one per collider it touches).
ColliderContacts make_collider_contacts(const ColliderContactInput& input);
/// The same into `out`: every field replaced, its arrays keep their capacity (the collision
/// stage's per-substep contacts). On InvalidInput `out` is left empty. The input's spans must
/// not point into `out`.
void make_collider_contacts(const ColliderContactInput& input, ColliderContacts& out);

/// Position solve of contacts [begin, end) once (accumulating λ; of `settings`, only
/// lambda_starts_at_zero is read), W at a time on the active SIMD target, writing the
/// corrected positions of movable particles (the range rules of every batched kernel,
/// constraint_batch.hpp).
void project_collider_contacts(ParticleArrays particles, ColliderContacts& contacts,
                               std::size_t begin, std::size_t end,
                               const ProjectionSettings& settings = {});

/// Velocity solve (restitution) of contacts [begin, end) after the velocity update of a
/// substep. `velocities` as given by velocity_arrays_of (particle_state.hpp).
/// Same sharing rules as the position solve; λ is only read.
void solve_collider_contact_velocities(ParticleArrays velocities,
                                       const ColliderContacts& contacts, std::size_t begin,
                                       std::size_t end);

// ------------------------------------------------------------ the family's entry points
// project_sequentially, Collider contact: PositionBasedDynamicsExtensions::
// solve_ColliderContactConstraint with (normal, offset, anchor, static_friction,
// dynamic_friction) and the batch's lambda, accumulating it. The contact's multiplier rule is
// its own (the penetration, ≥ 0): settings are not used.
// constraint_residuals, Collider contact: the penetration depth max(0, −C) in length units,
// C = n · p − offset (stored normal and offset). 0 while the particle is on the admissible
// side.
TESSERA_FAMILY_ENTRY_POINTS(ColliderContacts, project_collider_contacts)

/// The velocity pass (solve_collider_contact_velocities); restitution sets a velocity, so the
/// substep's dt is not used.
inline void solve_velocity_constraints(ParticleArrays velocities, const ColliderContacts& batch,
                                       std::size_t begin, std::size_t end, Real /*dt*/) {
  solve_collider_contact_velocities(velocities, batch, begin, end);
}

}  // namespace tessera
