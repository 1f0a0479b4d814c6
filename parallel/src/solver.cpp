// The solver's loops (see solver.hpp for the step and schedule.hpp for the layout). Every
// parallel loop is a parallel_for over a fixed list of work items (blocks of a phase,
// chunks of particles or incidences) with a static partitioner inside the solver's arena:
// the items are fixed by the schedule, so results do not depend on the thread count, and a
// static split gives each worker the same items every iteration (its particles stay in its
// cache).
#include <tessera/parallel/solver.hpp>

#include <tessera/core/time_integration.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <span>
#include <string>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/partitioner.h>

#include <tessera/core/error.hpp>
#include <tessera/core/sequential_projection.hpp>
#include <tessera/parallel/threads.hpp>

#include <tessera/core/batch_reorder.hpp>
#include "contact_colouring.hpp"
#include "jacobi_set.hpp"
#include "phase_region.hpp"
#include "residual_sum.hpp"

namespace tessera {

namespace {

/// Particles (or incidences) per parallel chunk of the element-wise loops.
constexpr std::size_t kParticleChunk = 4096;
/// The most phases one region of whole substeps holds (Solver::run_substeps_in_one_region).
constexpr std::size_t kMostRegionPhases = 4096;
/// Constraints per chunk of the residual sums.
constexpr std::size_t kResidualChunk = detail::kLongestResidualRange;

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void check_settings(const SolverSettings& s) {
  if (!(std::isfinite(s.time_step) && s.time_step > 0))
    throw InvalidInput("solver settings: time step must be positive and finite (got " +
                       std::to_string(s.time_step) + ")");
  if (s.substeps == 0) throw InvalidInput("solver settings: substeps must be at least 1");
  if (!(std::isfinite(s.velocity_damping) && s.velocity_damping >= 0))
    throw InvalidInput("solver settings: velocity damping must be >= 0 and finite (got " +
                       std::to_string(s.velocity_damping) + ")");
  if (!(s.jacobi_relaxation > 0 && s.jacobi_relaxation < 2))
    throw InvalidInput("solver settings: Jacobi relaxation must be in (0, 2) (got " +
                       std::to_string(s.jacobi_relaxation) + ")");
  if (!(s.chebyshev_rho > 0 && s.chebyshev_rho < 1))
    throw InvalidInput("solver settings: chebyshev_rho (the Chebyshev spectral radius "
                       "estimate) must be in (0, 1) (got " +
                       std::to_string(s.chebyshev_rho) + ")");
  if (s.chebyshev_delay == 0)
    throw InvalidInput("solver settings: chebyshev_delay must be at least 1");
  if (s.block_size == 0) throw InvalidInput("solver settings: block size must be at least 1");
  if (!s.gravity.allFinite()) throw InvalidInput("solver settings: gravity is not finite");
  if (!(s.divergence_rms > 0))
    throw InvalidInput("solver settings: divergence bound must be positive (got " +
                       std::to_string(s.divergence_rms) + "; infinity turns the check off)");
}

/// The model's particles renumbered into the schedule's order.
ParticleState scheduled_particles(const ParticleState& user, const Schedule& schedule) {
  const std::size_t n = user.size();
  if (schedule.particle_new_to_old().empty()) return user;
  ParticleState state(n);
  const auto to_user = schedule.particle_new_to_old();
  const auto copy = [&](AlignedVector<Real>& to, const AlignedVector<Real>& from) {
    for (std::size_t p = 0; p < n; ++p) to[p] = from[to_user[p]];
  };
  copy(state.x, user.x);
  copy(state.y, user.y);
  copy(state.z, user.z);
  copy(state.inverse_mass, user.inverse_mass);
  copy(state.previous_x, user.previous_x);
  copy(state.previous_y, user.previous_y);
  copy(state.previous_z, user.previous_z);
  copy(state.velocity_x, user.velocity_x);
  copy(state.velocity_y, user.velocity_y);
  copy(state.velocity_z, user.velocity_z);
  return state;
}

/// Each family's entry points behind one signature per kind: the solver's dispatch tables,
/// generated from the family list (constraint_families.hpp), indexed by ConstraintFamily.
using ProjectBlock = void (*)(ParticleArrays, ConstraintSets&, std::size_t, std::size_t,
                              const ProjectionSettings&);
using VelocityBlock = void (*)(ParticleArrays, const ConstraintSets&, std::size_t, std::size_t,
                               Real);

template <ConstraintFamily Family>
void project_block(ParticleArrays particles, ConstraintSets& sets, std::size_t begin,
                   std::size_t end, const ProjectionSettings& settings) {
  using Batch = FamilyBatchOf<Family>;
  project_constraints(particles, sets.get<Family>(), begin, end, settings_for<Batch>(settings));
}

template <ConstraintFamily Family>
void project_block_sequentially(ParticleArrays particles, ConstraintSets& sets,
                                std::size_t begin, std::size_t end,
                                const ProjectionSettings& settings) {
  using Batch = FamilyBatchOf<Family>;
  project_sequentially(particles, sets.get<Family>(), begin, end, settings_for<Batch>(settings));
}

/// The velocity solve of a family that has one; nothing for the others.
template <ConstraintFamily Family>
void velocity_block(ParticleArrays velocities, const ConstraintSets& sets, std::size_t begin,
                    std::size_t end, Real dt) {
  if constexpr (FamilyBatchOf<Family>::kTraits.velocity_pass)
    solve_velocity_constraints(velocities, sets.get<Family>(), begin, end, dt);
}

template <class Entry, template <ConstraintFamily> class Make, std::size_t... F>
constexpr std::array<Entry, kConstraintFamilyCount> table(std::index_sequence<F...>) {
  return {Make<ConstraintFamily(F)>::value...};
}
/// λ of constraints [begin, end) of a batch set to 0; nothing for a family without λ.
template <class Batch>
void zero_lambda_range(Batch& batch, std::size_t begin, std::size_t end) {
  if (Real* lambda = lambda_of(batch)) std::fill(lambda + begin, lambda + end, Real(0));
}

template <ConstraintFamily Family>
void zero_lambdas(ConstraintSets& sets, std::size_t begin, std::size_t end) {
  zero_lambda_range(sets.get<Family>(), begin, end);
}
using ZeroLambdas = void (*)(ConstraintSets&, std::size_t, std::size_t);

template <ConstraintFamily F>
struct ProjectEntry { static constexpr ProjectBlock value = &project_block<F>; };
template <ConstraintFamily F>
struct ZeroLambdasEntry { static constexpr ZeroLambdas value = &zero_lambdas<F>; };
template <ConstraintFamily F>
struct SequentialEntry { static constexpr ProjectBlock value = &project_block_sequentially<F>; };
template <ConstraintFamily F>
struct VelocityEntry { static constexpr VelocityBlock value = &velocity_block<F>; };
constexpr auto kFamilies = std::make_index_sequence<kConstraintFamilyCount>();
constexpr auto kProjectBlock = table<ProjectBlock, ProjectEntry>(kFamilies);
constexpr auto kProjectSequentially = table<ProjectBlock, SequentialEntry>(kFamilies);
constexpr auto kVelocityBlock = table<VelocityBlock, VelocityEntry>(kFamilies);
constexpr auto kZeroLambdas = table<ZeroLambdas, ZeroLambdasEntry>(kFamilies);

}  // namespace

Solver::Solver(Model model, const Colouring& colouring, const SolverSettings& settings)
    : settings_(settings) {
  check_settings(settings_);
  projection_dt_ = settings_.time_step / Real(settings_.substeps);
  const auto start = Clock::now();
  const std::size_t threads =
      settings_.mode == SolverMode::sequential ? 1 : worker_threads(settings_.threads);
  schedule_ = Schedule(model, &colouring,
                       {settings_.mode, settings_.block_size, settings_.hybrid_threshold, threads,
                        settings_.sequential_order, settings_.sweep_order,
                        settings_.particles_per_part});
  state_ = scheduled_particles(model.particles, schedule_);
  jacobi_work_.bind(schedule_.jacobi());
  if (settings_.chebyshev && settings_.mode == SolverMode::jacobi)
    for (AlignedVector<Real>& previous : chebyshev_previous_)
      previous.assign(schedule_.jacobi().particles.size(), 0);
  build_stages();
  statistics_.seconds_schedule = seconds_since(start);

  arena_ = std::make_unique<tbb::task_arena>(int(threads));
  statistics_.threads = threads;
  statistics_.particles = state_.size();
  statistics_.constraints_per_family = model.constraints.sizes();
  statistics_.constraints = model.constraints.size();
  statistics_.coloured_phases = schedule_.phase_count();
  statistics_.part_count = schedule_.part_count();
  for (std::size_t part = 0; part < schedule_.part_count(); ++part)
    for (const ScheduleBlock& block : schedule_.part_blocks(part))
      statistics_.part_constraints += block.end - block.begin;
  statistics_.phase_sizes.assign(schedule_.phase_sizes().begin(), schedule_.phase_sizes().end());
  statistics_.jacobi_constraints = schedule_.jacobi().constraint_count;
}

Solver::Solver(Model model, const SolverSettings& settings)
    : Solver(std::move(model),
             [&]() -> const Colouring& {
               if (settings.mode != SolverMode::sequential)
                 throw InvalidInput("solver: mode " +
                                    std::string(solver_mode_name(settings.mode)) +
                                    " needs a colouring");
               static const Colouring kNone;
               return kNone;
             }(),
             settings) {}

Solver::~Solver() = default;
Solver::Solver(Solver&&) noexcept = default;
Solver& Solver::operator=(Solver&&) noexcept = default;

template <class Body>
void Solver::parallel_chunks(std::size_t count, std::size_t chunk, Body&& body) {
  const std::size_t chunks = (count + chunk - 1) / chunk;
  if (chunks <= 1) {
    if (count != 0) body(std::size_t(0), count);
    return;
  }
  arena_->execute([&] {
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, chunks, 1),
        [&](const tbb::blocked_range<std::size_t>& r) {
          for (std::size_t k = r.begin(); k != r.end(); ++k)
            body(k * chunk, std::min(count, (k + 1) * chunk));
        },
        tbb::static_partitioner());
  });
}

template <class Body>
void Solver::for_each_share(std::span<const ScheduleBlock> blocks, Body&& body) {
  const std::size_t shares = statistics_.threads;
  parallel_chunks(shares, 1, [&](std::size_t first, std::size_t last) {
    for (std::size_t share = first; share < last; ++share)
      detail::for_share_of_phase(blocks, share, shares, body);
  });
}

void Solver::JacobiWork::bind(const JacobiSet& jacobi) {
  x.assign(jacobi.incidence_count, 0);
  y.assign(jacobi.incidence_count, 0);
  z.assign(jacobi.incidence_count, 0);
}

bool Solver::colours_contacts() const {
  return settings_.contact_scheduling == ContactScheduling::coloured &&
         (settings_.mode == SolverMode::gs || settings_.mode == SolverMode::hybrid);
}

void Solver::build_stages() {
  stages_.assign(schedule_.iteration_stages().begin(), schedule_.iteration_stages().end());
  velocity_stages_.assign(schedule_.velocity_stages().begin(), schedule_.velocity_stages().end());
  const std::size_t contact_colours = contact_colours_ ? contact_colours_->colour_count() : 0;
  const auto contact_colour_stage = [&](std::size_t k) {
    return Stage{StageKind::coloured_phase, StageSet::contact_colours,
                 contact_colours_->colour_offsets[k], contact_colours_->colour_offsets[k + 1]};
  };
  // The dynamic constraints, then the contact colours (contact_colouring.hpp), then the
  // contacts' Jacobi set: each swept after the schedule's.
  for (const StageSet set : {StageSet::dynamic, StageSet::contact_colours, StageSet::contacts}) {
    if (set == StageSet::contact_colours) {
      for (std::size_t k = 0; k < contact_colours; ++k)
        stages_.push_back(contact_colour_stage(k));
      for (std::size_t k = 0; k < contact_colours; ++k) {
        const auto blocks = contact_colours_->colour_blocks(k);
        if (std::any_of(blocks.begin(), blocks.end(), [](const ScheduleBlock& b) {
              return family_traits(b.family).velocity_pass;
            })) {
          Stage velocity = contact_colour_stage(k);
          velocity.kind = StageKind::velocity_pass;
          velocity_stages_.push_back(velocity);
        }
      }
      continue;
    }
    const JacobiSet& extra = set == StageSet::dynamic ? dynamic_ : contacts_;
    if (extra.constraint_count == 0) continue;
    const Stage all{StageKind::sequential_sweep, set, 0, std::uint32_t(extra.blocks.size())};
    const bool velocity_pass =
        std::any_of(extra.blocks.begin(), extra.blocks.end(), [](const ScheduleBlock& b) {
          return family_traits(b.family).velocity_pass;
        });
    if (velocity_pass) velocity_stages_.push_back({StageKind::velocity_pass, set, 0, all.last_block});
    if (settings_.mode == SolverMode::sequential) {
      stages_.push_back(all);
      continue;
    }
    stages_.push_back({StageKind::jacobi_projection, set, 0, all.last_block});
    stages_.push_back({StageKind::jacobi_reduction, set, 0, all.last_block});
  }
}

ConstraintSets& Solver::batches_of(StageSet set) {
  switch (set) {
    case StageSet::coloured: return schedule_.coloured();
    case StageSet::jacobi: return schedule_.jacobi().constraints;
    case StageSet::dynamic: break;
    case StageSet::contacts: return contacts_.constraints;
    case StageSet::contact_colours: return contact_colours_->constraints;
  }
  return dynamic_.constraints;
}

std::span<const ScheduleBlock> Solver::blocks_of(const Stage& stage) const {
  // A part stage's range names parts, not blocks (Schedule::part_blocks).
  if (stage.kind == StageKind::part_sweep || stage.kind == StageKind::part_velocity_pass) return {};
  const std::vector<ScheduleBlock>* blocks = &dynamic_.blocks;
  if (stage.set == StageSet::jacobi) blocks = &schedule_.jacobi().blocks;
  if (stage.set == StageSet::contacts) blocks = &contacts_.blocks;
  if (stage.set == StageSet::contact_colours) blocks = &contact_colours_->blocks;
  const ScheduleBlock* base =
      stage.set == StageSet::coloured ? schedule_.blocks().data() : blocks->data();
  return {base + stage.first_block, base + stage.last_block};
}

void Solver::run_stage(const Stage& stage, const ProjectionSettings& projection) {
  ConstraintSets& sets = batches_of(stage.set);
  const auto blocks = blocks_of(stage);
  JacobiSet& jacobi = stage.set == StageSet::jacobi     ? schedule_.jacobi()
                     : stage.set == StageSet::contacts ? contacts_
                                                       : dynamic_;
  JacobiWork& work = stage.set == StageSet::jacobi     ? jacobi_work_
                     : stage.set == StageSet::contacts ? contacts_work_
                                                       : dynamic_work_;
  switch (stage.kind) {
    case StageKind::part_sweep:
    case StageKind::part_velocity_pass: {
      // One worker per part, the part's blocks in order (its colours one after another).
      const ParticleArrays arrays =
          stage.kind == StageKind::part_sweep ? sweep_arrays() : velocity_arrays_of(state_);
      parallel_chunks(stage.last_block - stage.first_block, 1, [&](std::size_t first, std::size_t last) {
        for (std::size_t part = first; part < last; ++part)
          for (const ScheduleBlock& b : schedule_.part_blocks(stage.first_block + part)) {
            if (stage.kind == StageKind::part_sweep)
              project_range(arrays, stage.set, b.family, b.begin, b.end, projection);
            else
              kVelocityBlock[std::size_t(b.family)](arrays, sets, b.begin, b.end, projection.dt);
          }
      });
      return;
    }
    case StageKind::coloured_phase: {
      const ParticleArrays particles = sweep_arrays();
      for_each_share(blocks, [&](ConstraintFamily f, std::size_t begin, std::size_t end) {
        project_range(particles, stage.set, f, begin, end, projection);
      });
      return;
    }
    case StageKind::jacobi_projection: return jacobi_projection(jacobi, work, blocks, projection);
    case StageKind::jacobi_reduction:
      // Contacts are not over-relaxed: ω > 1 overshoots every push out of a collider and
      // every friction correction, so a block resting on a slope crept uphill and hovered
      // 1.3 mm above it (ω = 1.5); ω = 1 leaves it at rest on the surface.
      return jacobi_reduction(jacobi, work,
                              stage.set == StageSet::contacts ? Real(1) : settings_.jacobi_relaxation,
                              settings_.chebyshev && settings_.mode == SolverMode::jacobi &&
                                  stage.set == StageSet::jacobi);
    case StageKind::sequential_sweep: {
      const ParticleArrays particles = sweep_arrays();
      for (const ScheduleBlock& block : blocks)
        kProjectSequentially[std::size_t(block.family)](particles, sets, block.begin, block.end,
                                                        projection);
      return;
    }
    case StageKind::velocity_pass: {
      const ParticleArrays velocities = velocity_arrays_of(state_);
      const auto solve = [&](const ScheduleBlock& block) {
        kVelocityBlock[std::size_t(block.family)](velocities, sets, block.begin, block.end,
                                                  projection.dt);
      };
      if ((stage.set == StageSet::coloured || stage.set == StageSet::contact_colours) &&
          settings_.mode != SolverMode::sequential) {
        for_each_share(blocks, [&](ConstraintFamily f, std::size_t begin, std::size_t end) {
          solve({f, std::uint32_t(begin), std::uint32_t(end)});
        });
      } else {
        // A Jacobi set's (or the input order's) constraints may share particles: in order.
        for (const ScheduleBlock& block : blocks) solve(block);
      }
      return;
    }
  }
}

void Solver::jacobi_projection(JacobiSet& jacobi, JacobiWork& work,
                               std::span<const ScheduleBlock> blocks,
                               const ProjectionSettings& projection) {
  std::array<Real*, kConstraintFamilyCount> lambdas{};
  jacobi.constraints.for_each([&](ConstraintFamily family, auto& batch) {
    if (family_traits(family).xpbd) lambdas[std::size_t(family)] = lambda_of(batch);
  });
  const Real omega = settings_.jacobi_relaxation;
  parallel_chunks(blocks.size(), 1, [&](std::size_t first, std::size_t last) {
    for (std::size_t b = first; b < last; ++b) {
      const ScheduleBlock& block = blocks[b];
      const std::size_t f = std::size_t(block.family);
      // Gather from the particles, store into this family's incidences.
      ParticleArrays particles = sweep_arrays();
      particles.corrected_x = work.x.data() + jacobi.incidence_base[f];
      particles.corrected_y = work.y.data() + jacobi.incidence_base[f];
      particles.corrected_z = work.z.data() + jacobi.incidence_base[f];
      particles.corrected_stride = jacobi.incidence_stride[f];
      Real* lambda = lambdas[f];
      if (lambda == nullptr || projection.semantics != ConstraintSemantics::compliance) {
        kProjectBlock[f](particles, jacobi.constraints, block.begin, block.end, projection);
        continue;
      }
      // Δλ scaled by the constraint's share (JacobiSet::lambda_share), in sub-blocks whose
      // λ fit on the stack.
      const Real* share = jacobi.lambda_share[f].data();
      constexpr std::size_t kSub = 8 * kMaxLanes;
      for (std::size_t i = block.begin; i < block.end; i += kSub) {
        const std::size_t end = std::min<std::size_t>(block.end, i + kSub);
        Real before[kSub];
        std::copy(lambda + i, lambda + end, before);
        kProjectBlock[f](particles, jacobi.constraints, i, end, projection);
        for (std::size_t c = i; c < end; ++c)
          lambda[c] = before[c - i] + omega * share[c] * (lambda[c] - before[c - i]);
      }
    }
  });
}

void Solver::jacobi_reduction(const JacobiSet& jacobi, const JacobiWork& work, Real omega,
                              bool chebyshev) {
  // Chebyshev (SolverSettings::chebyshev): iteration n reads qₙ₋₁ here and makes q̂ₙ; it
  // keeps qₙ₋₁ for iteration n + 1 (from n = delay on) and, past the delay, moves to
  // qₙ₋₂ + ωₙ (q̂ₙ − qₙ₋₂). Element-wise per particle: no order, no thread dependence.
  const std::size_t n = chebyshev_iteration_, delay = settings_.chebyshev_delay;
  const bool keep = chebyshev && n >= delay;
  const bool extrapolate = chebyshev && n > delay;
  const Real weight = chebyshev_weight_;
  Real* previous_x = chebyshev_previous_[0].data();
  Real* previous_y = chebyshev_previous_[1].data();
  Real* previous_z = chebyshev_previous_[2].data();
  const ParticleArrays particles = sweep_arrays();
  const std::size_t stride = particles.stride;
  const auto reduce = [&]<bool Keep, bool Extrapolate>(std::size_t first, std::size_t last) {
    for (std::size_t k = first; k < last; ++k) {
      const ParticleIndex p = jacobi.particles[k];
      const std::uint32_t begin = jacobi.particle_offsets[k], end = jacobi.particle_offsets[k + 1];
      const std::size_t at = p * stride;
      const Real x = particles.x[at], y = particles.y[at], z = particles.z[at];
      Real dx = 0, dy = 0, dz = 0;
      for (std::uint32_t j = begin; j < end; ++j) {
        const std::uint32_t i = jacobi.particle_incidences[j];
        dx += work.x[i] - x;
        dy += work.y[i] - y;
        dz += work.z[i] - z;
      }
      const Real scale = omega / Real(end - begin);
      Real qx = x + scale * dx, qy = y + scale * dy, qz = z + scale * dz;
      if constexpr (Extrapolate) {
        qx = previous_x[k] + weight * (qx - previous_x[k]);
        qy = previous_y[k] + weight * (qy - previous_y[k]);
        qz = previous_z[k] + weight * (qz - previous_z[k]);
      }
      if constexpr (Keep) {
        previous_x[k] = x;
        previous_y[k] = y;
        previous_z[k] = z;
      }
      particles.x[at] = qx;
      particles.y[at] = qy;
      particles.z[at] = qz;
    }
  };
  parallel_chunks(jacobi.particles.size(), kParticleChunk, [&](std::size_t first, std::size_t last) {
    if (extrapolate) reduce.template operator()<true, true>(first, last);
    else if (keep) reduce.template operator()<true, false>(first, last);
    else reduce.template operator()<false, false>(first, last);
  });
}

void Solver::iterate(const ProjectionSettings& projection, std::size_t iteration) {
  const std::size_t delay = settings_.chebyshev_delay;
  const Real rho2 = settings_.chebyshev_rho * settings_.chebyshev_rho;
  chebyshev_iteration_ = iteration;
  chebyshev_weight_ = iteration <= delay     ? Real(1)
                      : iteration == delay + 1 ? Real(2) / (Real(2) - rho2)
                                               : Real(4) / (Real(4) - rho2 * chebyshev_weight_);
  if (!phase_hook_) {
    // Runs of coloured phases go to one parallel region each (phase_region.hpp).
    const auto in_region = [](const Stage& stage) {
      return stage.kind == StageKind::coloured_phase &&
             (stage.set == StageSet::coloured || stage.set == StageSet::contact_colours);
    };
    for (std::size_t i = 0; i < stages_.size();) {
      std::size_t end = i;
      while (end < stages_.size() && in_region(stages_[end])) ++end;
      if (settings_.phase_regions && end - i >= 2 && statistics_.threads > 1) {
        run_phase_region(i, end, projection);
        i = end;
      } else {
        run_stage(stages_[i++], projection);
      }
    }
    return;
  }
  phase_hook_(kBeforePhases, sweep_arrays());
  std::size_t phase = 0;
  for (const Stage& stage : stages_) {
    run_stage(stage, projection);
    if (stage.kind == StageKind::coloured_phase && stage.set == StageSet::coloured)
      phase_hook_(phase++, sweep_arrays());
  }
}

void Solver::run_phase_region(std::size_t first, std::size_t last,
                              const ProjectionSettings& projection) {
  const std::size_t shares = statistics_.threads;
  if (!phase_region_) phase_region_ = std::make_unique<detail::PhaseRegion>();
  detail::PhaseRegion& region = *phase_region_;
  region.reset(last - first, shares);
  const ParticleArrays particles = sweep_arrays();
  const auto run_share = [&](std::size_t phase, std::size_t share) {
    const Stage& stage = stages_[first + phase];
    // The same slice every iteration, so a thread's particles stay in its cache.
    detail::for_share_of_phase(
        blocks_of(stage), share, shares,
        [&](ConstraintFamily f, std::size_t begin, std::size_t end) {
          project_range(particles, stage.set, f, begin, end, projection);
        });
  };
  parallel_chunks(shares, 1, [&](std::size_t first_share, std::size_t last_share) {
    for (std::size_t share = first_share; share < last_share; ++share) region.run(share, run_share);
  });
}

bool Solver::substeps_fit_one_region() const {
  // Every substep but the last (which may read residuals, and ends with the velocity update
  // alone) is: the iterations' coloured phases, then the velocity update fused with the next
  // prediction. Nothing else may run between them: no contacts to detect, no velocity pass,
  // no Jacobi stage, no hook that reads the phases.
  if (!settings_.phase_regions || statistics_.threads < 2 || phase_hook_ || collisions_)
    return false;
  if (settings_.substeps < 2 || settings_.iterations == 0) return false;
  if (settings_.mode != SolverMode::gs && settings_.mode != SolverMode::hybrid) return false;
  if (!velocity_stages_.empty() || stages_.empty() || dynamic_count_ != 0) return false;
  return std::all_of(stages_.begin(), stages_.end(), [](const Stage& stage) {
    return stage.kind == StageKind::coloured_phase && stage.set == StageSet::coloured;
  });
}

double Solver::run_substeps_in_one_region(Real h, const ProjectionSettings& projection,
                                          std::size_t substeps, bool predict_first) {
  //   predict_first:           the first substep's prediction
  //   per substep:             iterations × the coloured phases (the first zeroes λ), then
  //                            the velocity update fused with the next substep's prediction
  // Each a phase of one region: the threads fork once instead of (iterations + 1) times per
  // substep, and every pass is cut the same way each time.
  const std::size_t shares = statistics_.threads;
  const std::size_t colours = stages_.size(), iterations = settings_.iterations;
  const std::size_t per_substep = iterations * colours + 1;
  const std::size_t first = predict_first ? 1 : 0;
  const IntegrationStep step = integration_step(h);
  const bool interleaved = prepare_interleaved();
  Real* xyzw = interleaved ? interleaved_.data() : nullptr;
  const std::size_t n = state_.size();
  // A share of the particle passes: cut at whole vectors (the passes run whole vectors).
  const auto cut = [&](std::size_t s) {
    return s == shares ? n : std::min(n, (n * s / shares) / kMaxLanes * kMaxLanes);
  };
  // What sweep_arrays() gives while sweeping.
  const ParticleArrays particles =
      interleaved ? ParticleArrays::of_interleaved(xyzw, n) : ParticleArrays::of(state_);
  if (!phase_region_) phase_region_ = std::make_unique<detail::PhaseRegion>();
  detail::PhaseRegion& region = *phase_region_;
  region.reset(first + substeps * per_substep, shares);
  double particle_pass_seconds = 0;  // share 0's, to leave out of the projection time
  const auto run_share = [&](std::size_t phase, std::size_t share) {
    const std::size_t within = phase < first ? per_substep - 1 : (phase - first) % per_substep;
    if (within == per_substep - 1) {  // a particle pass
      const auto start = Clock::now();
      if (phase < first)
        predict_positions(state_, step, xyzw, cut(share), cut(share + 1));
      else
        update_velocities_and_predict(state_, step, xyzw, interleaved, cut(share), cut(share + 1));
      if (share == 0) particle_pass_seconds += seconds_since(start);
      return;
    }
    const Stage& stage = stages_[within % colours];
    detail::for_share_of_phase(blocks_of(stage), share, shares,
                               [&](ConstraintFamily f, std::size_t begin, std::size_t end) {
                                 project_range(particles, stage.set, f, begin, end, projection,
                                               within < colours);
                               });
  };
  // Set last, once nothing is left to allocate: a throw before the region must not copy a
  // stale interleaved copy into the state.
  fresh_lambdas_ = true;  // substeps before the last read no residual before their iterations
  sweeping_ = interleaved;
  const EndSweeps end_sweeps_on_exit{this};  // if a phase throws: the sweeps' positions back
  parallel_chunks(shares, 1, [&](std::size_t first_share, std::size_t last_share) {
    for (std::size_t share = first_share; share < last_share; ++share) region.run(share, run_share);
  });
  // The state holds the last prediction, and so does the copy.
  sweeping_ = false;
  interleaved_current_ = interleaved;
  return particle_pass_seconds;
}

void Solver::set_phase_hook(PhaseHook hook) {
  if (hook && schedule_.part_count() != 0)
    throw InvalidInput(std::string("set_phase_hook: sweep order part-major") +
                       (settings_.sweep_order == SweepOrder::automatic
                            ? " (chosen by auto for " + std::to_string(schedule_.part_count()) +
                                  " parts)"
                            : "") +
                       " sweeps the parts' colours without a phase boundary between them "
                       "(colour-major has one)");
  if (hook && settings_.mode != SolverMode::gs)
    throw InvalidInput(std::string("set_phase_hook: mode ") +
                       std::string(solver_mode_name(settings_.mode)) +
                       " has no coloured phases between which to run it (mode gs has)");
  phase_hook_ = std::move(hook);
}

bool Solver::guards_divergence() const {
  return settings_.report_residuals && std::isfinite(settings_.divergence_rms);
}

void Solver::save_state() {
  if (!settings_.check_finite && !guards_divergence()) return;
  AlignedVector<Real>* arrays[6] = {&state_.x, &state_.y, &state_.z,
                                    &state_.velocity_x, &state_.velocity_y, &state_.velocity_z};
  for (std::size_t a = 0; a < 6; ++a) saved_[a].assign(arrays[a]->begin(), arrays[a]->end());
}

void Solver::restore_if_not_finite(const char* operation) {
  if (!settings_.check_finite) return;
  AlignedVector<Real>* arrays[6] = {&state_.x, &state_.y, &state_.z,
                                    &state_.velocity_x, &state_.velocity_y, &state_.velocity_z};
  // The first non-finite particle of each chunk, then the first overall (deterministic).
  const std::size_t n = state_.size();
  const std::size_t chunks = (n + kParticleChunk - 1) / kParticleChunk;
  std::vector<std::size_t>& first_bad = first_bad_;  // kept: a step allocates nothing
  first_bad.assign(chunks, n);
  parallel_chunks(n, kParticleChunk, [&](std::size_t first, std::size_t last) {
    for (std::size_t i = first; i < last; ++i) {
      Real sum = 0;  // finite iff every term is (x - x is 0 only for finite x)
      for (const AlignedVector<Real>* a : arrays) sum += (*a)[i] - (*a)[i];
      if (sum != 0 || sum != sum) {
        first_bad[first / kParticleChunk] = i;
        return;
      }
    }
  });
  const auto bad = std::min_element(first_bad.begin(), first_bad.end());
  if (bad == first_bad.end() || *bad == n) return;
  const ParticleIndex particle = schedule_.user_particle(ParticleIndex(*bad));
  restore_saved_state();
  throw NumericalFailure(std::string("solver: ") + operation + " made particle " +
                         std::to_string(particle) +
                         " non-finite; positions and velocities are restored to before it "
                         "(check the time step, compliance and velocities)");
}

void Solver::restore_saved_state() {
  AlignedVector<Real>* arrays[6] = {&state_.x, &state_.y, &state_.z,
                                    &state_.velocity_x, &state_.velocity_y, &state_.velocity_z};
  for (std::size_t a = 0; a < 6; ++a) std::copy(saved_[a].begin(), saved_[a].end(), arrays[a]->begin());
}

void Solver::restore_if_diverged(const char* operation) {
  if (!guards_divergence()) return;
  const Residual& after = report_.residual_after;
  if (!(after.rms > double(settings_.divergence_rms))) return;
  const FamilyResidual& worst = after.of(after.worst_family);
  restore_saved_state();
  char numbers[160];
  std::snprintf(numbers, sizeof numbers, "residual RMS %.3g exceeds the bound %.3g; the largest, %.3g, is ",
                after.rms, double(settings_.divergence_rms), worst.max);
  throw NumericalFailure(std::string("solver: ") + operation + " diverged: " + numbers +
                         std::string(family_name(after.worst_family)) +
                         (worst.worst_is_dynamic ? " dynamic constraint " : " constraint ") +
                         std::to_string(worst.worst) +
                         "; positions and velocities are restored to before it (more substeps or "
                         "iterations, a smaller time step, or SolverSettings::divergence_rms)");
}

void Solver::project(std::size_t iterations, Real dt) {
  if (!(std::isfinite(dt) && dt > 0))
    throw InvalidInput("solver: projection time step must be positive and finite (got " +
                       std::to_string(dt) + ")");
  const ProjectionSettings projection{settings_.semantics, dt};
  projection_dt_ = dt;
  const auto start = Clock::now();
  save_state();
  interleaved_current_ = false;  // the state may have been set since the last step
  {
    begin_sweeps();
    const EndSweeps end_sweeps_on_exit{this};  // also when a phase hook throws
    for (std::size_t it = 0; it < iterations; ++it) iterate(projection, it + 1);
  }
  restore_if_not_finite("a projection");
  statistics_.seconds_projection += seconds_since(start);
  statistics_.projections +=
      std::uint64_t(iterations) * (statistics_.constraints + dynamic_count_);
}

void Solver::project_range(const ParticleArrays& particles, StageSet set, ConstraintFamily f,
                           std::size_t begin, std::size_t end,
                           const ProjectionSettings& projection) {
  project_range(particles, set, f, begin, end, projection, chebyshev_iteration_ == 1);
}

void Solver::project_range(const ParticleArrays& particles, StageSet set, ConstraintFamily f,
                           std::size_t begin, std::size_t end,
                           const ProjectionSettings& projection, bool first_iteration) {
  ConstraintSets& sets = batches_of(set);
  if (fresh_lambdas_ && set == StageSet::coloured && first_iteration) {
    // The substep's λ reset. Under compliance semantics every family with λ stores it, so
    // the kernel starts from 0 without reading it; under stiffness semantics only the
    // contacts do, and the range is zeroed as a reset would.
    if (projection.semantics == ConstraintSemantics::compliance) {
      ProjectionSettings fresh = projection;
      fresh.lambda_starts_at_zero = true;
      kProjectBlock[std::size_t(f)](particles, sets, begin, end, fresh);
      return;
    }
    kZeroLambdas[std::size_t(f)](sets, begin, end);
  }
  kProjectBlock[std::size_t(f)](particles, sets, begin, end, projection);
}

void Solver::reset_lambdas() { zero_lambdas(true); }

void Solver::zero_lambdas(bool coloured) {
  // In parallel chunks: on the 1024² cloth the multipliers are 25 MB per substep.
  constexpr std::size_t kLambdaChunk = std::size_t(1) << 16;
  const auto reset = [&](ConstraintFamily, auto& batch) {
    if (lambda_of(batch))
      parallel_chunks(padded_size(batch.size()), kLambdaChunk,
                      [&](std::size_t first, std::size_t last) {
                        zero_lambda_range(batch, first, last);
                      });
  };
  if (coloured) schedule_.coloured().for_each(reset);
  schedule_.jacobi().constraints.for_each(reset);
  dynamic_.constraints.for_each(reset);
  contacts_.constraints.for_each(reset);
  if (contact_colours_) contact_colours_->constraints.for_each(reset);
}

IntegrationStep Solver::integration_step(Real h) const {
  IntegrationStep step{h, {settings_.gravity.x() * h, settings_.gravity.y() * h,
                           settings_.gravity.z() * h}};
  step.velocity_scale = std::max(Real(0), Real(1) - settings_.velocity_damping * h) / h;
  return step;
}

void Solver::integrate(Real h) {
  // Interleaved, the prediction also makes the sweeps' copy (begin_sweeps has nothing to do).
  const IntegrationStep step = integration_step(h);
  Real* xyzw = prepare_interleaved() ? interleaved_.data() : nullptr;
  parallel_chunks(state_.size(), kParticleChunk, [&](std::size_t first, std::size_t last) {
    predict_positions(state_, step, xyzw, first, last);
  });
  interleaved_current_ = xyzw != nullptr;
}

ParticleArrays Solver::sweep_arrays() {
  if (!sweeping_) return ParticleArrays::of(state_);
  return ParticleArrays::of_interleaved(interleaved_.data(), state_.size());
}

bool Solver::prepare_interleaved() {
  interleaved_current_ = false;
  if (settings_.particle_layout != ParticleLayout::interleaved) return false;
  interleaved_.resize(4 * padded_size(state_.size()));  // the passes run whole vectors
  return true;
}

void Solver::begin_sweeps() {
  const bool current = interleaved_current_;  // made by this substep's prediction
  if (!prepare_interleaved()) return;
  if (!current)
    parallel_chunks(state_.size(), kParticleChunk, [&](std::size_t first, std::size_t last) {
      interleave_particles(state_, interleaved_.data(), first, last);
    });
  sweeping_ = true;
}

void Solver::end_sweeps() {
  fresh_lambdas_ = false;  // the first iteration is over (or threw)
  if (!sweeping_) return;
  parallel_chunks(state_.size(), kParticleChunk, [&](std::size_t first, std::size_t last) {
    deinterleave_positions(interleaved_.data(), state_, first, last);
  });
  sweeping_ = false;
}

void Solver::update_velocities(Real h) {
  const Real scale = std::max(Real(0), Real(1) - settings_.velocity_damping * h) / h;
  parallel_chunks(state_.size(), kParticleChunk, [&](std::size_t first, std::size_t last) {
    for (std::size_t i = first; i < last; ++i) {
      if (!(state_.inverse_mass[i] > 0)) {
        state_.velocity_x[i] = state_.velocity_y[i] = state_.velocity_z[i] = 0;
        continue;
      }
      state_.velocity_x[i] = (state_.x[i] - state_.previous_x[i]) * scale;
      state_.velocity_y[i] = (state_.y[i] - state_.previous_y[i]) * scale;
      state_.velocity_z[i] = (state_.z[i] - state_.previous_z[i]) * scale;
    }
  });
}

void Solver::update_velocities_and_integrate(Real h) {
  // Reads the sweeps' positions (the interleaved copy while sweeping) and writes the
  // prediction to the state and, interleaved, to the next substep's sweep copy: between two
  // substeps the copies in and out of the interleaved layout cost no pass of their own.
  const IntegrationStep step = integration_step(h);
  const bool interleaved = sweeping_;
  Real* xyzw = interleaved ? interleaved_.data() : nullptr;
  parallel_chunks(state_.size(), kParticleChunk, [&](std::size_t first, std::size_t last) {
    update_velocities_and_predict(state_, step, xyzw, interleaved, first, last);
  });
  sweeping_ = false;  // the state holds the positions again, and the copy the prediction
  interleaved_current_ = interleaved;
}

void Solver::step() {
  const auto start = Clock::now();
  const Real h = settings_.time_step / Real(settings_.substeps);
  const ProjectionSettings projection{settings_.semantics, h};
  projection_dt_ = h;
  report_.history.clear();
  save_state();
  interleaved_current_ = false;  // a copy left by a step that threw is not this state's
  bool predicted = false;  // by the fused pass at the end of the substep before
  std::size_t substep = 0;
  if (substeps_fit_one_region()) {
    // Regions of at most kMostRegionPhases phases (their claims are phases × threads bytes).
    const std::size_t per_substep = settings_.iterations * stages_.size() + 1;
    const std::size_t per_region = std::max<std::size_t>(1, kMostRegionPhases / per_substep);
    for (const std::size_t before_last = settings_.substeps - 1; substep < before_last;) {
      const std::size_t count = std::min(per_region, before_last - substep);
      const auto region_start = Clock::now();
      const double particle_passes =
          run_substeps_in_one_region(h, projection, count, substep == 0);
      statistics_.seconds_projection +=
          std::max(0.0, seconds_since(region_start) - particle_passes);
      statistics_.projections += std::uint64_t(count) * settings_.iterations *
                                 (statistics_.constraints + dynamic_count_);
      substep += count;
    }
    predicted = true;
    ++statistics_.steps_in_one_region;
  }
  for (; substep < settings_.substeps; ++substep) {
    const bool last = substep + 1 == settings_.substeps;
    if (!predicted) integrate(h);
    predicted = false;
    if (collisions_) detect_contacts(h);
    // The coloured set's λ are zeroed by the first iteration, range by range, unless a
    // residual reads them before it (fresh_lambdas_).
    // Not with a phase hook, which may read λ of phases not yet swept.
    fresh_lambdas_ = settings_.iterations != 0 && !phase_hook_ &&
                     (settings_.mode == SolverMode::gs || settings_.mode == SolverMode::hybrid) &&
                     !(last && (settings_.report_residuals || settings_.record_convergence));
    zero_lambdas(!fresh_lambdas_);
    if (last && settings_.report_residuals) report_.residual_before = residual();
    if (last && settings_.record_convergence) report_.history.push_back(report_.residual_before);
    const auto projection_start = Clock::now();
    {
      begin_sweeps();
      const EndSweeps end_sweeps_on_exit{this};  // also when a phase hook throws
      for (std::size_t it = 0; it < settings_.iterations; ++it) {
        iterate(projection, it + 1);
        if (last && settings_.record_convergence) {
          statistics_.seconds_projection += seconds_since(projection_start);
          report_.history.push_back(residual());
        }
      }
      if (!(last && settings_.record_convergence))
        statistics_.seconds_projection += seconds_since(projection_start);
      statistics_.projections += std::uint64_t(settings_.iterations) *
                                 (statistics_.constraints + dynamic_count_ +
                                  contacts_.constraint_count +
                                  (contact_colours_ ? contact_colours_->constraint_count : 0));
      // Between two substeps with no velocity pass, the velocity update and the next
      // prediction are one pass over the particles, reading the sweeps' copy directly.
      if (!last && velocity_stages_.empty()) {
        update_velocities_and_integrate(h);
        predicted = true;
      }
    }
    if (predicted) continue;
    update_velocities(h);
    for (const Stage& stage : velocity_stages_) run_stage(stage, projection);
    if (last && settings_.report_residuals) report_.residual_after = residual();
  }
  const std::string operation = "step " + std::to_string(statistics_.steps + 1);
  restore_if_not_finite(operation.c_str());
  restore_if_diverged(operation.c_str());
  ++statistics_.steps;
  statistics_.seconds_stepping += seconds_since(start);
}

Residual Solver::residual() {
  static const std::array<std::vector<ScheduleBlock>, kConstraintFamilyCount> kNoRanges;
  if (!residual_scratch_) residual_scratch_ = std::make_unique<detail::ResidualScratch>();
  std::vector<detail::ResidualRange>& ranges = residual_scratch_->ranges;
  detail::residual_ranges(schedule_, dynamic_.constraints, contacts_.constraints,
                          contact_colours_ ? contact_colours_->ranges : kNoRanges,
                          kResidualChunk, ranges);
  std::vector<detail::ResidualPartial>& partials = residual_scratch_->partials;
  partials.assign(ranges.size(), {});
  const ParticleArrays particles = sweep_arrays();
  // XPBD: the residual of the equations the last projections solved, C + α̃λ at their dt.
  const Real compliance_dt =
      settings_.semantics == ConstraintSemantics::compliance ? projection_dt_ : Real(0);
  parallel_chunks(ranges.size(), 1, [&](std::size_t first, std::size_t last) {
    for (std::size_t k = first; k < last; ++k) {
      const auto& range = ranges[k];
      const ConstraintSets& sets = range.set == detail::ResidualRange::coloured
                                       ? schedule_.coloured()
                                   : range.set == detail::ResidualRange::jacobi
                                       ? schedule_.jacobi().constraints
                                   : range.set == detail::ResidualRange::contacts
                                       ? contacts_.constraints
                                   : range.set == detail::ResidualRange::contact_colours
                                       ? contact_colours_->constraints
                                       : dynamic_.constraints;
      partials[k] = detail::residual_of_range(range, sets, particles, compliance_dt);
    }
  });
  std::array<detail::WorstPlace, kConstraintFamilyCount> worst;
  Residual result = detail::combine_residual(ranges, partials, worst);
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f) {
    FamilyResidual& family = result.families[f];
    if (family.constraints == 0) continue;
    family.worst_is_dynamic = worst[f].set == detail::ResidualRange::dynamic;
    const bool coloured_contact = worst[f].set == detail::ResidualRange::contact_colours;
    family.worst_is_contact = worst[f].set == detail::ResidualRange::contacts || coloured_contact;
    const auto& contact_source = contact_source_[f];
    family.worst = family.worst_is_dynamic ? dynamic_user_index(ConstraintFamily(f), worst[f].slot)
                   : coloured_contact ? contact_colours_->source[f][worst[f].slot]
                   : family.worst_is_contact
                       ? (contact_source.empty() ? worst[f].slot : contact_source[worst[f].slot])
                       : schedule_.user_constraint(ConstraintFamily(f),
                                                   worst[f].set == detail::ResidualRange::jacobi,
                                                   worst[f].slot);
  }
  return result;
}

std::size_t Solver::dynamic_user_index(ConstraintFamily family, std::uint32_t slot) const {
  const auto& source = dynamic_source_[std::size_t(family)];
  return source.empty() ? slot : source[slot];
}

void Solver::check_particle(ParticleIndex particle) const {
  if (particle >= state_.size())
    throw InvalidInput("particle " + std::to_string(particle) + " does not exist (the model has " +
                       std::to_string(state_.size()) + ")");
}

Vector3r Solver::position(ParticleIndex particle) const {
  check_particle(particle);
  return state_.position(schedule_.scheduled_particle(particle));
}

Vector3r Solver::velocity(ParticleIndex particle) const {
  check_particle(particle);
  return state_.velocity(schedule_.scheduled_particle(particle));
}

Real Solver::inverse_mass(ParticleIndex particle) const {
  check_particle(particle);
  return state_.inverse_mass[schedule_.scheduled_particle(particle)];
}

std::vector<Vector3r> Solver::positions() const {
  std::vector<Vector3r> result(state_.size());
  for (std::size_t p = 0; p < result.size(); ++p)
    result[schedule_.user_particle(ParticleIndex(p))] = state_.position(p);
  return result;
}

std::vector<Vector3r> Solver::velocities() const {
  std::vector<Vector3r> result(state_.size());
  for (std::size_t p = 0; p < result.size(); ++p)
    result[schedule_.user_particle(ParticleIndex(p))] = state_.velocity(p);
  return result;
}

void Solver::set_position(ParticleIndex particle, const Vector3r& position) {
  check_particle(particle);
  if (!position.allFinite())
    throw InvalidInput("particle " + std::to_string(particle) + ": position is not finite");
  state_.set_position(schedule_.scheduled_particle(particle), position);
}

void Solver::set_velocity(ParticleIndex particle, const Vector3r& velocity) {
  check_particle(particle);
  if (!velocity.allFinite())
    throw InvalidInput("particle " + std::to_string(particle) + ": velocity is not finite");
  const ParticleIndex p = schedule_.scheduled_particle(particle);
  state_.velocity_x[p] = velocity.x();
  state_.velocity_y[p] = velocity.y();
  state_.velocity_z[p] = velocity.z();
}

Real Solver::lambda(ConstraintIndex constraint) const {
  const ConstraintLocation where = schedule_.locate(constraint);
  Real result = 0;
  const auto read = [&](ConstraintFamily family, auto& batch) {
    if (family != where.family) return;
    if (const Real* lambda = lambda_of(batch)) result = lambda[where.slot];
  };
  auto& sets = const_cast<Schedule&>(schedule_);
  if (where.in_jacobi_set)
    sets.jacobi().constraints.for_each(read);
  else
    sets.coloured().for_each(read);
  return result;
}

void Solver::set_dynamic_constraints(ConstraintSets constraints) {
  constraints.for_each([&](ConstraintFamily family, const auto& batch) {
    const std::size_t built_for = built_for_particles(batch);
    if (batch.size() != 0 && built_for > state_.size())
      throw InvalidInput("dynamic " + std::string(family_name(family)) +
                         " constraints were built for " + std::to_string(built_for) +
                         " particles, the model has " + std::to_string(state_.size()));
  });
  dynamic_count_ = constraints.size();
  extra_set(constraints, dynamic_source_, false, dynamic_);
  dynamic_work_.bind(dynamic_);
  build_stages();
}

void Solver::extra_set(const ConstraintSets& constraints,
                       std::array<std::vector<std::uint32_t>, kConstraintFamilyCount>& source,
                       bool scheduled_numbering, JacobiSet& set) {
  const auto sizes = constraints.sizes();
  if (settings_.mode == SolverMode::sequential) {
    // Swept as given, family by family (the user's numbering is the solver's). Copied into
    // the set's own arrays (a copy assignment keeps their capacity).
    for (auto& list : source) list.clear();
    set.incidence_base = {};
    set.incidence_stride = {};
    set.incidence_particle.clear();
    set.incidence_count = 0;
    set.particles.clear();
    set.particle_offsets.clear();
    set.particle_incidences.clear();
    for (auto& share : set.lambda_share) share.clear();
    set.blocks.clear();
    for (std::size_t f = 0; f < kConstraintFamilyCount; ++f)
      if (sizes[f] != 0) set.blocks.push_back({ConstraintFamily(f), 0, std::uint32_t(sizes[f])});
    set.constraint_count = constraints.size();
    set.constraints = constraints;
    return;
  }
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f) {
    source[f].resize(sizes[f]);
    for (std::size_t i = 0; i < sizes[f]; ++i) source[f][i] = std::uint32_t(i);
  }
  if (!jacobi_scratch_) jacobi_scratch_ = std::make_unique<detail::JacobiSetScratch>();
  detail::build_jacobi_set(
      set, *jacobi_scratch_, constraints, source, state_.size(),
      [&](ParticleIndex p) { return scheduled_numbering ? p : schedule_.scheduled_particle(p); },
      [&](ParticleIndex scheduled) { return state_.inverse_mass[scheduled] > 0; },
      schedule_.options());
}

void Solver::set_collisions(CollisionSettings settings,
                            std::span<const std::uint32_t> surface_triangles,
                            std::span<const std::uint32_t> tetrahedra) {
  // Both element lists in the schedule's numbering, so no contact is renumbered per substep.
  const auto scheduled = [&](std::span<const std::uint32_t> elements, std::size_t corners,
                             const char* what, const char* whole, const char* noun) {
    if (elements.size() % corners != 0)
      throw InvalidInput("collisions: the " + std::string(whole) + " has " +
                         std::to_string(elements.size()) + " " + noun +
                         " indices, not a multiple of " + std::to_string(corners));
    std::vector<std::uint32_t> result(elements.size());
    for (std::size_t i = 0; i < elements.size(); ++i) {
      if (elements[i] >= state_.size())
        throw InvalidInput("collisions: " + std::string(what) + " " +
                           std::to_string(i / corners) + " names particle " +
                           std::to_string(elements[i]) + ", the model has " +
                           std::to_string(state_.size()));
      result[i] = schedule_.scheduled_particle(elements[i]);
    }
    return result;
  };
  std::vector<std::uint32_t> triangles = scheduled(surface_triangles, 3, "surface triangle", "surface", "triangle");
  const std::vector<std::uint32_t> tets = scheduled(tetrahedra, 4, "tetrahedron", "solid", "tetrahedron");
  collisions_ = std::make_unique<CollisionStage>(std::move(settings), std::move(triangles),
                                                 state_.size(), tets);
  if (colours_contacts()) contact_masks_.assign(state_.size(), 0);
}

std::vector<std::uint32_t> Solver::contact_counts() const {
  std::vector<std::uint32_t> counts(state_.size(), 0);
  contacts_found_.for_each([&](ConstraintFamily, const auto& batch) {
    // Contacts are fixed-arity families (shape matching, with its clusters, never is one).
    if constexpr (kFixedArity<std::decay_t<decltype(batch)>>)
      for (const auto& slot : batch.particles.particle)
        for (std::size_t c = 0; c < batch.size(); ++c) ++counts[schedule_.user_particle(slot[c])];
  });
  return counts;
}

void Solver::clear_collisions() {
  collisions_.reset();
  contacts_ = JacobiSet();
  contacts_found_ = ConstraintSets();
  contact_colours_.reset();
  contact_source_ = {};
  contacts_work_.bind(contacts_);
  build_stages();
}

void Solver::detect_contacts(Real h) {
  arena_->execute(
      [&] { collisions_->detect(state_, h, Real(settings_.gravity.norm()), contacts_found_); });
  // The contacts come in the schedule's numbering, sorted by particle: the sets' order is
  // theirs, whatever the thread count.
  const auto start = Clock::now();
  if (!colours_contacts()) {
    extra_set(contacts_found_, contact_source_, true, contacts_);
  } else {
    // Coloured into the same buffers every substep: no allocation once the contacts stop
    // growing.
    if (!contact_colours_) contact_colours_ = std::make_unique<detail::ColouredContacts>();
    detail::colour_contacts(contacts_found_, contact_masks_, inverse_masses(), *contact_colours_);
    // The overflow as a Jacobi set; its slots lead back to the found contacts.
    std::size_t overflowed = 0;
    contact_overflow_.for_each([&](ConstraintFamily family, auto& batch) {
      using Batch = std::decay_t<decltype(batch)>;
      const auto& list = contact_colours_->overflow[std::size_t(family)];
      overflowed += list.size();
      detail::reorder_batch_into(batch, contacts_found_.of_type<Batch>(), list,
                                 detail::kNoContact, state_.size(),
                                 [](std::size_t, std::size_t, ParticleIndex p) { return p; });
    });
    if (overflowed != 0) {
      extra_set(contact_overflow_, contact_source_, true, contacts_);
    } else if (contacts_.constraint_count != 0 || !contacts_.blocks.empty()) {
      contacts_ = JacobiSet();
    }
    if (overflowed == 0)
      for (auto& list : contact_source_) list.clear();
    for (std::size_t f = 0; f < kConstraintFamilyCount; ++f)
      for (std::uint32_t& s : contact_source_[f]) s = contact_colours_->overflow[f][s];
    const std::size_t colours = contact_colours_->colour_count();
    statistics_.contact_colours_total += colours;
    statistics_.contact_colours_max = std::max(statistics_.contact_colours_max, colours);
    statistics_.contacts_overflowed += overflowed;
  }
  contacts_work_.bind(contacts_);
  build_stages();
  ++statistics_.contact_substeps;
  statistics_.seconds_contact_scheduling += seconds_since(start);
}

}  // namespace tessera
