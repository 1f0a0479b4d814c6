// Solver mode, sequential order, contact scheduling, particle layout and sweep order names (solver_mode.hpp).
#include <tessera/parallel/solver_mode.hpp>

#include <string>

#include <tessera/core/error.hpp>

namespace tessera {

namespace {

/// The value among `values` whose name_of is `name`; InvalidInput "unknown <what> '<name>'
/// (known: a, b, ...)" otherwise.
template <class Value, std::size_t N, class NameOf>
Value parse_named(std::string_view name, const Value (&values)[N], NameOf name_of,
                  const char* what) {
  std::string known;
  for (const Value value : values) {
    if (name_of(value) == name) return value;
    known += (known.empty() ? "" : ", ") + std::string(name_of(value));
  }
  throw InvalidInput("unknown " + std::string(what) + " '" + std::string(name) + "' (known: " +
                     known + ")");
}

}  // namespace

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
  return parse_named(name, kSolverModes, solver_mode_name, "solver mode");
}

std::string_view sequential_order_name(SequentialOrder order) {
  switch (order) {
    case SequentialOrder::groups: return "groups";
    case SequentialOrder::input: return "input";
  }
  return "unknown";
}

SequentialOrder parse_sequential_order(std::string_view name) {
  constexpr SequentialOrder kOrders[] = {SequentialOrder::groups, SequentialOrder::input};
  return parse_named(name, kOrders, sequential_order_name, "sequential order");
}

std::string_view contact_scheduling_name(ContactScheduling scheduling) {
  switch (scheduling) {
    case ContactScheduling::jacobi: return "jacobi";
    case ContactScheduling::coloured: return "coloured";
  }
  return "unknown";
}

ContactScheduling parse_contact_scheduling(std::string_view name) {
  constexpr ContactScheduling kSchedulings[] = {ContactScheduling::jacobi,
                                                ContactScheduling::coloured};
  return parse_named(name, kSchedulings, contact_scheduling_name, "contact scheduling");
}

std::string_view particle_layout_name(ParticleLayout layout) {
  switch (layout) {
    case ParticleLayout::separate: return "separate";
    case ParticleLayout::interleaved: return "interleaved";
  }
  return "unknown";
}

ParticleLayout parse_particle_layout(std::string_view name) {
  constexpr ParticleLayout kLayouts[] = {ParticleLayout::separate, ParticleLayout::interleaved};
  return parse_named(name, kLayouts, particle_layout_name, "particle layout");
}

std::string_view sweep_order_name(SweepOrder order) {
  switch (order) {
    case SweepOrder::colour_major: return "colour-major";
    case SweepOrder::part_major: return "part-major";
    case SweepOrder::automatic: return "auto";
  }
  return "unknown";
}

SweepOrder parse_sweep_order(std::string_view name) {
  constexpr SweepOrder kOrders[] = {SweepOrder::colour_major, SweepOrder::part_major,
                                    SweepOrder::automatic};
  return parse_named(name, kOrders, sweep_order_name, "sweep order");
}

}  // namespace tessera
