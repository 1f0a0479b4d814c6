// Colouring: grouping constraints by colour with a counting sort (linear, stable, so the order
// within a colour is the order constraints are visited in, which is deterministic).
#include <tessera/coloring/colouring.hpp>

#include <algorithm>
#include <limits>
#include <string>

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

}  // namespace

Colouring Colouring::from_colours(std::vector<Colour> colour_of_constraint) {
  Colouring colouring;
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

}  // namespace tessera
