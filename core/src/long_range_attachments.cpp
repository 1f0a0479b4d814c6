// Long-range attachments (long_range_attachments.hpp): a multi-source Dijkstra over the
// edges' rest lengths (in double, so a long path's length does not drift with float rounding),
// then one tether per reached movable particle.
#include <tessera/core/long_range_attachments.hpp>

#include <cmath>
#include <algorithm>
#include <cstdint>
#include <limits>
#include <queue>
#include <tuple>
#include <string>
#include <utility>
#include <vector>

#include <tessera/core/error.hpp>

namespace tessera {
namespace {

/// The edge graph as CSR: neighbours[offsets[p], offsets[p + 1]) of particle p.
struct EdgeGraph {
  std::vector<std::uint32_t> offsets;
  std::vector<ParticleIndex> neighbours;
};

EdgeGraph edge_graph(std::span<const ParticleIndex> edges, std::size_t n) {
  EdgeGraph graph;
  graph.offsets.assign(n + 1, 0);
  for (const ParticleIndex p : edges) ++graph.offsets[p + 1];
  for (std::size_t p = 0; p < n; ++p) graph.offsets[p + 1] += graph.offsets[p];
  graph.neighbours.resize(edges.size());
  std::vector<std::uint32_t> next(graph.offsets.begin(), graph.offsets.end() - 1);
  for (std::size_t e = 0; e + 1 < edges.size(); e += 2) {
    graph.neighbours[next[edges[e]]++] = edges[e + 1];
    graph.neighbours[next[edges[e + 1]]++] = edges[e];
  }
  return graph;
}

void check_input(std::span<const Vector3r> rest_positions, std::span<const Real> inverse_masses,
                 std::span<const ParticleIndex> edges, const LongRangeAttachmentOptions& o) {
  const std::string context = "long-range attachments: ";
  if (inverse_masses.size() != rest_positions.size())
    throw InvalidInput(context + std::to_string(inverse_masses.size()) + " inverse masses for " +
                       std::to_string(rest_positions.size()) + " particles");
  if (edges.size() % 2 != 0)
    throw InvalidInput(context + std::to_string(edges.size()) +
                       " edge indices is not a whole number of edges (2 each)");
  for (std::size_t i = 0; i < edges.size(); ++i)
    if (edges[i] >= rest_positions.size())
      throw InvalidInput(context + "edge " + std::to_string(i / 2) + ": particle " +
                         std::to_string(edges[i]) + " is out of range (" +
                         std::to_string(rest_positions.size()) + " particles)");
  for (std::size_t p = 0; p < rest_positions.size(); ++p)
    if (!rest_positions[p].allFinite())
      throw InvalidInput(context + "rest position of particle " + std::to_string(p) +
                         " is not finite");
  if (!(std::isfinite(o.reach_scale) && o.reach_scale > 0))
    throw InvalidInput(context + "reach scale must be positive and finite");
  if (o.attachments < 1)
    throw InvalidInput(context + "attachments per particle must be at least 1");
}

}  // namespace

TetherConstraints make_long_range_attachments(std::span<const Vector3r> rest_positions,
                                              std::span<const Real> inverse_masses,
                                              std::span<const ParticleIndex> edges,
                                              const LongRangeAttachmentOptions& options) {
  check_input(rest_positions, inverse_masses, edges, options);
  const std::size_t n = rest_positions.size();
  const EdgeGraph graph = edge_graph(edges, n);

  // Dijkstra from every attachment at once, each particle settled once per attachment up to
  // `attachments` times: queue entries (length, attachment, particle) leave in that order, so
  // a particle keeps its nearest attachments, of equally near ones the smaller numbers, and
  // the search grows from each attachment as its own would until the particles it reaches
  // have enough nearer ones. Every settled (particle, attachment) relaxes the particle's edges
  // once: at most attachments × 2 × edges queue entries.
  std::size_t attachment_count = 0;
  for (std::size_t p = 0; p < n; ++p) attachment_count += !(inverse_masses[p] > 0);
  const std::size_t wanted = std::min(options.attachments, attachment_count);
  struct Settled {
    ParticleIndex attachment;
    double distance;
  };
  constexpr ParticleIndex kNoParticle = std::numeric_limits<ParticleIndex>::max();
  std::vector<Settled> settled(n * wanted);
  std::vector<std::uint32_t> settled_count(n, 0);
  const auto has = [&](ParticleIndex p, ParticleIndex a) {
    for (std::uint32_t k = 0; k < settled_count[p]; ++k)
      if (settled[p * wanted + k].attachment == a) return true;
    return false;
  };
  // Per particle, `wanted` slots remembering the shortest length already queued for an
  // attachment. An entry no shorter than a queued one of the same (attachment, particle)
  // would leave the queue after it and be skipped, so it is not queued at all: on a cloth
  // that is most of the entries (each particle is reached from each settled neighbour). The
  // slots only ever skip such entries, so the result is the same whatever they forget.
  std::vector<Settled> queued(n * wanted, {kNoParticle, 0.0});
  const auto queued_no_longer = [&](ParticleIndex q, ParticleIndex a, double d) {
    Settled* slots = &queued[q * wanted];
    Settled* victim = slots;  // the first free slot, else the longest
    for (std::size_t k = 0; k < wanted; ++k) {
      if (slots[k].attachment == a) {
        if (slots[k].distance <= d) return true;
        slots[k].distance = d;
        return false;
      }
      if (victim->attachment != kNoParticle &&
          (slots[k].attachment == kNoParticle || slots[k].distance > victim->distance))
        victim = &slots[k];
    }
    if (victim->attachment == kNoParticle || d < victim->distance) *victim = {a, d};
    return false;
  };
  using Entry = std::tuple<double, ParticleIndex, ParticleIndex>;  // length, attachment, particle
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
  for (std::size_t p = 0; p < n; ++p)
    if (!(inverse_masses[p] > 0) && graph.offsets[p + 1] > graph.offsets[p])
      queue.push({0.0, ParticleIndex(p), ParticleIndex(p)});
  while (!queue.empty()) {
    const auto [d, a, p] = queue.top();
    queue.pop();
    if (settled_count[p] == wanted || has(p, a)) continue;
    settled[p * wanted + settled_count[p]++] = {a, d};
    // A settled pair is never queued again (has() above): its slot is free for another.
    for (std::size_t k = 0; k < wanted; ++k)
      if (queued[p * wanted + k].attachment == a) queued[p * wanted + k].attachment = kNoParticle;
    for (std::uint32_t k = graph.offsets[p]; k < graph.offsets[p + 1]; ++k) {
      const ParticleIndex q = graph.neighbours[k];
      if (!(inverse_masses[q] > 0) || settled_count[q] == wanted || has(q, a)) continue;
      const double length = d + (rest_positions[p] - rest_positions[q]).cast<double>().norm();
      if (queued_no_longer(q, a, length)) continue;
      queue.push({length, a, q});
    }
  }

  std::vector<ParticleIndex> pairs;
  std::vector<Real> reach;
  for (std::size_t p = 0; p < n; ++p) {
    if (!(inverse_masses[p] > 0)) continue;
    for (std::uint32_t k = 0; k < settled_count[p]; ++k) {
      const Settled& s = settled[p * wanted + k];
      const Real d = Real(s.distance * double(options.reach_scale));
      if (!(d > 0)) continue;  // coincident with its attachment at rest: nothing to hold
      pairs.insert(pairs.end(), {ParticleIndex(p), s.attachment});
      reach.push_back(d);
    }
  }
  return make_tether_constraints(
      {.particles = pairs,
       .rest_positions = rest_positions,
       .max_distances = reach,
       .stiffness = options.stiffness,
       .compliance = options.compliance});
}

}  // namespace tessera
