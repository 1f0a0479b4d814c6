// Each substep's contacts coloured among themselves, first-fit, and swept Gauss–Seidel after
// the model's constraints (ContactScheduling::coloured).
//
// Why: a Jacobi set averages the corrections of all the contacts at a particle, so a particle
// pressed by several contacts moves by their mean, and a stack of contacts needs many
// iterations to push through; Gauss–Seidel applies each contact to positions the previous
// ones already corrected. The contacts change every substep, so no graph is built: each
// particle carries a 64-bit mask of the colours its contacts took so far, and a contact takes
// the lowest colour none of its movable particles carries.
//
//   static phases  0 ████  1 ████  2 ████ │ contact colours  c0 ▒▒▒  c1 ▒▒  c2 ▒ │ overflow
//   stage list     ph0     ph1     ph2    │ (dynamic set)    c0      c1     c2  │ Jacobi set
//
// The contacts come last in every iteration, so they have the last word: after the
// iterations no contact is left violated by a constraint swept after it. Colouring them on
// top of the static colours instead (first-fit against the static phases a particle is in,
// contact colour k right after static phase k) was measured and dropped: it needs more
// colours (a particle's static phases are taken), and the cloth's later phases pulled
// particles back into the colliders (the drape's collider contacts 1.2 mm deep after the
// iterations against 0 contacts-last; the 64² drape's residual max 0.60 against 0.35).
// Contacts that find no colour among the 64 go to a Jacobi set (the overflow). Static
// particles separate nothing. Deterministic: the contacts are coloured one after another in
// the order the collision stage gives them (sorted), family by family.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <tessera/parallel/schedule.hpp>

namespace tessera::detail {

/// Colours a contact can take: one bit each in a particle's mask.
inline constexpr std::size_t kContactColours = 64;

/// The substep's contacts laid out colour-major like the schedule's coloured batches.
struct ColouredContacts {
  ConstraintSets constraints;
  /// Colour k's blocks are blocks[colour_offsets[k], colour_offsets[k + 1]).
  std::vector<ScheduleBlock> blocks;
  std::vector<std::uint32_t> colour_offsets{0};
  /// Per family, the real ranges (no padding), for residuals.
  std::array<std::vector<ScheduleBlock>, kConstraintFamilyCount> ranges;
  /// Per family, the found contact (its index in the collision stage's batch) in each slot,
  /// or kNoContact for padding.
  std::array<std::vector<std::uint32_t>, kConstraintFamilyCount> source;
  /// Per family, the contacts that found no colour (indices into the found batch), in order.
  std::array<std::vector<std::uint32_t>, kConstraintFamilyCount> overflow;
  std::size_t constraint_count = 0;
  /// colour_contacts' working lists, kept with the result so that colouring each substep's
  /// contacts into the same ColouredContacts allocates nothing once the contacts stop growing.
  struct Scratch {
    std::array<std::vector<std::uint8_t>, kConstraintFamilyCount> colour_of;
    std::array<std::vector<std::uint32_t>, kConstraintFamilyCount> by_colour_offsets;
    std::array<std::vector<std::uint32_t>, kConstraintFamilyCount> by_colour;
    std::vector<std::uint32_t> next;
  } scratch;
  std::size_t colour_count() const { return colour_offsets.size() - 1; }
  std::span<const ScheduleBlock> colour_blocks(std::size_t k) const {
    return {blocks.data() + colour_offsets[k], blocks.data() + colour_offsets[k + 1]};
  }
};
inline constexpr std::uint32_t kNoContact = ~std::uint32_t(0);

/// Colours `found` (in the schedule's numbering) into `result`, whose earlier contents are
/// replaced (its arrays keep their capacity). `contact_masks` is scratch of one word per
/// particle, all zero, and left all zero. Each colour holds one block per family (the solver
/// cuts it into one share per thread).
void colour_contacts(const ConstraintSets& found, std::span<std::uint64_t> contact_masks,
                     std::span<const Real> inverse_mass, ColouredContacts& result);

}  // namespace tessera::detail
