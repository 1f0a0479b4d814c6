// Model bookkeeping: family names and global constraint ids.
#include <tessera/core/model.hpp>

#include <numeric>
#include <string>

#include <tessera/core/error.hpp>


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

}  // namespace tessera
