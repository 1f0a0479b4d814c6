// Building the constraint graph: validate every index at the door, then two counting sorts.
//
// Pass 1 walks each constraint once, checking ranges and duplicates with a per-particle stamp
// (the id of the last constraint that named the particle, so the check is O(size) for any
// constraint size, clusters included) and counting movable incidences per constraint and per
// particle. Pass 2 fills both CSR arrays. Filling particle → constraint lists in increasing
// constraint order makes them sorted without a sort, which keeps every strategy deterministic.
#include <tessera/coloring/constraint_graph.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

#include <tessera/core/error.hpp>
#include <tessera/core/huge_pages.hpp>

namespace tessera {
namespace {

std::string group_label(const std::string& name) { return "constraint group '" + name + "'"; }

}  // namespace

ConstraintGroup ConstraintGroup::fixed_arity(std::string name, std::size_t arity,
                                             std::span<const ParticleIndex> indices) {
  if (arity == 0) throw InvalidInput(group_label(name) + ": arity must be at least 1");
  if (indices.size() % arity != 0)
    throw InvalidInput(group_label(name) + ": " + std::to_string(indices.size()) +
                       " indices are not a whole number of constraints of arity " +
                       std::to_string(arity));
  ConstraintGroup group;
  group.name_ = std::move(name);
  group.arity_ = arity;
  group.indices_ = indices;
  return group;
}

ConstraintGroup ConstraintGroup::variable_size(std::string name,
                                               std::span<const ParticleIndex> offsets,
                                               std::span<const ParticleIndex> indices) {
  if (offsets.empty())
    throw InvalidInput(group_label(name) +
                       ": offsets must have one entry more than there are constraints");
  if (offsets.front() != 0)
    throw InvalidInput(group_label(name) + ": offsets must start at 0, not " +
                       std::to_string(offsets.front()));
  for (std::size_t i = 0; i + 1 < offsets.size(); ++i)
    if (offsets[i + 1] < offsets[i])
      throw InvalidInput(group_label(name) + ", constraint " + std::to_string(i) +
                         ": offsets decrease (" + std::to_string(offsets[i]) + " then " +
                         std::to_string(offsets[i + 1]) + ")");
  if (offsets.back() != indices.size())
    throw InvalidInput(group_label(name) + ": offsets end at " + std::to_string(offsets.back()) +
                       " but there are " + std::to_string(indices.size()) + " indices");
  ConstraintGroup group;
  group.name_ = std::move(name);
  group.offsets_ = offsets;
  group.indices_ = indices;
  return group;
}

std::size_t ConstraintGroup::constraint_count() const {
  return arity_ != 0 ? indices_.size() / arity_ : offsets_.size() - 1;
}

std::span<const ParticleIndex> ConstraintGroup::constraint(std::size_t i) const {
  if (arity_ != 0) return indices_.subspan(i * arity_, arity_);
  return indices_.subspan(offsets_[i], offsets_[i + 1] - offsets_[i]);
}

ConstraintGraph::ConstraintGraph(std::span<const Real> inverse_masses,
                                 std::span<const ConstraintGroup> groups) {
  constexpr std::size_t kIndexLimit = std::numeric_limits<std::uint32_t>::max();
  const std::size_t particle_count = inverse_masses.size();
  if (particle_count > kIndexLimit)
    throw InvalidInput(std::to_string(particle_count) +
                       " particles do not fit a 32-bit particle index");

  movable_.resize(particle_count);
  for (std::size_t p = 0; p < particle_count; ++p) {
    const Real w = inverse_masses[p];
    if (!std::isfinite(w))
      throw InvalidInput("particle " + std::to_string(p) + ": inverse mass is not finite");
    if (w < 0)
      throw InvalidInput("particle " + std::to_string(p) + ": inverse mass " + std::to_string(w) +
                         " is negative");
    movable_[p] = w > 0 ? 1 : 0;
    movable_count_ += movable_[p];
  }

  std::size_t total_constraints = 0, total_indices = 0;
  for (const ConstraintGroup& group : groups) {
    total_constraints += group.constraint_count();
    total_indices += group.incidence_count();
  }
  if (total_constraints >= kIndexLimit || total_indices >= kIndexLimit)
    throw InvalidInput(std::to_string(total_constraints) + " constraints with " +
                       std::to_string(total_indices) +
                       " particle indices do not fit 32-bit constraint and offset indices");

  // Pass 1: validate, count movable incidences per constraint and per particle.
  constraint_offsets_ = make_large_vector<std::uint32_t>(total_constraints + 1, 0);
  particle_offsets_.assign(particle_count + 1, 0);
  std::vector<std::uint32_t> last_named_by(particle_count, std::numeric_limits<std::uint32_t>::max());
  ConstraintIndex global = 0;
  group_first_.reserve(groups.size() + 1);
  for (const ConstraintGroup& group : groups) {
    group_names_.push_back(group.name());
    group_first_.push_back(global);
    for (std::size_t i = 0; i < group.constraint_count(); ++i, ++global) {
      std::uint32_t movable_in_constraint = 0;
      for (ParticleIndex p : group.constraint(i)) {
        if (p >= particle_count)
          throw InvalidInput(group_label(group.name()) + ", constraint " + std::to_string(i) +
                             ": particle index " + std::to_string(p) + " out of range [0, " +
                             std::to_string(particle_count) + ")");
        if (last_named_by[p] == global)
          throw InvalidInput(group_label(group.name()) + ", constraint " + std::to_string(i) +
                             ": particle " + std::to_string(p) + " appears twice");
        last_named_by[p] = global;
        if (movable_[p]) {
          ++movable_in_constraint;
          ++particle_offsets_[p + 1];
        }
      }
      constraint_offsets_[global + 1] = movable_in_constraint;
    }
  }
  group_first_.push_back(global);

  for (std::size_t c = 0; c < total_constraints; ++c) constraint_offsets_[c + 1] += constraint_offsets_[c];
  for (std::size_t p = 0; p < particle_count; ++p) {
    lower_bound_ = std::max<std::size_t>(lower_bound_, particle_offsets_[p + 1]);
    particle_offsets_[p + 1] += particle_offsets_[p];
  }
  if (total_constraints > 0) lower_bound_ = std::max<std::size_t>(lower_bound_, 1);

  // Pass 2: fill both directions in constraint order.
  constraint_particles_ = make_large_vector<ParticleIndex>(constraint_offsets_.back());
  particle_constraints_ = make_large_vector<ConstraintIndex>(particle_offsets_.back());
  std::vector<std::uint32_t> particle_cursor(particle_offsets_.begin(), particle_offsets_.end() - 1);
  global = 0;
  std::uint32_t write = 0;
  for (const ConstraintGroup& group : groups) {
    for (std::size_t i = 0; i < group.constraint_count(); ++i, ++global) {
      for (ParticleIndex p : group.constraint(i)) {
        if (!movable_[p]) continue;
        constraint_particles_[write++] = p;
        particle_constraints_[particle_cursor[p]++] = global;
      }
    }
  }
}

std::size_t ConstraintGraph::group_of(ConstraintIndex c) const {
  // group_first_ is non-decreasing; the owning group is the last one starting at or before c
  // among groups that are not empty.
  const auto it = std::upper_bound(group_first_.begin(), group_first_.end() - 1, c);
  return static_cast<std::size_t>(it - group_first_.begin()) - 1;
}

std::string ConstraintGraph::describe_constraint(ConstraintIndex c) const {
  const std::size_t g = group_of(c);
  return group_label(group_names_[g]) + ", constraint " + std::to_string(c - group_first_[g]);
}

}  // namespace tessera
