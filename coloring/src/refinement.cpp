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
// Balancing moves constraints out of colours above the mean: alone, into the smallest colour
// free for it; by ejection, taking a colour from its single blocker there, which moves on to a
// small colour free for it; and, when neither is left (typical when the count equals the lower
// bound), by swapping two colours along a short Kempe chain: the connected set of constraints
// coloured a or b reachable from it, whose a/b swap keeps the colouring valid. Sweeps, chain
// lengths and the total neighbourhood scanning are capped, so the pass is a few graph sweeps.
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

/// "No constraint" (no blocker found).
constexpr ConstraintIndex kNone = ~ConstraintIndex(0);

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
  constexpr ConstraintIndex kSeveral = kNone - 1;
  std::vector<ConstraintIndex> blockers;
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
    // One scan of c's neighbourhood finds, per colour, its single blocker (or several).
    blockers.assign(count, kNone);
    for (ParticleIndex p : particles)
      for (ConstraintIndex n : graph.constraints_of(p)) {
        if (n == c) continue;
        ConstraintIndex& b = blockers[colours[n]];
        b = (b == kNone || b == n) ? n : kSeveral;
      }
    bool moved = false;
    for (Colour k = 0; k < count && !moved; ++k) {
      const ConstraintIndex blocker = blockers[k];
      if (k == smallest || blocker == kNone || blocker == kSeveral) continue;
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
  // Rounds stop early once kStallRounds in a row (one of each class order, and one more) have
  // not lowered the count: on large meshes a round costs a full first-fit pass, and gains after
  // such a plateau are rare.
  constexpr std::size_t kStallRounds = 4;
  std::size_t best = count, stalled = 0;
  for (std::size_t round = 0; round < options.reduction_rounds && count > floor && stalled < kStallRounds;
       ++round) {
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
    if (count < best) {
      best = count;
      stalled = 0;
    } else {
      ++stalled;
    }
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

  // Kempe exchanges are bounded three ways, so the pass costs a few sweeps of the graph at
  // most: chains longer than kLongestChain are abandoned, only the kReceivers smallest colours
  // below the mean are tried as partners, and all chain searches and blocker scans together
  // visit at most kWorkPerIncidence × incidences (particle-list entries). A chain can only pay
  // off when the constraint it starts from has a single neighbour in the partner colour (it
  // starts one a ahead and ends ahead only if few b's join), so that is checked first with one
  // scan of the constraint's neighbourhood, which is far cheaper than the chain search.
  constexpr std::size_t kLongestChain = 48;
  constexpr std::size_t kReceivers = 3;
  constexpr std::size_t kWorkPerIncidence = 6;
  constexpr int kMaximumKempePasses = 8;
  constexpr int kMaximumSweeps = 32;
  int sweeps = 0;
  std::size_t work_left = kWorkPerIncidence * std::max<std::size_t>(graph.incidence_count(), 1);
  std::vector<std::uint32_t> visited(colours.size(), 0);
  std::uint32_t stamp = 0;
  std::vector<ConstraintIndex> chain;
  // Kempe chain of c over colours {a, b}; false when abandoned (too long, or out of work).
  auto kempe_chain = [&](ConstraintIndex c, Colour a, Colour b) {
    chain.clear();
    ++stamp;
    chain.push_back(c);
    visited[c] = stamp;
    for (std::size_t head = 0; head < chain.size(); ++head) {
      for (ParticleIndex p : graph.particles_of(chain[head])) {
        const auto around = graph.constraints_of(p);
        if (around.size() > work_left) return false;
        work_left -= around.size();
        for (ConstraintIndex n : around) {
          if (visited[n] == stamp || (colours[n] != a && colours[n] != b)) continue;
          if (chain.size() == kLongestChain) return false;
          visited[n] = stamp;
          chain.push_back(n);
        }
      }
    }
    return true;
  };
  // Whether c has exactly one neighbour coloured b (charged to the work budget).
  auto single_neighbour_in = [&](ConstraintIndex c, Colour b) {
    ConstraintIndex found = kNone;
    for (ParticleIndex p : graph.particles_of(c)) {
      const auto around = graph.constraints_of(p);
      if (around.size() > work_left) return false;
      work_left -= around.size();
      for (ConstraintIndex n : around) {
        if (n == c || colours[n] != b) continue;
        if (found != kNone && found != n) return false;
        found = n;
      }
    }
    return found != kNone;
  };

  const std::span<const ConstraintIndex> schedule_order = colouring.constraints_by_colour();
  const std::size_t below = colours.size() / count;  // floor(mean)
  // The smallest colour free at all `particles`, other than the two excluded (count if none).
  auto smallest_free = [&](std::span<const ParticleIndex> particles, Colour excluded0, Colour excluded1) {
    Colour best = static_cast<Colour>(count);
    for (std::size_t w = 0; w < masks.words(); ++w) {
      for (std::uint64_t free = ~masks.taken_word(particles, w); free != 0; free &= free - 1) {
        const Colour k = static_cast<Colour>(w * 64 + std::countr_zero(free));
        if (k >= count) break;
        if (k == excluded0 || k == excluded1) continue;
        if (best == count || sizes[k] < sizes[best]) best = k;
      }
    }
    return best;
  };
  constexpr ConstraintIndex kSeveral = kNone - 1;
  std::vector<ConstraintIndex> blockers;
  std::vector<Colour> receivers;
  auto choose_receivers = [&] {
    receivers.clear();
    for (Colour k = 0; k < count; ++k)
      if (sizes[k] < below) receivers.push_back(k);
    std::stable_sort(receivers.begin(), receivers.end(),
                     [&](Colour x, Colour y) { return sizes[x] < sizes[y]; });
    if (receivers.size() > kReceivers) receivers.resize(kReceivers);
  };
  // Cheap single moves first, until none is left; then Kempe exchanges into the smallest
  // colours, and single moves again after each exchange pass.
  for (int kempe_passes = 0; kempe_passes <= kMaximumKempePasses; ++kempe_passes) {
    // Sweeps of direct moves to a fixed point; then sweeps that also try ejections, while the
    // work budget lasts.
    for (bool ejections = false;; ejections = true) {
      bool moved_any = false;
      for (bool moved = true; moved && sweeps < kMaximumSweeps; ++sweeps) {
        moved = false;
        for (ConstraintIndex c : schedule_order) {
          const Colour a = colours[c];
          if (sizes[a] <= target) continue;
          const auto particles = graph.particles_of(c);
          // Into the smallest colour free for c, when that narrows the gap between the two:
          // each move lowers the sum of squared sizes, and the sweeps are capped in number
          // (kMaximumSweeps over the whole pass), since near-equal colours can trade single
          // constraints for many sweeps while gaining little.
          const Colour best = smallest_free(particles, a, a);
          if (best < count && sizes[best] + 1 < sizes[a]) {
            move(graph, masks, colours, c, best);
            --sizes[a];
            ++sizes[best];
            moved = true;
            continue;
          }
          if (!ejections || work_left == 0) continue;
          // Ejection: c takes colour b from its single blocker n there, and n moves to a
          // small colour d free for it; sizes: a − 1, d + 1, b unchanged.
          blockers.assign(count, kNone);
          for (ParticleIndex p : particles) {
            const auto around = graph.constraints_of(p);
            work_left -= std::min(work_left, around.size());
            for (ConstraintIndex n : around) {
              if (n == c) continue;
              ConstraintIndex& blocker = blockers[colours[n]];
              blocker = (blocker == kNone || blocker == n) ? n : kSeveral;
            }
          }
          for (Colour b = 0; b < count; ++b) {
            const ConstraintIndex n = blockers[b];
            if (b == a || n == kNone || n == kSeveral) continue;
            const Colour d = smallest_free(graph.particles_of(n), a, b);
            if (d >= count || sizes[d] + 1 >= sizes[a]) continue;
            move(graph, masks, colours, n, d);
            move(graph, masks, colours, c, b);
            --sizes[a];
            ++sizes[d];
            moved = true;
            break;
          }
        }
        moved_any = moved_any || moved;
      }
      if (ejections || work_left == 0) break;
    }
    if (kempe_passes == kMaximumKempePasses || work_left == 0) break;
    choose_receivers();
    if (receivers.empty()) break;
    bool exchanged = false;
    for (ConstraintIndex c : schedule_order) {
      if (work_left == 0) break;
      const Colour a = colours[c];
      if (sizes[a] <= target) continue;
      // Swapping a and b along c's chain moves (#a − #b) constraints from a to b.
      for (Colour b : receivers) {
        if (sizes[b] >= below || b == a) continue;
        if (!single_neighbour_in(c, b)) continue;
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
        choose_receivers();
        break;
      }
      if (receivers.empty()) break;
    }
    if (!exchanged) break;
  }
  return rebuild(graph, colouring, std::move(colours));
}

}  // namespace tessera
