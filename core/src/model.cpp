// Model bookkeeping: global constraint ids.
#include <tessera/core/model.hpp>

#include <string>

#include <tessera/core/error.hpp>


namespace tessera {

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
