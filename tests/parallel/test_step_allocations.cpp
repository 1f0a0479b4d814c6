// A step in steady state allocates nothing from the C++ heap: an embedding simulator calls
// step() thousands of times a second, and a malloc per step costs time, contends between
// threads and fragments memory (a long soak once grew by a new malloc arena). This binary
// replaces the global operator new with a counting one; after two warm-up steps (buffers
// sized, the phase region made), further steps must not call it, in every mode, on 1 and 2
// threads, with residual reports and the finite and divergence checks on. With a collision
// stage the contacts are remade every substep into the same buffers: once a scene has
// settled (its contact counts no longer reach new highs), its steps allocate nothing either
// (ten steps in a row), for cloth on colliders and against itself and for solids on solids,
// with either contact scheduling; before, a substep allocated some 500 times.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdio>
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

/// Two 12 × 12 sheets 0.3 m wide, one on the ground and one 2 cm above it, shifted by half
/// a cell, with self-collision and a sphere under a corner: collider contacts, and the upper
/// sheet's vertex–triangle and edge–edge contacts with the lower once it has landed on it.
CollisionScene stacked_sheets() {
  CollisionScene scene;
  const std::size_t n = 12;
  const Real h = Real(0.3) / Real(n - 1);
  const io::ClothGrid grid = io::make_cloth_grid(n, n, h);
  std::vector<Vector3r> positions;
  std::vector<ParticleIndex> edges, bending;
  for (int layer = 0; layer < 2; ++layer) {
    const std::uint32_t first = std::uint32_t(positions.size());
    for (const Vector3r& p : grid.positions)
      positions.push_back(layer == 0 ? Vector3r(p.x(), Real(0.005), p.y())
                                     : Vector3r(p.x() + h / 2, Real(0.025), p.y() + h / 2));
    for (const auto v : grid.triangle_indices) scene.triangles.push_back(first + v);
    for (const auto v : grid.edge_indices) edges.push_back(first + v);
    for (const auto v : grid.bending_indices) bending.push_back(first + v);
  }
  scene.model.particles =
      ParticleState(positions, std::vector<Real>(positions.size(), Real(1)));
  scene.model.constraints.distance =
      make_distance_constraints({edges, positions, Real(1), Real(0)});
  scene.model.constraints.dihedral =
      make_dihedral_constraints({bending, positions, Real(1), Real(1e-3)});
  scene.collisions.colliders = {PlaneCollider{Vector3r(0, 1, 0), 0},
                                SphereCollider{Vector3r(0, 0, 0), Real(0.05)}};
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

/// Steps until ten steps in a row have called operator new zero times (at most
/// `most_steps`; 0 if that never happens), and the contacts of the last step. A step with
/// collisions allocates while a contact count still reaches new highs (the buffers grow to
/// it), so the window is looked for rather than placed at a fixed step: where a scene settles
/// differs a little between SIMD targets, precisions and builds.
std::pair<int, std::array<std::size_t, kConstraintFamilyCount>> steps_until_ten_without_allocation(const CollisionScene& scene,
                                                               const SolverSettings& settings,
                                                               int most_steps) {
  Solver solver = test::make_solver(scene.model, settings);
  solver.set_collisions(scene.collisions, scene.triangles, scene.tetrahedra);
  int quiet = 0;
  for (int step = 1; step <= most_steps; ++step) {
    const std::size_t before = g_allocations.load();
    solver.step();
    quiet = g_allocations.load() == before ? quiet + 1 : 0;
    if (quiet == 10) return {step, solver.contacts().sizes()};
  }
  return {0, solver.contacts().sizes()};
}

TEST(StepAllocations, ASettledStepWithCollisionsAllocatesNothing) {
  const CollisionScene cloth = stacked_sheets(), blocks = stacked_blocks();
  // Mode jacobi and sequential, and gs with ContactScheduling::jacobi, rebuild the contacts'
  // Jacobi set every substep; gs and hybrid colour them. Mode jacobi sweeps the cloth only:
  // with 2 Jacobi iterations per substep the upper block does not stay on the lower.
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
                       Case{SolverMode::sequential, ContactScheduling::jacobi, 1}}) {
    SolverSettings settings = settings_of(c.mode, c.threads);
    settings.substeps = 8;
    settings.iterations = 2;
    settings.contact_scheduling = c.scheduling;
    const bool with_blocks = c.mode != SolverMode::jacobi;
    const auto [cloth_quiet, cloth_contacts] =
        steps_until_ten_without_allocation(cloth, settings, 150);
    const auto [block_quiet, block_contacts] =
        with_blocks ? steps_until_ten_without_allocation(blocks, settings, 150)
                    : std::pair{1, std::array<std::size_t, kConstraintFamilyCount>{}};
    const std::string name = std::string(solver_mode_name(c.mode)) + ", " +
                             (c.scheduling == ContactScheduling::coloured ? "coloured" : "jacobi") +
                             " contact scheduling, " + std::to_string(c.threads) + " threads";
    // Measured (Zen 3, release): the quiet steps start by step 65 (sheets) and 20 (blocks);
    // 150 leaves room.
    EXPECT_GT(cloth_quiet, 0) << "cloth, " << name;
    EXPECT_GT(block_quiet, 0) << "blocks, " << name;
    std::printf("%s: quiet from step %d (sheets), %d (blocks)\n", name.c_str(),
                cloth_quiet - 9, with_blocks ? block_quiet - 9 : 0);

    // With every kind of contact in place (not a scene that went quiet by losing them).
    const auto of = [](const auto& sizes, ConstraintFamily family) {
      return sizes[std::size_t(family)];
    };
    EXPECT_GT(of(cloth_contacts, ConstraintFamily::collider_contact), 0u) << name;
    EXPECT_GT(of(cloth_contacts, ConstraintFamily::triangle_point_distance) +
                  of(cloth_contacts, ConstraintFamily::edge_edge_distance),
              0u)
        << name;
    if (!with_blocks) continue;
    EXPECT_GT(of(block_contacts, ConstraintFamily::collider_contact), 0u) << name;
    EXPECT_GT(of(block_contacts, ConstraintFamily::particle_tet_contact), 0u) << name;
  }
}

}  // namespace
}  // namespace tessera
