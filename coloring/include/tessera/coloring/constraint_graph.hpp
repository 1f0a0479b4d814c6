// The constraint graph: which movable particles each constraint touches, and which
// constraints touch each movable particle. Two constraints conflict (must get different
// colours) exactly when they share a movable particle; static particles (inverse mass 0)
// are left out of the graph, so constraints that meet only at pinned particles never
// conflict.
//
// Layout: two CSR arrays, constraint → movable particles and particle → constraints. Both are
// built by counting sorts, so construction is linear in the number of incidences and the
// lists are in a deterministic order: a constraint's particles in the order the constraint
// names them, a particle's constraints by increasing constraint id. Strategies never build
// the constraint-to-constraint adjacency (it is ~degree times larger); they walk the two CSR
// arrays instead.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <tessera/core/indices.hpp>
#include <tessera/core/real.hpp>

namespace tessera {

// ParticleIndex (a particle as the constraint groups name it) and ConstraintIndex (a global
// constraint id: the groups' constraints concatenated in group order) come from core.

/// A named view of one family's particle indices. It does not own the indices; they must
/// outlive the ConstraintGraph's construction (the graph copies what it needs).
class ConstraintGroup {
 public:
  /// Constraints of `arity` particles each, stored back to back in `indices` (indices.size() must
  /// be a multiple of arity): an edge 2, a triangle 3, a tetrahedron or bending stencil 4.
  static ConstraintGroup fixed_arity(std::string name, std::size_t arity,
                                     std::span<const ParticleIndex> indices);
  /// Constraints of varying size in CSR form: constraint i names
  /// indices[offsets[i], offsets[i+1]). offsets has one entry more than there are
  /// constraints, starts at 0, never decreases and ends at indices.size() (shape matching
  /// clusters, long-range attachments...).
  static ConstraintGroup variable_size(std::string name, std::span<const ParticleIndex> offsets,
                                       std::span<const ParticleIndex> indices);

  const std::string& name() const { return name_; }
  std::size_t constraint_count() const;
  /// The particles of the group's i-th constraint (i < constraint_count()).
  std::span<const ParticleIndex> constraint(std::size_t i) const;
  /// True for fixed-arity groups.
  bool has_fixed_arity() const { return arity_ != 0; }
  std::size_t arity() const { return arity_; }
  std::size_t incidence_count() const { return indices_.size(); }

 private:
  ConstraintGroup() = default;
  std::string name_;
  std::size_t arity_ = 0;  // 0 for variable-size groups
  std::span<const ParticleIndex> offsets_;
  std::span<const ParticleIndex> indices_;
};

/// Constraint ↔ movable-particle incidence of a whole model.
class ConstraintGraph {
 public:
  /// An empty graph: no particles, no constraints.
  ConstraintGraph() = default;

  /// Builds the graph of `groups` over particles with the given inverse masses. Throws
  /// tessera::InvalidInput (naming the group, the constraint's position in its group and the
  /// problem) for: a negative or non-finite inverse mass, an index out of range, a particle
  /// named twice in one constraint, malformed group shape (indices not a multiple of the
  /// arity, bad CSR offsets), more constraints or incidences than a 32-bit index holds.
  ConstraintGraph(std::span<const Real> inverse_masses, std::span<const ConstraintGroup> groups);

  std::size_t particle_count() const { return movable_.size(); }
  std::size_t constraint_count() const { return constraint_offsets_.empty() ? 0 : constraint_offsets_.size() - 1; }
  /// Number of (constraint, movable particle) pairs.
  std::size_t incidence_count() const { return constraint_particles_.size(); }
  bool is_movable(ParticleIndex p) const { return movable_[p] != 0; }
  std::size_t movable_particle_count() const { return movable_count_; }

  /// The movable particles of constraint c, in the order the constraint names them.
  std::span<const ParticleIndex> particles_of(ConstraintIndex c) const {
    return {constraint_particles_.data() + constraint_offsets_[c],
            constraint_particles_.data() + constraint_offsets_[c + 1]};
  }
  /// The constraints that touch particle p, by increasing id (empty for static particles).
  std::span<const ConstraintIndex> constraints_of(ParticleIndex p) const {
    return {particle_constraints_.data() + particle_offsets_[p],
            particle_constraints_.data() + particle_offsets_[p + 1]};
  }
  std::size_t particle_degree(ParticleIndex p) const {
    return particle_offsets_[p + 1] - particle_offsets_[p];
  }

  /// The most constraints that meet at one movable particle. They all conflict pairwise, so
  /// no valid colouring has fewer colours (0 when there are no constraints, 1 when no
  /// constraint touches a movable particle).
  std::size_t colour_lower_bound() const { return lower_bound_; }

  /// Raw CSR arrays, for strategies that stream over them.
  std::span<const std::uint32_t> constraint_offsets() const { return constraint_offsets_; }
  std::span<const ParticleIndex> constraint_particles() const { return constraint_particles_; }
  std::span<const std::uint32_t> particle_offsets() const { return particle_offsets_; }
  std::span<const ConstraintIndex> particle_constraints() const { return particle_constraints_; }

  /// Group bookkeeping: names and the global id of each group's first constraint, so a
  /// global constraint id maps back to (group, position) for messages and schedules.
  std::size_t group_count() const { return group_names_.size(); }
  const std::string& group_name(std::size_t g) const { return group_names_[g]; }
  ConstraintIndex group_first_constraint(std::size_t g) const { return group_first_[g]; }
  /// The group holding constraint c (binary search over the group starts).
  std::size_t group_of(ConstraintIndex c) const;
  /// "constraint group '<family>', constraint 17" for global id c.
  std::string describe_constraint(ConstraintIndex c) const;

 private:
  std::vector<std::uint8_t> movable_;
  std::size_t movable_count_ = 0;
  std::vector<std::uint32_t> constraint_offsets_;
  std::vector<ParticleIndex> constraint_particles_;
  std::vector<std::uint32_t> particle_offsets_;
  std::vector<ConstraintIndex> particle_constraints_;
  std::size_t lower_bound_ = 0;
  std::vector<std::string> group_names_;
  std::vector<ConstraintIndex> group_first_;  // group_count() + 1 entries
};

}  // namespace tessera
