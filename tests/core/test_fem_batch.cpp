// The batched FEM triangle and FEM tetrahedron kernels against the scalar API on every SIMD
// target — with mildly deformed, heavily compressed, flat and inverted tetrahedra, inversion
// handling on and off, PBD and XPBD — plus the branch-free lane SVD (kernels/svd3-inl.h) and
// the inversion-robust material built on it, checked against Eigen's JacobiSVD and
// PositionBasedDynamics::computeGreenStrainAndPiolaStressInversion (the Eigen reference);
// and validation of the batch input.
#include <Eigen/SVD>
#include <limits>

#include <tessera/core/error.hpp>
#include <tessera/core/fem_tetra_constraints.hpp>
#include <tessera/core/fem_triangle_constraints.hpp>
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

// The lane formulas themselves, compiled here for the static SIMD target only.
#include "../../core/src/kernels/fem-inl.h"

#include "batch_test_support.hpp"

namespace tessera {
namespace fem_batch_tests {

using test::Random;
using PBD = PositionBasedDynamics;
namespace lanes = HWY_NAMESPACE;
namespace hn = hwy::HWY_NAMESPACE;

// ------------------------------------------------------------------------------ lane SVD
/// Relative accuracy expected of the lane SVD (a few hundred flops on FᵀF).
constexpr Real kSvdTolerance = kDoublePrecision ? Real(1e-11) : Real(2e-5);

Matrix3r from_diagonal(Random& random, Real s0, Real s1, Real s2) {
  return random.rotation() * Vector3r(s0, s1, s2).asDiagonal() * random.rotation().transpose();
}

/// Random matrices and the near-degenerate cases: repeated, zero and tiny singular values,
/// inverted, huge and tiny scales, zero.
std::vector<Matrix3r> test_matrices(Random& random) {
  std::vector<Matrix3r> matrices;
  for (int i = 0; i < 300; ++i) {
    Matrix3r m;
    for (int r = 0; r < 3; ++r) m.row(r) = random.vector().transpose();
    matrices.push_back(m);
  }
  const Real cases[][3] = {{3, 2, 1},    {1, 1, Real(0.5)}, {2, Real(0.5), Real(0.5)},
                           {1, 1, 1},    {1, Real(0.5), 0}, {1, 0, 0},
                           {1, Real(0.7), Real(-0.3)},      {1, 1, Real(-1e-5)},
                           {1, Real(1e-4), Real(1e-4)},     {1, Real(0.3), Real(-0.3)},
                           {1, Real(1 - 1e-4), Real(0.2)},  {Real(0.05), Real(0.04), Real(-0.03)}};
  for (const auto& s : cases)
    for (const Real scale : {Real(1), Real(1e6), Real(1e-6)})
      for (int i = 0; i < 10; ++i)
        matrices.push_back(scale * from_diagonal(random, s[0], s[1], s[2]));
  matrices.push_back(Matrix3r::Zero());
  matrices.push_back(Matrix3r::Identity());
  matrices.push_back(-Matrix3r::Identity());
  return matrices;
}

::testing::AssertionResult is_rotation(const Matrix3r& r) {
  const Real error = (r.transpose() * r - Matrix3r::Identity()).cwiseAbs().maxCoeff();
  if (error > 10 * kSvdTolerance || std::abs(r.determinant() - 1) > 10 * kSvdTolerance)
    return ::testing::AssertionFailure() << "not a rotation: |RᵀR - I| = " << error
                                         << ", det = " << r.determinant() << "\n" << r;
  return ::testing::AssertionSuccess();
}

void expect_valid_svd(const Matrix3r& F, const Matrix3r& u, const Vector3r& sigma,
                      const Matrix3r& v) {
  SCOPED_TRACE(::testing::Message() << "F =\n" << F);
  EXPECT_TRUE(is_rotation(u));
  EXPECT_TRUE(is_rotation(v));
  const Real scale = std::max(F.cwiseAbs().maxCoeff(), std::numeric_limits<Real>::min());
  EXPECT_LE((u * sigma.asDiagonal() * v.transpose() - F).cwiseAbs().maxCoeff(),
            10 * kSvdTolerance * scale);
  // Same singular values as Eigen's JacobiSVD, largest first; the sign of det F on the last.
  const Eigen::JacobiSVD<Matrix3r> reference(F);
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(std::abs(sigma[i]), reference.singularValues()[i], 10 * kSvdTolerance * scale);
  EXPECT_GE(sigma[0] + kSvdTolerance * scale, sigma[1]);
  EXPECT_GE(sigma[1] + kSvdTolerance * scale, std::abs(sigma[2]));
  const Real det = F.determinant();
  if (std::abs(det) > Real(1e-3) * scale * scale * scale) {
    EXPECT_EQ(sigma[2] < 0, det < 0);
  }
}

TEST(LaneSvd, MatchesEigenOnOneLane) {
  Random random(1);
  for (const Matrix3r& F : test_matrices(random)) {
    const lanes::Svd3<Real> svd = lanes::svd3<Real>(lanes::from_eigen(F));
    expect_valid_svd(F, lanes::to_eigen(svd.u), lanes::to_eigen(svd.sigma), lanes::to_eigen(svd.v));
  }
}

TEST(LaneSvd, EveryLaneOfAVectorEqualsTheOneLaneResult) {
  // The static target's vectors: each lane must give what the one-lane instantiation gives
  // (same formula, no cross-lane effects), whatever its neighbours hold.
  using D = hn::ScalableTag<Real>;
  const D d;
  const std::size_t width = hn::Lanes(d);
  Random random(2);
  const std::vector<Matrix3r> matrices = test_matrices(random);
  for (std::size_t first = 0; first + width <= matrices.size(); first += width) {
    HWY_ALIGN Real entries[9][kMaxLanes];
    for (std::size_t lane = 0; lane < width; ++lane)
      for (int j = 0; j < 3; ++j)
        for (int r = 0; r < 3; ++r) entries[3 * j + r][lane] = matrices[first + lane](r, j);
    lanes::Mat3<hn::Vec<D>> F;
    for (int j = 0; j < 3; ++j)
      F.col[j] = {hn::Load(d, entries[3 * j]), hn::Load(d, entries[3 * j + 1]),
                  hn::Load(d, entries[3 * j + 2])};
    const lanes::Svd3<hn::Vec<D>> svd = lanes::svd3(F);
    HWY_ALIGN Real sigma[3][kMaxLanes];
    hn::Store(svd.sigma.x, d, sigma[0]);
    hn::Store(svd.sigma.y, d, sigma[1]);
    hn::Store(svd.sigma.z, d, sigma[2]);
    for (std::size_t lane = 0; lane < width; ++lane) {
      const lanes::Svd3<Real> one = lanes::svd3<Real>(lanes::from_eigen(matrices[first + lane]));
      const Real scale = matrices[first + lane].cwiseAbs().maxCoeff();
      EXPECT_NEAR(sigma[0][lane], one.sigma.x, kSvdTolerance * scale);
      EXPECT_NEAR(sigma[1][lane], one.sigma.y, kSvdTolerance * scale);
      EXPECT_NEAR(sigma[2][lane], one.sigma.z, kSvdTolerance * scale);
    }
  }
}

// ------------------------------------------------------- inversion-robust material vs Eigen
struct RestTet {
  std::array<Vector3r, 4> p;
  Real volume;
  Matrix3r inv_rest;
};

RestTet random_rest_tet(Random& random) {
  RestTet t;
  const Vector3r a = random.vector(-5, 5);
  const Matrix3r frame = random.rotation() * Real(random.uniform(Real(0.5), 2));
  t.p = {a, a + frame.col(0), a + frame.col(1) + Real(0.3) * frame.col(0),
         a + frame.col(2) - Real(0.2) * frame.col(1)};
  if (random.uniform(0, 1) < Real(0.5)) std::swap(t.p[1], t.p[2]);  // both orientations
  EXPECT_TRUE(PBD::init_FEMTetraConstraint(t.p[0], t.p[1], t.p[2], t.p[3], t.volume, t.inv_rest));
  return t;
}

enum class Deformation { mild, compressed, flat, inverted, deeply_inverted };

/// Moves the movable vertices of a rest tetrahedron (w > 0) into the given kind of shape.
/// Pushing one vertex through the opposite face leaves the face's plane isometric, so one
/// singular value of F is 1 and, the further the vertex goes, the closer |σ2| gets to it: a
/// tie that makes Irving et al.'s split (which direction carries the inversion) ill-posed
/// (the material is discontinuous there, and any two implementations may split it
/// differently). The deeply inverted shape is therefore also squashed sideways, which keeps
/// the singular values apart as they are in real simulations.
std::array<Vector3r, 4> deform(const std::array<Vector3r, 4>& rest,
                               const std::array<Real, 4>& w, Deformation kind,
                               Random& random) {
  std::array<Vector3r, 4> p = rest;
  const Vector3r centroid = (rest[0] + rest[1] + rest[2] + rest[3]) / 4;
  auto move = [&](int i, const Vector3r& to) {
    if (w[std::size_t(i)] > 0) p[std::size_t(i)] = to;
  };
  switch (kind) {
    case Deformation::mild:
      for (int i = 0; i < 4; ++i) move(i, rest[std::size_t(i)] + Real(0.15) * random.vector());
      break;
    case Deformation::compressed: {  // squashed to 2-8 % along a random direction
      const Vector3r n = random.unit_vector();
      const Real keep = random.uniform(Real(0.02), Real(0.08));
      for (int i = 0; i < 4; ++i) {
        const Vector3r r = rest[std::size_t(i)] - centroid;
        move(i, centroid + r - (1 - keep) * r.dot(n) * n);
      }
      break;
    }
    case Deformation::flat:
    case Deformation::inverted:
    case Deformation::deeply_inverted: {  // vertex 3 onto / through the opposite face
      const Vector3r n = (rest[1] - rest[0]).cross(rest[2] - rest[0]).normalized();
      const Real height = (rest[3] - rest[0]).dot(n);
      const Real through = kind == Deformation::flat       ? Real(1)
                           : kind == Deformation::inverted ? random.uniform(Real(1.2), Real(1.8))
                                                           : random.uniform(Real(2.5), 4);
      if (w[3] > 0) {
        move(3, rest[3] - through * height * n);
      } else {  // vertex 3 is static: move the face instead
        for (int i = 0; i < 3; ++i) move(i, rest[std::size_t(i)] + through * height * n);
      }
      if (kind == Deformation::deeply_inverted) {
        const Vector3r side = n.cross(random.unit_vector()).normalized();
        const Real keep = random.uniform(Real(0.3), Real(0.6));
        const std::array<Vector3r, 4> pushed = p;
        for (int i = 0; i < 4; ++i) {
          const Vector3r r = pushed[std::size_t(i)] - centroid;
          move(i, centroid + r - (1 - keep) * r.dot(side) * side);
        }
      }
      break;
    }
  }
  return p;
}

TEST(LaneInversionMaterial, MatchesTheEigenReference) {
  Random random(3);
  const Real mu = 350, lambda = 580;
  for (int trial = 0; trial < 200; ++trial) {
    const RestTet t = random_rest_tet(random);
    const Deformation kind = Deformation(trial % 5);
    const auto p = deform(t.p, {1, 1, 1, 1}, kind, random);
    Matrix3r epsilon, sigma;
    Real energy;
    PBD::computeGreenStrainAndPiolaStressInversion(p[0], p[1], p[2], p[3], t.inv_rest, t.volume,
                                                   mu, lambda, epsilon, sigma, energy);
    const lanes::Vec3<Real> x[4] = {lanes::from_eigen(p[0]), lanes::from_eigen(p[1]),
                                    lanes::from_eigen(p[2]), lanes::from_eigen(p[3])};
    const auto lane = lanes::green_strain_material_inversion<Real>(
        lanes::deformation_gradient<Real>(x, lanes::from_eigen(t.inv_rest)), t.volume, mu,
        lambda);
    SCOPED_TRACE(::testing::Message() << "trial " << trial);
    const Real stress_scale = sigma.cwiseAbs().maxCoeff() + mu;
    EXPECT_LE((lanes::to_eigen(lane.stress) - sigma).cwiseAbs().maxCoeff(),
              100 * kSvdTolerance * stress_scale);
    EXPECT_LE((lanes::to_eigen(lane.strain) - epsilon).cwiseAbs().maxCoeff(),
              100 * kSvdTolerance * (1 + epsilon.cwiseAbs().maxCoeff()));
    EXPECT_NEAR(lane.energy, energy, 100 * kSvdTolerance * (energy + mu * t.volume));
  }
}

TEST(FEMTetraBatch, InvertedElementsProjectLikeTheEigenReference) {
  // The batch kernel (lane SVD) against the projection written from the Eigen-based material.
  test::for_each_simd_target([](const std::string&) {
    Random random(4);
    const Real E = 2000, nu = Real(0.35);
    const Real mu = E / (2 * (1 + nu)), lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
    for (int trial = 0; trial < 40; ++trial) {
      const RestTet t = random_rest_tet(random);
      const std::array<Real, 4> w = {1, Real(0.5), 2, Real(1.5)};
      const Deformation kind = trial % 2 ? Deformation::inverted : Deformation::deeply_inverted;
      const auto p = deform(t.p, w, kind, random);
      Matrix3r epsilon, sigma;
      Real energy;
      PBD::computeGreenStrainAndPiolaStressInversion(p[0], p[1], p[2], p[3], t.inv_rest,
                                                     t.volume, mu, lambda, epsilon, sigma, energy);
      std::array<Vector3r, 4> gradient;
      PBD::computeGradCGreen(t.volume, t.inv_rest, sigma, gradient.data());
      Real weighted = 0;
      for (int i = 0; i < 4; ++i) weighted += w[i] * gradient[i].squaredNorm();

      const std::vector<Vector3r> rest(t.p.begin(), t.p.end());
      const std::vector<ParticleIndex> indices = {0, 1, 2, 3};
      FEMTetraConstraintInput input;
      input.particles = indices;
      input.rest_positions = rest;
      input.youngs_modulus = E;
      input.poisson_ratio = nu;
      FEMTetraConstraints constraints = make_fem_tetra_constraints(input);
      ParticleState state(std::vector<Vector3r>(p.begin(), p.end()),
                          std::vector<Real>(w.begin(), w.end()));
      project_fem_tetra_constraints(ParticleArrays::of(state), constraints, 0, 1, {});
      for (int i = 0; i < 4; ++i)
        EXPECT_TRUE(test::near_relative(state.position(std::size_t(i)) - p[std::size_t(i)],
                                        -energy / weighted * w[i] * gradient[i],
                                        10 * test::kRoundOff))
            << "trial " << trial << " vertex " << i;
    }
  });
}

// ------------------------------------------------------------------ batch vs scalar: tetra
struct TetScene {
  test::DisjointConstraintSet<4> set;
  std::vector<Vector3r> rest;
};

/// Rest tetrahedra on disjoint particles, then each one deformed in one of the five ways.
TetScene random_tet_scene(Random& random, std::size_t count) {
  TetScene scene;
  scene.set = test::make_disjoint_constraints<4>(random, count, Real(0.2), [](Random& r) {
    return random_rest_tet(r).p;
  });
  scene.rest = scene.set.positions;
  for (std::size_t c = 0; c < count; ++c) {
    std::array<Vector3r, 4> rest;
    std::array<Real, 4> w;
    for (int k = 0; k < 4; ++k) {
      const ParticleIndex i = scene.set.indices[4 * c + std::size_t(k)];
      rest[std::size_t(k)] = scene.rest[i];
      w[std::size_t(k)] = scene.set.inverse_masses[i];
    }
    const auto p = deform(rest, w, Deformation(random.integer(0, 4)), random);
    for (int k = 0; k < 4; ++k) {
      const ParticleIndex i = scene.set.indices[4 * c + std::size_t(k)];
      if (scene.set.inverse_masses[i] > 0) scene.set.positions[i] = p[std::size_t(k)];
    }
  }
  return scene;
}

FEMTetraConstraints build_tets(const TetScene& scene, Random& random, bool handle_inversion) {
  FEMTetraConstraintInput input;
  input.particles = scene.set.indices;
  input.rest_positions = scene.rest;
  input.handle_inversion = handle_inversion;
  FEMTetraConstraints constraints = make_fem_tetra_constraints(input);
  for (std::size_t c = 0; c < scene.set.count; ++c) {
    constraints.youngs_modulus[c] = random.uniform(100, 5000);
    constraints.poisson_ratio[c] = random.uniform(Real(-0.3), Real(0.45));
    constraints.compliance[c] = random.uniform(0, 1) < Real(0.2) ? 0 : random.uniform(Real(1e-5), Real(1e-2));
  }
  return constraints;
}

TEST(FEMTetraBatch, MatchesScalarApiOnEveryTarget) {
  test::for_each_simd_target([](const std::string&) {
    for (unsigned seed = 1; seed <= 6; ++seed) {
      Random random(200 + seed);
      const bool handle_inversion = seed % 3 != 0;
      const std::size_t count = std::size_t(random.integer(1, 300));
      const TetScene scene = random_tet_scene(random, count);
      const auto& set = scene.set;
      FEMTetraConstraints constraints = build_tets(scene, random, handle_inversion);
      const auto [begin, end] = test::random_range(random, count);
      for (const auto semantics :
           {ConstraintSemantics::stiffness, ConstraintSemantics::compliance}) {
        const ProjectionSettings settings{semantics, Real(1) / 120};
        ParticleState state(set.positions, set.inverse_masses);
        std::vector<Vector3r> expected = set.positions;
        std::vector<Real> expected_lambda(count, Real(-0.125));
        std::fill(constraints.lambda.begin(), constraints.lambda.begin() + long(count),
                  Real(-0.125));
        for (std::size_t c = begin; c < end; ++c) {
          ParticleIndex i[4];
          Vector3r x[4];
          Real w[4];
          for (int k = 0; k < 4; ++k) {
            i[k] = set.indices[4 * c + std::size_t(k)];
            x[k] = expected[i[k]];
            w[k] = set.inverse_masses[i[k]];
          }
          Matrix3r rest_inverse;
          for (int k = 0; k < 3; ++k)
            for (int j = 0; j < 3; ++j) rest_inverse(k, j) = constraints.rest_inverse[3 * k + j][c];
          Vector3r corr[4];
          if (semantics == ConstraintSemantics::stiffness)
            PBD::solve_FEMTetraConstraint(x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3],
                                          constraints.volume[c], rest_inverse,
                                          constraints.youngs_modulus[c],
                                          constraints.poisson_ratio[c], handle_inversion,
                                          corr[0], corr[1], corr[2], corr[3]);
          else
            XPBD::solve_FEMTetraConstraint(x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3],
                                           constraints.volume[c], rest_inverse,
                                           constraints.poisson_ratio[c],
                                           constraints.compliance[c], handle_inversion,
                                           settings.dt, expected_lambda[c], corr[0], corr[1],
                                           corr[2], corr[3]);
          for (int k = 0; k < 4; ++k)
            if (w[k] > 0) expected[i[k]] += corr[k];
        }
        project_fem_tetra_constraints(ParticleArrays::of(state), constraints, begin, end,
                                      settings);
        EXPECT_TRUE(test::positions_match(state, expected, 10)) << "seed " << seed;
        for (std::size_t c = 0; c < count; ++c) {
          if (semantics == ConstraintSemantics::compliance && c >= begin && c < end) {
            EXPECT_NEAR(constraints.lambda[c], expected_lambda[c],
                        10 * test::kBatchTolerance * (1 + std::abs(expected_lambda[c])));
          } else {
            EXPECT_EQ(constraints.lambda[c], Real(-0.125)) << "λ outside the range changed";
          }
        }
        if (semantics == ConstraintSemantics::compliance)
          test::expect_lambda_starting_at_zero_reads_no_lambda(
              ParticleState(set.positions, set.inverse_masses), constraints, begin, end,
              settings, project_fem_tetra_constraints);
      }
    }
  });
}

TEST(FEMTetraBatch, InvertedElementsRecoverOverRepeatedSweeps) {
  for (const auto semantics : {ConstraintSemantics::stiffness, ConstraintSemantics::compliance}) {
    Random random(9);
    std::vector<Vector3r> rest, current;
    std::vector<ParticleIndex> indices;
    for (int c = 0; c < 37; ++c) {
      const RestTet t = random_rest_tet(random);
      const auto p = deform(t.p, {1, 1, 1, 1}, Deformation::inverted, random);
      for (int k = 0; k < 4; ++k) {
        indices.push_back(ParticleIndex(rest.size()));
        rest.push_back(t.p[std::size_t(k)]);
        current.push_back(p[std::size_t(k)]);
      }
    }
    FEMTetraConstraintInput input;
    input.particles = indices;
    input.rest_positions = rest;
    input.youngs_modulus = 1000;
    FEMTetraConstraints constraints = make_fem_tetra_constraints(input);
    std::fill(constraints.compliance.begin(), constraints.compliance.end(), Real(0));
    ParticleState state(current, std::vector<Real>(current.size(), Real(1)));
    for (int sweep = 0; sweep < 150; ++sweep)
      project_fem_tetra_constraints(ParticleArrays::of(state), constraints, 0, 37,
                                    {semantics, Real(1) / 60});
    for (std::size_t c = 0; c < 37; ++c) {
      Vector3r x[4], r[4];
      for (int k = 0; k < 4; ++k) {
        x[k] = state.position(indices[4 * c + std::size_t(k)]);
        r[k] = rest[indices[4 * c + std::size_t(k)]];
      }
      const Real volume = (x[1] - x[0]).cross(x[2] - x[0]).dot(x[3] - x[0]);
      const Real rest_volume = (r[1] - r[0]).cross(r[2] - r[0]).dot(r[3] - r[0]);
      EXPECT_GT(volume / rest_volume, Real(0.5)) << "constraint " << c << " still inverted";
    }
  }
}

// --------------------------------------------------------------- batch vs scalar: triangle
TEST(FEMTriangleBatch, MatchesScalarApiOnEveryTarget) {
  test::for_each_simd_target([](const std::string&) {
    for (unsigned seed = 1; seed <= 6; ++seed) {
      Random random(300 + seed);
      const std::size_t count = std::size_t(random.integer(1, 300));
      auto set = test::make_disjoint_constraints<3>(random, count, Real(0.2), [](Random& r) {
        const Vector3r a = r.vector(-5, 5);
        const Matrix3r frame = r.rotation() * Real(r.uniform(Real(0.5), 2));
        return std::array<Vector3r, 3>{a, a + frame.col(0), a + frame.col(1) + Real(0.4) * frame.col(0)};
      });
      const std::vector<Vector3r> rest = set.positions;
      for (std::size_t p = 0; p < set.positions.size(); ++p)
        if (set.inverse_masses[p] > 0) set.positions[p] += Real(0.25) * random.vector();
      FEMTriangleConstraintInput input;
      input.particles = set.indices;
      input.rest_positions = rest;
      FEMTriangleConstraints constraints = make_fem_triangle_constraints(input);
      for (std::size_t c = 0; c < count; ++c) {  // positive definite orthotropic materials
        constraints.youngs_modulus_x[c] = random.uniform(100, 2000);
        constraints.youngs_modulus_y[c] = random.uniform(100, 2000);
        constraints.youngs_modulus_shear[c] = random.uniform(50, 800);
        constraints.poisson_ratio_xy[c] = random.uniform(0, Real(0.45));
        constraints.poisson_ratio_yx[c] = random.uniform(0, Real(0.45));
      }
      // A few elements exactly at rest (true, zero corrections in both paths).
      for (std::size_t c = 0; c < count; c += 17)
        for (int k = 0; k < 3; ++k) {
          const ParticleIndex p = set.indices[3 * c + std::size_t(k)];
          set.positions[p] = rest[p];
        }
      const auto [begin, end] = test::random_range(random, count);
      std::vector<Vector3r> expected = set.positions;
      for (std::size_t c = begin; c < end; ++c) {
        ParticleIndex i[3];
        for (int k = 0; k < 3; ++k) i[k] = set.indices[3 * c + std::size_t(k)];
        Matrix2r rest_inverse;
        for (int k = 0; k < 2; ++k)
          for (int j = 0; j < 2; ++j) rest_inverse(k, j) = constraints.rest_inverse[2 * k + j][c];
        Vector3r corr[3];
        PBD::solve_FEMTriangleConstraint(
            expected[i[0]], set.inverse_masses[i[0]], expected[i[1]], set.inverse_masses[i[1]],
            expected[i[2]], set.inverse_masses[i[2]], constraints.area[c], rest_inverse,
            constraints.youngs_modulus_x[c], constraints.youngs_modulus_y[c],
            constraints.youngs_modulus_shear[c], constraints.poisson_ratio_xy[c],
            constraints.poisson_ratio_yx[c], corr[0], corr[1], corr[2]);
        for (int k = 0; k < 3; ++k)
          if (set.inverse_masses[i[k]] > 0) expected[i[k]] += corr[k];
      }
      ParticleState state(set.positions, set.inverse_masses);
      project_fem_triangle_constraints(ParticleArrays::of(state), constraints, begin, end, {});
      EXPECT_TRUE(test::positions_match(state, expected, 10)) << "seed " << seed;
    }
  });
}

TEST(FEMBatch, BitwiseReproducibleAndStaticParticlesUntouched) {
  test::for_each_simd_target([](const std::string&) {
    Random random(77);
    const TetScene scene = random_tet_scene(random, 203);
    FEMTetraConstraints constraints = build_tets(scene, random, true);
    for (const auto semantics :
         {ConstraintSemantics::stiffness, ConstraintSemantics::compliance}) {
      ParticleState first(scene.set.positions, scene.set.inverse_masses), second = first;
      const ParticleState before = first;
      // Each run has its own λ (XPBD accumulates it across iterations).
      FEMTetraConstraints other = constraints;
      project_fem_tetra_constraints(ParticleArrays::of(first), constraints, 50, 50,
                                    {semantics, Real(0.01)});
      EXPECT_TRUE(test::same_bits(first, before));
      for (int iteration = 0; iteration < 4; ++iteration) {
        project_fem_tetra_constraints(ParticleArrays::of(first), constraints, 0, 203,
                                      {semantics, Real(0.01)});
        project_fem_tetra_constraints(ParticleArrays::of(second), other, 0, 203,
                                      {semantics, Real(0.01)});
      }
      EXPECT_TRUE(test::same_bits(first, second));
      EXPECT_TRUE(constraints.lambda == other.lambda);
      EXPECT_FALSE(test::same_bits(first, before));
      for (std::size_t i = 0; i < scene.set.positions.size(); ++i) {
        if (scene.set.inverse_masses[i] == 0) {
          EXPECT_EQ(first.position(i), before.position(i));
        }
        EXPECT_TRUE(first.position(i).allFinite());
      }
    }
  });
}

// ------------------------------------------------------------------ validation at the door
using test::error_of;

TEST(FEMBatchValidation, NamesTheConstraintAndTheProblem) {
  const std::vector<Vector3r> rest = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0),
                                      Vector3r(0, 0, 1), Vector3r(2, 0, 0),
                                      Vector3r(0, Real(NAN), 0)};
  auto tetra = [&](std::vector<ParticleIndex> indices, Real E = 1, Real nu = Real(0.3)) {
    return error_of([&] {
      FEMTetraConstraintInput input;
      input.particles = indices;
      input.rest_positions = rest;
      input.youngs_modulus = E;
      input.poisson_ratio = nu;
      make_fem_tetra_constraints(input);
    });
  };
  EXPECT_EQ(tetra({0, 1, 2, 3, 0, 1, 2, 7}),
            "FEM tetra constraint 1: particle index 7 is out of range (6 particles)");
  EXPECT_EQ(tetra({0, 1, 2, 3, 0, 1, 1, 3}), "FEM tetra constraint 1: particle 1 appears twice");
  EXPECT_EQ(tetra({0, 1, 2}), "FEM tetra constraints: 3 particle indices is not a multiple of 4");
  EXPECT_EQ(tetra({0, 1, 2, 3, 0, 1, 4, 3}),
            "FEM tetra constraint 1: rest tetrahedron is flat (zero volume)");
  EXPECT_EQ(tetra({0, 1, 5, 3}), "FEM tetra constraint 0: rest position is not finite");
  EXPECT_EQ(tetra({0, 1, 2, 3}, 0), "FEM tetra constraints: Young's modulus is 0, must be finite and > 0");
  EXPECT_EQ(tetra({0, 1, 2, 3}, Real(INFINITY)),
            "FEM tetra constraints: Young's modulus is inf, must be finite and > 0");
  EXPECT_EQ(tetra({0, 1, 2, 3}, 1, Real(0.5)),
            "FEM tetra constraints: Poisson ratio is 0.5, must lie in (-1, 0.5)");
  EXPECT_EQ(tetra({0, 1, 2, 3}, 1, Real(-1)),
            "FEM tetra constraints: Poisson ratio is -1, must lie in (-1, 0.5)");
  EXPECT_EQ(tetra({0, 1, 2, 3}, 1, Real(NAN)),
            "FEM tetra constraints: Poisson ratio is nan, must lie in (-1, 0.5)");
  // An inverted rest tetrahedron (other orientation) is accepted; its compliance is 1/E.
  EXPECT_EQ(tetra({0, 2, 1, 3}), "");
  {
    const std::vector<ParticleIndex> indices = {0, 2, 1, 3};
    FEMTetraConstraintInput input;
    input.particles = indices;
    input.rest_positions = rest;
    input.youngs_modulus = 400;
    const FEMTetraConstraints constraints = make_fem_tetra_constraints(input);
    EXPECT_FLOAT_EQ(constraints.compliance[0], Real(1) / 400);
    EXPECT_FLOAT_EQ(constraints.volume[0], Real(1) / 6);
  }

  auto triangle = [&](std::vector<ParticleIndex> indices, Real ex = 1, Real nxy = Real(0.3),
                      Real nyx = Real(0.3)) {
    return error_of([&] {
      FEMTriangleConstraintInput input;
      input.particles = indices;
      input.rest_positions = rest;
      input.youngs_modulus_x = ex;
      input.poisson_ratio_xy = nxy;
      input.poisson_ratio_yx = nyx;
      make_fem_triangle_constraints(input);
    });
  };
  EXPECT_EQ(triangle({0, 1, 8}),
            "FEM triangle constraint 0: particle index 8 is out of range (6 particles)");
  EXPECT_EQ(triangle({0, 1, 2, 2, 1, 2}), "FEM triangle constraint 1: particle 2 appears twice");
  EXPECT_EQ(triangle({0, 1, 2, 0}),
            "FEM triangle constraints: 4 particle indices is not a multiple of 3");
  EXPECT_EQ(triangle({0, 1, 2, 0, 1, 4}), "FEM triangle constraint 1: rest triangle has zero area");
  EXPECT_EQ(triangle({0, 1, 5}), "FEM triangle constraint 0: rest position is not finite");
  EXPECT_EQ(triangle({0, 1, 2}, Real(NAN)),
            "FEM triangle constraints: Young's modulus x is not finite");
  const std::string not_positive_definite =
      "FEM triangle constraints: material is not positive definite (E_x, E_y, G > 0, ν_xy ν_yx "
      "< 1 and a positive normal-stress determinant are required)";
  EXPECT_EQ(triangle({0, 1, 2}, -1), not_positive_definite);
  EXPECT_EQ(triangle({0, 1, 2}, 1, Real(1.2), Real(0.9)), not_positive_definite);
  EXPECT_EQ(triangle({0, 1, 2}, 1, Real(0.1), Real(1.95)), not_positive_definite);
  EXPECT_EQ(triangle({0, 2, 1}), "");
}

TEST(FEMBatchValidation, RangeAndParticleCountAreChecked) {
  const std::vector<Vector3r> rest = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0)};
  const std::vector<ParticleIndex> indices = {0, 1, 2};
  FEMTriangleConstraintInput input;
  input.particles = indices;
  input.rest_positions = rest;
  FEMTriangleConstraints constraints = make_fem_triangle_constraints(input);
  ParticleState three(rest, std::vector<Real>{1, 1, 1});
  EXPECT_THROW(project_fem_triangle_constraints(ParticleArrays::of(three), constraints, 1, 0, {}),
               InvalidInput);
  ParticleState two(2);
  EXPECT_THROW(project_fem_triangle_constraints(ParticleArrays::of(two), constraints, 0, 1, {}),
               InvalidInput);
}

}  // namespace fem_batch_tests
}  // namespace tessera
