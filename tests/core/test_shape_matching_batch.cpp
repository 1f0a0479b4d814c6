// The batched shape-matching kernel against the scalar API (whose rotation comes from Eigen's
// SVD, the batch's from a branch-free polar iteration) on every SIMD target the machine has:
// clusters of varying size, rigid and with stretch, large rotations, mirrored and collapsed
// clusters, static particles; plus validation of the CSR input.
#include <tessera/core/error.hpp>
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/shape_matching_constraints.hpp>

#include "batch_test_support.hpp"

namespace tessera {
namespace shape_matching_batch_tests {

using test::Random;
using PBD = PositionBasedDynamics;

/// Clusters whose movable particles are all distinct, with some entries on static particles
/// shared between clusters; current positions are a random rigid motion of the rest shape
/// plus noise, sometimes mirrored or collapsed onto a line.
struct ClusterScene {
  std::vector<Vector3r> rest, current;
  std::vector<Real> inverse_masses;
  std::vector<std::uint32_t> offsets = {0};
  std::vector<ParticleIndex> particles;

  std::size_t count() const { return offsets.size() - 1; }
};

ClusterScene make_scene(Random& random, std::size_t count, bool allow_stretch) {
  constexpr std::size_t kSharedStatic = 4;
  ClusterScene scene;
  std::vector<std::size_t> sizes(count);
  std::size_t own = 0;
  for (auto& size : sizes) own += size = std::size_t(random.integer(4, 30));
  const std::size_t particle_count = own + kSharedStatic;
  std::vector<ParticleIndex> permutation(particle_count);
  std::iota(permutation.begin(), permutation.end(), ParticleIndex(0));
  for (std::size_t i = particle_count - 1; i > 0; --i)
    std::swap(permutation[i], permutation[std::size_t(random.integer(0, int(i)))]);
  scene.rest.assign(particle_count, Vector3r::Zero());
  scene.current.assign(particle_count, Vector3r::Zero());
  scene.inverse_masses.assign(particle_count, Real(0));
  for (std::size_t s = 0; s < kSharedStatic; ++s) {
    const ParticleIndex p = permutation[own + s];
    scene.rest[p] = scene.current[p] = random.vector(-3, 3);
  }
  std::size_t next = 0;
  for (std::size_t c = 0; c < count; ++c) {
    // Sometimes one entry is a shared static particle: the cluster is placed around it and
    // moved rigidly about it (so it anchors the goal without making A_pq ill-conditioned).
    const bool with_shared = random.uniform(0, 1) < Real(0.2);
    const ParticleIndex shared =
        permutation[own + std::size_t(random.integer(0, int(kSharedStatic) - 1))];
    const std::size_t shared_slot = std::size_t(random.integer(0, int(sizes[c]) - 1));
    const Vector3r pivot = with_shared ? scene.rest[shared] : random.vector(-5, 5);
    const Vector3r centre = pivot + (with_shared ? random.vector(Real(-0.5), Real(0.5))
                                                 : Vector3r::Zero());
    const Matrix3r rotation = random.rotation();
    const Vector3r shift = with_shared ? Vector3r::Zero() : random.vector(-1, 1);
    const Real kind = random.uniform(0, 1);
    const Vector3r line = random.unit_vector();
    for (std::size_t k = 0; k < sizes[c]; ++k) {
      if (with_shared && k == shared_slot) {
        scene.particles.push_back(shared);
        continue;
      }
      const ParticleIndex p = permutation[next++];
      const Vector3r x0 = centre + random.vector(-1, 1);
      Vector3r x = rotation * (x0 - pivot) + pivot + shift + Real(0.1) * random.vector();
      if (kind < Real(0.1)) x.z() = 2 * centre.z() - x.z();  // mirrored
      if (kind > Real(0.95) && !allow_stretch)
        x = centre + random.uniform(-1, 1) * line;  // on one line: rotation undetermined
      scene.rest[p] = x0;
      scene.current[p] = x;
      scene.inverse_masses[p] = random.uniform(0, 1) < Real(0.1) ? 0 : random.inverse_mass();
      scene.particles.push_back(p);
    }
    scene.offsets.push_back(std::uint32_t(scene.particles.size()));
  }
  // Own particles left over (a shared static took their place) are in no cluster.
  return scene;
}

ShapeMatchingConstraints build(const ClusterScene& scene, bool allow_stretch, Real stiffness) {
  return make_shape_matching_constraints({scene.offsets, scene.particles, scene.rest,
                                          scene.inverse_masses, stiffness, allow_stretch});
}

/// The scalar API applied cluster by cluster to `x` (a copy of the particles).
void scalar_project(const ClusterScene& scene, const ShapeMatchingConstraints& constraints,
                    std::size_t begin, std::size_t end, std::vector<Vector3r>& x,
                    std::vector<bool>* solved = nullptr) {
  for (std::size_t c = begin; c < end; ++c) {
    std::vector<Vector3r> x0, xc, corr;
    std::vector<Real> w;
    for (std::size_t e = scene.offsets[c]; e < scene.offsets[c + 1]; ++e) {
      x0.push_back(scene.rest[scene.particles[e]]);
      xc.push_back(x[scene.particles[e]]);
      w.push_back(scene.inverse_masses[scene.particles[e]]);
    }
    const int n = int(x0.size());
    corr.resize(x0.size());
    Vector3r rest_cm;
    PBD::init_ShapeMatchingConstraint(x0.data(), w.data(), n, rest_cm);
    const bool ok = PBD::solve_ShapeMatchingConstraint(
        x0.data(), xc.data(), w.data(), n, rest_cm, constraints.stiffness[c],
        constraints.allow_stretch, corr.data());
    if (solved != nullptr) solved->push_back(ok);
    for (int k = 0; k < n; ++k)
      if (w[std::size_t(k)] > 0)
        x[scene.particles[scene.offsets[c] + std::size_t(k)]] += corr[std::size_t(k)];
  }
}

TEST(ShapeMatchingBatch, MatchesScalarApiOnEveryTarget) {
  test::for_each_simd_target([](const std::string&) {
    std::size_t refused = 0, matched = 0;
    for (const bool allow_stretch : {false, true}) {
      for (unsigned seed = 1; seed <= 5; ++seed) {
        Random random(seed + (allow_stretch ? 100 : 0));
        const std::size_t count = std::size_t(random.integer(1, 120));
        const ClusterScene scene = make_scene(random, count, allow_stretch);
        ShapeMatchingConstraints constraints = build(scene, allow_stretch, Real(0.7));
        for (std::size_t c = 0; c < count; ++c)
          constraints.stiffness[c] = random.uniform(Real(0.2), 1);
        const auto [begin, end] = test::random_range(random, count);
        std::vector<Vector3r> expected = scene.current;
        std::vector<bool> solved;
        scalar_project(scene, constraints, begin, end, expected, &solved);
        for (const bool ok : solved) ++(ok ? matched : refused);
        ParticleState state(scene.current, scene.inverse_masses);
        project_shape_matching_constraints(ParticleArrays::of(state), constraints, begin, end);
        EXPECT_TRUE(test::positions_match(state, expected, 10)) << "stretch " << allow_stretch;
        // Clusters outside the range, and refused ones, are untouched.
        for (std::size_t c = 0; c < count; ++c) {
          const bool moved = c >= begin && c < end && solved[c - begin];
          if (moved) continue;
          for (std::size_t e = scene.offsets[c]; e < scene.offsets[c + 1]; ++e)
            EXPECT_EQ(state.position(scene.particles[e]), scene.current[scene.particles[e]]);
        }
      }
    }
    // Both kinds occurred: collapsed clusters refused by the scalar API, the rest matched.
    EXPECT_GT(refused, 0u);
    EXPECT_GT(matched, 10 * refused);
  });
}

TEST(ShapeMatchingBatch, LargeRotationsAndMirrorsGiveTheSvdRotation) {
  // Stiffness 1 moves every movable particle onto its goal, so the result shows T directly.
  test::for_each_simd_target([](const std::string&) {
    Random random(17);
    ClusterScene scene;
    for (int c = 0; c < 40; ++c) {
      const std::size_t first = scene.rest.size();
      const Matrix3r rotation = c == 0 ? Matrix3r(Vector3r(-1, -1, 1).asDiagonal())  // 180°
                                       : random.rotation();
      const bool mirrored = c % 5 == 1;
      for (int k = 0; k < 12; ++k) {
        const Vector3r x0 = Vector3r(Real(2) * Real(k % 3), Real(k % 4), Real(k % 2)) +
                            Real(0.3) * random.vector();
        Vector3r x = rotation * x0 + Vector3r(1, 2, 3) + Real(0.05) * random.vector();
        if (mirrored) x.z() = -x.z();
        scene.rest.push_back(x0);
        scene.current.push_back(x);
        scene.inverse_masses.push_back(random.inverse_mass());
        scene.particles.push_back(ParticleIndex(first + std::size_t(k)));
      }
      scene.offsets.push_back(std::uint32_t(scene.particles.size()));
    }
    ShapeMatchingConstraints constraints = build(scene, false, 1);
    std::vector<Vector3r> expected = scene.current;
    std::vector<bool> solved;
    scalar_project(scene, constraints, 0, scene.count(), expected, &solved);
    for (const bool ok : solved) ASSERT_TRUE(ok);
    ParticleState state(scene.current, scene.inverse_masses);
    project_shape_matching_constraints(ParticleArrays::of(state), constraints, 0, scene.count());
    EXPECT_TRUE(test::positions_match(state, expected, 10));
  });
}

TEST(ShapeMatchingBatch, RigidMotionIsAFixedPointAndProjectionConverges) {
  // Movable clusters of 5..25 particles moved by one rigid motion: matched exactly.
  Random random(5);
  ClusterScene scene;
  const Matrix3r rotation = random.rotation();
  const Vector3r translation = random.vector(-2, 2);
  for (int c = 0; c < 37; ++c) {
    const Vector3r centre = random.vector(-5, 5);
    const int size = random.integer(5, 25);
    for (int k = 0; k < size; ++k) {
      const Vector3r x0 = centre + random.vector(-1, 1);
      scene.particles.push_back(ParticleIndex(scene.rest.size()));
      scene.rest.push_back(x0);
      scene.current.push_back(rotation * x0 + translation);
      scene.inverse_masses.push_back(random.inverse_mass());
    }
    scene.offsets.push_back(std::uint32_t(scene.particles.size()));
  }
  ShapeMatchingConstraints constraints = build(scene, false, 1);
  ParticleState state(scene.current, scene.inverse_masses);
  project_shape_matching_constraints(ParticleArrays::of(state), constraints, 0, scene.count());
  EXPECT_TRUE(test::positions_match(state, scene.current, 10));
  // Perturbed, repeated projection with k = 0.5 restores a rigid image of every cluster.
  for (std::size_t i = 0; i < scene.rest.size(); ++i)
    state.set_position(i, state.position(i) + Real(0.3) * random.vector());
  for (std::size_t c = 0; c < scene.count(); ++c) constraints.stiffness[c] = Real(0.5);
  for (int iteration = 0; iteration < 40; ++iteration)
    project_shape_matching_constraints(ParticleArrays::of(state), constraints, 0, scene.count());
  std::vector<Vector3r> settled(scene.rest.size());
  for (std::size_t i = 0; i < settled.size(); ++i) settled[i] = state.position(i);
  for (std::size_t c = 0; c < scene.count(); ++c) constraints.stiffness[c] = 1;
  project_shape_matching_constraints(ParticleArrays::of(state), constraints, 0, scene.count());
  EXPECT_TRUE(test::positions_match(state, settled, 10));
  // And it is rigid: distances within each cluster are the rest distances.
  for (std::size_t c = 0; c < scene.count(); ++c) {
    const ParticleIndex a = scene.particles[scene.offsets[c]];
    const ParticleIndex b = scene.particles[scene.offsets[c + 1] - 1];
    EXPECT_NEAR((state.position(a) - state.position(b)).norm(),
                (scene.rest[a] - scene.rest[b]).norm(), 100 * test::kBatchTolerance);
  }
}

TEST(ShapeMatchingBatch, BitwiseReproducibleAndStaticParticlesUntouched) {
  test::for_each_simd_target([](const std::string&) {
    Random random(42);
    const ClusterScene scene = make_scene(random, 77, false);
    ShapeMatchingConstraints constraints = build(scene, false, Real(0.9));
    ParticleState first(scene.current, scene.inverse_masses), second = first;
    const ParticleState before = first;
    for (int iteration = 0; iteration < 4; ++iteration) {
      project_shape_matching_constraints(ParticleArrays::of(first), constraints, 0, 77);
      project_shape_matching_constraints(ParticleArrays::of(second), constraints, 0, 77);
    }
    EXPECT_TRUE(test::same_bits(first, second));
    EXPECT_FALSE(test::same_bits(first, before));
    for (std::size_t i = 0; i < scene.current.size(); ++i)
      if (scene.inverse_masses[i] == 0) {
        EXPECT_EQ(first.position(i), before.position(i));
      }
    project_shape_matching_constraints(ParticleArrays::of(first), constraints, 30, 30);
    EXPECT_TRUE(test::same_bits(first, second));
  });
}

// ------------------------------------------------------------------ validation at the door
std::string error_of(const ShapeMatchingInput& input) {
  return test::error_of([&] { make_shape_matching_constraints(input); });
}

TEST(ShapeMatchingBatchValidation, NamesTheClusterAndTheProblem) {
  const std::vector<Vector3r> rest = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0),
                                      Vector3r(0, 0, 1), Vector3r(2, 0, 0), Vector3r(3, 0, 0),
                                      Vector3r(0, Real(NAN), 0)};
  const std::vector<Real> w = {1, 1, 1, 1, 1, 1, 1};
  const std::vector<std::uint32_t> two = {0, 4, 8};
  const std::vector<ParticleIndex> fine = {0, 1, 2, 3, 3, 2, 1, 0};
  EXPECT_EQ(error_of({two, fine, rest, w}), "");
  EXPECT_EQ(error_of({two, fine, rest, w, 1, true}), "");
  const std::vector<ParticleIndex> out_of_range = {0, 1, 2, 3, 0, 1, 2, 9};
  EXPECT_EQ(error_of({two, out_of_range, rest, w}),
            "shape matching constraint 1: particle index 9 is out of range (7 particles)");
  const std::vector<ParticleIndex> repeated = {0, 1, 2, 3, 0, 1, 2, 1};
  EXPECT_EQ(error_of({two, repeated, rest, w}),
            "shape matching constraint 1: particle 1 appears twice");
  const std::vector<std::uint32_t> with_empty = {0, 4, 4, 8};
  EXPECT_EQ(error_of({with_empty, fine, rest, w}),
            "shape matching constraint 1: cluster is empty");
  const std::vector<ParticleIndex> not_finite = {0, 1, 2, 3, 0, 1, 2, 6};
  EXPECT_EQ(error_of({two, not_finite, rest, w}),
            "shape matching constraint 1: rest position is not finite");
  const std::vector<ParticleIndex> collinear = {0, 1, 2, 3, 0, 1, 4, 5};
  EXPECT_EQ(error_of({two, collinear, rest, w}),
            "shape matching constraint 1: rest cluster is degenerate (all points on one line)");
  const std::vector<ParticleIndex> planar = {0, 1, 2, 3, 0, 1, 2, 4};
  EXPECT_EQ(error_of({two, planar, rest, w}), "");
  EXPECT_EQ(error_of({two, planar, rest, w, 1, true}),
            "shape matching constraint 1: rest cluster is degenerate (all points in one plane: "
            "no linear fit)");
  std::vector<Real> negative = w;
  negative[2] = -1;
  EXPECT_EQ(error_of({two, fine, rest, negative}),
            "shape matching constraint 0: inverse mass is -1, must not be negative");
  EXPECT_EQ(error_of({two, fine, rest, w, Real(-0.5)}),
            "shape matching constraints: stiffness is -0.5, must be finite and ≥ 0");
  const std::vector<Real> short_w = {1, 1};
  EXPECT_EQ(error_of({two, fine, rest, short_w}),
            "shape matching constraints: 7 rest positions but 2 inverse masses");
  const std::vector<std::uint32_t> decreasing = {0, 9, 8};
  EXPECT_EQ(error_of({decreasing, fine, rest, w}),
            "shape matching constraints: offsets decrease at cluster 1");
  const std::vector<std::uint32_t> short_end = {0, 4, 7};
  EXPECT_EQ(error_of({short_end, fine, rest, w}),
            "shape matching constraints: the last offset is 7, not the number of entries 8");
  const std::vector<std::uint32_t> late_start = {1, 4, 8};
  EXPECT_EQ(error_of({late_start, fine, rest, w}),
            "shape matching constraints: offsets do not start at 0");
}

TEST(ShapeMatchingBatchValidation, RangeAndParticleCountAreChecked) {
  const std::vector<Vector3r> rest = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0),
                                      Vector3r(0, 0, 1)};
  const std::vector<Real> w(4, 1);
  const std::vector<std::uint32_t> one = {0, 4};
  const std::vector<ParticleIndex> cluster = {0, 1, 2, 3};
  ShapeMatchingConstraints constraints = make_shape_matching_constraints({one, cluster, rest, w});
  EXPECT_EQ(constraints.max_cluster_size, 4u);
  ParticleState state(rest, w);
  EXPECT_THROW(project_shape_matching_constraints(ParticleArrays::of(state), constraints, 0, 2),
               InvalidInput);
  ParticleState small(3);
  EXPECT_THROW(project_shape_matching_constraints(ParticleArrays::of(small), constraints, 0, 1),
               InvalidInput);
}

}  // namespace shape_matching_batch_tests
}  // namespace tessera
