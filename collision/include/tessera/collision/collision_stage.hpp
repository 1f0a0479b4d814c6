// The collision stage: contacts found from the positions every substep, handed to the solver
// as constraint batches it schedules (coloured among themselves, or a Jacobi set;
// SolverSettings::contact_scheduling) and projects like any family.
//
//   per substep, after the prediction (x = predicted, previous = start of the substep):
//
//     state ──► colliders (plane, sphere, box, capsule, mesh)  ──► collider_contact
//          │     one closest-point query per movable particle        (unilateral, friction,
//          │                                                          restitution)
//          └──► self-collision (the surface)                    ──► triangle_point_distance
//                spatial hash of the swept primitives,                edge_edge_distance
//                vertex–triangle and edge–edge within reach           (compression only)
//                  a vertex near a solid's boundary face      ──► particle_tet_contact
//                  (solid_contacts.hpp)                               (outwards, friction)
//
// Why per substep: a contact is a linearisation (a tangent plane, a closest pair) that is
// valid only near the positions it was made at; remade every substep (h = 1/60/32 s by
// default) it never drifts far, where one made per frame lets a fast particle pass a thin
// collider or a cloth layer before the next detection. What it costs is measured in the
// collision benchmarks.
//
// Numbering: the stage works in the numbering of the state it is given (the solver hands it
// the scheduled state and the surface renumbered once), so no contact is renumbered per
// substep. Lists come out sorted by particle, so every thread count gives the same contacts.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <tessera/collision/colliders.hpp>
#include <tessera/core/constraint_families.hpp>
#include <tessera/core/particle_state.hpp>
#include <tessera/core/real.hpp>

namespace tessera {

/// Defaults of the stage: 5 mm of contact distance, friction of cloth on a dry surface.
inline constexpr Real kDefaultThickness = Real(0.005);
inline constexpr Real kDefaultStaticFriction = Real(0.4);
inline constexpr Real kDefaultDynamicFriction = Real(0.3);
/// The most substeps between self-collision grid builds (CollisionSettings::
/// self_collision_interval). A build puts each particle on the straight path of its motion
/// and lists the candidate pairs whose paths can come within reach before its horizon: the
/// substeps in which its fast particles close SelfCollision::kHorizonReachShare of the reach,
/// at most interval − 1 (SelfCollisionSettings::horizon). Each particle has room to stray
/// from its path (kSelfCollisionMotionSubsteps substeps of the change of its motion, plus
/// kSelfCollisionSkin thicknesses); every substep until the next build tests the candidates
/// at its own positions, and a particle that has strayed beyond its room gets its primitives
/// re-boxed (SelfCollision::update; a full build when they pass SelfCollision::kReboxedShare
/// of the mesh). So the contacts are exactly those of a detection every substep: every
/// setting below ends the drape and the pile on the same state_hash, only the cost moves.
/// Detection seconds, 1 thread, Zen 3 VM, one run each (runs differ by up to 10 %); the
/// drape 30 frames, the pile 90:
///
///   horizon                                  drape 30 frames    pile
///   fixed 3 (interval 4)                     13.6–14.8 s        1.03 s (725 builds)
///   0.75 of the reach, at most 15 (default)  12.9 s             0.81 s (232 builds)
///   0.5 / 1 of the reach, at most 15         14.8 / 13.4 s      0.78 / 0.80 s
///   0.75 of the reach, at most 31            12.8 s             0.82 s
///   room (substeps, skin) 1.5, 0.1 / 3, 0.1 / 2, 0.05 / 2, 0.2 (horizon 3): drape 14.5–15.3,
///   14.1–14.5, 14.8–15.7, 13.7–15.1 s against 13.6–14.8 s for 2, 0.1 (the default)
///
/// A fixed long horizon lists more candidates on the drape (each pair allows for horizon
/// substeps of its paths' relative motion, and the boxes are swept along the paths): 15 and
/// 31 substeps took 28 s and 47 s; the pile, whose paths barely diverge, wants a long one.
/// Before the paths, with one frame moving at the cloth's median motion, the drape took
/// 23.6–27.3 s and the pile 0.82–0.85 s (docs/performance.md, "Paths").
inline constexpr std::size_t kDefaultSelfCollisionInterval = 16;
inline constexpr std::size_t kSelfCollisionMotionSubsteps = 2;
inline constexpr Real kSelfCollisionSkin = Real(0.1);

struct CollisionSettings {
  /// Static colliders.
  std::vector<Collider> colliders;
  /// Contact distance: a particle keeps this far outside a collider and from the cloth's
  /// triangles and edges; > 0 where self-collision is on, ≥ 0 otherwise, finite.
  Real thickness = kDefaultThickness;
  /// Coulomb friction against colliders (Macklin et al. 2014, position-based): the tangential
  /// motion of a substep is removed when below static_friction × penetration, else shortened
  /// by dynamic_friction × penetration. ≥ 0, finite.
  Real static_friction = kDefaultStaticFriction;
  Real dynamic_friction = kDefaultDynamicFriction;
  /// Coefficient of restitution e ∈ [0, 1] against colliders; approaches slower than
  /// 2 |g| h bounce with e = 0 (so resting contacts do not jitter).
  Real restitution = 0;
  /// The surface against itself: vertex–triangle and edge–edge contacts of the surface
  /// (cloth folding onto itself; solids against one another, whose vertex–face contacts
  /// are particle–tet contacts with friction dynamic_friction).
  bool self_collision = false;
  /// Stiffness of the self-contacts (PBD, compression only), in [0, 1].
  Real self_stiffness = 1;
  /// The self-collision grids are built at least every this many substeps, and sooner when
  /// a particle outruns what the last build covers; every other substep tests the last
  /// build's candidates at its own positions (the same contacts either way); colliders are
  /// queried every substep. ≥ 1. See kDefaultSelfCollisionInterval for the measurement.
  std::size_t self_collision_interval = kDefaultSelfCollisionInterval;
};

/// Throws InvalidInput naming the setting: negative or non-finite thickness, friction or
/// restitution outside its range, self-collision with thickness 0, a stiffness outside [0, 1].
void check_collision_settings(const CollisionSettings& settings);

/// What detection found, per substep and summed.
struct CollisionStatistics {
  /// Contacts of the last substep, by kind.
  std::size_t collider_contacts = 0;
  std::size_t vertex_triangle_contacts = 0;
  std::size_t edge_edge_contacts = 0;
  std::size_t particle_tet_contacts = 0;
  /// Over every substep detected so far: the number of substeps, the sum and the largest
  /// number of contacts of one substep, and the wall time of detection (broad + narrow phase
  /// and building the batches).
  std::uint64_t substeps = 0;
  /// The substeps that built the self-collision grids, and those that re-boxed the
  /// primitives of particles that outran their room (the others refined the candidates).
  std::uint64_t self_detections = 0;
  std::uint64_t self_reboxes = 0;
  std::uint64_t contacts_sum = 0;
  std::size_t contacts_max = 0;
  double seconds_detection = 0;
  /// The part of seconds_detection spent in self-collision, by what the substep did: built
  /// the grids, re-boxed the primitives of particles that outran their room, or only
  /// filtered the candidates (each includes that substep's filtering). Where a run's
  /// detection time goes: a build costs tens of filterings.
  double seconds_self_built = 0;
  double seconds_self_reboxed = 0;
  double seconds_self_refined = 0;

  std::size_t contacts() const {
    return collider_contacts + vertex_triangle_contacts + edge_edge_contacts +
           particle_tet_contacts;
  }
  double contacts_mean() const { return substeps == 0 ? 0 : double(contacts_sum) / double(substeps); }
};

class CollisionStage {
 public:
  /// `triangles` (3 indices each, in the numbering of the states detect() will be given) is
  /// the surface self-collision works on; empty without self-collision. `tetrahedra` (4 each,
  /// same numbering) are the solids: a surface triangle that is a face of one gets
  /// particle–tet contacts (solid_contacts.hpp). Throws InvalidInput for bad settings, an
  /// index ≥ particle_count or a tetrahedron naming a particle twice.
  CollisionStage(CollisionSettings settings, std::vector<std::uint32_t> triangles,
                 std::size_t particle_count, std::span<const std::uint32_t> tetrahedra = {});
  ~CollisionStage();
  CollisionStage(CollisionStage&&) noexcept;
  CollisionStage& operator=(CollisionStage&&) noexcept;

  /// The contacts of `state` (positions predicted, previous = start of the substep) for a
  /// substep of length h under gravity of magnitude `gravity`: replaces `contacts` with
  /// collider contacts and self-contacts (λ = 0), reusing its arrays (pass the same set each
  /// substep and, once the contacts stop growing, detection allocates nothing). Runs its
  /// parallel loops in the calling task arena.
  void detect(const ParticleState& state, Real h, Real gravity, ConstraintSets& contacts);

  const CollisionSettings& settings() const { return settings_; }
  const CollisionStatistics& statistics() const { return statistics_; }
  std::span<const std::uint32_t> triangles() const { return triangles_; }

 private:
  struct Buffers;
  CollisionSettings settings_;
  std::vector<std::uint32_t> triangles_;
  std::size_t particle_count_ = 0;
  std::unique_ptr<Buffers> buffers_;
  CollisionStatistics statistics_;
};

}  // namespace tessera
