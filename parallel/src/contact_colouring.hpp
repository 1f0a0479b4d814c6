// Contacts coloured on top of the static colouring, anew every substep
// (ContactScheduling::coloured).
//
// Why: a Jacobi set averages the corrections of all contacts at a particle, so a particle
// pressed by several contacts moves by their mean, and a stack of contacts needs many
// iterations to push through; Gauss–Seidel applies each contact to positions the previous
// ones already corrected. Colouring the contacts from scratch each substep would cost a
// graph; instead each particle carries the bits of the static phases it is in (built once
// per schedule) and a contact takes, first-fit, the lowest colour none of its movable
// particles carries — a static phase's colour, where it runs right after that phase's
// constraints, or a colour past the static ones:
//
//   static phases      0 ████  1 ████  2 ████  3 ████
//   contact colours    0 ▒     1 ▒▒    2 ▒     3 ▒      4 ▒▒  5 ▒   │ overflow: Jacobi set
//   stage list         ph0 c0  ph1 c1  ph2 c2  ph3 c3   c4   c5    │ (no colour among 64)
//
// A colour's contacts share no movable particle with each other or with that phase's
// constraints, so running them as a phase of their own right after it is the same
// Gauss–Seidel order as running them inside it. Deterministic: the contacts are coloured one
// after another in the order the collision stage gives them (sorted), family by family.
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

/// Per scheduled particle, the bits of the schedule's Gauss–Seidel phases below
/// kContactColours that have a constraint moving it (phase k: bit k).
std::vector<std::uint64_t> static_phase_masks(const Schedule& schedule,
                                              std::span<const Real> inverse_mass);

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
  std::size_t colour_count() const { return colour_offsets.size() - 1; }
  std::span<const ScheduleBlock> colour_blocks(std::size_t k) const {
    return {blocks.data() + colour_offsets[k], blocks.data() + colour_offsets[k + 1]};
  }
};
inline constexpr std::uint32_t kNoContact = ~std::uint32_t(0);

/// Colours `found` (in the schedule's numbering) against `static_masks`. `contact_masks` is
/// scratch of one word per particle, all zero, and left all zero.
ColouredContacts colour_contacts(const ConstraintSets& found,
                                 std::span<const std::uint64_t> static_masks,
                                 std::span<std::uint64_t> contact_masks,
                                 std::span<const Real> inverse_mass,
                                 const ScheduleOptions& options);

}  // namespace tessera::detail
