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

#include <tbb/parallel_for.h>

#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/refinement.hpp>
#include <tessera/core/huge_pages.hpp>

#include "colour_masks.hpp"
#include "large_buffer.hpp"

namespace tessera {
namespace detail {

namespace {

/// The one-word first-fit step: the lowest colour none of particles[begin, end) carries in
/// `bits`, taken for them and written to `colour`; false (nothing changed) when all 64 are
/// taken (a 65th colour: the general loop, whose sets grow, takes over).
inline bool first_fit_in_one_word(std::uint64_t* bits, const ParticleIndex* particles,
                                  std::uint32_t begin, std::uint32_t end, Colour& colour) {
  std::uint64_t taken = 0;
  for (std::uint32_t j = begin; j < end; ++j) taken |= bits[particles[j]];
  if (taken == ~std::uint64_t(0)) return false;
  const Colour k = static_cast<Colour>(std::countr_one(taken));
  const std::uint64_t bit = std::uint64_t(1) << k;
  for (std::uint32_t j = begin; j < end; ++j) bits[particles[j]] |= bit;
  colour = k;
  return true;
}

}  // namespace

std::size_t first_fit_in_order(const ConstraintGraph& graph, std::span<const ConstraintIndex> order,
                               ParticleColourMasks& masks, std::span<Colour> colours) {
  constexpr std::size_t kPrefetchDistance = 16;
  Colour largest = 0;
  std::size_t i = 0;
  // While 64 colours suffice, raw arrays and a prefetch in three stages, each reading what the
  // one before brought in: the constraint's CSR offsets 3d ahead, its particle list 2d ahead,
  // its particles' sets d ahead (an order is a gather: each stage is a cache miss otherwise).
  if (masks.words() == 1) {
    constexpr std::size_t d = kPrefetchDistance / 2;
    std::uint64_t* bits = masks.data();
    const std::uint32_t* offsets = graph.constraint_offsets().data();
    const ParticleIndex* particles = graph.constraint_particles().data();
    const std::size_t count = order.size();
    for (; i < count; ++i) {
      if (i + 3 * d < count) __builtin_prefetch(&offsets[order[i + 3 * d]]);
      if (i + 2 * d < count) {
        __builtin_prefetch(&particles[offsets[order[i + 2 * d]]]);
        __builtin_prefetch(&colours[order[i + 2 * d]], 1);
      }
      if (i + d < count) {
        const ConstraintIndex ahead = order[i + d];
        for (std::uint32_t j = offsets[ahead]; j < offsets[ahead + 1]; ++j)
          __builtin_prefetch(&bits[particles[j]]);
      }
      const ConstraintIndex c = order[i];
      if (!first_fit_in_one_word(bits, particles, offsets[c], offsets[c + 1], colours[c])) break;
      largest = std::max(largest, colours[c]);
    }
  }
  for (; i < order.size(); ++i) {
    if (i + kPrefetchDistance < order.size())
      masks.prefetch(graph.particles_of(order[i + kPrefetchDistance]));
    const auto particles = graph.particles_of(order[i]);
    const Colour k = masks.first_free_growing(particles);
    masks.take(particles, k);
    colours[order[i]] = k;
    largest = std::max(largest, k);
  }
  return order.empty() ? 0 : std::size_t(largest) + 1;
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
      if (!first_fit_in_one_word(bits, particles, begin, end, colours[c])) break;
      largest = std::max(largest, colours[c]);
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

namespace {

/// Constraints per chunk of the stencil order's parallel passes (fixed, so the same work split
/// and the same arrays for any thread count).
constexpr std::size_t kStencilChunk = std::size_t(1) << 16;

/// Sorts v[0..n) in place: a network for the usual sizes, std::sort beyond.
inline void sort_small(ParticleIndex* v, std::size_t n) {
  const auto order = [&](std::size_t i, std::size_t j) {
    const ParticleIndex a = v[i], b = v[j];
    v[i] = std::min(a, b);
    v[j] = std::max(a, b);
  };
  switch (n) {
    case 0: case 1: return;
    case 2: order(0, 1); return;
    case 3: order(0, 1); order(1, 2); order(0, 1); return;
    case 4: order(0, 1); order(2, 3); order(0, 2); order(1, 3); order(1, 2); return;
    default: std::sort(v, v + n);
  }
}

/// A constraint's shape: its particle count n and the offsets of its sorted particles from the
/// first. Up to four particles whose offsets are below 2^20 (every generated mesh, and most
/// read ones after a locality order) are packed exactly into a key with the top bit set;
/// anything else is keyed by the hash of the shape. Hashing every constraint cost half the
/// stencil order's time; the hash by which classes are ranked is now taken once per class,
/// from its first constraint. (A hash key equal to a packed key of another shape would join
/// the two shapes in one class: a 2^-64 chance per pair, as two shapes of one hash before.)
constexpr unsigned kOffsetBits = 20;
constexpr std::uint64_t kPackedShape = std::uint64_t(1) << 63;

std::uint64_t shape_hash(std::size_t n, const ParticleIndex* sorted) {
  std::uint64_t h = mix_hash(0x5EED, n);
  for (std::size_t i = 1; i < n; ++i) h = mix_hash(h, sorted[i] - sorted[0]);
  return h;
}

std::uint64_t shape_key(std::size_t n, const ParticleIndex* sorted) {
  if (n > 4) return shape_hash(n, sorted);
  std::uint64_t key = kPackedShape | (std::uint64_t(n) << 60);
  for (std::size_t i = 1; i < n; ++i) {
    const std::uint64_t offset = sorted[i] - sorted[0];
    if (offset >> kOffsetBits) return shape_hash(n, sorted);
    key |= offset << (kOffsetBits * (i - 1));
  }
  return key;
}

/// Constraint c's particles, sorted, in `small` (or in `large` beyond its eight).
const ParticleIndex* sorted_particles(const std::uint32_t* offsets,
                                      const ParticleIndex* incidences, std::size_t c,
                                      ParticleIndex (&small)[8],
                                      std::vector<ParticleIndex>& large) {
  const std::size_t n = offsets[c + 1] - offsets[c];
  ParticleIndex* sorted = small;
  if (n > 8) {
    large.resize(n);
    sorted = large.data();
  }
  std::copy(incidences + offsets[c], incidences + offsets[c + 1], sorted);
  sort_small(sorted, n);
  return sorted;
}

/// Shape classes: distinct shape keys with their size and arity, found through an
/// open-addressing table. Class ids are in order of first appearance; nothing downstream
/// depends on them (ranks sort classes by arity, size and the shape's hash).
class ShapeClasses {
 public:
  struct Class {
    std::uint64_t shape;  // the key (shape_key)
    std::uint32_t size;
    std::uint32_t arity;
    std::size_t first;  // the class's first constraint
    std::uint64_t hash;  // the shape's hash (shape_hash), taken before the classes are ranked
  };
  ShapeClasses() : slots_(std::size_t(1) << 10, kEmpty) {}

  std::uint32_t add(std::uint64_t shape, std::uint32_t arity, std::size_t constraint) {
    std::size_t mask = slots_.size() - 1;
    for (std::size_t s = slot_of(shape) & mask;; s = (s + 1) & mask) {
      const std::uint32_t k = slots_[s];
      if (k == kEmpty) {
        const auto id = static_cast<std::uint32_t>(classes_.size());
        classes_.push_back({shape, 1, arity, constraint, 0});
        slots_[s] = id;
        if (2 * classes_.size() > slots_.size()) grow();
        return id;
      }
      if (classes_[k].shape == shape) {
        ++classes_[k].size;
        return k;
      }
    }
  }
  std::vector<Class>& classes() { return classes_; }

 private:
  static constexpr std::uint32_t kEmpty = ~std::uint32_t(0);
  /// Spreads a packed key's offsets (small numbers in the low bits) over the slots.
  static std::size_t slot_of(std::uint64_t shape) {
    return std::size_t((shape * 0x9E3779B97F4A7C15ull) >> 32);
  }
  void grow() {
    std::vector<std::uint32_t> wider(2 * slots_.size(), kEmpty);
    const std::size_t mask = wider.size() - 1;
    for (std::uint32_t k = 0; k < classes_.size(); ++k) {
      std::size_t s = slot_of(classes_[k].shape) & mask;
      while (wider[s] != kEmpty) s = (s + 1) & mask;
      wider[s] = k;
    }
    slots_ = std::move(wider);
  }
  std::vector<std::uint32_t> slots_;
  std::vector<Class> classes_;
};

/// Stable sort of keys (anchor << 32 | constraint id) by anchor, least significant digit
/// first. A run already in anchor order (the usual case for generated meshes) is left as it is.
void sort_by_anchor(std::span<std::uint64_t> keys) {
  bool sorted = true;
  std::uint64_t largest = 0;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (i > 0 && (keys[i] >> 32) < (keys[i - 1] >> 32)) sorted = false;
    largest = std::max(largest, keys[i] >> 32);
  }
  if (sorted) return;
  constexpr unsigned kDigitBits = 11;
  constexpr std::size_t kBuckets = std::size_t(1) << kDigitBits;
  LargeBuffer<std::uint64_t> scratch(keys.size());
  std::uint64_t* from = keys.data();
  std::uint64_t* to = scratch.data();
  unsigned passes = 0;
  for (unsigned shift = 32; shift < 64 && (largest >> (shift - 32)) != 0; shift += kDigitBits) {
    std::vector<std::uint32_t> start(kBuckets + 1, 0);
    for (std::size_t i = 0; i < keys.size(); ++i) ++start[((from[i] >> shift) & (kBuckets - 1)) + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    for (std::size_t i = 0; i < keys.size(); ++i) to[start[(from[i] >> shift) & (kBuckets - 1)]++] = from[i];
    std::swap(from, to);
    ++passes;
  }
  if (passes % 2 == 1) std::copy(from, from + keys.size(), keys.data());
}

}  // namespace

/// See colour_masks.hpp. Steps, all linear:
///  1. per constraint (in parallel), the sorted movable particles p0 < p1 < ...; its anchor is
///     p0 and its shape (count, p1 − p0, p2 − p0, ...), packed or hashed (shape_key);
///  2. shapes counted into classes (a hash table); a class holding fewer than kSmallestClass
///     constraints is not a pattern (irregular meshes have almost only those) and joins the
///     catch-all class of its arity, so irregular input degrades to "by smallest particle";
///  3. classes ranked by arity (larger stencils first, they are the hard ones to pack), then
///     by size, then by shape; constraints counting-sorted by rank (in parallel over fixed
///     chunks, stably), then each rank's run sorted stably by anchor (runs in parallel).
/// The order is by (rank, anchor, constraint id) whatever the thread count.
LargeBuffer<ConstraintIndex> stencil_order(const ConstraintGraph& graph) {
  constexpr std::size_t kSmallestClass = 64;
  const std::size_t count = graph.constraint_count();
  const std::size_t chunks = (count + kStencilChunk - 1) / kStencilChunk;
  const std::uint32_t* offsets = graph.constraint_offsets().data();
  const ParticleIndex* incidences = graph.constraint_particles().data();

  // 1. Shape and anchor of every constraint.
  LargeBuffer<std::uint64_t> shape(count);
  LargeBuffer<ParticleIndex> anchor(count);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
    ParticleIndex small[8];
    std::vector<ParticleIndex> large;
    const std::size_t end = std::min(count, (chunk + 1) * kStencilChunk);
    for (std::size_t c = chunk * kStencilChunk; c < end; ++c) {
      const std::size_t n = offsets[c + 1] - offsets[c];
      const ParticleIndex* sorted = sorted_particles(offsets, incidences, c, small, large);
      shape[c] = shape_key(n, sorted);
      anchor[c] = n > 0 ? sorted[0] : 0;
    }
  });

  // 2. Classes, and the class of every constraint.
  ShapeClasses table;
  LargeBuffer<std::uint32_t> class_of(count);
  {
    std::uint64_t previous_shape = 0;
    std::uint32_t previous_class = ~std::uint32_t(0);
    for (std::size_t c = 0; c < count; ++c) {
      // Runs of one shape are common (a family generated row by row): skip the probe.
      if (shape[c] == previous_shape && previous_class != ~std::uint32_t(0)) {
        ++table.classes()[previous_class].size;
      } else {
        previous_class = table.add(shape[c], offsets[c + 1] - offsets[c], c);
        previous_shape = shape[c];
      }
      class_of[c] = previous_class;
    }
  }
  std::vector<ShapeClasses::Class>& classes = table.classes();
  {  // Each class ranked by its shape's hash, taken from its first constraint.
    ParticleIndex small[8];
    std::vector<ParticleIndex> large;
    for (ShapeClasses::Class& k : classes)
      k.hash = shape_hash(k.arity, sorted_particles(offsets, incidences, k.first, small, large));
  }

  // 3. Rank: small classes of one arity share a catch-all rank placed after that arity's
  // patterns. Catch-alls are modelled as a class of size 0 per arity.
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
    return classes[a].hash < classes[b].hash;
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
  const std::size_t ranks = classes.empty() ? 0 : std::size_t(rank) + 1;

  // 4. Stable counting sort by rank: per-chunk counts, then each chunk scatters from its own
  // cursors. Keys carry the anchor so the runs sort without another gather.
  std::vector<std::uint32_t> chunk_cursor(chunks * ranks, 0);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
    std::uint32_t* counts = chunk_cursor.data() + chunk * ranks;
    const std::size_t end = std::min(count, (chunk + 1) * kStencilChunk);
    for (std::size_t c = chunk * kStencilChunk; c < end; ++c) {
      class_of[c] = rank_of_class[class_of[c]];  // from here on: the rank
      ++counts[class_of[c]];
    }
  });
  std::vector<std::uint32_t> rank_start(ranks + 1, 0);
  {
    std::uint32_t next = 0;
    for (std::size_t r = 0; r < ranks; ++r) {
      rank_start[r] = next;
      for (std::size_t chunk = 0; chunk < chunks; ++chunk) {
        const std::uint32_t n = chunk_cursor[chunk * ranks + r];
        chunk_cursor[chunk * ranks + r] = next;
        next += n;
      }
    }
    rank_start[ranks] = next;
  }
  // The shapes are no longer needed: their storage takes the keys.
  LargeBuffer<std::uint64_t> keys = std::move(shape);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
    std::uint32_t* cursor = chunk_cursor.data() + chunk * ranks;
    const std::size_t end = std::min(count, (chunk + 1) * kStencilChunk);
    for (std::size_t c = chunk * kStencilChunk; c < end; ++c)
      keys[cursor[class_of[c]]++] = (std::uint64_t(anchor[c]) << 32) | c;
  });

  // 5. Each rank's run by anchor (ids already increase within a run).
  LargeBuffer<ConstraintIndex> order(count);
  tbb::parallel_for(std::size_t(0), ranks, [&](std::size_t r) {
    const std::size_t begin = rank_start[r], end = rank_start[r + 1];
    sort_by_anchor({keys.data() + begin, end - begin});
    for (std::size_t i = begin; i < end; ++i) order[i] = static_cast<ConstraintIndex>(keys[i]);
  }, tbb::simple_partitioner());
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
