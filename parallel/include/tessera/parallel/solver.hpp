// The solver: XPBD (or PBD) time stepping of a Model over its Schedule.
//
//   per substep (h = time_step / substeps):
//     v += h·g, x_prev = x, x += h·v          (movable particles; parallel over particles)
//     λ = 0
//     iterations × the mode's stages           (stage.hpp; modes in solver_mode.hpp)
//       gs:     for each colour phase: one share per thread, the same slice of each family
//               → batched SIMD kernel
//       jacobi: all blocks at once into incidences → per-particle averaged sum
//       hybrid: the gs phases, then one Jacobi phase for the small colours
//       sequential: every constraint through the scalar API, one thread, group after group
//                   (the reference library's order) or in input order
//     v = (x − x_prev)/h · max(0, 1 − damping·h)
//     velocity passes (families with a velocity solve, e.g. particle–tet contact friction)
//
// Forks: in gs with coloured phases only (no Jacobi stage, velocity pass, collisions or phase
// hook), every substep but the last runs as phases of one parallel region per step
// (phase_region.hpp): prediction, each iteration's colours, the velocity update fused with
// the next prediction, the threads meeting at a spin barrier between them. A 64² cloth at 160
// substeps of 1 iteration steps 1.25× faster on 2 threads than with a fork per pass.
//
// Threads: every parallel loop runs in the solver's own tbb::task_arena of `threads`
// workers; no global TBB state is touched. Any thread count gives bitwise the same positions:
// a colour's constraints share no movable particle, each SIMD lane's arithmetic does not
// depend on its neighbours, block boundaries are fixed by the schedule, and the Jacobi sums
// run in the schedule's fixed order.
//
// Numbering: the solver keeps particles in the schedule's order (the colouring's locality
// order); everything public takes and returns the user's particle numbers and global
// constraint ids (see Model).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include <oneapi/tbb/task_arena.h>

#include <tessera/collision/collision_stage.hpp>
#include <tessera/coloring/colouring.hpp>
#include <tessera/core/constraint_batch.hpp>
#include <tessera/core/particle_state.hpp>
#include <tessera/core/real.hpp>
#include <tessera/coloring/model_graph.hpp>
#include <tessera/core/model.hpp>
#include <tessera/core/time_integration.hpp>
#include <tessera/parallel/residual.hpp>
#include <tessera/parallel/schedule.hpp>
#include <tessera/parallel/solver_mode.hpp>
#include <tessera/parallel/stage.hpp>

namespace tessera {

namespace detail {
struct ColouredContacts;
class PhaseRegion;
struct ResidualScratch;
struct JacobiSetScratch;
}

/// Jacobi over-relaxation ω when nothing else is said (see the README for the measurement).
inline constexpr Real kDefaultJacobiRelaxation = Real(1.5);
/// Chebyshev acceleration of the Jacobi iterations when nothing else is said (see
/// SolverSettings::chebyshev for the measurement).
inline constexpr bool kDefaultChebyshev = false;
inline constexpr Real kDefaultChebyshevRho = Real(0.9);
inline constexpr std::size_t kDefaultChebyshevDelay = 2;
/// Contacts as a Jacobi set or coloured among themselves and swept Gauss–Seidel after the
/// model's constraints (SolverSettings::contact_scheduling, contact_colouring.hpp). Coloured,
/// measured side by side (`tessera run SCENE`, 32 × 1, 1 and 2 threads, a 2-core Xeon): on
/// the pile (8 FEM blocks, 90 frames) no contact is left violated after the iterations
/// (particle–tet residual max 0, against 0.63 mm as a Jacobi set) and the FEM residual max
/// falls from 0.0109 to 0.0042, in 24 contact colours per substep, with scheduling 35 %
/// cheaper (0.135 against 0.21 s: no incidence lists) and the same stepping time (0.82–0.89
/// against 0.91–0.94 s); on the 64² drape (120 frames) the residual max falls from 0.41 to
/// 0.35 for 2 % less stepping, 15,502 of 1.6 million contacts overflowing into the Jacobi
/// set.
inline constexpr ContactScheduling kDefaultContactScheduling = ContactScheduling::coloured;
/// The sweeps' particle layout (measured: docs/performance.md, "Interleaved particles").
inline constexpr ParticleLayout kDefaultParticleLayout = ParticleLayout::interleaved;

struct SolverSettings {
  SolverMode mode = SolverMode::gs;
  /// Worker threads; 0 takes every hardware thread TBB reports (worker_threads, threads.hpp).
  std::size_t threads = 0;
  /// XPBD compliance (default) or PBD stiffness. Families without an XPBD form (the three
  /// proximity families, strain, FEM triangle, shape matching) use their PBD stiffness in
  /// either case.
  ConstraintSemantics semantics = ConstraintSemantics::compliance;
  /// Length of one step() and the substeps it is split into.
  Real time_step = Real(1) / Real(60);
  std::size_t substeps = 1;
  /// Projection sweeps per substep.
  std::size_t iterations = 10;
  Vector3r gravity = Vector3r(0, Real(-9.81), 0);
  /// Fraction of the velocity removed per second (v ← v · max(0, 1 − damping · h)); ≥ 0.
  Real velocity_damping = 0;
  /// Jacobi over-relaxation ω (jacobi and hybrid modes), in (0, 2).
  Real jacobi_relaxation = kDefaultJacobiRelaxation;
  /// Chebyshev semi-iterative acceleration of the Jacobi iterations (Wang 2015, "A Chebyshev
  /// semi-iterative approach for accelerating projective and position-based dynamics"):
  /// within one solve (the iterations of a substep, or one project() call), the n-th
  /// iteration's Jacobi result q̂ₙ (already relaxed by jacobi_relaxation, which plays the
  /// paper's γ) is extrapolated from the positions of the iteration before last,
  ///   qₙ = ωₙ (q̂ₙ − qₙ₋₂) + qₙ₋₂,
  /// ωₙ = 1 for n ≤ chebyshev_delay (the paper's S), 2 / (2 − ρ²) for the next, then
  /// 4 / (4 − ρ² ωₙ₋₁), with ρ = chebyshev_rho the estimated spectral radius of the
  /// iteration, in (0, 1); chebyshev_delay ≥ 1. It applies to the particles of the
  /// schedule's Jacobi set in mode jacobi only (in hybrid, whose Jacobi phase follows the
  /// coloured ones, it gave 1-3 % fewer iterations on the cloth and a non-monotonic residual
  /// on the bar): not to the dynamic constraints, never to a static particle. It costs one
  /// more copy of x, y, z of the set's movable particles and three loads and stores per
  /// particle in the reduction; the result stays bitwise the same for any thread count.
  ///
  /// Off by default (an option), measured with bench/chebyshev_report (one step of 1/60 s
  /// from a moving state; iterations until the residual plain Jacobi reaches after 32 / 128 /
  /// 256 iterations): with ρ = 0.9, delay 2, the 256² cloth (distance RMS) takes 15 / 57 /
  /// 113, the 12×12×48 FEM bar (E = 10⁶) 21 / 55 / 74, i.e. 1.5-3.5× fewer. Cost per
  /// iteration (bench_solver solver/chebyshev, 1 thread, fastest of 10-15 repetitions on a
  /// 2-core machine under a load of 7-9, so only indicative): cloth256 +2 to +5 %, tetbar200k
  /// +16 to +26 %, which three more loads and stores per particle cannot explain; measure
  /// again on a quiet machine before relying on it. Larger ρ converge faster
  /// in long solves (ρ = 0.99: 14 / 21 / 37 and 15 / 24 / 30) but made 60-frame runs of the
  /// cloth diverge (chebyshev_report --frames: ρ = 0.99 at 4 substeps × 8 and 8 × 4, ρ = 0.95
  /// at 8 × 4), and delay 1 made 16 × 2 diverge even at ρ = 0.9 (the last iteration of every
  /// substep then overshoots by ω₂ = 1.68 and the velocity update keeps it). ρ = 0.9 with
  /// delay 2 was stable and ended with a lower residual than plain Jacobi at 16 × 3, 8 × 4,
  /// 8 × 6, 4 × 8, 2 × 16 and 1 × 32 on the cloth and the bar, and solves of 1 or 2
  /// iterations (the tool's 16 × 2) are exactly plain Jacobi. It is not the default because
  /// the extrapolation breaks two things plain Jacobi gets right: unilateral constraints (a
  /// particle–tet contact in the Jacobi set is extrapolated through the surface: 6 mm of
  /// penetration where plain Jacobi leaves < 2 mm, parallel.Contacts test), and a damped
  /// 2×2×10 bar at 100 iterations per step settles 0.37 away from the sequential solver's
  /// shape instead of < 0.08 (parallel.Solver.ModesReachTheSameRestShape).
  bool chebyshev = kDefaultChebyshev;
  Real chebyshev_rho = kDefaultChebyshevRho;
  std::size_t chebyshev_delay = kDefaultChebyshevDelay;
  /// Constraints per parallel work block of a Jacobi set (the schedule's, the dynamic
  /// constraints', the contacts'; a colour phase is cut into one share per thread instead),
  /// and the hybrid mode's colour-size threshold.
  std::size_t block_size = kDefaultBlockSize;
  std::size_t hybrid_threshold = kDefaultHybridThreshold;
  /// Residual before and after the last substep's iterations of every step (StepReport).
  /// Each evaluation costs about half a projection sweep (measured 0.44 of a sweep on one
  /// thread on a 256² cloth, batched SIMD residuals), so at 10 iterations a step pays ~9 %;
  /// throughput runs turn it off.
  bool report_residuals = true;
  /// Also the residual after every iteration of the last substep (convergence history).
  bool record_convergence = false;
  /// Check after every step() and project() that every position and velocity is finite; if
  /// one is not, restore the state from before and throw NumericalFailure. Costs a copy and
  /// a scan of the particle arrays per call (not per iteration).
  bool check_finite = true;
  /// Divergence is a failure, not a result: a step whose residual after its last substep
  /// (report_residuals; without it nothing is checked) has an RMS above this bound restores
  /// the state from before and throws NumericalFailure naming the family and constraint with
  /// the largest residual. The residuals are relative (10 is constraints off by 1000 % on
  /// average), so no physical state comes near the default; free fall has none. Positive;
  /// infinity turns the check off.
  Real divergence_rms = 10;
  /// Mode sequential: the reference library's greedy groups one after another (default) or
  /// the input order (solver_mode.hpp says which is which and why groups is the default).
  SequentialOrder sequential_order = SequentialOrder::groups;
  /// Modes gs and hybrid: how the collision stage's contacts are scheduled each substep
  /// (solver_mode.hpp); see kDefaultContactScheduling for the measurement.
  ContactScheduling contact_scheduling = kDefaultContactScheduling;
  /// How the sweeps hold the particles (solver_mode.hpp); the same bits either way.
  ParticleLayout particle_layout = kDefaultParticleLayout;
  /// Modes gs and hybrid: colour after colour, or part after part, or chosen by the scene
  /// (automatic, the default: part after part from kPartMajorFromParts parts up;
  /// solver_mode.hpp). The parts are the colouring's (strategies metis and blocks, sized by
  /// their ColouringOptions), or for any other colouring runs of particles_per_part movable
  /// particles of its particle order (0: kDefaultParticlesPerRun; set only for those runs,
  /// with part_major or automatic in mode gs or hybrid, InvalidInput otherwise).
  /// schedule().options().sweep_order is the order chosen.
  SweepOrder sweep_order = SweepOrder::automatic;
  std::size_t particles_per_part = 0;
  /// Consecutive coloured phases run in one parallel region per iteration, the threads
  /// meeting at a spin barrier between colours (parallel/src/phase_region.hpp); with coloured
  /// phases only, a step's substeps but the last and their particle passes run in one region
  /// (SolverStatistics::steps_in_one_region). false: a parallel_for per phase and per pass.
  /// The same bits either way.
  bool phase_regions = true;
};

/// What the last step() measured.
struct StepReport {
  /// At the start of the last substep's iterations (after prediction) and after them.
  Residual residual_before;
  Residual residual_after;
  /// record_convergence: history[i] is the residual after i iterations (history[0] = before).
  std::vector<Residual> history;
};

struct SolverStatistics {
  std::size_t particles = 0;
  std::array<std::size_t, kConstraintFamilyCount> constraints_per_family{};
  std::size_t constraints = 0;
  /// Colours run as Gauss–Seidel phases, their sizes, and the constraints of the Jacobi set
  /// (SweepOrder::part_major: the crossing constraints' phases; the parts' interior
  /// constraints are the rest, part_constraints, swept by part_count workers' parts).
  std::size_t part_count = 0;
  std::size_t part_constraints = 0;
  std::size_t coloured_phases = 0;
  std::vector<std::size_t> phase_sizes;
  std::size_t jacobi_constraints = 0;
  std::size_t threads = 0;
  double seconds_schedule = 0;
  /// Time spent projecting (iterations only) and in whole steps, since construction.
  double seconds_projection = 0;
  double seconds_stepping = 0;
  /// Constraint projections done (constraints × iterations × substeps × steps).
  std::uint64_t projections = 0;
  std::uint64_t steps = 0;
  /// Steps whose substeps but the last ran as one parallel region (one fork per step, not
  /// iterations + 1 per substep; a region per 4,096 phases at most): phase_regions on, gs or
  /// hybrid with coloured phases only (no Jacobi set), more than one substep and thread, no
  /// collisions, dynamic constraints, velocity passes or phase hook.
  std::uint64_t steps_in_one_region = 0;
  /// With a collision stage: time spent turning each substep's contacts into their schedule
  /// (a Jacobi set, or the contact colours and the overflow's set), and, with
  /// ContactScheduling::coloured, the contact colours summed over the substeps and their most
  /// in one substep, and the contacts that found no colour.
  double seconds_contact_scheduling = 0;
  std::uint64_t contact_substeps = 0;
  std::uint64_t contact_colours_total = 0;
  std::size_t contact_colours_max = 0;
  std::uint64_t contacts_overflowed = 0;
};

class Solver {
 public:
  /// Builds the schedule of `model` from `colouring` (which must colour
  /// constraint_graph(model)). Mode sequential ignores the colouring. Throws InvalidInput
  /// for bad settings (time step ≤ 0 or not finite, 0 substeps, damping < 0, ω outside
  /// (0, 2), Chebyshev ρ outside (0, 1) or delay 0, block size 0) or a colouring that does
  /// not fit the model.
  Solver(Model model, const Colouring& colouring, const SolverSettings& settings);
  /// Mode sequential only (no colouring needed); InvalidInput for any other mode.
  Solver(Model model, const SolverSettings& settings);
  ~Solver();
  Solver(Solver&&) noexcept;
  Solver& operator=(Solver&&) noexcept;

  /// One time step of settings().time_step, in settings().substeps substeps. Throws
  /// NumericalFailure (state restored) if it produced a non-finite value (check_finite) or
  /// diverged (divergence_rms).
  void step();
  /// `iterations` projection sweeps at the current positions, with no time integration
  /// (λ kept from before; call reset_lambdas() first for a fresh XPBD solve). For tests,
  /// quasi-static solves and benchmarks; `dt` is the compliance time step.
  void project(std::size_t iterations, Real dt);
  void reset_lambdas();

  /// The normalised residual now (see residual.hpp): under compliance semantics, the XPBD
  /// residual |C + α̃λ| of the families with an XPBD form (Macklin et al. 2016, eq. 11: what
  /// the compliant solve drives to zero, α̃ = α / dt² at the dt of the last step's substeps
  /// or the last project()), which is the violation |C| itself for a hard constraint (α = 0)
  /// and right after a λ reset; |C| for the others and under stiffness semantics.
  Residual residual();

  const StepReport& last_step() const { return report_; }
  const SolverStatistics& statistics() const { return statistics_; }
  const SolverSettings& settings() const { return settings_; }
  const Schedule& schedule() const { return schedule_; }

  /// Particles in the user's numbering.
  std::size_t particle_count() const { return state_.size(); }
  Vector3r position(ParticleIndex particle) const;
  Vector3r velocity(ParticleIndex particle) const;
  Real inverse_mass(ParticleIndex particle) const;
  std::vector<Vector3r> positions() const;
  std::vector<Vector3r> velocities() const;
  /// Moves a particle (a kinematic, static one between steps, or any particle to reset it).
  void set_position(ParticleIndex particle, const Vector3r& position);
  void set_velocity(ParticleIndex particle, const Vector3r& velocity);
  /// The XPBD multiplier of a constraint (global id); 0 for families without one.
  Real lambda(ConstraintIndex constraint) const;

  /// Replaces the dynamic constraints — the ones made anew between steps, like collision
  /// and contact constraints (the proximity families, particle–tet contacts) — by
  /// `constraints`, which name particles in the user's numbering; an empty ConstraintSets
  /// removes them. They are not coloured: they form a Jacobi set of their own, projected
  /// after the model's constraints in every iteration (mode sequential: one after another
  /// through the scalar API), reset with the model's λ every substep, counted in residuals;
  /// a family with a velocity solve (contact friction) runs it after every velocity update,
  /// one constraint after another. Throws InvalidInput when a batch was built for more
  /// particles than the model has.
  void set_dynamic_constraints(ConstraintSets constraints);
  std::size_t dynamic_constraint_count() const { return dynamic_count_; }

  /// Collision detection every substep (collision_stage.hpp): after each prediction the
  /// stage finds the contacts of the predicted positions (colliders, and with
  /// settings.self_collision the surface against itself), which the solver then projects in
  /// every iteration after the model's and the dynamic constraints, as
  /// SolverSettings::contact_scheduling says (coloured among themselves by default, or a
  /// Jacobi set of their own; mode jacobi: that set; mode sequential: one after another),
  /// with their velocity pass after the velocity update. `surface_triangles` (3 particles each, the user's numbering) is the
  /// surface self-collision works on; `tetrahedra` (4 each) are the solids, whose boundary
  /// faces among those triangles get particle–tet contacts (solid_contacts.hpp). Replaces an
  /// earlier stage; throws InvalidInput for bad settings or an element naming a particle the
  /// model does not have.
  void set_collisions(CollisionSettings settings, std::span<const std::uint32_t> surface_triangles,
                      std::span<const std::uint32_t> tetrahedra = {});
  /// Turns collision detection off and drops the last contacts.
  void clear_collisions();
  /// The stage (its settings and statistics), or null.
  const CollisionStage* collisions() const { return collisions_.get(); }
  /// The contacts of the last substep as the collision stage found them, in the schedule's
  /// numbering.
  const ConstraintSets& contacts() const { return contacts_found_; }
  /// Per particle (the user's numbering), the number of the last substep's contacts it is in.
  std::vector<std::uint32_t> contact_counts() const;

  /// The particles in the schedule's numbering, for code that works on the arrays.
  const ParticleState& scheduled_state() const { return state_; }

  /// Code that must run between the colours of mode gs (the distributed solver's exchanges:
  /// distributed/). Every iteration calls it with kBeforePhases before its first coloured
  /// phase, then after each coloured phase with that phase's number (0, 1, ... in the order
  /// the phases run: colour k of the colouring is phase k), with the particles in the
  /// schedule's numbering to read and write. An empty function removes it. Throws
  /// InvalidInput in another mode.
  using PhaseHook = std::function<void(std::size_t phase, ParticleArrays particles)>;
  static constexpr std::size_t kBeforePhases = ~std::size_t(0);
  void set_phase_hook(PhaseHook hook);

 private:
  void check_particle(ParticleIndex particle) const;
  std::size_t dynamic_user_index(ConstraintFamily family, std::uint32_t slot) const;
  /// check_finite: snapshot before an operation, and the scan after it (restores and throws).
  void save_state();
  void restore_if_not_finite(const char* operation);
  /// The scan after a step: restores and throws when its residual_after is beyond the bound.
  void restore_if_diverged(const char* operation);
  bool guards_divergence() const;
  void restore_saved_state();
  void integrate(Real h);
  /// The particles as the sweeps see them: the interleaved copy between begin_sweeps() and
  /// end_sweeps() (ParticleLayout::interleaved), else the state's arrays.
  ParticleArrays sweep_arrays();
  /// Copy the state into the sweeps' layout before a solve's first iteration, and the
  /// positions back after its last (nothing for ParticleLayout::separate).
  void begin_sweeps();
  void end_sweeps();
  /// Sizes the interleaved copy when the layout is interleaved (false: separate); the copy
  /// is no longer current.
  bool prepare_interleaved();
  IntegrationStep integration_step(Real h) const;
  struct EndSweeps {
    Solver* solver;
    ~EndSweeps() { solver->end_sweeps(); }
  };
  /// The collision stage's contacts for the substep of length h just predicted.
  void detect_contacts(Real h);
  /// A set swept after the schedule's (dynamic constraints, contacts): a Jacobi set built
  /// from `constraints`, whose particles renumber() maps to the schedule's numbering (mode
  /// sequential: the blocks only, in input order). source gets the caller's index per slot.
  /// Built into `set`, whose arrays keep their capacity (contacts: every substep).
  void extra_set(const ConstraintSets& constraints,
                 std::array<std::vector<std::uint32_t>, kConstraintFamilyCount>& source,
                 bool scheduled_numbering, JacobiSet& set);
  void update_velocities(Real h);
  /// update_velocities(h) then integrate(h) in one pass over the particles (the same
  /// arithmetic per particle, so the same bits): between two substeps with no velocity pass.
  void update_velocities_and_integrate(Real h);
  /// The corrected positions of a Jacobi set's incidences.
  struct JacobiWork {
    AlignedVector<Real> x, y, z;
    void bind(const JacobiSet& jacobi);
  };
  /// The stage lists: the schedule's, then the dynamic constraints' (stage.hpp).
  void build_stages();
  /// The one dispatcher: runs any stage.
  void run_stage(const Stage& stage, const ProjectionSettings& projection);
  /// Projects constraints [begin, end) of family f of the set `set`: the one kernel call of
  /// the coloured phases, the phase regions and the part sweeps. With fresh_lambdas_, in a
  /// solve's first iteration, the range's λ start at 0 (ProjectionSettings::
  /// lambda_starts_at_zero, or zeroed first under stiffness semantics; see fresh_lambdas_).
  void project_range(const ParticleArrays& particles, StageSet set, ConstraintFamily f,
                     std::size_t begin, std::size_t end, const ProjectionSettings& projection);
  /// The same in a solve's first iteration or not, whatever the iteration under way.
  void project_range(const ParticleArrays& particles, StageSet set, ConstraintFamily f,
                     std::size_t begin, std::size_t end, const ProjectionSettings& projection,
                     bool first_iteration);
  /// Whether step() may run all substeps but the last in one parallel region
  /// (run_substeps_in_one_region): coloured phases only, nothing between the substeps.
  bool substeps_fit_one_region() const;
  /// `substeps` substeps of step() (iterations, then the velocity update fused with the next
  /// prediction; with predict_first, the first one's prediction before) as the phases of one
  /// region (phase_region.hpp): the same bits as running them one by one. Returns the seconds
  /// one thread spent in the particle passes.
  double run_substeps_in_one_region(Real h, const ProjectionSettings& projection,
                                    std::size_t substeps, bool predict_first);
  /// reset_lambdas(), with or without the schedule's coloured set.
  void zero_lambdas(bool coloured);
  ConstraintSets& batches_of(StageSet set);
  std::span<const ScheduleBlock> blocks_of(const Stage& stage) const;
  /// The `iteration`th (1-based) iteration of a solve (a substep's or a project() call's).
  void iterate(const ProjectionSettings& projection, std::size_t iteration);
  /// Coloured phases [first, last) of stages_ in one parallel region (phase_region.hpp).
  void run_phase_region(std::size_t first, std::size_t last, const ProjectionSettings& projection);
  void jacobi_projection(JacobiSet& jacobi, JacobiWork& work,
                         std::span<const ScheduleBlock> blocks,
                         const ProjectionSettings& projection);
  /// chebyshev: the schedule's set, accelerated (see SolverSettings::chebyshev) in the
  /// `iteration`th (1-based) iteration of a solve.
  void jacobi_reduction(const JacobiSet& jacobi, const JacobiWork& work, Real omega,
                        bool chebyshev = false);
  template <class Body>
  void parallel_chunks(std::size_t count, std::size_t chunk, Body&& body);
  /// body(family, begin, end) over a coloured phase's blocks, one share per thread, each
  /// share the same slice of every family (detail::for_share_of_phase).
  template <class Body>
  void for_each_share(std::span<const ScheduleBlock> blocks, Body&& body);

  SolverSettings settings_;
  Schedule schedule_;
  /// Scratch of the per-step checks (residual(), restore_if_not_finite()), kept so that a
  /// step in steady state allocates nothing (tests/parallel/test_step_allocations.cpp).
  std::unique_ptr<detail::ResidualScratch> residual_scratch_;
  std::vector<std::size_t> first_bad_;
  ParticleState state_;
  /// ParticleLayout::interleaved: x, y, z, w per particle while sweeping (sweeping_).
  AlignedVector<Real> interleaved_;
  bool sweeping_ = false;
  /// The copy equals the state: made by this substep's prediction, for begin_sweeps.
  bool interleaved_current_ = false;
  /// The schedule's Jacobi set's work, and the dynamic constraints' set (mode sequential:
  /// the constraints as given and one block per family, swept in order) and work.
  JacobiWork jacobi_work_;
  JacobiSet dynamic_;
  JacobiWork dynamic_work_;
  /// Per family, the dynamic constraint (the caller's index) in each slot of dynamic_ (empty:
  /// the slots are the caller's order).
  std::array<std::vector<std::uint32_t>, kConstraintFamilyCount> dynamic_source_;
  std::vector<Stage> stages_, velocity_stages_;
  PhaseHook phase_hook_;
  /// Chebyshev acceleration: the schedule's Jacobi set's particles (JacobiSet::particles
  /// order) one iteration before the last, the iteration under way and its weight ω.
  std::array<AlignedVector<Real>, 3> chebyshev_previous_;
  std::size_t chebyshev_iteration_ = 0;
  /// Set by step() for a substep whose first iteration starts the coloured set's λ at 0 range
  /// by range, as it projects them, instead of a pass of their own over λ (25 MB per substep
  /// on the 1024² cloth, and two fork-joins on any scene). Not when a residual is read before
  /// the iterations (it needs the λ = 0 of a fresh solve).
  bool fresh_lambdas_ = false;
  Real chebyshev_weight_ = 1;
  std::size_t dynamic_count_ = 0;
  /// The collision stage, its contacts of the current substep (as found; as a Jacobi set, with
  /// ContactScheduling::coloured the overflow only; coloured) and their work.
  std::unique_ptr<CollisionStage> collisions_;
  ConstraintSets contacts_found_;
  JacobiSet contacts_;
  std::unique_ptr<detail::ColouredContacts> contact_colours_;
  /// The contacts that found no colour, before they become the Jacobi set contacts_.
  ConstraintSets contact_overflow_;
  /// extra_set's working lists (the contacts' Jacobi set is rebuilt every substep).
  std::unique_ptr<detail::JacobiSetScratch> jacobi_scratch_;
  /// ContactScheduling::coloured: scratch (zero between substeps) for the substep's contact
  /// colours, a word per particle.
  std::vector<std::uint64_t> contact_masks_;
  /// The inverse masses without the arrays' padding (one per particle).
  std::span<const Real> inverse_masses() const { return {state_.inverse_mass.data(), state_.size()}; }
  /// Whether the contacts are coloured (the setting, in mode gs or hybrid).
  bool colours_contacts() const;
  JacobiWork contacts_work_;
  std::array<std::vector<std::uint32_t>, kConstraintFamilyCount> contact_source_;
  /// The time step of the last projections (step: the substep; project: its dt), which the
  /// XPBD residual C + α̃λ is measured at.
  Real projection_dt_ = 0;
  /// Positions and velocities from before the current step() or project() (check_finite),
  /// and the λ arrays are not restored (they are reset at the next step).
  std::array<AlignedVector<Real>, 6> saved_;
  std::unique_ptr<tbb::task_arena> arena_;
  /// The claims and counts of run_phase_region, kept between iterations (phase_region.hpp).
  std::unique_ptr<detail::PhaseRegion> phase_region_;
  StepReport report_;
  SolverStatistics statistics_;
};

}  // namespace tessera
