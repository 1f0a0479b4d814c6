// The one place a scene's simulation settings become the solver's settings. io keeps them in
// its own plain struct (io::SimulationSettings), because io depends on core only and cannot
// name the solver; the tool, which depends on everything, maps that struct here, once.
#pragma once

#include <tessera/io/scene_description.hpp>
#include <tessera/parallel/solver.hpp>

namespace tessera::cli {

/// The mode parsed from its name (InvalidInput naming it when unknown), the thread count as
/// given (0 stays 0: the solver reads it through worker_threads), the time step, substeps,
/// iterations, gravity, velocity damping and (when set) the Chebyshev acceleration and its ρ;
/// every other field keeps SolverSettings' default.
SolverSettings solver_settings(const io::SimulationSettings& simulation);

/// The scene's contacts as the collision stage's settings: its colliders (a mesh collider
/// from scene.collider_meshes, in order), thickness, friction, restitution, self-collision.
/// Throws InvalidInput for a collider the collision module rejects.
CollisionSettings collision_settings(const io::Scene& scene);

}  // namespace tessera::cli
