// The constraint graph: which movable particles each constraint touches, and which
// constraints touch each movable particle. Two constraints conflict (must get different
// colours) exactly when they share a movable particle; static particles (inverse mass 0)
// are left out of the graph, so constraints that meet only at pinned particles never
// conflict.
//
// Layout: two CSR arrays, constraint → movable particles and particle → constraints, the lists
// in a deterministic order: a constraint's particles in the order the constraint names them,
// a particle's constraints by increasing constraint id. Strategies never build the
// constraint-to-constraint adjacency (it is ~degree times larger); they walk the two CSR
// arrays instead.
//
// Start-up cost. The constructor validates the input and builds only the first direction, in
// parallel over fixed chunks of constraints (the same arrays for any thread count). The
// particle → constraint direction and the lower bound are built on first use: first-fit
// strategies (greedy, stencil) colour with per-particle colour sets and never read them, and
// on a 6.3 M-constraint cloth that direction cost as much as the rest of the graph.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
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
  /// Constraints of slots.size() particles each, one array per slot (structure of arrays, as
  /// the model's batches store them): constraint i names slots[0][i], slots[1][i], ... Every
  /// slot must hold the same number of indices, and there must be at least one slot.
  static ConstraintGroup by_slot(std::string name,
                                 std::span<const std::span<const ParticleIndex>> slots);

  const std::string& name() const { return name_; }
  std::size_t constraint_count() const;
  /// The particles of the group's i-th constraint (i < constraint_count()). Groups built
  /// by_slot do not store a constraint's particles together: use particle(i, k) there (this
  /// throws tessera::InvalidInput for them).
  std::span<const ParticleIndex> constraint(std::size_t i) const;
  /// Number of particles of constraint i, and its k-th particle (k < constraint_size(i)), for
  /// every kind of group.
  std::size_t constraint_size(std::size_t i) const;
  ParticleIndex particle(std::size_t i, std::size_t k) const;
  /// True for fixed-arity groups (by_slot groups included).
  bool has_fixed_arity() const { return arity_ != 0; }
  /// True for groups built by_slot.
  bool is_by_slot() const { return !slots_.empty(); }
  std::size_t arity() const { return arity_; }
  std::size_t incidence_count() const;
  /// The raw arrays: the indices of a fixed-arity or variable-size group, the offsets of a
  /// variable-size one (empty where the layout has none), slot k of a by_slot group.
  std::span<const ParticleIndex> indices() const { return indices_; }
  std::span<const ParticleIndex> offsets() const { return offsets_; }
  std::span<const ParticleIndex> slot(std::size_t k) const { return slots_[k]; }

 private:
  ConstraintGroup() = default;
  std::string name_;
  std::size_t arity_ = 0;  // 0 for variable-size groups
  std::span<const ParticleIndex> offsets_;
  std::span<const ParticleIndex> indices_;
  std::vector<std::span<const ParticleIndex>> slots_;  // by_slot groups only
};

namespace detail {

/// The particle → constraint direction of a graph (see the file comment), built once on first
/// use and then shared, immutable, by copies of the graph.
struct ParticleIncidence {
  std::vector<std::uint32_t> offsets;
  std::vector<ConstraintIndex> constraints;
};

/// A value computed on first use by whichever thread asks first; the others wait for it.
/// Copies share the computed value (it is immutable); a copy made before the first use
/// computes its own.
template <class T>
class Lazy {
 public:
  Lazy() = default;
  Lazy(const Lazy& other) : value_(other.snapshot()), ready_(value_.get()) {}
  Lazy& operator=(const Lazy& other) {
    if (this != &other) reset(other.snapshot());
    return *this;
  }
  Lazy(Lazy&& other) noexcept : Lazy(static_cast<const Lazy&>(other)) {}
  Lazy& operator=(Lazy&& other) noexcept { return *this = static_cast<const Lazy&>(other); }

  template <class Make>
  const T& get(Make&& make) const {
    if (const T* ready = ready_.load(std::memory_order_acquire)) return *ready;
    std::lock_guard lock(*mutex_);
    if (!value_) {
      value_ = std::make_shared<const T>(make());
      ready_.store(value_.get(), std::memory_order_release);
    }
    return *value_;
  }

 private:
  std::shared_ptr<const T> snapshot() const {
    std::lock_guard lock(*mutex_);
    return value_;
  }
  void reset(std::shared_ptr<const T> value) {
    std::lock_guard lock(*mutex_);
    value_ = std::move(value);
    ready_.store(value_.get(), std::memory_order_release);
  }

  std::unique_ptr<std::mutex> mutex_ = std::make_unique<std::mutex>();
  mutable std::shared_ptr<const T> value_;
  mutable std::atomic<const T*> ready_{nullptr};
};

}  // namespace detail

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
  /// The first call of this or of particle_degree, particle_offsets, particle_constraints
  /// builds that direction (thread-safe); a loop calling it often can take the raw arrays once.
  std::span<const ConstraintIndex> constraints_of(ParticleIndex p) const {
    const detail::ParticleIncidence& incidence = particle_incidence();
    return {incidence.constraints.data() + incidence.offsets[p],
            incidence.constraints.data() + incidence.offsets[p + 1]};
  }
  std::size_t particle_degree(ParticleIndex p) const {
    const detail::ParticleIncidence& incidence = particle_incidence();
    return incidence.offsets[p + 1] - incidence.offsets[p];
  }

  /// The most constraints that meet at one movable particle. They all conflict pairwise, so
  /// no valid colouring has fewer colours (0 when there are no constraints, 1 when no
  /// constraint touches a movable particle). Counted on first use.
  std::size_t colour_lower_bound() const;

  /// Raw CSR arrays, for strategies that stream over them.
  std::span<const std::uint32_t> constraint_offsets() const { return constraint_offsets_; }
  std::span<const ParticleIndex> constraint_particles() const { return constraint_particles_; }
  std::span<const std::uint32_t> particle_offsets() const { return particle_incidence().offsets; }
  std::span<const ConstraintIndex> particle_constraints() const {
    return particle_incidence().constraints;
  }

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
  const detail::ParticleIncidence& particle_incidence() const;
  // Built on first use (see the file comment).
  detail::Lazy<detail::ParticleIncidence> particle_incidence_;
  detail::Lazy<std::size_t> lower_bound_;
  std::vector<std::string> group_names_;
  std::vector<ConstraintIndex> group_first_;  // group_count() + 1 entries
};

}  // namespace tessera
