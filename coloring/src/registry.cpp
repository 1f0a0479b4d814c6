// The strategy registry: a list searched by name (strategies are few; order of insertion is
// the listing order).
#include <algorithm>

#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/core/error.hpp>

namespace tessera {

ColouringRegistry ColouringRegistry::with_builtin_strategies() {
  ColouringRegistry registry;
  registry.add(make_greedy_strategy());
  registry.add(make_largest_first_strategy());
  registry.add(make_smallest_last_strategy());
  registry.add(make_dsatur_strategy());
  registry.add(make_stencil_strategy());
  registry.add(make_iterated_greedy_strategy());
  registry.add(make_random_strategy());
  registry.add(make_metis_strategy());
  registry.add(make_blocks_strategy());
  return registry;
}

void ColouringRegistry::add(std::shared_ptr<const ColouringStrategy> strategy) {
  if (!strategy) throw InvalidInput("colouring registry: cannot add a null strategy");
  if (strategy->name().empty()) throw InvalidInput("colouring registry: strategy without a name");
  if (contains(strategy->name()))
    throw InvalidInput("colouring registry: a strategy named '" + std::string(strategy->name()) +
                       "' is already registered");
  strategies_.push_back(std::move(strategy));
}

bool ColouringRegistry::contains(std::string_view name) const {
  return std::any_of(strategies_.begin(), strategies_.end(),
                     [&](const auto& s) { return s->name() == name; });
}

const ColouringStrategy& ColouringRegistry::get(std::string_view name) const {
  for (const auto& strategy : strategies_)
    if (strategy->name() == name) return *strategy;
  std::string known;
  for (const auto& strategy : strategies_) known += (known.empty() ? "" : ", ") + std::string(strategy->name());
  throw InvalidInput("unknown colouring strategy '" + std::string(name) + "' (known: " + known + ")");
}

std::vector<std::string_view> ColouringRegistry::names() const {
  std::vector<std::string_view> result;
  for (const auto& strategy : strategies_) result.push_back(strategy->name());
  return result;
}

}  // namespace tessera
