// Building a Jacobi set (the picture is in schedule.hpp), in four steps:
//
//   sort_by_smallest_particle   the set's order (free: its constraints run all at once)
//   lay_out_incidences          each family's incidence block: base, stride, size
//   fill_set                    the reordered batches, each incidence's particle, the blocks
//   index_particles             each movable particle's incidences (CSR, ascending)
//   lambda_shares               the XPBD multipliers' share per constraint
#include "jacobi_set.hpp"

#include <algorithm>
#include <limits>
#include <utility>

#include <tessera/core/batch_reorder.hpp>

namespace tessera::detail {

namespace {

using SourceLists = std::array<std::vector<std::uint32_t>, kConstraintFamilyCount>;
using Renumber = std::function<ParticleIndex(ParticleIndex)>;
using Movable = std::function<bool(ParticleIndex)>;

/// No Jacobi slot is padding: every listed constraint is real.
constexpr std::uint32_t kNoPadding = std::numeric_limits<std::uint32_t>::max();

/// Incidences of a family in the set: slot k of constraint j is base + k·stride + j (a
/// vector of W constraints reads W consecutive incidences); shape-matching entry e is
/// base + e.
struct IncidenceLayout {
  std::size_t base = 0;
  std::size_t stride = 0;
  std::size_t size = 0;
};
using Layouts = std::array<IncidenceLayout, kConstraintFamilyCount>;

/// The constraints are projected all at once, so their order is free: sort them by their
/// smallest (renumbered) particle. Then the incidences of neighbouring particles lie close
/// together in every slot array, and the per-particle sums read memory almost in order (in
/// colour order they jumped across the whole set).
void sort_by_smallest_particle(const ConstraintSets& sets, SourceLists& source_of_family,
                               const Renumber& renumber,
                               std::vector<std::pair<ParticleIndex, std::uint32_t>>& keyed) {
  sets.for_each([&](ConstraintFamily family, const auto& batch) {
    using Batch = std::decay_t<decltype(batch)>;
    auto& source = source_of_family[std::size_t(family)];
    if (source.empty()) return;
    keyed.resize(source.size());
    for (std::size_t j = 0; j < source.size(); ++j) {
      ParticleIndex smallest = std::numeric_limits<ParticleIndex>::max();
      if constexpr (kFixedArity<Batch>) {
        for (const auto& slot : batch.particles.particle)
          smallest = std::min(smallest, renumber(slot[source[j]]));
      } else {
        for (auto e = batch.offsets[source[j]]; e < batch.offsets[source[j] + 1]; ++e)
          smallest = std::min(smallest, renumber(batch.particle[e]));
      }
      keyed[j] = {smallest, source[j]};
    }
    std::sort(keyed.begin(), keyed.end());
    for (std::size_t j = 0; j < source.size(); ++j) source[j] = keyed[j].second;
  });
}

Layouts lay_out_incidences(const ConstraintSets& sets, const SourceLists& source_of_family,
                           std::size_t& incidences) {
  Layouts layout;
  incidences = 0;
  sets.for_each([&](ConstraintFamily family, const auto& batch) {
    using Batch = std::decay_t<decltype(batch)>;
    const auto& source = source_of_family[std::size_t(family)];
    IncidenceLayout& l = layout[std::size_t(family)];
    l.base = incidences;
    if constexpr (kFixedArity<Batch>) {
      l.stride = padded_size(source.size());
      l.size = source.empty() ? 0 : l.stride * std::size_t(Batch::kTraits.arity);
    } else {
      std::size_t entries = 0;
      for (const std::uint32_t s : source) entries += batch.offsets[s + 1] - batch.offsets[s];
      l.size = padded_size(entries);
    }
    incidences += l.size;
  });
  return layout;
}

/// The reordered batches and each incidence's particle; real_incidence marks the incidences
/// that belong to a constraint (the rest is padding).
void fill_set(JacobiSet& jacobi, const ConstraintSets& sets, const SourceLists& source_of_family,
              const Layouts& layout, std::size_t particle_count, const Renumber& renumber,
              const ScheduleOptions& options, std::vector<std::uint8_t>& real_incidence) {
  jacobi.constraints.for_each([&](ConstraintFamily family, auto& batch) {
    using Batch = std::decay_t<decltype(batch)>;
    const auto& source = source_of_family[std::size_t(family)];
    const IncidenceLayout& l = layout[std::size_t(family)];
    jacobi.incidence_base[std::size_t(family)] = l.base;
    jacobi.incidence_stride[std::size_t(family)] = l.stride;
    const auto renumber_and_record = [&](std::size_t k, std::size_t j, ParticleIndex p) {
      const std::size_t incidence = l.base + k * l.stride + j;
      jacobi.incidence_particle[incidence] = renumber(p);
      real_incidence[incidence] = 1;
      return renumber(p);
    };
    reorder_batch_into(batch, sets.of_type<Batch>(), source, kNoPadding, particle_count,
                       renumber_and_record);
    split_into_blocks(family, 0, source.size(), options, jacobi.blocks);
    jacobi.constraint_count += source.size();
  });
}

/// Each movable particle's incidences, ascending (a counting sort by particle); `count` gets
/// the count per particle (count[p + 1] for particle p); `start` is scratch.
void index_particles(JacobiSet& jacobi, std::size_t particle_count, const Movable& movable,
                     const std::vector<std::uint8_t>& real_incidence,
                     std::vector<std::uint32_t>& count, std::vector<std::uint32_t>& start) {
  count.assign(particle_count + 1, 0);
  const auto counted = [&](std::size_t i) {
    return real_incidence[i] && movable(jacobi.incidence_particle[i]);
  };
  for (std::size_t i = 0; i < jacobi.incidence_count; ++i)
    if (counted(i)) ++count[jacobi.incidence_particle[i] + 1];
  for (std::size_t p = 0; p < particle_count; ++p)
    if (count[p + 1] != 0) jacobi.particles.push_back(ParticleIndex(p));
  start.assign(particle_count + 1, 0);
  for (std::size_t p = 0; p < particle_count; ++p) start[p + 1] = start[p] + count[p + 1];
  jacobi.particle_incidences.resize(start[particle_count]);
  jacobi.particle_offsets.reserve(jacobi.particles.size() + 1);
  for (const ParticleIndex p : jacobi.particles) jacobi.particle_offsets.push_back(start[p]);
  jacobi.particle_offsets.push_back(start[particle_count]);
  for (std::size_t i = 0; i < jacobi.incidence_count; ++i)
    if (counted(i)) jacobi.particle_incidences[start[jacobi.incidence_particle[i]]++] = std::uint32_t(i);
}

/// λ shares: the mean count over each constraint's movable incidences (JacobiSet::lambda_share).
void lambda_shares(JacobiSet& jacobi, const Movable& movable,
                   const std::vector<std::uint32_t>& count) {
  jacobi.constraints.for_each([&](ConstraintFamily family, auto& batch) {
    using Batch = std::decay_t<decltype(batch)>;
    jacobi.lambda_share[std::size_t(family)].clear();
    if constexpr (Batch::kTraits.xpbd && kFixedArity<Batch>) {
      if (batch.size() == 0) return;
      auto& share = jacobi.lambda_share[std::size_t(family)];
      share.assign(padded_size(batch.size()), 0);
      for (std::size_t j = 0; j < batch.size(); ++j) {
        std::size_t movable_particles = 0, incidences_there = 0;
        for (const auto& slot : batch.particles.particle) {
          const ParticleIndex p = slot[j];
          if (!movable(p)) continue;
          ++movable_particles;
          incidences_there += count[p + 1];
        }
        if (incidences_there != 0)
          share[j] = Real(double(movable_particles) / double(incidences_there));
      }
    }
  });
}

}  // namespace

void build_jacobi_set(JacobiSet& jacobi, JacobiSetScratch& scratch, const ConstraintSets& sets,
                      SourceLists& source_of_family, std::size_t particle_count,
                      const Renumber& renumber, const Movable& movable,
                      const ScheduleOptions& options) {
  jacobi.particles.clear();
  jacobi.particle_offsets.clear();
  jacobi.blocks.clear();
  jacobi.constraint_count = 0;
  sort_by_smallest_particle(sets, source_of_family, renumber, scratch.keyed);
  std::size_t incidences = 0;
  const Layouts layout = lay_out_incidences(sets, source_of_family, incidences);
  jacobi.incidence_count = padded_size(incidences);
  jacobi.incidence_particle.assign(jacobi.incidence_count, 0);
  scratch.real_incidence.assign(jacobi.incidence_count, 0);
  fill_set(jacobi, sets, source_of_family, layout, particle_count, renumber, options,
           scratch.real_incidence);
  index_particles(jacobi, particle_count, movable, scratch.real_incidence, scratch.count,
                  scratch.start);
  lambda_shares(jacobi, movable, scratch.count);
}

JacobiSet build_jacobi_set(const ConstraintSets& sets, SourceLists& source_of_family,
                           std::size_t particle_count, const Renumber& renumber,
                           const Movable& movable, const ScheduleOptions& options) {
  JacobiSet jacobi;
  JacobiSetScratch scratch;
  build_jacobi_set(jacobi, scratch, sets, source_of_family, particle_count, renumber, movable,
                   options);
  return jacobi;
}

}  // namespace tessera::detail
