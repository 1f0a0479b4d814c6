// Solids against solids: a vertex that comes near a boundary face of a tetrahedral mesh
// (another body's, or a far part of its own) is held outside by a particle–tet contact on the
// tetrahedron under that face, instead of the unsigned vertex–triangle distance cloth uses.
//
//            p •                 face (a, b, c) on the boundary, d the tet's fourth vertex
//              ¦  n (outwards: away from d)
//     a ───────q────── b         q  the point of the face closest to p (predicted positions)
//       ╲     ¦     ╱            q* = q + thickness · n, written in barycentric coordinates
//         ╲   d   ╱                   of (a, b, c, d), so it moves with the tetrahedron
//           ╲ ╱                  C  = n · (p − q*) ≥ 0     (particle_tet_contact, λ ≥ 0)
//            c
//
// Why a tetrahedron and not the triangle: a solid has an inside. The distance kernels measure
// |p − q| and push p away from the face on whichever side p is, so a vertex that has crossed
// a face (a fast body, a deep stack) is pushed further in; the contact above knows the
// outside (the side away from d) and pushes p back out from any depth, and it carries the
// family's Coulomb friction in the velocity pass. The pairs themselves come from the
// self-collision detection (self_collision.hpp: vertex–triangle pairs within reach during the
// substep's motion), so solids need no second broad phase.
//
// Which normal, taken at the start of the substep (the closest point is the one at the start
// too, carried by the tetrahedron):
//   p in front of the face (its projection on the face's plane inside the triangle): the
//     face's normal, outwards;
//   p beside the face and in front of its plane: the direction from the closest point (on an
//     edge or corner) to p;
//   p beside the face and behind its plane: no contact (p is beside the body, another face
//     of it faces p).
//        p1 ●             p1: the face's normal    p2: from the edge    p3: none
//   ────────────┐ ● p2
//      body     │ ● p3
// The face's normal everywhere pushed a vertex beside a face (p3, on top of a block near its
// side) sideways by the thickness every iteration: harmless averaged in a Jacobi set, but
// with the contacts swept Gauss–Seidel (mode sequential, ContactScheduling::coloured) the
// eight-block pile blew up within ten frames (2 million contacts). The direction from the
// closest point for every pair near an edge, in front of the face too, tipped a block dropped
// flat and centred across another off it (5 cm drop, E = 1 and 10 MPa). Dropping p2 as well
// let a bar landing edge-first sink through a slab (the slab's vertices under its edge face
// neither of its faces), so p2 keeps its contact.
//
// Edge–edge pairs between two solids are dropped. The distance kernel is unsigned: once two
// edges have crossed (a block landing edge-on across another's edge does that within a few
// substeps), it holds them crossed and pulls the bodies into each other, measured at 2.6 cm
// deep in a 4 mm contact distance on the two-block test, against 0 without them. What that
// leaves: two edges can pass through each other while no vertex reaches the other's faces,
// which on meshes of a few centimetres stays within one cell and is undone as soon as a
// vertex comes within reach of a face. Edge pairs with a cloth edge stay distance contacts.
//
// The run summary's penetration measure for solids is solid_penetration_depth below: how deep
// a boundary vertex lies inside another body (a connected part of the tetrahedra).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <tessera/collision/self_collision.hpp>
#include <tessera/core/particle_state.hpp>
#include <tessera/core/particle_tet_contact_constraints.hpp>
#include <tessera/core/real.hpp>

namespace tessera {

/// Which surface triangles are faces of which tetrahedra.
class SolidSurface {
 public:
  static constexpr std::uint32_t kNone = 0xffffffffu;
  /// `tetrahedra`: four particles each; `triangles`: three each (the self-collision surface).
  /// A triangle that is a face of a tetrahedron belongs to it (the first such tetrahedron);
  /// others (cloth) to none. Throws InvalidInput for an index ≥ particle_count, an index
  /// count that is not a multiple of 4, or a tetrahedron naming a particle twice.
  SolidSurface(std::span<const std::uint32_t> tetrahedra, std::span<const std::uint32_t> triangles,
               std::size_t particle_count);

  bool empty() const { return solid_faces_ == 0; }
  /// The number of triangles that are faces of a tetrahedron.
  std::size_t solid_face_count() const { return solid_faces_; }
  /// The fourth vertex of the tetrahedron under triangle t, or kNone.
  std::uint32_t opposite_vertex(std::size_t triangle) const { return opposite_[triangle]; }
  /// Whether particle i is a corner of a tetrahedron.
  bool solid_particle(std::size_t i) const { return solid_particle_[i] != 0; }

 private:
  std::vector<std::uint32_t> opposite_;
  std::vector<std::uint8_t> solid_particle_;
  std::size_t solid_faces_ = 0;
};

/// split_solid_contacts' working lists, kept between calls.
struct SolidContactScratch {
  std::vector<ParticleIndex> particles;
  std::vector<Vector3r> barycentric, normals;
};

/// A detection's vertex–triangle pairs, split: those on a solid face whose tetrahedron does
/// not hold the vertex become particle–tet contacts (see the top of this file; friction μ,
/// made at `state`, whose positions are the predicted ones); the rest stay in
/// `remaining_triangle_point` (four particles each, in their order). A pair whose tetrahedron
/// is degenerate (no finite barycentric coordinates) stays a distance contact too.
/// `scratch`, if given, holds the working lists between calls (the collision stage keeps one,
/// so a substep allocates nothing once the contacts stop growing); `particle_tet` keeps its
/// arrays' capacity too.
void split_solid_contacts(const SolidSurface& surface, const SelfCollision::Contacts& contacts,
                          const ParticleState& state, Real thickness, Real friction,
                          std::vector<ParticleIndex>& remaining_triangle_point,
                          ParticleTetContacts& particle_tet,
                          SolidContactScratch* scratch = nullptr);

/// Removes from `edge_edge` (four particles per pair) the pairs whose four particles are all
/// corners of tetrahedra, keeping the order of the rest.
void drop_solid_edge_pairs(const SolidSurface& surface, std::vector<ParticleIndex>& edge_edge);

/// The deepest point of the solids inside one another: over every vertex of a boundary face
/// inside a tetrahedron of another body (connected set of tetrahedra), its distance to that
/// body's boundary; 0 when none is inside (a vertex resting on a face measures 0). Parallel (TBB). Throws InvalidInput for an index
/// out of range or a count that is not a multiple of 4.
Real solid_penetration_depth(std::span<const Vector3r> positions,
                             std::span<const std::uint32_t> tetrahedra);

}  // namespace tessera
