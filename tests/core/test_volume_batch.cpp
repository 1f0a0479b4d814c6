// The batched volume kernel against the scalar API (PBD and XPBD) on every SIMD target the
// machine has: random tetrahedra of both orientations, inverted and flat ones, and ones
// collapsed to a point (degenerate: zero correction). Plus reproducibility, static
// particles, convergence to the rest volumes and validation of the batch input.
#include <tessera/core/error.hpp>
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/volume_constraints.hpp>
#include <tessera/core/xpbd.hpp>

#include "batch_test_support.hpp"

namespace tessera {
namespace volume_batch_tests {

using test::Random;
using Tetrahedron = std::array<Vector3r, 4>;

Real signed_volume(const Tetrahedron& p) {
  return (p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]) / 6;
}

/// A well-conditioned tetrahedron rigidly moved and scaled, with a random mix of the hard
/// cases: 0 inverted (two vertices swapped), 1 flat (p3 in the plane of p0 p1 p2),
/// 2 collapsed to a point (degenerate: gradients far below the tolerance), otherwise regular.
/// (Points merely near one line are not used: there the gradients are rounding noise just
/// above the degenerate tolerance, and any two evaluation orders disagree.)
Tetrahedron random_tetrahedron(Random& random) {
  Tetrahedron t = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(Real(0.3), 1, 0),
                   Vector3r(Real(0.3), Real(0.3), 1)};
  for (Vector3r& p : t) p += random.vector(Real(-0.15), Real(0.15));
  switch (random.integer(0, 9)) {
    case 0: std::swap(t[1], t[2]); break;
    case 1: t[3] = t[0] + Real(0.4) * (t[1] - t[0]) + Real(0.3) * (t[2] - t[0]); break;
    case 2: t = {t[0], t[0], t[0], t[0]}; break;
    default: break;
  }
  const Matrix3r rotation = random.rotation();
  const Real scale = random.uniform(Real(0.5), 2);
  const Vector3r shift = random.vector(-5, 5);
  for (Vector3r& p : t) p = scale * (rotation * p) + shift;
  return t;
}

test::DisjointConstraintSet<4> random_set(Random& random, std::size_t count) {
  return test::make_disjoint_constraints<4>(random, count, Real(0.2), random_tetrahedron);
}

/// Rest positions: the current ones, each moved by up to ±0.2 (the rest tetrahedra of the
/// random set are far from flat, the flat and collapsed current ones get a regular rest
/// shape).
std::vector<Vector3r> rest_positions(const test::DisjointConstraintSet<4>& set, Random& random) {
  std::vector<Vector3r> rest = set.positions;
  std::vector<int> uses(set.positions.size(), 0);
  for (ParticleIndex i : set.indices) ++uses[i];
  for (std::size_t c = 0; c < set.count; ++c) {
    Tetrahedron t = set.points(c);
    if (std::abs(signed_volume(t)) < Real(0.02)) {  // flat or collapsed now: regular at rest
      const Vector3r anchor = t[0];
      t = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0), Vector3r(0, 0, 1)};
      for (Vector3r& p : t) p += anchor;
    }
    for (std::size_t k = 0; k < 4; ++k) {
      const ParticleIndex p = set.indices[4 * c + k];
      if (uses[p] == 1) rest[p] = t[k] + random.vector(Real(-0.1), Real(0.1));
    }
  }
  return rest;
}

VolumeConstraints build(const test::DisjointConstraintSet<4>& set, Random& random) {
  const std::vector<Vector3r> rest = rest_positions(set, random);
  return make_volume_constraints({set.indices, rest, Real(0.9), Real(1e-4)});
}

void project_scalar(const test::DisjointConstraintSet<4>& set,
                    const VolumeConstraints& constraints, std::size_t begin, std::size_t end,
                    const ProjectionSettings& settings, std::vector<Vector3r>& expected,
                    std::vector<Real>& lambda) {
  const std::vector<Real>& w = set.inverse_masses;
  test::project_scalar_range<4>(
      set, begin, end, expected,
      [&](const ParticleIndex* i, std::size_t c, Vector3r(&corr)[4]) {
        if (settings.semantics == ConstraintSemantics::stiffness)
          PositionBasedDynamics::solve_VolumeConstraint(
              expected[i[0]], w[i[0]], expected[i[1]], w[i[1]], expected[i[2]], w[i[2]],
              expected[i[3]], w[i[3]], constraints.rest_volume[c], constraints.stiffness[c],
              corr[0], corr[1], corr[2], corr[3]);
        else
          XPBD::solve_VolumeConstraint(expected[i[0]], w[i[0]], expected[i[1]], w[i[1]],
                                       expected[i[2]], w[i[2]], expected[i[3]], w[i[3]],
                                       constraints.rest_volume[c], constraints.compliance[c],
                                       settings.dt, lambda[c], corr[0], corr[1], corr[2], corr[3]);
      });
}

TEST(VolumeBatch, MatchesScalarApiOnEveryTarget) {
  test::expect_batch_matches_scalar_with_lambda(random_set, build, project_volume_constraints,
                                                project_scalar);
}

TEST(VolumeBatch, BitwiseReproducibleOnEveryTarget) {
  test::expect_bitwise_reproducible(random_set, build, project_volume_constraints);
}

TEST(VolumeBatch, StaticParticlesAndEmptyRangesAreNotWritten) {
  const ProjectionSettings xpbd{ConstraintSemantics::compliance, Real(0.01)};
  test::expect_static_particles_and_empty_ranges_not_written(
      random_set, build, project_volume_constraints, {ProjectionSettings{}, xpbd}, true);
}

TEST(VolumeBatch, RepeatedProjectionReachesTheRestVolumes) {
  Random random(11);
  const auto set = random_set(random, 64);
  VolumeConstraints constraints = build(set, random);
  ParticleState state(set.positions, set.inverse_masses);
  for (int iteration = 0; iteration < 100; ++iteration)
    project_volume_constraints(ParticleArrays::of(state), constraints, 0, 64, {});
  std::size_t checked = 0;
  for (std::size_t c = 0; c < 64; ++c) {
    const ParticleIndex* i = &set.indices[4 * c];
    Tetrahedron now;
    bool all_static = true;
    for (std::size_t k = 0; k < 4; ++k) {
      now[k] = state.position(i[k]);
      all_static = all_static && set.inverse_masses[i[k]] == 0;
    }
    const Tetrahedron start = set.points(c);
    // Collapsed to a point (up to the rounding of the shift onto a shared particle): stays.
    bool collapsed = true;
    for (std::size_t k = 1; k < 4; ++k)
      collapsed = collapsed && (start[k] - start[0]).norm() < Real(1e-3);
    if (all_static || collapsed) continue;
    ++checked;
    EXPECT_NEAR(signed_volume(now), constraints.rest_volume[c],
                Real(1e-3) * (1 + std::abs(constraints.rest_volume[c])))
        << "constraint " << c;
  }
  EXPECT_GT(checked, 32u);
}

// ------------------------------------------------------------------ validation at the door
std::string error_of(const VolumeConstraintInput& input) {
  return test::error_of([&] { make_volume_constraints(input); });
}

TEST(VolumeBatchValidation, NamesTheConstraintAndTheProblem) {
  // 0..3: the unit corner tetrahedron (V0 = 1/6); 4: in the plane z = 0; 5: not finite.
  const std::vector<Vector3r> rest = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0),
                                      Vector3r(0, 0, 1), Vector3r(1, 1, 0),
                                      Vector3r(0, Real(NAN), 0)};
  const std::vector<ParticleIndex> fine = {0, 1, 2, 3, 0, 2, 1, 3};
  ASSERT_EQ(error_of({fine, rest}), "");
  const VolumeConstraints built = make_volume_constraints({fine, rest});
  EXPECT_NEAR(built.rest_volume[0], Real(1) / 6, test::kEpsilon);
  EXPECT_NEAR(built.rest_volume[1], -Real(1) / 6, test::kEpsilon) << "signed: orientation kept";

  const std::vector<ParticleIndex> out_of_range = {0, 1, 2, 3, 0, 1, 2, 9};
  EXPECT_EQ(error_of({out_of_range, rest}),
            "volume constraint 1: particle index 9 is out of range (6 particles)");
  const std::vector<ParticleIndex> repeated = {0, 1, 2, 3, 0, 1, 3, 3};
  EXPECT_EQ(error_of({repeated, rest}), "volume constraint 1: particle 3 appears twice");
  const std::vector<ParticleIndex> six = {0, 1, 2, 3, 4, 5};
  EXPECT_EQ(error_of({six, rest}), "volume constraints: 6 particle indices is not a multiple of 4");
  const std::vector<ParticleIndex> not_finite = {0, 1, 2, 5};
  EXPECT_EQ(error_of({not_finite, rest}), "volume constraint 0: rest position is not finite");
  const std::vector<ParticleIndex> flat = {0, 1, 2, 3, 0, 1, 2, 4};
  EXPECT_EQ(error_of({flat, rest}), "volume constraint 1: rest volume is 0 (flat tetrahedron)");
  EXPECT_EQ(error_of({fine, rest, Real(-1)}),
            "volume constraints: stiffness is -1, must be finite and ≥ 0");
  EXPECT_EQ(error_of({fine, rest, 1, Real(NAN)}),
            "volume constraints: compliance is nan, must be finite and ≥ 0");
}

/// Flat is judged relative to the tetrahedron's size: a small well-shaped tetrahedron is
/// accepted, a large sliver is not.
TEST(VolumeBatchValidation, FlatnessIsRelativeToSize) {
  const Real small = Real(1e-3);  // volume 1.7e-10, below any absolute tolerance of float
  const std::vector<Vector3r> tiny = {Vector3r(0, 0, 0), Vector3r(small, 0, 0),
                                      Vector3r(0, small, 0), Vector3r(0, 0, small)};
  const std::vector<ParticleIndex> tet = {0, 1, 2, 3};
  EXPECT_EQ(error_of({tet, tiny}), "");
  const Real thin = kDegenerateTolerance / 10;
  const std::vector<Vector3r> sliver = {Vector3r(0, 0, 0), Vector3r(100, 0, 0),
                                        Vector3r(0, 100, 0), Vector3r(50, 50, 100 * thin)};
  EXPECT_EQ(error_of({tet, sliver}).rfind("volume constraint 0: rest volume is ", 0), 0u);
}

TEST(VolumeBatchValidation, RangeAndParticleCountAreChecked) {
  const std::vector<Vector3r> rest = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0),
                                      Vector3r(0, 0, 1)};
  const std::vector<ParticleIndex> tet = {0, 1, 2, 3};
  VolumeConstraints constraints = make_volume_constraints({tet, rest});
  ParticleState four(rest, std::vector<Real>(4, 1));
  EXPECT_THROW(project_volume_constraints(ParticleArrays::of(four), constraints, 1, 0, {}),
               InvalidInput);
  ParticleState three(3);
  EXPECT_THROW(project_volume_constraints(ParticleArrays::of(three), constraints, 0, 1, {}),
               InvalidInput);
}

}  // namespace volume_batch_tests
}  // namespace tessera
