// Colouring: grouping constraints by colour with a counting sort (linear, stable, so the order
// within a colour is the order constraints are visited in, which is deterministic).
//
// from_colours is on every strategy's path, so on large inputs with few colours it counts and
// scatters in parallel: each fixed chunk of constraints counts its colours, the counts are
// summed in chunk order into each chunk's cursors, and each chunk scatters from its own,
// which is the sequential result for any thread count. Many colours (a histogram per chunk
// would outweigh the work), small inputs and invalid input (for its message) take the
// sequential path.
#include <tessera/coloring/colouring.hpp>

#include <algorithm>
#include <limits>
#include <string>

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <tessera/core/error.hpp>
#include <tessera/core/huge_pages.hpp>

namespace tessera {
namespace {

std::vector<std::uint32_t> colour_offsets_of(std::span<const Colour> colour_of) {
  // One pass: the counts grow with the largest colour seen (rarely, so the branch is free).
  // Dense colours are below the constraint count; a larger one is refused before it sizes the
  // counts (a stray "uncoloured" marker would ask for 2^32 of them).
  std::vector<std::uint32_t> offsets(1, 0);
  for (std::size_t c = 0; c < colour_of.size(); ++c) {
    const std::size_t k = colour_of[c];
    if (k + 1 >= offsets.size()) {
      if (k >= colour_of.size())
        throw InvalidInput("colouring: constraint " + std::to_string(c) + " has colour " +
                           std::to_string(k) + ", but " + std::to_string(colour_of.size()) +
                           " constraints need at most that many colours (colours must be dense)");
      offsets.resize(k + 2, 0);
    }
    ++offsets[k + 1];
  }
  const std::size_t count = offsets.size() - 1;
  for (std::size_t k = 0; k < count; ++k) {
    if (offsets[k + 1] == 0)
      throw InvalidInput("colouring: colour " + std::to_string(k) + " of " +
                         std::to_string(count) + " is empty (colours must be dense)");
    offsets[k + 1] += offsets[k];
  }
  return offsets;
}

/// Constraints per chunk of the parallel grouping, and the limits past which it is not used.
constexpr std::size_t kGroupingChunk = std::size_t(1) << 16;
constexpr std::size_t kParallelGroupingMinimum = 4 * kGroupingChunk;
constexpr std::size_t kParallelGroupingColours = 1024;

/// The parallel grouping (see the file comment); false, with nothing written, when the input
/// is not for it.
bool group_in_parallel(std::span<const Colour> colour_of, std::vector<std::uint32_t>& offsets,
                       std::vector<ConstraintIndex>& by_colour) {
  const std::size_t count = colour_of.size();
  if (count < kParallelGroupingMinimum) return false;
  const std::size_t chunks = (count + kGroupingChunk - 1) / kGroupingChunk;
  const auto chunk_end = [&](std::size_t chunk) { return std::min(count, (chunk + 1) * kGroupingChunk); };
  const Colour largest = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, chunks, 1), Colour(0),
      [&](const tbb::blocked_range<std::size_t>& range, Colour m) {
        for (std::size_t chunk = range.begin(); chunk < range.end(); ++chunk)
          for (std::size_t c = chunk * kGroupingChunk; c < chunk_end(chunk); ++c) m = std::max(m, colour_of[c]);
        return m;
      },
      [](Colour a, Colour b) { return std::max(a, b); }, tbb::simple_partitioner());
  const std::size_t colours = std::size_t(largest) + 1;
  if (colours > kParallelGroupingColours || colours > count) return false;
  std::vector<std::uint32_t> cursor(chunks * colours, 0);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
    std::uint32_t* counts = cursor.data() + chunk * colours;
    for (std::size_t c = chunk * kGroupingChunk; c < chunk_end(chunk); ++c) ++counts[colour_of[c]];
  });
  std::vector<std::uint32_t> result(colours + 1, 0);
  for (std::size_t k = 0; k < colours; ++k) {
    std::uint32_t next = result[k];
    for (std::size_t chunk = 0; chunk < chunks; ++chunk) {
      const std::uint32_t n = cursor[chunk * colours + k];
      cursor[chunk * colours + k] = next;
      next += n;
    }
    if (next == result[k]) return false;  // an empty colour: the sequential path says which
    result[k + 1] = next;
  }
  by_colour = make_large_vector<ConstraintIndex>(count);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t chunk) {
    std::uint32_t* next = cursor.data() + chunk * colours;
    for (std::size_t c = chunk * kGroupingChunk; c < chunk_end(chunk); ++c)
      by_colour[next[colour_of[c]]++] = static_cast<ConstraintIndex>(c);
  });
  offsets = std::move(result);
  return true;
}

}  // namespace

Colouring Colouring::from_colours(std::vector<Colour> colour_of_constraint) {
  Colouring colouring;
  if (group_in_parallel(colour_of_constraint, colouring.offsets_, colouring.constraints_by_colour_)) {
    colouring.colour_of_ = std::move(colour_of_constraint);
    return colouring;
  }
  colouring.offsets_ = colour_offsets_of(colour_of_constraint);
  colouring.constraints_by_colour_ = make_large_vector<ConstraintIndex>(colour_of_constraint.size());
  if (!colouring.offsets_.empty()) {
    std::vector<std::uint32_t> cursor(colouring.offsets_.begin(), colouring.offsets_.end() - 1);
    for (std::size_t c = 0; c < colour_of_constraint.size(); ++c)
      colouring.constraints_by_colour_[cursor[colour_of_constraint[c]]++] =
          static_cast<ConstraintIndex>(c);
  }
  colouring.colour_of_ = std::move(colour_of_constraint);
  return colouring;
}

Colouring Colouring::from_colours(std::vector<Colour> colour_of_constraint,
                                  std::span<const ConstraintIndex> constraint_order) {
  if (constraint_order.size() != colour_of_constraint.size())
    throw InvalidInput("colouring: constraint order lists " +
                       std::to_string(constraint_order.size()) + " constraints, expected " +
                       std::to_string(colour_of_constraint.size()));
  std::vector<std::uint8_t> seen(colour_of_constraint.size(), 0);
  for (ConstraintIndex c : constraint_order) {
    if (c >= colour_of_constraint.size() || seen[c])
      throw InvalidInput("colouring: constraint order is not a permutation (entry " +
                         std::to_string(c) + ")");
    seen[c] = 1;
  }
  Colouring colouring;
  colouring.offsets_ = colour_offsets_of(colour_of_constraint);
  colouring.constraints_by_colour_ = make_large_vector<ConstraintIndex>(colour_of_constraint.size());
  if (!colouring.offsets_.empty()) {
    std::vector<std::uint32_t> cursor(colouring.offsets_.begin(), colouring.offsets_.end() - 1);
    for (ConstraintIndex c : constraint_order)
      colouring.constraints_by_colour_[cursor[colour_of_constraint[c]]++] = c;
  }
  colouring.colour_of_ = std::move(colour_of_constraint);
  return colouring;
}

void Colouring::set_particle_order(std::vector<ParticleIndex> new_to_old) {
  std::vector<ParticleIndex> old_to_new(new_to_old.size(), std::numeric_limits<ParticleIndex>::max());
  for (std::size_t n = 0; n < new_to_old.size(); ++n) {
    const ParticleIndex old = new_to_old[n];
    if (old >= new_to_old.size() || old_to_new[old] != std::numeric_limits<ParticleIndex>::max())
      throw InvalidInput("colouring: particle order is not a permutation (new particle " +
                         std::to_string(n) + " maps to " + std::to_string(old) + ")");
    old_to_new[old] = static_cast<ParticleIndex>(n);
  }
  particle_new_to_old_ = std::move(new_to_old);
  particle_old_to_new_ = std::move(old_to_new);
}

void Colouring::set_parts(std::vector<std::uint32_t> part_of_constraint, std::size_t part_count) {
  if (part_of_constraint.size() != constraint_count())
    throw InvalidInput("colouring: parts name " + std::to_string(part_of_constraint.size()) +
                       " constraints, the colouring has " + std::to_string(constraint_count()));
  for (std::size_t c = 0; c < part_of_constraint.size(); ++c)
    if (part_of_constraint[c] > part_count)
      throw InvalidInput("colouring: constraint " + std::to_string(c) + " is in part " +
                         std::to_string(part_of_constraint[c]) + " of " +
                         std::to_string(part_count));
  part_of_constraint_ = std::move(part_of_constraint);
  part_count_ = part_count;
  has_parts_ = true;
}

}  // namespace tessera
