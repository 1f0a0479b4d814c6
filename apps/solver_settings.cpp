// io::SimulationSettings → SolverSettings (see solver_settings.hpp).
#include "solver_settings.hpp"

namespace tessera::cli {

SolverSettings solver_settings(const io::SimulationSettings& simulation) {
  SolverSettings settings;
  settings.mode = parse_solver_mode(simulation.mode);
  settings.threads = simulation.threads;
  settings.time_step = simulation.time_step;
  settings.substeps = simulation.substeps;
  settings.iterations = simulation.iterations;
  settings.gravity = simulation.gravity;
  settings.velocity_damping = simulation.velocity_damping;
  settings.sequential_order = parse_sequential_order(simulation.sequential_order);
  settings.divergence_rms = simulation.divergence_rms;
  if (simulation.contact_scheduling)
    settings.contact_scheduling = parse_contact_scheduling(*simulation.contact_scheduling);
  if (simulation.chebyshev) settings.chebyshev = *simulation.chebyshev;
  if (simulation.chebyshev_rho) settings.chebyshev_rho = *simulation.chebyshev_rho;
  return settings;
}

CollisionSettings collision_settings(const io::Scene& scene) {
  const io::CollisionDescription& description = scene.description.collisions;
  CollisionSettings settings;
  std::size_t mesh = 0;
  for (const io::ColliderDescription& collider : description.colliders) {
    switch (collider.shape) {
      case io::ColliderShape::plane:
        settings.colliders.push_back(PlaneCollider{collider.normal.normalized(), collider.offset / collider.normal.norm()});
        break;
      case io::ColliderShape::sphere:
        settings.colliders.push_back(SphereCollider{collider.centre, collider.radius});
        break;
      case io::ColliderShape::box:
        settings.colliders.push_back(BoxCollider{collider.centre, collider.half_extents});
        break;
      case io::ColliderShape::capsule:
        settings.colliders.push_back(CapsuleCollider{collider.a, collider.b, collider.radius});
        break;
      case io::ColliderShape::mesh: {
        const io::Mesh& source = scene.collider_meshes.at(mesh++);
        settings.colliders.push_back(MeshCollider(source.positions, source.triangles));
        break;
      }
    }
  }
  settings.thickness = description.thickness;
  settings.static_friction = description.static_friction;
  settings.dynamic_friction = description.dynamic_friction;
  settings.restitution = description.restitution;
  settings.self_collision = description.self_collision;
  settings.self_collision_interval = description.self_collision_interval;
  return settings;
}

}  // namespace tessera::cli
