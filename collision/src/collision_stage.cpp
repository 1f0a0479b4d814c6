// The collision stage (collision_stage.hpp): colliders and self-collision, each substep.
#include <tessera/collision/collision_stage.hpp>

#include <chrono>
#include <cmath>
#include <string>

#include <tessera/collision/self_collision.hpp>
#include <tessera/collision/solid_contacts.hpp>
#include <tessera/core/error.hpp>

namespace tessera {

namespace {

void check_range(const char* name, Real value, Real low, Real high) {
  if (!(std::isfinite(value) && value >= low && value <= high))
    throw InvalidInput(std::string("collisions: ") + name + " must be in [" + std::to_string(low) +
                       ", " + (std::isfinite(high) ? std::to_string(high) : std::string("inf")) +
                       "), not " + std::to_string(value));
}

}  // namespace

void check_collision_settings(const CollisionSettings& settings) {
  constexpr Real kUnbounded = std::numeric_limits<Real>::max();
  check_range("thickness", settings.thickness, 0, kUnbounded);
  check_range("static friction", settings.static_friction, 0, kUnbounded);
  check_range("dynamic friction", settings.dynamic_friction, 0, kUnbounded);
  check_range("restitution", settings.restitution, 0, 1);
  check_range("self-contact stiffness", settings.self_stiffness, 0, 1);
  if (settings.self_collision && !(settings.thickness > 0))
    throw InvalidInput("collisions: self-collision needs a positive thickness");
  validate_colliders(settings.colliders);
  if (settings.self_collision_interval == 0)
    throw InvalidInput("collisions: the self-collision interval must be at least 1 substep");
}

struct CollisionStage::Buffers {
  ColliderHits hits;
  std::unique_ptr<SelfCollision> self;
  SelfCollision::Contacts self_contacts;
  SolidContactScratch solid_scratch;
  /// The faces of the solids among the surface triangles (null without solids).
  std::unique_ptr<SolidSurface> solids;
  std::vector<ParticleIndex> distance_contacts;
  std::size_t substeps_since_detection = 0;
};

CollisionStage::CollisionStage(CollisionSettings settings, std::vector<std::uint32_t> triangles,
                               std::size_t particle_count,
                               std::span<const std::uint32_t> tetrahedra)
    : settings_(std::move(settings)),
      triangles_(std::move(triangles)),
      particle_count_(particle_count),
      buffers_(std::make_unique<Buffers>()) {
  check_collision_settings(settings_);
  if (triangles_.size() % 3 != 0)
    throw InvalidInput("collisions: " + std::to_string(triangles_.size()) +
                       " triangle indices, not a multiple of 3");
  for (std::size_t i = 0; i < triangles_.size(); ++i)
    if (triangles_[i] >= particle_count_)
      throw InvalidInput("collisions: triangle " + std::to_string(i / 3) + " names particle " +
                         std::to_string(triangles_[i]) + ", there are " +
                         std::to_string(particle_count_));
  if (settings_.self_collision && !triangles_.empty())
    buffers_->self = std::make_unique<SelfCollision>(triangles_, particle_count_);
  if (!tetrahedra.empty()) {
    auto solids = std::make_unique<SolidSurface>(tetrahedra, triangles_, particle_count_);
    if (!solids->empty()) buffers_->solids = std::move(solids);
  }
}

CollisionStage::~CollisionStage() = default;
CollisionStage::CollisionStage(CollisionStage&&) noexcept = default;
CollisionStage& CollisionStage::operator=(CollisionStage&&) noexcept = default;

void CollisionStage::detect(const ParticleState& state, Real h, Real gravity,
                            ConstraintSets& contacts) {
  const auto start = std::chrono::steady_clock::now();
  Buffers& buffers = *buffers_;
  // The families this stage makes are rebuilt into `contacts` below, keeping their arrays'
  // capacity (a substep in steady state allocates nothing); every other family is emptied.
  const auto rebuilt = [&](ConstraintFamily family) {
    switch (family) {
      case ConstraintFamily::collider_contact: return true;
      case ConstraintFamily::triangle_point_distance:
      case ConstraintFamily::edge_edge_distance: return buffers.self != nullptr;
      case ConstraintFamily::particle_tet_contact: return buffers.self && buffers.solids;
      default: return false;
    }
  };
  contacts.for_each([&](ConstraintFamily family, auto& batch) {
    if (!rebuilt(family)) batch = {};
  });
  // A contact reaches one thickness beyond the contact distance, so a particle the
  // iterations push towards a collider (or a layer) still finds the contact made for it.
  const Real margin = settings_.thickness;

  find_collider_contacts(settings_.colliders, state, settings_.thickness, margin, buffers.hits);
  const std::size_t hit_count = buffers.hits.particles.size();
  {
    // Slow approaches do not bounce (resting contacts would jitter): an approach slower
    // than what gravity adds in two substeps gets e = 0.
    const Real slow = 2 * gravity * h;
    ColliderContactInput input{.particles = buffers.hits.particles,
                               .particle_count = state.size(),
                               .normals = buffers.hits.normals,
                               .offsets = buffers.hits.offsets,
                               .anchors = buffers.hits.anchors,
                               .normal_speeds = buffers.hits.normal_speeds,
                               .static_friction = settings_.static_friction,
                               .dynamic_friction = settings_.dynamic_friction,
                               .restitution = settings_.restitution};
    make_collider_contacts(input, contacts.collider_contact);
    auto& made = contacts.collider_contact;
    for (std::size_t c = 0; c < hit_count; ++c)
      if (-buffers.hits.normal_speeds[c] <= slow) made.restitution[c] = 0;
  }
  statistics_.collider_contacts = hit_count;
  statistics_.vertex_triangle_contacts = statistics_.edge_edge_contacts = 0;
  statistics_.particle_tet_contacts = 0;

  if (buffers.self) {
    const std::size_t interval = settings_.self_collision_interval;
    // Half a thickness of reach beyond the contact distance: the detection adds each pair's
    // motion (self_collision.hpp). A surface made only of solids' faces has no edge pair to
    // keep (solid_contacts.hpp): its edge–edge search, three quarters of a detection, is
    // skipped.
    const bool all_solid =
        buffers.solids && buffers.solids->solid_face_count() * 3 == triangles_.size();
    SelfCollisionSettings self{.thickness = settings_.thickness,
                               .margin = settings_.thickness / 2,
                               .stiffness = settings_.self_stiffness,
                               .edge_edge = !all_solid,
                               .motion_scale = Real(kSelfCollisionMotionSubsteps),
                               .skin = kSelfCollisionSkin * settings_.thickness,
                               .horizon = interval - 1};
    // The grids at most every `interval` substeps; in between, the last build's candidates
    // filtered at this substep's positions, the primitives of a particle that moved beyond
    // its room re-boxed first (self_collision.hpp): the same contacts as a build every
    // substep.
    const auto self_start = std::chrono::steady_clock::now();
    SelfCollision::Update done = SelfCollision::Update::built;
    if (statistics_.substeps == 0 || buffers.substeps_since_detection + 1 >= interval)
      buffers.self->detect(state, self, buffers.self_contacts);
    else
      done = buffers.self->update(state, self, buffers.self_contacts);
    const double self_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - self_start).count();
    switch (done) {
      case SelfCollision::Update::built:
        buffers.substeps_since_detection = 0;
        ++statistics_.self_detections;
        statistics_.seconds_self_built += self_seconds;
        break;
      case SelfCollision::Update::reboxed:
        ++statistics_.self_reboxes;
        ++buffers.substeps_since_detection;
        statistics_.seconds_self_reboxed += self_seconds;
        break;
      case SelfCollision::Update::refined:
        ++buffers.substeps_since_detection;
        statistics_.seconds_self_refined += self_seconds;
        break;
    }
    if (buffers.solids) {
      // Vertex–face pairs of solids become particle–tet contacts; the rest stay distances.
      // Edge pairs of two solids are dropped (solid_contacts.hpp).
      split_solid_contacts(*buffers.solids, buffers.self_contacts, state, settings_.thickness,
                           settings_.dynamic_friction, buffers.distance_contacts,
                           contacts.particle_tet_contact, &buffers.solid_scratch);
      buffers.self_contacts.triangle_point.swap(buffers.distance_contacts);
      buffers.self_contacts.triangle_point_triangle.clear();
      drop_solid_edge_pairs(*buffers.solids, buffers.self_contacts.edge_edge);
    }
    make_self_collision_constraints(buffers.self_contacts, state.size(), self,
                                    contacts.triangle_point_distance,
                                    contacts.edge_edge_distance);
    statistics_.vertex_triangle_contacts = buffers.self_contacts.triangle_point_count();
    statistics_.edge_edge_contacts = buffers.self_contacts.edge_edge_count();
    if (buffers.solids) statistics_.particle_tet_contacts = contacts.particle_tet_contact.size();
  }

  ++statistics_.substeps;
  statistics_.contacts_sum += statistics_.contacts();
  statistics_.contacts_max = std::max(statistics_.contacts_max, statistics_.contacts());
  statistics_.seconds_detection +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace tessera
