// Building the constraint graph: validate every index at the door, then fill the constraint →
// particle CSR; the particle → constraint direction waits until something reads it.
//
// Both passes run in parallel over fixed chunks of kChunkConstraints constraints of one group,
// so the work split, and with it every array, is the same for any thread count. Pass 1
// validates each constraint (range, a particle named twice) and counts the chunk's movable
// incidences; an exclusive scan over the chunks gives each its first output slot; pass 2
// writes offsets and particles. A group is read through an accessor specialised for its
// layout (interleaved, one array per slot, CSR) and, for fixed arities up to 5, for its
// arity, so the inner loops have constant trip counts. Input with an error is rare and its
// message must name the first bad constraint, so when pass 1 finds one the whole input is
// checked again in order, sequentially, by the code that throws.
//
// The particle → constraint lists are a counting sort over the constraint CSR in increasing
// constraint order, which makes them sorted without a sort and keeps every strategy
// deterministic.
#include <tessera/coloring/constraint_graph.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

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

ConstraintGroup ConstraintGroup::by_slot(std::string name,
                                         std::span<const std::span<const ParticleIndex>> slots) {
  if (slots.empty()) throw InvalidInput(group_label(name) + ": a group needs at least one slot");
  for (std::size_t k = 1; k < slots.size(); ++k)
    if (slots[k].size() != slots[0].size())
      throw InvalidInput(group_label(name) + ": slot " + std::to_string(k) + " holds " +
                         std::to_string(slots[k].size()) + " indices, slot 0 holds " +
                         std::to_string(slots[0].size()));
  ConstraintGroup group;
  group.name_ = std::move(name);
  group.arity_ = slots.size();
  group.slots_.assign(slots.begin(), slots.end());
  return group;
}

std::size_t ConstraintGroup::constraint_count() const {
  if (!slots_.empty()) return slots_[0].size();
  return arity_ != 0 ? indices_.size() / arity_ : offsets_.size() - 1;
}

std::size_t ConstraintGroup::incidence_count() const {
  return slots_.empty() ? indices_.size() : slots_.size() * slots_[0].size();
}

std::span<const ParticleIndex> ConstraintGroup::constraint(std::size_t i) const {
  if (!slots_.empty())
    throw InvalidInput(group_label(name_) +
                       ": a group built by slot has no contiguous constraints (use particle(i, k))");
  if (arity_ != 0) return indices_.subspan(i * arity_, arity_);
  return indices_.subspan(offsets_[i], offsets_[i + 1] - offsets_[i]);
}

std::size_t ConstraintGroup::constraint_size(std::size_t i) const {
  return arity_ != 0 ? arity_ : offsets_[i + 1] - offsets_[i];
}

ParticleIndex ConstraintGroup::particle(std::size_t i, std::size_t k) const {
  if (!slots_.empty()) return slots_[k][i];
  if (arity_ != 0) return indices_[i * arity_ + k];
  return indices_[offsets_[i] + k];
}

namespace {

// Accessors: constraint i's size and k-th particle for each group layout. Arity > 0 fixes the
// arity at compile time; 0 reads it at run time.
template <std::size_t Arity>
struct Interleaved {
  const ParticleIndex* indices;
  std::size_t arity;
  std::size_t size(std::size_t) const { return Arity != 0 ? Arity : arity; }
  ParticleIndex at(std::size_t i, std::size_t k) const { return indices[i * size(i) + k]; }
};

template <std::size_t Arity>
struct Slotted {
  const std::span<const ParticleIndex>* slots;
  std::size_t arity;
  std::size_t size(std::size_t) const { return Arity != 0 ? Arity : arity; }
  ParticleIndex at(std::size_t i, std::size_t k) const { return slots[k][i]; }
};

struct Clustered {
  const ParticleIndex* offsets;
  const ParticleIndex* indices;
  std::size_t size(std::size_t i) const { return offsets[i + 1] - offsets[i]; }
  ParticleIndex at(std::size_t i, std::size_t k) const { return indices[offsets[i] + k]; }
};

/// Calls f with the accessor fitting the group's layout and arity.
template <class F>
void with_accessor(const ConstraintGroup& group, F&& f) {
  const std::size_t arity = group.arity();
  if (group.is_by_slot()) {
    std::vector<std::span<const ParticleIndex>> slots(arity);
    for (std::size_t k = 0; k < arity; ++k) slots[k] = group.slot(k);
    switch (arity) {
      case 1: return f(Slotted<1>{slots.data(), 1});
      case 2: return f(Slotted<2>{slots.data(), 2});
      case 3: return f(Slotted<3>{slots.data(), 3});
      case 4: return f(Slotted<4>{slots.data(), 4});
      case 5: return f(Slotted<5>{slots.data(), 5});
      default: return f(Slotted<0>{slots.data(), arity});
    }
  }
  if (group.has_fixed_arity()) {
    const ParticleIndex* indices = group.indices().data();
    switch (arity) {
      case 1: return f(Interleaved<1>{indices, 1});
      case 2: return f(Interleaved<2>{indices, 2});
      case 3: return f(Interleaved<3>{indices, 3});
      case 4: return f(Interleaved<4>{indices, 4});
      case 5: return f(Interleaved<5>{indices, 5});
      default: return f(Interleaved<0>{indices, arity});
    }
  }
  f(Clustered{group.offsets().data(), group.indices().data()});
}

}  // namespace

namespace {

/// Constraints per chunk of the parallel passes: large enough that a task's overhead is
/// nothing, small enough that 2 threads stay balanced on a 0.4 M-constraint scene.
constexpr std::size_t kChunkConstraints = std::size_t(1) << 14;

/// Particles per chunk of the inverse-mass pass.
constexpr std::size_t kChunkParticles = std::size_t(1) << 16;

/// A run of constraints of one group: [begin, end) in the group, `first` the global id of begin.
struct Chunk {
  std::size_t group;
  std::size_t begin, end;
  ConstraintIndex first;
};

/// True when particle p appears twice among constraint i's first n particles.
template <class Accessor>
bool names_a_particle_twice(const Accessor& a, std::size_t i, std::size_t n,
                            std::vector<ParticleIndex>& scratch) {
  if (n <= 16) {
    for (std::size_t k = 1; k < n; ++k)
      for (std::size_t j = 0; j < k; ++j)
        if (a.at(i, j) == a.at(i, k)) return true;
    return false;
  }
  scratch.resize(n);
  for (std::size_t k = 0; k < n; ++k) scratch[k] = a.at(i, k);
  std::sort(scratch.begin(), scratch.end());
  return std::adjacent_find(scratch.begin(), scratch.end()) != scratch.end();
}

/// Pass 1 over one chunk: false if a constraint is invalid, else the movable incidences.
template <class Accessor>
bool count_chunk(const Accessor& a, const Chunk& chunk, const std::uint8_t* movable,
                 std::size_t particle_count, std::uint64_t& incidences) {
  std::vector<ParticleIndex> scratch;
  std::uint64_t total = 0;
  for (std::size_t i = chunk.begin; i < chunk.end; ++i) {
    const std::size_t n = a.size(i);
    for (std::size_t k = 0; k < n; ++k) {
      const ParticleIndex p = a.at(i, k);
      if (p >= particle_count) return false;
      total += movable[p];
    }
    if (names_a_particle_twice(a, i, n, scratch)) return false;
  }
  incidences = total;
  return true;
}

/// Pass 2 over one chunk: offsets[c + 1] and the movable particles from `write` on.
template <class Accessor>
void fill_chunk(const Accessor& a, const Chunk& chunk, const std::uint8_t* movable,
                std::uint32_t* offsets, ParticleIndex* particles, std::uint32_t write) {
  ConstraintIndex c = chunk.first;
  for (std::size_t i = chunk.begin; i < chunk.end; ++i, ++c) {
    const std::size_t n = a.size(i);
    for (std::size_t k = 0; k < n; ++k) {
      const ParticleIndex p = a.at(i, k);
      if (movable[p]) particles[write++] = p;
    }
    offsets[c + 1] = write;
  }
}

/// The validation of the sequential build, kept for its messages: throws InvalidInput naming
/// the first bad constraint in group order. Called only when the parallel pass found one.
void throw_first_invalid_constraint(std::span<const ConstraintGroup> groups,
                                    std::size_t particle_count) {
  std::vector<std::uint32_t> last_named_by(particle_count, std::numeric_limits<std::uint32_t>::max());
  std::uint32_t global = 0;
  for (const ConstraintGroup& group : groups) {
    for (std::size_t i = 0; i < group.constraint_count(); ++i, ++global) {
      for (std::size_t k = 0; k < group.constraint_size(i); ++k) {
        const ParticleIndex p = group.particle(i, k);
        if (p >= particle_count)
          throw InvalidInput(group_label(group.name()) + ", constraint " + std::to_string(i) +
                             ": particle index " + std::to_string(p) + " out of range [0, " +
                             std::to_string(particle_count) + ")");
        if (last_named_by[p] == global)
          throw InvalidInput(group_label(group.name()) + ", constraint " + std::to_string(i) +
                             ": particle " + std::to_string(p) + " appears twice");
        last_named_by[p] = global;
      }
    }
  }
  throw std::logic_error("constraint graph: the parallel check found an invalid constraint, the "
                         "sequential one none");
}

void throw_first_invalid_mass(std::span<const Real> inverse_masses) {
  for (std::size_t p = 0; p < inverse_masses.size(); ++p) {
    const Real w = inverse_masses[p];
    if (!std::isfinite(w))
      throw InvalidInput("particle " + std::to_string(p) + ": inverse mass is not finite");
    if (w < 0)
      throw InvalidInput("particle " + std::to_string(p) + ": inverse mass " + std::to_string(w) +
                         " is negative");
  }
  throw std::logic_error("constraint graph: the parallel check found an invalid inverse mass, "
                         "the sequential one none");
}

}  // namespace

ConstraintGraph::ConstraintGraph(std::span<const Real> inverse_masses,
                                 std::span<const ConstraintGroup> groups) {
  constexpr std::size_t kIndexLimit = std::numeric_limits<std::uint32_t>::max();
  const std::size_t particle_count = inverse_masses.size();
  if (particle_count > kIndexLimit)
    throw InvalidInput(std::to_string(particle_count) +
                       " particles do not fit a 32-bit particle index");

  // Movable flags, in parallel; a bad mass is looked for again in order for its message.
  movable_ = make_large_vector<std::uint8_t>(particle_count, 0);
  struct MassCheck {
    std::size_t movable = 0;
    bool valid = true;
  };
  const MassCheck masses = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, particle_count, kChunkParticles), MassCheck{},
      [&](const tbb::blocked_range<std::size_t>& range, MassCheck check) {
        for (std::size_t p = range.begin(); p < range.end(); ++p) {
          const Real w = inverse_masses[p];
          check.valid &= std::isfinite(w) && w >= 0;
          movable_[p] = w > 0 ? 1 : 0;
          check.movable += movable_[p];
        }
        return check;
      },
      [](MassCheck a, MassCheck b) { return MassCheck{a.movable + b.movable, a.valid && b.valid}; },
      tbb::simple_partitioner());
  if (!masses.valid) throw_first_invalid_mass(inverse_masses);
  movable_count_ = masses.movable;

  std::size_t total_constraints = 0, total_indices = 0;
  for (const ConstraintGroup& group : groups) {
    total_constraints += group.constraint_count();
    total_indices += group.incidence_count();
  }
  if (total_constraints >= kIndexLimit || total_indices >= kIndexLimit)
    throw InvalidInput(std::to_string(total_constraints) + " constraints with " +
                       std::to_string(total_indices) +
                       " particle indices do not fit 32-bit constraint and offset indices");

  std::vector<Chunk> chunks;
  ConstraintIndex global = 0;
  group_first_.reserve(groups.size() + 1);
  for (std::size_t g = 0; g < groups.size(); ++g) {
    group_names_.push_back(groups[g].name());
    group_first_.push_back(global);
    const std::size_t count = groups[g].constraint_count();
    for (std::size_t begin = 0; begin < count; begin += kChunkConstraints) {
      const std::size_t end = std::min(count, begin + kChunkConstraints);
      chunks.push_back({g, begin, end, static_cast<ConstraintIndex>(global + begin)});
    }
    global += static_cast<ConstraintIndex>(count);
  }
  group_first_.push_back(global);

  // Pass 1: validate and count each chunk's movable incidences.
  const std::uint8_t* movable = movable_.data();
  std::vector<std::uint64_t> chunk_start(chunks.size() + 1, 0);
  std::vector<std::uint8_t> chunk_valid(chunks.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks.size(), 1),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t j = range.begin(); j < range.end(); ++j)
                        with_accessor(groups[chunks[j].group], [&](const auto& accessor) {
                          chunk_valid[j] = count_chunk(accessor, chunks[j], movable, particle_count,
                                                       chunk_start[j + 1]);
                        });
                    },
                    tbb::simple_partitioner());
  if (std::find(chunk_valid.begin(), chunk_valid.end(), 0) != chunk_valid.end())
    throw_first_invalid_constraint(groups, particle_count);
  for (std::size_t j = 0; j < chunks.size(); ++j) chunk_start[j + 1] += chunk_start[j];

  // Pass 2: offsets and particles, each chunk from its first slot.
  constraint_offsets_ = make_large_vector<std::uint32_t>(total_constraints + 1, 0);
  const std::size_t incidences = chunk_start.back();
  constraint_particles_ = make_large_vector<ParticleIndex>(incidences);
  std::uint32_t* offsets = constraint_offsets_.data();
  ParticleIndex* particles = constraint_particles_.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks.size(), 1),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t j = range.begin(); j < range.end(); ++j)
                        with_accessor(groups[chunks[j].group], [&](const auto& accessor) {
                          fill_chunk(accessor, chunks[j], movable, offsets, particles,
                                     static_cast<std::uint32_t>(chunk_start[j]));
                        });
                    },
                    tbb::simple_partitioner());
}

const detail::ParticleIncidence& ConstraintGraph::particle_incidence() const {
  return particle_incidence_.get([&] {
    // Counting sort of the constraint CSR by particle, in increasing constraint order.
    detail::ParticleIncidence incidence;
    const std::size_t particle_count = movable_.size();
    incidence.offsets = make_large_vector<std::uint32_t>(particle_count + 1, 0);
    for (ParticleIndex p : constraint_particles_) ++incidence.offsets[p + 1];
    for (std::size_t p = 0; p < particle_count; ++p) incidence.offsets[p + 1] += incidence.offsets[p];
    incidence.constraints = make_large_vector<ConstraintIndex>(constraint_particles_.size());
    std::vector<std::uint32_t> cursor = make_large_vector<std::uint32_t>(particle_count);
    std::copy(incidence.offsets.begin(), incidence.offsets.end() - 1, cursor.begin());
    const std::size_t count = constraint_count();
    for (std::size_t c = 0; c < count; ++c)
      for (std::uint32_t j = constraint_offsets_[c]; j < constraint_offsets_[c + 1]; ++j)
        incidence.constraints[cursor[constraint_particles_[j]]++] = static_cast<ConstraintIndex>(c);
    return incidence;
  });
}

std::size_t ConstraintGraph::colour_lower_bound() const {
  return lower_bound_.get([&]() -> std::size_t {
    if (constraint_count() == 0) return 0;
    // A histogram of the incidences (the particle lists themselves are not needed).
    std::vector<std::uint32_t> degree = make_large_vector<std::uint32_t>(movable_.size(), 0);
    for (ParticleIndex p : constraint_particles_) ++degree[p];
    const std::uint32_t largest = degree.empty() ? 0 : *std::max_element(degree.begin(), degree.end());
    return std::max<std::size_t>(largest, 1);
  });
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
