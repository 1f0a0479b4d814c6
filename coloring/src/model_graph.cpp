// The constraint graph of a model: every non-empty family as one constraint group, named by
// family_name, so global constraint ids are the model's.
#include <tessera/coloring/model_graph.hpp>

#include <span>
#include <string>
#include <vector>

#include <tessera/core/error.hpp>

namespace tessera {

ConstraintGraph constraint_graph(const Model& model) {
  // The groups read the batches' own arrays: fixed-size families by slot (one array per
  // particle of the constraint, as the batches store them), clusters as CSR. Nothing is copied
  // before the graph's own pass (interleaving the slots first cost a third of the graph's
  // build on the 6.3 M-constraint cloth, most of it faulting in the copy).
  std::vector<std::vector<std::span<const ParticleIndex>>> slots;
  std::vector<ConstraintGroup> groups;
  slots.reserve(kConstraintFamilyCount);
  model.constraints.for_each([&](ConstraintFamily family, const auto& batch) {
    const std::size_t n = batch.size();
    if (n == 0) return;
    const std::string name(family_name(family));
    if constexpr (!requires { batch.particles; }) {
      if (batch.particle_count > model.particles.size())
        throw InvalidInput(name + " constraints were built for " +
                           std::to_string(batch.particle_count) + " particles, the model has " +
                           std::to_string(model.particles.size()));
      groups.push_back(ConstraintGroup::variable_size(
          name, std::span<const ParticleIndex>(batch.offsets.data(), n + 1),
          std::span<const ParticleIndex>(batch.particle.data(), batch.entry_count())));
    } else {
      constexpr std::size_t N = decltype(batch.particles)::kParticlesPerConstraint;
      if (batch.particles.particle_count > model.particles.size())
        throw InvalidInput(name + " constraints were built for " +
                           std::to_string(batch.particles.particle_count) +
                           " particles, the model has " + std::to_string(model.particles.size()));
      auto& family_slots = slots.emplace_back(N);
      for (std::size_t k = 0; k < N; ++k)
        family_slots[k] = std::span<const ParticleIndex>(batch.particles.particle[k].data(), n);
      groups.push_back(ConstraintGroup::by_slot(name, family_slots));
    }
  });
  const std::span<const Real> inverse_masses(model.particles.inverse_mass.data(), model.particles.size());
  return ConstraintGraph(inverse_masses, groups);
}

}  // namespace tessera
