// The schedule: a model's constraints laid out colour-major for the solver, built once.
//
//   user batches (input order)           scheduled batches (one per family)
//   family f: c0 c1 c2 c3 c4 ...   ──►   | colour 0 ......|pad| colour 1 ...|pad| colour 2 ..
//                                          ▲ every colour starts on a kMaxLanes boundary, so
//                                            work blocks of one colour never share a vector
//   a colour's phase = one block per family, [family, begin, end); the solver cuts the phase
//   into one share per thread, the same slice of every family (phase_region.hpp), and the
//   phases run one after another. block_size cuts only Jacobi sets (the schedule's, the
//   dynamic constraints', the contacts'), whose blocks parallel_for takes one by one.
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
// the colouring's order inside each colour; the remap tables (one old→new table per family),
// locate() and the particle maps lead back to the user's numbering.
//
// The schedule also builds the mode's stage list (stage.hpp): what one iteration runs.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include <tessera/coloring/colouring.hpp>
#include <tessera/coloring/model_graph.hpp>
#include <tessera/core/aligned_vector.hpp>
#include <tessera/core/model.hpp>
#include <tessera/parallel/solver_mode.hpp>
#include <tessera/parallel/stage.hpp>

namespace tessera {

/// Constraints per parallel work block of a Jacobi set when nothing else is said (README,
/// `solver/block_size`).
inline constexpr std::size_t kDefaultBlockSize = 512;
/// Splitting a Jacobi set into more blocks for more threads stops at blocks of this many
/// constraints (or block_size, if smaller): a smaller block costs a task more than its
/// projections. Measured side by side on 2 threads (`tessera run`, stepping seconds, before
/// -> after, when the floor was one vector of 16): the pile (8 FEM blocks, 1,152 particles,
/// contact colours of a few dozen) 1.22 -> 0.84 s, faster than its 1 thread (0.86 s) where
/// it had been slower; the 10×10×40 bar 0.36 -> 0.31 s; the default cloth 1.84 -> 1.66 s;
/// the same state hashes (blocks never change a result).
inline constexpr std::size_t kSmallestSplitBlock = 256;
/// hybrid: colours with fewer constraints than this go to the Jacobi phase.
inline constexpr std::size_t kDefaultHybridThreshold = 1024;

struct ScheduleOptions {
  SolverMode mode = SolverMode::gs;
  /// Constraints per work block of a Jacobi set at most, rounded up to a multiple of
  /// kMaxLanes. (A colour phase is one block per family: the solver cuts it per thread.)
  std::size_t block_size = kDefaultBlockSize;
  std::size_t hybrid_threshold = kDefaultHybridThreshold;
  /// Threads the blocks are for: a Jacobi set is cut into smaller blocks
  /// (down to kSmallestSplitBlock) when it has fewer than 4 per thread of block_size. Any value gives the same results; 0 means
  /// every hardware thread (worker_threads).
  std::size_t threads = 1;
  /// Mode sequential: the order of the sweep.
  SequentialOrder sequential_order = SequentialOrder::groups;
  /// Modes gs and hybrid: colour after colour, or part after part (InvalidInput in another
  /// mode), or automatic, which the schedule resolves to one of them (options() holds the
  /// choice; in another mode colour_major). Part after part takes the colouring's parts
  /// (Colouring::has_parts), or, for a colouring without parts, runs of particles_per_part
  /// movable particles of the schedule's particle order (0: kDefaultParticlesPerRun; any other
  /// value with a colour-major sweep, a colouring with parts or a mode other than gs and
  /// hybrid is InvalidInput, as it would size nothing; with automatic it sizes the runs the
  /// choice counts, whichever order it makes).
  SweepOrder sweep_order = SweepOrder::automatic;
  std::size_t particles_per_part = 0;
};

/// Constraints [begin, end) of one family's scheduled batch: a colour's family (cut per
/// thread by the solver) or one unit of a Jacobi set's parallel work.
struct ScheduleBlock {
  ConstraintFamily family;
  std::uint32_t begin;
  std::uint32_t end;
  friend bool operator==(const ScheduleBlock&, const ScheduleBlock&) = default;
};

/// Where one constraint of a family went: the entry of the family's old→new table.
struct ConstraintSlot {
  bool in_jacobi_set;
  std::uint32_t slot;
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
  /// ignored and may be null (the groups order colours the graph itself, greedily).
  Schedule(const Model& model, const Colouring* colouring, const ScheduleOptions& options);

  SolverMode mode() const { return options_.mode; }
  const ScheduleOptions& options() const { return options_; }

  /// What one iteration runs, and what runs after each velocity update (stage.hpp), for the
  /// schedule's own constraints (the solver adds its dynamic ones).
  std::span<const Stage> iteration_stages() const { return iteration_stages_; }
  std::span<const Stage> velocity_stages() const { return velocity_stages_; }
  /// The blocks the coloured stages name: every phase's, then (mode sequential) one per
  /// family range.
  std::span<const ScheduleBlock> blocks() const { return blocks_; }

  /// The coloured batches (mode sequential: laid out group by group, or the model's batches
  /// unchanged in input order).
  ConstraintSets& coloured() { return coloured_; }
  const ConstraintSets& coloured() const { return coloured_; }
  /// One Gauss–Seidel phase per coloured colour, in colouring order (mode sequential, groups
  /// order: one per group, swept one after another by the one sequential stage).
  std::size_t phase_count() const { return phase_offsets_.empty() ? 0 : phase_offsets_.size() - 1; }
  /// A phase's blocks: one per family it holds, in family order.
  std::span<const ScheduleBlock> phase_blocks(std::size_t phase) const {
    return {blocks_.data() + phase_offsets_[phase], blocks_.data() + phase_offsets_[phase + 1]};
  }
  /// Constraints of each phase.
  std::span<const std::size_t> phase_sizes() const { return phase_sizes_; }
  /// SweepOrder::part_major: the parts, and each part's blocks (its interior constraints
  /// colour after colour, one block per colour and family), at the front of blocks(); the
  /// phases hold the crossing constraints. No parts otherwise.
  std::size_t part_count() const { return part_offsets_.empty() ? 0 : part_offsets_.size() - 1; }
  std::span<const ScheduleBlock> part_blocks(std::size_t part) const {
    return {blocks_.data() + part_offsets_[part], blocks_.data() + part_offsets_[part + 1]};
  }
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

  std::size_t constraint_count() const { return family_first_.back(); }
  /// Family f's old→new table: where each of its constraints (the model's index within the
  /// family) was placed.
  std::span<const ConstraintSlot> remap(ConstraintFamily family) const {
    return remap_[std::size_t(family)];
  }
  /// Where the user's constraint (global id, see Model) was placed.
  ConstraintLocation locate(ConstraintIndex user_constraint) const;
  /// The other way: the global id of the constraint in a slot (a real one, not padding) of
  /// the coloured batches or of the Jacobi set.
  ConstraintIndex user_constraint(ConstraintFamily family, bool in_jacobi_set,
                                  std::uint32_t slot) const;

 private:
  /// Per family, the model's constraint that each scheduled slot holds (or a padding mark).
  using SourceLists = std::array<std::vector<std::uint32_t>, kConstraintFamilyCount>;
  void lay_out_in_input_order(const Model& model);
  void take_particle_order(const Colouring& colouring, std::size_t particle_count);
  void place_by_colour(const Colouring& colouring, SourceLists& coloured, SourceLists& jacobi);
  /// part_of[c]: constraint c's part, or `parts` for a crossing one.
  void place_by_part(const Colouring& colouring, std::span<const std::uint32_t> part_of,
                     std::size_t parts, SourceLists& coloured, SourceLists& jacobi);
  /// members[f] = the constraints (global ids) of family f, as indices within the family.
  void split_by_family(std::span<const ConstraintIndex> constraints, SourceLists& members) const;
  /// Appends one colour's (or one part's colour's) constraints, per family, to the coloured
  /// batches, each family's run aligned to kMaxLanes and one block.
  void append_group(const SourceLists& members, SourceLists& coloured);
  /// The phase of one colour's members: appended, or (to_jacobi) left for the Jacobi set.
  void append_phase(const SourceLists& members, std::size_t size, bool to_jacobi,
                    SourceLists& coloured, SourceLists& jacobi);
  void build_stages();

  /// Mode hybrid: a colour this small goes to the Jacobi set; mode jacobi: every colour.
  bool to_jacobi(std::size_t colour_size) const {
    return options_.mode == SolverMode::jacobi ||
           (options_.mode == SolverMode::hybrid && colour_size < options_.hybrid_threshold);
  }

  ScheduleOptions options_;
  ConstraintSets coloured_;
  std::vector<ScheduleBlock> blocks_;
  std::vector<std::size_t> phase_offsets_;
  std::vector<std::size_t> phase_sizes_;
  std::vector<std::size_t> part_offsets_;
  std::array<std::vector<ScheduleBlock>, kConstraintFamilyCount> ranges_;
  JacobiSet jacobi_;
  std::vector<ParticleIndex> new_to_old_, old_to_new_;
  std::array<std::vector<ConstraintSlot>, kConstraintFamilyCount> remap_;
  /// Its inverse: per family, the model's constraint in each slot (empty: the input order).
  SourceLists coloured_source_, jacobi_source_;
  /// The global id of each family's first constraint (and the total, last).
  std::array<ConstraintIndex, kConstraintFamilyCount + 1> family_first_{};
  std::vector<Stage> iteration_stages_, velocity_stages_;
};

}  // namespace tessera
