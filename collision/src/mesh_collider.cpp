// The mesh collider: validation, pseudo-normals and a BVH built once, then closest-point and
// segment queries that walk it.
//
// The BVH is binary, split at the median triangle centroid along the longest axis of the
// centroid bounds, with up to kLeafSize triangles per leaf; the triangles are stored in leaf
// order so a leaf reads consecutive memory. The closest-point walk visits the nearer child
// first and skips every box farther than the best distance so far; the segment walk skips
// boxes the segment (clipped at the best crossing so far) misses. Only the corners are read
// during a walk; the normals of the one triangle found are read at the end.
#include <tessera/collision/mesh_collider.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <unordered_map>

#include <tessera/core/error.hpp>

namespace tessera {

namespace {

constexpr std::size_t kLeafSize = 4;
/// A closest point whose barycentric coordinate is below this is on the edge (or vertex) it
/// is next to: there the face normal alone could give the wrong sign, the pseudo-normal
/// cannot (it blends the neighbour's normal in, never reverses).
constexpr Real kFeatureSnap = 64 * std::numeric_limits<Real>::epsilon();

/// Where on a triangle its closest point lies. Edge k runs from corner k to corner k + 1.
enum class Feature : std::uint8_t { face, edge0, edge1, edge2, vertex0, vertex1, vertex2 };

struct TrianglePoint {
  Vector3r point;
  Feature feature;
};

/// The closest point of triangle (a, b, c) to p and the feature it lies on (Ericson, Real-Time
/// Collision Detection, 5.1.5), feature snapped to an edge or vertex within kFeatureSnap.
TrianglePoint closest_on_triangle(const Vector3r& p, const Vector3r& a, const Vector3r& b,
                                  const Vector3r& c) {
  const Vector3r ab = b - a, ac = c - a, ap = p - a;
  const Real d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {a, Feature::vertex0};
  const Vector3r bp = p - b;
  const Real d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {b, Feature::vertex1};
  const auto on_edge = [](const Vector3r& from, const Vector3r& along, Real t, Feature edge,
                          Feature start, Feature end) -> TrianglePoint {
    if (t <= kFeatureSnap) return {from, start};
    if (t >= 1 - kFeatureSnap) return {from + along, end};
    return {from + t * along, edge};
  };
  const Real vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0)
    return on_edge(a, ab, d1 / (d1 - d3), Feature::edge0, Feature::vertex0, Feature::vertex1);
  const Vector3r cp = p - c;
  const Real d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {c, Feature::vertex2};
  const Real vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0)
    return on_edge(c, a - c, 1 - d2 / (d2 - d6), Feature::edge2, Feature::vertex2,
                   Feature::vertex0);
  const Real va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
    return on_edge(b, c - b, (d4 - d3) / ((d4 - d3) + (d5 - d6)), Feature::edge1,
                   Feature::vertex1, Feature::vertex2);
  const Real denominator = 1 / (va + vb + vc);
  const Real v = vb * denominator, w = vc * denominator, u = 1 - v - w;
  const Vector3r point = a + v * ab + w * ac;
  // Snap the interior point to the edge opposite a vanishing coordinate, or to the vertex
  // when two vanish.
  const bool near_a = u <= kFeatureSnap, near_b = v <= kFeatureSnap, near_c = w <= kFeatureSnap;
  if (near_b && near_c) return {a, Feature::vertex0};
  if (near_a && near_c) return {b, Feature::vertex1};
  if (near_a && near_b) return {c, Feature::vertex2};
  if (near_c) return {point, Feature::edge0};
  if (near_a) return {point, Feature::edge1};
  if (near_b) return {point, Feature::edge2};
  return {point, Feature::face};
}

/// Branch-free (maxss): which side of a box a point is on is unpredictable during a walk.
inline Real larger(Real a, Real b) { return a > b ? a : b; }

[[gnu::always_inline]] inline Real squared_distance_to_box(const Vector3r& p, const Vector3r& lower,
                                                           const Vector3r& upper) {
  const Real dx = larger(larger(lower.x() - p.x(), p.x() - upper.x()), Real(0));
  const Real dy = larger(larger(lower.y() - p.y(), p.y() - upper.y()), Real(0));
  const Real dz = larger(larger(lower.z() - p.z(), p.z() - upper.z()), Real(0));
  return dx * dx + dy * dy + dz * dz;
}

std::string triangle_name(std::size_t t) {
  return "mesh collider: triangle " + std::to_string(t);
}

}  // namespace

struct MeshCollider::Data {
  /// An inner node (count 0) has its children at first and first + 1; a leaf holds triangles
  /// [first, first + count) of the leaf-ordered arrays.
  struct Node {
    Vector3r lower, upper;
    std::uint32_t first;
    std::uint32_t count;
  };
  std::vector<Node> nodes;
  std::vector<std::array<Vector3r, 3>> corners;
  /// A ball around each triangle (centre, radius): a triangle whose ball is farther than the
  /// best distance so far is skipped with one dot product.
  std::vector<Vector4r> ball;
  std::vector<Vector3r> face_normal;
  std::vector<std::array<Vector3r, 3>> edge_normal;    // edge k: corner k → k + 1
  std::vector<std::array<Vector3r, 3>> vertex_normal;  // at corner k
  bool closed = false;

  Vector3r pseudo_normal(std::size_t t, Feature feature) const {
    switch (feature) {
      case Feature::face: return face_normal[t];
      case Feature::edge0: return edge_normal[t][0];
      case Feature::edge1: return edge_normal[t][1];
      case Feature::edge2: return edge_normal[t][2];
      case Feature::vertex0: return vertex_normal[t][0];
      case Feature::vertex1: return vertex_normal[t][1];
      case Feature::vertex2: return vertex_normal[t][2];
    }
    return face_normal[t];
  }

  /// Builds the node for leaf-ordered triangles [first, first + count) and its subtree.
  void build(std::vector<std::uint32_t>& order, const std::vector<Vector3r>& centroids,
             const std::vector<std::array<Vector3r, 3>>& input_corners, std::size_t node,
             std::uint32_t first, std::uint32_t count) {
    Vector3r lower = Vector3r::Constant(std::numeric_limits<Real>::max());
    Vector3r upper = -lower;
    Vector3r centroid_lower = lower, centroid_upper = upper;
    for (std::uint32_t i = first; i < first + count; ++i) {
      for (const Vector3r& corner : input_corners[order[i]]) {
        lower = lower.cwiseMin(corner);
        upper = upper.cwiseMax(corner);
      }
      centroid_lower = centroid_lower.cwiseMin(centroids[order[i]]);
      centroid_upper = centroid_upper.cwiseMax(centroids[order[i]]);
    }
    nodes[node].lower = lower;
    nodes[node].upper = upper;
    if (count <= kLeafSize) {
      nodes[node].first = first;
      nodes[node].count = count;
      return;
    }
    int axis = 0;
    (centroid_upper - centroid_lower).maxCoeff(&axis);
    const std::uint32_t half = count / 2;
    // Ties broken by input index, so the tree does not depend on nth_element's internals.
    std::nth_element(order.begin() + first, order.begin() + first + half,
                     order.begin() + first + count, [&](std::uint32_t l, std::uint32_t r) {
                       return centroids[l][axis] < centroids[r][axis] ||
                              (centroids[l][axis] == centroids[r][axis] && l < r);
                     });
    const std::size_t left = nodes.size();
    nodes.resize(left + 2);
    nodes[node].first = std::uint32_t(left);
    nodes[node].count = 0;
    build(order, centroids, input_corners, left, first, half);
    build(order, centroids, input_corners, left + 1, first + half, count - half);
  }
};

MeshCollider::MeshCollider(std::span<const Vector3r> positions,
                           std::span<const ParticleIndex> triangles) {
  if (triangles.empty()) throw InvalidInput("mesh collider: no triangles");
  if (triangles.size() % 3 != 0)
    throw InvalidInput("mesh collider: " + std::to_string(triangles.size()) +
                       " triangle indices, not a multiple of 3");
  const std::size_t count = triangles.size() / 3;
  if (count > std::numeric_limits<std::uint32_t>::max() / 2)
    throw InvalidInput("mesh collider: " + std::to_string(count) + " triangles are too many");

  // Corners and face normals in input order, validated.
  std::vector<std::array<Vector3r, 3>> input_corners(count);
  std::vector<Vector3r> input_normals(count);
  for (std::size_t t = 0; t < count; ++t) {
    for (int k = 0; k < 3; ++k) {
      const ParticleIndex v = triangles[3 * t + k];
      if (v >= positions.size())
        throw InvalidInput(triangle_name(t) + ": vertex index " + std::to_string(v) +
                           " is out of range (" + std::to_string(positions.size()) +
                           " positions)");
      if (!positions[v].allFinite())
        throw InvalidInput(triangle_name(t) + ": position of vertex " + std::to_string(v) +
                           " is not finite");
      input_corners[t][k] = positions[v];
    }
    const ParticleIndex* v = &triangles[3 * t];
    if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0])
      throw InvalidInput(triangle_name(t) + " is degenerate: it names vertex " +
                         std::to_string(v[0] == v[1] || v[0] == v[2] ? v[0] : v[1]) + " twice");
    const auto& [a, b, c] = input_corners[t];
    const Vector3r cross = (b - a).cross(c - a);
    const Real longest_squared =
        std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
    const Real area2 = cross.norm();
    if (!(area2 > kDegenerateTolerance * longest_squared))
      throw InvalidInput(triangle_name(t) + " is degenerate: its corners (vertices " +
                         std::to_string(v[0]) + ", " + std::to_string(v[1]) + ", " +
                         std::to_string(v[2]) + ") are collinear or coincide");
    input_normals[t] = cross / area2;
  }

  auto data = std::make_shared<Data>();

  // Pseudo-normals (Bærentzen & Aanæs): an edge sums the normals of its triangles, a vertex
  // sums them weighted by the triangle's angle at the vertex.
  std::unordered_map<std::uint64_t, Vector3r> edge_sums;
  std::unordered_map<std::uint64_t, std::uint32_t> edge_uses;
  std::vector<Vector3r> vertex_sums(positions.size(), Vector3r::Zero());
  const auto edge_key = [&](std::size_t t, int k) {
    const std::uint64_t u = triangles[3 * t + k], w = triangles[3 * t + (k + 1) % 3];
    return std::min(u, w) << 32 | std::max(u, w);
  };
  for (std::size_t t = 0; t < count; ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t key = edge_key(t, k);
      auto [it, inserted] = edge_sums.try_emplace(key, Vector3r::Zero());
      it->second += input_normals[t];
      ++edge_uses[key];
      const Vector3r& corner = input_corners[t][k];
      const Vector3r to_next = (input_corners[t][(k + 1) % 3] - corner).normalized();
      const Vector3r to_previous = (input_corners[t][(k + 2) % 3] - corner).normalized();
      const Real angle = std::acos(std::clamp(to_next.dot(to_previous), Real(-1), Real(1)));
      vertex_sums[triangles[3 * t + k]] += angle * input_normals[t];
    }
  data->closed = std::all_of(edge_uses.begin(), edge_uses.end(),
                             [](const auto& entry) { return entry.second == 2; });

  // The BVH, then every per-triangle array in its leaf order.
  std::vector<std::uint32_t> order(count);
  std::vector<Vector3r> centroids(count);
  for (std::size_t t = 0; t < count; ++t) {
    order[t] = std::uint32_t(t);
    centroids[t] = (input_corners[t][0] + input_corners[t][1] + input_corners[t][2]) / 3;
  }
  data->nodes.reserve(2 * count);
  data->nodes.resize(1);
  data->build(order, centroids, input_corners, 0, 0, std::uint32_t(count));

  data->corners.resize(count);
  data->ball.resize(count);
  data->face_normal.resize(count);
  data->edge_normal.resize(count);
  data->vertex_normal.resize(count);
  // A pseudo-normal sum may vanish (two triangles folded onto each other); the face normal is
  // then the best there is.
  const auto unit_or = [](const Vector3r& sum, const Vector3r& fallback) -> Vector3r {
    const Real length = sum.norm();
    return length > kDegenerateTolerance ? Vector3r(sum / length) : fallback;
  };
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t t = order[i];
    data->corners[i] = input_corners[t];
    const Vector3r& centre = centroids[t];
    Real radius = 0;
    for (const Vector3r& corner : input_corners[t]) radius = std::max(radius, (corner - centre).norm());
    data->ball[i] << centre, radius * (1 + 4 * std::numeric_limits<Real>::epsilon());
    data->face_normal[i] = input_normals[t];
    for (int k = 0; k < 3; ++k) {
      data->edge_normal[i][k] = unit_or(edge_sums.at(edge_key(t, k)), input_normals[t]);
      data->vertex_normal[i][k] = unit_or(vertex_sums[triangles[3 * t + k]], input_normals[t]);
    }
  }
  data_ = std::move(data);
}

std::size_t MeshCollider::triangle_count() const { return data_->corners.size(); }

bool MeshCollider::closed() const { return data_->closed; }

Bounds3 MeshCollider::bounds() const { return {data_->nodes[0].lower, data_->nodes[0].upper}; }

SurfaceQuery MeshCollider::closest_surface(const Vector3r& p) const {
  const Data& mesh = *data_;
  Real best_squared = std::numeric_limits<Real>::infinity();
  std::size_t best_triangle = 0;
  TrianglePoint best{};
  // Nodes to visit with their box's squared distance, so a node the bound has passed since
  // it was pushed is dropped without testing its box again. The tree's depth is at most
  // log2(count) + 1: 64 entries are enough for any mesh that fits in memory.
  struct Pending {
    std::uint32_t node;
    Real squared_distance;
  };
  Pending stack[64];
  int top = 0;
  stack[top++] = {0, 0};
  while (top > 0) {
    const Pending pending = stack[--top];
    if (pending.squared_distance >= best_squared) continue;
    const Data::Node& node = mesh.nodes[pending.node];
    if (node.count > 0) {
      for (std::uint32_t t = node.first; t < node.first + node.count; ++t) {
        const Vector4r& ball = mesh.ball[t];
        const Real to_centre = (p - ball.head<3>()).norm() - ball[3];
        if (to_centre > 0 && to_centre * to_centre >= best_squared) continue;
        const auto& [a, b, c] = mesh.corners[t];
        const TrianglePoint candidate = closest_on_triangle(p, a, b, c);
        const Real squared = (p - candidate.point).squaredNorm();
        if (squared < best_squared) {
          best_squared = squared;
          best_triangle = t;
          best = candidate;
        }
      }
      continue;
    }
    const Data::Node& left = mesh.nodes[node.first];
    const Data::Node& right = mesh.nodes[node.first + 1];
    const Real to_left = squared_distance_to_box(p, left.lower, left.upper);
    const Real to_right = squared_distance_to_box(p, right.lower, right.upper);
    // Push the farther child first so the nearer one is walked first and shrinks the bound.
    if (to_left <= to_right) {
      if (to_right < best_squared) stack[top++] = {node.first + 1, to_right};
      if (to_left < best_squared) stack[top++] = {node.first, to_left};
    } else {
      if (to_left < best_squared) stack[top++] = {node.first, to_left};
      if (to_right < best_squared) stack[top++] = {node.first + 1, to_right};
    }
  }
  const Vector3r pseudo_normal = mesh.pseudo_normal(best_triangle, best.feature);
  const Vector3r away = p - best.point;
  const Real distance = std::sqrt(best_squared);
  const Real sign = away.dot(pseudo_normal) < 0 ? Real(-1) : Real(1);
  // On the surface (or so near that the direction is noise) the feature's normal says it.
  if (!(distance > kDegenerateTolerance * (Real(1) + p.cwiseAbs().maxCoeff())))
    return {0, pseudo_normal, best.point};
  return {sign * distance, sign * away / distance, best.point};
}

bool MeshCollider::first_entry(const Vector3r& from, const Vector3r& to, Vector3r& point,
                               Vector3r& normal) const {
  const Data& mesh = *data_;
  const Vector3r direction = to - from;
  if (!(direction.squaredNorm() > 0)) return false;
  const Vector3r inverse = direction.cwiseInverse();  // ±inf on an axis it does not move along
  Real best_t = std::numeric_limits<Real>::infinity();
  std::size_t best_triangle = 0;
  const auto segment_meets_box = [&](const Data::Node& node) {
    Real near = 0, far = std::min(Real(1), best_t);
    for (int k = 0; k < 3; ++k) {
      if (direction[k] == 0) {
        if (from[k] < node.lower[k] || from[k] > node.upper[k]) return false;
        continue;
      }
      Real t0 = (node.lower[k] - from[k]) * inverse[k];
      Real t1 = (node.upper[k] - from[k]) * inverse[k];
      if (t0 > t1) std::swap(t0, t1);
      near = std::max(near, t0);
      far = std::min(far, t1);
      if (near > far) return false;
    }
    return true;
  };
  std::uint32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Data::Node& node = mesh.nodes[stack[--top]];
    if (!segment_meets_box(node)) continue;
    if (node.count == 0) {
      stack[top++] = node.first + 1;
      stack[top++] = node.first;
      continue;
    }
    for (std::uint32_t t = node.first; t < node.first + node.count; ++t) {
      // Only a crossing against the normal is an entry.
      if (!(direction.dot(mesh.face_normal[t]) < 0)) continue;
      // Möller–Trumbore.
      const auto& [a, b, c] = mesh.corners[t];
      const Vector3r ab = b - a, ac = c - a;
      const Vector3r h = direction.cross(ac);
      const Real det = ab.dot(h);
      if (det == 0) continue;
      const Real inverse_det = 1 / det;
      const Vector3r s = from - a;
      // A little slack on the barycentric bounds, so a segment through an edge or a vertex is
      // not missed by both of its triangles through rounding (it may then hit both: the
      // nearer crossing wins either way).
      const Real u = s.dot(h) * inverse_det;
      if (u < -kFeatureSnap || u > 1 + kFeatureSnap) continue;
      const Vector3r q = s.cross(ab);
      const Real v = direction.dot(q) * inverse_det;
      if (v < -kFeatureSnap || u + v > 1 + kFeatureSnap) continue;
      const Real t_hit = ac.dot(q) * inverse_det;
      if (t_hit < 0 || t_hit > 1 || t_hit >= best_t) continue;
      best_t = t_hit;
      best_triangle = t;
    }
  }
  if (!(best_t <= 1)) return false;
  point = from + best_t * direction;
  normal = mesh.face_normal[best_triangle];
  return true;
}

}  // namespace tessera
