// Solver mode, sequential order and contact scheduling names (solver_mode.hpp).
#include <tessera/parallel/solver_mode.hpp>

#include <string>

#include <tessera/core/error.hpp>

namespace tessera {

std::string_view solver_mode_name(SolverMode mode) {
  switch (mode) {
    case SolverMode::gs: return "gs";
    case SolverMode::jacobi: return "jacobi";
    case SolverMode::hybrid: return "hybrid";
    case SolverMode::sequential: return "sequential";
  }
  return "unknown";
}

SolverMode parse_solver_mode(std::string_view name) {
  std::string known;
  for (const SolverMode mode : kSolverModes) {
    if (solver_mode_name(mode) == name) return mode;
    known += (known.empty() ? "" : ", ") + std::string(solver_mode_name(mode));
  }
  throw InvalidInput("unknown solver mode '" + std::string(name) + "' (known: " + known + ")");
}

std::string_view sequential_order_name(SequentialOrder order) {
  switch (order) {
    case SequentialOrder::groups: return "groups";
    case SequentialOrder::input: return "input";
  }
  return "unknown";
}

SequentialOrder parse_sequential_order(std::string_view name) {
  for (const SequentialOrder order : {SequentialOrder::groups, SequentialOrder::input})
    if (sequential_order_name(order) == name) return order;
  throw InvalidInput("unknown sequential order '" + std::string(name) +
                     "' (known: groups, input)");
}

std::string_view contact_scheduling_name(ContactScheduling scheduling) {
  switch (scheduling) {
    case ContactScheduling::jacobi: return "jacobi";
    case ContactScheduling::coloured: return "coloured";
  }
  return "unknown";
}

ContactScheduling parse_contact_scheduling(std::string_view name) {
  for (const ContactScheduling scheduling : {ContactScheduling::jacobi, ContactScheduling::coloured})
    if (contact_scheduling_name(scheduling) == name) return scheduling;
  throw InvalidInput("unknown contact scheduling '" + std::string(name) +
                     "' (known: jacobi, coloured)");
}

}  // namespace tessera
