// The batched distance kernel against the scalar API, on every SIMD target the machine has,
// plus validation of the batch input.
#include <tessera/core/distance_constraints.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "batch_test_support.hpp"

namespace tessera {
namespace distance_batch_tests {

using test::Random;

test::DisjointConstraintSet<2> random_edges(Random& random, std::size_t count) {
  return test::make_disjoint_constraints<2>(random, count, Real(0.2), [](Random& r) {
    const Vector3r a = r.vector(-5, 5);
    return std::array<Vector3r, 2>{a, a + r.unit_vector() * r.uniform(Real(0.2), 2)};
  });
}

/// Rest lengths differ from the current ones by up to ±30 %.
DistanceConstraints build(const test::DisjointConstraintSet<2>& set, Random& random) {
  std::vector<Vector3r> rest = set.positions;
  for (Vector3r& p : rest) p *= random.uniform(Real(0.7), Real(1.3));
  DistanceConstraints constraints =
      make_distance_constraints({set.indices, rest, Real(0.8), Real(1e-4)});
  return constraints;
}

void project_scalar(const test::DisjointConstraintSet<2>& set,
                    const DistanceConstraints& constraints, std::size_t begin, std::size_t end,
                    const ProjectionSettings& settings, std::vector<Vector3r>& expected,
                    std::vector<Real>& expected_lambda) {
  const std::vector<Real>& w = set.inverse_masses;
  test::project_scalar_range<2>(
      set, begin, end, expected,
      [&](const ParticleIndex* i, std::size_t c, Vector3r(&corr)[2]) {
        if (settings.semantics == ConstraintSemantics::stiffness)
          PositionBasedDynamics::solve_DistanceConstraint(
              expected[i[0]], w[i[0]], expected[i[1]], w[i[1]], constraints.rest_length[c],
              constraints.stiffness[c], corr[0], corr[1]);
        else
          XPBD::solve_DistanceConstraint(expected[i[0]], w[i[0]], expected[i[1]], w[i[1]],
                                         constraints.rest_length[c], constraints.compliance[c],
                                         settings.dt, expected_lambda[c], corr[0], corr[1]);
      });
}

TEST(DistanceBatch, MatchesScalarApiOnEveryTarget) {
  test::expect_batch_matches_scalar_with_lambda(random_edges, build, project_distance_constraints,
                                                project_scalar);
}

TEST(DistanceBatch, BitwiseReproducibleOnEveryTarget) {
  test::expect_bitwise_reproducible(random_edges, build, project_distance_constraints);
}

TEST(DistanceBatch, ARangeIsItsConstraintsProjectedOneByOne) {
  test::expect_range_is_its_constraints_one_by_one(random_edges, build,
                                                   project_distance_constraints);
}

TEST(DistanceBatch, StaticParticlesAndEmptyRangesAreNotWritten) {
  test::expect_static_particles_and_empty_ranges_not_written(
      random_edges, build, project_distance_constraints, {ProjectionSettings{}}, false);
}

// The kernel gathers each block's particles while it projects the block before, and scatters
// each block after it projects the block after (batch_loop-inl.h). It must never read or write
// the particles of a constraint at or past the range's end, wherever the end falls in a block:
// another thread may be writing them. Here the constraints past the end name a particle far
// past the arrays (set after validation; small enough that four times it is still a positive
// 32-bit index), so a read or write of one faults (and AddressSanitizer names it); the range's
// result is the scalar API's, in both particle layouts, for ranges starting at 0 and off a
// block's start.
TEST(DistanceBatch, TheNextBlockIsGatheredOnlyWithinTheRange) {
  constexpr std::size_t kLanes = kMaxLanes;
  constexpr std::size_t kCount = 3 * kLanes + 5;
  constexpr ParticleIndex kFarAway = 0x1fffffff;
  test::for_each_simd_target([&](const std::string&) {
    for (const std::size_t begin : {std::size_t(0), std::size_t(3)}) {
      for (const std::size_t end : {begin + 1, kLanes - 1, kLanes, kLanes + 1, 2 * kLanes,
                                    2 * kLanes + 3, 3 * kLanes, kCount - 1}) {
        SCOPED_TRACE("range [" + std::to_string(begin) + ", " + std::to_string(end) + ")");
        Random random(11);
        const auto set = random_edges(random, kCount);
        for (const bool interleaved : {false, true}) {
          DistanceConstraints constraints = build(set, random);
          for (auto& slot : constraints.particles.particle)
            for (std::size_t j = end; j < kCount; ++j) slot[j] = kFarAway;
          const ProjectionSettings settings{ConstraintSemantics::compliance, Real(1) / 120};
          std::vector<Vector3r> expected = set.positions;
          std::vector<Real> expected_lambda(kCount, Real(0));
          project_scalar(set, constraints, begin, end, settings, expected, expected_lambda);
          ParticleState state(set.positions, set.inverse_masses);
          test::project_in_layout(project_distance_constraints, state, constraints, begin, end,
                                  settings, interleaved);
          EXPECT_TRUE(test::positions_match(state, expected, 10)) << "interleaved " << interleaved;
        }
      }
    }
  });
}

TEST(DistanceBatch, AllTargetsAvailableIncludeThePortableFallback) {
  const auto targets = available_simd_targets();
  ASSERT_FALSE(targets.empty());
  EXPECT_EQ(targets.front(), active_simd_target());
  EXPECT_THROW(force_simd_target("NO-SUCH-ISA"), InvalidInput);
  EXPECT_EQ(active_simd_target(), targets.front());
}

// ------------------------------------------------------------------ validation at the door
std::string error_of(const DistanceConstraintInput& input) {
  return test::error_of([&] { make_distance_constraints(input); });
}

TEST(DistanceBatchValidation, NamesTheConstraintAndTheProblem) {
  const std::vector<Vector3r> rest = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(1, 0, 0),
                                      Vector3r(0, Real(NAN), 0)};
  const std::vector<ParticleIndex> out_of_range = {0, 1, 1, 9};
  EXPECT_EQ(error_of({out_of_range, rest}),
            "distance constraint 1: particle index 9 is out of range (4 particles)");
  const std::vector<ParticleIndex> repeated = {0, 1, 2, 2};
  EXPECT_EQ(error_of({repeated, rest}), "distance constraint 1: particle 2 appears twice");
  const std::vector<ParticleIndex> odd = {0, 1, 2};
  EXPECT_EQ(error_of({odd, rest}),
            "distance constraints: 3 particle indices is not a multiple of 2");
  const std::vector<ParticleIndex> coincident = {0, 1, 1, 2};
  EXPECT_EQ(error_of({coincident, rest}),
            "distance constraint 1: rest length is 0 (particles 1 and 2 coincide at rest)");
  const std::vector<ParticleIndex> not_finite = {0, 3};
  EXPECT_EQ(error_of({not_finite, rest}), "distance constraint 0: rest position is not finite");
  const std::vector<ParticleIndex> fine = {0, 1};
  EXPECT_EQ(error_of({fine, rest, Real(-1)}),
            "distance constraints: stiffness is -1, must be finite and ≥ 0");
  EXPECT_EQ(error_of({fine, rest, 1, Real(INFINITY)}),
            "distance constraints: compliance is inf, must be finite and ≥ 0");
  EXPECT_EQ(error_of({fine, rest}), "");
}

TEST(DistanceBatchValidation, RangeAndParticleCountAreChecked) {
  const std::vector<Vector3r> rest = {Vector3r(0, 0, 0), Vector3r(1, 0, 0)};
  const std::vector<ParticleIndex> edge = {0, 1};
  DistanceConstraints constraints = make_distance_constraints({edge, rest});
  ParticleState two(rest, std::vector<Real>{1, 1});
  EXPECT_THROW(project_distance_constraints(ParticleArrays::of(two), constraints, 0, 2, {}),
               InvalidInput);
  ParticleState one(1);
  EXPECT_THROW(project_distance_constraints(ParticleArrays::of(one), constraints, 0, 1, {}),
               InvalidInput);
}

}  // namespace distance_batch_tests
}  // namespace tessera
