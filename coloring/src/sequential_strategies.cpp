// The sequential strategies: first-fit in a chosen order (greedy, largest-first,
// smallest-last), DSatur, and iterated greedy.
//
// All of them work on the implicit conflict graph: a constraint's neighbours are the other
// constraints at its movable particles. "Degree" below is the conflict weight
// Σ_p (deg(p) − 1) over the constraint's movable particles: the neighbour count when two
// constraints share at most one particle (distance constraints on a mesh), an upper bound
// otherwise. It is what the particle CSR gives in O(arity) and what degrees drop by as
// constraints are removed, which keeps smallest-last linear in Σ_p deg(p)².
//
// Determinism: every tie is broken by constraint id or by a fixed scan order, and nothing
// depends on threads, so the same graph always gets the same colouring.
#include <algorithm>
#include <numeric>

#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/refinement.hpp>

#include "colour_masks.hpp"

namespace tessera {
namespace detail {

std::size_t first_fit_in_order(const ConstraintGraph& graph, std::span<const ConstraintIndex> order,
                               ParticleColourMasks& masks, std::span<Colour> colours) {
  constexpr std::size_t kPrefetchDistance = 16;
  Colour largest = 0;
  bool any = false;
  for (std::size_t i = 0; i < order.size(); ++i) {
    if (i + kPrefetchDistance < order.size())
      masks.prefetch(graph.particles_of(order[i + kPrefetchDistance]));
    const auto particles = graph.particles_of(order[i]);
    const Colour k = masks.first_free_growing(particles);
    masks.take(particles, k);
    colours[order[i]] = k;
    largest = std::max(largest, k);
    any = true;
  }
  return any ? std::size_t(largest) + 1 : 0;
}

std::size_t first_fit_in_id_order(const ConstraintGraph& graph, ParticleColourMasks& masks,
                                  std::span<Colour> colours) {
  constexpr std::size_t kPrefetchDistance = 16;
  const std::size_t count = graph.constraint_count();
  Colour largest = 0;
  for (std::size_t c = 0; c < count; ++c) {
    if (c + kPrefetchDistance < count)
      masks.prefetch(graph.particles_of(static_cast<ConstraintIndex>(c + kPrefetchDistance)));
    const auto particles = graph.particles_of(static_cast<ConstraintIndex>(c));
    const Colour k = masks.first_free_growing(particles);
    masks.take(particles, k);
    colours[c] = k;
    largest = std::max(largest, k);
  }
  return count > 0 ? std::size_t(largest) + 1 : 0;
}

std::size_t compact_colours(std::span<Colour> colours) {
  Colour largest = 0;
  for (Colour k : colours) largest = std::max(largest, k);
  std::vector<Colour> renamed(colours.empty() ? 0 : std::size_t(largest) + 1, 0);
  for (Colour k : colours) renamed[k] = 1;
  Colour next = 0;
  for (Colour& r : renamed) r = r ? next++ : 0;
  for (Colour& k : colours) k = renamed[k];
  return next;
}

/// Conflict weight of every constraint (see the file comment).
std::vector<std::uint32_t> conflict_weights(const ConstraintGraph& graph) {
  std::vector<std::uint32_t> weight(graph.constraint_count(), 0);
  for (std::size_t c = 0; c < weight.size(); ++c)
    for (ParticleIndex p : graph.particles_of(static_cast<ConstraintIndex>(c)))
      weight[c] += static_cast<std::uint32_t>(graph.particle_degree(p) - 1);
  return weight;
}

/// Constraints by decreasing conflict weight, ties by increasing id (a stable counting sort).
std::vector<ConstraintIndex> largest_first_order(const ConstraintGraph& graph) {
  const std::vector<std::uint32_t> weight = detail::conflict_weights(graph);
  const std::uint32_t heaviest = weight.empty() ? 0 : *std::max_element(weight.begin(), weight.end());
  std::vector<std::uint32_t> start(std::size_t(heaviest) + 2, 0);
  for (std::uint32_t w : weight) ++start[heaviest - w + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<ConstraintIndex> order(weight.size());
  for (std::size_t c = 0; c < weight.size(); ++c)
    order[start[heaviest - weight[c]]++] = static_cast<ConstraintIndex>(c);
  return order;
}

/// Matula–Beck smallest-last order, with the Batagelj–Zaversnik bucket array: constraints
/// sorted by current weight in one array, bucket starts per weight, and each constraint's
/// position, so removing a constraint and decrementing its neighbours is O(1) per incidence.
/// Returns the colouring order: the reverse of the removal order.
std::vector<ConstraintIndex> smallest_last_order(const ConstraintGraph& graph) {
  const std::size_t count = graph.constraint_count();
  std::vector<std::uint32_t> weight = detail::conflict_weights(graph);
  const std::uint32_t heaviest = weight.empty() ? 0 : *std::max_element(weight.begin(), weight.end());
  std::vector<std::uint32_t> bucket_start(std::size_t(heaviest) + 2, 0);
  for (std::uint32_t w : weight) ++bucket_start[w + 1];
  std::partial_sum(bucket_start.begin(), bucket_start.end(), bucket_start.begin());
  std::vector<ConstraintIndex> sorted(count);
  std::vector<std::uint32_t> position(count);
  {
    std::vector<std::uint32_t> cursor(bucket_start.begin(), bucket_start.end() - 1);
    for (std::size_t c = 0; c < count; ++c) {
      position[c] = cursor[weight[c]]++;
      sorted[position[c]] = static_cast<ConstraintIndex>(c);
    }
  }
  std::vector<std::uint8_t> removed(count, 0);
  for (std::size_t i = 0; i < count; ++i) {
    const ConstraintIndex c = sorted[i];
    removed[c] = 1;
    for (ParticleIndex p : graph.particles_of(c)) {
      for (ConstraintIndex n : graph.constraints_of(p)) {
        if (removed[n]) continue;
        // Move n to the front of its bucket, then shrink the bucket past it: n now has
        // weight − 1. Buckets below i are consumed, so never start a bucket before i + 1.
        const std::uint32_t w = weight[n];
        std::uint32_t front = std::max<std::uint32_t>(bucket_start[w], static_cast<std::uint32_t>(i + 1));
        const ConstraintIndex other = sorted[front];
        std::swap(sorted[front], sorted[position[n]]);
        position[other] = position[n];
        position[n] = front;
        bucket_start[w] = front + 1;
        --weight[n];
      }
    }
  }
  std::reverse(sorted.begin(), sorted.end());
  return sorted;
}

}  // namespace detail

namespace {

using detail::largest_first_order;
using detail::smallest_last_order;

using detail::ParticleColourMasks;

Colouring colour_first_fit(const ConstraintGraph& graph, std::span<const ConstraintIndex> order) {
  std::vector<Colour> colours(graph.constraint_count(), 0);
  ParticleColourMasks masks(graph.particle_count(), graph.colour_lower_bound());
  detail::first_fit_in_order(graph, order, masks, colours);
  return Colouring::from_colours(std::move(colours));
}

/// DSatur (Brélaz): repeatedly colour the uncoloured constraint whose neighbours already use
/// the most distinct colours. Saturation is the popcount of the OR of the particles' colour
/// sets. The queue is one stack per saturation with lazy deletion (an entry is stale when the
/// constraint is coloured or its saturation moved on); all constraints start in stack 0
/// pushed by increasing weight, so ties go to the heaviest, then to the most recently
/// touched, which grows one coloured front like the classic algorithm.
Colouring colour_dsatur(const ConstraintGraph& graph) {
  const std::size_t count = graph.constraint_count();
  std::vector<Colour> colours(count, 0);
  if (count == 0) return Colouring::from_colours(std::move(colours));
  ParticleColourMasks masks(graph.particle_count(), graph.colour_lower_bound());
  std::vector<std::uint8_t> coloured(count, 0);
  std::vector<std::uint32_t> saturation(count, 0);
  std::vector<std::vector<ConstraintIndex>> stacks(1);
  {
    std::vector<ConstraintIndex> order = largest_first_order(graph);
    stacks[0].assign(order.rbegin(), order.rend());
  }
  auto saturation_of = [&](ConstraintIndex c) {
    const auto particles = graph.particles_of(c);
    std::uint32_t s = 0;
    for (std::size_t w = 0; w < masks.words(); ++w)
      s += static_cast<std::uint32_t>(std::popcount(masks.taken_word(particles, w)));
    return s;
  };
  std::size_t top = 0;
  for (std::size_t done = 0; done < count;) {
    while (stacks[top].empty()) --top;
    const ConstraintIndex c = stacks[top].back();
    stacks[top].pop_back();
    if (coloured[c] || saturation[c] != top) continue;
    const auto particles = graph.particles_of(c);
    const Colour k = masks.first_free_growing(particles);
    masks.take(particles, k);
    colours[c] = k;
    coloured[c] = 1;
    ++done;
    for (ParticleIndex p : particles) {
      for (ConstraintIndex n : graph.constraints_of(p)) {
        if (coloured[n]) continue;
        const std::uint32_t s = saturation_of(n);
        if (s == saturation[n]) continue;
        saturation[n] = s;
        if (s >= stacks.size()) stacks.resize(std::size_t(s) + 1);
        stacks[s].push_back(n);
        top = std::max<std::size_t>(top, s);
      }
    }
  }
  return Colouring::from_colours(std::move(colours));
}

class FirstFitStrategy final : public ColouringStrategy {
 public:
  std::string_view name() const override { return "greedy"; }
  std::string_view description() const override {
    return "first-fit in input order (the usual PBD baseline)";
  }
  Colouring colour(const ConstraintGraph& graph, const ColouringOptions&) const override {
    std::vector<Colour> colours(graph.constraint_count(), 0);
    ParticleColourMasks masks(graph.particle_count(), graph.colour_lower_bound());
    detail::first_fit_in_id_order(graph, masks, colours);
    return Colouring::from_colours(std::move(colours));
  }
};

class LargestFirstStrategy final : public ColouringStrategy {
 public:
  std::string_view name() const override { return "largest-first"; }
  std::string_view description() const override {
    return "first-fit by decreasing conflict degree (Welsh-Powell)";
  }
  Colouring colour(const ConstraintGraph& graph, const ColouringOptions&) const override {
    return colour_first_fit(graph, largest_first_order(graph));
  }
};

class SmallestLastStrategy final : public ColouringStrategy {
 public:
  std::string_view name() const override { return "smallest-last"; }
  std::string_view description() const override {
    return "first-fit in smallest-last degeneracy order (Matula-Beck)";
  }
  Colouring colour(const ConstraintGraph& graph, const ColouringOptions&) const override {
    return colour_first_fit(graph, smallest_last_order(graph));
  }
};

class DsaturStrategy final : public ColouringStrategy {
 public:
  std::string_view name() const override { return "dsatur"; }
  std::string_view description() const override {
    return "most saturated constraint first (Brelaz DSatur)";
  }
  Colouring colour(const ConstraintGraph& graph, const ColouringOptions&) const override {
    return colour_dsatur(graph);
  }
};

class IteratedGreedyStrategy final : public ColouringStrategy {
 public:
  std::string_view name() const override { return "iterated-greedy"; }
  std::string_view description() const override {
    return "smallest-last, then iterated greedy and colour elimination (fewest colours)";
  }
  Colouring colour(const ConstraintGraph& graph, const ColouringOptions& options) const override {
    return reduce_colours(graph, colour_first_fit(graph, smallest_last_order(graph)), options);
  }
};

}  // namespace

std::shared_ptr<const ColouringStrategy> make_greedy_strategy() {
  return std::make_shared<FirstFitStrategy>();
}
std::shared_ptr<const ColouringStrategy> make_largest_first_strategy() {
  return std::make_shared<LargestFirstStrategy>();
}
std::shared_ptr<const ColouringStrategy> make_smallest_last_strategy() {
  return std::make_shared<SmallestLastStrategy>();
}
std::shared_ptr<const ColouringStrategy> make_dsatur_strategy() {
  return std::make_shared<DsaturStrategy>();
}
std::shared_ptr<const ColouringStrategy> make_iterated_greedy_strategy() {
  return std::make_shared<IteratedGreedyStrategy>();
}

}  // namespace tessera
