// Tethers (long-range attachments): the scalar API's known answers (inactive within reach,
// back onto the sphere of radius d beyond it, static particles never move, λ only pulls), the
// batched kernel against the scalar API on every SIMD target, validation at the door, and
// make_long_range_attachments' geodesic reaches and nearest attachments.
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include <tessera/core/error.hpp>
#include <tessera/core/long_range_attachments.hpp>
#include <tessera/core/position_based_dynamics_extensions.hpp>
#include <tessera/core/tether_constraints.hpp>

#include "batch_test_support.hpp"

namespace tessera {
namespace tether_tests {

using test::Random;
using PBD = PositionBasedDynamicsExtensions;
using XPBDx = XPBDExtensions;

constexpr Real kTolerance = kDoublePrecision ? Real(1e-12) : Real(1e-5);

// ---------------------------------------------------------------------------- scalar API
TEST(Tether, NoCorrectionWithinReach) {
  const Vector3r anchor(1, 2, 3);
  Vector3r c0(9, 9, 9), c1(9, 9, 9);
  for (const Real distance : {Real(0.1), Real(1.0), Real(1.999)}) {
    const Vector3r p = anchor + distance * Vector3r(0.6, 0, 0.8);
    EXPECT_FALSE(PBD::solve_TetherConstraint(p, 1, anchor, 0, 2, 1, c0, c1));
    EXPECT_EQ(c0, Vector3r::Zero());
    EXPECT_EQ(c1, Vector3r::Zero());
    Real lambda = Real(-0.5);
    EXPECT_FALSE(XPBDx::solve_TetherConstraint(p, 1, anchor, 0, 2, Real(1e-3), Real(0.01),
                                               lambda, c0, c1));
    EXPECT_EQ(c0, Vector3r::Zero());
    EXPECT_EQ(lambda, Real(-0.5)) << "an inactive tether keeps its λ";
  }
}

TEST(Tether, StretchedTetherGoesBackOntoTheSphereOfItsReach) {
  const Vector3r anchor(1, 2, 3);
  const Vector3r direction = Vector3r(2, -1, 2).normalized();
  const Vector3r p = anchor + Real(3.5) * direction;
  Vector3r c0, c1;
  ASSERT_TRUE(PBD::solve_TetherConstraint(p, Real(0.7), anchor, 0, Real(2), 1, c0, c1));
  EXPECT_NEAR(((p + c0) - anchor).norm(), 2, kTolerance);
  EXPECT_NEAR(((p + c0) - (anchor + 2 * direction)).norm(), 0, kTolerance)
      << "moved along the line to the attachment";
  EXPECT_EQ(c1, Vector3r::Zero()) << "a static attachment never moves";

  // Stiffness k moves it a fraction k of the way.
  ASSERT_TRUE(PBD::solve_TetherConstraint(p, 1, anchor, 0, 2, Real(0.25), c0, c1));
  EXPECT_NEAR(((p + c0) - anchor).norm(), Real(3.5) - Real(0.25) * Real(1.5), kTolerance);

  // Hard XPBD (α = 0) reaches the sphere in one step, λ < 0 (it pulls).
  Real lambda = 0;
  ASSERT_TRUE(XPBDx::solve_TetherConstraint(p, 1, anchor, 0, 2, 0, Real(0.01), lambda, c0, c1));
  EXPECT_NEAR(((p + c0) - anchor).norm(), 2, kTolerance);
  EXPECT_LT(lambda, 0);
}

TEST(Tether, TwoMovableEndsShareTheCorrectionByInverseMass) {
  const Vector3r a(0, 0, 0), b(3, 0, 0);
  Vector3r c0, c1;
  ASSERT_TRUE(PBD::solve_TetherConstraint(a, 1, b, 3, 2, 1, c0, c1));
  EXPECT_NEAR(((a + c0) - (b + c1)).norm(), 2, kTolerance);
  EXPECT_NEAR((c0 + c1 / 3).norm(), 0, kTolerance) << "mass-weighted corrections sum to zero";
}

TEST(Tether, CompliantTetherAccumulatesANegativeMultiplier) {
  const Vector3r anchor(0, 0, 0);
  Vector3r p(0, -3, 0);
  Real lambda = 0;
  Vector3r c0, c1;
  const Real compliance = Real(1e-4), dt = Real(1) / 60;
  for (int i = 0; i < 50; ++i) {
    if (XPBDx::solve_TetherConstraint(p, 1, anchor, 0, 2, compliance, dt, lambda, c0, c1))
      p += c0;
    EXPECT_LE(lambda, 0);
  }
  // The converged compliant solution: C = -α̃ λ with α̃ = α/dt² (λ < 0: C > 0, a small stretch).
  const Real C = p.norm() - 2;
  EXPECT_NEAR(C, -compliance / (dt * dt) * lambda, Real(1e-3));
  EXPECT_GT(C, 0);
}

TEST(Tether, DegenerateInputGivesFalseAndZeroCorrections) {
  Vector3r c0(1, 1, 1), c1(1, 1, 1);
  const Vector3r a(1, 1, 1);
  EXPECT_FALSE(PBD::solve_TetherConstraint(a, 1, a, 0, 1, 1, c0, c1)) << "coincident";
  EXPECT_EQ(c0, Vector3r::Zero());
  EXPECT_FALSE(PBD::solve_TetherConstraint(a, 0, Vector3r(9, 9, 9), 0, 1, 1, c0, c1))
      << "both static";
  EXPECT_EQ(c0, Vector3r::Zero());
  EXPECT_EQ(c1, Vector3r::Zero());
}

// -------------------------------------------------------------------------------- batch
test::DisjointConstraintSet<2> random_tethers(Random& random, std::size_t count) {
  return test::make_disjoint_constraints<2>(random, count, Real(0.3), [](Random& r) {
    const Vector3r a = r.vector(-5, 5);
    return std::array<Vector3r, 2>{a, a + r.unit_vector() * r.uniform(Real(0.2), 2)};
  });
}

/// Reaches between 0.6 and 1.4 of the current lengths: about half the tethers are stretched.
TetherConstraints build(const test::DisjointConstraintSet<2>& set, Random& random) {
  std::vector<Real> reach(set.count);
  for (std::size_t c = 0; c < set.count; ++c) {
    const auto p = set.points(c);
    reach[c] = (p[0] - p[1]).norm() * random.uniform(Real(0.6), Real(1.4));
  }
  return make_tether_constraints({.particles = set.indices,
                                  .rest_positions = set.positions,
                                  .max_distances = reach,
                                  .stiffness = Real(0.8),
                                  .compliance = Real(1e-4)});
}

void project_scalar(const test::DisjointConstraintSet<2>& set, const TetherConstraints& b,
                    std::size_t begin, std::size_t end, const ProjectionSettings& settings,
                    std::vector<Vector3r>& expected, std::vector<Real>& expected_lambda) {
  const std::vector<Real>& w = set.inverse_masses;
  test::project_scalar_range<2>(
      set, begin, end, expected, [&](const ParticleIndex* i, std::size_t c, Vector3r(&corr)[2]) {
        if (settings.semantics == ConstraintSemantics::stiffness)
          PBD::solve_TetherConstraint(expected[i[0]], w[i[0]], expected[i[1]], w[i[1]],
                                      b.max_distance[c], b.stiffness[c], corr[0], corr[1]);
        else
          XPBDx::solve_TetherConstraint(expected[i[0]], w[i[0]], expected[i[1]], w[i[1]],
                                        b.max_distance[c], b.compliance[c], settings.dt,
                                        expected_lambda[c], corr[0], corr[1]);
      });
}

TEST(TetherBatch, MatchesScalarApiOnEveryTarget) {
  test::expect_batch_matches_scalar_with_lambda(random_tethers, build, project_tether_constraints,
                                                project_scalar);
}

TEST(TetherBatch, BitwiseReproducibleOnEveryTarget) {
  test::expect_bitwise_reproducible(random_tethers, build, project_tether_constraints);
}

TEST(TetherBatch, ARangeIsItsTethersProjectedOneByOne) {
  test::expect_range_is_its_constraints_one_by_one(random_tethers, build,
                                                   project_tether_constraints);
}

TEST(TetherBatch, StaticParticlesAndEmptyRangesAreNotWritten) {
  test::expect_static_particles_and_empty_ranges_not_written(
      random_tethers, build, project_tether_constraints, {ProjectionSettings{}}, true);
}

TEST(TetherBatch, ResidualIsTheRelativeOvershoot) {
  const std::vector<Vector3r> positions = {Vector3r(0, 0, 0), Vector3r(3, 0, 0),
                                           Vector3r(0, 1, 0)};
  const std::vector<ParticleIndex> pairs = {1, 0, 2, 0};
  const std::vector<Real> reach = {2, 2};
  const TetherConstraints batch = make_tether_constraints({pairs, positions, reach});
  ParticleState state(positions, std::vector<Real>{0, 1, 1});
  Real out[2] = {-1, -1};
  constraint_residuals(ParticleArrays::of(state), batch, 0, 2, out);
  EXPECT_NEAR(out[0], Real(0.5), kTolerance) << "3 against a reach of 2";
  EXPECT_EQ(out[1], 0) << "within reach";
}

TEST(TetherBatchValidation, NamesTheTetherAndTheProblem) {
  const std::vector<Vector3r> rest = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(1, 0, 0)};
  const auto error_of = [&](const TetherConstraintInput& input) {
    return test::error_of([&] { make_tether_constraints(input); });
  };
  const std::vector<ParticleIndex> ok = {0, 1}, out_of_range = {0, 7}, repeated = {1, 1},
                                   coincident = {1, 2}, odd = {0, 1, 2};
  EXPECT_EQ(error_of({out_of_range, rest}),
            "tether constraint 0: particle index 7 is out of range (3 particles)");
  EXPECT_NE(error_of({repeated, rest}).find("tether constraint 0"), std::string::npos);
  EXPECT_NE(error_of({coincident, rest}).find("reach"), std::string::npos)
      << "a zero rest distance is no reach";
  EXPECT_NE(error_of({odd, rest}).find("not a multiple of 2"), std::string::npos);
  const std::vector<Real> negative = {-1}, two = {1, 1};
  EXPECT_NE(error_of({ok, rest, negative}).find("tether constraint 0: reach is -1"),
            std::string::npos);
  EXPECT_NE(error_of({ok, rest, two}).find("2 reaches for 1 tethers"), std::string::npos);
  EXPECT_NE(error_of({.particles = ok, .rest_positions = rest, .stiffness = Real(-1)}).find("stiffness"),
            std::string::npos);
  EXPECT_NE(error_of({.particles = ok, .rest_positions = rest, .max_distance = Real(-2)})
                .find("tether constraint 0: reach is -2"),
            std::string::npos);
  // One reach for every tether.
  EXPECT_EQ(make_tether_constraints({.particles = ok, .rest_positions = rest, .max_distance = 3})
                .max_distance[0],
            3);
  EXPECT_NO_THROW(make_tether_constraints({ok, rest}));
}

// ------------------------------------------------------------ long-range attachments
/// An L-shaped path 0-1-2-3-4 (unit edges, a right angle at 2) fixed at 0.
TEST(LongRangeAttachments, ReachIsTheGeodesicDistanceAlongTheEdges) {
  const std::vector<Vector3r> positions = {Vector3r(0, 0, 0), Vector3r(1, 0, 0),
                                           Vector3r(2, 0, 0), Vector3r(2, 1, 0),
                                           Vector3r(2, 2, 0)};
  const std::vector<Real> inverse_masses = {0, 1, 1, 1, 1};
  const std::vector<ParticleIndex> edges = {0, 1, 2, 1, 2, 3, 3, 4, 1, 2};  // one repeated
  const TetherConstraints tethers =
      make_long_range_attachments(positions, inverse_masses, edges);
  ASSERT_EQ(tethers.size(), 4u);
  for (std::size_t c = 0; c < 4; ++c) {
    EXPECT_EQ(tethers.particles.particle[0][c], c + 1) << "in particle order";
    EXPECT_EQ(tethers.particles.particle[1][c], 0u);
    EXPECT_NEAR(tethers.max_distance[c], Real(c + 1), kTolerance)
        << "the path length, not the straight distance (" << (positions[c + 1]).norm() << ")";
  }
  // A reach scale stretches every reach.
  const TetherConstraints loose =
      make_long_range_attachments(positions, inverse_masses, edges, {.reach_scale = Real(1.1)});
  EXPECT_NEAR(loose.max_distance[3], Real(4.4), kTolerance);
}

TEST(LongRangeAttachments, EachParticleTakesItsNearestAttachmentAndTiesTheSmallerNumber) {
  // A chain 0 - 1 - 2 - 3 - 4 with both ends fixed: 1 → 0, 3 → 4, 2 is as far from both
  // and takes 0.
  std::vector<Vector3r> positions;
  for (int i = 0; i < 5; ++i) positions.emplace_back(Real(i), 0, 0);
  const std::vector<Real> inverse_masses = {0, 1, 1, 1, 0};
  const std::vector<ParticleIndex> edges = {3, 4, 2, 3, 1, 2, 0, 1};
  const TetherConstraints tethers =
      make_long_range_attachments(positions, inverse_masses, edges);
  ASSERT_EQ(tethers.size(), 3u);
  EXPECT_EQ(tethers.particles.particle[1][0], 0u);
  EXPECT_EQ(tethers.particles.particle[1][1], 0u);
  EXPECT_EQ(tethers.particles.particle[1][2], 4u);
  EXPECT_NEAR(tethers.max_distance[1], 2, kTolerance);
  EXPECT_NEAR(tethers.max_distance[2], 1, kTolerance);
}

TEST(LongRangeAttachments, SeveralAttachmentsNearestFirstHoldATautChainStraight) {
  // A chain 0 - 1 - ... - 6 with both ends fixed, at rest exactly as long as their distance.
  // With two attachments each, particle i may be no farther than i from 0 and 6 − i from 6:
  // the two spheres touch only on the segment, so a sag of the middle is a tether violation
  // (with one, particle 3 could sag anywhere within 3 of particle 0).
  std::vector<Vector3r> positions;
  for (int i = 0; i < 7; ++i) positions.emplace_back(Real(i), 0, 0);
  const std::vector<Real> inverse_masses = {0, 1, 1, 1, 1, 1, 0};
  std::vector<ParticleIndex> edges;
  for (ParticleIndex i = 0; i < 6; ++i) edges.insert(edges.end(), {i, ParticleIndex(i + 1)});
  const TetherConstraints two =
      make_long_range_attachments(positions, inverse_masses, edges, {.attachments = 2});
  ASSERT_EQ(two.size(), 10u) << "two per movable particle";
  for (std::size_t i = 1; i <= 5; ++i) {
    const std::size_t first = 2 * (i - 1), second = first + 1;
    EXPECT_EQ(two.particles.particle[0][first], i);
    EXPECT_EQ(two.particles.particle[0][second], i);
    // The nearer attachment first; particle 3 is as far from both and takes 0 first.
    const ParticleIndex nearer = i <= 3 ? 0 : 6, farther = i <= 3 ? 6 : 0;
    EXPECT_EQ(two.particles.particle[1][first], nearer) << "particle " << i;
    EXPECT_EQ(two.particles.particle[1][second], farther) << "particle " << i;
    EXPECT_NEAR(two.max_distance[first], Real(std::min(i, 6 - i)), kTolerance);
    EXPECT_NEAR(two.max_distance[second], Real(std::max(i, 6 - i)), kTolerance);
  }
  // A sagging middle breaks the far tether of both attachments' spheres.
  std::vector<Vector3r> sagging = positions;
  sagging[3].y() = Real(-0.5);
  const Real reach_to_0 = two.max_distance[4], reach_to_6 = two.max_distance[5];
  EXPECT_GT((sagging[3] - positions[0]).norm(), reach_to_0);
  EXPECT_GT((sagging[3] - positions[6]).norm(), reach_to_6);
  // One attachment each is today's default of the core call: the nearest only.
  EXPECT_EQ(make_long_range_attachments(positions, inverse_masses, edges).size(), 5u);
  // More than there are attachments gives each particle all of them.
  EXPECT_EQ(make_long_range_attachments(positions, inverse_masses, edges, {.attachments = 9})
                .size(),
            10u);
}

/// A side × side grid (rows 1.3 apart, columns spaced unevenly, so that no particle is as far
/// from two attachments)
/// with structural and shear edges, fixed at `fixed`: every particle's k-th attachment and
/// reach, for k = 1 .. max_k, must equal a brute-force shortest path from each attachment,
/// sorted by (length, number).
void expect_attachments_are_the_shortest_paths(int side, const std::vector<std::size_t>& fixed,
                                               std::size_t max_k) {
  std::vector<Vector3r> positions;
  for (int r = 0; r < side; ++r)
    for (int c = 0; c < side; ++c)
      positions.emplace_back(Real(c) + Real(0.01) * Real(c * c), Real(r) * Real(1.3), 0);
  std::vector<Real> inverse_masses(positions.size(), 1);
  for (const std::size_t a : fixed) inverse_masses[a] = 0;
  std::vector<ParticleIndex> edges;
  for (int r = 0; r < side; ++r)
    for (int c = 0; c < side; ++c) {
      const auto p = ParticleIndex(r * side + c);
      if (c + 1 < side) edges.insert(edges.end(), {p, ParticleIndex(p + 1)});
      if (r + 1 < side) edges.insert(edges.end(), {p, ParticleIndex(p + side)});
      if (c + 1 < side && r + 1 < side) edges.insert(edges.end(), {p, ParticleIndex(p + side + 1)});
    }
  // Bellman–Ford from each attachment over movable particles only (a path ends at an attachment).
  const std::size_t n = positions.size();
  const auto shortest_from = [&](std::size_t a) {
    std::vector<double> d(n, 1e30);
    d[a] = 0;
    for (std::size_t round = 0; round < n; ++round)
      for (std::size_t e = 0; e < edges.size(); e += 2)
        for (int end = 0; end < 2; ++end) {
          const std::size_t p = edges[e + end], q = edges[e + 1 - end];
          if (p != a && inverse_masses[p] == 0) continue;
          if (inverse_masses[q] == 0) continue;
          d[q] = std::min(d[q], d[p] + (positions[p] - positions[q]).cast<double>().norm());
        }
    return d;
  };
  std::vector<std::size_t> attachments = fixed;
  std::sort(attachments.begin(), attachments.end());
  std::vector<std::vector<double>> from;
  for (const std::size_t a : attachments) from.push_back(shortest_from(a));
  for (std::size_t k = 1; k <= max_k; ++k) {
    const TetherConstraints tethers =
        make_long_range_attachments(positions, inverse_masses, edges, {.attachments = k});
    std::size_t t = 0;
    for (std::size_t p = 0; p < n; ++p) {
      if (inverse_masses[p] == 0) continue;
      std::vector<std::pair<double, std::size_t>> expected;
      for (std::size_t a = 0; a < attachments.size(); ++a)
        expected.emplace_back(from[a][p], attachments[a]);
      std::sort(expected.begin(), expected.end());
      for (std::size_t j = 0; j < std::min(k, attachments.size()); ++j, ++t) {
        ASSERT_LT(t, tethers.size());
        EXPECT_EQ(tethers.particles.particle[0][t], p);
        EXPECT_EQ(tethers.particles.particle[1][t], expected[j].second) << "particle " << p << ", k " << k;
        EXPECT_NEAR(tethers.max_distance[t], Real(expected[j].first), kTolerance);
      }
    }
    EXPECT_EQ(t, tethers.size());
  }
}

TEST(LongRangeAttachments, SeveralAttachmentsReachEachAlongItsOwnShortestPath) {
  // Three fixed corners of a 4 × 4 grid.
  expect_attachments_are_the_shortest_paths(4, {0, 3, 15}, 3);
}

TEST(LongRangeAttachments, ManyAttachmentsFewKeptEachStillTheNearest) {
  // A 9 × 9 grid fixed along its top row and at two inner points: eleven attachments, of which
  // each particle keeps one, two or three. The search reaches a particle from many
  // attachments and remembers only as many queued lengths as it keeps; what it forgets must
  // not change which it keeps.
  std::vector<std::size_t> fixed = {20, 58};
  for (std::size_t c = 0; c < 9; ++c) fixed.push_back(72 + c);
  expect_attachments_are_the_shortest_paths(9, fixed, 3);
}

TEST(LongRangeAttachments, NothingWithoutAttachmentsOrForUnconnectedParticles) {
  const std::vector<Vector3r> positions = {Vector3r(0, 0, 0), Vector3r(1, 0, 0),
                                           Vector3r(5, 0, 0), Vector3r(6, 0, 0)};
  const std::vector<ParticleIndex> edges = {0, 1, 2, 3};
  EXPECT_EQ(make_long_range_attachments(positions, std::vector<Real>(4, 1), edges).size(), 0u);
  const TetherConstraints one =
      make_long_range_attachments(positions, std::vector<Real>{0, 1, 1, 1}, edges);
  ASSERT_EQ(one.size(), 1u) << "2 and 3 reach no attachment";
  EXPECT_EQ(one.particles.particle[0][0], 1u);
}

TEST(LongRangeAttachments, BadInputIsNamed) {
  const std::vector<Vector3r> positions = {Vector3r(0, 0, 0), Vector3r(1, 0, 0)};
  const std::vector<Real> w = {0, 1};
  const auto error_of = [&](std::span<const ParticleIndex> edges, std::span<const Real> masses,
                            Real scale = 1) {
    return test::error_of([&] {
      make_long_range_attachments(positions, masses, edges, {.reach_scale = scale});
    });
  };
  const std::vector<ParticleIndex> odd = {0, 1, 1}, far = {0, 5}, ok = {0, 1};
  EXPECT_EQ(error_of(odd, w),
            "long-range attachments: 3 edge indices is not a whole number of edges (2 each)");
  EXPECT_EQ(error_of(far, w),
            "long-range attachments: edge 0: particle 5 is out of range (2 particles)");
  EXPECT_EQ(error_of(ok, std::vector<Real>{0}),
            "long-range attachments: 1 inverse masses for 2 particles");
  EXPECT_EQ(error_of(ok, w, Real(0)),
            "long-range attachments: reach scale must be positive and finite");
  EXPECT_EQ(test::error_of([&] {
              make_long_range_attachments(positions, w, ok, {.attachments = 0});
            }),
            "long-range attachments: attachments per particle must be at least 1");
}

}  // namespace tether_tests
}  // namespace tessera
