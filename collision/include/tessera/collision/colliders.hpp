// Static colliders (a plane, sphere, oriented box, capsule or triangle mesh that never moves)
// and the contacts particles make with them each substep.
//
// Every collider answers one question, closest_surface: the signed distance of a point
// (negative inside), the unit outward normal and the closest surface point. Contact
// generation turns the answer into a one-sided constraint per particle: the particle must
// stay on the admissible side n · p ≥ n · q + thickness of the plane tangent at q, which the
// collider-contact constraint family projects (ColliderContactInput in core maps one to one
// onto ColliderHits).
//
// The shapes are plain structs; validate_colliders checks them (find_collider_contacts and
// penetration_depth call it, closest_surface does not: it runs per point).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <variant>
#include <vector>

#include <tessera/collision/mesh_collider.hpp>
#include <tessera/core/indices.hpp>
#include <tessera/core/particle_state.hpp>
#include <tessera/core/real.hpp>

namespace tessera {

/// The half-space n · x ≤ offset; its free side is n · x > offset. The normal must be unit
/// (| |n|² − 1 | ≤ 1e-4): a plane is usually written from a known direction, and a silently
/// normalised one would move the surface when offset was meant for the unit normal.
struct PlaneCollider {
  Vector3r normal = Vector3r::UnitY();
  Real offset = 0;
};

/// A solid ball. At its exact centre the outward normal is +y.
struct SphereCollider {
  Vector3r centre = Vector3r::Zero();
  Real radius = 1;
};

/// A solid oriented box: the points centre + rotation · l with |l_k| ≤ half_extents_k. The
/// rotation's columns are the box's axes in world space (orthonormal, determinant +1). A zero
/// half extent (a flat plate) is allowed. Inside, the nearest face is the surface (ties go to
/// the lowest axis, then the positive face).
struct BoxCollider {
  Vector3r centre = Vector3r::Zero();
  Vector3r half_extents = Vector3r::Ones();
  Matrix3r rotation = Matrix3r::Identity();
};

/// A solid capsule: the points within radius of the segment a–b. a == b makes it a sphere.
/// On the axis the outward normal is the unit vector perpendicular to the axis closest to +y
/// (+z when the axis is along y; +y for a ball).
struct CapsuleCollider {
  Vector3r a = Vector3r::Zero();
  Vector3r b = Vector3r::UnitY();
  Real radius = 1;
};

using Collider =
    std::variant<PlaneCollider, SphereCollider, BoxCollider, CapsuleCollider, MeshCollider>;

/// Throws InvalidInput naming the collider ("collider 2 (sphere): radius -1 must be finite
/// and > 0") for: a non-finite value, a plane normal that is not unit, a radius that is not
/// finite and > 0, a negative half extent, a box rotation that is not a rotation (columns not
/// orthonormal within 1e-4, or a reflection). Mesh colliders are validated when built.
void validate_colliders(std::span<const Collider> colliders);

/// Signed distance, unit outward normal and closest surface point of p; point = p − distance
/// · normal. The collider must be valid (validate_colliders).
SurfaceQuery closest_surface(const Collider& collider, const Vector3r& p);

/// The contacts of one substep, one entry per (particle, collider) pair in contact, ordered
/// by particle, then collider. The arrays map one to one onto ColliderContactInput.
struct ColliderHits {
  std::vector<ParticleIndex> particles;
  /// Unit outward normal n of the contact plane.
  std::vector<Vector3r> normals;
  /// n · q + thickness (q the surface point): the admissible side is n · p ≥ offset.
  std::vector<Real> offsets;
  /// The particle's position at the start of the substep (friction measures sliding from it).
  std::vector<Vector3r> anchors;
  /// v · n of the particle's velocity (negative when approaching: restitution reads it).
  std::vector<Real> normal_speeds;
  /// Which collider, as a position in the span given.
  std::vector<std::uint32_t> collider;

  std::size_t size() const { return particles.size(); }
  /// Empties the hits; keeps every buffer's capacity.
  void clear();

  /// One hit, as a chunk of particles finds it before the chunks are joined.
  struct Hit {
    ParticleIndex particle;
    std::uint32_t collider;
    Vector3r normal;
    Real offset;
    Vector3r anchor;
    Real normal_speed;
  };
  /// Workspace of find_collider_contacts, kept here so that a substep allocates nothing once
  /// the buffers have grown: the hits of each fixed chunk of particles.
  std::vector<std::vector<Hit>> chunk_hits;
  /// Workspace: the bounds of each mesh collider (unused for the others).
  std::vector<Bounds3> mesh_bounds;
};

/// Finds the contacts of the predicted positions (state.x, y, z) with the colliders: for every
/// movable particle (inverse mass > 0) and every collider with closest_surface(p).distance <
/// thickness + margin, one hit with the contact plane at the closest surface point. out is
/// overwritten. Parallel over fixed chunks of particles, joined in particle order: the result
/// is the same for any number of threads. Throws InvalidInput for an invalid collider (see
/// validate_colliders) or a thickness or margin that is negative or not finite.
///
/// Tunnelling. For a mesh collider the segment previous → predicted position is tested as
/// well: when it enters the mesh through a triangle's front side, the hit is that triangle's
/// plane at the crossing point (the entry side), whatever the distance of the predicted
/// position, so a particle that went through a thin wall within one substep is pushed back,
/// not out of the far side. A particle outside the mesh's bounds grown by thickness + margin
/// makes no contact with it (exact for a closed mesh; for an open mesh it limits its back
/// side, which counts as inside, to the bounds). The analytic shapes are tested at the
/// predicted position only: a particle that crosses more than half of a sphere, box or
/// capsule within one substep is pushed out of the far side (a plane is a half-space and
/// cannot be crossed).
void find_collider_contacts(std::span<const Collider> colliders, const ParticleState& state,
                            Real thickness, Real margin, ColliderHits& out);

/// The deepest penetration of any position into any collider: max(0, −distance) over all
/// pairs, 0 when none is inside (or there are no colliders). As for contacts, a position
/// outside a mesh's bounds is not inside it. Validates the colliders.
Real penetration_depth(std::span<const Collider> colliders,
                       std::span<const Vector3r> positions);

}  // namespace tessera
