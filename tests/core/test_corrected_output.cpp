// The redirected output of the batched kernels (ParticleArrays::corrected_*, what the solver's
// Jacobi sweeps use): the corrected position a kernel stores for a slot is bitwise the one it
// would have scattered into the particle arrays, the particle arrays stay untouched, and
// static particles' slots are not written. One family per kernel loop that writes positions:
// the shared loop (distance, volume), FEM tetra, strain triangle, and shape matching.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include <tessera/core/distance_constraints.hpp>
#include <tessera/core/fem_tetra_constraints.hpp>
#include <tessera/core/shape_matching_constraints.hpp>
#include <tessera/core/strain_triangle_constraints.hpp>
#include <tessera/core/volume_constraints.hpp>

#include "batch_test_support.hpp"

namespace tessera {
namespace corrected_output_tests {

using test::Random;

constexpr std::size_t kCount = 101;  // not a multiple of any lane count

/// `slots` slots per constraint, particles numbered slot-major or by a random permutation; a
/// tenth of the particles static.
struct Scene {
  std::vector<Vector3r> positions;
  std::vector<Vector3r> rest;
  std::vector<Real> inverse_masses;
  std::vector<ParticleIndex> indices;  // constraint-major
};

Scene make_scene(Random& random, std::size_t slots) {
  Scene scene;
  const std::size_t n = kCount * slots;
  std::vector<ParticleIndex> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = ParticleIndex(i);
  for (std::size_t i = n; i > 1; --i) std::swap(order[i - 1], order[std::size_t(random.integer(0, int(i) - 1))]);
  scene.positions.resize(n);
  scene.rest.resize(n);
  scene.inverse_masses.resize(n);
  for (std::size_t c = 0; c < kCount; ++c) {
    const Vector3r centre = random.vector(-10, 10);
    for (std::size_t k = 0; k < slots; ++k) {
      const ParticleIndex p = order[c * slots + k];
      scene.indices.push_back(p);
      // A well-shaped rest stencil (unit axes plus noise), deformed now.
      Vector3r offset = Vector3r::Zero();
      if (k > 0) offset[int(k - 1) % 3] = 1;
      scene.rest[p] = centre + offset + random.vector(Real(-0.1), Real(0.1));
      scene.positions[p] = scene.rest[p] + random.vector(Real(-0.3), Real(0.3));
      scene.inverse_masses[p] = random.uniform(0, 1) < Real(0.1) ? 0 : random.uniform(Real(0.5), 2);
    }
  }
  return scene;
}

/// Projects in place and redirected, then compares slot by slot. slot_particle(k, c) is the
/// particle whose corrected position lands at corrected[k * stride + c].
template <class Batch, class Project, class SlotParticle>
void expect_redirect_matches(const Scene& scene, Batch batch, std::size_t slots,
                             std::size_t stride, Project&& project, SlotParticle&& slot_particle,
                             const ProjectionSettings& settings, std::size_t per_slot = kCount) {
  test::for_each_simd_target([&](const std::string&) {
    Batch in_place_batch = batch, redirected_batch = batch;
    ParticleState in_place(scene.positions, scene.inverse_masses);
    ParticleState redirected = in_place;
    const ParticleState before = in_place;
    project(ParticleArrays::of(in_place), in_place_batch, 0, kCount, settings);
    const Real sentinel = std::numeric_limits<Real>::quiet_NaN();
    std::vector<Real> x(std::max(slots * stride, per_slot) + kMaxLanes, sentinel), y = x, z = x;
    ParticleArrays arrays = ParticleArrays::of(redirected);
    arrays.corrected_x = x.data();
    arrays.corrected_y = y.data();
    arrays.corrected_z = z.data();
    arrays.corrected_stride = stride;
    project(arrays, redirected_batch, 0, kCount, settings);
    EXPECT_TRUE(test::same_bits(redirected, before)) << "the particle arrays were written";
    for (std::size_t c = 0; c < per_slot; ++c)
      for (std::size_t k = 0; k < slots; ++k) {
        const ParticleIndex p = slot_particle(k, c);
        const std::size_t at = k * stride + c;
        if (scene.inverse_masses[p] == 0) {
          EXPECT_TRUE(std::isnan(x[at])) << "static slot written, constraint " << c;
          continue;
        }
        const Vector3r stored(x[at], y[at], z[at]);
        EXPECT_EQ(std::memcmp(stored.data(), in_place.position(p).data(), sizeof(Vector3r)), 0)
            << "constraint " << c << " slot " << k;
      }
  });
}

template <int N>
auto slot_major(const Scene& scene) {
  return [&scene](std::size_t k, std::size_t c) { return scene.indices[c * N + k]; };
}

TEST(CorrectedOutput, DistanceKernelStoresWhatItWouldScatter) {
  Random random(1);
  const Scene scene = make_scene(random, 2);
  const auto batch = make_distance_constraints({scene.indices, scene.rest, Real(0.9), Real(1e-4)});
  for (const auto semantics : {ConstraintSemantics::stiffness, ConstraintSemantics::compliance})
    expect_redirect_matches(scene, batch, 2, padded_size(kCount), project_distance_constraints,
                            slot_major<2>(scene), {semantics, Real(0.01)});
}

TEST(CorrectedOutput, VolumeKernelStoresWhatItWouldScatter) {
  Random random(2);
  const Scene scene = make_scene(random, 4);
  const auto batch = make_volume_constraints({scene.indices, scene.rest, Real(1), Real(1e-5)});
  expect_redirect_matches(scene, batch, 4, padded_size(kCount) + 3, project_volume_constraints,
                          slot_major<4>(scene), {ConstraintSemantics::compliance, Real(0.01)});
}

TEST(CorrectedOutput, FEMTetraKernelStoresWhatItWouldScatter) {
  Random random(3);
  const Scene scene = make_scene(random, 4);
  const auto batch = make_fem_tetra_constraints({scene.indices, scene.rest, Real(1e3), Real(0.3), true});
  for (const auto semantics : {ConstraintSemantics::stiffness, ConstraintSemantics::compliance})
    expect_redirect_matches(scene, batch, 4, padded_size(kCount), project_fem_tetra_constraints,
                            slot_major<4>(scene), {semantics, Real(0.01)});
}

TEST(CorrectedOutput, StrainTriangleKernelStoresWhatItWouldScatter) {
  Random random(4);
  const Scene scene = make_scene(random, 3);
  const auto batch = make_strain_triangle_constraints({scene.indices, scene.rest});
  expect_redirect_matches(scene, batch, 3, padded_size(kCount),
                          project_strain_triangle_constraints, slot_major<3>(scene),
                          ProjectionSettings{});
}

TEST(CorrectedOutput, ShapeMatchingStoresEachEntryOfItsCluster) {
  Random random(5);
  const Scene scene = make_scene(random, 5);  // clusters of 5
  std::vector<std::uint32_t> offsets(kCount + 1);
  for (std::size_t c = 0; c <= kCount; ++c) offsets[c] = std::uint32_t(5 * c);
  const auto batch = make_shape_matching_constraints(
      {offsets, scene.indices, scene.rest, scene.inverse_masses, Real(0.8), false});
  // Entry e = 5c + k holds the corrected position of the cluster's k-th particle; with
  // stride 0 the "slot" index k·0 + e is the entry.
  expect_redirect_matches(
      scene, batch, 1, 0,
      [](ParticleArrays p, ShapeMatchingConstraints& b, std::size_t begin, std::size_t end,
         const ProjectionSettings&) { project_shape_matching_constraints(p, b, begin, end); },
      [&](std::size_t, std::size_t e) { return scene.indices[e]; }, ProjectionSettings{},
      5 * kCount);
}

}  // namespace corrected_output_tests
}  // namespace tessera
