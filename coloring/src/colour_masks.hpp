// Internal: one bit set of colours per particle, the workhorse of every strategy.
//
// Colours at a particle are "taken" when a constraint through that particle has that colour.
// The colours free for a constraint are the complement of the OR of its particles' sets, so
// first-fit costs O(arity × words) instead of a walk over all neighbouring constraints. In a
// valid colouring a colour appears at most once per particle, so clearing a bit is exact and
// the same structure supports moving constraints between colours (balance, reduction).
//
// Layout: particle-major, `words` 64-bit words per particle, contiguous. The word count grows
// on demand (a rare copy), and the one-word case, by far the common one, has its own branch.
#pragma once

#include <bit>
#include <cstdint>
#include <span>
#include <vector>

#include <tessera/coloring/colouring.hpp>
#include <tessera/core/huge_pages.hpp>

#include "large_buffer.hpp"

namespace tessera::detail {

class ParticleColourMasks {
 public:
  ParticleColourMasks(std::size_t particle_count, std::size_t colour_capacity)
      : particle_count_(particle_count), words_(words_for(colour_capacity)),
        bits_(make_large_vector<std::uint64_t>(particle_count * words_, 0)) {}

  std::size_t capacity() const { return words_ * 64; }

  /// Makes room for colours [0, colour_count).
  void reserve(std::size_t colour_count) {
    const std::size_t words = words_for(colour_count);
    if (words <= words_) return;
    std::vector<std::uint64_t> wider = make_large_vector<std::uint64_t>(particle_count_ * words, 0);
    for (std::size_t p = 0; p < particle_count_; ++p)
      for (std::size_t w = 0; w < words_; ++w) wider[p * words + w] = bits_[p * words_ + w];
    bits_ = std::move(wider);
    words_ = words;
  }

  /// The smallest colour taken at none of `particles` (capacity() if all are taken there).
  Colour first_free(std::span<const ParticleIndex> particles) const {
    if (words_ == 1) {
      std::uint64_t taken = 0;
      for (ParticleIndex p : particles) taken |= bits_[p];
      return static_cast<Colour>(std::countr_one(taken));
    }
    for (std::size_t w = 0; w < words_; ++w) {
      std::uint64_t taken = 0;
      for (ParticleIndex p : particles) taken |= bits_[p * words_ + w];
      if (~taken != 0) return static_cast<Colour>(w * 64 + std::countr_one(taken));
    }
    return static_cast<Colour>(capacity());
  }

  /// First-fit that grows the sets when every colour in capacity is taken.
  Colour first_free_growing(std::span<const ParticleIndex> particles) {
    Colour k = first_free(particles);
    if (k >= capacity()) reserve(std::size_t(k) + 1);
    return k;
  }

  /// Word w of the OR of the particles' sets (colours 64w .. 64w+63 taken somewhere).
  std::uint64_t taken_word(std::span<const ParticleIndex> particles, std::size_t w) const {
    std::uint64_t taken = 0;
    for (ParticleIndex p : particles) taken |= bits_[p * words_ + w];
    return taken;
  }
  std::size_t words() const { return words_; }
  /// The raw sets (particle p's words at p * words()), for loops that specialise on one word.
  std::uint64_t* data() { return bits_.data(); }

  bool is_free(std::span<const ParticleIndex> particles, Colour k) const {
    const std::uint64_t bit = std::uint64_t(1) << (k % 64);
    for (ParticleIndex p : particles)
      if (bits_[p * words_ + k / 64] & bit) return false;
    return true;
  }
  void take(std::span<const ParticleIndex> particles, Colour k) {
    const std::uint64_t bit = std::uint64_t(1) << (k % 64);
    for (ParticleIndex p : particles) bits_[p * words_ + k / 64] |= bit;
  }
  void release(std::span<const ParticleIndex> particles, Colour k) {
    const std::uint64_t bit = std::uint64_t(1) << (k % 64);
    for (ParticleIndex p : particles) bits_[p * words_ + k / 64] &= ~bit;
  }
  /// Hints the cache that the particles' sets are about to be read.
  void prefetch(std::span<const ParticleIndex> particles) const {
    for (ParticleIndex p : particles) __builtin_prefetch(&bits_[p * words_]);
  }

  /// Sets of a whole valid colouring.
  static ParticleColourMasks of(const ConstraintGraph& graph, std::span<const Colour> colours,
                                std::size_t colour_count) {
    ParticleColourMasks masks(graph.particle_count(), colour_count);
    for (std::size_t c = 0; c < colours.size(); ++c)
      masks.take(graph.particles_of(static_cast<ConstraintIndex>(c)), colours[c]);
    return masks;
  }

 private:
  static std::size_t words_for(std::size_t colours) { return colours <= 64 ? 1 : (colours + 63) / 64; }

  std::size_t particle_count_;
  std::size_t words_;
  std::vector<std::uint64_t> bits_;
};

/// First-fit colouring of the constraints in `order` (every constraint exactly once),
/// continuing from the sets in `masks`. Writes colours[c]; returns the number of colours used
/// (the largest colour + 1, or 0).
std::size_t first_fit_in_order(const ConstraintGraph& graph, std::span<const ConstraintIndex> order,
                               ParticleColourMasks& masks, std::span<Colour> colours);

/// First-fit in constraint id order.
std::size_t first_fit_in_id_order(const ConstraintGraph& graph, ParticleColourMasks& masks,
                                  std::span<Colour> colours);

/// Conflict weight Σ_p (deg(p) − 1) of every constraint over its movable particles.
std::vector<std::uint32_t> conflict_weights(const ConstraintGraph& graph);
/// Constraints by decreasing conflict weight, ties by increasing id.
std::vector<ConstraintIndex> largest_first_order(const ConstraintGraph& graph);
/// Matula–Beck smallest-last colouring order (reverse of the min-weight removal order).
std::vector<ConstraintIndex> smallest_last_order(const ConstraintGraph& graph);

/// Stencil order: constraints grouped by the shape of their particle stencil (the offsets of
/// their sorted movable particle ids from the smallest), largest shape classes first, each
/// class by its smallest particle. Independent of the input order of the constraints. See
/// sequential_strategies.cpp for why this colours regular meshes at their lower bound.
LargeBuffer<ConstraintIndex> stencil_order(const ConstraintGraph& graph);

/// Renumbers colours so they are dense (unused colours removed, order kept); returns the count.
std::size_t compact_colours(std::span<Colour> colours);

/// A 64-bit mix of (seed, value): splitmix64 finaliser, the per-constraint random priority of
/// the parallel strategies (a pure function, so no shared generator and no thread dependence).
inline std::uint64_t mix_hash(std::uint64_t seed, std::uint64_t value) {
  std::uint64_t z = seed * 0x9E3779B97F4A7C15ull + value + 0x632BE59BD9B4E019ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

}  // namespace tessera::detail
