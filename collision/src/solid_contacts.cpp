// Solid contacts (solid_contacts.hpp): the faces of the tetrahedra, the split of the
// vertex–triangle pairs, and the penetration measure.
#include <tessera/collision/solid_contacts.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <numeric>
#include <optional>
#include <string>

#include <Eigen/Dense>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <tessera/collision/spatial_hash.hpp>
#include <tessera/core/error.hpp>

#include "closest_distance.hpp"

namespace tessera {

namespace {

using Key = std::array<std::uint32_t, 3>;

Key sorted_key(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  Key key{a, b, c};
  std::sort(key.begin(), key.end());
  return key;
}

/// Every face of every tetrahedron: its sorted key, its tetrahedron and the fourth vertex,
/// sorted by (key, tetrahedron).
struct TetFace {
  Key key;
  std::uint32_t tet;
  std::uint32_t opposite;
};

std::vector<TetFace> tet_faces(std::span<const std::uint32_t> tetrahedra,
                               std::size_t particle_count, const char* context) {
  if (tetrahedra.size() % 4 != 0)
    throw InvalidInput(std::string(context) + ": " + std::to_string(tetrahedra.size()) +
                       " tetrahedron indices, not a multiple of 4");
  const std::size_t count = tetrahedra.size() / 4;
  std::vector<TetFace> faces;
  faces.reserve(4 * count);
  for (std::size_t t = 0; t < count; ++t) {
    const std::uint32_t* v = tetrahedra.data() + 4 * t;
    for (int k = 0; k < 4; ++k) {
      if (v[k] >= particle_count)
        throw InvalidInput(std::string(context) + ": tetrahedron " + std::to_string(t) +
                           " names particle " + std::to_string(v[k]) + ", there are " +
                           std::to_string(particle_count));
      for (int l = 0; l < k; ++l)
        if (v[l] == v[k])
          throw InvalidInput(std::string(context) + ": tetrahedron " + std::to_string(t) +
                             " names particle " + std::to_string(v[k]) + " twice");
    }
    for (int k = 0; k < 4; ++k)  // the face opposite corner k
      faces.push_back({sorted_key(v[(k + 1) % 4], v[(k + 2) % 4], v[(k + 3) % 4]),
                       std::uint32_t(t), v[k]});
  }
  std::sort(faces.begin(), faces.end(), [](const TetFace& l, const TetFace& r) {
    return l.key != r.key ? l.key < r.key : l.tet < r.tet;
  });
  return faces;
}

Vector3r position(const ParticleState& state, std::uint32_t i) {
  return Vector3r(state.x[i], state.y[i], state.z[i]);
}

/// Union–find over the particles of the tetrahedra: the body of each particle.
std::vector<std::uint32_t> bodies_of(std::span<const std::uint32_t> tetrahedra,
                                     std::size_t particle_count) {
  std::vector<std::uint32_t> parent(particle_count);
  std::iota(parent.begin(), parent.end(), 0u);
  const auto find = [&](std::uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (std::size_t t = 0; t + 3 < tetrahedra.size(); t += 4)
    for (int k = 1; k < 4; ++k) {
      const std::uint32_t a = find(tetrahedra[t]), b = find(tetrahedra[t + std::size_t(k)]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  for (std::uint32_t i = 0; i < particle_count; ++i) parent[i] = find(i);
  return parent;
}

}  // namespace

SolidSurface::SolidSurface(std::span<const std::uint32_t> tetrahedra,
                           std::span<const std::uint32_t> triangles, std::size_t particle_count)
    : opposite_(triangles.size() / 3, kNone), solid_particle_(particle_count, 0) {
  const std::vector<TetFace> faces = tet_faces(tetrahedra, particle_count, "solid contacts");
  for (const std::uint32_t i : tetrahedra) solid_particle_[i] = 1;
  for (std::size_t t = 0; t < opposite_.size(); ++t) {
    const Key key = sorted_key(triangles[3 * t], triangles[3 * t + 1], triangles[3 * t + 2]);
    const auto found = std::lower_bound(
        faces.begin(), faces.end(), key,
        [](const TetFace& face, const Key& k) { return face.key < k; });
    if (found != faces.end() && found->key == key) {
      opposite_[t] = found->opposite;
      ++solid_faces_;
    }
  }
}

namespace {

/// Whether p's projection on the plane of (a, b, c) (unit normal n) lies in the triangle, up
/// to a sliver of 1e-3 of its size: the signed areas of the three sub-triangles.
bool projects_inside(const Vector3r& p, const Vector3r& a, const Vector3r& b, const Vector3r& c,
                     const Vector3r& n) {
  const Vector3r q = p - n * n.dot(p - a);
  const Real area = (b - a).cross(c - a).dot(n);
  if (!(std::abs(area) > 0)) return false;
  const Real tolerance = Real(-1e-3) * std::abs(area);
  const Real sign = area > 0 ? Real(1) : Real(-1);
  return sign * (b - q).cross(c - q).dot(n) >= tolerance &&
         sign * (c - q).cross(a - q).dot(n) >= tolerance &&
         sign * (a - q).cross(b - q).dot(n) >= tolerance;
}

}  // namespace

void split_solid_contacts(const SolidSurface& surface, const SelfCollision::Contacts& contacts,
                          const ParticleState& state, Real thickness, Real friction,
                          std::vector<ParticleIndex>& remaining_triangle_point,
                          ParticleTetContacts& particle_tet, SolidContactScratch* scratch) {
  remaining_triangle_point.clear();
  SolidContactScratch local;
  SolidContactScratch& lists = scratch ? *scratch : local;
  auto& particles = lists.particles;
  auto& barycentric = lists.barycentric;
  auto& normals = lists.normals;
  particles.clear(), barycentric.clear(), normals.clear();
  const bool has_start = state.previous_x.size() == state.size();
  const auto start = [&](std::uint32_t i) {
    return has_start ? Vector3r(state.previous_x[i], state.previous_y[i], state.previous_z[i])
                     : position(state, i);
  };
  using Frame = Eigen::Matrix<Real, 3, 3>;
  /// The tetrahedron's edges from a as columns, or nothing when it is (nearly) flat.
  const auto frame = [](const Vector3r& a, const Vector3r& b, const Vector3r& c,
                        const Vector3r& d) -> std::optional<Frame> {
    Frame edges;
    edges << b - a, c - a, d - a;
    const Real scale = (b - a).norm() * (c - a).norm() * (d - a).norm();
    if (!(std::abs(edges.determinant()) > Real(1e-4) * scale)) return std::nullopt;
    return edges;
  };
  const std::size_t count = contacts.triangle_point_count();
  for (std::size_t k = 0; k < count; ++k) {
    const ParticleIndex* contact = contacts.triangle_point.data() + 4 * k;
    const std::uint32_t d = surface.opposite_vertex(contacts.triangle_point_triangle[k]);
    const std::uint32_t p = contact[0], a = contact[1], b = contact[2], c = contact[3];
    bool made = false;
    if (d != SolidSurface::kNone && d != p) {
      // The closest point and the normal at the start of the substep, while p was outside.
      const Vector3r sp = start(p), sa = start(a), sb = start(b), sc = start(c), sd = start(d);
      const auto start_edges = frame(sa, sb, sc, sd);
      const auto edges = frame(position(state, a), position(state, b), position(state, c),
                               position(state, d));
      Vector3r face_normal = (sb - sa).cross(sc - sa).normalized();
      if (face_normal.dot(sd - sa) > 0) face_normal = -face_normal;  // away from d
      const Vector3r closest = detail::closest_point_on_triangle(sp, sa, sb, sc);
      // See "Which normal" in solid_contacts.hpp: the face's in front of it, the direction
      // from the closest edge point beside it, nothing behind its plane beside it.
      Vector3r n = face_normal;
      if (!projects_inside(sp, sa, sb, sc, face_normal)) {
        const Vector3r away = sp - closest;
        if (!(face_normal.dot(away) > 0) || !(away.norm() > Real(1e-6))) continue;
        n = away.normalized();
      }
      if (start_edges && edges) {
        // The closest point moves with the tetrahedron (its coordinates at the start); the
        // contact point is the thickness beyond it along n, in the predicted tetrahedron.
        const Vector3r weights =
            start_edges->inverse() * (closest - sa) + edges->inverse() * (thickness * n);
        if (weights.allFinite() && n.allFinite()) {
          particles.insert(particles.end(), {p, a, b, c, d});
          barycentric.push_back(weights);
          normals.push_back(n);
          made = true;
        }
      }
    }
    if (!made) remaining_triangle_point.insert(remaining_triangle_point.end(), contact, contact + 4);
  }
  make_particle_tet_contacts(
      {.particles = particles, .barycentric = barycentric, .normals = normals, .friction = friction},
      state, particle_tet);
}

void drop_solid_edge_pairs(const SolidSurface& surface, std::vector<ParticleIndex>& edge_edge) {
  std::size_t kept = 0;
  for (std::size_t k = 0; k + 3 < edge_edge.size(); k += 4) {
    const ParticleIndex* pair = edge_edge.data() + k;
    if (surface.solid_particle(pair[0]) && surface.solid_particle(pair[1]) &&
        surface.solid_particle(pair[2]) && surface.solid_particle(pair[3]))
      continue;
    std::copy_n(pair, 4, edge_edge.data() + kept);
    kept += 4;
  }
  edge_edge.resize(kept);
}

Real solid_penetration_depth(std::span<const Vector3r> positions,
                             std::span<const std::uint32_t> tetrahedra) {
  const std::vector<TetFace> faces =
      tet_faces(tetrahedra, positions.size(), "solid penetration depth");
  const std::vector<std::uint32_t> body = bodies_of(tetrahedra, positions.size());
  // Boundary faces (a key met once), grouped by body; their vertices are the ones tested.
  std::vector<Key> boundary;
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j == i + 1) boundary.push_back(faces[i].key);
    i = j;
  }
  std::stable_sort(boundary.begin(), boundary.end(), [&](const Key& l, const Key& r) {
    return body[l[0]] < body[r[0]];
  });
  std::vector<std::uint32_t> boundary_vertices;
  for (const Key& key : boundary) boundary_vertices.insert(boundary_vertices.end(), key.begin(), key.end());
  std::sort(boundary_vertices.begin(), boundary_vertices.end());
  boundary_vertices.erase(std::unique(boundary_vertices.begin(), boundary_vertices.end()),
                          boundary_vertices.end());

  const std::size_t tet_count = tetrahedra.size() / 4;
  std::vector<Aabb> boxes(tet_count);
  for (std::size_t t = 0; t < tet_count; ++t) {
    const Vector3r& first = positions[tetrahedra[4 * t]];
    Aabb box{{first.x(), first.y(), first.z()}, {first.x(), first.y(), first.z()}};
    for (int k = 1; k < 4; ++k) {
      const Vector3r& v = positions[tetrahedra[4 * t + std::size_t(k)]];
      for (int axis = 0; axis < 3; ++axis)
        box.lo[axis] = std::min(box.lo[axis], v[axis]), box.hi[axis] = std::max(box.hi[axis], v[axis]);
    }
    boxes[t] = box;
  }
  UniformGrid grid;
  grid.build(boxes);

  // In the closed tetrahedron, in double: a point on an inner face of the other body is in
  // (its depth is measured to the body's boundary), and one on its boundary measures 0.
  const auto inside = [&](const Vector3r& point, std::size_t t) {
    Eigen::Vector3d x[4];
    for (int k = 0; k < 4; ++k) x[k] = positions[tetrahedra[4 * t + std::size_t(k)]].cast<double>();
    const Eigen::Vector3d p = point.cast<double>();
    const auto volume = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                           const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
      return (b - a).dot((c - a).cross(d - a));
    };
    const double whole = volume(x[0], x[1], x[2], x[3]);
    if (whole == 0) return false;
    const double parts[4] = {volume(p, x[1], x[2], x[3]), volume(x[0], p, x[2], x[3]),
                             volume(x[0], x[1], p, x[3]), volume(x[0], x[1], x[2], p)};
    for (const double part : parts)
      if (!(part / whole >= -1e-9)) return false;
    return true;
  };
  const auto depth_in_body = [&](const Vector3r& point, std::uint32_t b) {
    const auto first = std::lower_bound(boundary.begin(), boundary.end(), b,
                                        [&](const Key& key, std::uint32_t v) { return body[key[0]] < v; });
    Real nearest = std::numeric_limits<Real>::max();
    for (auto face = first; face != boundary.end() && body[(*face)[0]] == b; ++face)
      nearest = std::min(nearest, detail::squared_point_triangle_distance(
                                      point, positions[(*face)[0]], positions[(*face)[1]],
                                      positions[(*face)[2]]));
    return std::sqrt(nearest);
  };
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, boundary_vertices.size(), 256), Real(0),
      [&](const tbb::blocked_range<std::size_t>& range, Real deepest) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          const std::uint32_t v = boundary_vertices[i];
          const Vector3r& point = positions[v];
          const Aabb query{{point.x(), point.y(), point.z()}, {point.x(), point.y(), point.z()}};
          std::uint32_t measured_body = SolidSurface::kNone;
          grid.for_each_overlap(query, [&](std::uint32_t t) {
            const std::uint32_t b = body[tetrahedra[4 * std::size_t(t)]];
            if (b == body[v] || b == measured_body || !inside(point, t)) return;
            measured_body = b;  // one measure per body met (a vertex is rarely in two)
            deepest = std::max(deepest, depth_in_body(point, b));
          });
        }
        return deepest;
      },
      [](Real l, Real r) { return std::max(l, r); });
}

}  // namespace tessera
