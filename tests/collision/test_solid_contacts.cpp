// Solid contacts: which surface triangles are tetrahedron faces, the split of vertex–triangle
// pairs into particle–tet contacts with the outward normal (known answers on one
// tetrahedron), a vertex that has crossed the face pushed back out (where the unsigned
// distance contact pushes it further in), and the penetration measure between bodies.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <tessera/collision/self_collision.hpp>
#include <tessera/collision/solid_contacts.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/particle_state.hpp>
#include <tessera/core/proximity_distance_constraints.hpp>
#include <tessera/io/generators.hpp>

namespace tessera {
namespace solid_contacts_tests {

constexpr Real kThickness = Real(0.05);

/// Tetrahedron 0..3 with its face (0, 1, 2) in the plane y = 0 and its fourth vertex 3
/// below (so the face's outward normal is +y), and particle 4 at `p`.
ParticleState tet_and_point(const Vector3r& p) {
  const std::vector<Vector3r> positions = {Vector3r(0, 0, 0), Vector3r(1, 0, 0),
                                           Vector3r(0, 0, 1), Vector3r(Real(0.2), -1, Real(0.2)),
                                           p};
  return ParticleState(positions, std::vector<Real>(5, Real(1)));
}
const std::vector<std::uint32_t> kTet = {0, 1, 2, 3};
/// The surface: the tet's face (0, 1, 2), listed in another order (faces match as sets).
const std::vector<std::uint32_t> kFace = {2, 1, 0};

/// A vertex–triangle pair (4, face 0) as self-collision would report it.
SelfCollision::Contacts pair_with_face() {
  SelfCollision::Contacts contacts;
  contacts.triangle_point = {4, 2, 1, 0};
  contacts.triangle_point_triangle = {0};
  return contacts;
}

TEST(SolidContacts, SurfaceTrianglesThatAreTetFacesKnowTheirFourthVertex) {
  const std::vector<std::uint32_t> triangles = {2, 1, 0, 0, 1, 4};
  const SolidSurface surface(kTet, triangles, 5);
  EXPECT_EQ(surface.solid_face_count(), 1u);
  EXPECT_EQ(surface.opposite_vertex(0), 3u);
  EXPECT_EQ(surface.opposite_vertex(1), SolidSurface::kNone);  // a cloth triangle
  EXPECT_TRUE(SolidSurface({}, triangles, 5).empty());
}

TEST(SolidContacts, AVertexAboveAFaceGetsAContactWithTheOutwardNormalAndTheThickness) {
  const ParticleState state = tet_and_point(Vector3r(Real(0.3), Real(0.02), Real(0.3)));
  std::vector<ParticleIndex> rest;
  ParticleTetContacts contacts;
  split_solid_contacts(SolidSurface(kTet, kFace, 5), pair_with_face(), state, kThickness,
                       Real(0.4), rest, contacts);
  EXPECT_TRUE(rest.empty());
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_EQ(contacts.particles.particle[0][0], 4u);
  EXPECT_EQ(contacts.particles.particle[4][0], 3u);  // the fourth vertex last
  EXPECT_NEAR(contacts.normal[0][0], 0, 1e-6);
  EXPECT_NEAR(contacts.normal[1][0], 1, 1e-6);
  EXPECT_NEAR(contacts.normal[2][0], 0, 1e-6);
  EXPECT_EQ(contacts.friction[0], Real(0.4));
  // The contact point: (0.3, thickness, 0.3) in the coordinates of (0, 1, 2, 3).
  const Real b1 = contacts.barycentric[0][0], b2 = contacts.barycentric[1][0],
             b3 = contacts.barycentric[2][0];
  const Vector3r point = (1 - b1 - b2 - b3) * state.position(2) + b1 * state.position(1) +
                         b2 * state.position(0) + b3 * state.position(3);
  EXPECT_NEAR((point - Vector3r(Real(0.3), kThickness, Real(0.3))).norm(), 0, 1e-5);
}

TEST(SolidContacts, AVertexThatCrossedTheFaceIsPushedBackOutWhereADistanceContactPushesItIn) {
  // 1 cm below the face, inside the tetrahedron.
  const Vector3r inside(Real(0.3), Real(-0.01), Real(0.3));
  ParticleState state = tet_and_point(inside);
  std::vector<ParticleIndex> rest;
  ParticleTetContacts contacts;
  split_solid_contacts(SolidSurface(kTet, kFace, 5), pair_with_face(), state, kThickness, 0,
                       rest, contacts);
  ASSERT_EQ(contacts.size(), 1u);
  for (int i = 0; i < 20; ++i)
    project_particle_tet_contacts(ParticleArrays::of(state), contacts, 0, 1);
  // Out on the outer side, the thickness above the (moved) face.
  const Real face_y = (state.position(0).y() + state.position(1).y() + state.position(2).y()) / 3;
  EXPECT_GT(state.position(4).y(), face_y + kThickness / 2);

  // The same pair as a distance contact (cloth's) ends on the wrong side.
  ParticleState cloth = tet_and_point(inside);
  const std::vector<ParticleIndex> particles = {4, 2, 1, 0};
  TrianglePointDistanceConstraints distance = make_triangle_point_distance_constraints(
      {.particles = particles, .particle_count = 5, .rest_distance = kThickness,
       .rest_distances = {}, .compression_stiffness = 1, .stretch_stiffness = 0});
  for (int i = 0; i < 20; ++i)
    project_triangle_point_distance_constraints(ParticleArrays::of(cloth), distance, 0, 1);
  EXPECT_LT(cloth.position(4).y(), 0);
}

TEST(SolidContacts, ACornerOfTheTetAndADegenerateTetStayDistanceContacts) {
  // The point is the tet's fourth vertex: no particle–tet contact can hold it.
  ParticleState state = tet_and_point(Vector3r(Real(0.3), Real(0.02), Real(0.3)));
  const std::vector<std::uint32_t> with_point = {0, 1, 2, 4};
  std::vector<ParticleIndex> rest;
  ParticleTetContacts contacts;
  split_solid_contacts(SolidSurface(with_point, kFace, 5), pair_with_face(), state, kThickness,
                       0, rest, contacts);
  EXPECT_EQ(contacts.size(), 0u);
  EXPECT_EQ(rest, (std::vector<ParticleIndex>{4, 2, 1, 0}));
  // A flat tetrahedron (its fourth vertex in the face's plane).
  state.set_position(3, Vector3r(Real(0.2), 0, Real(0.2)));
  split_solid_contacts(SolidSurface(kTet, kFace, 5), pair_with_face(), state, kThickness, 0,
                       rest, contacts);
  EXPECT_EQ(contacts.size(), 0u);
  EXPECT_EQ(rest.size(), 4u);
}

TEST(SolidContacts, EdgePairsOfTwoSolidsAreDroppedAndPairsWithAClothEdgeKept) {
  // Particles 0..3 a tetrahedron, 4 and 5 a cloth edge.
  const SolidSurface surface(kTet, kFace, 6);
  std::vector<ParticleIndex> pairs = {0, 1, 2, 3, 0, 1, 4, 5, 1, 2, 0, 3, 4, 5, 2, 3};
  drop_solid_edge_pairs(surface, pairs);
  EXPECT_EQ(pairs, (std::vector<ParticleIndex>{0, 1, 4, 5, 4, 5, 2, 3}));
}

TEST(SolidContacts, BadTetrahedraAreErrors) {
  EXPECT_THROW(SolidSurface(std::vector<std::uint32_t>{0, 1, 2}, kFace, 5), InvalidInput);
  EXPECT_THROW(SolidSurface(std::vector<std::uint32_t>{0, 1, 2, 9}, kFace, 5), InvalidInput);
  EXPECT_THROW(SolidSurface(std::vector<std::uint32_t>{0, 1, 1, 3}, kFace, 5), InvalidInput);
}

/// Two bodies: blocks of 2 × 2 × 2 cells of side 0.5 (1 m cubes), the second shifted by
/// `offset`.
struct TwoBlocks {
  std::vector<Vector3r> positions;
  std::vector<std::uint32_t> tetrahedra;
  explicit TwoBlocks(const Vector3r& offset) {
    const io::TetrahedralBar block = io::make_tetrahedral_bar(2, 2, 2, Real(0.5));
    for (int b = 0; b < 2; ++b) {
      const std::uint32_t first = std::uint32_t(positions.size());
      for (const Vector3r& p : block.positions) positions.push_back(b == 0 ? p : Vector3r(p + offset));
      for (const auto v : block.tetrahedron_indices) tetrahedra.push_back(first + v);
    }
  }
};

TEST(SolidContacts, PenetrationDepthIsHowDeepABoundaryVertexIsInsideAnotherBody) {
  // Apart, and face to face (touching is not inside): 0.
  EXPECT_EQ(solid_penetration_depth(TwoBlocks(Vector3r(2, 0, 0)).positions,
                                    TwoBlocks(Vector3r(2, 0, 0)).tetrahedra),
            0);
  const TwoBlocks touching(Vector3r(1, 0, 0));
  EXPECT_LE(solid_penetration_depth(touching.positions, touching.tetrahedra), Real(1e-6));
  // Overlapping by 0.2 along x, offset by 0.3 in y and z: the second block's corner
  // (0.8, 0.3, 0.3) is 0.2 inside the first (on an inner face of its tetrahedra), and the
  // first's vertex (1, 0.5, 0.5) 0.2 inside the second.
  const TwoBlocks overlapping(Vector3r(Real(0.8), Real(0.3), Real(0.3)));
  EXPECT_NEAR(solid_penetration_depth(overlapping.positions, overlapping.tetrahedra),
              Real(0.2), Real(1e-5));
  // One body alone is never inside itself.
  const io::TetrahedralBar block = io::make_tetrahedral_bar(2, 2, 2, Real(0.5));
  EXPECT_EQ(solid_penetration_depth(block.positions, block.tetrahedron_indices), 0);
  EXPECT_THROW(solid_penetration_depth(block.positions, std::vector<std::uint32_t>{0, 1, 2}),
               InvalidInput);
}

}  // namespace solid_contacts_tests
}  // namespace tessera
