// Self-collision detection per substep, in four steps (the picture and the contact rule are
// in self_collision.hpp):
//
//   reach_boxes        each particle's motion and budget (what it may move until the next
//                      detection); the boxes of vertices, triangles and edges at the start,
//                      grown by their budgets and by r (vertices), r/2 (edges)
//   leaves             vertices, triangles and edges in leaves of kBlockLanes
//                      (primitive_leaves.hpp), the triangle and edge leaves' boxes in a
//                      uniform grid each
//   vertex–triangle    each vertex leaf queries the triangle leaves' grid once; each vertex
//                      against the met leaves' members, a vector at a time: box, topology,
//                      statics and distance as lane masks
//   edge–edge          each edge leaf the same against its own and higher edge leaves
//   filter             the candidates that meet the contact rule at this substep (also
//                      what refine() does on later substeps)
//
// Both candidate lists come out of chunked loops (chunked_output.hpp) and a counting sort:
// sorted by key, whatever the thread count. Re-boxes query the same leaf grids, each met
// leaf's members by their boxes of the build (re-boxed ones in a second grid of their own).
#include <tessera/collision/self_collision.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <tessera/core/error.hpp>

#include "chunked_output.hpp"
#include "closest_distance.hpp"
#include "leaf_scan.hpp"
#include "primitive_leaves.hpp"
#include "segment_distances.hpp"
#include "triangle_distances.hpp"

namespace tessera {

struct SelfCollision::Chunks {
  detail::ChunkedOutput<Candidate> triangle_point_candidates, edge_edge_candidates,
      triangle_point_others;
  detail::ChunkedOutput<Pair> triangle_point, edge_edge;
  detail::ChunkedOutput<std::uint32_t> vertices;
  /// The filter's measured candidates per chunk, a cache line each (one thread per chunk).
  struct alignas(64) Count {
    std::size_t measured;
  };
  std::vector<Count> measured;
  /// The largest coordinate of each chunk of particles (measure_departures).
  struct alignas(64) Largest {
    Real coordinate;
  };
  std::vector<Largest> largest;
};

namespace {
/// A triangle leaf's lanes: corners a, b, c (x, y, z each), budget, velocity ball (centre,
/// radius), box (lo, hi), corners' particles, all static; an edge leaf's: p, q (x, y, z
/// each), budget, ball, box, particles (p, q, q), all static.
constexpr std::size_t kTriangleLeafFields = 9 + detail::kLeafTailFields,
                      kEdgeLeafFields = 6 + detail::kLeafTailFields;
constexpr Aabb kEmptyBox{{std::numeric_limits<Real>::max(), std::numeric_limits<Real>::max(),
                          std::numeric_limits<Real>::max()},
                         {std::numeric_limits<Real>::lowest(), std::numeric_limits<Real>::lowest(),
                          std::numeric_limits<Real>::lowest()}};
/// Leaves per chunk of a build's chunked loops (chunked_output.hpp): kCollisionChunk / 2
/// primitives, each a query.
constexpr std::size_t kLeafChunk = detail::kCollisionChunk / 2 / detail::kBlockLanes;
/// Queries per chunk of a re-box's loops over its outran vertices and new edges: a re-box
/// of the 128² drape has ~190 and ~730, about a microsecond each. At kCollisionChunk they
/// were one and two tasks, so the vertices' queries ran on one thread.
constexpr std::size_t kReboxQueryChunk = 32;
/// parallel_over's grain (a range of at most this many items is not split): per particle
/// or primitive, cheap bodies.
constexpr std::size_t kItemGrain = 2048;
/// Per leaf of kBlockLanes primitives: a body kBlockLanes times the work, and a mesh of
/// 10^4–10^5 primitives has only 10^3–10^4 leaves. At kItemGrain the 128² drape's 1,024
/// vertex leaves and 2,017 triangle leaves were one task each.
constexpr std::size_t kLeafGrain = 32;
}  // namespace

struct SelfCollision::Leaves {
  detail::PrimitiveLeaves vertices, triangles, edges;
  detail::LeafFields<kTriangleLeafFields> triangle_fields;
  detail::LeafFields<kEdgeLeafFields> edge_fields;
};

namespace {

std::vector<std::uint32_t> unique_edges(std::span<const std::uint32_t> triangles) {
  std::vector<std::uint64_t> keys;
  keys.reserve(triangles.size());
  for (std::size_t t = 0; t + 2 < triangles.size(); t += 3)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = triangles[t + std::size_t(k)];
      const std::uint32_t b = triangles[t + std::size_t((k + 1) % 3)];
      keys.push_back((std::uint64_t(std::min(a, b)) << 32) | std::max(a, b));
    }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<std::uint32_t> edges;
  edges.reserve(2 * keys.size());
  for (const std::uint64_t key : keys) {
    edges.push_back(std::uint32_t(key >> 32));
    edges.push_back(std::uint32_t(key));
  }
  return edges;
}

/// Grows `box` to hold p.
void include(Aabb& box, Real x, Real y, Real z) {
  box.lo[0] = std::min(box.lo[0], x), box.hi[0] = std::max(box.hi[0], x);
  box.lo[1] = std::min(box.lo[1], y), box.hi[1] = std::max(box.hi[1], y);
  box.lo[2] = std::min(box.lo[2], z), box.hi[2] = std::max(box.hi[2], z);
}

void inflate(Aabb& box, Real by) {
  for (int axis = 0; axis < 3; ++axis) box.lo[axis] -= by, box.hi[axis] += by;
}

/// The paths of particles `ids` and what they may stray: the box of their references now
/// and `steps` substeps on (every reference between is on the segments, so in the box),
/// grown by their largest budget, their largest speed (one substep of relative motion) and
/// `reach`.
struct Paths {
  const Vector3r* reference;
  const Vector3r* velocity;
  const Real* speed;
  const Real* budget;
};
template <std::size_t N>
Aabb swept_box(const std::uint32_t (&ids)[N], const Paths& paths, Real steps, Real reach) {
  const Vector3r& a = paths.reference[ids[0]];
  Aabb box{{a.x(), a.y(), a.z()}, {a.x(), a.y(), a.z()}};
  Real budget = 0, speed = 0;
  for (const std::uint32_t i : ids) {
    const Vector3r& now = paths.reference[i];
    const Vector3r later = now + steps * paths.velocity[i];
    include(box, now.x(), now.y(), now.z());
    include(box, later.x(), later.y(), later.z());
    budget = std::max(budget, paths.budget[i]);
    speed = std::max(speed, paths.speed[i]);
  }
  inflate(box, budget + speed + reach);
  return box;
}

/// Reads the particles' arrays by index.
struct Particles {
  const SelfCollisionPositions& p;
  Vector3r start(std::uint32_t i) const {
    return Vector3r(p.previous_x[i], p.previous_y[i], p.previous_z[i]);
  }
  bool all_static(std::initializer_list<std::uint32_t> ids) const {
    for (const std::uint32_t i : ids)
      if (p.inverse_mass[i] != 0) return false;
    return true;
  }
  /// Whether edges (p0, p1) and (p2, p3) can be an edge–edge contact: no shared vertex, not
  /// all four static.
  bool may_touch(std::uint32_t p0, std::uint32_t p1, std::uint32_t p2, std::uint32_t p3) const {
    return p0 != p2 && p0 != p3 && p1 != p2 && p1 != p3 && !all_static({p0, p1, p2, p3});
  }
};

/// Whether the point sets a and b are farther apart than `within` along some axis: then no
/// point of the one's hull is within `within` of the other's (every distance is at least its
/// largest axis difference), so the exact distance test can be skipped with the same answer.
template <std::size_t N, std::size_t M>
bool separated_along_an_axis(const Vector3r (&a)[N], const Vector3r (&b)[M], Real within) {
  for (int axis = 0; axis < 3; ++axis) {
    Real a_lo = a[0][axis], a_hi = a_lo, b_lo = b[0][axis], b_hi = b_lo;
    for (std::size_t i = 1; i < N; ++i) a_lo = std::min(a_lo, a[i][axis]), a_hi = std::max(a_hi, a[i][axis]);
    for (std::size_t i = 1; i < M; ++i) b_lo = std::min(b_lo, b[i][axis]), b_hi = std::max(b_hi, b[i][axis]);
    if (b_lo - a_hi > within || a_lo - b_hi > within) return true;
  }
  return false;
}

/// The most any point of the one primitive's hull moves relative to any point of the
/// other's over the substep: max |Δa − Δb| over their corners (each point moves by a convex
/// combination of its corners' motions, and so does their difference).
template <std::size_t N, std::size_t M>
Real relative_motion(const Vector3r* motion, const std::uint32_t (&a)[N],
                     const std::uint32_t (&b)[M]) {
  Real most = 0;
  for (const std::uint32_t i : a)
    for (const std::uint32_t j : b) most = std::max(most, (motion[i] - motion[j]).squaredNorm());
  return std::sqrt(most);
}

/// A velocity ball: the centre and radius of a primitive's corners' velocities.
struct VelocityBall {
  Real centre[3], radius;
};

/// A record's velocity ball.
template <class Record>
VelocityBall ball_of(const Record& record) {
  return {{record.centre[0], record.centre[1], record.centre[2]}, record.radius};
}

/// What `steps` substeps of relative motion of two primitives can close at most: steps ρ,
/// with ρ = max |V_i − V_j| over their corners at most the distance of their balls' centres
/// plus both radii.
template <class Record>
Real allowed_between(const VelocityBall& own, const Record& other, Real steps) {
  const Real dx = own.centre[0] - other.centre[0], dy = own.centre[1] - other.centre[1],
             dz = own.centre[2] - other.centre[2];
  return steps * (own.radius + other.radius + std::sqrt(dx * dx + dy * dy + dz * dz));
}

/// The edges one edge's query met, their references by coordinate and each one's distance
/// allowance (its budget and the pair's relative motion to the horizon), for the batched
/// segment distances; one per thread, kept (allocation-free once grown).
struct EdgeBatch {
  std::vector<std::uint32_t> edges, within;
  std::vector<Real> px, py, pz, qx, qy, qz, budget, allowed, squared;

  std::size_t count() const { return edges.size(); }
  /// Sizes the arrays to the edges met (padded to the lanes) and fills them: the ends'
  /// references from `references` (the ends by `ends`, two per edge), allowed[k] the pair's
  /// relative motion over `steps` substeps from `anchors`, budget[k] that plus the edge's
  /// budget.
  template <class Anchors>
  void gather(const Anchors* anchors, const std::uint32_t* ends, const Vector3r* references,
              const VelocityBall& own, Real steps) {
    const std::size_t n = count();
    const std::size_t padded = detail::padded_to_lanes(n);
    for (std::vector<Real>* v : {&px, &py, &pz, &qx, &qy, &qz, &budget, &allowed, &squared})
      if (v->size() < padded) v->resize(padded);
    if (within.size() < padded) within.resize(padded);
    for (std::size_t k = 0; k < n; ++k) {
      const Anchors& edge = anchors[edges[k]];
      const Vector3r &p = references[ends[2 * std::size_t(edges[k])]],
                     &q = references[ends[2 * std::size_t(edges[k]) + 1]];
      px[k] = p[0], py[k] = p[1], pz[k] = p[2];
      qx[k] = q[0], qy[k] = q[1], qz[k] = q[2];
      allowed[k] = allowed_between(own, edge, steps);
      budget[k] = edge.budget + allowed[k];
    }
    // The padding lanes: a point at the origin, measured and dropped.
    for (std::size_t k = n; k < padded; ++k)
      px[k] = py[k] = pz[k] = qx[k] = qy[k] = qz[k] = budget[k] = 0;
  }
  /// The edges within own + their budget of segment (p, q), as positions in the batch.
  std::span<const std::uint32_t> measure(const Vector3r& p, const Vector3r& q, Real own) {
    const std::size_t found = detail::segments_within(
        p, q, own, {px.data(), py.data(), pz.data(), qx.data(), qy.data(), qz.data(), count()},
        budget.data(), squared.data(), within.data());
    return {within.data(), found};
  }
};

/// The triangles one vertex's query met, their references by coordinate and distance
/// allowances (as EdgeBatch's), for the batched point–triangle distances; one per thread,
/// kept.
struct TriangleBatch {
  std::vector<std::uint32_t> triangles, within;
  std::vector<Real> coordinates[9], budget, allowed, squared;  // a, b, c; x, y, z each

  std::size_t count() const { return triangles.size(); }
  template <class Anchors>
  void gather(const Anchors* anchors, const std::uint32_t* corners, const Vector3r* references,
              const VelocityBall& own, Real steps) {
    const std::size_t n = count();
    const std::size_t padded = detail::padded_to_lanes(n);
    if (budget.size() < padded) {
      for (std::vector<Real>& v : coordinates) v.resize(padded);
      budget.resize(padded), allowed.resize(padded), squared.resize(padded), within.resize(padded);
    }
    for (std::size_t k = 0; k < n; ++k) {
      const Anchors& triangle = anchors[triangles[k]];
      const std::uint32_t* ids = corners + 3 * std::size_t(triangles[k]);
      for (int j = 0; j < 9; ++j) coordinates[j][k] = references[ids[j / 3]][j % 3];
      allowed[k] = allowed_between(own, triangle, steps);
      budget[k] = triangle.budget + allowed[k];
    }
    for (std::size_t k = n; k < padded; ++k) {  // padding: computed and dropped
      for (std::vector<Real>& v : coordinates) v[k] = 0;
      budget[k] = 0;
    }
  }
  /// The triangles within own + their budget of p, as positions in the batch.
  std::span<const std::uint32_t> measure(const Vector3r& p, Real own) {
    const detail::TriangleBatch batch{
        coordinates[0].data(), coordinates[1].data(), coordinates[2].data(),
        coordinates[3].data(), coordinates[4].data(), coordinates[5].data(),
        coordinates[6].data(), coordinates[7].data(), coordinates[8].data(),
        budget.data(),         count()};
    return {within.data(), detail::triangles_within(p, own, batch, squared.data(), within.data())};
  }
};

/// The calling thread's leaf query (kept between calls).
detail::LeafQuery& leaf_query() {
  thread_local detail::LeafQuery query;
  return query;
}

/// Calls visit(m) for each member m of `leaves` whose box at the last build (its lanes in
/// `fields`, after `coordinates` fields) overlaps `box`: the leaf grid, then the met leaves'
/// lanes a vector at a time (leaf_scan.cpp), in the grid's order and lane order. The
/// thread's leaf_query() holds the answers while visit runs, so visit must not use it (no
/// leaf query, no TBB call that could let the thread take another chunk).
template <std::size_t Fields, class Visit>
void for_each_built_box_meeting(const detail::PrimitiveLeaves& leaves,
                                const detail::LeafFields<Fields>& fields, std::size_t coordinates,
                                const Aabb& box, Visit&& visit) {
  constexpr std::size_t kLanes = detail::PrimitiveLeaves::kLeafSize;
  detail::LeafQuery& query = leaf_query();
  query.clear();
  leaves.grid().for_each_overlap(box, [&](std::uint32_t leaf) { query.leaves.push_back(leaf); });
  if (query.leaves.empty()) return;
  query.fit();
  const std::size_t found =
      detail::lanes_meeting_box(box, fields.data(), Fields, coordinates + detail::kLeafLo,
                                query.leaves.data(), query.leaves.size(), query.within.data());
  for (std::size_t w = 0; w < found; ++w) {
    const std::uint32_t k = query.within[w];
    const std::uint32_t member = leaves.members(query.leaves[k / kLanes])[k % kLanes];
    if (member != detail::PrimitiveLeaves::kNone) visit(member);
  }
}

TriangleBatch& triangle_batch() {
  thread_local TriangleBatch batch;
  return batch;
}

/// The edge pairs the filter measures exactly, by coordinate, and each pair's candidate
/// index and distance to meet; one per thread, kept.
struct EdgePairBatch {
  std::vector<std::uint32_t> candidate, passing;
  std::vector<Real> coordinates[12], within;  // first p, q, second p, q; x, y, z each
  std::size_t count = 0;

  void clear() { count = 0; }
  void add(std::size_t k, const Vector3r (&first)[2], const Vector3r (&second)[2], Real limit) {
    if (candidate.size() <= count + detail::kSegmentBatchLanes) {
      const std::size_t room = 2 * (count + detail::kSegmentBatchLanes);
      candidate.resize(room), passing.resize(room), within.resize(room);
      for (std::vector<Real>& v : coordinates) v.resize(room);
    }
    const Vector3r* points[4] = {&first[0], &first[1], &second[0], &second[1]};
    const Real tiny = kDegenerateTolerance * kDegenerateTolerance;
    if (detail::dot3(first[1] - first[0], first[1] - first[0]) <= tiny) {
      // A point-like first edge: the scalar rule decides, and the lane holds a pair that
      // meets (distance 0) with a limit of 1 or 0 by its answer.
      const bool meets = detail::squared_segment_distance(first[0], first[1], second[0],
                                                          second[1]) < limit * limit;
      static const Vector3r unit[4] = {Vector3r::Zero(), Vector3r::UnitX(), Vector3r::Zero(),
                                       Vector3r::UnitY()};
      for (int j = 0; j < 4; ++j) points[j] = &unit[j];
      limit = meets ? Real(1) : Real(0);
    }
    for (int j = 0; j < 4; ++j)
      for (int axis = 0; axis < 3; ++axis) coordinates[3 * j + axis][count] = (*points[j])[axis];
    within[count] = limit;
    candidate[count++] = std::uint32_t(k);
  }
  /// The candidates whose pair is closer than its limit, in the order added.
  std::vector<std::uint32_t>& measure() {
    found.clear();
    if (count == 0) return found;
    const std::size_t padded = detail::padded_to_lanes(count);
    for (std::size_t k = count; k < padded; ++k) {  // padding: computed and dropped
      for (std::vector<Real>& v : coordinates) v[k] = 0;
      coordinates[3][k] = 1;  // the first segment from the origin along x
      within[k] = 0;
    }
    const auto batch = [&](int at) {
      return detail::SegmentBatch{coordinates[at].data(),     coordinates[at + 1].data(),
                                  coordinates[at + 2].data(), coordinates[at + 3].data(),
                                  coordinates[at + 4].data(), coordinates[at + 5].data(),
                                  count};
    };
    const std::size_t n =
        detail::segment_pairs_within(batch(0), batch(6), within.data(), passing.data());
    for (std::size_t j = 0; j < n; ++j) found.push_back(candidate[passing[j]]);
    return found;
  }
  std::vector<std::uint32_t> found;
};

EdgePairBatch& edge_pair_batch() {
  thread_local EdgePairBatch batch;
  return batch;
}

EdgeBatch& edge_batch() {
  thread_local EdgeBatch batch;
  return batch;
}

/// The candidate lists' order: by first, then by second.
constexpr auto by_pair = [](const auto& l, const auto& r) {
  return l.first != r.first ? l.first < r.first : l.second < r.second;
};
/// by_pair within one run of the same first.
constexpr auto by_second = [](const auto& l, const auto& r) { return l.second < r.second; };

template <class Body>
void parallel_over(std::size_t n, Body&& body, std::size_t grain = kItemGrain) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i != range.end(); ++i) body(i);
                    });
}

}  // namespace

SelfCollision::SelfCollision(std::span<const std::uint32_t> triangles,
                             std::size_t particle_count)
    : particle_count_(particle_count),
      triangles_(triangles.begin(), triangles.end()),
      chunks_(std::make_unique<Chunks>()),
      leaves_(std::make_unique<Leaves>()) {
  if (triangles.size() % 3 != 0)
    throw InvalidInput("self collision: " + std::to_string(triangles.size()) +
                       " triangle indices are not a multiple of 3");
  for (std::size_t t = 0; t < triangles.size() / 3; ++t) {
    const std::uint32_t* v = triangles.data() + 3 * t;
    for (int k = 0; k < 3; ++k)
      if (v[k] >= particle_count)
        throw InvalidInput("self collision: triangle " + std::to_string(t) + " names particle " +
                           std::to_string(v[k]) + " of " + std::to_string(particle_count));
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
      throw InvalidInput("self collision: triangle " + std::to_string(t) +
                         " names a particle twice");
  }
  edges_ = unique_edges(triangles);
  // Each vertex's triangles and edges (CSR): what a particle that outran its room re-boxes.
  const auto incidence = [&](std::span<const std::uint32_t> items, std::size_t per_item,
                             std::vector<std::uint32_t>& start, std::vector<std::uint32_t>& list) {
    start.assign(particle_count + 1, 0);
    for (const std::uint32_t v : items) ++start[v + 1];
    for (std::size_t v = 0; v < particle_count; ++v) start[v + 1] += start[v];
    list.resize(items.size());
    std::vector<std::uint32_t> cursor(start.begin(), start.end() - 1);
    for (std::size_t k = 0; k < items.size(); ++k)
      list[cursor[items[k]]++] = std::uint32_t(k / per_item);
  };
  incidence(triangles_, 3, vertex_triangle_start_, vertex_triangles_);
  incidence(edges_, 2, vertex_edge_start_, vertex_edges_);
}

SelfCollision::SelfCollision(SelfCollision&&) noexcept = default;
SelfCollision& SelfCollision::operator=(SelfCollision&&) noexcept = default;
SelfCollision::~SelfCollision() = default;

void SelfCollision::check(const SelfCollisionPositions& positions,
                          const SelfCollisionSettings& settings) const {
  if (positions.count != particle_count_)
    throw InvalidInput("self collision: " + std::to_string(positions.count) +
                       " particles given for a mesh of " + std::to_string(particle_count_));
  if (!(settings.thickness > 0) || !std::isfinite(settings.thickness))
    throw InvalidInput("self collision: thickness must be positive and finite");
  if (!(settings.margin >= 0) || !std::isfinite(settings.margin))
    throw InvalidInput("self collision: margin must be finite and not negative");
  if (!(settings.motion_scale >= 1) || !std::isfinite(settings.motion_scale))
    throw InvalidInput("self collision: motion scale must be finite and at least 1");
  if (!(settings.skin >= 0) || !std::isfinite(settings.skin))
    throw InvalidInput("self collision: skin must be finite and not negative");
}

void SelfCollision::measure_motion(const SelfCollisionPositions& positions) {
  const Particles particles{positions};
  motion_.resize(particle_count_);
  parallel_over(particle_count_, [&](std::size_t i) {
    motion_[i] = Vector3r(positions.x[i], positions.y[i], positions.z[i]) -
                 particles.start(std::uint32_t(i));
  });
}

SelfCollision::Reach SelfCollision::compute_motion(const SelfCollisionPositions& positions,
                                                   const SelfCollisionSettings& settings) {
  measure_motion(positions);
  return {settings.thickness + settings.margin};
}

namespace {

/// The median of `count` vectors, per axis, over an even sample of them (the same for any
/// thread count): the motion of the bulk of the cloth, which a part that rests or falls as a
/// whole shares exactly.
template <class Of>
Vector3r median_of(std::size_t count, Of&& of, std::vector<Real>& scratch) {
  // Over at most kMedianSample particles spread evenly over the indices: any frame keeps the
  // contacts exact (pair distances do not depend on it), the median only makes it the
  // bulk's, and a sample of 2,048 finds that at a fraction of three nth_elements over every
  // particle twice a substep (4 % of the drape's run).
  constexpr std::size_t kMedianSample = 2048;
  Vector3r median = Vector3r::Zero();
  if (count == 0) return median;
  const std::size_t samples = std::min(count, kMedianSample);
  // Each sample read once (all three axes), then the axes' medians side by side (each an
  // nth_element of its own, ~15 µs: a substep's serial part otherwise).
  scratch.resize(3 * samples);
  for (std::size_t k = 0; k < samples; ++k) {
    const Vector3r v = of(k * count / samples);
    for (int axis = 0; axis < 3; ++axis) scratch[std::size_t(axis) * samples + k] = v[axis];
  }
  tbb::parallel_for(0, 3, [&](int axis) {
    const auto begin = scratch.begin() + std::ptrdiff_t(std::size_t(axis) * samples);
    const auto middle = begin + std::ptrdiff_t(samples / 2);
    std::nth_element(begin, middle, begin + std::ptrdiff_t(samples));
    median[axis] = *middle;
  });
  return median;
}

}  // namespace

Vector3r SelfCollision::bulk_motion() {
  return median_of(particle_count_, [&](std::size_t i) { return motion_[i]; }, scratch_);
}

void SelfCollision::anchor_on_path(std::uint32_t i, const Frame& frame,
                                   const SelfCollisionPositions& positions,
                                   const SelfCollisionSettings& settings) {
  const Particles particles{positions};
  velocity_[i] = motion_[i] - frame.motion;
  speed_[i] = velocity_[i].norm();
  anchor_[i] = particles.start(i) - frame.way - frame.substep * velocity_[i];
  // A change of motion a per substep strays a particle by about a τ (τ + 1) / 2 from its path
  // after τ substeps, and its motion by a τ (the solver's corrections come on top of the
  // prediction: measured on the drape, the first substep strays by about a already); b/2
  // holds both for k substeps.
  const Real change = previous_motion_.size() == particle_count_
                          ? (motion_[i] - previous_motion_[i]).norm()
                          : Real(0);
  const Real k = settings.motion_scale;
  budget_[i] = settings.skin + k * (k + 1) * change;
}

std::size_t SelfCollision::horizon_for(Real reach, const SelfCollisionSettings& settings) {
  // The horizon's cost is what the paths may close over it (each pair allows T ρ, each box
  // is swept T |V| long); its gain, builds T substeps apart. Past a share of the reach the
  // first outgrows the second (measured: docs/performance.md, "Paths"), so T is that share
  // over the fast particles' speed (the 90th percentile of |V|), at most the setting's.
  const std::size_t longest = std::min(settings.horizon, kLongestHorizon);
  if (longest <= 1 || particle_count_ == 0) return longest;
  scratch_.assign(speed_.begin(), speed_.end());
  const auto at = scratch_.begin() + std::ptrdiff_t(scratch_.size() * 9 / 10);
  std::nth_element(scratch_.begin(), at, scratch_.end());
  const Real fast = *at, closing = kHorizonReachShare * reach;
  if (!(fast * Real(longest) > closing)) return longest;
  return std::max<std::size_t>(1, std::size_t(closing / fast));
}

void SelfCollision::refresh_references(const SelfCollisionSettings& settings) {
  const Real tau = Real(substep_);
  parallel_over(particle_count_,
                [&](std::size_t i) { reference_[i] = anchor_[i] + tau * velocity_[i]; });
  // Budgets and velocity balls change with a re-anchoring only (the new primitives'); the
  // records hold no reference (the queries read them from reference_), so no other record
  // changes.
  parallel_over(new_triangles_.size(),
                [&](std::size_t k) { set_triangle_anchors(new_triangles_[k]); });
  parallel_over(settings.edge_edge ? new_edges_.size() : 0,
                [&](std::size_t k) { set_edge_anchors(new_edges_[k]); });
}

template <std::size_t N>
void SelfCollision::velocity_ball(const std::uint32_t (&ids)[N], Real (&centre)[3],
                                  Real& radius) const {
  Vector3r mean = Vector3r::Zero();
  for (const std::uint32_t i : ids) mean += velocity_[i];
  mean /= Real(N);
  Real most = 0;
  for (const std::uint32_t i : ids) most = std::max(most, (velocity_[i] - mean).squaredNorm());
  for (int axis = 0; axis < 3; ++axis) centre[axis] = mean[axis];
  radius = std::sqrt(most);
}

void SelfCollision::add_edge_edge_candidate(std::uint32_t e, std::uint32_t f, Real reach,
                                            const SelfCollisionPositions& positions,
                                            std::vector<Candidate>& out) const {
  const Particles particles{positions};
  const std::uint32_t p0 = edges_[2 * e], p1 = edges_[2 * e + 1];
  const std::uint32_t p2 = edges_[2 * f], p3 = edges_[2 * f + 1];
  if (!particles.may_touch(p0, p1, p2, p3)) return;
  const Real squared = detail::squared_segment_distance(reference_[p0], reference_[p1],
                                                        reference_[p2], reference_[p3]);
  const EdgeAnchors& own = edge_anchors_[e];
  const Real allowed = allowed_between(ball_of(own), edge_anchors_[f], substeps_allowed());
  const Real within = reach + edge_slack_ + own.budget + edge_anchors_[f].budget + allowed;
  if (squared < within * within)
    out.push_back(candidate_of(std::min(e, f), std::max(e, f), squared, allowed, substeps_allowed()));
}

void SelfCollision::set_triangle_anchors(std::uint32_t t) {
  TriangleAnchors& record = triangle_anchors_[t];
  const std::uint32_t ids[3] = {triangles_[3 * std::size_t(t)], triangles_[3 * std::size_t(t) + 1],
                                triangles_[3 * std::size_t(t) + 2]};
  record.budget = std::max({budget_[ids[0]], budget_[ids[1]], budget_[ids[2]]});
  velocity_ball(ids, record.centre, record.radius);
}

template <class Collect>
void SelfCollision::add_triangle_point_candidates(std::uint32_t p, Real reach,
                                                  const SelfCollisionPositions& positions,
                                                  std::vector<Candidate>& out,
                                                  Collect&& collect) const {
  const Particles particles{positions};
  TriangleBatch& batch = triangle_batch();
  batch.triangles.clear();
  collect([&](std::uint32_t t) { batch.triangles.push_back(t); });
  if (batch.count() == 0) return;
  // The candidate rule: the distance test first (a vector at a time), then the topology of
  // those within it (not a corner of the triangle, not all four static).
  const Vector3r& v = velocity_[p];
  batch.gather(triangle_anchors_.data(), triangles_.data(), reference_.data(),
               VelocityBall{{v.x(), v.y(), v.z()}, 0}, substeps_allowed());
  for (const std::uint32_t k : batch.measure(reference_[p], reach + budget_[p])) {
    const std::uint32_t t = batch.triangles[k];
    const std::uint32_t a = triangles_[3 * t], b = triangles_[3 * t + 1], c = triangles_[3 * t + 2];
    if (p == a || p == b || p == c || particles.all_static({p, a, b, c})) continue;
    out.push_back(candidate_of(p, t, batch.squared[k], batch.allowed[k], substeps_allowed()));
  }
}

void SelfCollision::set_edge_anchors(std::uint32_t e) {
  const std::uint32_t p = edges_[2 * e], q = edges_[2 * e + 1];
  EdgeAnchors& record = edge_anchors_[e];
  record.budget = std::max(budget_[p], budget_[q]);
  const std::uint32_t ids[2] = {p, q};
  velocity_ball(ids, record.centre, record.radius);
}

template <class Collect>
void SelfCollision::add_edge_edge_candidates(std::uint32_t e, Real reach,
                                             const SelfCollisionPositions& positions,
                                             std::vector<Candidate>& out,
                                             Collect&& collect) const {
  const Particles particles{positions};
  const std::uint32_t p0 = edges_[2 * e], p1 = edges_[2 * e + 1];
  EdgeBatch& batch = edge_batch();
  batch.edges.clear();
  collect([&](std::uint32_t f) { batch.edges.push_back(f); });
  if (batch.count() == 0) return;
  const Real tiny = kDegenerateTolerance * kDegenerateTolerance;
  const Vector3r way = reference_[p1] - reference_[p0];
  if (detail::dot3(way, way) <= tiny) {  // as the rule
    // A point-like edge: the scalar rule, which handles it.
    for (const std::uint32_t f : batch.edges) add_edge_edge_candidate(e, f, reach, positions, out);
    return;
  }
  // The distance test first (a vector at a time, no branch per edge met), then the topology
  // of the few within it: the same candidates as add_edge_edge_candidate, in the same order.
  const EdgeAnchors& record = edge_anchors_[e];
  batch.gather(edge_anchors_.data(), edges_.data(), reference_.data(), ball_of(record),
               substeps_allowed());
  for (const std::uint32_t k :
       batch.measure(reference_[p0], reference_[p1], reach + edge_slack_ + record.budget)) {
    const std::uint32_t f = batch.edges[k];
    if (particles.may_touch(p0, p1, edges_[2 * f], edges_[2 * f + 1]))
      out.push_back(candidate_of(std::min(e, f), std::max(e, f), batch.squared[k], batch.allowed[k],
                                 substeps_allowed()));
  }
}

// The boxes of the paths from now to the horizon's end.
Aabb SelfCollision::vertex_box(std::uint32_t p, Real reach) const {
  const std::uint32_t ids[1] = {p};
  return swept_box(ids, {reference_.data(), velocity_.data(), speed_.data(), budget_.data()},
                   Real(horizon_ - substep_), reach);
}
Aabb SelfCollision::triangle_box(std::uint32_t t) const {
  const std::uint32_t ids[3] = {triangles_[3 * t], triangles_[3 * t + 1], triangles_[3 * t + 2]};
  return swept_box(ids, {reference_.data(), velocity_.data(), speed_.data(), budget_.data()},
                   Real(horizon_ - substep_), 0);
}
Aabb SelfCollision::edge_box(std::uint32_t e, Real reach) const {
  const std::uint32_t ids[2] = {edges_[2 * e], edges_[2 * e + 1]};
  return swept_box(ids, {reference_.data(), velocity_.data(), speed_.data(), budget_.data()},
                   Real(horizon_ - substep_), reach / 2);
}

void SelfCollision::detect(const SelfCollisionPositions& positions,
                           const SelfCollisionSettings& settings, Contacts& out) {
  check(positions, settings);
  const Real reach = compute_motion(positions, settings).distance;
  const Vector3r bulk = build(positions, settings, reach);
  // This substep's contacts among the candidates: every particle on its path (w = m = 0).
  measure_departures(positions, Frame{Vector3r::Zero(), bulk, 0});
  filter_candidates(positions, settings, reach);
  emit(out);
  previous_motion_.swap(motion_);
}

Vector3r SelfCollision::build(const SelfCollisionPositions& positions,
                              const SelfCollisionSettings& settings, Real reach) {
  const Particles particles{positions};
  const std::size_t triangle_count = triangles_.size() / 3;
  const std::size_t edge_count = edges_.size() / 2;
  // Every particle anchored here on the path of its motion against the bulk's: the frame's
  // origin (covers()).
  const Vector3r bulk = bulk_motion();
  substep_ = 0;
  built_reach_ = reach;
  for (auto* v : {&anchor_, &velocity_, &reference_, &frame_origin_}) v->resize(particle_count_);
  budget_.resize(particle_count_);
  speed_.resize(particle_count_);
  parallel_over(particle_count_, [&](std::size_t i) {
    anchor_on_path(std::uint32_t(i), Frame{Vector3r::Zero(), bulk, 0}, positions, settings);
    reference_[i] = anchor_[i];
    frame_origin_[i] = particles.start(std::uint32_t(i));
  });
  horizon_ = horizon_for(reach, settings);
  // The edge pairs' rounding room (edge_slack_): the largest reference coordinate's share.
  Real largest = 0;
  for (const Vector3r& r : reference_) largest = std::max(largest, r.cwiseAbs().maxCoeff());
  edge_slack_ = kAllowancePerCoordinate * largest;
  reboxed_triangle_.assign(triangle_count, 0);
  reboxed_edge_.assign(edge_count, 0);
  reboxed_triangles_.clear();
  reboxed_edges_.clear();
  reboxed_triangle_grid_.build({});
  reboxed_edge_grid_.build({});

  // Candidates: the pairs whose references can come closer than the reach plus their
  // particles' budgets and a substep of relative motion before the horizon's end (the top of
  // self_collision.hpp). Boxes: the paths to then, grown by the budgets, the speeds and the
  // reach, the vertex's by all of the reach and an edge's by half. A pair in contact at
  // some substep is within that distance there, and no coordinate differs by more than the
  // distance, so its boxes overlap: the grid misses no contact (a candidate that only
  // recedes may be missed; it is no contact).
  vertex_boxes_.resize(particle_count_);
  parallel_over(particle_count_,
                [&](std::size_t i) { vertex_boxes_[i] = vertex_box(std::uint32_t(i), reach); });
  triangle_boxes_.resize(triangle_count);
  triangle_anchors_.resize(triangle_count);
  parallel_over(triangle_count, [&](std::size_t t) {
    triangle_boxes_[t] = triangle_box(std::uint32_t(t));
    set_triangle_anchors(std::uint32_t(t));
  });
  const std::size_t edge_queries = settings.edge_edge ? edge_count : 0;
  built_with_edge_edge_ = settings.edge_edge;
  edge_anchors_.resize(edge_queries);
  parallel_over(edge_queries, [&](std::size_t e) { set_edge_anchors(std::uint32_t(e)); });
  edge_boxes_.resize(edge_queries);
  parallel_over(edge_queries,
                [&](std::size_t e) { edge_boxes_[e] = edge_box(std::uint32_t(e), reach); });

  // The leaves (primitive_leaves.hpp): ordered once, by the references of the first build;
  // boxed by their members' boxes; the triangles' and edges' records as lanes.
  Leaves& leaves = *leaves_;
  if (!leaves_ordered_) {
    std::vector<Vector3r> points(reference_.begin(), reference_.end());
    leaves.vertices.order(points);
    points.resize(triangle_count);
    for (std::size_t t = 0; t < triangle_count; ++t)
      points[t] = (reference_[triangles_[3 * t]] + reference_[triangles_[3 * t + 1]] +
                   reference_[triangles_[3 * t + 2]]) / Real(3);
    leaves.triangles.order(points);
    points.resize(edge_count);
    for (std::size_t e = 0; e < edge_count; ++e)
      points[e] = (reference_[edges_[2 * e]] + reference_[edges_[2 * e + 1]]) / Real(2);
    leaves.edges.order(points);
    leaves.triangle_fields.resize(leaves.triangles.leaf_count());
    leaves.edge_fields.resize(leaves.edges.leaf_count());
    leaves_ordered_ = true;
  }
  constexpr std::size_t kLanes = detail::PrimitiveLeaves::kLeafSize;
  const auto parallel = [](std::size_t n, auto&& body) { parallel_over(n, body, kLeafGrain); };
  leaves.vertices.box(vertex_boxes_, parallel, /*grid=*/false);  // they query only
  leaves.triangles.box(triangle_boxes_, parallel);
  // Each leaf's lanes: the coordinates, then the tail (segment_distances.hpp, LeafField). A
  // padding lane repeats the leaf's first member with an empty box: it pairs with nothing.
  const auto fill_tail = [&](auto& fields, std::size_t leaf, std::size_t lane,
                             std::size_t coordinates, const auto& record, const Aabb& box,
                             const std::uint32_t* ids, std::size_t id_count) {
    const auto field = [&](std::size_t f) -> Real& { return fields.block(leaf, coordinates + f)[lane]; };
    field(detail::kLeafBudget) = record.budget;
    field(detail::kLeafRadius) = record.radius;
    bool all_static = true;
    for (std::size_t j = 0; j < 3; ++j) {
      field(detail::kLeafCentre + j) = record.centre[j];
      field(detail::kLeafLo + j) = box.lo[j];
      field(detail::kLeafHi + j) = box.hi[j];
      field(detail::kLeafIds + j) = detail::id_lane(ids[std::min(j, id_count - 1)]);
      if (j < id_count) all_static = all_static && positions.inverse_mass[ids[j]] == 0;
    }
    field(detail::kLeafStatic) = all_static ? Real(1) : Real(0);
  };
  // The records are in index order and the leaves in Morton order: the next leaf's records
  // are fetched while this one's are copied. (The references the fills read through the
  // primitives' particles are not: 16 k particles' references stay in L2.)
  const auto prefetch_members = [&](const detail::PrimitiveLeaves& of, std::size_t leaf,
                                    const auto* records, const Aabb* boxes) {
    if (leaf >= of.leaf_count()) return;
    const std::uint32_t* members = of.members(leaf);
    for (std::size_t k = 0; k < kLanes; ++k)
      if (members[k] != detail::PrimitiveLeaves::kNone)
        __builtin_prefetch(records + members[k]), __builtin_prefetch(boxes + members[k]);
  };
  parallel_over(leaves.triangles.leaf_count(), [&](std::size_t leaf) {
    prefetch_members(leaves.triangles, leaf + 1, triangle_anchors_.data(), triangle_boxes_.data());
    const std::uint32_t* members = leaves.triangles.members(leaf);
    for (std::size_t k = 0; k < kLanes; ++k) {
      const bool padding = members[k] == detail::PrimitiveLeaves::kNone;
      const std::uint32_t t = members[padding ? 0 : k];
      const TriangleAnchors& record = triangle_anchors_[t];
      const std::uint32_t* corners = triangles_.data() + 3 * std::size_t(t);
      for (std::size_t j = 0; j < 9; ++j)
        leaves.triangle_fields.block(leaf, j)[k] = reference_[corners[j / 3]][j % 3];
      fill_tail(leaves.triangle_fields, leaf, k, 9, record, padding ? kEmptyBox : triangle_boxes_[t],
                triangles_.data() + 3 * std::size_t(t), 3);
    }
  }, kLeafGrain);
  if (edge_queries > 0) {
    leaves.edges.box(edge_boxes_, parallel);
    parallel_over(leaves.edges.leaf_count(), [&](std::size_t leaf) {
      prefetch_members(leaves.edges, leaf + 1, edge_anchors_.data(), edge_boxes_.data());
      const std::uint32_t* members = leaves.edges.members(leaf);
      for (std::size_t k = 0; k < kLanes; ++k) {
        const bool padding = members[k] == detail::PrimitiveLeaves::kNone;
        const std::uint32_t e = members[padding ? 0 : k];
        const EdgeAnchors& record = edge_anchors_[e];
        const Vector3r &p = reference_[edges_[2 * std::size_t(e)]],
                       &q = reference_[edges_[2 * std::size_t(e) + 1]];
        for (std::size_t j = 0; j < 3; ++j)
          leaves.edge_fields.block(leaf, j)[k] = p[j],
          leaves.edge_fields.block(leaf, 3 + j)[k] = q[j];
        fill_tail(leaves.edge_fields, leaf, k, 6, record, padding ? kEmptyBox : edge_boxes_[e],
                  edges_.data() + 2 * std::size_t(e), 2);
      }
    }, kLeafGrain);
  }
  const Real steps = substeps_allowed();

  // Vertex–triangle: each vertex of a leaf against every triangle of the triangle leaves
  // its leaf's box meets, the distances a vector at a time (triangle_distances.cpp, the
  // scalar rule's bits), the box overlap and topology (not a corner, not all static) as lane
  // masks before the distance.
  chunks_->triangle_point_candidates.run(
      leaves.vertices.leaf_count(),
      [&](std::size_t leaf, std::vector<Candidate>& buffer) {
        detail::LeafQuery& query = leaf_query();
        query.clear();
        leaves.triangles.grid().for_each_overlap(
            leaves.vertices.leaf_box(leaf), [&](std::uint32_t met) { query.leaves.push_back(met); });
        if (query.leaves.empty()) return;
        query.fit();
        const std::uint32_t* members = leaves.vertices.members(leaf);
        for (std::size_t j = 0; j < kLanes && members[j] != detail::PrimitiveLeaves::kNone; ++j) {
          const std::uint32_t p = members[j];
          const Real id = detail::id_lane(p);
          const detail::BlockQuery own{{velocity_[p].x(), velocity_[p].y(), velocity_[p].z()},
                                       0, steps, vertex_boxes_[p], {id, id},
                                       positions.inverse_mass[p] == 0};
          const std::size_t found = detail::triangles_within_leaves(
              reference_[p], reach + budget_[p], own, leaves.triangle_fields.data(),
              query.leaves.data(), query.leaves.size(), query.squared.data(),
              query.allowed.data(), query.within.data());
          for (std::size_t w = 0; w < found; ++w) {
            const std::uint32_t k = query.within[w];
            const std::uint32_t t = leaves.triangles.members(query.leaves[k / kLanes])[k % kLanes];
            buffer.push_back(candidate_of(p, t, query.squared[k], query.allowed[k], steps));
          }
        }
      },
      candidate_triangle_point_, kLeafChunk);
  sort_candidates(candidate_triangle_point_, particle_count_);

  // Edge–edge: each edge of a leaf against every edge of the leaves at or after its own that
  // its leaf's box meets (in its own leaf, the edges after it), the distances a vector at a
  // time (segment_distances.cpp: the box and topology as masks, then the scalar distance's
  // bits with the querying edge first, hence edge_slack_ in the limit).
  chunks_->edge_edge_candidates.run(
      edge_queries > 0 ? leaves.edges.leaf_count() : 0,
      [&](std::size_t leaf, std::vector<Candidate>& buffer) {
        detail::LeafQuery& query = leaf_query();
        query.clear();
        // The own leaf first: its pairs are kept from their first edge.
        query.leaves.push_back(std::uint32_t(leaf));
        leaves.edges.grid().for_each_overlap(leaves.edges.leaf_box(leaf), [&](std::uint32_t met) {
          if (met > leaf) query.leaves.push_back(met);
        });
        query.fit();
        const std::uint32_t* members = leaves.edges.members(leaf);
        const auto own_field = [&](std::size_t field, std::size_t j) {
          return leaves.edge_fields.block(leaf, field)[j];
        };
        for (std::size_t j = 0; j < kLanes && members[j] != detail::PrimitiveLeaves::kNone; ++j) {
          const std::uint32_t e = members[j];
          // The edge's own record and box, from its leaf's lanes (in cache, unlike
          // edge_anchors_[e] and edge_boxes_[e]).
          const Vector3r p(own_field(0, j), own_field(1, j), own_field(2, j)),
              q(own_field(3, j), own_field(4, j), own_field(5, j));
          const std::size_t tail = 6;
          Aabb box;
          for (std::size_t axis = 0; axis < 3; ++axis)
            box.lo[axis] = own_field(tail + detail::kLeafLo + axis, j),
            box.hi[axis] = own_field(tail + detail::kLeafHi + axis, j);
          const detail::BlockQuery own{
              {own_field(tail + detail::kLeafCentre, j), own_field(tail + detail::kLeafCentre + 1, j),
               own_field(tail + detail::kLeafCentre + 2, j)},
              own_field(tail + detail::kLeafRadius, j),
              steps,
              box,
              {own_field(tail + detail::kLeafIds, j), own_field(tail + detail::kLeafIds + 1, j)},
              own_field(tail + detail::kLeafStatic, j) != 0};
          const Vector3r way = q - p;
          if (detail::dot3(way, way) <= kDegenerateTolerance * kDegenerateTolerance) {
            // A point-like edge: the scalar rule, which handles it.
            for (std::size_t k = j + 1; k < query.leaves.size() * kLanes; ++k) {
              const std::uint32_t f = leaves.edges.members(query.leaves[k / kLanes])[k % kLanes];
              if (f != detail::PrimitiveLeaves::kNone)  // the lower edge first, as the filter
                add_edge_edge_candidate(std::min(e, f), std::max(e, f), reach, positions, buffer);
            }
            continue;
          }
          const std::size_t found = detail::segments_within_leaves(
              p, q, reach + edge_slack_ + own_field(tail + detail::kLeafBudget, j), own,
              leaves.edge_fields.data(), query.leaves.data(), query.leaves.size(),
              query.squared.data(), query.allowed.data(), query.within.data());
          for (std::size_t w = 0; w < found; ++w) {
            const std::uint32_t k = query.within[w];
            if (k <= j) continue;  // the own leaf's earlier edges, and itself
            const std::uint32_t f = leaves.edges.members(query.leaves[k / kLanes])[k % kLanes];
            buffer.push_back(candidate_of(std::min(e, f), std::max(e, f), query.squared[k],
                                          query.allowed[k], steps));
          }
        }
      },
      candidate_edge_edge_, kLeafChunk);
  sort_candidates(candidate_edge_edge_, edge_count);
  return bulk;
}

SelfCollision::Frame SelfCollision::frame(const SelfCollisionPositions& positions) {
  const Particles particles{positions};
  Frame frame;
  frame.way = median_of(
      particle_count_,
      [&](std::size_t i) { return Vector3r(particles.start(std::uint32_t(i)) - frame_origin_[i]); },
      scratch_);
  frame.motion = bulk_motion();
  return frame;
}

SelfCollision::Departure SelfCollision::squared_departure(
    std::uint32_t i, const Frame& frame, const SelfCollisionPositions& positions) const {
  const Particles particles{positions};
  // w = |x_start − W − R(τ)| (how far it is from its path, in the frame that moves by the
  // bulk's way W) and m = |Δ − ū − V| (this substep's motion against its path's).
  const Vector3r on_path = anchor_[i] + frame.substep * velocity_[i];
  return {(particles.start(i) - frame.way - on_path).squaredNorm(),
          (motion_[i] - frame.motion - velocity_[i]).squaredNorm()};
}

bool SelfCollision::outran(const Departure& squared, std::uint32_t i) const {
  // w and m each within half the budget.
  const Real half = budget_[i] / 2;
  return squared.way > half * half || squared.motion > half * half;
}

bool SelfCollision::covers(const SelfCollisionPositions& positions) {
  if (positions.count != particle_count_ || anchor_.size() != particle_count_) return false;
  if (substep_ + 1 > horizon_) return false;
  measure_motion(positions);  // scratch: every entry point measures it anew
  Frame now = frame(positions);
  now.substep = Real(substep_ + 1);  // the substep refine() would filter
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, particle_count_, 4096), true,
      [&](const tbb::blocked_range<std::size_t>& range, bool all) {
        for (std::size_t i = range.begin(); all && i != range.end(); ++i)
          all = !outran(squared_departure(std::uint32_t(i), now, positions), std::uint32_t(i));
        return all;
      },
      [](bool l, bool r) { return l && r; });
}

SelfCollision::Update SelfCollision::update(const SelfCollisionPositions& positions,
                                            const SelfCollisionSettings& settings,
                                            Contacts& out) {
  check(positions, settings);
  // Before any detection, when edge–edge contacts were switched since the last one (its edge
  // grid, records and candidates are those of the other setting), or when the reach grew
  // (its candidates were chosen for a shorter one): a build.
  if (anchor_.size() != particle_count_ || settings.edge_edge != built_with_edge_edge_ ||
      settings.thickness + settings.margin > built_reach_) {
    detect(positions, settings, out);
    return Update::built;
  }
  const Real reach = compute_motion(positions, settings).distance;
  Frame now = frame(positions);
  Update done = Update::refined;
  if (substep_ + 1 > horizon_) {
    done = Update::built;  // past the horizon the candidates' allowance ends
  } else {
    ++substep_;
    now.substep = Real(substep_);
    // The departures and the particles that outran their room, in one pass.
    measure_departures(positions, now, &outran_);
    if (!outran_.empty()) done = rebox(positions, settings, reach, now) ? Update::reboxed : Update::built;
  }
  // A build anchors every particle on its path at its start: a new frame that has not
  // moved. (A re-box settled its particles' departures itself.)
  if (done == Update::built) {
    build(positions, settings, reach);
    measure_departures(positions, Frame{Vector3r::Zero(), now.motion, 0});
  }
  filter_candidates(positions, settings, reach);
  emit(out);
  previous_motion_.swap(motion_);
  return done;
}

bool SelfCollision::rebox(const SelfCollisionPositions& positions,
                          const SelfCollisionSettings& settings, Real reach, const Frame& now) {
  const std::size_t triangle_count = triangles_.size() / 3;
  // New: the primitives of the particles that outran their room (N); reboxed: those and
  // the ones reboxed since the build (C), whose boxes in the build's leaves are stale.
  new_triangle_.assign(triangle_count, 0);
  new_edge_.assign(edges_.size() / 2, 0);
  std::size_t reboxed = reboxed_triangles_.size() + reboxed_edges_.size();
  new_triangles_.clear();
  new_edges_.clear();
  for (const std::uint32_t i : outran_) {
    for (std::uint32_t k = vertex_triangle_start_[i]; k < vertex_triangle_start_[i + 1]; ++k) {
      const std::uint32_t t = vertex_triangles_[k];
      if (!new_triangle_[t]) new_triangle_[t] = 1, new_triangles_.push_back(t);
    }
    for (std::uint32_t k = vertex_edge_start_[i]; k < vertex_edge_start_[i + 1]; ++k) {
      const std::uint32_t e = vertex_edges_[k];
      if (!new_edge_[e]) new_edge_[e] = 1, new_edges_.push_back(e);
    }
  }
  for (const std::uint32_t t : new_triangles_) reboxed += !reboxed_triangle_[t];
  for (const std::uint32_t e : new_edges_) reboxed += !reboxed_edge_[e];
  // Past a share of the mesh, a full build costs less than queries one by one.
  if (double(reboxed) > kReboxedShare * double(triangle_count + edges_.size() / 2)) return false;
  std::sort(new_triangles_.begin(), new_triangles_.end());
  std::sort(new_edges_.begin(), new_edges_.end());

  // Re-anchor the particles that outran their room on the path of their motion now, in the
  // frame; their departures under `now` measured again (about 0: on the path, up to
  // rounding), and the allowance grown to their new anchors' coordinates.
  Real largest = 0;
  for (const std::uint32_t i : outran_) {
    anchor_on_path(i, now, positions, settings);
    const Departure squared = squared_departure(i, now, positions);
    departure_[i] = {std::sqrt(squared.way), std::sqrt(squared.motion)};
    largest = std::max(largest, anchor_[i].cwiseAbs().maxCoeff());
  }
  departure_allowance_ = std::max(departure_allowance_, kAllowancePerCoordinate * largest);
  edge_slack_ = std::max(edge_slack_, kAllowancePerCoordinate * largest);
  // Every reference at this substep, and the new primitives' records: the new primitives
  // are tested against the others where both are now, with the horizon left.
  refresh_references(settings);
  for (const std::uint32_t t : new_triangles_)
    if (!reboxed_triangle_[t]) reboxed_triangle_[t] = 1, reboxed_triangles_.push_back(t);
  for (const std::uint32_t e : new_edges_)
    if (!reboxed_edge_[e]) reboxed_edge_[e] = 1, reboxed_edges_.push_back(e);
  // The reboxed primitives' boxes, in a second pair of grids (entry k: reboxed_*_[k]).
  reboxed_triangle_boxes_.resize(reboxed_triangles_.size());
  for (std::size_t k = 0; k < reboxed_triangles_.size(); ++k)
    reboxed_triangle_boxes_[k] = triangle_box(reboxed_triangles_[k]);
  reboxed_edge_boxes_.resize(reboxed_edges_.size());
  for (std::size_t k = 0; k < reboxed_edges_.size(); ++k)
    reboxed_edge_boxes_[k] = edge_box(reboxed_edges_[k], reach);
  reboxed_triangle_grid_.build(reboxed_triangle_boxes_);
  reboxed_edge_grid_.build(reboxed_edge_boxes_);

  // Drop the candidates of the new primitives (in the merges at the end) and find theirs
  // again: the new vertices against every triangle, the other vertices against the new
  // triangles, the new edges against every edge. The build's leaves hold stale boxes of
  // reboxed primitives, skipped; their boxes now are in the second grids.
  new_vertex_.assign(particle_count_, 0);
  for (const std::uint32_t i : outran_) new_vertex_[i] = 1;
  chunks_->triangle_point_candidates.run(
      outran_.size(),
      [&](std::size_t k, std::vector<Candidate>& buffer) {
        const std::uint32_t p = outran_[k];
        const std::size_t first = buffer.size();
        const Aabb box = vertex_box(p, reach);
        add_triangle_point_candidates(p, reach, positions, buffer, [&](auto&& visit) {
          for_each_built_box_meeting(leaves_->triangles, leaves_->triangle_fields, 9, box,
                                     [&](std::uint32_t t) {
                                       if (!reboxed_triangle_[t]) visit(t);
                                     });
          reboxed_triangle_grid_.for_each_overlap(
              box, [&](std::uint32_t entry) { visit(reboxed_triangles_[entry]); });
        });
        std::sort(buffer.begin() + std::ptrdiff_t(first), buffer.end(), by_second);
      },
      found_triangle_point_, kReboxQueryChunk);
  if (!new_triangles_.empty()) {
    Aabb reach_of_new = triangle_box(new_triangles_[0]);
    for (const std::uint32_t t : new_triangles_) {
      const Aabb box = triangle_box(t);
      for (int axis = 0; axis < 3; ++axis)
        reach_of_new.lo[axis] = std::min(reach_of_new.lo[axis], box.lo[axis]),
        reach_of_new.hi[axis] = std::max(reach_of_new.hi[axis], box.hi[axis]);
    }
    chunks_->triangle_point_others.run(
        particle_count_,
        [&](std::size_t vertex, std::vector<Candidate>& buffer) {
          const std::uint32_t p = std::uint32_t(vertex);
          if (new_vertex_[p]) return;
          const Aabb box = vertex_box(p, reach);
          if (!overlap(box, reach_of_new)) return;
          const std::size_t first = buffer.size();
          add_triangle_point_candidates(p, reach, positions, buffer, [&](auto&& visit) {
            reboxed_triangle_grid_.for_each_overlap(box, [&](std::uint32_t entry) {
              const std::uint32_t t = reboxed_triangles_[entry];
              if (new_triangle_[t]) visit(t);
            });
          });
          std::sort(buffer.begin() + std::ptrdiff_t(first), buffer.end(), by_second);
        },
        found_others_);
    merge_sorted(found_triangle_point_, found_others_);
  }
  merge_sorted(candidate_triangle_point_, found_triangle_point_, new_vertex_.data(),
               new_triangle_.data());

  if (settings.edge_edge) {
    chunks_->edge_edge_candidates.run(
        new_edges_.size(),
        [&](std::size_t k, std::vector<Candidate>& buffer) {
          const std::uint32_t e = new_edges_[k];
          const Aabb box = edge_box(e, reach);
          add_edge_edge_candidates(e, reach, positions, buffer, [&](auto&& visit) {
            for_each_built_box_meeting(leaves_->edges, leaves_->edge_fields, 6, box,
                                       [&](std::uint32_t f) {
                                         if (!reboxed_edge_[f]) visit(f);
                                       });
            reboxed_edge_grid_.for_each_overlap(box, [&](std::uint32_t entry) {
              const std::uint32_t f = reboxed_edges_[entry];
              // A pair of two new edges is found from both: kept from the lower.
              if (f != e && !(new_edge_[f] && f < e)) visit(f);
            });
          });
        },
        found_edge_edge_, kReboxQueryChunk);
    // The pairs are unique (each found from one new edge; a pair of two new edges from the
    // lower), so their sorted order is one, whatever the sort and the threads.
    tbb::parallel_sort(found_edge_edge_.begin(), found_edge_edge_.end(), by_pair);
  } else {
    found_edge_edge_.clear();
  }
  merge_sorted(candidate_edge_edge_, found_edge_edge_, new_edge_.data(), new_edge_.data());
  return true;
}

void SelfCollision::sort_candidates(std::vector<Candidate>& candidates, std::size_t keys) {
  // By first: a counting sort (stable); then each first's few by second.
  key_start_.assign(keys + 1, 0);
  for (const Candidate& pair : candidates) ++key_start_[pair.first + 1];
  for (std::size_t k = 0; k < keys; ++k) key_start_[k + 1] += key_start_[k];
  merged_.resize(candidates.size());
  for (const Candidate& pair : candidates) merged_[key_start_[pair.first]++] = pair;
  candidates.swap(merged_);
  // key_start_[k] is now the end of key k's run; the runs are sorted in parallel, each on
  // its own (the pairs are unique, so the order is one whatever the threads).
  parallel_over(keys, [&](std::size_t k) {
    std::sort(candidates.data() + (k == 0 ? 0 : key_start_[k - 1]),
              candidates.data() + key_start_[k], by_second);
  });
}

void SelfCollision::merge_sorted(std::vector<Candidate>& into, const std::vector<Candidate>& more,
                                 const std::uint8_t* drop_first, const std::uint8_t* drop_second) {
  // In blocks of `into`, each with the run of `more` that sorts among its pairs: each
  // block's kept pairs moved to its front, then each block merged at its place, both in
  // parallel. The result is the one sorted list, whatever the blocks and threads.
  //
  //   into:  [ block 0 ·····|  block 1 ·····| block 2 ··· ]   (dropped pairs removed)
  //   more:  [ ·· run 0 ··|·· run 1 ········|· run 2 ·· ]     (split at each block's first)
  //   out:   [ kept 0 + run 0 | kept 1 + run 1 | kept 2 + run 2 ]
  //
  // (A single pass that skips and merges at once measured slower on one thread than these
  // two: std::merge's branches predict the long runs of kept pairs.)
  //
  // A block is at least 4096 pairs (64 KB in float), enough to be worth a task; 4 per
  // thread share out blocks whose runs differ in length. One thread, or a short list, takes
  // one block without TBB: remove_if, then std::merge.
  constexpr std::size_t kLeastBlock = 4096, kBlocksPerThread = 4;
  if (more.empty() && !drop_first && !drop_second) return;
  const std::size_t n = into.size();
  const std::size_t threads = std::size_t(tbb::this_task_arena::max_concurrency());
  const std::size_t blocks =
      threads == 1 ? 1 : std::clamp<std::size_t>(n / kLeastBlock, 1, kBlocksPerThread * threads);
  const auto block_begin = [&](std::size_t b) { return n * b / blocks; };
  // merge_run_[b]: how many pairs of `more` sort below block b's first pair, read before
  // remove_if moves the block's pairs; merge_kept_[b]: the kept pairs of the blocks before b.
  merge_kept_.assign(blocks + 1, 0);
  merge_run_.assign(blocks + 1, more.size());
  merge_run_[0] = 0;
  const auto keep = [&](std::size_t b) {
    if (b > 0)
      merge_run_[b] = std::size_t(
          std::lower_bound(more.begin(), more.end(), into[block_begin(b)], by_pair) -
          more.begin());
    const auto first = into.begin() + std::ptrdiff_t(block_begin(b)),
               last = into.begin() + std::ptrdiff_t(block_begin(b + 1));
    merge_kept_[b + 1] = std::size_t(
        std::remove_if(first, last,
                       [&](const Candidate& pair) {
                         return (drop_first && drop_first[pair.first]) ||
                                (drop_second && drop_second[pair.second]);
                       }) -
        first);
  };
  // Each block by a task, or one block without TBB.
  const auto for_each_block = [&](auto&& body) {
    if (blocks == 1)
      body(std::size_t(0));
    else
      tbb::parallel_for(std::size_t(0), blocks, body);
  };
  for_each_block(keep);
  for (std::size_t b = 0; b < blocks; ++b) merge_kept_[b + 1] += merge_kept_[b];
  merged_.resize(merge_kept_[blocks] + more.size());
  // Block b's kept pairs: into [block_begin(b), + merge_kept_[b + 1] − merge_kept_[b]).
  const auto merge = [&](std::size_t b) {
    const auto first = into.begin() + std::ptrdiff_t(block_begin(b));
    const std::size_t run = merge_run_[b];
    std::merge(first, first + std::ptrdiff_t(merge_kept_[b + 1] - merge_kept_[b]),
               more.begin() + std::ptrdiff_t(run), more.begin() + std::ptrdiff_t(merge_run_[b + 1]),
               merged_.begin() + std::ptrdiff_t(merge_kept_[b] + run), by_pair);
  };
  for_each_block(merge);
  into.swap(merged_);
}

void SelfCollision::emit(Contacts& out) const {
  out.triangle_point.resize(4 * triangle_point_pairs_.size());
  out.triangle_point_triangle.resize(triangle_point_pairs_.size());
  parallel_over(triangle_point_pairs_.size(), [&](std::size_t k) {
    const auto [p, t] = triangle_point_pairs_[k];
    out.triangle_point_triangle[k] = t;
    ParticleIndex* contact = out.triangle_point.data() + 4 * k;
    contact[0] = p;
    std::copy_n(triangles_.data() + 3 * std::size_t(t), 3, contact + 1);
  });
  out.edge_edge.resize(4 * edge_edge_pairs_.size());
  parallel_over(edge_edge_pairs_.size(), [&](std::size_t k) {
    const auto [e, f] = edge_edge_pairs_[k];
    ParticleIndex* contact = out.edge_edge.data() + 4 * k;
    std::copy_n(edges_.data() + 2 * std::size_t(e), 2, contact);
    std::copy_n(edges_.data() + 2 * std::size_t(f), 2, contact + 2);
  });
}

void SelfCollision::refine(const SelfCollisionPositions& positions,
                           const SelfCollisionSettings& settings, Contacts& out) {
  check(positions, settings);
  const Reach reach = compute_motion(positions, settings);
  if (anchor_.size() != particle_count_) {  // no detection: no candidates
    triangle_point_pairs_.clear(), edge_edge_pairs_.clear();
    measured_candidates_ = 0;
    emit(out);
    return;
  }
  // The next substep on the paths (past the horizon they stop: covers() is false there).
  substep_ = std::min(substep_ + 1, horizon_);
  Frame now = frame(positions);
  now.substep = Real(substep_);
  measure_departures(positions, now);
  filter_candidates(positions, settings, reach.distance);
  emit(out);
  previous_motion_.swap(motion_);
}

void SelfCollision::measure_departures(const SelfCollisionPositions& positions,
                                       const Frame& frame,
                                       std::vector<std::uint32_t>* outran_list) {
  const Particles particles{positions};
  departure_.resize(particle_count_);
  // The largest coordinate met, for the rounding allowance: the distances compared are
  // differences of coordinates that large. One entry per chunk (one thread per chunk).
  chunks_->largest.assign((particle_count_ + detail::kCollisionChunk - 1) / detail::kCollisionChunk,
                          {0});
  chunks_->vertices.run(
      particle_count_,
      [&](std::size_t item, std::vector<std::uint32_t>& buffer) {
        const std::uint32_t i = std::uint32_t(item);
        const Departure squared = squared_departure(i, frame, positions);
        // Eigen's norm() is the root of squaredNorm(): the same lengths as measuring apart.
        departure_[i] = {std::sqrt(squared.way), std::sqrt(squared.motion)};
        if (outran_list && outran(squared, i)) buffer.push_back(i);
        Real& most = chunks_->largest[item / detail::kCollisionChunk].coordinate;
        most = std::max({most, particles.start(i).cwiseAbs().maxCoeff(),
                         anchor_[i].cwiseAbs().maxCoeff()});
      },
      outran_list ? *outran_list : outran_scratch_);
  Real largest = 0;
  for (const Chunks::Largest& chunk : chunks_->largest) largest = std::max(largest, chunk.coordinate);
  departure_allowance_ = kAllowancePerCoordinate * largest;
}

void SelfCollision::filter_candidates(const SelfCollisionPositions& positions,
                                      const SelfCollisionSettings& settings, Real reach) {
  const Particles particles{positions};
  const Departure* departure = departure_.data();
  // Past this bound on d_start − max |Δp − Δx| a candidate cannot be a contact (the bound
  // and its allowance are at the top of self_collision.hpp).
  const Real ruled_out = reach + Real(1e-3) * reach + departure_allowance_;
  // The substeps of the horizon after this one: each candidate's bound is that many
  // substeps of its relative motion above its least. Credited short by
  // kAllowancePerCoordinate: bound and credit are each up to T ρ, which need not be small
  // beside the reach (a long horizon, a fast pair), and their rounding is then not the
  // distances' that the allowance above covers; 10⁻⁵ of the credit is far above it.
  const Real left =
      Real(horizon_ > substep_ ? horizon_ - substep_ : 0) * (Real(1) - kAllowancePerCoordinate);
  const std::size_t chunks =
      (std::max(candidate_triangle_point_.size(), candidate_edge_edge_.size()) +
       detail::kCollisionChunk - 1) / detail::kCollisionChunk;
  chunks_->measured.assign(2 * chunks, {0});
  // Each primitive's largest way plus largest motion, once per substep: the bound below
  // then reads two numbers per candidate instead of every corner's departure (the same
  // sums, so the same decisions).
  const std::size_t triangle_count = triangles_.size() / 3, edge_count = edges_.size() / 2;
  vertex_spread_.resize(particle_count_);
  triangle_spread_.resize(triangle_count);
  edge_spread_.resize(edge_count);
  parallel_over(particle_count_, [&](std::size_t i) {
    vertex_spread_[i] = departure[i].way + departure[i].motion;
  });
  parallel_over(triangle_count, [&](std::size_t t) {
    const Departure &da = departure[triangles_[3 * t]], &db = departure[triangles_[3 * t + 1]],
                    &dc = departure[triangles_[3 * t + 2]];
    triangle_spread_[t] =
        std::max({da.way, db.way, dc.way}) + std::max({da.motion, db.motion, dc.motion});
  });
  parallel_over(settings.edge_edge ? edge_count : 0, [&](std::size_t e) {
    const Departure &d0 = departure[edges_[2 * e]], &d1 = departure[edges_[2 * e + 1]];
    edge_spread_[e] = std::max(d0.way, d1.way) + std::max(d0.motion, d1.motion);
  });
  // The candidates of the last detection, filtered by the contact rule at this substep's
  // start positions and motions; their order (sorted by key) is kept.
  chunks_->triangle_point.run(
      candidate_triangle_point_.size(),
      [&](std::size_t k, std::vector<Pair>& buffer) {
        const Candidate candidate = candidate_triangle_point_[k];
        const std::uint32_t p = candidate.first, t = candidate.second;
        if (candidate.bound + left * candidate.rate - vertex_spread_[p] - triangle_spread_[t] >
            ruled_out)
          return;
        const std::uint32_t a = triangles_[3 * t], b = triangles_[3 * t + 1], c = triangles_[3 * t + 2];
        ++chunks_->measured[k / detail::kCollisionChunk].measured;
        const std::uint32_t point_id[1] = {p}, corner_ids[3] = {a, b, c};
        const Real within = reach + relative_motion(motion_.data(), point_id, corner_ids);
        const Vector3r point[1] = {particles.start(p)};
        const Vector3r corners[3] = {particles.start(a), particles.start(b), particles.start(c)};
        if (separated_along_an_axis(point, corners, within)) return;
        if (detail::squared_point_triangle_distance(point[0], corners[0], corners[1], corners[2]) <
            within * within)
          buffer.push_back({p, t});
      },
      triangle_point_pairs_);
  // Edge–edge: the bound and the axis test one candidate at a time, the exact distances of
  // those left a vector at a time (segment_distances.cpp, squared_segment_distance's bits), in
  // candidate order.
  chunks_->edge_edge.run_chunks(
      settings.edge_edge ? candidate_edge_edge_.size() : 0,
      [&](std::size_t begin, std::size_t end, std::vector<Pair>& buffer) {
        EdgePairBatch& pairs = edge_pair_batch();
        pairs.clear();
        std::size_t measured = 0;
        for (std::size_t k = begin; k < end; ++k) {
          const Candidate candidate = candidate_edge_edge_[k];
          if (candidate.bound + left * candidate.rate - edge_spread_[candidate.first] -
                  edge_spread_[candidate.second] >
              ruled_out)
            continue;
          const std::uint32_t p0 = edges_[2 * candidate.first], p1 = edges_[2 * candidate.first + 1];
          const std::uint32_t p2 = edges_[2 * candidate.second], p3 = edges_[2 * candidate.second + 1];
          ++measured;
          const std::uint32_t first_ids[2] = {p0, p1}, second_ids[2] = {p2, p3};
          const Real within = reach + relative_motion(motion_.data(), first_ids, second_ids);
          const Vector3r first[2] = {particles.start(p0), particles.start(p1)};
          const Vector3r second[2] = {particles.start(p2), particles.start(p3)};
          if (separated_along_an_axis(first, second, within)) continue;
          pairs.add(k, first, second, within);
        }
        chunks_->measured[chunks + begin / detail::kCollisionChunk].measured = measured;
        for (const std::uint32_t k : pairs.measure()) {
          const Candidate& candidate = candidate_edge_edge_[k];
          buffer.push_back({candidate.first, candidate.second});
        }
      },
      edge_edge_pairs_);
  measured_candidates_ = 0;
  for (const Chunks::Count& count : chunks_->measured) measured_candidates_ += count.measured;
}

void make_self_collision_constraints(const SelfCollision::Contacts& contacts,
                                     std::size_t particle_count,
                                     const SelfCollisionSettings& settings,
                                     TrianglePointDistanceConstraints& triangle_point,
                                     EdgeEdgeDistanceConstraints& edge_edge) {
  ProximityDistanceConstraintInput input;
  input.particle_count = particle_count;
  input.rest_distance = settings.thickness;
  input.compression_stiffness = settings.stiffness;
  input.stretch_stiffness = 0;
  input.particles = contacts.triangle_point;
  make_triangle_point_distance_constraints(input, triangle_point);
  input.particles = contacts.edge_edge;
  make_edge_edge_distance_constraints(input, edge_edge);
}

SelfCollisionConstraints make_self_collision_constraints(const SelfCollision::Contacts& contacts,
                                                         std::size_t particle_count,
                                                         const SelfCollisionSettings& settings) {
  SelfCollisionConstraints result;
  make_self_collision_constraints(contacts, particle_count, settings, result.triangle_point,
                                  result.edge_edge);
  return result;
}

}  // namespace tessera
