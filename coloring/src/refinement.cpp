// Colour reduction and balancing post-passes.
//
// Both keep the colouring valid at every step and rely on the per-particle colour sets of a
// valid colouring being exact (each colour at most once per particle), so "is colour k free
// for constraint c" is an OR over c's particles, and moving c is a clear and a set.
//
// Reduction alternates two moves. Iterated greedy (Culberson 1992) recolours first-fit, whole
// colour class after whole colour class; a class is an independent set, so the i-th class
// visited gets colours ≤ i and the count never grows, while a new class order lets first-fit
// pack differently. Elimination tries to empty the smallest colour: each of its constraints
// moves to a colour free at all its particles, or to a colour blocked by exactly one
// constraint that itself can move elsewhere.
//
// Balancing moves constraints out of colours above the mean, either alone (into the smallest
// colour free for it) or, when every colour is taken around it (typical when the count equals
// the lower bound), by swapping two colours along a short Kempe chain: the connected set of
// constraints coloured a or b reachable from it, whose a/b swap keeps the colouring valid.
//
// Determinism: constraints and colours are scanned in fixed orders and the class shuffles use
// a hash of (seed, round), so the result depends on the input and the seed only.
#include <tessera/coloring/refinement.hpp>

#include <algorithm>
#include <numeric>

#include "colour_masks.hpp"

namespace tessera {
namespace {

using detail::ParticleColourMasks;

Colouring rebuild(const ConstraintGraph& graph, const Colouring& original, std::vector<Colour> colours) {
  (void)graph;
  Colouring result = Colouring::from_colours(std::move(colours), original.constraints_by_colour());
  if (original.renumbers_particles())
    result.set_particle_order({original.particle_new_to_old().begin(), original.particle_new_to_old().end()});
  return result;
}

/// Finds, at each particle of c, the constraint holding colour k there; returns it when all
/// such blockers are one constraint, or `none` when there are several (or none).
constexpr ConstraintIndex kNone = ~ConstraintIndex(0);

ConstraintIndex single_blocker(const ConstraintGraph& graph, std::span<const Colour> colours,
                               ConstraintIndex c, Colour k) {
  ConstraintIndex blocker = kNone;
  for (ParticleIndex p : graph.particles_of(c)) {
    for (ConstraintIndex n : graph.constraints_of(p)) {
      if (n == c || colours[n] != k) continue;
      if (blocker != kNone && blocker != n) return kNone;
      blocker = n;
    }
  }
  return blocker;
}

/// Lowest colour below `limit` free at all of c's particles, other than the excluded ones.
Colour free_colour_except(const ParticleColourMasks& masks, std::span<const ParticleIndex> particles,
                          std::size_t limit, Colour excluded0, Colour excluded1) {
  for (std::size_t w = 0; w < masks.words() && w * 64 < limit; ++w) {
    std::uint64_t free = ~masks.taken_word(particles, w);
    for (Colour excluded : {excluded0, excluded1})
      if (excluded / 64 == w) free &= ~(std::uint64_t(1) << (excluded % 64));
    while (free != 0) {
      const Colour k = static_cast<Colour>(w * 64 + std::countr_zero(free));
      if (k >= limit) break;
      return k;
    }
  }
  return static_cast<Colour>(limit);
}

void move(const ConstraintGraph& graph, ParticleColourMasks& masks, std::span<Colour> colours,
          ConstraintIndex c, Colour to) {
  const auto particles = graph.particles_of(c);
  masks.release(particles, colours[c]);
  masks.take(particles, to);
  colours[c] = to;
}

/// Tries to empty the smallest colour; on success renames the last colour into its place
/// and returns the new count, otherwise returns `count` (constraints moved so far stay moved).
std::size_t eliminate_smallest_colour(const ConstraintGraph& graph, ParticleColourMasks& masks,
                                      std::span<Colour> colours, std::size_t count) {
  std::vector<std::size_t> sizes(count, 0);
  for (Colour k : colours) ++sizes[k];
  const Colour smallest = static_cast<Colour>(std::min_element(sizes.begin(), sizes.end()) - sizes.begin());
  bool emptied = true;
  for (std::size_t i = 0; i < colours.size(); ++i) {
    const ConstraintIndex c = static_cast<ConstraintIndex>(i);
    if (colours[c] != smallest) continue;
    const auto particles = graph.particles_of(c);
    const Colour direct = free_colour_except(masks, particles, count, smallest, smallest);
    if (direct < count) {
      move(graph, masks, colours, c, direct);
      continue;
    }
    bool moved = false;
    for (Colour k = 0; k < count && !moved; ++k) {
      if (k == smallest) continue;
      const ConstraintIndex blocker = single_blocker(graph, colours, c, k);
      if (blocker == kNone) continue;
      const Colour elsewhere =
          free_colour_except(masks, graph.particles_of(blocker), count, smallest, k);
      if (elsewhere >= count) continue;
      move(graph, masks, colours, blocker, elsewhere);
      move(graph, masks, colours, c, k);
      moved = true;
    }
    emptied = emptied && moved;
  }
  if (!emptied) return count;
  const Colour last = static_cast<Colour>(count - 1);
  if (smallest != last)
    for (std::size_t c = 0; c < colours.size(); ++c)
      if (colours[c] == last) move(graph, masks, colours, static_cast<ConstraintIndex>(c), smallest);
  return count - 1;
}

/// One iterated-greedy round: classes visited in the given order, first-fit from scratch.
std::size_t recolour_by_classes(const ConstraintGraph& graph, std::span<Colour> colours,
                                std::span<const Colour> class_order, std::size_t count,
                                ParticleColourMasks& masks) {
  std::vector<std::uint32_t> rank(count);
  for (std::size_t i = 0; i < class_order.size(); ++i) rank[class_order[i]] = static_cast<std::uint32_t>(i);
  std::vector<std::uint32_t> start(count + 1, 0);
  for (Colour k : colours) ++start[rank[k] + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<ConstraintIndex> order(colours.size());
  for (std::size_t c = 0; c < colours.size(); ++c) order[start[rank[colours[c]]]++] = static_cast<ConstraintIndex>(c);
  masks = ParticleColourMasks(graph.particle_count(), count);
  return detail::first_fit_in_order(graph, order, masks, colours);
}

}  // namespace

Colouring reduce_colours(const ConstraintGraph& graph, const Colouring& colouring,
                         const ColouringOptions& options) {
  std::vector<Colour> colours(colouring.colours().begin(), colouring.colours().end());
  std::size_t count = colouring.colour_count();
  const std::size_t floor = graph.colour_lower_bound();
  if (count <= floor) return rebuild(graph, colouring, std::move(colours));
  ParticleColourMasks masks = ParticleColourMasks::of(graph, colours, count);
  for (std::size_t round = 0; round < options.reduction_rounds && count > floor; ++round) {
    for (std::size_t before = count + 1; count < before && count > floor;) {
      before = count;
      count = eliminate_smallest_colour(graph, masks, colours, count);
    }
    if (count <= floor) break;
    std::vector<std::size_t> sizes(count, 0);
    for (Colour k : colours) ++sizes[k];
    std::vector<Colour> class_order(count);
    std::iota(class_order.begin(), class_order.end(), Colour(0));
    switch (round % 3) {
      case 0:  // reverse: the classic move, the last (usually smallest) classes go first
        std::reverse(class_order.begin(), class_order.end());
        break;
      case 1:  // largest first, so small classes are spread into the big ones' gaps
        std::stable_sort(class_order.begin(), class_order.end(),
                         [&](Colour a, Colour b) { return sizes[a] > sizes[b]; });
        break;
      default:  // seeded shuffle (Fisher–Yates on a hash, not a shared generator)
        for (std::size_t i = count; i > 1; --i)
          std::swap(class_order[i - 1], class_order[detail::mix_hash(options.seed, round * 1000003u + i) % i]);
        break;
    }
    count = recolour_by_classes(graph, colours, class_order, count, masks);
  }
  return rebuild(graph, colouring, std::move(colours));
}

Colouring balance_colours(const ConstraintGraph& graph, const Colouring& colouring) {
  const std::size_t count = colouring.colour_count();
  std::vector<Colour> colours(colouring.colours().begin(), colouring.colours().end());
  if (count < 2) return rebuild(graph, colouring, std::move(colours));
  ParticleColourMasks masks = ParticleColourMasks::of(graph, colours, count);
  std::vector<std::size_t> sizes(count, 0);
  for (Colour k : colours) ++sizes[k];
  const std::size_t target = (colours.size() + count - 1) / count;  // ceil(mean)

  constexpr std::size_t kLongestChain = 48;
  constexpr int kMaximumKempePasses = 4;
  std::vector<std::uint32_t> visited(colours.size(), 0);
  std::uint32_t stamp = 0;
  std::vector<ConstraintIndex> chain;
  // Kempe chain of c over colours {a, b}, abandoned past kLongestChain constraints.
  auto kempe_chain = [&](ConstraintIndex c, Colour a, Colour b) {
    chain.clear();
    ++stamp;
    chain.push_back(c);
    visited[c] = stamp;
    for (std::size_t head = 0; head < chain.size(); ++head) {
      for (ParticleIndex p : graph.particles_of(chain[head])) {
        for (ConstraintIndex n : graph.constraints_of(p)) {
          if (visited[n] == stamp || (colours[n] != a && colours[n] != b)) continue;
          if (chain.size() == kLongestChain) return false;
          visited[n] = stamp;
          chain.push_back(n);
        }
      }
    }
    return true;
  };

  const std::span<const ConstraintIndex> schedule_order = colouring.constraints_by_colour();
  const std::size_t below = colours.size() / count;  // floor(mean)
  // Cheap single moves first, until none is left; then Kempe exchanges into colours below the
  // mean, which need a chain search per try, and single moves again after each exchange pass.
  for (int kempe_passes = 0; kempe_passes <= kMaximumKempePasses; ++kempe_passes) {
    for (bool moved_any = true; moved_any;) {
      moved_any = false;
      for (ConstraintIndex c : schedule_order) {
        const Colour a = colours[c];
        if (sizes[a] <= target) continue;
        const auto particles = graph.particles_of(c);
        Colour best = static_cast<Colour>(count);
        for (std::size_t w = 0; w < masks.words(); ++w) {
          for (std::uint64_t free = ~masks.taken_word(particles, w); free != 0; free &= free - 1) {
            const Colour k = static_cast<Colour>(w * 64 + std::countr_zero(free));
            if (k >= count) break;
            if (best == count || sizes[k] < sizes[best]) best = k;
          }
        }
        // Only into colours below the mean: every move then removes excess for good, so the
        // passes end after few sweeps instead of shuffling between two large colours.
        if (best < count && sizes[best] < below && sizes[best] + 1 < sizes[a]) {
          move(graph, masks, colours, c, best);
          --sizes[a];
          ++sizes[best];
          moved_any = true;
        }
      }
    }
    if (kempe_passes == kMaximumKempePasses) break;
    bool exchanged = false;
    for (ConstraintIndex c : schedule_order) {
      const Colour a = colours[c];
      if (sizes[a] <= target) continue;
      // Swapping a and b along c's chain moves (#a − #b) constraints from a to b.
      for (Colour b = 0; b < count; ++b) {
        if (b == a || sizes[b] >= below) continue;
        if (!kempe_chain(c, a, b)) continue;
        std::size_t in_a = 0;
        for (ConstraintIndex x : chain) in_a += colours[x] == a;
        const std::size_t in_b = chain.size() - in_a;
        if (in_a <= in_b || sizes[b] + (in_a - in_b) >= sizes[a]) continue;
        for (ConstraintIndex x : chain) masks.release(graph.particles_of(x), colours[x]);
        for (ConstraintIndex x : chain) {
          colours[x] = colours[x] == a ? b : a;
          masks.take(graph.particles_of(x), colours[x]);
        }
        sizes[a] -= in_a - in_b;
        sizes[b] += in_a - in_b;
        exchanged = true;
        break;
      }
    }
    if (!exchanged) break;
  }
  return rebuild(graph, colouring, std::move(colours));
}

}  // namespace tessera
