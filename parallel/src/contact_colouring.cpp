// First-fit colouring of each substep's contacts (see contact_colouring.hpp for the picture):
// mask, pick, lay out.
#include "contact_colouring.hpp"

#include <bit>

#include <tessera/core/batch_reorder.hpp>
#include "jacobi_set.hpp"

namespace tessera::detail {

namespace {

/// Calls visit(particle) for every particle of constraint j of `batch`.
template <class Batch, class Visit>
void for_each_particle(const Batch& batch, std::size_t j, Visit&& visit) {
  if constexpr (kFixedArity<Batch>) {
    for (const auto& slot : batch.particles.particle) visit(slot[j]);
  } else {
    for (auto e = batch.offsets[j]; e < batch.offsets[j + 1]; ++e) visit(batch.particle[e]);
  }
}

}  // namespace

void colour_contacts(const ConstraintSets& found, std::span<std::uint64_t> contact_masks,
                     std::span<const Real> inverse_mass, ColouredContacts& result) {
  result.blocks.clear();
  result.colour_offsets.assign(1, 0);
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f) {
    result.ranges[f].clear();
    result.source[f].clear();
    result.overflow[f].clear();
  }
  result.constraint_count = 0;
  // References, not a structured binding: clang 14 cannot capture a binding in a lambda.
  auto& colour_of = result.scratch.colour_of;
  auto& by_colour_offsets = result.scratch.by_colour_offsets;
  auto& by_colour = result.scratch.by_colour;
  auto& next = result.scratch.next;
  // 1. Each contact's colour, first-fit in the stage's order (kContactColours: overflow).
  std::size_t colours = 0;
  found.for_each([&](ConstraintFamily family, const auto& batch) {
    auto& colour = colour_of[std::size_t(family)];
    colour.resize(batch.size());
    for (std::size_t j = 0; j < batch.size(); ++j) {
      std::uint64_t taken = 0;
      for_each_particle(batch, j, [&](ParticleIndex p) {
        if (inverse_mass[p] > 0) taken |= contact_masks[p];
      });
      if (taken == ~std::uint64_t(0)) {
        colour[j] = std::uint8_t(kContactColours);
        result.overflow[std::size_t(family)].push_back(std::uint32_t(j));
        continue;
      }
      const int k = std::countr_one(taken);
      colour[j] = std::uint8_t(k);
      colours = std::max(colours, std::size_t(k) + 1);
      const std::uint64_t bit = std::uint64_t(1) << k;
      for_each_particle(batch, j, [&](ParticleIndex p) {
        if (inverse_mass[p] > 0) contact_masks[p] |= bit;
      });
    }
  });
  // The scratch back to zero, touching only the contacts' particles.
  found.for_each([&](ConstraintFamily, const auto& batch) {
    for (std::size_t j = 0; j < batch.size(); ++j)
      for_each_particle(batch, j, [&](ParticleIndex p) { contact_masks[p] = 0; });
  });

  // 2. Slots colour by colour, each family's range of a colour starting on a kMaxLanes
  //    boundary (a counting sort by colour keeps the stage's order inside a colour).
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f) {
    const auto& colour = colour_of[f];
    auto& offsets = by_colour_offsets[f];
    offsets.assign(colours + 2, 0);
    for (const std::uint8_t k : colour) ++offsets[std::min<std::size_t>(k, colours) + 1];
    for (std::size_t k = 0; k <= colours; ++k) offsets[k + 1] += offsets[k];
    by_colour[f].resize(colour.size());
    next.assign(offsets.begin(), offsets.end() - 1);
    for (std::size_t j = 0; j < colour.size(); ++j)
      by_colour[f][next[std::min<std::size_t>(colour[j], colours)]++] = std::uint32_t(j);
  }
  for (std::size_t k = 0; k < colours; ++k) {
    for (std::size_t f = 0; f < kConstraintFamilyCount; ++f) {
      const std::uint32_t first = by_colour_offsets[f][k], last = by_colour_offsets[f][k + 1];
      if (first == last) continue;
      auto& source = result.source[f];
      source.resize(round_up(source.size(), kMaxLanes), kNoContact);
      const std::size_t begin = source.size();
      source.insert(source.end(), by_colour[f].begin() + first, by_colour[f].begin() + last);
      result.ranges[f].push_back({ConstraintFamily(f), std::uint32_t(begin),
                                  std::uint32_t(source.size())});
      // One block per family: the solver cuts a colour into one share per thread.
      result.blocks.push_back(result.ranges[f].back());
      result.constraint_count += last - first;
    }
    result.colour_offsets.push_back(std::uint32_t(result.blocks.size()));
  }

  // 3. The batches gathered through the slots (the particles keep their numbers).
  const std::size_t particle_count = inverse_mass.size();
  result.constraints.for_each([&](ConstraintFamily family, auto& batch) {
    using Batch = std::decay_t<decltype(batch)>;
    reorder_batch_into(batch, found.of_type<Batch>(), result.source[std::size_t(family)],
                       kNoContact, particle_count,
                       [](std::size_t, std::size_t, ParticleIndex p) { return p; });
  });
}

}  // namespace tessera::detail
