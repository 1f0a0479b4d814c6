// The mesh collider: validation, pseudo-normals and a BVH built once, then closest-point and
// segment queries that walk it.
//
// The BVH is built binary with binned surface-area splits (Wald 2007; on the 10k-triangle
// sphere of mesh_collider.hpp they made queries about 1.6x faster than median splits), up to
// kLeafSize triangles per leaf, then collapsed to four children per node with their boxes
// side by side. The triangles are stored in leaf order so a leaf reads consecutive memory. The
// closest-point walk visits the nearest child first and drops every box farther than the best
// distance so far; the segment walk drops boxes the segment (clipped at the best crossing so
// far) misses. Only the corners are read during a walk; the normals of the one triangle found
// are read at the end.
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
/// Surface-area splits may cut off few triangles at a time; from this depth on the builder
/// halves at the median instead, so the binary tree is at most kMaxSplitDepth + 32 deep (the
/// 2^32 triangles of a ParticleIndex halved 32 times) and a walk's stack of kWalkStack entries
/// (at most 3 per level, plus 4) can never overflow.
constexpr std::uint32_t kMaxSplitDepth = 40;
constexpr std::size_t kWalkStack = 256;
static_assert(3 * (kMaxSplitDepth + 32) + 4 <= kWalkStack);
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

/// Branch-free (maxss, and the four box distances of a node vectorise): which side of a box a
/// point is on is unpredictable during a walk.
inline Real larger(Real a, Real b) { return a > b ? a : b; }

std::string triangle_name(std::size_t t) {
  return "mesh collider: triangle " + std::to_string(t);
}

}  // namespace

struct MeshCollider::Data {
  /// The binary tree as built: an inner node (count 0) has its children at first and
  /// first + 1; a leaf holds triangles [first, first + count) of the leaf-ordered arrays.
  struct Node {
    Vector3r lower, upper;
    std::uint32_t first;
    std::uint32_t count;
  };
  /// The tree walked: the binary one collapsed to four children per node, their boxes side
  /// by side so that a node's four box distances are computed together (one SIMD pass) and
  /// a walk visits half as many nodes. Slot k holds an inner node (count 0, child its index),
  /// a leaf (count > 0, triangles [child, child + count)) or nothing (kEmpty, a box no
  /// point is near).
  struct WideNode {
    std::array<Real, 4> lower_x, lower_y, lower_z, upper_x, upper_y, upper_z;
    std::array<std::uint32_t, 4> child, count;
  };
  static constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();
  std::vector<Node> nodes;
  std::vector<WideNode> wide;
  Bounds3 bounds;
  std::vector<std::array<Vector3r, 3>> corners;
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

  /// Builds the node at `depth` for leaf-ordered triangles [first, first + count) and its
  /// subtree.
  void build(std::vector<std::uint32_t>& order, const std::vector<Vector3r>& centroids,
             const std::vector<std::array<Vector3r, 3>>& input_corners, std::size_t node,
             std::uint32_t first, std::uint32_t count, std::uint32_t depth) {
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
    const std::uint32_t half = split(order, centroids, input_corners, first, count,
                                     centroid_lower, centroid_upper, depth < kMaxSplitDepth);
    const std::size_t left = nodes.size();
    nodes.resize(left + 2);
    nodes[node].first = std::uint32_t(left);
    nodes[node].count = 0;
    build(order, centroids, input_corners, left, first, half, depth + 1);
    build(order, centroids, input_corners, left + 1, first + half, count - half, depth + 1);
  }

  /// Reorders triangles [first, first + count) into two halves and returns the size of the
  /// first: the binned surface-area split (Wald 2007), which keeps boxes small and apart so a
  /// walk opens few of them, or the median along the longest axis when no split separates
  /// the centroids or `by_area` is false.
  static std::uint32_t split(std::vector<std::uint32_t>& order,
                             const std::vector<Vector3r>& centroids,
                             const std::vector<std::array<Vector3r, 3>>& input_corners,
                             std::uint32_t first, std::uint32_t count,
                             const Vector3r& centroid_lower, const Vector3r& centroid_upper,
                             bool by_area) {
    constexpr int kBins = 16;
    struct Bin {
      Vector3r lower = Vector3r::Constant(std::numeric_limits<Real>::max());
      Vector3r upper = Vector3r::Constant(-std::numeric_limits<Real>::max());
      std::uint32_t count = 0;
      void grow(const Bin& other) {
        lower = lower.cwiseMin(other.lower);
        upper = upper.cwiseMax(other.upper);
        count += other.count;
      }
      Real cost() const {
        if (count == 0) return 0;
        const Vector3r size = upper - lower;
        return (size.x() * size.y() + size.y() * size.z() + size.z() * size.x()) * Real(count);
      }
    };
    const auto bin_of = [&](std::uint32_t t, int axis) {
      const Real extent = centroid_upper[axis] - centroid_lower[axis];
      const int bin = int((centroids[t][axis] - centroid_lower[axis]) / extent * kBins);
      return std::clamp(bin, 0, kBins - 1);
    };
    Real best_cost = std::numeric_limits<Real>::infinity();
    int best_axis = -1, best_bin = 0;
    for (int axis = 0; axis < 3 && by_area; ++axis) {
      if (!(centroid_upper[axis] > centroid_lower[axis])) continue;
      std::array<Bin, kBins> bins;
      for (std::uint32_t i = first; i < first + count; ++i) {
        Bin& bin = bins[bin_of(order[i], axis)];
        for (const Vector3r& corner : input_corners[order[i]]) {
          bin.lower = bin.lower.cwiseMin(corner);
          bin.upper = bin.upper.cwiseMax(corner);
        }
        ++bin.count;
      }
      std::array<Real, kBins> right_cost{};
      Bin right;
      for (int b = kBins - 1; b > 0; --b) {
        right.grow(bins[b]);
        right_cost[b] = right.cost();
      }
      Bin left;
      for (int b = 0; b + 1 < kBins; ++b) {
        left.grow(bins[b]);
        const Real cost = left.cost() + right_cost[b + 1];
        if (left.count > 0 && left.count < count && cost < best_cost) {
          best_cost = cost;
          best_axis = axis;
          best_bin = b;
        }
      }
    }
    if (best_axis >= 0) {
      const auto middle =
          std::partition(order.begin() + first, order.begin() + first + count,
                         [&](std::uint32_t t) { return bin_of(t, best_axis) <= best_bin; });
      return std::uint32_t(middle - (order.begin() + first));
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
    return half;
  }

  /// The wide node made of binary node `binary`'s descendants (its children, then the
  /// children of the largest inner ones, up to four) and its subtree; returns its index.
  std::uint32_t collapse(std::uint32_t binary) {
    std::array<std::uint32_t, 4> slots{};
    std::size_t used = 0;
    if (nodes[binary].count > 0) {
      slots[used++] = binary;
    } else {
      slots[used++] = nodes[binary].first;
      slots[used++] = nodes[binary].first + 1;
    }
    while (used < 4) {
      std::size_t largest = used;
      Real largest_area = -1;
      for (std::size_t k = 0; k < used; ++k) {
        const Node& node = nodes[slots[k]];
        if (node.count > 0) continue;
        const Vector3r size = node.upper - node.lower;
        const Real area = size.x() * size.y() + size.y() * size.z() + size.z() * size.x();
        if (area > largest_area) {
          largest_area = area;
          largest = k;
        }
      }
      if (largest == used) break;
      const std::uint32_t opened = slots[largest];
      slots[largest] = nodes[opened].first;
      slots[used++] = nodes[opened].first + 1;
    }
    const std::uint32_t index = std::uint32_t(wide.size());
    wide.emplace_back();
    for (std::size_t k = 0; k < 4; ++k) {
      const bool present = k < used;
      const Node* node = present ? &nodes[slots[k]] : nullptr;
      const Real far = std::numeric_limits<Real>::max();
      wide[index].lower_x[k] = present ? node->lower.x() : far;
      wide[index].lower_y[k] = present ? node->lower.y() : far;
      wide[index].lower_z[k] = present ? node->lower.z() : far;
      wide[index].upper_x[k] = present ? node->upper.x() : -far;
      wide[index].upper_y[k] = present ? node->upper.y() : -far;
      wide[index].upper_z[k] = present ? node->upper.z() : -far;
      wide[index].count[k] = present ? node->count : 0;
      wide[index].child[k] = present ? node->first : kEmpty;
    }
    for (std::size_t k = 0; k < used; ++k)
      if (nodes[slots[k]].count == 0) {
        const std::uint32_t child = collapse(slots[k]);
        wide[index].child[k] = child;
      }
    return index;
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
    const Real area2 = cross.stableNorm();  // no underflow for triangles of 1e-10 and below
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
  data->build(order, centroids, input_corners, 0, 0, std::uint32_t(count), 0);
  data->bounds = {data->nodes[0].lower, data->nodes[0].upper};
  data->wide.reserve(data->nodes.size() / 2 + 1);
  data->collapse(0);
  data->nodes = {};

  data->corners.resize(count);
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

Bounds3 MeshCollider::bounds() const { return data_->bounds; }

SurfaceQuery MeshCollider::closest_surface(const Vector3r& p) const {
  const Data& mesh = *data_;
  Real best_squared = std::numeric_limits<Real>::infinity();
  Real best_distance = std::numeric_limits<Real>::infinity();
  std::size_t best_triangle = 0;
  TrianglePoint best{};
  // Nodes and leaves to visit with their box's squared distance, so one the bound has passed
  // since it was pushed is dropped without testing its box again (kWalkStack is enough).
  struct Pending {
    std::uint32_t index;
    std::uint32_t count;  // 0: a wide node, else a leaf's triangle count
    Real squared_distance;
  };
  Pending stack[kWalkStack];
  int top = 0;
  stack[top++] = {0, 0, 0};
  while (top > 0) {
    const Pending pending = stack[--top];
    if (pending.squared_distance >= best_squared) continue;
    if (pending.count > 0) {
      for (std::uint32_t t = pending.index; t < pending.index + pending.count; ++t) {
        const auto& [a, b, c] = mesh.corners[t];
        const TrianglePoint candidate = closest_on_triangle(p, a, b, c);
        const Real squared = (p - candidate.point).squaredNorm();
        if (squared < best_squared) {
          best_squared = squared;
          best_distance = std::sqrt(squared);
          best_triangle = t;
          best = candidate;
        }
      }
      continue;
    }
    const Data::WideNode& node = mesh.wide[pending.index];
    std::array<Real, 4> to_child;
    for (std::size_t k = 0; k < 4; ++k) {
      const Real dx = larger(larger(node.lower_x[k] - p.x(), p.x() - node.upper_x[k]), Real(0));
      const Real dy = larger(larger(node.lower_y[k] - p.y(), p.y() - node.upper_y[k]), Real(0));
      const Real dz = larger(larger(node.lower_z[k] - p.z(), p.z() - node.upper_z[k]), Real(0));
      to_child[k] = dx * dx + dy * dy + dz * dz;
    }
    // Push the nearest last, so it is walked first and shrinks the bound; the order of the
    // others matters less than the branches a full sort would cost.
    std::size_t nearest = 0;
    for (std::size_t k = 1; k < 4; ++k)
      if (to_child[k] < to_child[nearest]) nearest = k;
    for (std::size_t k = 0; k < 4; ++k)
      if (k != nearest && to_child[k] < best_squared)
        stack[top++] = {node.child[k], node.count[k], to_child[k]};
    if (to_child[nearest] < best_squared)
      stack[top++] = {node.child[nearest], node.count[nearest], to_child[nearest]};
  }
  const Vector3r pseudo_normal = mesh.pseudo_normal(best_triangle, best.feature);
  const Vector3r away = p - best.point;
  const Real distance = best_distance;
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
  const auto segment_meets_box = [&](const Data::WideNode& node, std::size_t slot) {
    const Vector3r lower(node.lower_x[slot], node.lower_y[slot], node.lower_z[slot]);
    const Vector3r upper(node.upper_x[slot], node.upper_y[slot], node.upper_z[slot]);
    Real near = 0, far = std::min(Real(1), best_t);
    for (int k = 0; k < 3; ++k) {
      if (direction[k] == 0) {
        if (from[k] < lower[k] || from[k] > upper[k]) return false;
        continue;
      }
      Real t0 = (lower[k] - from[k]) * inverse[k];
      Real t1 = (upper[k] - from[k]) * inverse[k];
      if (t0 > t1) std::swap(t0, t1);
      near = std::max(near, t0);
      far = std::min(far, t1);
      if (near > far) return false;
    }
    return true;
  };
  struct Pending {
    std::uint32_t index;
    std::uint32_t count;
  };
  Pending stack[kWalkStack];
  int top = 0;
  stack[top++] = {0, 0};
  while (top > 0) {
    const Pending pending = stack[--top];
    if (pending.count == 0) {
      const Data::WideNode& node = mesh.wide[pending.index];
      for (std::size_t k = 0; k < 4; ++k)
        if (node.child[k] != Data::kEmpty && segment_meets_box(node, k))
          stack[top++] = {node.child[k], node.count[k]};
      continue;
    }
    for (std::uint32_t t = pending.index; t < pending.index + pending.count; ++t) {
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
