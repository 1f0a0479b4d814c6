// Residual sums: per-constraint measures from core (constraint_residual), summed per range
// and combined in range order.
#include <tessera/parallel/residual.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <type_traits>

#include <tessera/core/constraint_residual.hpp>

#include "residual_sum.hpp"

namespace tessera {

namespace detail {

void residual_ranges(
    const Schedule& schedule, const ConstraintSets& dynamic, const ConstraintSets& contacts,
    const std::array<std::vector<ScheduleBlock>, kConstraintFamilyCount>& contact_colour_ranges,
    std::size_t chunk, std::vector<ResidualRange>& ranges) {
  ranges.clear();
  const auto add = [&](ConstraintFamily family, ResidualRange::Set set, std::size_t begin,
                       std::size_t end) {
    for (std::size_t b = begin; b < end; b += chunk)
      ranges.push_back({family, set, std::uint32_t(b), std::uint32_t(std::min(end, b + chunk))});
  };
  const auto jacobi_sizes = schedule.jacobi().constraints.sizes();
  const auto dynamic_sizes = dynamic.sizes();
  const auto contact_sizes = contacts.sizes();
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f) {
    for (const ScheduleBlock& r : schedule.coloured_ranges(ConstraintFamily(f)))
      add(r.family, ResidualRange::coloured, r.begin, r.end);
    add(ConstraintFamily(f), ResidualRange::jacobi, 0, jacobi_sizes[f]);
    add(ConstraintFamily(f), ResidualRange::dynamic, 0, dynamic_sizes[f]);
    add(ConstraintFamily(f), ResidualRange::contacts, 0, contact_sizes[f]);
    for (const ScheduleBlock& r : contact_colour_ranges[f])
      add(r.family, ResidualRange::contact_colours, r.begin, r.end);
  }
}

ResidualPartial residual_of_range(const ResidualRange& range, const ConstraintSets& sets,
                                  const ParticleArrays& particles, Real compliance_dt) {
  ResidualPartial partial;
  Real values[kLongestResidualRange];
  sets.for_each([&](ConstraintFamily family, const auto& batch) {
    if (family != range.family) return;
    // The batched evaluation (SIMD lanes), then the sums in constraint order.
    using Batch = std::decay_t<decltype(batch)>;
    if constexpr (Batch::kTraits.xpbd) {
      if (compliance_dt > 0)
        xpbd_residuals(particles, batch, range.begin, range.end, compliance_dt, values);
      else
        constraint_residuals(particles, batch, range.begin, range.end, values);
    } else {
      constraint_residuals(particles, batch, range.begin, range.end, values);
    }
    for (std::size_t c = 0; c < std::size_t(range.end - range.begin); ++c) {
      const double r = double(values[c]);
      partial.sum_of_squares += r * r;
      if (r > partial.max) {
        partial.max = r;
        partial.max_slot = std::uint32_t(range.begin + c);
      }
    }
  });
  return partial;
}

Residual combine_residual(std::span<const ResidualRange> ranges,
                          std::span<const ResidualPartial> partials,
                          std::array<WorstPlace, kConstraintFamilyCount>& worst) {
  Residual result;
  std::array<double, kConstraintFamilyCount> sums{};
  double total = 0;
  worst = {};
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    const std::size_t f = std::size_t(ranges[i].family);
    FamilyResidual& family = result.families[f];
    if (family.constraints == 0 || partials[i].max > family.max) {
      family.max = partials[i].max;
      worst[f] = {ranges[i].set, partials[i].max_slot};
    }
    family.constraints += ranges[i].end - ranges[i].begin;
    sums[f] += partials[i].sum_of_squares;
  }
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f) {
    FamilyResidual& family = result.families[f];
    if (family.constraints == 0) continue;
    family.rms = std::sqrt(sums[f] / double(family.constraints));
    if (result.constraints == 0 || family.max > result.max) {
      result.max = family.max;
      result.worst_family = ConstraintFamily(f);
    }
    result.constraints += family.constraints;
    total += sums[f];
  }
  if (result.constraints != 0) result.rms = std::sqrt(total / double(result.constraints));
  return result;
}

}  // namespace detail

std::string format_residual(const Residual& residual) {
  char buffer[128];
  std::snprintf(buffer, sizeof buffer, "rms %.3g, max %.3g", residual.rms, residual.max);
  std::string text = buffer;
  const char* separator = " (";
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f) {
    const FamilyResidual& family = residual.families[f];
    if (family.constraints == 0) continue;
    std::snprintf(buffer, sizeof buffer, "%s rms %.3g, max %.3g",
                  std::string(family_name(ConstraintFamily(f))).c_str(), family.rms, family.max);
    text += separator;
    text += buffer;
    separator = "; ";
  }
  if (*separator == ';') text += ")";
  return text;
}

}  // namespace tessera
