// The batched dihedral kernel against the scalar API (PBD and XPBD) on every SIMD target the
// machine has: random bent stencils, exactly flat ones (where the sign convention decides the
// direction), nearly folded ones, stencils degenerate in their current shape, and an angle
// sweep over [0, π] that exercises every branch of the lane atan2. Plus reproducibility,
// static particles and validation of the batch input.
#include <numbers>

#include <tessera/core/dihedral_constraints.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "batch_test_support.hpp"

namespace tessera {
namespace dihedral_batch_tests {

using test::Random;
using Stencil = std::array<Vector3r, 4>;
constexpr Real kPi = std::numbers::pi_v<Real>;

/// Shared edge p2 = 0, p3 = length · e_x; wing p0 in the xy plane; wing p1 rotated about the
/// edge so that the angle between the normals is `angle`.
Stencil hinge(Real angle, Real length = 1) {
  return {Vector3r(Real(0.4), 1, 0), Vector3r(Real(0.6), -std::cos(angle), std::sin(angle)),
          Vector3r(0, 0, 0), Vector3r(length, 0, 0)};
}

/// A well-conditioned stencil, with a random mix of the hard cases:
/// 0 bent (random angle), 1 exactly flat in z = 0, 2 nearly folded (φ close to π),
/// 3 degenerate now (wing p0 on the edge line: zero-area triangle).
Stencil random_stencil(Random& random) {
  const int kind = random.integer(0, 9);
  if (kind == 1) {
    return {Vector3r(random.uniform(-1, 1), random.uniform(Real(0.5), 1), 0),
            Vector3r(random.uniform(-1, 1), -random.uniform(Real(0.5), 1), 0), Vector3r(0, 0, 0),
            Vector3r(random.uniform(Real(0.5), Real(1.5)), 0, 0)};
  }
  if (kind == 2) return hinge(kPi - random.uniform(0, Real(1e-2)));
  if (kind == 3) return {Vector3r(2, 0, 0), Vector3r(Real(0.5), -1, Real(0.3)), Vector3r(0, 0, 0),
                         Vector3r(1, 0, 0)};
  // Bent: a hinge at a random angle, rigidly moved.
  const Matrix3r rotation = random.rotation();
  const Vector3r shift = random.vector(-5, 5);
  Stencil s = hinge(random.uniform(Real(0.05), kPi - Real(0.05)), random.uniform(Real(0.5), 2));
  for (Vector3r& p : s) p = rotation * p + shift;
  return s;
}

test::DisjointConstraintSet<4> random_set(Random& random, std::size_t count) {
  return test::make_disjoint_constraints<4>(random, count, Real(0.2), random_stencil);
}

/// Rest positions: a random hinge per constraint, rigidly translated (so φ0 varies over
/// [0, 2.8] and is rarely the current angle). A constraint on a shared static particle is
/// translated so that particle's rest position is its (one) current position.
std::vector<Vector3r> rest_positions(const test::DisjointConstraintSet<4>& set, Random& random) {
  return test::translated_rest_stencils<4>(
      set, random, [](Random& r) { return hinge(r.uniform(0, Real(2.8))); },
      [&](std::size_t c, const Stencil& s) -> Vector3r {
        return set.positions[set.indices[4 * c + 2]] - s[2];
      });
}

DihedralConstraints build(const test::DisjointConstraintSet<4>& set, Random& random) {
  const std::vector<Vector3r> rest = rest_positions(set, random);
  return make_dihedral_constraints({set.indices, rest, Real(0.8), Real(1e-3)});
}

/// The scalar API applied constraint by constraint over [begin, end) on `expected`.
void project_scalar(const test::DisjointConstraintSet<4>& set,
                    const DihedralConstraints& constraints, std::size_t begin, std::size_t end,
                    const ProjectionSettings& settings, std::vector<Vector3r>& expected,
                    std::vector<Real>& lambda) {
  const std::vector<Real>& w = set.inverse_masses;
  test::project_scalar_range<4>(
      set, begin, end, expected,
      [&](const ParticleIndex* i, std::size_t c, Vector3r(&corr)[4]) {
        if (settings.semantics == ConstraintSemantics::stiffness)
          PositionBasedDynamics::solve_DihedralConstraint(
              expected[i[0]], w[i[0]], expected[i[1]], w[i[1]], expected[i[2]], w[i[2]],
              expected[i[3]], w[i[3]], constraints.rest_angle[c], constraints.stiffness[c], corr[0],
              corr[1], corr[2], corr[3]);
        else
          XPBD::solve_DihedralConstraint(expected[i[0]], w[i[0]], expected[i[1]], w[i[1]],
                                         expected[i[2]], w[i[2]], expected[i[3]], w[i[3]],
                                         constraints.rest_angle[c], constraints.compliance[c],
                                         settings.dt, lambda[c], corr[0], corr[1], corr[2],
                                         corr[3]);
      });
}

TEST(DihedralBatch, MatchesScalarApiOnEveryTarget) {
  test::expect_batch_matches_scalar_with_lambda(random_set, build, project_dihedral_constraints,
                                                project_scalar);
}

/// Every angle class of the lane atan2: 0, (0, π/4), π/4, (π/4, π/2), π/2, (π/2, π), π, with
/// the rest angle 0 so the correction is proportional to the measured angle.
TEST(DihedralBatch, AngleSweepMatchesScalarOnEveryTarget) {
  constexpr std::size_t kAngles = 129;
  std::vector<Vector3r> positions;
  std::vector<ParticleIndex> indices;
  for (std::size_t a = 0; a < kAngles; ++a) {
    const Stencil s = hinge(kPi * Real(a) / Real(kAngles - 1));
    for (const Vector3r& p : s) {
      indices.push_back(ParticleIndex(positions.size()));
      positions.push_back(p);
    }
  }
  const std::vector<Real> w(positions.size(), 1);
  // Flat rest stencils (φ0 = 0): hinge(0) for every constraint.
  std::vector<Vector3r> rest = positions;
  for (std::size_t a = 0; a < kAngles; ++a) {
    const Stencil s = hinge(0);
    for (std::size_t k = 0; k < 4; ++k) rest[4 * a + k] = s[k];
  }
  DihedralConstraints constraints = make_dihedral_constraints({indices, rest});
  for (std::size_t a = 0; a < kAngles; ++a) ASSERT_EQ(constraints.rest_angle[a], Real(0));
  test::for_each_simd_target([&](const std::string&) {
    ParticleState state(positions, w);
    project_dihedral_constraints(ParticleArrays::of(state), constraints, 0, kAngles, {});
    for (std::size_t a = 0; a < kAngles; ++a) {
      const ParticleIndex* i = &indices[4 * a];
      Vector3r corr[4];
      ASSERT_TRUE(PositionBasedDynamics::solve_DihedralConstraint(
          positions[i[0]], 1, positions[i[1]], 1, positions[i[2]], 1, positions[i[3]], 1, 0, 1,
          corr[0], corr[1], corr[2], corr[3]))
          << "angle " << a;
      for (std::size_t k = 0; k < 4; ++k) {
        const Vector3r moved = state.position(i[k]) - positions[i[k]];
        EXPECT_LE((moved - corr[k]).norm(), test::kBatchTolerance * (1 + corr[k].norm()))
            << "angle " << a << " slot " << k << ": batch " << moved.transpose() << ", scalar "
            << corr[k].transpose();
      }
    }
  });
}

TEST(DihedralBatch, BitwiseReproducibleOnEveryTarget) {
  test::expect_bitwise_reproducible(random_set, build, project_dihedral_constraints);
}

TEST(DihedralBatch, StaticParticlesAndEmptyRangesAreNotWritten) {
  const ProjectionSettings xpbd{ConstraintSemantics::compliance, Real(0.01)};
  test::expect_static_particles_and_empty_ranges_not_written(
      random_set, build, project_dihedral_constraints, {ProjectionSettings{}, xpbd}, true);
}

TEST(DihedralBatch, RepeatedProjectionReachesTheRestAngles) {
  Random random(11);
  const auto set = random_set(random, 64);
  DihedralConstraints constraints = build(set, random);
  ParticleState state(set.positions, set.inverse_masses);
  for (int iteration = 0; iteration < 200; ++iteration)
    project_dihedral_constraints(ParticleArrays::of(state), constraints, 0, 64, {});
  for (std::size_t c = 0; c < 64; ++c) {
    const ParticleIndex* i = &set.indices[4 * c];
    const Vector3r p[4] = {state.position(i[0]), state.position(i[1]), state.position(i[2]),
                           state.position(i[3])};
    const Vector3r n1 = (p[2] - p[0]).cross(p[3] - p[0]);
    const Vector3r n2 = (p[3] - p[1]).cross(p[2] - p[1]);
    const bool all_static = set.inverse_masses[i[0]] == 0 && set.inverse_masses[i[1]] == 0 &&
                            set.inverse_masses[i[2]] == 0 && set.inverse_masses[i[3]] == 0;
    if (all_static || n1.norm() < Real(1e-3) || n2.norm() < Real(1e-3)) continue;
    const Real angle = std::atan2(n1.cross(n2).norm(), n1.dot(n2));
    EXPECT_NEAR(angle, constraints.rest_angle[c], Real(2e-2)) << "constraint " << c;
  }
}

// ------------------------------------------------------------------ validation at the door
std::string error_of(const DihedralConstraintInput& input) {
  return test::error_of([&] { make_dihedral_constraints(input); });
}

TEST(DihedralBatchValidation, NamesTheConstraintAndTheProblem) {
  // 0..3: a right-angle hinge; 4: on the edge line; 5: coincides with 2; 6: not finite.
  const Stencil right = hinge(kPi / 2);
  const std::vector<Vector3r> rest = {right[0], right[1],          right[2],
                                      right[3], Vector3r(3, 0, 0), right[2],
                                      Vector3r(0, Real(NAN), 0)};
  const std::vector<ParticleIndex> fine = {0, 1, 2, 3};
  EXPECT_EQ(error_of({fine, rest}), "");
  const DihedralConstraints built = make_dihedral_constraints({fine, rest});
  EXPECT_NEAR(built.rest_angle[0], kPi / 2, 10 * test::kEpsilon);

  const std::vector<ParticleIndex> out_of_range = {0, 1, 2, 3, 0, 1, 2, 9};
  EXPECT_EQ(error_of({out_of_range, rest}),
            "dihedral constraint 1: particle index 9 is out of range (7 particles)");
  const std::vector<ParticleIndex> repeated = {0, 1, 2, 3, 0, 1, 3, 3};
  EXPECT_EQ(error_of({repeated, rest}), "dihedral constraint 1: particle 3 appears twice");
  const std::vector<ParticleIndex> five = {0, 1, 2, 3, 4};
  EXPECT_EQ(error_of({five, rest}),
            "dihedral constraints: 5 particle indices is not a multiple of 4");
  const std::vector<ParticleIndex> not_finite = {0, 1, 2, 6};
  EXPECT_EQ(error_of({not_finite, rest}), "dihedral constraint 0: rest position is not finite");
  const std::vector<ParticleIndex> zero_edge = {0, 1, 2, 3, 0, 1, 2, 5};
  EXPECT_EQ(error_of({zero_edge, rest}),
            "dihedral constraint 1: degenerate rest stencil: shared edge p2-p3 has zero length");
  const std::vector<ParticleIndex> flat_wing0 = {4, 1, 2, 3};
  EXPECT_EQ(error_of({flat_wing0, rest}),
            "dihedral constraint 0: degenerate rest stencil: triangle (p0, p2, p3) has zero "
            "area");
  const std::vector<ParticleIndex> flat_wing1 = {0, 4, 2, 3};
  EXPECT_EQ(error_of({flat_wing1, rest}),
            "dihedral constraint 0: degenerate rest stencil: triangle (p1, p3, p2) has zero "
            "area");
  EXPECT_EQ(error_of({fine, rest, Real(-1)}),
            "dihedral constraints: stiffness is -1, must be finite and ≥ 0");
  EXPECT_EQ(error_of({fine, rest, 1, Real(INFINITY)}),
            "dihedral constraints: compliance is inf, must be finite and ≥ 0");
}

TEST(DihedralBatchValidation, RangeAndParticleCountAreChecked) {
  const Stencil s = hinge(1);
  const std::vector<Vector3r> rest(s.begin(), s.end());
  const std::vector<ParticleIndex> stencil = {0, 1, 2, 3};
  DihedralConstraints constraints = make_dihedral_constraints({stencil, rest});
  ParticleState four(rest, std::vector<Real>(4, 1));
  EXPECT_THROW(project_dihedral_constraints(ParticleArrays::of(four), constraints, 0, 2, {}),
               InvalidInput);
  ParticleState three(3);
  EXPECT_THROW(project_dihedral_constraints(ParticleArrays::of(three), constraints, 0, 1, {}),
               InvalidInput);
}

}  // namespace dihedral_batch_tests
}  // namespace tessera
