// The sequential strategies: first-fit in a chosen order (greedy, largest-first,
// smallest-last, stencil), DSatur, and iterated greedy.
//
// Stencil order. On a regular mesh numbered regularly (a generated grid, a structured tet
// mesh) constraints come in a few shape classes: translates of one stencil, e.g. the bending
// rhombi of one orientation. First-fit over one class in anchor order colours it periodically
// with the fewest colours translation allows (the rhombi {0, p, q, p+q} get 4: the 2×2
// sublattice), and the next class then starts above them. On the uniformly triangulated cloth
// with distance + bending this gives 3 × 4 rhombus colours + 3 × 2 edge colours = 18, the
// lower bound (each colour is then an exact cover of the interior vertices), where
// smallest-last, DSatur and iterated greedy stop at 20. The key uses particle ids only, so the
// constraints' input order does not matter; on irregular meshes there are no large classes
// and it degrades to first-fit by smallest particle.
//
// All of them work on the implicit conflict graph: a constraint's neighbours are the other
// constraints at its movable particles. "Degree" below is the conflict weight
// Σ_p (deg(p) − 1) over the constraint's movable particles: the neighbour count when two
// constraints share at most one particle (the edges of a mesh), an upper bound
// otherwise. It is what the particle CSR gives in O(arity) and what degrees drop by as
// constraints are removed, which keeps smallest-last linear in Σ_p deg(p)².
//
// Determinism: every tie is broken by constraint id or by a fixed scan order, and nothing
// depends on threads, so the same graph always gets the same colouring.
#include <algorithm>
#include <numeric>

#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/refinement.hpp>
#include <tessera/core/huge_pages.hpp>

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
  constexpr std::size_t kPrefetchDistance = 32;
  const std::size_t count = graph.constraint_count();
  Colour largest = 0;
  std::size_t c = 0;
  // While 64 colours suffice (one word per particle), a loop over the raw CSR arrays: in
  // input order consecutive constraints share particles, so each first-fit waits for the
  // previous one's store; keeping that chain to load, OR, count, shift, OR, store is what
  // makes it fast (the general loop below recomputed word offsets and spans around it).
  if (masks.words() == 1) {
    std::uint64_t* bits = masks.data();
    const std::uint32_t* offsets = graph.constraint_offsets().data();
    const ParticleIndex* particles = graph.constraint_particles().data();
    for (; c < count; ++c) {
      const std::uint32_t begin = offsets[c], end = offsets[c + 1];
      // Every particle of the constraint 32 ahead: in shuffled input they lie on different
      // cache lines (68 against 86 ms on the shuffled 6.3 M cloth, prefetching only the first
      // at 16 ahead). A constraint without a movable particle has an empty range here.
      if (c + kPrefetchDistance < count)
        for (std::uint32_t j = offsets[c + kPrefetchDistance]; j < offsets[c + kPrefetchDistance + 1]; ++j)
          __builtin_prefetch(&bits[particles[j]]);
      std::uint64_t taken = 0;
      for (std::uint32_t j = begin; j < end; ++j) taken |= bits[particles[j]];
      if (taken == ~std::uint64_t(0)) break;  // a 65th colour: the general loop grows the sets
      const Colour k = static_cast<Colour>(std::countr_one(taken));
      const std::uint64_t bit = std::uint64_t(1) << k;
      for (std::uint32_t j = begin; j < end; ++j) bits[particles[j]] |= bit;
      colours[c] = k;
      largest = std::max(largest, k);
    }
  }
  for (; c < count; ++c) {
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

/// See colour_masks.hpp. Steps, all linear except one sort of 64-bit keys:
///  1. per constraint, the sorted movable particles p0 < p1 < ...; its anchor is p0 and its
///     shape a hash of (count, p1 − p0, p2 − p0, ...);
///  2. shapes sorted to count each class; a class holding fewer than kSmallestClass
///     constraints is not a pattern (irregular meshes have almost only those) and joins the
///     catch-all class of its arity, so irregular input degrades to "by smallest particle";
///  3. classes ranked by arity (larger stencils first, they are the hard ones to pack), then
///     by size, then by shape; constraints counting-sorted by anchor, then stably by rank.
std::vector<ConstraintIndex> stencil_order(const ConstraintGraph& graph) {
  constexpr std::size_t kSmallestClass = 64;
  const std::size_t count = graph.constraint_count();
  std::vector<std::uint64_t> shape(count);
  std::vector<ParticleIndex> anchor(count, 0);
  std::vector<std::uint32_t> arity(count);
  std::vector<ParticleIndex> sorted;
  for (std::size_t c = 0; c < count; ++c) {
    const auto particles = graph.particles_of(static_cast<ConstraintIndex>(c));
    sorted.assign(particles.begin(), particles.end());
    std::sort(sorted.begin(), sorted.end());
    arity[c] = static_cast<std::uint32_t>(sorted.size());
    std::uint64_t h = mix_hash(0x5EED, sorted.size());
    for (std::size_t i = 1; i < sorted.size(); ++i) h = mix_hash(h, sorted[i] - sorted[0]);
    shape[c] = h;
    if (!sorted.empty()) anchor[c] = sorted[0];
  }
  // Class sizes: sort the distinct shapes with their multiplicity.
  std::vector<std::uint64_t> shapes = shape;
  std::sort(shapes.begin(), shapes.end());
  struct ShapeClass {
    std::uint64_t shape;
    std::uint32_t size;
    std::uint32_t arity;
  };
  std::vector<ShapeClass> classes;
  for (std::size_t i = 0; i < shapes.size();) {
    std::size_t j = i;
    while (j < shapes.size() && shapes[j] == shapes[i]) ++j;
    classes.push_back({shapes[i], static_cast<std::uint32_t>(j - i), 0});
    i = j;
  }
  const auto class_index = [&](std::uint64_t h) {
    return static_cast<std::size_t>(
        std::lower_bound(classes.begin(), classes.end(), h,
                         [](const ShapeClass& a, std::uint64_t b) { return a.shape < b; }) -
        classes.begin());
  };
  std::vector<std::uint32_t> class_of(count);
  for (std::size_t c = 0; c < count; ++c) {
    class_of[c] = static_cast<std::uint32_t>(class_index(shape[c]));
    classes[class_of[c]].arity = arity[c];
  }
  // Rank: small classes of one arity share a catch-all rank placed after that arity's
  // patterns. Catch-alls are modelled as a class of size 0 with shape 0 per arity.
  std::vector<std::size_t> ranking(classes.size());
  std::iota(ranking.begin(), ranking.end(), std::size_t(0));
  const auto effective_size = [&](std::size_t k) {
    return classes[k].size >= kSmallestClass ? classes[k].size : 0u;
  };
  std::sort(ranking.begin(), ranking.end(), [&](std::size_t a, std::size_t b) {
    if (classes[a].arity != classes[b].arity) return classes[a].arity > classes[b].arity;
    const std::uint32_t sa = effective_size(a), sb = effective_size(b);
    if (sa != sb) return sa > sb;
    if (sa == 0) return false;  // both catch-all: same rank
    return classes[a].shape < classes[b].shape;
  });
  std::vector<std::uint32_t> rank_of_class(classes.size());
  std::uint32_t rank = 0;
  for (std::size_t i = 0; i < ranking.size(); ++i) {
    const std::size_t k = ranking[i];
    if (i > 0) {
      const std::size_t previous = ranking[i - 1];
      const bool same_catch_all = effective_size(k) == 0 && effective_size(previous) == 0 &&
                                  classes[k].arity == classes[previous].arity;
      if (!same_catch_all) ++rank;
    }
    rank_of_class[k] = rank;
  }
  // Counting sort by anchor, then stable counting sort by rank.
  std::vector<std::uint32_t> start(graph.particle_count() + 1, 0);
  for (std::size_t c = 0; c < count; ++c) ++start[anchor[c] + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<ConstraintIndex> by_anchor(count);
  for (std::size_t c = 0; c < count; ++c) by_anchor[start[anchor[c]]++] = static_cast<ConstraintIndex>(c);
  std::vector<std::uint32_t> rank_start(std::size_t(rank) + 2, 0);
  for (std::size_t c = 0; c < count; ++c) ++rank_start[rank_of_class[class_of[c]] + 1];
  std::partial_sum(rank_start.begin(), rank_start.end(), rank_start.begin());
  std::vector<ConstraintIndex> order(count);
  for (ConstraintIndex c : by_anchor) order[rank_start[rank_of_class[class_of[c]]]++] = c;
  return order;
}

}  // namespace detail

namespace {

using detail::largest_first_order;
using detail::smallest_last_order;

using detail::ParticleColourMasks;

// First-fit starts with one word of colours per particle and grows the sets on demand: asking
// the graph for its lower bound would count every particle's degree, which first-fit never
// needs (the same colours either way).
constexpr std::size_t kFirstFitCapacity = 64;

Colouring colour_first_fit(const ConstraintGraph& graph, std::span<const ConstraintIndex> order) {
  std::vector<Colour> colours = make_large_vector<Colour>(graph.constraint_count(), 0);
  ParticleColourMasks masks(graph.particle_count(), kFirstFitCapacity);
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
  std::vector<Colour> colours = make_large_vector<Colour>(count, 0);
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
    std::vector<Colour> colours = make_large_vector<Colour>(graph.constraint_count(), 0);
    ParticleColourMasks masks(graph.particle_count(), kFirstFitCapacity);
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

class StencilStrategy final : public ColouringStrategy {
 public:
  std::string_view name() const override { return "stencil"; }
  std::string_view description() const override {
    return "first-fit by stencil shape class, then by smallest particle (regular meshes)";
  }
  Colouring colour(const ConstraintGraph& graph, const ColouringOptions&) const override {
    return colour_first_fit(graph, detail::stencil_order(graph));
  }
};

class IteratedGreedyStrategy final : public ColouringStrategy {
 public:
  std::string_view name() const override { return "iterated-greedy"; }
  std::string_view description() const override {
    return "best of stencil and smallest-last, then iterated greedy and colour elimination";
  }
  Colouring colour(const ConstraintGraph& graph, const ColouringOptions& options) const override {
    // Stencil order is linear and optimal on regular meshes; smallest-last (seconds on
    // millions of constraints) only runs when the stencil start is above the lower bound.
    Colouring start = colour_first_fit(graph, detail::stencil_order(graph));
    if (start.colour_count() <= graph.colour_lower_bound()) return start;
    Colouring degeneracy = colour_first_fit(graph, smallest_last_order(graph));
    if (degeneracy.colour_count() < start.colour_count()) start = std::move(degeneracy);
    return reduce_colours(graph, start, options);
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
std::shared_ptr<const ColouringStrategy> make_stencil_strategy() {
  return std::make_shared<StencilStrategy>();
}
std::shared_ptr<const ColouringStrategy> make_iterated_greedy_strategy() {
  return std::make_shared<IteratedGreedyStrategy>();
}

}  // namespace tessera
