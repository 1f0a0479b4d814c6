// Particle–collider contacts: the scalar API's known answers (a particle below the plane is
// put on it, a static particle or one on the admissible side is left alone, static friction
// holds within μs d and dynamic friction takes μk d off the sliding, restitution bounces with
// −e ṽ_n), the batched kernels against the scalar API on every SIMD target, the residual,
// the sequential mapping, and validation at the door.
#include <cmath>
#include <string>
#include <vector>

#include <tessera/core/collider_contact_constraints.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/position_based_dynamics_extensions.hpp>

#include "batch_test_support.hpp"

namespace tessera {
namespace collider_contact_tests {

using test::Random;
using PBD = PositionBasedDynamicsExtensions;

constexpr Real kTolerance = kDoublePrecision ? Real(1e-12) : Real(1e-5);

/// The tilted plane of the scalar tests: unit normal n, the point q on it, offset n · q.
const Vector3r kNormal = Vector3r(Real(0.3), Real(-0.4), Real(1)).normalized();
const Vector3r kOnPlane(1, 2, 3);
const Real kOffset = kNormal.dot(kOnPlane);

/// A unit vector in the plane (tangential).
Vector3r tangent() { return kNormal.cross(Vector3r(1, 0, 0)).normalized(); }

// ---------------------------------------------------------------------------- scalar API
TEST(ColliderContact, ParticleBelowThePlaneIsPutOnIt) {
  const Vector3r p = kOnPlane - Real(0.3) * kNormal;
  Real lambda = 0;
  Vector3r corr;
  // No tangential motion since the anchor: the push alone, along n, by the depth.
  ASSERT_TRUE(PBD::solve_ColliderContactConstraint(p, Real(0.7), kNormal, kOffset, p, 0, 0,
                                                   lambda, corr));
  EXPECT_NEAR((p + corr - kOnPlane).norm(), 0, kTolerance);
  EXPECT_NEAR((corr - Real(0.3) * kNormal).norm(), 0, kTolerance);
  EXPECT_NEAR(lambda, Real(0.3), kTolerance);
  // λ accumulates the penetration over the iterations of a substep.
  ASSERT_TRUE(PBD::solve_ColliderContactConstraint(p, 1, kNormal, kOffset, p, 0, 0, lambda,
                                                   corr));
  EXPECT_NEAR(lambda, Real(0.6), kTolerance);
  // A frictionless contact keeps the tangential motion: only the normal part is undone.
  const Vector3r anchor = p - Real(0.5) * tangent();
  ASSERT_TRUE(PBD::solve_ColliderContactConstraint(p, 1, kNormal, kOffset, anchor, 0, 0, lambda,
                                                   corr));
  EXPECT_NEAR((corr - Real(0.3) * kNormal).norm(), 0, kTolerance);
}

TEST(ColliderContact, NothingHappensOnTheAdmissibleSide) {
  for (const Real height : {Real(0), Real(1e-3), Real(2)}) {
    const Vector3r p = kOnPlane + height * kNormal;
    Real lambda = Real(0.25);
    Vector3r corr(9, 9, 9);
    EXPECT_FALSE(PBD::solve_ColliderContactConstraint(p, 1, kNormal, kOffset,
                                                      p - tangent(), 1, 1, lambda, corr))
        << height;
    EXPECT_EQ(corr, Vector3r::Zero()) << "no friction without contact either";
    EXPECT_EQ(lambda, Real(0.25));
  }
}

TEST(ColliderContact, StaticParticleStaysPut) {
  const Vector3r p = kOnPlane - kNormal;
  Real lambda = 0;
  Vector3r corr(9, 9, 9);
  EXPECT_FALSE(PBD::solve_ColliderContactConstraint(p, 0, kNormal, kOffset, p, 1, 1, lambda,
                                                    corr));
  EXPECT_EQ(corr, Vector3r::Zero());
  EXPECT_EQ(lambda, 0);
  Vector3r corr_v(9, 9, 9);
  EXPECT_FALSE(PBD::velocitySolve_ColliderContactConstraint(Vector3r(0, 0, -1), 0, kNormal, -1,
                                                            1, 1, corr_v));
  EXPECT_EQ(corr_v, Vector3r::Zero());
}

TEST(ColliderContact, NormalThatIsNotAUnitVectorGivesNoCorrection) {
  Real lambda = 0;
  Vector3r corr(9, 9, 9);
  EXPECT_FALSE(PBD::solve_ColliderContactConstraint(Vector3r(0, 0, -1), 1, Vector3r(0, 0, 2), 0,
                                                    Vector3r(0, 0, -1), 0, 0, lambda, corr));
  EXPECT_EQ(corr, Vector3r::Zero());
  EXPECT_EQ(lambda, 0);
}

TEST(ColliderContact, StaticFrictionHoldsWithinMuSTimesTheDepth) {
  // Depth d = 0.3 and a tangential motion of 0.1 since the anchor: μs d = 0.15 holds it, and
  // the particle ends on the plane exactly below (along n) its anchor.
  const Vector3r anchor = kOnPlane + Real(0.05) * kNormal;
  const Vector3r p = kOnPlane - Real(0.3) * kNormal + Real(0.1) * tangent();
  Real lambda = 0;
  Vector3r corr;
  ASSERT_TRUE(PBD::solve_ColliderContactConstraint(p, 1, kNormal, kOffset, anchor, Real(0.5),
                                                   Real(0.1), lambda, corr));
  EXPECT_NEAR((p + corr - kOnPlane).norm(), 0, kTolerance);
  EXPECT_NEAR(lambda, Real(0.3), kTolerance);
}

TEST(ColliderContact, DynamicFrictionShortensTheSlidingByMuKTimesTheDepth) {
  // Tangential motion 0.5 > μs d = 0.15: it slides, μk d = 0.12 shorter.
  const Vector3r p = kOnPlane - Real(0.3) * kNormal + Real(0.5) * tangent();
  Real lambda = 0;
  Vector3r corr;
  ASSERT_TRUE(PBD::solve_ColliderContactConstraint(p, 1, kNormal, kOffset, kOnPlane, Real(0.5),
                                                   Real(0.4), lambda, corr));
  EXPECT_NEAR((p + corr - (kOnPlane + Real(0.38) * tangent())).norm(), 0, kTolerance);
  // A dynamic bound beyond the motion stops it, never reverses it (the min(·, 1)).
  ASSERT_TRUE(PBD::solve_ColliderContactConstraint(p, 1, kNormal, kOffset, kOnPlane, 0,
                                                   Real(10), lambda, corr));
  EXPECT_NEAR((p + corr - kOnPlane).norm(), 0, kTolerance);
}

TEST(ColliderContact, RestitutionBouncesWithMinusETimesTheApproachSpeed) {
  // Approached at ṽ_n = −3; after the position solve v has v_n = −2 and a tangential part.
  const Vector3r v = Real(-2) * kNormal + Real(0.7) * tangent();
  Vector3r corr;
  ASSERT_TRUE(PBD::velocitySolve_ColliderContactConstraint(v, 1, kNormal, -3, Real(0.5),
                                                           Real(0.01), corr));
  EXPECT_NEAR((v + corr).dot(kNormal), Real(1.5), kTolerance);
  EXPECT_NEAR(((v + corr) - Real(1.5) * kNormal - Real(0.7) * tangent()).norm(), 0, kTolerance)
      << "the tangential velocity is friction's, not restitution's";
  // e = 0 (the collision module zeroes it for slow approaches): the normal velocity stops.
  ASSERT_TRUE(PBD::velocitySolve_ColliderContactConstraint(v, 1, kNormal, -3, 0, Real(0.01),
                                                           corr));
  EXPECT_NEAR((v + corr).dot(kNormal), 0, kTolerance);
  // A separating approach (ṽ_n > 0) gets no bounce: max(−e ṽ_n, 0) = 0.
  ASSERT_TRUE(PBD::velocitySolve_ColliderContactConstraint(v, 1, kNormal, 1, 1, Real(0.01),
                                                           corr));
  EXPECT_NEAR((v + corr).dot(kNormal), 0, kTolerance);
  // A contact that did not push (λ = 0) leaves the velocity alone.
  EXPECT_FALSE(PBD::velocitySolve_ColliderContactConstraint(v, 1, kNormal, -3, 1, 0, corr));
  EXPECT_EQ(corr, Vector3r::Zero());
}

// -------------------------------------------------------------------------------- batch
/// Random particles; the contacts' planes through points near them, so about half penetrate.
struct ContactScene {
  test::DisjointConstraintSet<1> set;
  std::vector<Vector3r> normals, anchors, velocities;
  std::vector<Real> offsets, normal_speeds;
  ParticleState state;
};

ContactScene make_scene(Random& random, std::size_t count) {
  ContactScene scene{test::make_disjoint_constraints<1>(
                         random, count, Real(0.2),
                         [](Random& r) { return std::array<Vector3r, 1>{r.vector(-5, 5)}; }),
                     {}, {}, {}, {}, {}, {}};
  for (std::size_t c = 0; c < count; ++c) {
    const Vector3r p = scene.set.positions[scene.set.indices[c]];
    const Vector3r n = random.unit_vector();
    scene.normals.push_back(n);
    scene.offsets.push_back(n.dot(p) + random.uniform(Real(-0.3), Real(0.3)));
    // Sometimes no tangential motion at all, otherwise up to 0.3 in any direction.
    scene.anchors.push_back(random.uniform(0, 1) < Real(0.1) ? p
                                                             : Vector3r(p + Real(0.3) * random.vector()));
    scene.normal_speeds.push_back(random.uniform(-2, 1));
  }
  scene.state = ParticleState(scene.set.positions, scene.set.inverse_masses);
  for (std::size_t i = 0; i < scene.set.positions.size(); ++i) {
    const Vector3r v = random.vector(-2, 2);
    scene.velocities.push_back(v);
    scene.state.velocity_x[i] = v.x();
    scene.state.velocity_y[i] = v.y();
    scene.state.velocity_z[i] = v.z();
  }
  return scene;
}

/// The scene's contacts with random per-contact coefficients.
ColliderContacts build(const ContactScene& scene, Random& random) {
  ColliderContacts contacts = make_collider_contacts(
      {.particles = scene.set.indices,
       .particle_count = scene.set.positions.size(),
       .normals = scene.normals,
       .offsets = scene.offsets,
       .anchors = scene.anchors,
       .normal_speeds = scene.normal_speeds});
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    contacts.static_friction[c] = random.uniform(0, 1);
    contacts.dynamic_friction[c] = random.uniform(0, 1) * contacts.static_friction[c];
    contacts.restitution[c] = random.uniform(0, 1);
  }
  return contacts;
}

Vector3r column(const std::array<AlignedVector<Real>, 3>& arrays, std::size_t c) {
  return Vector3r(arrays[0][c], arrays[1][c], arrays[2][c]);
}

bool near(Real a, Real b) { return std::abs(a - b) <= test::kBatchTolerance * (1 + std::abs(b)); }

TEST(ColliderContactBatch, PositionSolveMatchesScalarApiOnEveryTarget) {
  test::for_each_simd_target([](const std::string&) {
    for (unsigned seed = 1; seed <= 6; ++seed) {
      Random random(100 + seed);
      const std::size_t count = std::size_t(random.integer(1, 300));
      const ContactScene scene = make_scene(random, count);
      ColliderContacts contacts = build(scene, random);
      std::vector<Real> expected_lambda(count);
      for (std::size_t c = 0; c < count; ++c)
        contacts.lambda[c] = expected_lambda[c] =
            random.uniform(0, 1) < Real(0.3) ? random.uniform(0, Real(0.2)) : Real(0);
      const std::vector<Real> lambda_before = expected_lambda;
      const auto [begin, end] = test::random_range(random, count);
      std::vector<Vector3r> expected = scene.set.positions;
      test::project_scalar_range<1>(
          scene.set, begin, end, expected,
          [&](const ParticleIndex* i, std::size_t c, Vector3r(&corr)[1]) {
            PBD::solve_ColliderContactConstraint(
                expected[i[0]], scene.set.inverse_masses[i[0]], column(contacts.normal, c),
                contacts.offset[c], column(contacts.anchor, c), contacts.static_friction[c],
                contacts.dynamic_friction[c], expected_lambda[c], corr[0]);
          });
      ParticleState state = scene.state;
      project_collider_contacts(ParticleArrays::of(state), contacts, begin, end);
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
          scene.state, contacts, begin, end, ProjectionSettings{}, project_collider_contacts);
    }
  });
}

TEST(ColliderContactBatch, VelocitySolveMatchesScalarApiOnEveryTarget) {
  test::for_each_simd_target([](const std::string&) {
    for (unsigned seed = 1; seed <= 6; ++seed) {
      Random random(200 + seed);
      const std::size_t count = std::size_t(random.integer(1, 300));
      const ContactScene scene = make_scene(random, count);
      ColliderContacts contacts = build(scene, random);
      for (std::size_t c = 0; c < count; ++c)
        contacts.lambda[c] = random.uniform(0, 1) < Real(0.3) ? 0 : random.uniform(0, Real(0.2));
      const auto [begin, end] = test::random_range(random, count);
      std::vector<Vector3r> expected = scene.velocities;
      for (std::size_t c = begin; c < end; ++c) {
        const ParticleIndex i = scene.set.indices[c];
        Vector3r corr;
        PBD::velocitySolve_ColliderContactConstraint(
            expected[i], scene.set.inverse_masses[i], column(contacts.normal, c),
            contacts.normal_speed[c], contacts.restitution[c], contacts.lambda[c], corr);
        if (scene.set.inverse_masses[i] > 0) expected[i] += corr;
      }
      ParticleState state = scene.state;
      solve_collider_contact_velocities(velocity_arrays_of(state), contacts, begin, end);
      for (std::size_t i = 0; i < expected.size(); ++i)
        EXPECT_LE((state.velocity(i) - expected[i]).norm(),
                  test::kBatchTolerance * std::max(Real(1), expected[i].norm()))
            << "particle " << i;
      EXPECT_TRUE(test::same_bits(state, scene.state)) << "positions changed";
    }
  });
}

void project(ParticleArrays particles, ColliderContacts& contacts, std::size_t begin,
             std::size_t end, const ProjectionSettings&) {
  project_collider_contacts(particles, contacts, begin, end);
}

ColliderContacts build_from_set(const test::DisjointConstraintSet<1>& set, Random& random) {
  ContactScene scene{set, {}, {}, {}, {}, {}, {}};
  for (std::size_t c = 0; c < set.count; ++c) {
    const Vector3r p = set.positions[set.indices[c]];
    const Vector3r n = random.unit_vector();
    scene.normals.push_back(n);
    scene.offsets.push_back(n.dot(p) + random.uniform(Real(-0.3), Real(0.3)));
    scene.anchors.push_back(p + Real(0.3) * random.vector());
    scene.normal_speeds.push_back(random.uniform(-2, 1));
  }
  return build(scene, random);
}

test::DisjointConstraintSet<1> random_particles(Random& random, std::size_t count) {
  return test::make_disjoint_constraints<1>(
      random, count, Real(0.2), [](Random& r) { return std::array<Vector3r, 1>{r.vector(-5, 5)}; });
}

TEST(ColliderContactBatch, BitwiseReproducibleOnEveryTarget) {
  test::expect_bitwise_reproducible(random_particles, build_from_set, project);
}

TEST(ColliderContactBatch, StaticParticlesAndEmptyRangesAreNotWritten) {
  test::expect_static_particles_and_empty_ranges_not_written(random_particles, build_from_set,
                                                             project, {ProjectionSettings{}}, true);
}

TEST(ColliderContactBatch, SequentialProjectionIsTheScalarApiInOrder) {
  // Two contacts on particle 1 (two colliders): in order, the second sees the first's result.
  const std::vector<Vector3r> positions = {Vector3r(0, 0, 0), Vector3r(Real(0.5), 0, Real(-0.2))};
  const std::vector<ParticleIndex> particles = {1, 1};
  const std::vector<Vector3r> normals = {Vector3r(0, 0, 1), Vector3r(-1, 0, 0)};
  const std::vector<Real> offsets = {0, Real(-0.4)};
  const std::vector<Vector3r> anchors = {positions[1], positions[1]};
  const std::vector<Real> speeds = {-1, 0};
  ColliderContacts contacts =
      make_collider_contacts({particles, 2, normals, offsets, anchors, speeds});
  ParticleState state(positions, std::vector<Real>{0, 1});
  project_sequentially(ParticleArrays::of(state), contacts, 0, 2);
  // Frictionless: first the floor z ≥ 0, then the wall x ≤ 0.4: in the corner.
  EXPECT_NEAR((state.position(1) - Vector3r(Real(0.4), 0, 0)).norm(), 0, kTolerance);
  EXPECT_NEAR(contacts.lambda[0], Real(0.2), kTolerance);
  EXPECT_NEAR(contacts.lambda[1], Real(0.1), kTolerance);
  // With friction, the wall's contact sees the floor's push (0.2 along the wall) as sliding
  // since the anchor: μs d = 0.05 does not hold it, μk d = 0.03 takes that much off.
  contacts.static_friction[1] = Real(0.5);
  contacts.dynamic_friction[1] = Real(0.3);
  ParticleState with_friction(positions, std::vector<Real>{0, 1});
  project_sequentially(ParticleArrays::of(with_friction), contacts, 0, 2);
  EXPECT_NEAR((with_friction.position(1) - Vector3r(Real(0.4), 0, Real(-0.03))).norm(), 0,
              kTolerance);
}

TEST(ColliderContactBatch, ResidualIsThePenetrationInLengthUnits) {
  const std::vector<Vector3r> positions = {Vector3r(0, 0, Real(-0.25)), Vector3r(1, 1, Real(0.5)),
                                           Vector3r(2, 0, 0)};
  const std::vector<ParticleIndex> particles = {0, 1, 2};
  const std::vector<Vector3r> normals(3, Vector3r(0, 0, 1));
  const std::vector<Real> offsets = {0, 0, Real(0.1)};
  const std::vector<Real> speeds(3, 0);
  const ColliderContacts contacts =
      make_collider_contacts({particles, 3, normals, offsets, positions, speeds});
  ParticleState state(positions, std::vector<Real>{1, 1, 0});
  Real out[3] = {-1, -1, -1};
  constraint_residuals(ParticleArrays::of(state), contacts, 0, 3, out);
  EXPECT_NEAR(out[0], Real(0.25), kTolerance);
  EXPECT_EQ(out[1], 0) << "above the plane";
  EXPECT_NEAR(out[2], Real(0.1), kTolerance) << "a static particle's penetration counts too";
}

// ------------------------------------------------------------------ validation at the door
TEST(ColliderContactBatchValidation, NamesTheContactAndTheProblem) {
  const std::vector<ParticleIndex> two = {0, 3};
  const std::vector<Vector3r> normals(2, Vector3r(0, 0, 1)), anchors(2, Vector3r::Zero());
  const std::vector<Real> offsets(2, 0), speeds(2, 0);
  const auto error_of = [&](const ColliderContactInput& input) {
    return test::error_of([&] { make_collider_contacts(input); });
  };
  const ColliderContactInput ok{two, 4, normals, offsets, anchors, speeds};
  EXPECT_EQ(error_of(ok), "");
  ColliderContactInput bad = ok;
  bad.particle_count = 3;
  EXPECT_EQ(error_of(bad),
            "collider contact constraint 1: particle index 3 is out of range (3 particles)");
  const std::vector<Real> one(1, 0);
  bad = ok;
  bad.offsets = one;
  EXPECT_EQ(error_of(bad), "collider contact constraints: 2 contacts but 2 normals, 1 offsets, "
                           "2 anchors and 2 normal speeds");
  std::vector<Vector3r> bad_normals = normals;
  bad_normals[1] = Vector3r(0, Real(NAN), 1);
  bad = ok;
  bad.normals = bad_normals;
  EXPECT_EQ(error_of(bad), "collider contact constraint 1: normal is not finite");
  bad_normals[1] = Vector3r(0, 0, Real(1.01));
  EXPECT_EQ(error_of(bad), "collider contact constraint 1: normal is not a unit vector");
  bad_normals[1] = Vector3r(0, 0, Real(1.00001));
  EXPECT_EQ(error_of(bad), "") << "within the unit tolerance";
  std::vector<Real> bad_values = offsets;
  bad_values[0] = Real(INFINITY);
  bad = ok;
  bad.offsets = bad_values;
  EXPECT_EQ(error_of(bad), "collider contact constraint 0: offset is not finite");
  bad = ok;
  bad.normal_speeds = bad_values;
  EXPECT_EQ(error_of(bad), "collider contact constraint 0: normal speed is not finite");
  std::vector<Vector3r> bad_anchors = anchors;
  bad_anchors[1].x() = Real(NAN);
  bad = ok;
  bad.anchors = bad_anchors;
  EXPECT_EQ(error_of(bad), "collider contact constraint 1: anchor is not finite");
  bad = ok;
  bad.static_friction = Real(-0.5);
  EXPECT_EQ(error_of(bad),
            "collider contact constraints: static friction is -0.5, must be finite and ≥ 0");
  bad = ok;
  bad.dynamic_friction = Real(INFINITY);
  EXPECT_EQ(error_of(bad),
            "collider contact constraints: dynamic friction is inf, must be finite and ≥ 0");
  bad = ok;
  bad.restitution = Real(1.5);
  EXPECT_EQ(error_of(bad), "collider contact constraints: restitution is 1.5, must lie in [0, 1]");
  bad.restitution = Real(NAN);
  EXPECT_EQ(error_of(bad), "collider contact constraints: restitution is nan, must lie in [0, 1]");
}

TEST(ColliderContactBatchValidation, BuildsThePerContactArraysAndChecksRanges) {
  const std::vector<ParticleIndex> one = {2};
  const std::vector<Vector3r> normals = {Vector3r(1, 0, 0)}, anchors = {Vector3r(1, 2, 3)};
  const std::vector<Real> offsets = {Real(0.5)}, speeds = {Real(-1.5)};
  ColliderContacts contacts = make_collider_contacts(
      {one, 3, normals, offsets, anchors, speeds, Real(0.6), Real(0.4), Real(0.2)});
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_EQ(contacts.particles.particle[0][0], 2u);
  EXPECT_EQ(column(contacts.normal, 0), normals[0]);
  EXPECT_EQ(column(contacts.anchor, 0), anchors[0]);
  EXPECT_EQ(contacts.offset[0], Real(0.5));
  EXPECT_EQ(contacts.normal_speed[0], Real(-1.5));
  EXPECT_EQ(contacts.static_friction[0], Real(0.6));
  EXPECT_EQ(contacts.dynamic_friction[0], Real(0.4));
  EXPECT_EQ(contacts.restitution[0], Real(0.2));
  EXPECT_EQ(contacts.lambda[0], 0);
  ParticleState state(std::vector<Vector3r>(3, Vector3r::Zero()), std::vector<Real>(3, 1));
  EXPECT_THROW(project_collider_contacts(ParticleArrays::of(state), contacts, 0, 2),
               InvalidInput);
  ParticleState small(2);
  EXPECT_THROW(project_collider_contacts(ParticleArrays::of(small), contacts, 0, 1),
               InvalidInput);
  EXPECT_THROW(solve_collider_contact_velocities(velocity_arrays_of(small), contacts, 0, 1),
               InvalidInput);
}

}  // namespace collider_contact_tests
}  // namespace tessera
