// A step in steady state allocates nothing from the C++ heap: an embedding simulator calls
// step() thousands of times a second, and a malloc per step costs time, contends between
// threads and fragments memory (a long soak once grew by a new malloc arena). This binary
// replaces the global operator new with a counting one; after two warm-up steps (buffers
// sized, the phase region made), further steps must not call it, in every mode, on 1 and 2
// threads, with residual reports and the finite and divergence checks on. With a collision
// stage the contacts are remade every substep into the same buffers: once a scene has
// settled (its contact counts no longer reach new highs), its steps allocate nothing either,
// for cloth on colliders and against itself and for solids on solids, with either contact
// scheduling.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include <tessera/io/generators.hpp>
#include <tessera/io/scenes.hpp>
#include <tessera/parallel/solver.hpp>

#include "scenes.hpp"
#include "test_support.hpp"

namespace {
std::atomic<std::size_t> g_allocations{0};
}  // namespace

// These operators are the program's allocator: g++ cannot see that the free() in a delete
// below pairs with the malloc() of a new above, and warns where it inlines them.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif

void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void* operator new(std::size_t size, std::align_val_t alignment) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  const std::size_t a = std::size_t(alignment);
  if (void* p = std::aligned_alloc(a, (size + a - 1) / a * a)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size, std::align_val_t alignment) {
  return operator new(size, alignment);
}
// The nothrow forms too (std::stable_sort's buffer is one): under AddressSanitizer, whose
// runtime defines them, a block from its nothrow new freed by the free() below would be an
// alloc-dealloc mismatch.
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept {
  return operator new(size, tag);
}
void* operator new(std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  const std::size_t a = std::size_t(alignment);
  return std::aligned_alloc(a, (size + a - 1) / a * a);
}
void* operator new[](std::size_t size, std::align_val_t alignment,
                     const std::nothrow_t& tag) noexcept {
  return operator new(size, alignment, tag);
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }

namespace tessera {
namespace {

/// Operator-new calls of five steps after two warm-up steps.
std::size_t allocations_of_steady_steps(const Model& model, const Colouring& colouring,
                                        const SolverSettings& settings) {
  Solver solver(model, colouring, settings);
  solver.step();
  solver.step();
  const std::size_t before = g_allocations.load();
  for (int step = 0; step < 5; ++step) solver.step();
  return g_allocations.load() - before;
}

SolverSettings settings_of(SolverMode mode, std::size_t threads) {
  SolverSettings settings;
  settings.mode = mode;
  settings.threads = threads;
  settings.substeps = 4;
  settings.iterations = 2;
  return settings;
}

TEST(StepAllocations, AStepInSteadyStateAllocatesNothing) {
  const Model cloth = test::cloth_model(24, 20);
  const Colouring colouring = test::colour_model(cloth, "greedy");
  for (const SolverMode mode :
       {SolverMode::gs, SolverMode::jacobi, SolverMode::hybrid, SolverMode::sequential})
    for (const std::size_t threads : {std::size_t(1), std::size_t(2)})
      for (const ParticleLayout layout : {ParticleLayout::interleaved, ParticleLayout::separate})
        for (const bool residuals : {false, true}) {
          SolverSettings settings = settings_of(mode, threads);
          settings.particle_layout = layout;
          settings.report_residuals = residuals;  // and with them the divergence check
          EXPECT_EQ(allocations_of_steady_steps(cloth, colouring, settings), 0u)
              << solver_mode_name(mode) << ", " << threads << " threads, "
              << particle_layout_name(layout) << ", residuals " << residuals;
        }
}

TEST(StepAllocations, PartMajorSweepsAndChebyshevAllocateNothingPerStep) {
  const Model cloth = test::cloth_model(24, 20);
  ColouringOptions options;
  options.particles_per_part = 128;
  const Colouring parts = test::colour_model(cloth, "metis", options);
  for (const std::size_t threads : {std::size_t(1), std::size_t(2)}) {
    SolverSettings part_major = settings_of(SolverMode::gs, threads);
    part_major.sweep_order = SweepOrder::part_major;
    EXPECT_EQ(allocations_of_steady_steps(cloth, parts, part_major), 0u)
        << "part-major, " << threads << " threads";
    for (const bool chebyshev : {false, true}) {
      SolverSettings jacobi = settings_of(SolverMode::jacobi, threads);
      jacobi.chebyshev = chebyshev;
      jacobi.iterations = 6;
      EXPECT_EQ(allocations_of_steady_steps(cloth, test::colour_model(cloth, "greedy"), jacobi),
                0u)
          << "jacobi, chebyshev " << chebyshev << ", " << threads << " threads";
    }
  }
}

/// A model with its collision stage's input.
struct CollisionScene {
  Model model;
  std::vector<std::uint32_t> triangles, tetrahedra;
  CollisionSettings collisions;
};

/// A free 16 × 16 cloth 0.6 m wide dropped 5 cm onto a sphere and the ground, with
/// self-collision: collider contacts, and vertex–triangle and edge–edge contacts where it
/// folds around the sphere.
CollisionScene draped_cloth() {
  CollisionScene scene;
  const std::size_t n = 16;
  io::ClothGrid grid = io::make_cloth_grid(n, n, Real(0.6) / Real(n - 1));
  for (Vector3r& p : grid.positions) p = Vector3r(p.x() - Real(0.3), Real(0.25), p.y() - Real(0.3));
  scene.model.particles =
      ParticleState(grid.positions, std::vector<Real>(grid.vertex_count(), Real(1)));
  scene.model.constraints.distance =
      make_distance_constraints({grid.edge_indices, grid.positions, Real(1), Real(0)});
  scene.model.constraints.dihedral = make_dihedral_constraints(
      {grid.bending_indices, grid.positions, Real(1), Real(1e-3)});
  scene.triangles.assign(grid.triangle_indices.begin(), grid.triangle_indices.end());
  scene.collisions.colliders = {SphereCollider{Vector3r(0, Real(0.1), 0), Real(0.1)},
                                PlaneCollider{Vector3r(0, 1, 0), 0}};
  scene.collisions.thickness = Real(0.005);
  scene.collisions.self_collision = true;
  return scene;
}

/// A tetrahedral block dropped 1 cm onto another resting on the ground: particle–tet
/// contacts between the solids, collider contacts under both.
CollisionScene stacked_blocks() {
  CollisionScene scene;
  const io::TetrahedralBar block = io::make_tetrahedral_bar(3, 2, 3, Real(0.04));
  std::vector<Vector3r> positions;
  for (const Vector3r& rest : block.positions) positions.push_back(rest + Vector3r(0, Real(0.004), 0));
  for (const Vector3r& rest : block.positions)
    positions.push_back(rest + Vector3r(Real(0.02), Real(0.004 + 0.08 + 0.004 + 0.01), Real(0.02)));
  scene.tetrahedra.assign(block.tetrahedron_indices.begin(), block.tetrahedron_indices.end());
  for (const auto v : block.tetrahedron_indices)
    scene.tetrahedra.push_back(std::uint32_t(block.positions.size()) + v);
  scene.model = io::make_solid(positions, scene.tetrahedra, {});
  scene.triangles = io::boundary_triangles(scene.tetrahedra);
  scene.collisions.colliders = {PlaneCollider{Vector3r(0, 1, 0), 0}};
  scene.collisions.thickness = Real(0.004);
  scene.collisions.self_collision = true;
  return scene;
}

/// Operator-new calls of ten steps after `settle` steps, and the contacts of the last.
std::pair<std::size_t, std::size_t> allocations_of_settled_steps(const CollisionScene& scene,
                                                                 const SolverSettings& settings,
                                                                 int settle) {
  Solver solver = test::make_solver(scene.model, settings);
  solver.set_collisions(scene.collisions, scene.triangles, scene.tetrahedra);
  for (int step = 0; step < settle; ++step) solver.step();
  const std::size_t before = g_allocations.load();
  for (int step = 0; step < 10; ++step) solver.step();
  return {g_allocations.load() - before, solver.contacts().size()};
}

TEST(StepAllocations, ASettledStepWithCollisionsAllocatesNothing) {
  const CollisionScene cloth = draped_cloth(), blocks = stacked_blocks();
  struct Case {
    SolverMode mode;
    ContactScheduling scheduling;
    std::size_t threads;
  };
  for (const Case c : {Case{SolverMode::gs, ContactScheduling::coloured, 1},
                       Case{SolverMode::gs, ContactScheduling::coloured, 2},
                       Case{SolverMode::gs, ContactScheduling::jacobi, 2},
                       Case{SolverMode::hybrid, ContactScheduling::coloured, 2},
                       Case{SolverMode::jacobi, ContactScheduling::jacobi, 2},
                       Case{SolverMode::sequential, ContactScheduling::coloured, 1}}) {
    SolverSettings settings = settings_of(c.mode, c.threads);
    settings.substeps = 8;
    settings.iterations = 2;
    settings.contact_scheduling = c.scheduling;
    const auto [cloth_allocations, cloth_contacts] =
        allocations_of_settled_steps(cloth, settings, 60);
    const auto [block_allocations, block_contacts] =
        allocations_of_settled_steps(blocks, settings, 80);
    const std::string name = std::string(solver_mode_name(c.mode)) + ", " +
                             (c.scheduling == ContactScheduling::coloured ? "coloured" : "jacobi") +
                             " contacts, " + std::to_string(c.threads) + " threads";
    EXPECT_GT(cloth_contacts, 0u) << name;
    EXPECT_GT(block_contacts, 0u) << name;
    EXPECT_EQ(cloth_allocations, 0u) << "cloth, " << name;
    EXPECT_EQ(block_allocations, 0u) << "blocks, " << name;
  }
}

}  // namespace
}  // namespace tessera
