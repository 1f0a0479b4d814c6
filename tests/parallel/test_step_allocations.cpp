// A step in steady state allocates nothing from the C++ heap: an embedding simulator calls
// step() thousands of times a second, and a malloc per step costs time, contends between
// threads and fragments memory (a long soak once grew by a new malloc arena). This binary
// replaces the global operator new with a counting one; after two warm-up steps (buffers
// sized, the phase region made), further steps must not call it, in every mode, on 1 and 2
// threads, with residual reports and the finite and divergence checks on.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

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

}  // namespace
}  // namespace tessera
