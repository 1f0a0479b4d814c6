// Particle–tetrahedron contacts as an SoA batch: a particle that has entered a tetrahedron of
// another body is pushed out along the contact normal (one-sided, accumulated multiplier
// clamped at 0), then Coulomb friction acts on the velocities. Contacts are made anew every
// step by collision detection, so building a batch also runs the seed's init_ for every
// contact (at the velocities of that moment) and resets λ.
//
//   slot 0: the particle;  slots 1..4: the tet's particles x[0..3]
//   barycentric (b1, b2, b3) of the contact point w.r.t. x[1..3] (b0 = 1 - b1 - b2 - b3)
//   normal: unit, from the tet towards the particle
#pragma once

#include <array>
#include <cstddef>
#include <span>

#include <tessera/core/constraint_batch.hpp>

namespace tessera {

struct ParticleTetContactInput {
  /// Five particle indices per contact: the particle, then the tet's four.
  std::span<const ParticleIndex> particles;
  /// (b1, b2, b3) per contact.
  std::span<const Vector3r> barycentric;
  /// The unit contact normal per contact.
  std::span<const Vector3r> normals;
  /// Coulomb friction coefficient μ ≥ 0 of every contact (changeable afterwards per contact).
  Real friction = 0;
};

struct ParticleTetContacts {
  static constexpr const char* kFamily = "particle-tet contact";
  static constexpr FamilyTraits kTraits = {
      .arity = 5, .xpbd = false, .multiplier = true, .velocity_pass = true,
      .cell = CellShape::none};
  /// Its arrays by constraint and its batch-wide fields (see constraint_families.hpp).
  template <class Self>
  static auto per_constraint_arrays(Self& b) {
    return std::tie(b.barycentric, b.normal, b.tangent, b.effective_mass, b.max_tangential_impulse,
                    b.normal_speed, b.friction, b.lambda);
  }
  template <class Self>
  static auto batch_wide_fields(Self&) {
    return std::tie();
  }
  ConstraintParticles<5> particles;
  std::array<AlignedVector<Real>, 3> barycentric;
  std::array<AlignedVector<Real>, 3> normal;
  /// Unit tangent of the sliding at init (0 when none), as in the seed's constraintInfo.col(1).
  std::array<AlignedVector<Real>, 3> tangent;
  /// 1 / (nᵀ K n), 0 for a contact between two static sides (which then does nothing).
  AlignedVector<Real> effective_mass;
  /// |u_t| / (tᵀ K t) at init: the impulse that would stop the sliding.
  AlignedVector<Real> max_tangential_impulse;
  /// u · n at init: the relative normal velocity.
  AlignedVector<Real> normal_speed;
  AlignedVector<Real> friction;
  /// Accumulated normal multiplier of the position solve (0 after make; ≥ 0 always).
  AlignedVector<Real> lambda;

  std::size_t size() const { return particles.count; }
};

/// Validates the contacts against `state` (its inverse masses and velocities are read for
/// init_) and builds the batch with λ = 0. Throws InvalidInput naming the contact for: an
/// index out of range, a particle named twice, non-finite barycentric coordinates, a normal
/// that is not finite or not a unit vector (| |n|² - 1 | > 1e-4), a non-finite velocity of one
/// of its particles, an index count that is not a multiple of 5, a count of barycentric
/// coordinates or normals that differs from the number of contacts, and a friction
/// coefficient that is negative or not finite. A contact whose both sides are static is kept
/// (effective mass 0) and does nothing.
ParticleTetContacts make_particle_tet_contacts(const ParticleTetContactInput& input,
                                               const ParticleState& state);
/// The same into `out`: every field replaced, its arrays keep their capacity (the collision
/// stage's per-substep contacts). On InvalidInput `out` is left empty. The input's spans must
/// not point into `out`.
void make_particle_tet_contacts(const ParticleTetContactInput& input, const ParticleState& state,
                                ParticleTetContacts& out);

/// Position solve of contacts [begin, end) once (accumulating λ; of `settings`, only
/// lambda_starts_at_zero is read), W at a time on the active SIMD target, writing the
/// corrected positions of movable particles. The contacts of the range must share no movable
/// particle; ranges solved concurrently must not share a block of kMaxLanes consecutive
/// contacts.
void project_particle_tet_contacts(ParticleArrays particles, ParticleTetContacts& contacts,
                                   std::size_t begin, std::size_t end,
                                   const ProjectionSettings& settings = {});

/// Velocity solve (friction) of contacts [begin, end) after the velocity update of a substep
/// of length dt: the normal impulse per unit time is λ / dt. `velocities` as given by
/// velocity_arrays_of (particle_state.hpp). Same sharing rules as the position solve; λ is
/// only read.
void solve_particle_tet_contact_velocities(ParticleArrays velocities,
                                           const ParticleTetContacts& contacts,
                                           std::size_t begin, std::size_t end, Real dt);

// ------------------------------------------------------------ the family's entry points
// project_sequentially, Particle–tet contacts, position solve only (friction stays with
// solve_particle_tet_contact_velocities): PositionBasedDynamics::
// solve_ParticleTetContactConstraint with the barycentric coordinates and a constraintInfo rebuilt
// from the batch (col 0 normal, col 1 tangent, (0,2) effective_mass, (1,2) max_tangential_impulse,
// (2,2) normal_speed), accumulating the batch's lambda. The contact's multiplier rule is its own
// (clamped at 0): settings are not used.
// constraint_residuals, Particle–tet contact: the penetration depth max(0, −C) in length units, C =
// n · (p0 − Σ b_i x_i) the kernel's signed distance of the particle above the contact plane (stored
// normal n and barycentric b). 0 while the particle is on the outer side.
TESSERA_FAMILY_ENTRY_POINTS(ParticleTetContacts, project_particle_tet_contacts)

/// The velocity pass (solve_particle_tet_contact_velocities).
inline void solve_velocity_constraints(ParticleArrays velocities, const ParticleTetContacts& batch,
                                       std::size_t begin, std::size_t end, Real dt) {
  solve_particle_tet_contact_velocities(velocities, batch, begin, end, dt);
}

}  // namespace tessera
