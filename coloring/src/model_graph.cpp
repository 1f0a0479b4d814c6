// The constraint graph of a model: every non-empty family as one constraint group, named by
// family_name, so global constraint ids are the model's.
#include <tessera/coloring/model_graph.hpp>

#include <string>
#include <vector>

#include <tessera/core/error.hpp>

namespace tessera {

ConstraintGraph constraint_graph(const Model& model) {
  // ConstraintGroup wants each constraint's particles back to back; the batches hold one
  // array per slot, so interleave them (the graph copies what it needs).
  std::vector<std::vector<ParticleIndex>> storage;
  std::vector<ConstraintGroup> groups;
  storage.reserve(2 * kConstraintFamilyCount);
  model.constraints.for_each([&](ConstraintFamily family, const auto& batch) {
    const std::size_t n = batch.size();
    if (n == 0) return;
    const std::string name(family_name(family));
    if constexpr (!requires { batch.particles; }) {
      if (batch.particle_count > model.particles.size())
        throw InvalidInput(name + " constraints were built for " +
                           std::to_string(batch.particle_count) + " particles, the model has " +
                           std::to_string(model.particles.size()));
      auto& offsets = storage.emplace_back(batch.offsets.begin(),
                                           batch.offsets.begin() + std::ptrdiff_t(n + 1));
      auto& indices = storage.emplace_back(
          batch.particle.begin(), batch.particle.begin() + std::ptrdiff_t(batch.entry_count()));
      groups.push_back(ConstraintGroup::variable_size(name, offsets, indices));
    } else {
      constexpr std::size_t N = decltype(batch.particles)::kParticlesPerConstraint;
      if (batch.particles.particle_count > model.particles.size())
        throw InvalidInput(name + " constraints were built for " +
                           std::to_string(batch.particles.particle_count) +
                           " particles, the model has " + std::to_string(model.particles.size()));
      auto& indices = storage.emplace_back(n * N);
      for (std::size_t c = 0; c < n; ++c)
        for (std::size_t k = 0; k < N; ++k) indices[c * N + k] = batch.particles.particle[k][c];
      groups.push_back(ConstraintGroup::fixed_arity(name, N, indices));
    }
  });
  const std::span<const Real> inverse_masses(model.particles.inverse_mass.data(), model.particles.size());
  return ConstraintGraph(inverse_masses, groups);
}

}  // namespace tessera
