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
// Balancing lowers Σ size² one move at a time (so it cannot cycle), in sweeps colour by
// colour, each colour's constraints by smallest particle (on a private copy of the particle
// lists renumbered that way, so memory access stays local whatever the input order). A
// constraint c of colour a moves
//  - directly into the smallest colour free at all its particles, when that is at least 2
//    below a; or
//  - by ejection into a colour b, taking it from its neighbours coloured b there (at most one
//    per particle of c: the owner of b at that particle, kept in a particle × colour table),
//    each of which moves on to the smallest colour then free for it (a included, since c left
//    it); the first b whose size changes lower Σ size² is taken.
// Ejection is what balances colourings near the lower bound, where almost no colour is free
// for a constraint: there the large colours are often the "wrong shape" (a colour of edges is
// a near-perfect matching, a colour of tetrahedra covers nearly every particle), and the
// useful moves trade one constraint against two or three from a large colour.
// When ejections stall short of balance, a second phase makes Kempe swaps: c, in a colour at
// or above the mean, and a smaller colour b exchange colours over the small component of
// constraints coloured a or b that c reaches through shared particles, when that component
// holds more of a than of b. Single ejections get stuck where every colour is as full as its
// shape allows everywhere at once (first-fit's periodic pattern on a cloth: edge colours
// large, bending colours near-perfect covers, so no constraint fits anywhere smaller even
// after ejecting one blocker); a swap of 3 to 7 constraints between two colours (c and a
// constraint of a trade places with the one of b between them) still fits, and they take
// greedy on the cloth and the tet bar colourings at 40 colours from 1.15–1.5 to about 1.01.
// Work is bounded: the pass ends once the largest and smallest colours are within 0.5 % of
// the mean; a phase ends after a sweep that moves fewer than 0.1 % of the constraints it
// visits or 1/16 of a sweep that moves fewer than 1 % of them (a local optimum, or a forced
// one: at the lower bound sizes are often fixed by the mesh); candidates tried are capped per
// constraint and, per phase, in total; Kempe components are capped at 8 constraints.
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
  // Parts say which particles a constraint touches, not its colour: they carry over.
  if (original.has_parts())
    result.set_parts({original.part_of_constraint().begin(), original.part_of_constraint().end()},
                     original.part_count());
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

namespace {

/// Sum-of-squares bookkeeping for a tentative move: unit changes to a few colour sizes, and
/// how much they would change Σ size². Every accepted move lowers Σ size² (an integer), so
/// the balance pass cannot cycle.
class SizeChanges {
 public:
  explicit SizeChanges(std::span<const std::size_t> sizes) : sizes_(sizes), delta_(sizes.size(), 0) {}
  void add(Colour k, std::int64_t d) {
    if (delta_[k] == 0) touched_.push_back(k);
    delta_[k] += d;
  }
  /// Size of k with the pending changes.
  std::int64_t size(Colour k) const { return std::int64_t(sizes_[k]) + delta_[k]; }
  std::int64_t square_sum_change() const {
    std::int64_t change = 0;
    for (Colour k : touched_) change += delta_[k] * (2 * std::int64_t(sizes_[k]) + delta_[k]);
    return change;
  }
  void clear() {
    for (Colour k : touched_) delta_[k] = 0;
    touched_.clear();
  }

 private:
  std::span<const std::size_t> sizes_;
  std::vector<std::int64_t> delta_;
  std::vector<Colour> touched_;
};

/// The balance pass (see the file comment): direct moves and ejections, sweep after sweep.
class ColourBalancer {
  // Work bounds, per phase: sweeps; ejection (or Kempe) candidates tried per constraint and
  // per constraint of the graph in all (a try that finds nothing costs one); a sweep moving
  // fewer than 1/kStallFraction of the constraints it visits, or a 1/16 block of a sweep
  // fewer than 1/kBlockStallFraction of its constraints, ends the phase.
  static constexpr int kMaximumSweeps = 16;
  static constexpr std::size_t kEvaluationsPerTry = 64;
  static constexpr std::size_t kEvaluationsPerConstraint = 16;
  static constexpr std::size_t kStallFraction = 1000;
  static constexpr std::size_t kBlockStallFraction = 100;
  static constexpr std::size_t kBlocksPerSweep = 16;
  static constexpr std::size_t kOwnerEntriesPerIncidence = 8;
  // Largest Kempe component swapped: the useful ones hold 3, 5 or 7 constraints; bigger caps
  // cost more (components near the lower bound mostly spread over the whole mesh) for little.
  static constexpr std::size_t kKempeComponentLimit = 8;

 public:
  /// Works on a private copy of the constraints' particle lists, renumbered by smallest
  /// particle, so that neighbouring constraints sit together in memory whatever the input
  /// order (on a shuffled cloth the pass is otherwise bound by cache misses).
  ColourBalancer(const ConstraintGraph& graph, std::span<const Colour> colours, std::size_t count)
      : count_(count), masks_(graph.particle_count(), count), sizes_(count, 0), changes_(sizes_) {
    const std::size_t total = colours.size();
    {
      std::vector<std::uint32_t> start(graph.particle_count() + 2, 0);
      std::vector<ParticleIndex> first(total, 0);
      for (std::size_t c = 0; c < total; ++c) {
        const auto particles = graph.particles_of(static_cast<ConstraintIndex>(c));
        if (!particles.empty()) first[c] = *std::min_element(particles.begin(), particles.end());
        ++start[first[c] + 1];
      }
      std::partial_sum(start.begin(), start.end(), start.begin());
      original_.resize(total);
      for (std::size_t c = 0; c < total; ++c) original_[start[first[c]]++] = static_cast<ConstraintIndex>(c);
    }
    offsets_.reserve(total + 1);
    offsets_.push_back(0);
    particles_.reserve(graph.incidence_count());
    colours_.resize(total);
    for (std::size_t i = 0; i < total; ++i) {
      const auto particles = graph.particles_of(original_[i]);
      particles_.insert(particles_.end(), particles.begin(), particles.end());
      offsets_.push_back(static_cast<std::uint32_t>(particles_.size()));
      colours_[i] = colours[original_[i]];
      masks_.take(particles, colours_[i]);
      ++sizes_[colours_[i]];
    }
    // The owner table costs particles × colours entries: only when that is within a few
    // times the graph itself (colourings with thousands of colours get direct moves only).
    ejections_ = graph.particle_count() * count <= kOwnerEntriesPerIncidence * graph.incidence_count() + 1024;
    if (ejections_) {
      owner_.assign(graph.particle_count() * count, kNone);
      for (std::size_t i = 0; i < total; ++i)
        for (ParticleIndex p : particles_of(static_cast<ConstraintIndex>(i)))
          owner_[std::size_t(p) * count_ + colours_[i]] = static_cast<ConstraintIndex>(i);
    }
    std::size_t widest = 1;
    for (std::size_t i = 0; i < total; ++i) widest = std::max<std::size_t>(widest, offsets_[i + 1] - offsets_[i]);
    ejected_.resize(widest);
    destination_.resize(widest);
    receivers_.resize(masks_.words());
    all_colours_.assign(masks_.words(), 0);
    for (std::size_t k = 0; k < count_; ++k) all_colours_[k / 64] |= std::uint64_t(1) << (k % 64);
    // Good enough: largest − smallest within 0.5 % of the mean (and at least 1).
    tolerance_ = std::max<std::size_t>(1, total / count_ / 200);
    evaluations_left_ = kEvaluationsPerConstraint * total;
  }

  /// Sweeps colour by colour (as the schedule does), each colour's constraints by smallest
  /// particle.
  void run() {
    std::vector<std::uint32_t> start(count_ + 1, 0);
    for (Colour k : colours_) ++start[k + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    std::vector<ConstraintIndex> order(colours_.size());
    for (std::size_t i = 0; i < colours_.size(); ++i) order[start[colours_[i]]++] = static_cast<ConstraintIndex>(i);
    sweep(order);
  }

  /// Writes the balanced colour of every constraint (input numbering).
  void write(std::span<Colour> colours) const {
    for (std::size_t i = 0; i < colours_.size(); ++i) colours[original_[i]] = colours_[i];
  }

 private:
  std::span<const ParticleIndex> particles_of(ConstraintIndex i) const {
    return {particles_.data() + offsets_[i], particles_.data() + offsets_[i + 1]};
  }

  /// Ejections first; if they stall short of balance, Kempe swaps (see the file comment).
  /// Each phase has its own evaluation budget.
  void sweep(std::span<const ConstraintIndex> order) {
    sweeps(order, false);
    if (balanced() || !ejections_) return;
    evaluations_left_ = kEvaluationsPerConstraint * order.size();
    sweeps(order, true);
  }

  void sweeps(std::span<const ConstraintIndex> all, bool kempe) {
    refresh_extremes();
    std::vector<ConstraintIndex> large;
    for (int sweep = 0; sweep < kMaximumSweeps && !balanced() && evaluations_left_ > 0; ++sweep) {
      // Kempe swaps only start from colours at or above the mean size, so that phase visits
      // just those constraints (in the same order); otherwise the blocks of small colours,
      // where nothing is tried, would end it by the stall test below.
      std::span<const ConstraintIndex> order = all;
      if (kempe) {
        large.clear();
        for (ConstraintIndex c : all)
          if (at_or_above_mean(colours_[c])) large.push_back(c);
        order = large;
      }
      // Progress is checked per block of constraints as well as per sweep, so a pass with
      // nothing to do (e.g. sizes forced at the lower bound) stops after a small part of a
      // sweep.
      const std::size_t block = std::max<std::size_t>(order.size() / kBlocksPerSweep, 4096);
      std::size_t moved = 0, moved_in_block = 0, visited = 0;
      for (ConstraintIndex c : order) {
        ++visited;
        if (visited % 1024 == 0) {
          refresh_extremes();
          if (balanced()) return;
        }
        if (visited % block == 0) {
          if (moved_in_block * kBlockStallFraction < block) return;
          moved_in_block = 0;
        }
        const bool moved_c = try_direct_move(c) || (kempe ? try_kempe_swap(c) : try_ejection(c));
        moved += moved_c;
        moved_in_block += moved_c;
      }
      refresh_extremes();
      // A sweep that moved almost nothing is the sign of a local optimum, often a forced one
      // (at the lower bound colour sizes are fixed by the mesh): stop rather than sweep again.
      if (moved * kStallFraction < order.size()) return;
    }
  }

  void refresh_extremes() {
    const auto [lo, hi] = std::minmax_element(sizes_.begin(), sizes_.end());
    smallest_ = *lo;
    largest_ = *hi;
  }
  bool balanced() const { return largest_ - smallest_ <= tolerance_; }
  bool at_or_above_mean(Colour k) const { return sizes_[k] * count_ >= colours_.size(); }

  /// Lower bound of the change of Σ size² when a constraint leaves a colour of size_a for one
  /// of size_b, ejecting `ejected` constraints from it to colours no smaller than the smallest.
  std::int64_t best_case_change(std::size_t size_a, std::size_t size_b, std::int64_t ejected) const {
    const std::int64_t a = std::int64_t(size_a), b = std::int64_t(size_b), low = std::int64_t(smallest_);
    return (1 - 2 * a) + (1 - ejected) * (2 * b + 1 - ejected) + ejected * (2 * low + 1);
  }

  /// The smallest colour (sizes with the pending changes) among `allowed` free at all
  /// `particles`, other than `excluded`; count_ if none.
  Colour smallest_free(std::span<const ParticleIndex> particles, Colour excluded,
                       std::span<const std::uint64_t> allowed) const {
    Colour best = static_cast<Colour>(count_);
    std::int64_t best_size = 0;
    for (std::size_t w = 0; w < masks_.words(); ++w) {
      std::uint64_t free = allowed[w] & ~masks_.taken_word(particles, w);
      if (excluded / 64 == w) free &= ~(std::uint64_t(1) << (excluded % 64));
      for (; free != 0; free &= free - 1) {
        const Colour k = static_cast<Colour>(w * 64 + std::countr_zero(free));
        const std::int64_t size = changes_.size(k);
        if (best == count_ || size < best_size) {
          best = k;
          best_size = size;
        }
      }
    }
    return best;
  }
  /// Sets receivers_ to the colours of at most `largest` constraints.
  void choose_receivers(std::size_t largest) {
    std::fill(receivers_.begin(), receivers_.end(), 0);
    for (std::size_t k = 0; k < count_; ++k)
      if (sizes_[k] <= largest) receivers_[k / 64] |= std::uint64_t(1) << (k % 64);
  }

  void leave(ConstraintIndex c) {
    const auto particles = particles_of(c);
    masks_.release(particles, colours_[c]);
    if (ejections_)
      for (ParticleIndex p : particles) owner_[std::size_t(p) * count_ + colours_[c]] = kNone;
    --sizes_[colours_[c]];
  }
  void enter(ConstraintIndex c, Colour k) {
    const auto particles = particles_of(c);
    masks_.take(particles, k);
    if (ejections_)
      for (ParticleIndex p : particles) owner_[std::size_t(p) * count_ + k] = c;
    colours_[c] = k;
    ++sizes_[k];
  }

  /// c alone into the smallest colour free for it, when that narrows the gap.
  bool try_direct_move(ConstraintIndex c) {
    const Colour a = colours_[c];
    if (sizes_[a] <= smallest_ + 1) return false;
    changes_.clear();
    const Colour to = smallest_free(particles_of(c), a, all_colours_);
    if (to >= count_ || sizes_[to] + 1 >= sizes_[a]) return false;
    leave(c);
    enter(c, to);
    return true;
  }

  /// c into a colour b, its neighbours coloured b (one per shared particle at most) each
  /// into the smallest colour then free for it; the first b that lowers Σ size² is taken.
  bool try_ejection(ConstraintIndex c) {
    const Colour a = colours_[c];
    const auto particles = particles_of(c);
    const std::int64_t arity = std::int64_t(particles.size());
    // Nothing can pay off unless c's colour is above the smallest (single ejections) or c can
    // eject several constraints from a large colour.
    if (best_case_change(sizes_[a], largest_, 1) >= 0 && best_case_change(sizes_[a], largest_, arity) >= 0)
      return false;
    if (!ejections_ || evaluations_left_ == 0) return false;
    // Ejected constraints only go to colours at least 2 below the larger of a and b (so
    // receivers_ is chosen once for the largest b, and checked per b).
    choose_receivers(std::max(sizes_[a], largest_) - 2);
    masks_.release(particles, a);  // c's own colour, as if c had left it
    bool moved = false;
    std::size_t evaluations = 0;
    for (std::size_t w = 0; w < masks_.words() && !moved && evaluations < kEvaluationsPerTry; ++w) {
      for (std::uint64_t blocked = masks_.taken_word(particles, w); blocked != 0 && !moved;
           blocked &= blocked - 1) {
        const Colour b = static_cast<Colour>(w * 64 + std::countr_zero(blocked));
        if (b >= count_) break;
        if (best_case_change(sizes_[a], sizes_[b], arity) >= 0 &&
            best_case_change(sizes_[a], sizes_[b], 1) >= 0)
          continue;
        std::size_t ejected = 0;
        for (ParticleIndex p : particles) {
          const ConstraintIndex e = owner_[std::size_t(p) * count_ + b];
          if (e != kNone && std::find(ejected_.begin(), ejected_.begin() + ejected, e) == ejected_.begin() + ejected)
            ejected_[ejected++] = e;
        }
        if (best_case_change(sizes_[a], sizes_[b], std::int64_t(ejected)) >= 0) continue;
        ++evaluations;
        changes_.clear();
        changes_.add(a, -1);
        changes_.add(b, 1 - std::int64_t(ejected));
        bool placed = true;
        for (std::size_t i = 0; i < ejected && placed; ++i) {
          destination_[i] = smallest_free(particles_of(ejected_[i]), b, receivers_);
          placed = destination_[i] < count_;
          if (placed) changes_.add(destination_[i], 1);
        }
        if (!placed || changes_.square_sum_change() >= 0) continue;
        masks_.take(particles, a);
        leave(c);
        for (std::size_t i = 0; i < ejected; ++i) leave(ejected_[i]);
        enter(c, b);
        for (std::size_t i = 0; i < ejected; ++i) enter(ejected_[i], destination_[i]);
        moved = true;
      }
    }
    if (!moved) masks_.take(particles, a);
    evaluations_left_ -= std::min(evaluations_left_, std::max<std::size_t>(evaluations, 1));
    return moved;
  }

  /// A Kempe swap: the constraints coloured a or b connected to c (through shared particles,
  /// alternating colours) exchange colours, which keeps the colouring valid. Worth it when
  /// that component holds δ more constraints of a than of b, with 1 ≤ δ < size(a) − size(b)
  /// (then Σ size² drops by 2δ(size(a) − size(b) − δ)). Candidates b are the colours at least
  /// 2 smaller than a, smallest first, in which c meets exactly one constraint (nearly every
  /// swap found has that shape: c and another constraint of a trade places with the one
  /// constraint of b between them, or a few more such links); components are explored
  /// breadth-first and dropped once they exceed kKempeComponentLimit or could no longer
  /// end with a surplus of a within it.
  bool try_kempe_swap(ConstraintIndex c) {
    const Colour a = colours_[c];
    if (!at_or_above_mean(a) || sizes_[a] < smallest_ + 2 || evaluations_left_ == 0) return false;
    const auto particles = particles_of(c);
    // Candidates first (c's own owner rows, in cache), so only the few kept are sorted.
    targets_.clear();
    for (std::size_t w = 0; w < masks_.words(); ++w)
      for (std::uint64_t blocked = masks_.taken_word(particles, w); blocked != 0; blocked &= blocked - 1) {
        const Colour b = static_cast<Colour>(w * 64 + std::countr_zero(blocked));
        if (b >= count_) break;
        if (b == a || sizes_[b] + 2 > sizes_[a]) continue;
        ConstraintIndex only = kNone;
        bool single = true;
        for (ParticleIndex p : particles) {
          const ConstraintIndex n = owner_[std::size_t(p) * count_ + b];
          if (n == kNone || n == only) continue;
          single = only == kNone;
          only = n;
          if (!single) break;
        }
        if (single) targets_.push_back(b);
      }
    std::sort(targets_.begin(), targets_.end(),
              [&](Colour x, Colour y) { return sizes_[x] < sizes_[y] || (sizes_[x] == sizes_[y] && x < y); });
    std::size_t evaluations = 0;
    bool moved = false;
    for (Colour b : targets_) {
      if (evaluations >= kEvaluationsPerTry) break;
      ++evaluations;
      component_.clear();
      component_.push_back(c);
      std::int64_t surplus = 1;  // constraints of a minus constraints of b in the component
      bool bounded = true;
      for (std::size_t i = 0; i < component_.size() && bounded; ++i) {
        const ConstraintIndex x = component_[i];
        const Colour other = colours_[x] == a ? b : a;
        // The walk is bound by cache misses (owner rows and particle lists of constraints
        // around c, tens of MB on large meshes): start the loads of a member's rows together,
        // and a new member's list as soon as it is found.
        for (ParticleIndex p : particles_of(x)) __builtin_prefetch(&owner_[std::size_t(p) * count_ + other]);
        for (ParticleIndex p : particles_of(x)) {
          const ConstraintIndex y = owner_[std::size_t(p) * count_ + other];
          if (y == kNone || std::find(component_.begin(), component_.end(), y) != component_.end()) continue;
          component_.push_back(y);
          __builtin_prefetch(&offsets_[y]);
          __builtin_prefetch(&colours_[y]);
          surplus += other == a ? 1 : -1;
          // Too big, or too many of b to end with a surplus even if all the rest were of a.
          if (component_.size() > kKempeComponentLimit ||
              surplus + std::int64_t(kKempeComponentLimit - component_.size()) < 1) {
            bounded = false;
            break;
          }
        }
      }
      if (!bounded || surplus < 1 || surplus >= std::int64_t(sizes_[a]) - std::int64_t(sizes_[b])) continue;
      for (ConstraintIndex x : component_) leave(x);
      for (ConstraintIndex x : component_) enter(x, colours_[x] == a ? b : a);
      moved = true;
      break;
    }
    evaluations_left_ -= std::min(evaluations_left_, std::max<std::size_t>(evaluations, 1));
    return moved;
  }

  std::size_t count_;
  std::vector<ConstraintIndex> original_;  // input id of each constraint of the private copy
  std::vector<std::uint32_t> offsets_;
  std::vector<ParticleIndex> particles_;
  std::vector<Colour> colours_;
  ParticleColourMasks masks_;
  std::vector<std::size_t> sizes_;
  std::vector<ConstraintIndex> owner_;  // owner_[p * count_ + k]: the constraint coloured k at p
  SizeChanges changes_;
  std::vector<ConstraintIndex> ejected_;
  std::vector<Colour> destination_;
  std::vector<std::uint64_t> receivers_;  // colours small enough to receive, one bit each
  std::vector<std::uint64_t> all_colours_;
  std::vector<Colour> targets_;              // candidate colours of a Kempe swap
  std::vector<ConstraintIndex> component_;   // the Kempe component being explored
  std::size_t tolerance_ = 1;
  std::size_t evaluations_left_ = 0;
  bool ejections_ = false;
  std::size_t smallest_ = 0, largest_ = 0;
};

}  // namespace

Colouring balance_colours(const ConstraintGraph& graph, const Colouring& colouring) {
  const std::size_t count = colouring.colour_count();
  std::vector<Colour> colours(colouring.colours().begin(), colouring.colours().end());
  if (count >= 2) {
    ColourBalancer balancer(graph, colours, count);
    balancer.run();
    balancer.write(colours);
  }
  return rebuild(graph, colouring, std::move(colours));
}

}  // namespace tessera
