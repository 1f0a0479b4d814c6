// Model bookkeeping: family names, global constraint ids and the constraint graph of all
// families (the colouring stage's input).
#include <tessera/parallel/model.hpp>

#include <numeric>
#include <string>
#include <vector>

#include <tessera/core/error.hpp>

#include "constraint_family.hpp"

namespace tessera {

std::string_view family_name(ConstraintFamily family) {
  static constexpr std::array<std::string_view, kConstraintFamilyCount> kNames = {
      "distance",        "dihedral",     "isometric_bending", "volume",
      "edge_point_distance", "triangle_point_distance", "edge_edge_distance",
      "strain_triangle", "strain_tetra", "fem_triangle",      "fem_tetra",
      "shape_matching"};
  return kNames.at(std::size_t(family));
}

std::array<std::size_t, kConstraintFamilyCount> ConstraintSets::sizes() const {
  std::array<std::size_t, kConstraintFamilyCount> result{};
  for_each([&](ConstraintFamily family, const auto& batch) {
    result[std::size_t(family)] = batch.size();
  });
  return result;
}

std::size_t ConstraintSets::size() const {
  const auto all = sizes();
  return std::accumulate(all.begin(), all.end(), std::size_t(0));
}

ConstraintIndex Model::constraint_id(ConstraintFamily family, std::size_t index) const {
  const auto all = constraints.sizes();
  if (index >= all[std::size_t(family)])
    throw InvalidInput(std::string(family_name(family)) + " constraint " +
                       std::to_string(index) + " does not exist (the model has " +
                       std::to_string(all[std::size_t(family)]) + ")");
  std::size_t first = 0;
  for (std::size_t f = 0; f < std::size_t(family); ++f) first += all[f];
  return ConstraintIndex(first + index);
}

ConstraintGraph Model::constraint_graph() const {
  // ConstraintGroup wants each constraint's particles back to back; the batches hold one
  // array per slot, so interleave them (the graph copies what it needs).
  std::vector<std::vector<ParticleIndex>> storage;
  std::vector<ConstraintGroup> groups;
  storage.reserve(2 * kConstraintFamilyCount);
  constraints.for_each([&](ConstraintFamily family, const auto& batch) {
    using Batch = std::decay_t<decltype(batch)>;
    const std::size_t n = batch.size();
    if (n == 0) return;
    const std::string name(family_name(family));
    if constexpr (detail::arity_of<Batch>() == 0) {
      if (batch.particle_count > particles.size())
        throw InvalidInput(name + " constraints were built for " +
                           std::to_string(batch.particle_count) + " particles, the model has " +
                           std::to_string(particles.size()));
      auto& offsets = storage.emplace_back(batch.offsets.begin(),
                                           batch.offsets.begin() + std::ptrdiff_t(n + 1));
      auto& indices = storage.emplace_back(
          batch.particle.begin(), batch.particle.begin() + std::ptrdiff_t(batch.entry_count()));
      groups.push_back(ConstraintGroup::variable_size(name, offsets, indices));
    } else {
      constexpr std::size_t N = detail::arity_of<Batch>();
      if (batch.particles.particle_count > particles.size())
        throw InvalidInput(name + " constraints were built for " +
                           std::to_string(batch.particles.particle_count) +
                           " particles, the model has " + std::to_string(particles.size()));
      auto& indices = storage.emplace_back(n * N);
      for (std::size_t c = 0; c < n; ++c)
        for (std::size_t k = 0; k < N; ++k) indices[c * N + k] = batch.particles.particle[k][c];
      groups.push_back(ConstraintGroup::fixed_arity(name, N, indices));
    }
  });
  const std::span<const Real> inverse_masses(particles.inverse_mass.data(), particles.size());
  return ConstraintGraph(inverse_masses, groups);
}

}  // namespace tessera
