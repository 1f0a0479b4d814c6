// The batched strain triangle and strain tetrahedron kernels against the scalar API, on every
// SIMD target the machine has, for every normalisation switch, with switched-off
// sub-constraints and collapsed (degenerate) elements among well-shaped ones; plus
// validation of the batch input.
#include <tessera/core/error.hpp>
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/strain_tetra_constraints.hpp>
#include <tessera/core/strain_triangle_constraints.hpp>

#include "batch_test_support.hpp"

namespace tessera {
namespace strain_batch_tests {

using test::Random;
using PBD = PositionBasedDynamics;

/// Rest positions: the current ones moved by up to 0.2 in every coordinate, so every element
/// is stretched, compressed and sheared at once.
std::vector<Vector3r> perturbed_rest(const std::vector<Vector3r>& positions, Random& random) {
  std::vector<Vector3r> rest = positions;
  for (Vector3r& p : rest) p += Real(0.2) * random.vector();
  return rest;
}

/// A stiffness in [0.2, 1], or 0 (sub-constraint switched off) one time in five.
Real random_stiffness(Random& random) {
  return random.uniform(0, 1) < Real(0.2) ? Real(0) : random.uniform(Real(0.2), 1);
}

/// Collapses about one element in ten whose particles are all movable to a point: exactly
/// degenerate (a zero column of F). A partly collapsed element would not be degenerate but
/// ill-conditioned (a Newton step on |f|² - 1 from a tiny f is ~1/|f| long), which amplifies
/// round-off beyond any batch-vs-scalar tolerance in both paths alike.
template <int N>
void collapse_some(test::DisjointConstraintSet<N>& set, Random& random) {
  for (std::size_t c = 0; c < set.count; ++c) {
    if (random.uniform(0, 1) > Real(0.15)) continue;
    bool all_movable = true;
    for (int k = 0; k < N; ++k)
      all_movable = all_movable && set.inverse_masses[set.indices[c * N + std::size_t(k)]] > 0;
    if (!all_movable) continue;
    const Vector3r centre = set.positions[set.indices[c * N]];
    for (int k = 1; k < N; ++k) set.positions[set.indices[c * N + std::size_t(k)]] = centre;
  }
}

// ------------------------------------------------------------------------------ triangle
test::DisjointConstraintSet<3> random_triangles(Random& random, std::size_t count) {
  return test::make_disjoint_constraints<3>(random, count, Real(0.2), [](Random& r) {
    // Roughly in the xy plane (the rest frame of the family), never thin.
    const Vector3r a = r.vector(-5, 5);
    const Vector3r u(r.uniform(Real(0.5), 2), r.uniform(Real(-0.3), Real(0.3)), r.uniform(-1, 1));
    const Vector3r v(r.uniform(Real(-0.3), Real(0.3)), r.uniform(Real(0.5), 2), r.uniform(-1, 1));
    return std::array<Vector3r, 3>{a, a + u, a + v};
  });
}

StrainTriangleConstraints build_triangles(const test::DisjointConstraintSet<3>& set,
                                          Random& random, bool normalize_stretch,
                                          bool normalize_shear) {
  StrainTriangleConstraintInput input;
  const std::vector<Vector3r> rest = perturbed_rest(set.positions, random);
  input.particles = set.indices;
  input.rest_positions = rest;
  input.normalize_stretch = normalize_stretch;
  input.normalize_shear = normalize_shear;
  StrainTriangleConstraints constraints = make_strain_triangle_constraints(input);
  for (std::size_t c = 0; c < set.count; ++c) {
    constraints.xx_stiffness[c] = random_stiffness(random);
    constraints.yy_stiffness[c] = random_stiffness(random);
    constraints.xy_stiffness[c] = random_stiffness(random);
  }
  return constraints;
}

TEST(StrainTriangleBatch, MatchesScalarApiOnEveryTarget) {
  test::for_each_simd_target([](const std::string&) {
    for (unsigned seed = 1; seed <= 8; ++seed) {
      Random random(seed);
      const bool normalize_stretch = (seed & 1) != 0, normalize_shear = (seed & 2) != 0;
      const std::size_t count = std::size_t(random.integer(1, 300));
      auto set = random_triangles(random, count);
      StrainTriangleConstraints constraints =
          build_triangles(set, random, normalize_stretch, normalize_shear);
      collapse_some(set, random);
      const auto [begin, end] = test::random_range(random, count);
      ParticleState state(set.positions, set.inverse_masses);
      std::vector<Vector3r> expected = set.positions;
      int degenerate = 0;
      for (std::size_t c = begin; c < end; ++c) {
        ParticleIndex i[3];
        for (int k = 0; k < 3; ++k) i[k] = set.indices[3 * c + std::size_t(k)];
        Matrix2r rest_inverse;
        for (int k = 0; k < 2; ++k)
          for (int j = 0; j < 2; ++j) rest_inverse(k, j) = constraints.rest_inverse[2 * k + j][c];
        Vector3r corr[3];
        if (!PBD::solve_StrainTriangleConstraint(
                expected[i[0]], set.inverse_masses[i[0]], expected[i[1]],
                set.inverse_masses[i[1]], expected[i[2]], set.inverse_masses[i[2]],
                rest_inverse, constraints.xx_stiffness[c], constraints.yy_stiffness[c],
                constraints.xy_stiffness[c], normalize_stretch, normalize_shear, corr[0],
                corr[1], corr[2]))
          ++degenerate;
        for (int k = 0; k < 3; ++k)
          if (set.inverse_masses[i[k]] > 0) expected[i[k]] += corr[k];
      }
      project_strain_triangle_constraints(ParticleArrays::of(state), constraints, begin, end,
                                          {});
      EXPECT_TRUE(test::positions_match(state, expected, 10)) << "seed " << seed;
      // Particles of constraints outside the range are untouched.
      for (std::size_t c = 0; c < count; ++c)
        if (c < begin || c >= end)
          for (int k = 0; k < 3; ++k) {
            const ParticleIndex p = set.indices[3 * c + std::size_t(k)];
            EXPECT_EQ(state.position(p), set.positions[p]);
          }
      if (normalize_stretch && count > 100) {
        EXPECT_GT(degenerate, 0) << "no degenerate lane";
      }
    }
  });
}

// ------------------------------------------------------------------------------ tetra
test::DisjointConstraintSet<4> random_tets(Random& random, std::size_t count) {
  return test::make_disjoint_constraints<4>(random, count, Real(0.2), [](Random& r) {
    const Vector3r a = r.vector(-5, 5);
    const Matrix3r frame = r.rotation() * Real(r.uniform(Real(0.5), 2));
    return std::array<Vector3r, 4>{a, a + frame.col(0), a + frame.col(1), a + frame.col(2)};
  });
}

StrainTetraConstraints build_tets(const test::DisjointConstraintSet<4>& set, Random& random,
                                  bool normalize_stretch, bool normalize_shear) {
  StrainTetraConstraintInput input;
  const std::vector<Vector3r> rest = perturbed_rest(set.positions, random);
  input.particles = set.indices;
  input.rest_positions = rest;
  input.normalize_stretch = normalize_stretch;
  input.normalize_shear = normalize_shear;
  StrainTetraConstraints constraints = make_strain_tetra_constraints(input);
  for (std::size_t c = 0; c < set.count; ++c)
    for (int s = 0; s < 3; ++s) {
      constraints.stretch_stiffness[std::size_t(s)][c] = random_stiffness(random);
      constraints.shear_stiffness[std::size_t(s)][c] = random_stiffness(random);
    }
  return constraints;
}

/// The scalar API applied to constraints [begin, end) in order.
std::vector<Vector3r> scalar_tets(const test::DisjointConstraintSet<4>& set,
                                  const StrainTetraConstraints& constraints, std::size_t begin,
                                  std::size_t end, int* degenerate = nullptr) {
  std::vector<Vector3r> expected = set.positions;
  for (std::size_t c = begin; c < end; ++c) {
    ParticleIndex i[4];
    for (int k = 0; k < 4; ++k) i[k] = set.indices[4 * c + std::size_t(k)];
    Matrix3r rest_inverse;
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j) rest_inverse(k, j) = constraints.rest_inverse[3 * k + j][c];
    Vector3r stretch, shear;
    for (int s = 0; s < 3; ++s) {
      stretch[s] = constraints.stretch_stiffness[std::size_t(s)][c];
      shear[s] = constraints.shear_stiffness[std::size_t(s)][c];
    }
    Vector3r corr[4];
    const bool ok = PBD::solve_StrainTetraConstraint(
        expected[i[0]], set.inverse_masses[i[0]], expected[i[1]], set.inverse_masses[i[1]],
        expected[i[2]], set.inverse_masses[i[2]], expected[i[3]], set.inverse_masses[i[3]],
        rest_inverse, stretch, shear, constraints.normalize_stretch,
        constraints.normalize_shear, corr[0], corr[1], corr[2], corr[3]);
    if (!ok && degenerate) ++*degenerate;
    for (int k = 0; k < 4; ++k)
      if (set.inverse_masses[i[k]] > 0) expected[i[k]] += corr[k];
  }
  return expected;
}

TEST(StrainTetraBatch, MatchesScalarApiOnEveryTarget) {
  test::for_each_simd_target([](const std::string&) {
    for (unsigned seed = 1; seed <= 8; ++seed) {
      Random random(100 + seed);
      const bool normalize_stretch = (seed & 1) != 0, normalize_shear = (seed & 2) != 0;
      const std::size_t count = std::size_t(random.integer(1, 300));
      auto set = random_tets(random, count);
      StrainTetraConstraints constraints =
          build_tets(set, random, normalize_stretch, normalize_shear);
      collapse_some(set, random);
      const auto [begin, end] = test::random_range(random, count);
      int degenerate = 0;
      const std::vector<Vector3r> expected = scalar_tets(set, constraints, begin, end, &degenerate);
      ParticleState state(set.positions, set.inverse_masses);
      project_strain_tetra_constraints(ParticleArrays::of(state), constraints, begin, end, {});
      EXPECT_TRUE(test::positions_match(state, expected, 10)) << "seed " << seed;
      if (normalize_stretch && count > 100) {
        EXPECT_GT(degenerate, 0) << "no degenerate lane";
      }
    }
  });
}

TEST(StrainTetraBatch, RepeatedSweepsRestoreTheRestMetric) {
  // Only the first batch sweep is compared above; this checks the kernel keeps working on its
  // own output (no drift from the scalar API over many sweeps, and S → I).
  Random random(5);
  auto set = random_tets(random, 64);
  for (std::size_t i = 0; i < set.inverse_masses.size(); ++i)
    if (set.inverse_masses[i] == 0) set.inverse_masses[i] = 1;  // all movable: reachable rest
  StrainTetraConstraintInput input;
  const std::vector<Vector3r> rest = perturbed_rest(set.positions, random);
  input.particles = set.indices;
  input.rest_positions = rest;
  // Shared static slots were made movable, so constraints now share particles: project them
  // one at a time (each range a single constraint) to keep the ranges valid.
  StrainTetraConstraints constraints = make_strain_tetra_constraints(input);
  ParticleState state(set.positions, set.inverse_masses);
  for (int sweep = 0; sweep < 200; ++sweep)
    for (std::size_t c = 0; c < set.count; ++c)
      project_strain_tetra_constraints(ParticleArrays::of(state), constraints, c, c + 1, {});
  Real worst = 0;
  for (std::size_t c = 0; c < set.count; ++c) {
    Matrix3r edges, rest_inverse;
    for (int k = 0; k < 3; ++k) {
      edges.col(k) = state.position(set.indices[4 * c + std::size_t(k) + 1]) -
                     state.position(set.indices[4 * c]);
      for (int j = 0; j < 3; ++j) rest_inverse(k, j) = constraints.rest_inverse[3 * k + j][c];
    }
    const Matrix3r F = edges * rest_inverse;
    worst = std::max(worst, (F.transpose() * F - Matrix3r::Identity()).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, Real(0.05));
}

TEST(StrainBatch, BitwiseReproducibleAndStaticParticlesUntouched) {
  test::for_each_simd_target([](const std::string&) {
    Random random(42);
    const auto set = random_tets(random, 257);
    StrainTetraConstraints constraints = build_tets(set, random, true, false);
    ParticleState first(set.positions, set.inverse_masses), second = first;
    const ParticleState before = first;
    for (int iteration = 0; iteration < 5; ++iteration) {
      project_strain_tetra_constraints(ParticleArrays::of(first), constraints, 0, 257, {});
      project_strain_tetra_constraints(ParticleArrays::of(second), constraints, 0, 257, {});
    }
    EXPECT_TRUE(test::same_bits(first, second));
    for (std::size_t i = 0; i < set.positions.size(); ++i)
      if (set.inverse_masses[i] == 0) {
        EXPECT_EQ(first.position(i), before.position(i));
      }
    EXPECT_FALSE(test::same_bits(first, before));

    const auto triangles = random_triangles(random, 130);
    StrainTriangleConstraints triangle_constraints = build_triangles(triangles, random, false, true);
    ParticleState a(triangles.positions, triangles.inverse_masses), b = a;
    const ParticleState start = a;
    project_strain_triangle_constraints(ParticleArrays::of(a), triangle_constraints, 7, 7, {});
    EXPECT_TRUE(test::same_bits(a, start));
    for (int iteration = 0; iteration < 3; ++iteration) {
      project_strain_triangle_constraints(ParticleArrays::of(a), triangle_constraints, 0, 130, {});
      project_strain_triangle_constraints(ParticleArrays::of(b), triangle_constraints, 0, 130, {});
    }
    EXPECT_TRUE(test::same_bits(a, b));
    for (std::size_t i = 0; i < triangles.positions.size(); ++i)
      if (triangles.inverse_masses[i] == 0) {
        EXPECT_EQ(a.position(i), start.position(i));
      }
  });
}

// ------------------------------------------------------------------ validation at the door
using test::error_of;

TEST(StrainBatchValidation, NamesTheConstraintAndTheProblem) {
  const std::vector<Vector3r> rest = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0),
                                      Vector3r(0, 0, 1), Vector3r(2, 0, 5),
                                      Vector3r(0, Real(NAN), 0)};
  auto triangle = [&](std::vector<ParticleIndex> indices, Real xx = 1) {
    return error_of([&] {
      StrainTriangleConstraintInput input;
      input.particles = indices;
      input.rest_positions = rest;
      input.xx_stiffness = xx;
      make_strain_triangle_constraints(input);
    });
  };
  EXPECT_EQ(triangle({0, 1, 2, 0, 1, 9}),
            "strain triangle constraint 1: particle index 9 is out of range (6 particles)");
  EXPECT_EQ(triangle({0, 1, 2, 0, 2, 2}), "strain triangle constraint 1: particle 2 appears twice");
  EXPECT_EQ(triangle({0, 1}),
            "strain triangle constraints: 2 particle indices is not a multiple of 3");
  // 0, 1, 4 has area in 3D but is a segment in the xy plane, the family's rest frame.
  EXPECT_EQ(triangle({0, 1, 2, 0, 1, 4}),
            "strain triangle constraint 1: rest triangle has zero area in the xy plane");
  EXPECT_EQ(triangle({0, 1, 5}), "strain triangle constraint 0: rest position is not finite");
  EXPECT_EQ(triangle({0, 1, 2}, Real(-0.5)),
            "strain triangle constraints: xx stiffness is -0.5, must be finite and ≥ 0");
  EXPECT_EQ(triangle({0, 1, 2}), "");

  auto tetra = [&](std::vector<ParticleIndex> indices, Vector3r shear = Vector3r::Ones()) {
    return error_of([&] {
      StrainTetraConstraintInput input;
      input.particles = indices;
      input.rest_positions = rest;
      input.shear_stiffness = shear;
      make_strain_tetra_constraints(input);
    });
  };
  EXPECT_EQ(tetra({0, 1, 2, 3, 0, 1, 2, 6}),
            "strain tetra constraint 1: particle index 6 is out of range (6 particles)");
  EXPECT_EQ(tetra({0, 1, 2, 3, 3, 1, 2, 3}), "strain tetra constraint 1: particle 3 appears twice");
  EXPECT_EQ(tetra({0, 1, 2, 3, 0}),
            "strain tetra constraints: 5 particle indices is not a multiple of 4");
  // Four points of the xy plane: a flat rest tetrahedron.
  const std::vector<Vector3r> flat_rest = {Vector3r(0, 0, 0), Vector3r(1, 0, 0),
                                           Vector3r(0, 1, 0), Vector3r(1, 1, 0)};
  EXPECT_EQ(error_of([&] {
              const std::vector<ParticleIndex> indices = {0, 1, 2, 3};
              StrainTetraConstraintInput input;
              input.particles = indices;
              input.rest_positions = flat_rest;
              make_strain_tetra_constraints(input);
            }),
            "strain tetra constraint 0: rest tetrahedron is flat (zero volume)");
  EXPECT_EQ(tetra({0, 1, 2, 5}), "strain tetra constraint 0: rest position is not finite");
  EXPECT_EQ(tetra({0, 1, 2, 3}, Vector3r(1, Real(INFINITY), 1)),
            "strain tetra constraints: xz shear stiffness is inf, must be finite and ≥ 0");
  // Either orientation of the rest tetrahedron is accepted.
  EXPECT_EQ(tetra({0, 1, 2, 3, 0, 2, 1, 4}), "");
}

TEST(StrainBatchValidation, RangeAndParticleCountAreChecked) {
  const std::vector<Vector3r> rest = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0),
                                      Vector3r(0, 0, 1)};
  const std::vector<ParticleIndex> indices = {0, 1, 2, 3};
  StrainTetraConstraintInput input;
  input.particles = indices;
  input.rest_positions = rest;
  StrainTetraConstraints constraints = make_strain_tetra_constraints(input);
  ParticleState four(rest, std::vector<Real>{1, 1, 1, 1});
  EXPECT_THROW(project_strain_tetra_constraints(ParticleArrays::of(four), constraints, 0, 2, {}),
               InvalidInput);
  ParticleState three(3);
  EXPECT_THROW(project_strain_tetra_constraints(ParticleArrays::of(three), constraints, 0, 1, {}),
               InvalidInput);
}

}  // namespace strain_batch_tests
}  // namespace tessera
