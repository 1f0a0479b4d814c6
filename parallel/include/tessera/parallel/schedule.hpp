// The schedule: a model's constraints laid out colour-major for the solver, built once.
//
//   user batches (input order)           scheduled batches (one per family)
//   distance: d0 d1 d2 d3 d4 ...   ──►   | colour 0 ......|pad| colour 1 ...|pad| colour 2 ..
//                                          ▲ every colour starts on a kMaxLanes boundary, so
//                                            work blocks of one colour never share a vector
//   a colour's phase = its blocks of every family: [family, begin, end) ranges of at most
//   block_size constraints, run by parallel_for; the phases run one after another.
//
//   Jacobi set (mode jacobi, and the small tail colours of mode hybrid): every slot of every
//   constraint has an "incidence", a private place for its result, so all the constraints
//   can be projected at once from the same positions:
//     project:   the batched kernels gather the particles as usual but store each corrected
//                position in its slot's incidence (ParticleArrays::corrected_*: whole-vector
//                stores, slot k of constraint j at base + k·stride + j) instead of scattering
//     reduce:    particle p += ω · Σ (incidence − p) / count, over p's incidences in a fixed
//                order (CSR), so the sum is the same for any thread count (no atomics).
//
// Particles are renumbered as the colouring asks (its locality order), constraints follow
// the colouring's order inside each colour; locate() and the particle maps lead back to the
// user's numbering.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include <tessera/coloring/colouring.hpp>
#include <tessera/core/aligned_vector.hpp>
#include <tessera/parallel/model.hpp>

namespace tessera {

/// How the solver projects the constraints each iteration.
enum class SolverMode : std::uint8_t {
  /// Coloured Gauss–Seidel: colour after colour, each colour in parallel.
  gs,
  /// Jacobi with constraint averaging: every constraint from the same positions, then
  /// x += ω · (sum of corrections) / (count) per particle.
  jacobi,
  /// gs for the colours with at least hybrid_threshold constraints, one Jacobi phase for the
  /// smaller ones after them.
  hybrid,
  /// The classic PBD loop and reference: one thread, constraints in input order (family by
  /// family), the scalar API per constraint; no colouring.
  sequential,
};

/// "gs", "jacobi", "hybrid", "sequential".
std::string_view solver_mode_name(SolverMode mode);
/// The mode of that name; throws InvalidInput listing the names for any other.
SolverMode parse_solver_mode(std::string_view name);

/// Constraints per parallel work item when nothing else is said (see solver.hpp for the
/// measurement behind it).
inline constexpr std::size_t kDefaultBlockSize = 512;
/// hybrid: colours with fewer constraints than this go to the Jacobi phase.
inline constexpr std::size_t kDefaultHybridThreshold = 1024;

struct ScheduleOptions {
  SolverMode mode = SolverMode::gs;
  /// Constraints per work block at most, rounded up to a multiple of kMaxLanes.
  std::size_t block_size = kDefaultBlockSize;
  std::size_t hybrid_threshold = kDefaultHybridThreshold;
  /// Threads the blocks are for: a colour is cut into smaller blocks (down to kMaxLanes) when
  /// it has fewer than 4 per thread of block_size. Any value gives the same results; 0 means
  /// every hardware thread (worker_threads).
  std::size_t threads = 1;
};

/// Constraints [begin, end) of one family's scheduled batch: one unit of parallel work.
struct ScheduleBlock {
  ConstraintFamily family;
  std::uint32_t begin;
  std::uint32_t end;
};

/// Where a user's constraint went: a slot of the coloured batches or of the Jacobi set.
struct ConstraintLocation {
  bool in_jacobi_set;
  ConstraintFamily family;
  std::uint32_t slot;
};

/// The constraints projected together from private particle copies (see the diagram above).
struct JacobiSet {
  /// The constraints, with renumbered particles like the coloured batches.
  ConstraintSets constraints;
  /// Where each family's incidences start, and its slot stride (see the diagram above).
  std::array<std::size_t, kConstraintFamilyCount> incidence_base{};
  std::array<std::size_t, kConstraintFamilyCount> incidence_stride{};
  /// The (renumbered) particle of every incidence; padding incidences name particle 0 and
  /// belong to no particle's list.
  AlignedVector<ParticleIndex> incidence_particle;
  std::size_t incidence_count = 0;  // including padding
  /// Movable particles that have incidences, ascending, and their incidences (CSR).
  std::vector<ParticleIndex> particles;
  std::vector<std::uint32_t> particle_offsets;
  std::vector<std::uint32_t> particle_incidences;
  /// Per family with XPBD multipliers, per constraint: 1 / (the mean number of Jacobi
  /// constraints at its movable particles). A constraint's position corrections reach its
  /// particles divided by their counts, so its λ may only grow by the same share, or the
  /// compliance term α̃λ would see forces the positions never felt (the material would act
  /// several times softer); the solver scales Δλ by ω times this.
  std::array<AlignedVector<Real>, kConstraintFamilyCount> lambda_share;
  /// The whole set split into work blocks.
  std::vector<ScheduleBlock> blocks;
  std::size_t constraint_count = 0;
};

class Schedule {
 public:
  Schedule() = default;
  /// Lays out `model`'s constraints. colouring must colour constraint_graph(model) (same
  /// constraint count; InvalidInput otherwise) unless options.mode is sequential, where it is
  /// ignored and may be null.
  Schedule(const Model& model, const Colouring* colouring, const ScheduleOptions& options);

  SolverMode mode() const { return options_.mode; }
  const ScheduleOptions& options() const { return options_; }

  /// The coloured batches (mode sequential: the model's batches, unchanged).
  ConstraintSets& coloured() { return coloured_; }
  const ConstraintSets& coloured() const { return coloured_; }
  /// One Gauss–Seidel phase per coloured colour, in colouring order.
  std::size_t phase_count() const { return phase_offsets_.empty() ? 0 : phase_offsets_.size() - 1; }
  std::span<const ScheduleBlock> phase_blocks(std::size_t phase) const {
    return {blocks_.data() + phase_offsets_[phase], blocks_.data() + phase_offsets_[phase + 1]};
  }
  /// Constraints of each phase.
  std::span<const std::size_t> phase_sizes() const { return phase_sizes_; }
  /// The ranges of real (not padding) constraints of a family in coloured(), ascending.
  std::span<const ScheduleBlock> coloured_ranges(ConstraintFamily family) const {
    return ranges_[std::size_t(family)];
  }

  JacobiSet& jacobi() { return jacobi_; }
  const JacobiSet& jacobi() const { return jacobi_; }

  /// Particle renumbering (both empty when the user's numbering is kept): new_to_old[n] is
  /// the user's index of scheduled particle n.
  std::span<const ParticleIndex> particle_new_to_old() const { return new_to_old_; }
  std::span<const ParticleIndex> particle_old_to_new() const { return old_to_new_; }
  ParticleIndex scheduled_particle(ParticleIndex user) const {
    return old_to_new_.empty() ? user : old_to_new_[user];
  }
  ParticleIndex user_particle(ParticleIndex scheduled) const {
    return new_to_old_.empty() ? scheduled : new_to_old_[scheduled];
  }

  std::size_t constraint_count() const { return location_.size(); }
  /// Where the user's constraint (global id, see Model) was placed.
  ConstraintLocation locate(ConstraintIndex user_constraint) const;

 private:
  ScheduleOptions options_;
  ConstraintSets coloured_;
  std::vector<ScheduleBlock> blocks_;
  std::vector<std::size_t> phase_offsets_;
  std::vector<std::size_t> phase_sizes_;
  std::array<std::vector<ScheduleBlock>, kConstraintFamilyCount> ranges_;
  JacobiSet jacobi_;
  std::vector<ParticleIndex> new_to_old_, old_to_new_;
  /// Per global constraint id: the slot, with kJacobiBit set for the Jacobi set.
  std::vector<std::uint32_t> location_;
  std::array<ConstraintIndex, kConstraintFamilyCount + 1> family_first_{};
};

}  // namespace tessera
