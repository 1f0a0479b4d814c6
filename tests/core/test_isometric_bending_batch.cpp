// The batched isometric bending kernel against the scalar API (PBD and XPBD) on every SIMD
// target the machine has: random bent stencils far from the origin (the centroid-relative
// evaluation matters there), exactly flat stencils (satisfied: untouched, λ unchanged)
// and stencils collapsed to a point. Plus the stored Q against
// init_IsometricBendingConstraint, reproducibility, static particles, convergence to flat and
// validation of the batch input.
#include <tessera/core/error.hpp>
#include <tessera/core/isometric_bending_constraints.hpp>
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

#include "batch_test_support.hpp"

namespace tessera {
namespace isometric_bending_batch_tests {

using test::Random;
using Stencil = std::array<Vector3r, 4>;

/// A planar stencil (wings on opposite sides of the edge p2-p3), rigidly moved.
Stencil random_planar_stencil(Random& random, Real spread = 5) {
  const Stencil flat = {Vector3r(random.uniform(Real(-0.5), Real(1.5)), random.uniform(Real(0.3), Real(1.5)), 0),
                        Vector3r(random.uniform(Real(-0.5), Real(1.5)), -random.uniform(Real(0.3), Real(1.5)), 0),
                        Vector3r(0, 0, 0), Vector3r(random.uniform(Real(0.5), Real(1.5)), 0, 0)};
  const Matrix3r rotation = random.rotation();
  const Vector3r shift = random.vector(-spread, spread);
  Stencil s;
  for (std::size_t k = 0; k < 4; ++k) s[k] = rotation * flat[k] + shift;
  return s;
}

/// Current shapes: 0 collapsed to a point (∇C exactly 0), 1 planar but not an affine image of
/// its rest shape (so not flat for its Q), otherwise bent (a planar stencil with every point
/// moved by up to ±0.3).
Stencil random_current(Random& random) {
  const int kind = random.integer(0, 9);
  Stencil s = random_planar_stencil(random);
  if (kind == 0) {
    for (Vector3r& p : s) p = s[0];
  } else if (kind != 1) {
    for (Vector3r& p : s) p += random.vector(Real(-0.3), Real(0.3));
  }
  return s;
}

test::DisjointConstraintSet<4> random_set(Random& random, std::size_t count) {
  return test::make_disjoint_constraints<4>(random, count, Real(0.2), random_current);
}

/// Rest positions: a planar stencil per constraint, translated so that a shared static
/// particle keeps its one position. (Never the current shape itself: a stencil flat for its Q
/// only up to round-off has rounding-noise gradients, and its projection depends on the
/// evaluation order; the exactly flat case is FlatStencilsAreLeftAlone.)
std::vector<Vector3r> rest_positions(const test::DisjointConstraintSet<4>& set, Random& random) {
  return test::translated_rest_stencils<4>(
      set, random, [](Random& r) { return random_planar_stencil(r); },
      [](std::size_t, const Stencil&) -> Vector3r { return Vector3r::Zero(); });
}

IsometricBendingConstraints build(const test::DisjointConstraintSet<4>& set, Random& random) {
  const std::vector<Vector3r> rest = rest_positions(set, random);
  return make_isometric_bending_constraints({set.indices, rest, Real(0.7), Real(1e-3)});
}

void project_scalar(const test::DisjointConstraintSet<4>& set,
                    const IsometricBendingConstraints& constraints, std::size_t begin,
                    std::size_t end, const ProjectionSettings& settings,
                    std::vector<Vector3r>& expected, std::vector<Real>& lambda) {
  const std::vector<Real>& w = set.inverse_masses;
  test::project_scalar_range<4>(
      set, begin, end, expected,
      [&](const ParticleIndex* i, std::size_t c, Vector3r(&corr)[4]) {
        const Matrix4r Q = constraints.matrix(c);
        if (settings.semantics == ConstraintSemantics::stiffness)
          PositionBasedDynamics::solve_IsometricBendingConstraint(
              expected[i[0]], w[i[0]], expected[i[1]], w[i[1]], expected[i[2]], w[i[2]],
              expected[i[3]], w[i[3]], Q, constraints.stiffness[c], corr[0], corr[1], corr[2],
              corr[3]);
        else
          XPBD::solve_IsometricBendingConstraint(expected[i[0]], w[i[0]], expected[i[1]], w[i[1]],
                                                 expected[i[2]], w[i[2]], expected[i[3]], w[i[3]],
                                                 Q, constraints.compliance[c], settings.dt,
                                                 lambda[c], corr[0], corr[1], corr[2], corr[3]);
      });
}

TEST(IsometricBendingBatch, StoresTheMatrixOfInit) {
  Random random(3);
  const auto set = random_set(random, 50);
  const std::vector<Vector3r> rest = rest_positions(set, random);
  const IsometricBendingConstraints constraints =
      make_isometric_bending_constraints({set.indices, rest});
  for (std::size_t c = 0; c < 50; ++c) {
    const ParticleIndex* i = &set.indices[4 * c];
    Matrix4r Q;
    ASSERT_TRUE(PositionBasedDynamics::init_IsometricBendingConstraint(rest[i[0]], rest[i[1]],
                                                                       rest[i[2]], rest[i[3]], Q));
    // Stored as the rank-one factor k of Q = k kᵀ: k kᵀ gives Q back to round-off.
    const Matrix4r stored = constraints.matrix(c);
    EXPECT_LE((stored - Q).norm(), test::kRoundOff * Q.norm()) << "constraint " << c;
    EXPECT_EQ(stored, stored.transpose());
  }
}

TEST(IsometricBendingBatch, MatchesScalarApiOnEveryTarget) {
  test::expect_batch_matches_scalar_with_lambda(
      random_set, build, project_isometric_bending_constraints, project_scalar);
}

/// Stencils at their planar rest shape satisfy the constraint: not moved, λ unchanged. The
/// stencils are chosen so that every step is exact in binary floating point (dyadic wing
/// positions and heights, integer offsets), so ∇C vanishes exactly and not just to
/// round-off.
TEST(IsometricBendingBatch, FlatStencilsMoveOnlyByRoundOff) {
  std::vector<Vector3r> positions;
  std::vector<ParticleIndex> indices;
  int offset = 0;
  for (const Real along : {Real(0.25), Real(0.5), Real(0.75)})
    for (const Real height : {Real(0.5), Real(1), Real(2), Real(4)})
      for (const Real other : {Real(0.25), Real(0.75)}) {
        const Vector3r shift(Real(offset % 5), Real(offset % 3), Real(offset % 7));
        ++offset;
        const Stencil s = {Vector3r(along, height, 0), Vector3r(other, -height, 0),
                           Vector3r(0, 0, 0), Vector3r(1, 0, 0)};
        for (const Vector3r& p : s) {
          indices.push_back(ParticleIndex(positions.size()));
          positions.push_back(p + shift);
        }
      }
  const std::size_t count = indices.size() / 4;
  IsometricBendingConstraints constraints =
      make_isometric_bending_constraints({indices, positions});
  const std::vector<Real> w(positions.size(), 1);
  test::for_each_simd_target([&](const std::string&) {
    for (const auto semantics :
         {ConstraintSemantics::stiffness, ConstraintSemantics::compliance}) {
      std::fill(constraints.lambda.begin(), constraints.lambda.end(), Real(-0.5));
      ParticleState state(positions, w);
      project_isometric_bending_constraints(ParticleArrays::of(state), constraints, 0, count,
                                            {semantics, Real(0.01)});
      // The factor k of Q is rounded, so a flat stencil has a curvature vector u of rounding
      // size, and the step (∝ u) is of rounding size too: no jitter.
      for (std::size_t i = 0; i < positions.size(); ++i)
        EXPECT_LE((state.position(i) - positions[i]).norm(), 8 * test::kEpsilon)
            << "particle " << i;
    }
  });
  // The scalar API agrees: satisfied (true), corrections of rounding size.
  for (std::size_t c = 0; c < count; ++c) {
    const ParticleIndex* i = &indices[4 * c];
    Vector3r corr[4];
    EXPECT_TRUE(PositionBasedDynamics::solve_IsometricBendingConstraint(
        positions[i[0]], 1, positions[i[1]], 1, positions[i[2]], 1, positions[i[3]], 1,
        constraints.matrix(c), 1, corr[0], corr[1], corr[2], corr[3]));
    for (const Vector3r& v : corr) EXPECT_LE(v.norm(), 8 * test::kEpsilon);
  }
}

TEST(IsometricBendingBatch, BitwiseReproducibleOnEveryTarget) {
  test::expect_bitwise_reproducible(random_set, build, project_isometric_bending_constraints);
}

TEST(IsometricBendingBatch, StaticParticlesAndEmptyRangesAreNotWritten) {
  const ProjectionSettings xpbd{ConstraintSemantics::compliance, Real(0.01)};
  test::expect_static_particles_and_empty_ranges_not_written(
      random_set, build, project_isometric_bending_constraints, {ProjectionSettings{}, xpbd}, true);
}

TEST(IsometricBendingBatch, RepeatedProjectionFlattensTheStencils) {
  Random random(11);
  const auto set = random_set(random, 64);
  IsometricBendingConstraints constraints = build(set, random);
  ParticleState state(set.positions, set.inverse_masses);
  const auto energy = [&](std::size_t c) {
    const ParticleIndex* i = &set.indices[4 * c];
    const Matrix4r Q = constraints.matrix(c);
    Real C = 0;
    for (int r = 0; r < 4; ++r)
      for (int k = 0; k < 4; ++k)
        C += Q(r, k) * (state.position(i[r]) - state.position(i[0]))
                           .dot(state.position(i[k]) - state.position(i[0]));
    return C / 2;
  };
  std::vector<Real> start(64);
  for (std::size_t c = 0; c < 64; ++c) start[c] = energy(c);
  for (int iteration = 0; iteration < 100; ++iteration)
    project_isometric_bending_constraints(ParticleArrays::of(state), constraints, 0, 64, {});
  for (std::size_t c = 0; c < 64; ++c) {
    const ParticleIndex* i = &set.indices[4 * c];
    bool all_static = true;
    for (std::size_t k = 0; k < 4; ++k) all_static = all_static && set.inverse_masses[i[k]] == 0;
    if (all_static) continue;
    EXPECT_LE(energy(c), Real(1e-3) * (1 + start[c])) << "constraint " << c;
  }
}

// ------------------------------------------------------------------ validation at the door
std::string error_of(const IsometricBendingConstraintInput& input) {
  return test::error_of([&] { make_isometric_bending_constraints(input); });
}

TEST(IsometricBendingBatchValidation, NamesTheConstraintAndTheProblem) {
  // 0..3: a symmetric flat stencil; 4: on the edge line; 5: coincides with 2; 6: not finite.
  const std::vector<Vector3r> rest = {Vector3r(Real(0.5), 1, 0), Vector3r(Real(0.5), -1, 0),
                                      Vector3r(0, 0, 0),          Vector3r(1, 0, 0),
                                      Vector3r(3, 0, 0),          Vector3r(0, 0, 0),
                                      Vector3r(0, Real(NAN), 0)};
  const std::vector<ParticleIndex> fine = {0, 1, 2, 3};
  EXPECT_EQ(error_of({fine, rest}), "");
  const std::vector<ParticleIndex> out_of_range = {0, 1, 2, 3, 0, 1, 2, 9};
  EXPECT_EQ(error_of({out_of_range, rest}),
            "isometric bending constraint 1: particle index 9 is out of range (7 particles)");
  const std::vector<ParticleIndex> repeated = {0, 1, 2, 3, 0, 1, 3, 3};
  EXPECT_EQ(error_of({repeated, rest}), "isometric bending constraint 1: particle 3 appears twice");
  const std::vector<ParticleIndex> seven = {0, 1, 2, 3, 4, 5, 6};
  EXPECT_EQ(error_of({seven, rest}),
            "isometric bending constraints: 7 particle indices is not a multiple of 4");
  const std::vector<ParticleIndex> not_finite = {0, 1, 2, 6};
  EXPECT_EQ(error_of({not_finite, rest}),
            "isometric bending constraint 0: rest position is not finite");
  const std::vector<ParticleIndex> zero_edge = {0, 1, 2, 3, 0, 1, 2, 5};
  EXPECT_EQ(error_of({zero_edge, rest}),
            "isometric bending constraint 1: degenerate rest stencil: shared edge p2-p3 has "
            "zero length");
  const std::vector<ParticleIndex> flat_wing0 = {4, 1, 2, 3};
  EXPECT_EQ(error_of({flat_wing0, rest}),
            "isometric bending constraint 0: degenerate rest stencil: triangle (p0, p2, p3) has "
            "zero area");
  const std::vector<ParticleIndex> flat_wing1 = {0, 4, 2, 3};
  EXPECT_EQ(error_of({flat_wing1, rest}),
            "isometric bending constraint 0: degenerate rest stencil: triangle (p1, p3, p2) has "
            "zero area");
  EXPECT_EQ(error_of({fine, rest, Real(-0.5)}),
            "isometric bending constraints: stiffness is -0.5, must be finite and ≥ 0");
  EXPECT_EQ(error_of({fine, rest, 1, Real(-INFINITY)}),
            "isometric bending constraints: compliance is -inf, must be finite and ≥ 0");
}

TEST(IsometricBendingBatchValidation, RangeAndParticleCountAreChecked) {
  const std::vector<Vector3r> rest = {Vector3r(Real(0.5), 1, 0), Vector3r(Real(0.5), -1, 0),
                                      Vector3r(0, 0, 0), Vector3r(1, 0, 0)};
  const std::vector<ParticleIndex> stencil = {0, 1, 2, 3};
  IsometricBendingConstraints constraints = make_isometric_bending_constraints({stencil, rest});
  ParticleState four(rest, std::vector<Real>(4, 1));
  EXPECT_THROW(
      project_isometric_bending_constraints(ParticleArrays::of(four), constraints, 0, 2, {}),
      InvalidInput);
  ParticleState three(3);
  EXPECT_THROW(
      project_isometric_bending_constraints(ParticleArrays::of(three), constraints, 0, 1, {}),
      InvalidInput);
}

}  // namespace isometric_bending_batch_tests
}  // namespace tessera
