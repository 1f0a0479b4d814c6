// Collision benchmarks, each on a 128 × 128 cloth (16,384 particles, 32,258 triangles,
// 48,641 edges) folded in half over a cylinder of radius 0.4 h (h the spacing), its top
// layer rippled by ±0.3 h so that it comes within reach of the bottom one in places, and
// its upper half coming down onto the lower by 0.2 h over the substep. Thickness 0.4 h, margin 0.1 h.
//
//   collision/self_detect/folded128/threads:<T>   SelfCollision::detect, the whole per-substep
//       cost (boxes, two grid builds, both queries, narrow phase, output); counters
//       triangle_point and edge_edge (contacts found)
//   collision/self_detect_vertex_triangle/folded128/threads:<T>   the same without edge–edge
//       contacts (SelfCollisionSettings::edge_edge = false)
//   collision/self_refine/folded128/threads:<T>   SelfCollision::refine after a detection
//       reaching 4 substeps' motion: the per-substep cost between detections with
//       self_collision_interval = 4 (the candidates tested again, no grid)
//   collision/broad_vertices/folded128/threads:<T>    the grid's candidate pairs of the vertices
//       as points within 2r (r = thickness + margin): build + self_pairs
//   collision/broad_triangles/folded128/threads:<T>   the same for the triangles' boxes grown by
//       r/2: build + self_pairs
//   collision/self_intersections/folded128/threads:<T>   count_self_intersections
//   collision/reference/distance_sweep/cloth128/threads:<T>   one gs projection sweep of the
//       128² distance cloth: the yardstick of the detection's budget (about two sweeps)
//   collision/stage_detect/pile/threads:<T>   CollisionStage::detect on the pile scene
//       (`tessera run pile`, 8 FEM blocks, 1,152 particles) at frame 40, blocks lying on
//       each other and the ground: collider contacts, self-collision pairs, their split into
//       particle–tet contacts, the batches; counters particle_tet, collider, edge_edge
//   collision/reference/sweep/pile/threads:<T>   one gs sweep of the pile's FEM tetrahedra
//       and that substep's contacts, the yardstick for the pile
//   collision/stage_detect/drape/threads:<T>   CollisionStage::detect on the drape scene
//       (`tessera run drape`, 128² cloth, self-collision, sphere and ground) at frame 60, the
//       cloth in folds on the sphere, called once per iteration: with the default
//       self_collision_interval of 4, three refinements per grid build, as in a run; the
//       issue's budget is two of the sweeps below
//   collision/reference/sweep/drape/threads:<T>   one gs sweep of the drape's cloth and that
//       substep's contacts (a substep's projection: the scene runs 1 iteration)
//
// Threads: 1 and 2, each run inside a tbb::task_arena of that many threads.
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <vector>

#include <tbb/task_arena.h>

#include <tessera/collision/collision_stage.hpp>
#include <tessera/collision/self_collision.hpp>
#include <tessera/collision/self_intersections.hpp>
#include <tessera/collision/spatial_hash.hpp>
#include <tessera/io/generators.hpp>
#include <tessera/io/scene_file.hpp>
#include <tessera/parallel/solver.hpp>

#include "scenes.hpp"

namespace {

using namespace tessera;

constexpr std::size_t kSide = 128;

struct FoldedCloth {
  io::ClothGrid grid;
  ParticleState state;
  Real spacing;

  FoldedCloth() : grid(io::make_cloth_grid(kSide, kSide, Real(1) / Real(kSide - 1))) {
    spacing = Real(1) / Real(kSide - 1);
    const Real radius = Real(0.4) * spacing;
    std::vector<Vector3r> positions;
    for (const Vector3r& p : grid.positions) {
      const Real along = p.x() - Real(0.5);
      const Real angle = along / radius;
      if (along <= 0) {
        positions.emplace_back(p.x(), 0, p.y());
      } else if (angle <= std::numbers::pi_v<Real>) {
        positions.emplace_back(Real(0.5) + radius * std::sin(angle),
                               radius - radius * std::cos(angle), p.y());
      } else {
        const Real x = Real(0.5) - (along - std::numbers::pi_v<Real> * radius);
        const Real ripple =
            Real(0.3) * spacing * std::sin(Real(37) * x) * std::cos(Real(23) * p.y());
        positions.emplace_back(x, 2 * radius + ripple, p.y());
      }
    }
    std::vector<Real> inverse_masses(positions.size(), 1);
    inverse_masses[0] = inverse_masses[kSide - 1] = 0;
    state = ParticleState(positions, inverse_masses);
    // The upper half comes down onto the lower by 0.2 h in the substep (only relative
    // motion makes contacts).
    for (std::size_t i = 0; i < state.size(); ++i)
      if (state.y[i] > radius) state.previous_y[i] += Real(0.2) * spacing;
  }
  SelfCollisionSettings settings() const { return {Real(0.4) * spacing, Real(0.1) * spacing}; }
  Real reach() const { return settings().thickness + settings().margin; }
};

const FoldedCloth& folded() {
  static const FoldedCloth cloth;
  return cloth;
}

template <class Body>
void in_arena(benchmark::State& state, Body&& body) {
  tbb::task_arena(int(state.range(0))).execute(body);
}

void BM_SelfDetect(benchmark::State& state, bool edge_edge) {
  const FoldedCloth& cloth = folded();
  SelfCollisionSettings settings = cloth.settings();
  settings.edge_edge = edge_edge;
  in_arena(state, [&] {
    SelfCollision collision(cloth.grid.triangle_indices, cloth.state.size());
    SelfCollision::Contacts contacts;
    collision.detect(cloth.state, settings, contacts);  // buffers at their size
    for (auto _ : state) collision.detect(cloth.state, settings, contacts);
    state.counters["triangle_point"] = double(contacts.triangle_point_count());
    state.counters["edge_edge"] = double(contacts.edge_edge_count());
  });
}
BENCHMARK_CAPTURE(BM_SelfDetect, all, true)->Name("collision/self_detect/folded128")
    ->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_SelfDetect, vertex_triangle, false)
    ->Name("collision/self_detect_vertex_triangle/folded128")->ArgName("threads")->Arg(1)->Arg(2)
    ->UseRealTime()->Unit(benchmark::kMicrosecond);

void BM_SelfRefine(benchmark::State& state) {
  const FoldedCloth& cloth = folded();
  SelfCollisionSettings settings = cloth.settings();
  in_arena(state, [&] {
    SelfCollision collision(cloth.grid.triangle_indices, cloth.state.size());
    SelfCollision::Contacts contacts;
    settings.motion_scale = 4;
    collision.detect(cloth.state, settings, contacts);
    const double candidates = double(contacts.triangle_point_count() + contacts.edge_edge_count());
    settings.motion_scale = 1;
    for (auto _ : state) collision.refine(cloth.state, settings, contacts);
    state.counters["candidates"] = candidates;
    state.counters["contacts"] = double(contacts.triangle_point_count() + contacts.edge_edge_count());
  });
}
BENCHMARK(BM_SelfRefine)->Name("collision/self_refine/folded128")
    ->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

void run_broad_phase(benchmark::State& state, const std::vector<Aabb>& boxes) {
  in_arena(state, [&] {
    UniformGrid grid;
    std::vector<CandidatePair> pairs;
    for (auto _ : state) {
      grid.build(boxes);
      grid.self_pairs(pairs);
    }
    state.counters["pairs"] = double(pairs.size());
  });
}

void BM_BroadVertices(benchmark::State& state) {
  const FoldedCloth& cloth = folded();
  const Real half = cloth.reach();  // boxes of half-width r: pairs within 2r on each axis
  std::vector<Aabb> boxes(cloth.state.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    const Vector3r p = cloth.state.position(i);
    boxes[i] = {{p.x() - half, p.y() - half, p.z() - half}, {p.x() + half, p.y() + half, p.z() + half}};
  }
  run_broad_phase(state, boxes);
}
BENCHMARK(BM_BroadVertices)->Name("collision/broad_vertices/folded128")->ArgName("threads")
    ->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

void BM_BroadTriangles(benchmark::State& state) {
  const FoldedCloth& cloth = folded();
  const auto& t = cloth.grid.triangle_indices;
  std::vector<Aabb> boxes(cloth.grid.triangle_count());
  for (std::size_t k = 0; k < boxes.size(); ++k) {
    const Vector3r a = cloth.state.position(t[3 * k]), b = cloth.state.position(t[3 * k + 1]),
                   c = cloth.state.position(t[3 * k + 2]);
    const Vector3r lo = a.cwiseMin(b).cwiseMin(c).array() - cloth.reach() / 2;
    const Vector3r hi = a.cwiseMax(b).cwiseMax(c).array() + cloth.reach() / 2;
    boxes[k] = {{lo.x(), lo.y(), lo.z()}, {hi.x(), hi.y(), hi.z()}};
  }
  run_broad_phase(state, boxes);
}
BENCHMARK(BM_BroadTriangles)->Name("collision/broad_triangles/folded128")->ArgName("threads")
    ->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

void BM_SelfIntersections(benchmark::State& state) {
  const FoldedCloth& cloth = folded();
  std::vector<Vector3r> positions(cloth.state.size());
  for (std::size_t i = 0; i < positions.size(); ++i) positions[i] = cloth.state.position(i);
  in_arena(state, [&] {
    std::size_t count = 0;
    for (auto _ : state)
      benchmark::DoNotOptimize(count = count_self_intersections(positions, cloth.grid.triangle_indices));
    state.counters["intersections"] = double(count);
  });
}
BENCHMARK(BM_SelfIntersections)->Name("collision/self_intersections/folded128")
    ->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

void BM_DistanceSweep(benchmark::State& state) {
  static const Model model = test::cloth_model(kSide, kSide, test::ClothBending::none);
  SolverSettings settings;
  settings.threads = std::size_t(state.range(0));
  settings.report_residuals = false;
  settings.check_finite = false;
  Solver solver = test::make_solver(model, settings);
  solver.step();
  for (auto _ : state) solver.project(1, settings.time_step);
  state.SetItemsProcessed(state.iterations() * std::int64_t(model.constraints.size()));
}
BENCHMARK(BM_DistanceSweep)->Name("collision/reference/distance_sweep/cloth128")
    ->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

/// The pile scene run to frame 40 (blocks resting on each other), its solver kept for the
/// sweep and its state for detection.
struct SettledPile {
  io::Scene scene = io::build_scene(io::parse_scene_spec("pile"));
  CollisionSettings collisions;
  SolverSettings settings;
  std::unique_ptr<Solver> solver;
  ParticleState state;  // user numbering, previous = one substep back

  SettledPile() {
    collisions.colliders = {PlaneCollider{Vector3r(0, 1, 0), 0}};
    collisions.self_collision = true;
    settings.threads = 2;
    settings.substeps = scene.description.simulation.substeps;
    settings.iterations = scene.description.simulation.iterations;
    settings.report_residuals = false;
    solver = std::make_unique<Solver>(test::make_solver(scene.model, settings, "stencil"));
    solver->set_collisions(collisions, scene.surface_triangles, scene.mesh.tetrahedra);
    for (int frame = 0; frame < 40; ++frame) solver->step();
    const std::vector<Vector3r> x = solver->positions(), v = solver->velocities();
    const std::vector<Real> inverse_masses(
        scene.model.particles.inverse_mass.begin(),
        scene.model.particles.inverse_mass.begin() + std::ptrdiff_t(x.size()));
    state = ParticleState(x, inverse_masses);
    for (std::size_t i = 0; i < x.size(); ++i) {
      const Vector3r previous = x[i] - v[i] * substep();
      state.previous_x[i] = previous.x(), state.previous_y[i] = previous.y(),
      state.previous_z[i] = previous.z();
      state.velocity_x[i] = v[i].x(), state.velocity_y[i] = v[i].y(), state.velocity_z[i] = v[i].z();
    }
  }
  Real substep() const { return settings.time_step / Real(settings.substeps); }
};

SettledPile& settled_pile() {
  static SettledPile pile;
  return pile;
}

void BM_PileDetect(benchmark::State& state) {
  SettledPile& pile = settled_pile();
  in_arena(state, [&] {
    CollisionStage stage(pile.collisions,
                         std::vector<std::uint32_t>(pile.scene.surface_triangles.begin(),
                                                    pile.scene.surface_triangles.end()),
                         pile.state.size(), pile.scene.mesh.tetrahedra);
    ConstraintSets contacts;
    for (auto _ : state) stage.detect(pile.state, pile.substep(), Real(9.81), contacts);
    state.counters["particle_tet"] = double(contacts.particle_tet_contact.size());
    state.counters["collider"] = double(contacts.collider_contact.size());
    state.counters["edge_edge"] = double(contacts.edge_edge_distance.size());
  });
}
BENCHMARK(BM_PileDetect)->Name("collision/stage_detect/pile")
    ->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

void BM_PileSweep(benchmark::State& state) {
  SettledPile& pile = settled_pile();
  SolverSettings settings = pile.settings;
  settings.threads = std::size_t(state.range(0));
  settings.check_finite = false;
  Solver solver = test::make_solver(pile.scene.model, settings, "stencil");
  solver.set_collisions(pile.collisions, pile.scene.surface_triangles, pile.scene.mesh.tetrahedra);
  for (std::size_t i = 0; i < pile.state.size(); ++i) {
    solver.set_position(ParticleIndex(i), pile.state.position(i));
    solver.set_velocity(ParticleIndex(i), pile.state.velocity(i));
  }
  solver.step();  // a substep's contacts in place
  for (auto _ : state) solver.project(1, pile.substep());
  state.SetItemsProcessed(state.iterations() *
                          std::int64_t(pile.scene.model.constraints.size() + solver.contacts().size()));
}
BENCHMARK(BM_PileSweep)->Name("collision/reference/sweep/pile")
    ->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

/// The drape scene (`tessera run drape`: a 128² cloth with self-collision on a sphere and
/// the ground, 32 substeps × 1 iteration) run to frame 60, the cloth lying on the sphere in
/// folds; its solver kept for the sweep and its state for detection.
struct SettledDrape {
  io::Scene scene = io::build_scene(io::parse_scene_spec("drape"));
  CollisionSettings collisions;
  SolverSettings settings;
  std::unique_ptr<Solver> solver;
  ParticleState state;  // user numbering, previous = one substep back

  SettledDrape() {
    const io::CollisionDescription& described = scene.description.collisions;
    for (const io::ColliderDescription& collider : described.colliders)
      if (collider.shape == io::ColliderShape::sphere)
        collisions.colliders.push_back(SphereCollider{collider.centre, collider.radius});
      else
        collisions.colliders.push_back(PlaneCollider{collider.normal, collider.offset});
    collisions.thickness = described.thickness;
    collisions.static_friction = described.static_friction;
    collisions.dynamic_friction = described.dynamic_friction;
    collisions.self_collision = true;
    settings.threads = 2;
    settings.substeps = scene.description.simulation.substeps;
    settings.iterations = scene.description.simulation.iterations;
    settings.report_residuals = false;
    solver = std::make_unique<Solver>(test::make_solver(scene.model, settings, "stencil"));
    solver->set_collisions(collisions, scene.surface_triangles);
    for (int frame = 0; frame < 60; ++frame) solver->step();
    const std::vector<Vector3r> x = solver->positions(), v = solver->velocities();
    const auto masses = scene.model.particles.inverse_mass.begin();
    state = ParticleState(x, std::vector<Real>(masses, masses + std::ptrdiff_t(x.size())));
    for (std::size_t i = 0; i < x.size(); ++i) {
      const Vector3r previous = x[i] - v[i] * substep();
      state.previous_x[i] = previous.x(), state.previous_y[i] = previous.y(),
      state.previous_z[i] = previous.z();
      state.velocity_x[i] = v[i].x(), state.velocity_y[i] = v[i].y(), state.velocity_z[i] = v[i].z();
    }
  }
  Real substep() const { return settings.time_step / Real(settings.substeps); }
};

SettledDrape& settled_drape() {
  static SettledDrape drape;
  return drape;
}

/// One substep's detection as a run makes it: a stage called once per iteration, so every
/// 4th call (self_collision_interval) builds the grids and the others refine.
void BM_DrapeDetect(benchmark::State& state) {
  SettledDrape& drape = settled_drape();
  in_arena(state, [&] {
    CollisionStage stage(drape.collisions,
                         std::vector<std::uint32_t>(drape.scene.surface_triangles.begin(),
                                                    drape.scene.surface_triangles.end()),
                         drape.state.size());
    ConstraintSets contacts;
    for (auto _ : state) stage.detect(drape.state, drape.substep(), Real(9.81), contacts);
    state.counters["collider"] = double(contacts.collider_contact.size());
    state.counters["triangle_point"] = double(contacts.triangle_point_distance.size());
    state.counters["edge_edge"] = double(contacts.edge_edge_distance.size());
  });
}
BENCHMARK(BM_DrapeDetect)->Name("collision/stage_detect/drape")
    ->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

void BM_DrapeSweep(benchmark::State& state) {
  SettledDrape& drape = settled_drape();
  SolverSettings settings = drape.settings;
  settings.threads = std::size_t(state.range(0));
  settings.check_finite = false;
  Solver solver = test::make_solver(drape.scene.model, settings, "stencil");
  solver.set_collisions(drape.collisions, drape.scene.surface_triangles);
  for (std::size_t i = 0; i < drape.state.size(); ++i) {
    solver.set_position(ParticleIndex(i), drape.state.position(i));
    solver.set_velocity(ParticleIndex(i), drape.state.velocity(i));
  }
  solver.step();  // a substep's contacts in place
  for (auto _ : state) solver.project(1, drape.substep());
  state.SetItemsProcessed(state.iterations() *
                          std::int64_t(drape.scene.model.constraints.size() + solver.contacts().size()));
}
BENCHMARK(BM_DrapeSweep)->Name("collision/reference/sweep/drape")
    ->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

}  // namespace
