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
// head index at its first uncoloured entry; "am I the top of particle p" is then one load, and
// heads only move forward (amortised O(incidences) over all rounds). Only the constraint
// coloured at p in a round advances p's head, and no other selected constraint touches p, so
// phases need no atomics. The list of uncoloured constraints is compacted each round in fixed
// blocks (independent of the thread count) so late rounds stay cheap.
#include <algorithm>
#include <atomic>
#include <numeric>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <tessera/coloring/colouring_strategy.hpp>

#include "colour_masks.hpp"

namespace tessera {
namespace {

constexpr Colour kUncoloured = ~Colour(0);
constexpr std::size_t kCompactionBlock = 1 << 14;

/// Keeps the still-uncoloured entries of `list`, in order, in parallel.
std::vector<ConstraintIndex> compact_uncoloured(const std::vector<ConstraintIndex>& list,
                                                const std::vector<Colour>& colours) {
  const std::size_t blocks = (list.size() + kCompactionBlock - 1) / kCompactionBlock;
  std::vector<std::size_t> kept(blocks + 1, 0);
  tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
    const std::size_t end = std::min(list.size(), (b + 1) * kCompactionBlock);
    std::size_t n = 0;
    for (std::size_t i = b * kCompactionBlock; i < end; ++i) n += colours[list[i]] == kUncoloured;
    kept[b + 1] = n;
  });
  std::partial_sum(kept.begin(), kept.end(), kept.begin());
  std::vector<ConstraintIndex> result(kept.back());
  tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
    const std::size_t end = std::min(list.size(), (b + 1) * kCompactionBlock);
    std::size_t out = kept[b];
    for (std::size_t i = b * kCompactionBlock; i < end; ++i)
      if (colours[list[i]] == kUncoloured) result[out++] = list[i];
  });
  return result;
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
    std::vector<std::uint64_t> key(count);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const auto& range) {
      for (std::size_t c = range.begin(); c != range.end(); ++c)
        key[c] = (detail::mix_hash(options.seed, c) & 0xFFFFFFFF00000000ull) | c;
    });

    // Per-particle lists by decreasing key.
    const auto offsets = graph.particle_offsets();
    std::vector<ConstraintIndex> ranked(graph.particle_constraints().begin(),
                                        graph.particle_constraints().end());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, particle_count, 512), [&](const auto& range) {
      for (std::size_t p = range.begin(); p != range.end(); ++p)
        std::sort(ranked.begin() + offsets[p], ranked.begin() + offsets[p + 1],
                  [&](ConstraintIndex a, ConstraintIndex b) { return key[a] > key[b]; });
    });
    std::vector<std::uint32_t> head(offsets.begin(), offsets.end() - (particle_count > 0 ? 1 : 0));

    std::vector<Colour> colours(count, kUncoloured);
    std::vector<std::uint8_t> selected(count, 0);
    detail::ParticleColourMasks masks(particle_count, graph.colour_lower_bound());
    std::vector<ConstraintIndex> remaining(count);
    std::iota(remaining.begin(), remaining.end(), ConstraintIndex(0));

    while (!remaining.empty()) {
      // Phase 1: select the local maxima (read-only).
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, remaining.size(), 1024), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          const ConstraintIndex c = remaining[i];
          bool top = true;
          for (ParticleIndex p : graph.particles_of(c)) top = top && ranked[head[p]] == c;
          selected[c] = top ? 1 : 0;
        }
      });
      // Phase 2: colour them first-fit. A colour beyond the sets' capacity is left for after
      // the sets grow (the choice does not depend on the capacity).
      for (bool retry = true; retry;) {
        std::atomic<bool> out_of_capacity = false;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, remaining.size(), 1024), [&](const auto& range) {
          for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const ConstraintIndex c = remaining[i];
            if (!selected[c] || colours[c] != kUncoloured) continue;
            const auto particles = graph.particles_of(c);
            const Colour k = masks.first_free(particles);
            if (k >= masks.capacity()) {
              out_of_capacity.store(true, std::memory_order_relaxed);
              continue;
            }
            masks.take(particles, k);
            colours[c] = k;
            for (ParticleIndex p : particles)
              while (head[p] < offsets[p + 1] && colours[ranked[head[p]]] != kUncoloured) ++head[p];
          }
        });
        retry = out_of_capacity.load();
        if (retry) masks.reserve(masks.capacity() + 64);
      }
      remaining = compact_uncoloured(remaining, colours);
    }
    return Colouring::from_colours(std::move(colours));
  }
};

}  // namespace

std::shared_ptr<const ColouringStrategy> make_random_strategy() {
  return std::make_shared<JonesPlassmannStrategy>();
}

}  // namespace tessera
