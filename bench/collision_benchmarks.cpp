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
//   collision/self_refine/folded128/threads:<T>   SelfCollision::refine of the substep after
//       a detection, at the positions its motion reaches: the per-substep cost between
//       detections (the candidates tested again, no grid); counter candidates
//   collision/broad_vertices/folded128/threads:<T>    the grid's candidate pairs of the vertices
//       as points within 2r (r = thickness + margin): build + self_pairs
//   collision/broad_triangles/folded128/threads:<T>   the same for the triangles' boxes grown by
//       r/2: build + self_pairs
//   collision/self_intersections/folded128/threads:<T>   count_self_intersections
//   collision/reference/distance_sweep/cloth128/threads:<T>   one gs projection sweep of the
//       128² distance cloth: the yardstick of the detection's budget (about two sweeps)
//   collision/stage_detect/pile/threads:<T>   CollisionStage::detect on the pile scene
//       (`tessera run pile`, 8 FEM blocks, 1,152 particles) from frame 40, blocks lying on
//       each other and the ground, its 64 substeps replayed as the drape's below: collider
//       contacts, self-collision pairs, their split into particle–tet contacts, the
//       batches; counters particle_tet, collider, edge_edge
//   collision/reference/sweep/pile/threads:<T>   one gs sweep of the pile's FEM tetrahedra
//       and that substep's contacts, the yardstick for the pile
//   collision/stage_detect/drape/threads:<T>   CollisionStage::detect on the drape scene
//       (`tessera run drape`, 128² cloth, self-collision, sphere and ground) from frame 60,
//       the cloth in folds on the sphere: the 64 substeps that follow, recorded, replayed in
//       order, one per iteration, as a run meets them (a grid build at the end of each
//       build's horizon, about every 4th substep here, the others filtering its candidates
//       or re-boxing what strayed from its path; the replay's wrap-around is one more build
//       in 64); the budget is two of the sweeps below
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
    settings.horizon = 1;  // refine() then stays at the substep after the detection
    collision.detect(cloth.state, settings, contacts);
    ParticleState next = cloth.state;  // one more substep of the same motion
    for (std::size_t i = 0; i < next.size(); ++i) {
      const Real step = next.y[i] - next.previous_y[i];
      next.previous_y[i] = next.y[i];
      next.y[i] += step;
    }
    for (auto _ : state) collision.refine(next, settings, contacts);
    state.counters["candidates"] = double(collision.candidate_count());
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

/// A scene of the tool run some frames with its own colliders (planes and spheres), friction,
/// thickness, self-collision and substeps; its state kept for detection and for the sweep.
struct SettledScene {
  io::Scene scene;
  CollisionSettings collisions;
  SolverSettings settings;
  ParticleState state;  // user numbering, previous = one substep back

  SettledScene(const char* spec, int frames) : scene(io::build_scene(io::parse_scene_spec(spec))) {
    const io::CollisionDescription& described = scene.description.collisions;
    for (const io::ColliderDescription& collider : described.colliders)
      if (collider.shape == io::ColliderShape::sphere)
        collisions.colliders.push_back(SphereCollider{collider.centre, collider.radius});
      else
        collisions.colliders.push_back(PlaneCollider{collider.normal, collider.offset});
    collisions.thickness = described.thickness;
    collisions.static_friction = described.static_friction;
    collisions.dynamic_friction = described.dynamic_friction;
    collisions.self_collision = described.self_collision;
    settings.threads = 2;
    settings.substeps = scene.description.simulation.substeps;
    settings.iterations = scene.description.simulation.iterations;
    settings.report_residuals = false;
    Solver solver = solver_at(settings);
    for (int frame = 0; frame < frames; ++frame) solver.step();
    const std::vector<Vector3r> x = solver.positions(), v = solver.velocities();
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
  /// The `count` substeps that follow the settled state, each as a detection meets it: the
  /// start of the substep as previous, its end as the positions (the solver's own
  /// prediction differs by the substep's corrections).
  std::vector<ParticleState> substeps_after(std::size_t count) const {
    SolverSettings one = settings;
    one.time_step = substep();
    one.substeps = 1;
    Solver solver = solver_at(one);
    for (std::size_t i = 0; i < state.size(); ++i) {
      solver.set_position(ParticleIndex(i), state.position(i));
      solver.set_velocity(ParticleIndex(i), state.velocity(i));
    }
    std::vector<ParticleState> sequence;
    std::vector<Vector3r> start = solver.positions();
    const auto masses = scene.model.particles.inverse_mass.begin();
    for (std::size_t k = 0; k < count; ++k) {
      solver.step();
      const std::vector<Vector3r> end = solver.positions();
      ParticleState substep_state(end, std::vector<Real>(masses, masses + std::ptrdiff_t(end.size())));
      for (std::size_t i = 0; i < end.size(); ++i)
        substep_state.previous_x[i] = start[i].x(), substep_state.previous_y[i] = start[i].y(),
        substep_state.previous_z[i] = start[i].z();
      sequence.push_back(std::move(substep_state));
      start = end;
    }
    return sequence;
  }
  /// A solver of the scene with its collisions, at the start or at the settled state.
  Solver solver_at(const SolverSettings& with) const {
    Solver solver = test::make_solver(scene.model, with, "stencil");
    solver.set_collisions(collisions, scene.surface_triangles, scene.mesh.tetrahedra);
    return solver;
  }
};

/// The pile run to frame 40 (blocks resting on each other), the drape to frame 60 (the cloth
/// lying on the sphere in folds).
const SettledScene& settled_pile() {
  static const SettledScene pile("pile", 40);
  return pile;
}
const SettledScene& settled_drape() {
  static const SettledScene drape("drape", 60);
  return drape;
}

/// The 64 substeps after the settled frames.
const std::vector<ParticleState>& drape_substeps() {
  static const std::vector<ParticleState> sequence = settled_drape().substeps_after(64);
  return sequence;
}
const std::vector<ParticleState>& pile_substeps() {
  static const std::vector<ParticleState> sequence = settled_pile().substeps_after(64);
  return sequence;
}

/// One substep's detection as a run makes it: a stage called once per iteration on the
/// states of `sequence` in turn, so the self-collision grids are built every
/// self_collision_interval-th call at the latest and the other calls filter their
/// candidates or re-box.
void run_stage_detect(benchmark::State& state, const SettledScene& settled,
                      const std::vector<ParticleState>& sequence) {
  in_arena(state, [&] {
    CollisionStage stage(settled.collisions,
                         std::vector<std::uint32_t>(settled.scene.surface_triangles.begin(),
                                                    settled.scene.surface_triangles.end()),
                         settled.state.size(), settled.scene.mesh.tetrahedra);
    ConstraintSets contacts;
    std::size_t next = 0;
    for (auto _ : state) {
      const ParticleState& at = sequence[next++ % sequence.size()];
      stage.detect(at, settled.substep(), Real(9.81), contacts);
    }
    state.counters["particle_tet"] = double(contacts.particle_tet_contact.size());
    state.counters["collider"] = double(contacts.collider_contact.size());
    state.counters["triangle_point"] = double(contacts.triangle_point_distance.size());
    state.counters["edge_edge"] = double(contacts.edge_edge_distance.size());
  });
}

/// One gs sweep of the scene's constraints and that substep's contacts.
void run_sweep(benchmark::State& state, const SettledScene& settled) {
  SolverSettings settings = settled.settings;
  settings.threads = std::size_t(state.range(0));
  settings.check_finite = false;
  Solver solver = settled.solver_at(settings);
  for (std::size_t i = 0; i < settled.state.size(); ++i) {
    solver.set_position(ParticleIndex(i), settled.state.position(i));
    solver.set_velocity(ParticleIndex(i), settled.state.velocity(i));
  }
  solver.step();  // a substep's contacts in place
  for (auto _ : state) solver.project(1, settled.substep());
  state.SetItemsProcessed(state.iterations() * std::int64_t(settled.scene.model.constraints.size() +
                                                            solver.contacts().size()));
}

void BM_PileDetect(benchmark::State& state) {
  run_stage_detect(state, settled_pile(), pile_substeps());
}
BENCHMARK(BM_PileDetect)->Name("collision/stage_detect/pile")
    ->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

void BM_PileSweep(benchmark::State& state) { run_sweep(state, settled_pile()); }
BENCHMARK(BM_PileSweep)->Name("collision/reference/sweep/pile")
    ->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

void BM_DrapeDetect(benchmark::State& state) {
  run_stage_detect(state, settled_drape(), drape_substeps());
}
BENCHMARK(BM_DrapeDetect)->Name("collision/stage_detect/drape")
    ->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

void BM_DrapeSweep(benchmark::State& state) { run_sweep(state, settled_drape()); }
BENCHMARK(BM_DrapeSweep)->Name("collision/reference/sweep/drape")
    ->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

}  // namespace
