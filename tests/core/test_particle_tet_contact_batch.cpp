// The batched particle–tet contact kernels (init in make_, position solve, friction velocity
// solve) against the scalar API applied contact by contact, on every SIMD target the machine
// has, plus validation of the batch input.
#include <tessera/core/error.hpp>
#include <tessera/core/particle_tet_contact_constraints.hpp>
#include <tessera/core/position_based_dynamics.hpp>

#include "batch_test_support.hpp"

namespace tessera {
namespace particle_tet_contact_batch_tests {

using test::Random;
using PBD = PositionBasedDynamics;
using Info = Eigen::Matrix<Real, 3, 3, Eigen::DontAlign>;

/// A particle (slot 0) just below the top face of a jittered tet (slots 1..4).
test::DisjointConstraintSet<5> random_contacts(Random& random, std::size_t count) {
  return test::make_disjoint_constraints<5>(random, count, Real(0.2), [](Random& r) {
    const Vector3r origin = r.vector(-5, 5);
    std::array<Vector3r, 5> p;
    p[1] = origin;
    p[2] = origin + Vector3r(1, 0, 0);
    p[3] = origin + Vector3r(0, 1, 0);
    p[4] = origin + Vector3r(0, 0, 1);
    for (int k = 1; k < 5; ++k) p[std::size_t(k)] += Real(0.05) * r.vector();
    p[0] = origin + Vector3r(Real(0.2), Real(0.2), r.uniform(Real(-0.1), Real(0.4)));
    return p;
  });
}

struct ContactScene {
  test::DisjointConstraintSet<5> set;
  std::vector<Vector3r> barycentric, normals, velocities;
  ParticleState state;
};

ContactScene make_scene(Random& random, std::size_t count) {
  ContactScene scene{random_contacts(random, count), {}, {}, {}, {}};
  for (std::size_t c = 0; c < count; ++c) {
    scene.barycentric.emplace_back(random.uniform(Real(0.1), Real(0.3)),
                                   random.uniform(Real(0.1), Real(0.3)),
                                   random.uniform(Real(0.1), Real(0.3)));
    // Sometimes a purely normal approach (no tangent), otherwise a random direction.
    scene.normals.push_back(random.uniform(0, 1) < Real(0.8) ? random.unit_vector()
                                                              : Vector3r(0, 0, 1));
  }
  scene.state = ParticleState(scene.set.positions, scene.set.inverse_masses);
  for (std::size_t i = 0; i < scene.set.positions.size(); ++i) {
    const Vector3r v =
        random.uniform(0, 1) < Real(0.1) ? Vector3r::Zero() : random.vector(-2, 2);
    scene.velocities.push_back(v);
    scene.state.velocity_x[i] = v.x();
    scene.state.velocity_y[i] = v.y();
    scene.state.velocity_z[i] = v.z();
  }
  return scene;
}

/// The scalar arguments of contact c: inverse masses and the tet's points from `points`.
struct ScalarContact {
  Real w0;
  std::array<Real, 4> w;
  Vector3r p0;
  std::array<Vector3r, 4> p;
  std::array<ParticleIndex, 5> index;
};

ScalarContact scalar_contact(const test::DisjointConstraintSet<5>& set,
                             const std::vector<Vector3r>& points, std::size_t c) {
  ScalarContact s;
  for (int k = 0; k < 5; ++k) s.index[std::size_t(k)] = set.indices[5 * c + std::size_t(k)];
  s.w0 = set.inverse_masses[s.index[0]];
  s.p0 = points[s.index[0]];
  for (int k = 0; k < 4; ++k) {
    s.w[std::size_t(k)] = set.inverse_masses[s.index[std::size_t(k) + 1]];
    s.p[std::size_t(k)] = points[s.index[std::size_t(k) + 1]];
  }
  return s;
}

Info scalar_info(const ContactScene& scene, std::size_t c) {
  const ScalarContact s = scalar_contact(scene.set, scene.velocities, c);
  const ScalarContact x = scalar_contact(scene.set, scene.set.positions, c);
  Info info;
  PBD::init_ParticleTetContactConstraint(s.w0, x.p0, s.p0, s.w.data(), x.p.data(), s.p.data(),
                                         scene.barycentric[c], scene.normals[c], info);
  return info;
}

bool near(Real a, Real b) {
  return std::abs(a - b) <= test::kBatchTolerance * (1 + std::abs(b));
}

::testing::AssertionResult velocities_match(const ParticleState& state,
                                            const std::vector<Vector3r>& expected) {
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const Vector3r v = state.velocity(i);
    if (!v.allFinite() ||
        (v - expected[i]).norm() > test::kBatchTolerance * std::max(Real(1), expected[i].norm()))
      return ::testing::AssertionFailure() << "particle " << i << ": batch " << v.transpose()
                                           << ", scalar " << expected[i].transpose();
  }
  return ::testing::AssertionSuccess();
}

TEST(ParticleTetContactBatch, InitMatchesScalarApiOnEveryTarget) {
  test::for_each_simd_target([](const std::string&) {
    for (unsigned seed = 1; seed <= 4; ++seed) {
      Random random(seed);
      const std::size_t count = std::size_t(random.integer(1, 200));
      const ContactScene scene = make_scene(random, count);
      const ParticleTetContacts contacts = make_particle_tet_contacts(
          {scene.set.indices, scene.barycentric, scene.normals, Real(0.4)}, scene.state);
      ASSERT_EQ(contacts.size(), count);
      for (std::size_t c = 0; c < count; ++c) {
        const Info info = scalar_info(scene, c);
        for (int k = 0; k < 3; ++k) {
          EXPECT_TRUE(near(contacts.normal[std::size_t(k)][c], info(k, 0))) << c;
          EXPECT_TRUE(near(contacts.tangent[std::size_t(k)][c], info(k, 1))) << c;
        }
        EXPECT_TRUE(near(contacts.effective_mass[c], info(0, 2))) << c;
        EXPECT_TRUE(near(contacts.max_tangential_impulse[c], info(1, 2))) << c;
        EXPECT_TRUE(near(contacts.normal_speed[c], info(2, 2))) << c;
        EXPECT_EQ(contacts.lambda[c], 0);
        EXPECT_EQ(contacts.friction[c], Real(0.4));
      }
    }
  });
}

TEST(ParticleTetContactBatch, PositionSolveMatchesScalarApiOnEveryTarget) {
  test::for_each_simd_target([](const std::string&) {
    for (unsigned seed = 1; seed <= 6; ++seed) {
      Random random(100 + seed);
      const std::size_t count = std::size_t(random.integer(1, 300));
      const ContactScene scene = make_scene(random, count);
      ParticleTetContacts contacts = make_particle_tet_contacts(
          {scene.set.indices, scene.barycentric, scene.normals}, scene.state);
      // Some contacts start with a positive multiplier, so that a separated contact releases.
      std::vector<Real> expected_lambda(count);
      for (std::size_t c = 0; c < count; ++c)
        contacts.lambda[c] = expected_lambda[c] = random.uniform(0, 1) < Real(0.3)
                                                      ? random.uniform(0, Real(0.2))
                                                      : Real(0);
      const auto [begin, end] = test::random_range(random, count);
      ParticleState state = scene.state;
      std::vector<Vector3r> expected = scene.set.positions;
      for (std::size_t c = begin; c < end; ++c) {
        const ScalarContact s = scalar_contact(scene.set, expected, c);
        Info info = scalar_info(scene, c);
        Vector3r corr0;
        std::array<Vector3r, 4> corr;
        PBD::solve_ParticleTetContactConstraint(s.w0, s.p0, s.w.data(), s.p.data(),
                                                scene.barycentric[c], info, expected_lambda[c],
                                                corr0, corr.data());
        if (s.w0 > 0) expected[s.index[0]] += corr0;
        for (int k = 0; k < 4; ++k)
          if (s.w[std::size_t(k)] > 0)
            expected[s.index[std::size_t(k) + 1]] += corr[std::size_t(k)];
      }
      const std::vector<Real> lambda_before(contacts.lambda.begin(),
                                            contacts.lambda.begin() + long(count));
      project_particle_tet_contacts(ParticleArrays::of(state), contacts, begin, end);
      EXPECT_TRUE(test::positions_match(state, expected, 10));
      for (std::size_t c = 0; c < count; ++c) {
        if (c >= begin && c < end) {
          EXPECT_TRUE(near(contacts.lambda[c], expected_lambda[c])) << c;
          EXPECT_GE(contacts.lambda[c], 0);
        } else {
          EXPECT_EQ(contacts.lambda[c], lambda_before[c]) << "λ outside the range changed";
        }
      }
      test::expect_lambda_starting_at_zero_reads_no_lambda(
          scene.state, contacts, begin, end, ProjectionSettings{},
          project_particle_tet_contacts);
    }
  });
}

TEST(ParticleTetContactBatch, VelocitySolveMatchesScalarApiOnEveryTarget) {
  test::for_each_simd_target([](const std::string&) {
    for (unsigned seed = 1; seed <= 6; ++seed) {
      Random random(200 + seed);
      const std::size_t count = std::size_t(random.integer(1, 300));
      const ContactScene scene = make_scene(random, count);
      ParticleTetContacts contacts = make_particle_tet_contacts(
          {scene.set.indices, scene.barycentric, scene.normals, Real(0.5)}, scene.state);
      const Real dt = Real(1) / 120;
      for (std::size_t c = 0; c < count; ++c) {
        contacts.lambda[c] =
            random.uniform(0, 1) < Real(0.2) ? 0 : random.uniform(0, Real(0.02));
        contacts.friction[c] = random.uniform(0, 1);
      }
      const auto [begin, end] = test::random_range(random, count);
      ParticleState state = scene.state;
      std::vector<Vector3r> expected = scene.velocities;
      for (std::size_t c = begin; c < end; ++c) {
        const ScalarContact s = scalar_contact(scene.set, expected, c);
        const ScalarContact x = scalar_contact(scene.set, scene.set.positions, c);
        Info info = scalar_info(scene, c);
        Vector3r corr0;
        std::array<Vector3r, 4> corr;
        PBD::velocitySolve_ParticleTetContactConstraint(
            s.w0, x.p0, s.p0, s.w.data(), x.p.data(), s.p.data(), scene.barycentric[c],
            contacts.lambda[c] / dt, contacts.friction[c], info, corr0, corr.data());
        if (s.w0 > 0) expected[s.index[0]] += corr0;
        for (int k = 0; k < 4; ++k)
          if (s.w[std::size_t(k)] > 0)
            expected[s.index[std::size_t(k) + 1]] += corr[std::size_t(k)];
      }
      solve_particle_tet_contact_velocities(velocity_arrays_of(state), contacts, begin, end, dt);
      EXPECT_TRUE(velocities_match(state, expected));
      EXPECT_TRUE(test::same_bits(state, scene.state)) << "positions changed";
    }
  });
}

TEST(ParticleTetContactBatch, BitwiseReproducibleAndStaticParticlesUntouched) {
  test::for_each_simd_target([](const std::string&) {
    Random random(42);
    const ContactScene scene = make_scene(random, 257);
    ParticleTetContacts first_contacts = make_particle_tet_contacts(
        {scene.set.indices, scene.barycentric, scene.normals, Real(0.3)}, scene.state);
    ParticleTetContacts second_contacts = first_contacts;
    ParticleState first = scene.state, second = scene.state;
    for (int iteration = 0; iteration < 4; ++iteration) {
      project_particle_tet_contacts(ParticleArrays::of(first), first_contacts, 0, 257);
      project_particle_tet_contacts(ParticleArrays::of(second), second_contacts, 0, 257);
    }
    solve_particle_tet_contact_velocities(velocity_arrays_of(first), first_contacts, 0, 257,
                                          Real(0.01));
    solve_particle_tet_contact_velocities(velocity_arrays_of(second), second_contacts, 0, 257,
                                          Real(0.01));
    EXPECT_TRUE(test::same_bits(first, second));
    EXPECT_EQ(first.velocity_x, second.velocity_x);
    EXPECT_EQ(first_contacts.lambda, second_contacts.lambda);
    bool some_moved = false;
    for (std::size_t i = 0; i < scene.set.positions.size(); ++i) {
      if (scene.set.inverse_masses[i] == 0) {
        EXPECT_EQ(first.position(i), scene.state.position(i));
        EXPECT_EQ(first.velocity(i), scene.state.velocity(i));
      } else {
        some_moved = some_moved || first.position(i) != scene.state.position(i);
      }
    }
    EXPECT_TRUE(some_moved);
  });
}

TEST(ParticleTetContactBatch, PenetrationIsResolvedAndSeparationKept) {
  Random random(9);
  const ContactScene scene = make_scene(random, 100);
  ParticleTetContacts contacts = make_particle_tet_contacts(
      {scene.set.indices, scene.barycentric, scene.normals}, scene.state);
  ParticleState state = scene.state;
  for (int iteration = 0; iteration < 3; ++iteration)
    project_particle_tet_contacts(ParticleArrays::of(state), contacts, 0, 100);
  for (std::size_t c = 0; c < 100; ++c) {
    std::array<Vector3r, 5> p;
    for (int k = 0; k < 5; ++k)
      p[std::size_t(k)] = state.position(scene.set.indices[5 * c + std::size_t(k)]);
    const Vector3r& bary = scene.barycentric[c];
    const Vector3r point =
        (1 - bary.sum()) * p[1] + bary[0] * p[2] + bary[1] * p[3] + bary[2] * p[4];
    const Real C = scene.normals[c].dot(p[0] - point);
    if (contacts.effective_mass[c] > 0) {
      EXPECT_GE(C, -10 * test::kRoundOff) << c;
    }
    EXPECT_GE(contacts.lambda[c], 0);
  }
}

// ------------------------------------------------------------------ validation at the door
std::string error_of(const ParticleTetContactInput& input, const ParticleState& state) {
  return test::error_of([&] { make_particle_tet_contacts(input, state); });
}

TEST(ParticleTetContactBatchValidation, NamesTheContactAndTheProblem) {
  std::vector<Vector3r> points(7, Vector3r::Zero());
  for (std::size_t i = 0; i < points.size(); ++i) points[i] = Vector3r(Real(i), 0, 0);
  ParticleState state(points, std::vector<Real>(7, 1));
  const std::vector<ParticleIndex> two = {0, 1, 2, 3, 4, 5, 1, 2, 3, 4};
  const std::vector<Vector3r> bary(2, Vector3r(Real(0.25), Real(0.25), Real(0.25)));
  const std::vector<Vector3r> normals(2, Vector3r(0, 0, 1));
  EXPECT_EQ(error_of({two, bary, normals}, state), "");
  const std::vector<ParticleIndex> out_of_range = {0, 1, 2, 3, 4, 5, 1, 2, 3, 9};
  EXPECT_EQ(error_of({out_of_range, bary, normals}, state),
            "particle-tet contact constraint 1: particle index 9 is out of range (7 particles)");
  const std::vector<ParticleIndex> repeated = {0, 1, 2, 3, 4, 5, 1, 2, 1, 4};
  EXPECT_EQ(error_of({repeated, bary, normals}, state),
            "particle-tet contact constraint 1: particle 1 appears twice");
  const std::vector<ParticleIndex> six = {0, 1, 2, 3, 4, 5};
  EXPECT_EQ(error_of({six, bary, normals}, state),
            "particle-tet contact constraints: 6 particle indices is not a multiple of 5");
  const std::vector<Vector3r> one_bary(1, bary[0]);
  EXPECT_EQ(error_of({two, one_bary, normals}, state),
            "particle-tet contact constraints: 2 contacts but 1 barycentric coordinates and 2 "
            "normals");
  std::vector<Vector3r> bad = bary;
  bad[1].y() = Real(NAN);
  EXPECT_EQ(error_of({two, bad, normals}, state),
            "particle-tet contact constraint 1: barycentric coordinates are not finite");
  bad = normals;
  bad[0] = Vector3r(0, Real(INFINITY), 0);
  EXPECT_EQ(error_of({two, bary, bad}, state),
            "particle-tet contact constraint 0: normal is not finite");
  bad[0] = Vector3r(0, Real(1.1), 0);
  EXPECT_EQ(error_of({two, bary, bad}, state),
            "particle-tet contact constraint 0: normal is not a unit vector");
  EXPECT_EQ(error_of({two, bary, normals, Real(-0.5)}, state),
            "particle-tet contact constraints: friction is -0.5, must be finite and ≥ 0");
  ParticleState moving = state;
  moving.velocity_z[3] = Real(NAN);
  EXPECT_EQ(error_of({two, bary, normals}, moving),
            "particle-tet contact constraint 0: velocity of particle 3 is not finite");
}

TEST(ParticleTetContactBatchValidation, StaticPairsAreKeptInactiveAndRangesChecked) {
  std::vector<Vector3r> points = {Vector3r(Real(0.2), Real(0.2), Real(0.1)), Vector3r(0, 0, 0),
                                  Vector3r(1, 0, 0), Vector3r(0, 1, 0), Vector3r(0, 0, 1)};
  ParticleState state(points, std::vector<Real>(5, 0));
  const std::vector<ParticleIndex> one = {0, 1, 2, 3, 4};
  const std::vector<Vector3r> bary(1, Vector3r(Real(0.2), Real(0.2), Real(0.2)));
  const std::vector<Vector3r> normals(1, Vector3r(0, 0, 1));
  ParticleTetContacts contacts = make_particle_tet_contacts({one, bary, normals}, state);
  EXPECT_EQ(contacts.effective_mass[0], 0);
  const ParticleState before = state;
  project_particle_tet_contacts(ParticleArrays::of(state), contacts, 0, 1);
  EXPECT_TRUE(test::same_bits(state, before));
  EXPECT_EQ(contacts.lambda[0], 0);
  EXPECT_THROW(project_particle_tet_contacts(ParticleArrays::of(state), contacts, 0, 2),
               InvalidInput);
  ParticleState small(3);
  EXPECT_THROW(project_particle_tet_contacts(ParticleArrays::of(small), contacts, 0, 1),
               InvalidInput);
  EXPECT_THROW(
      solve_particle_tet_contact_velocities(velocity_arrays_of(state), contacts, 0, 1, 0),
      InvalidInput);
}

}  // namespace particle_tet_contact_batch_tests
}  // namespace tessera
