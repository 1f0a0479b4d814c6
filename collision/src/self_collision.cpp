// Self-collision detection per substep, in four steps (the picture and the contact rule are
// in self_collision.hpp):
//
//   reach_boxes        each particle's motion and budget (what it may move until the next
//                      detection); the boxes of vertices, triangles and edges at the start,
//                      grown by their budgets and by r (vertices), r/2 (edges)
//   grids              the triangles and the edges in a uniform grid each
//   vertex–triangle    each vertex queries the triangle grid; topology, statics, distance
//   edge–edge          each edge queries the edge grid for higher edges; same filters
//   filter             the candidates that meet the contact rule at this substep (also
//                      what refine() does on later substeps)
//
// Both contact lists come out of chunked loops (chunked_output.hpp): sorted by key, whatever
// the thread count.
#include <tessera/collision/self_collision.hpp>

#include <algorithm>
#include <cmath>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <tessera/core/error.hpp>

#include "chunked_output.hpp"
#include "closest_distance.hpp"

namespace tessera {

struct SelfCollision::Chunks {
  detail::ChunkedOutput<Pair> triangle_point, edge_edge;
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

/// Reads the particles' arrays by index.
struct Particles {
  const SelfCollisionPositions& p;
  Vector3r start(std::uint32_t i) const {
    return Vector3r(p.previous_x[i], p.previous_y[i], p.previous_z[i]);
  }
  /// The box of particles `ids` at the start of the substep, grown by the most any of them
  /// may move (its budget, see detect()) and by `reach`.
  template <std::size_t N>
  Aabb reach_box(const std::uint32_t (&ids)[N], const Real* budget, Real reach) const {
    const std::uint32_t first = ids[0];
    Aabb box{{p.previous_x[first], p.previous_y[first], p.previous_z[first]},
             {p.previous_x[first], p.previous_y[first], p.previous_z[first]}};
    Real grow = 0;
    for (const std::uint32_t i : ids) {
      include(box, p.previous_x[i], p.previous_y[i], p.previous_z[i]);
      grow = std::max(grow, budget[i]);
    }
    inflate(box, grow + reach);
    return box;
  }
  bool all_static(std::initializer_list<std::uint32_t> ids) const {
    for (const std::uint32_t i : ids)
      if (p.inverse_mass[i] != 0) return false;
    return true;
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

template <class Body>
void parallel_over(std::size_t n, Body&& body) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 2048),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i != range.end(); ++i) body(i);
                    });
}

}  // namespace

SelfCollision::SelfCollision(std::span<const std::uint32_t> triangles,
                             std::size_t particle_count)
    : particle_count_(particle_count),
      triangles_(triangles.begin(), triangles.end()),
      chunks_(std::make_unique<Chunks>()) {
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

SelfCollision::Reach SelfCollision::compute_motion(const SelfCollisionPositions& positions,
                                                   const SelfCollisionSettings& settings) {
  const Particles particles{positions};
  motion_.resize(particle_count_);
  parallel_over(particle_count_, [&](std::size_t i) {
    motion_[i] = Vector3r(positions.x[i], positions.y[i], positions.z[i]) -
                 particles.start(std::uint32_t(i));
  });
  return {settings.thickness + settings.margin};
}

namespace {

/// The median of `count` vectors, per axis (the same for any thread count): the motion of
/// the bulk of the cloth, which a part that rests or falls as a whole shares exactly.
template <class Of>
Vector3r median_of(std::size_t count, Of&& of, std::vector<Real>& scratch) {
  Vector3r median = Vector3r::Zero();
  if (count == 0) return median;
  scratch.resize(count);
  for (int axis = 0; axis < 3; ++axis) {
    for (std::size_t i = 0; i < count; ++i) scratch[i] = of(i)[axis];
    const auto middle = scratch.begin() + std::ptrdiff_t(count / 2);
    std::nth_element(scratch.begin(), middle, scratch.end());
    median[axis] = *middle;
  }
  return median;
}

}  // namespace

void SelfCollision::compute_budgets(const SelfCollisionPositions& positions,
                                    const SelfCollisionSettings& settings) {
  // b = 2 (k |Δ − ū| + skin / 2), ū the bulk's (median) motion: half for the motion of a
  // substep, half for the way since this detection (covers()).
  const Particles particles{positions};
  const Vector3r bulk_motion =
      median_of(particle_count_, [&](std::size_t i) { return motion_[i]; }, scratch_);
  budget_.resize(particle_count_);
  anchor_.resize(particle_count_);
  const Real scale = settings.motion_scale, skin = settings.skin;
  parallel_over(particle_count_, [&](std::size_t i) {
    budget_[i] = 2 * scale * (motion_[i] - bulk_motion).norm() + skin;
    anchor_[i] = particles.start(std::uint32_t(i));
  });
}

void SelfCollision::detect(const SelfCollisionPositions& positions,
                           const SelfCollisionSettings& settings, Contacts& out) {
  check(positions, settings);
  const Real reach = compute_motion(positions, settings).distance;
  compute_budgets(positions, settings);
  const Particles particles{positions};
  const std::size_t triangle_count = triangles_.size() / 3;
  const std::size_t edge_count = edges_.size() / 2;
  const Real* budget = budget_.data();
  const auto most = [&](std::initializer_list<std::uint32_t> ids) {
    Real m = 0;
    for (const std::uint32_t i : ids) m = std::max(m, budget[i]);
    return m;
  };

  // Candidates: the pairs closer at the start than the reach plus their particles' budgets.
  // Boxes: the start positions grown by the budgets and the reach, the vertex's by all of
  // the reach and an edge's by half. A pair within that distance has overlapping boxes, since
  // no coordinate differs by more than the distance; so the grid misses no candidate.
  vertex_boxes_.resize(particle_count_);
  parallel_over(particle_count_, [&](std::size_t i) {
    const std::uint32_t ids[1] = {std::uint32_t(i)};
    vertex_boxes_[i] = particles.reach_box(ids, budget, reach);
  });
  triangle_boxes_.resize(triangle_count);
  parallel_over(triangle_count, [&](std::size_t t) {
    const std::uint32_t ids[3] = {triangles_[3 * t], triangles_[3 * t + 1],
                                  triangles_[3 * t + 2]};
    triangle_boxes_[t] = particles.reach_box(ids, budget, 0);
  });
  const std::size_t edge_queries = settings.edge_edge ? edge_count : 0;
  edge_boxes_.resize(edge_queries);
  parallel_over(edge_queries, [&](std::size_t e) {
    const std::uint32_t ids[2] = {edges_[2 * e], edges_[2 * e + 1]};
    edge_boxes_[e] = particles.reach_box(ids, budget, reach / 2);
  });
  triangle_grid_.build(triangle_boxes_);
  edge_grid_.build(edge_boxes_);

  // Vertex–triangle: p against the triangles its box meets.
  chunks_->triangle_point.run(
      particle_count_,
      [&](std::size_t vertex, std::vector<Pair>& buffer) {
        const std::uint32_t p = std::uint32_t(vertex);
        const std::size_t first = buffer.size();
        const Vector3r start = particles.start(p);
        triangle_grid_.for_each_overlap(vertex_boxes_[p], [&](std::uint32_t t) {
          const std::uint32_t a = triangles_[3 * t], b = triangles_[3 * t + 1],
                              c = triangles_[3 * t + 2];
          if (p == a || p == b || p == c || particles.all_static({p, a, b, c})) return;
          const Real within = reach + budget[p] + most({a, b, c});
          if (detail::squared_point_triangle_distance(start, particles.start(a),
                                                      particles.start(b), particles.start(c)) <
              within * within)
            buffer.push_back({p, t});
        });
        std::sort(buffer.begin() + std::ptrdiff_t(first), buffer.end(),
                  [](const Pair& l, const Pair& r) { return l.second < r.second; });
      },
      candidate_triangle_point_);

  // Edge–edge: each edge against the higher edges its box meets.
  chunks_->edge_edge.run(
      edge_queries,
      [&](std::size_t edge, std::vector<Pair>& buffer) {
        const std::uint32_t e = std::uint32_t(edge);
        const std::uint32_t p0 = edges_[2 * e], p1 = edges_[2 * e + 1];
        const std::size_t first = buffer.size();
        const Vector3r s0 = particles.start(p0), s1 = particles.start(p1);
        const Real own = reach + most({p0, p1});
        edge_grid_.for_each_overlap_above(edge_boxes_[e], e, [&](std::uint32_t f) {
          const std::uint32_t p2 = edges_[2 * f], p3 = edges_[2 * f + 1];
          if (p0 == p2 || p0 == p3 || p1 == p2 || p1 == p3 ||
              particles.all_static({p0, p1, p2, p3}))
            return;
          const Real within = own + most({p2, p3});
          if (detail::squared_segment_distance(s0, s1, particles.start(p2),
                                               particles.start(p3)) < within * within)
            buffer.push_back({e, f});
        });
        std::sort(buffer.begin() + std::ptrdiff_t(first), buffer.end(),
                  [](const Pair& l, const Pair& r) { return l.second < r.second; });
      },
      candidate_edge_edge_);
  if (!settings.edge_edge) candidate_edge_edge_.clear();

  // This substep's contacts among them.
  filter_candidates(positions, settings, reach);
  emit(out);
}

bool SelfCollision::covers(const SelfCollisionPositions& positions) {
  if (positions.count != particle_count_ || anchor_.size() != particle_count_) return false;
  // w = |x_start − anchor − W| (the way since the detection, W the bulk's) and
  // m = |Δ − ū| (this substep's motion, ū the bulk's), each within half the budget.
  const Particles particles{positions};
  const auto way = [&](std::size_t i) {
    return Vector3r(particles.start(std::uint32_t(i)) - anchor_[i]);
  };
  const auto motion = [&](std::size_t i) {
    return Vector3r(Vector3r(positions.x[i], positions.y[i], positions.z[i]) -
                    particles.start(std::uint32_t(i)));
  };
  const Vector3r bulk_way = median_of(particle_count_, way, scratch_);
  const Vector3r bulk_motion = median_of(particle_count_, motion, scratch_);
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, particle_count_, 4096), true,
      [&](const tbb::blocked_range<std::size_t>& range, bool holds) {
        for (std::size_t i = range.begin(); holds && i != range.end(); ++i) {
          const Real half = budget_[i] / 2;
          holds = (way(i) - bulk_way).squaredNorm() <= half * half &&
                  (motion(i) - bulk_motion).squaredNorm() <= half * half;
        }
        return holds;
      },
      [](bool l, bool r) { return l && r; });
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
  filter_candidates(positions, settings, reach.distance);
  emit(out);
}

void SelfCollision::filter_candidates(const SelfCollisionPositions& positions,
                                      const SelfCollisionSettings& settings, Real reach) {
  const Particles particles{positions};
  // The candidates of the last detection, filtered by the contact rule at this substep's
  // start positions and motions; their order (sorted by key) is kept.
  chunks_->triangle_point.run(
      candidate_triangle_point_.size(),
      [&](std::size_t k, std::vector<Pair>& buffer) {
        const Pair pair = candidate_triangle_point_[k];
        const std::uint32_t p = pair.first, t = pair.second;
        const std::uint32_t a = triangles_[3 * t], b = triangles_[3 * t + 1], c = triangles_[3 * t + 2];
        const std::uint32_t point_id[1] = {p}, corner_ids[3] = {a, b, c};
        const Real within = reach + relative_motion(motion_.data(), point_id, corner_ids);
        const Vector3r point[1] = {particles.start(p)};
        const Vector3r corners[3] = {particles.start(a), particles.start(b), particles.start(c)};
        if (separated_along_an_axis(point, corners, within)) return;
        if (detail::squared_point_triangle_distance(point[0], corners[0], corners[1], corners[2]) <
            within * within)
          buffer.push_back(pair);
      },
      triangle_point_pairs_);
  chunks_->edge_edge.run(
      settings.edge_edge ? candidate_edge_edge_.size() : 0,
      [&](std::size_t k, std::vector<Pair>& buffer) {
        const Pair pair = candidate_edge_edge_[k];
        const std::uint32_t p0 = edges_[2 * pair.first], p1 = edges_[2 * pair.first + 1];
        const std::uint32_t p2 = edges_[2 * pair.second], p3 = edges_[2 * pair.second + 1];
        const std::uint32_t first_ids[2] = {p0, p1}, second_ids[2] = {p2, p3};
        const Real within = reach + relative_motion(motion_.data(), first_ids, second_ids);
        const Vector3r first[2] = {particles.start(p0), particles.start(p1)};
        const Vector3r second[2] = {particles.start(p2), particles.start(p3)};
        if (separated_along_an_axis(first, second, within)) return;
        if (detail::squared_segment_distance(first[0], first[1], second[0], second[1]) <
            within * within)
          buffer.push_back(pair);
      },
      edge_edge_pairs_);
}

SelfCollisionConstraints make_self_collision_constraints(const SelfCollision::Contacts& contacts,
                                                         std::size_t particle_count,
                                                         const SelfCollisionSettings& settings) {
  ProximityDistanceConstraintInput input;
  input.particle_count = particle_count;
  input.rest_distance = settings.thickness;
  input.compression_stiffness = settings.stiffness;
  input.stretch_stiffness = 0;
  SelfCollisionConstraints result;
  input.particles = contacts.triangle_point;
  result.triangle_point = make_triangle_point_distance_constraints(input);
  input.particles = contacts.edge_edge;
  result.edge_edge = make_edge_edge_distance_constraints(input);
  return result;
}

}  // namespace tessera
