// The residual's building blocks, shared by the solver: the partial sums of one range of a
// family's batch, and their combination in a fixed order (so the result does not depend on
// how the ranges were spread over threads).
#pragma once

#include <cstddef>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <tessera/parallel/residual.hpp>
#include <tessera/parallel/schedule.hpp>

namespace tessera::detail {

/// Constraints [begin, end) of one family of the coloured batches, the Jacobi set or the
/// dynamic constraints.
struct ResidualRange {
  enum Set : std::uint8_t { coloured, jacobi, dynamic, contacts, contact_colours };
  ConstraintFamily family;
  Set set;
  std::uint32_t begin;
  std::uint32_t end;
};

struct ResidualPartial {
  double sum_of_squares = 0;
  double max = 0;
  /// The slot (in the range's set) of the first constraint whose residual is max.
  std::uint32_t max_slot = 0;
};

/// Where a family's largest residual was found: a slot of the coloured batches, the Jacobi
/// set or the dynamic constraints (the solver turns it into the user's constraint).
struct WorstPlace {
  ResidualRange::Set set = ResidualRange::coloured;
  std::uint32_t slot = 0;
};

/// The longest range residual_of_range takes (its values live on the stack).
inline constexpr std::size_t kLongestResidualRange = 2048;

/// Every real constraint of the schedule, of `dynamic`, of the contacts' Jacobi set and of
/// the coloured contacts' real ranges, in ranges of at most `chunk` (≤ kLongestResidualRange)
/// constraints, into `ranges` (overwritten; its capacity is reused, so a solver that keeps
/// it allocates nothing from one residual to the next).
void residual_ranges(
    const Schedule& schedule, const ConstraintSets& dynamic, const ConstraintSets& contacts,
    const std::array<std::vector<ScheduleBlock>, kConstraintFamilyCount>& contact_colour_ranges,
    std::size_t chunk, std::vector<ResidualRange>& ranges);

/// What Solver::residual() keeps from one call to the next: the ranges and their partials.
struct ResidualScratch {
  std::vector<ResidualRange> ranges;
  std::vector<ResidualPartial> partials;
};

/// The partial sums of one range, at `particles`: of the XPBD residual C + α̃λ of the XPBD
/// families with α̃ = compliance / compliance_dt² when compliance_dt > 0 (compliance
/// semantics), of C otherwise.
ResidualPartial residual_of_range(const ResidualRange& range, const ConstraintSets& sets,
                                  const ParticleArrays& particles, Real compliance_dt);

/// Sums the partials (one per range, same order) family by family; `worst` gets, per family,
/// where its largest residual was found.
Residual combine_residual(std::span<const ResidualRange> ranges,
                          std::span<const ResidualPartial> partials,
                          std::array<WorstPlace, kConstraintFamilyCount>& worst);

}  // namespace tessera::detail
