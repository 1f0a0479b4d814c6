// The parallel randomized strategy: Jones–Plassmann over TBB.
//
// Every constraint gets a priority key (a hash of (seed, id) in the high 32 bits, the id in
// the low 32, so keys are distinct). In each round, an uncoloured constraint that outranks
// every uncoloured constraint at each of its movable particles is selected; selected
// constraints share no particle, so they are coloured at once, in parallel, each first-fit
// against the colours already at its particles. A constraint is therefore coloured after all
// its higher-ranked neighbours, with the colour sequential first-fit in decreasing key order
// would give it: the result is a pure function of (graph, seed), whatever the thread count or
// schedule.
//
// Data layout: each particle's constraint list is copied and sorted by decreasing key, with a
// head index at its first uncoloured entry; "am I the top of particle p" is then one load.
// Rounds are driven by a frontier, not by rescanning every uncoloured constraint (JP needs
// about as many rounds as the conflict degree, so rescans would cost O(constraints × degree)):
// colouring a frontier constraint advances the heads of its particles by one, and the new tops
// that are now on top everywhere form the next frontier. Total work is O(incidences × arity).
// Only the frontier constraint at p writes head[p] and p's colour set in phase 1, and phase 2
// only reads heads, so the phases need no atomics beyond a de-duplication flag.
#include <algorithm>
#include <atomic>
#include <numeric>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/core/huge_pages.hpp>

#include "colour_masks.hpp"

namespace tessera {
namespace {

constexpr Colour kUncoloured = ~Colour(0);

/// Concatenates and clears the per-thread lists, sorted by id: sweeping the frontier in id
/// order walks the graph arrays monotonically instead of at random (about twice as fast on a
/// 6 M-constraint cloth), and makes the frontier's order independent of the thread count.
std::vector<ConstraintIndex> gather(tbb::enumerable_thread_specific<std::vector<ConstraintIndex>>& lists) {
  std::vector<ConstraintIndex> all;
  for (std::vector<ConstraintIndex>& list : lists) {
    all.insert(all.end(), list.begin(), list.end());
    list.clear();
  }
  tbb::parallel_sort(all.begin(), all.end());
  return all;
}

class JonesPlassmannStrategy final : public ColouringStrategy {
 public:
  std::string_view name() const override { return "random"; }
  std::string_view description() const override {
    return "parallel Jones-Plassmann with seeded random priorities (same result for any thread count)";
  }

  Colouring colour(const ConstraintGraph& graph, const ColouringOptions& options) const override {
    const std::size_t count = graph.constraint_count();
    const std::size_t particle_count = graph.particle_count();
    std::vector<std::uint64_t> key = make_large_vector<std::uint64_t>(count);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const auto& range) {
      for (std::size_t c = range.begin(); c != range.end(); ++c)
        key[c] = (detail::mix_hash(options.seed, c) & 0xFFFFFFFF00000000ull) | c;
    });

    // Per-particle lists by decreasing key, copied, sorted and given their heads in one
    // parallel pass (a serial copy of the incidences first would not scale).
    const auto offsets = graph.particle_offsets();
    const auto by_particle = graph.particle_constraints();
    std::vector<ConstraintIndex> ranked = make_large_vector<ConstraintIndex>(graph.incidence_count());
    std::vector<std::uint32_t> head = make_large_vector<std::uint32_t>(particle_count);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, particle_count, 512), [&](const auto& range) {
      for (std::size_t p = range.begin(); p != range.end(); ++p) {
        const auto first = ranked.begin() + offsets[p], last = ranked.begin() + offsets[p + 1];
        std::copy(by_particle.begin() + offsets[p], by_particle.begin() + offsets[p + 1], first);
        std::sort(first, last, [&](ConstraintIndex a, ConstraintIndex b) { return key[a] > key[b]; });
        head[p] = offsets[p];
      }
    });

    std::vector<Colour> colours = make_large_vector<Colour>(count, kUncoloured);
    std::vector<std::uint8_t> queued = make_large_vector<std::uint8_t>(count, 0);
    detail::ParticleColourMasks masks(particle_count, graph.colour_lower_bound());
    auto is_ready = [&](ConstraintIndex c) {
      for (ParticleIndex p : graph.particles_of(c))
        if (ranked[head[p]] != c) return false;
      return true;
    };

    // The first frontier: constraints on top at every particle (or touching none).
    tbb::enumerable_thread_specific<std::vector<ConstraintIndex>> found;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 4096), [&](const auto& range) {
      std::vector<ConstraintIndex>& local = found.local();
      for (std::size_t c = range.begin(); c != range.end(); ++c)
        if (is_ready(static_cast<ConstraintIndex>(c))) {
          queued[c] = 1;
          local.push_back(static_cast<ConstraintIndex>(c));
        }
    });
    std::vector<ConstraintIndex> frontier = gather(found);

    while (!frontier.empty()) {
      // Phase 1: colour the frontier first-fit and move the heads of its particles past it.
      // A colour beyond the sets' capacity is left for after they grow (the choice does not
      // depend on the capacity).
      for (bool retry = true; retry;) {
        std::atomic<bool> out_of_capacity = false;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, frontier.size(), 256), [&](const auto& range) {
          for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const ConstraintIndex c = frontier[i];
            if (colours[c] != kUncoloured) continue;
            const auto particles = graph.particles_of(c);
            const Colour k = masks.first_free(particles);
            if (k >= masks.capacity()) {
              out_of_capacity.store(true, std::memory_order_relaxed);
              continue;
            }
            masks.take(particles, k);
            colours[c] = k;
            for (ParticleIndex p : particles) ++head[p];
          }
        });
        retry = out_of_capacity.load();
        if (retry) masks.reserve(masks.capacity() + 64);
      }
      // Phase 2 (heads are only read): the new top of each of those particles joins the next
      // frontier if it is now on top everywhere. Several particles may find the same
      // constraint; the atomic flag keeps one copy. The frontier is a set, and the order its
      // members are listed in does not affect any colour.
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, frontier.size(), 256), [&](const auto& range) {
        std::vector<ConstraintIndex>& local = found.local();
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          for (ParticleIndex p : graph.particles_of(frontier[i])) {
            if (head[p] == offsets[p + 1]) continue;
            const ConstraintIndex next = ranked[head[p]];
            // Test before test-and-set: a constraint already queued (found through another of
            // its particles) costs a plain load, not a locked exchange on a shared line.
            std::atomic_ref<std::uint8_t> flag(queued[next]);
            if (flag.load(std::memory_order_relaxed) != 0 || !is_ready(next)) continue;
            if (flag.exchange(1, std::memory_order_relaxed) == 0) local.push_back(next);
          }
        }
      });
      frontier = gather(found);
    }
    return Colouring::from_colours(std::move(colours));
  }
};

}  // namespace

std::shared_ptr<const ColouringStrategy> make_random_strategy() {
  return std::make_shared<JonesPlassmannStrategy>();
}

}  // namespace tessera
