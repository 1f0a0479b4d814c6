// The solver on many ranks, exact mode (distributed_solver.hpp): the rank's part of the model
// built through the decomposition, the ordinary Solver on it, and the colour exchanges run
// from its phase hook.
#include <tessera/distributed/distributed_solver.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>

#include <tessera/core/batch_reorder.hpp>
#include <tessera/core/error.hpp>

namespace tessera {
namespace {

MPI_Datatype real_type() { return std::is_same_v<Real, double> ? MPI_DOUBLE : MPI_FLOAT; }

constexpr std::uint32_t kNoSource = std::numeric_limits<std::uint32_t>::max();
constexpr std::size_t kNoColour = std::numeric_limits<std::size_t>::max();

/// The particles of `held` (global ids, ascending) as a model of their own.
ParticleState particles_held(const ParticleState& all, const std::vector<ParticleIndex>& held) {
  ParticleState part(held.size());
  const auto copy = [&](AlignedVector<Real>& to, const AlignedVector<Real>& from) {
    for (std::size_t i = 0; i < held.size(); ++i) to[i] = from[held[i]];
  };
  copy(part.x, all.x);
  copy(part.y, all.y);
  copy(part.z, all.z);
  copy(part.inverse_mass, all.inverse_mass);
  copy(part.previous_x, all.previous_x);
  copy(part.previous_y, all.previous_y);
  copy(part.previous_z, all.previous_z);
  copy(part.velocity_x, all.velocity_x);
  copy(part.velocity_y, all.velocity_y);
  copy(part.velocity_z, all.velocity_z);
  return part;
}

}  // namespace

DistributedSolver::DistributedSolver(const Model& model, const Colouring& colouring,
                                     SolverSettings settings, MPI_Comm communicator,
                                     DistributedMode mode)
    : communicator_(communicator), mode_(mode), divergence_rms_(settings.divergence_rms) {
  if (settings.mode != SolverMode::gs)
    throw InvalidInput(std::string("distributed ") +
                       (mode == DistributedMode::exact ? "exact" : "block") +
                       " mode: solver mode must be gs, not " +
                       std::string(solver_mode_name(settings.mode)));
  MPI_Comm_rank(communicator_, &rank_);
  MPI_Comm_size(communicator_, &rank_count_);
  const Decomposition plan = decompose(model, colouring, std::size_t(rank_count_));
  const RankDomain& mine = plan.ranks[std::size_t(rank_)];

  // Held particles (owned and ghosts) in ascending global order; local index = position.
  std::merge(mine.owned.begin(), mine.owned.end(), mine.ghosts.begin(), mine.ghosts.end(),
             std::back_inserter(held_));
  const auto local_of = [&](ParticleIndex global) {
    return std::uint32_t(std::lower_bound(held_.begin(), held_.end(), global) - held_.begin());
  };
  for (const ParticleIndex p : mine.owned) owned_local_.push_back(local_of(p));
  if (rank_ == 0)
    for (const RankDomain& domain : plan.ranks) owned_of_rank_.push_back(domain.owned);

  // The owned constraints, family by family (global ids run through the families in order),
  // their particles renamed to local indices.
  Model part;
  part.particles = particles_held(model.particles, held_);
  std::size_t next = 0;
  model.constraints.for_each([&](ConstraintFamily family, const auto& batch) {
    const ConstraintIndex first = batch.size() == 0 ? 0 : model.constraint_id(family, 0);
    std::vector<std::uint32_t> source;
    while (next < mine.constraints.size() && batch.size() != 0 &&
           mine.constraints[next] < first + batch.size())
      source.push_back(std::uint32_t(mine.constraints[next++] - first));
    using Batch = std::decay_t<decltype(batch)>;
    auto& out = part.constraints.of_type<Batch>();
    out = detail::reorder_batch(batch, source, kNoSource, held_.size(),
                                [&](std::size_t, std::size_t, ParticleIndex p) { return local_of(p); });
  });

  // The plan's transfers in local indices.
  colour_count_ = colouring.colour_count();
  sends_.resize(colour_count_);
  receives_.resize(colour_count_);
  for (std::size_t k = 0; k < colour_count_; ++k) {
    for (const RankExchange& send : mine.sends[k]) {
      Transfer& t = sends_[k].emplace_back(Transfer{int(send.rank), {}});
      for (const ParticleIndex p : send.particles) t.local.push_back(local_of(p));
    }
    for (const RankExchange& receive : mine.receives[k]) {
      Transfer& t = receives_[k].emplace_back(Transfer{int(receive.rank), {}});
      for (const ParticleIndex p : receive.particles) t.local.push_back(local_of(p));
    }
  }

  // Local colours: per global colour this rank has constraints in, its boundary part (the
  // constraints writing a particle the plan sends in that colour) then its interior part.
  std::vector<std::uint64_t> sent;  // (colour << 32) | local particle
  for (std::size_t k = 0; k < colour_count_; ++k)
    for (const Transfer& t : sends_[k])
      for (const std::uint32_t i : t.local) sent.push_back((std::uint64_t(k) << 32) | i);
  std::sort(sent.begin(), sent.end());
  std::vector<std::uint64_t> key(mine.constraints.size());  // (colour << 1) | interior
  std::vector<bool> moved_here(held_.size(), false);         // by this rank's constraints
  {
    std::size_t local = 0;
    part.constraints.for_each([&](ConstraintFamily, const auto& batch) {
      for (std::size_t i = 0; i < batch.size(); ++i, ++local) {
        const std::uint64_t colour = colouring.colour_of(mine.constraints[local]);
        bool boundary = false;
        const auto writes = [&](ParticleIndex p) {
          moved_here[p] = true;
          boundary = boundary || std::binary_search(sent.begin(), sent.end(), (colour << 32) | p);
        };
        if constexpr (requires { batch.particles; }) {
          for (const auto& slot : batch.particles.particle) writes(slot[i]);
        } else {
          for (std::size_t e = batch.offsets[i]; e < batch.offsets[i + 1]; ++e)
            writes(batch.particle[e]);
        }
        key[local] = (colour << 1) | (boundary ? 0 : 1);
      }
    });
  }
  std::vector<std::uint64_t> present(key);
  std::sort(present.begin(), present.end());
  present.erase(std::unique(present.begin(), present.end()), present.end());
  for (const std::uint64_t k : present) phases_.push_back({std::size_t(k >> 1), (k & 1) == 0});
  std::vector<Colour> local_colour(key.size());
  for (std::size_t i = 0; i < key.size(); ++i)
    local_colour[i] =
        Colour(std::lower_bound(present.begin(), present.end(), key[i]) - present.begin());
  open_colour_ = kNoColour;

  // Block mode's lists: who holds what besides its owner, and who moves it.
  if (mode_ == DistributedMode::block) {
    const auto movable = [&](ParticleIndex p) { return model.particles.inverse_mass[p] > 0; };
    std::vector<std::vector<ParticleIndex>> to_owner(static_cast<std::size_t>(rank_count_));
    for (const ParticleIndex p : mine.ghosts)
      if (movable(p)) to_owner[plan.owner_of_particle[p]].push_back(p);
    for (std::size_t r = 0; r < to_owner.size(); ++r) {
      if (to_owner[r].empty()) continue;
      Transfer& t = ghosts_by_owner_.emplace_back(Transfer{int(r), {}});
      for (const ParticleIndex p : to_owner[r]) t.local.push_back(local_of(p));
    }
    // My owned particles other ranks hold, per holder; and which of them my constraints move.
    std::vector<std::uint32_t> slot_of(held_.size(), kNoSource);
    for (std::size_t s = 0; s < plan.ranks.size(); ++s) {
      if (int(s) == rank_) continue;
      Transfer group{int(s), {}};
      std::vector<std::uint32_t> slots;
      for (const ParticleIndex p : plan.ranks[s].ghosts) {
        if (!movable(p) || plan.owner_of_particle[p] != Rank(rank_)) continue;
        const std::uint32_t i = local_of(p);
        if (slot_of[i] == kNoSource) {
          slot_of[i] = std::uint32_t(shared_owned_.size());
          shared_owned_.push_back(i);
        }
        group.local.push_back(i);
        slots.push_back(slot_of[i]);
      }
      if (group.local.empty()) continue;
      shared_by_holder_.push_back(std::move(group));
      holder_slot_.push_back(std::move(slots));
    }
    std::vector<std::uint32_t> movers(shared_owned_.size(), 0);
    for (const auto& slots : holder_slot_)
      for (const std::uint32_t slot : slots) ++movers[slot];
    for (std::size_t slot = 0; slot < shared_owned_.size(); ++slot)
      shared_weight_.push_back(Real(1) /
                               Real(movers[slot] + (moved_here[shared_owned_[slot]] ? 1 : 0)));
    for (const Transfer& t : ghosts_by_owner_)
      remembered_.insert(remembered_.end(), t.local.begin(), t.local.end());
    remembered_.insert(remembered_.end(), shared_owned_.begin(), shared_owned_.end());
  }

  statistics_.ranks = std::size_t(rank_count_);
  statistics_.owned_particles = mine.owned.size();
  statistics_.ghost_particles = mine.ghosts.size();
  statistics_.constraints = mine.constraints.size();

  // The finite and divergence checks are collective (step()); the rank's solver must not
  // throw on its own, or the other ranks would wait for it forever.
  check_finite_ = settings.check_finite;
  settings.check_finite = false;
  settings.divergence_rms = std::numeric_limits<Real>::infinity();
  settings.report_residuals = false;
  // The ghosts are exchanged between colours (the phase hook below), which a part-major sweep
  // does not keep apart: a rank sweeps colour by colour whatever its domain's size, and a part
  // size (which only sized the runs auto might have chosen) sizes nothing.
  if (settings.sweep_order == SweepOrder::automatic) {
    settings.sweep_order = SweepOrder::colour_major;
    settings.particles_per_part = 0;
  }
  solver_ = std::make_unique<Solver>(std::move(part), Colouring::from_colours(local_colour),
                                     settings);
  solver_->set_phase_hook([this](std::size_t phase, ParticleArrays particles) {
    if (mode_ == DistributedMode::block) {
      // One combination per iteration: after the last local colour (at the start for a rank
      // without colours, whose corrections are all zero).
      if (phase == Solver::kBeforePhases) remember_shared(particles);
      if ((phase == Solver::kBeforePhases && phases_.empty()) ||
          (phase != Solver::kBeforePhases && phase + 1 == phases_.size()))
        combine_shared(particles);
      return;
    }
    exchange_after(phase, particles);
  });
}

void DistributedSolver::exchange_after(std::size_t phase, ParticleArrays particles) {
  const auto start = std::chrono::steady_clock::now();
  std::size_t through = 0;  // the colours before this one are done
  if (phase != Solver::kBeforePhases) {
    const Phase& done = phases_[phase];
    if (open_colour_ != done.colour) start_exchange(done.colour, particles);
    const bool last_of_colour =
        phase + 1 == phases_.size() || phases_[phase + 1].colour != done.colour;
    if (!last_of_colour) {  // the interior part runs while the messages travel
      statistics_.seconds_exchange +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      return;
    }
    finish_exchange(particles);
    through = done.colour + 1;
  }
  // The colours this rank has nothing in, up to its next phase: receives only.
  const std::size_t next_phase = phase == Solver::kBeforePhases ? 0 : phase + 1;
  const std::size_t until =
      next_phase < phases_.size() ? phases_[next_phase].colour : colour_count_;
  for (std::size_t k = through; k < until; ++k) {
    start_exchange(k, particles);
    finish_exchange(particles);
  }
  statistics_.seconds_exchange +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void DistributedSolver::start_exchange(std::size_t k, ParticleArrays particles) {
  open_colour_ = k;
  requests_.clear();
  const auto& sends = sends_[k];
  const auto& receives = receives_[k];
  if (sends.empty() && receives.empty()) return;
  send_buffer_.clear();
  for (const Transfer& t : sends)
    for (const std::uint32_t i : t.local) {
      const std::size_t at = particles.at(i);
      send_buffer_.insert(send_buffer_.end(), {particles.x[at], particles.y[at], particles.z[at]});
    }
  // MPI guarantees tags up to 32767 (block mode uses the last two); order is per pair.
  post(sends, send_buffer_, receives, int(k % 32766));
}

void DistributedSolver::finish_exchange(ParticleArrays particles) {
  const std::size_t k = open_colour_;
  open_colour_ = kNoColour;
  if (requests_.empty()) return;
  MPI_Waitall(int(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE);
  requests_.clear();
  std::size_t offset = 0;
  for (const Transfer& t : receives_[k]) {
    const Real* in = receive_buffer_.data() + offset;
    for (std::size_t i = 0; i < t.local.size(); ++i) {
      particles.x[particles.at(t.local[i])] = in[3 * i];
      particles.y[particles.at(t.local[i])] = in[3 * i + 1];
      particles.z[particles.at(t.local[i])] = in[3 * i + 2];
    }
    offset += 3 * t.local.size();
  }
}

void DistributedSolver::remember_shared(ParticleArrays particles) {
  start_.resize(3 * remembered_.size());
  for (std::size_t i = 0; i < remembered_.size(); ++i) {
    start_[3 * i] = particles.x[particles.at(remembered_[i])];
    start_[3 * i + 1] = particles.y[particles.at(remembered_[i])];
    start_[3 * i + 2] = particles.z[particles.at(remembered_[i])];
  }
}

void DistributedSolver::post(const std::vector<Transfer>& sends,
                             const std::vector<Real>& send_values,
                             const std::vector<Transfer>& receives, int tag) {
  std::size_t receive_reals = 0;
  for (const Transfer& t : receives) receive_reals += 3 * t.local.size();
  receive_buffer_.resize(receive_reals);
  requests_.clear();
  std::size_t offset = 0;
  for (const Transfer& t : receives) {
    requests_.emplace_back();
    MPI_Irecv(receive_buffer_.data() + offset, int(3 * t.local.size()), real_type(), t.rank, tag,
              communicator_, &requests_.back());
    offset += 3 * t.local.size();
  }
  offset = 0;
  for (const Transfer& t : sends) {
    requests_.emplace_back();
    MPI_Isend(send_values.data() + offset, int(3 * t.local.size()), real_type(), t.rank, tag,
              communicator_, &requests_.back());
    offset += 3 * t.local.size();
    ++statistics_.messages_sent;
    statistics_.bytes_sent += 3 * t.local.size() * sizeof(Real);
  }
}

void DistributedSolver::send_and_receive(const std::vector<Transfer>& sends,
                                         const std::vector<Real>& send_values,
                                         const std::vector<Transfer>& receives, int tag) {
  post(sends, send_values, receives, tag);
  MPI_Waitall(int(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE);
}

void DistributedSolver::combine_shared(ParticleArrays particles) {
  const auto start = std::chrono::steady_clock::now();
  constexpr int kCorrections = 32768 - 2, kMeans = 32768 - 1;  // beyond the colours' tags
  // Round 1: my ghosts' corrections (position now − at the start) to their owners.
  std::size_t at = 0;
  send_buffer_.clear();
  for (const Transfer& t : ghosts_by_owner_)
    for (const std::uint32_t i : t.local) {
      send_buffer_.push_back(particles.x[particles.at(i)] - start_[3 * at]);
      send_buffer_.push_back(particles.y[particles.at(i)] - start_[3 * at + 1]);
      send_buffer_.push_back(particles.z[particles.at(i)] - start_[3 * at + 2]);
      ++at;
    }
  send_and_receive(ghosts_by_owner_, send_buffer_, shared_by_holder_, kCorrections);
  // The owner's mean: its own correction first, then the holders' in rank order.
  const std::size_t owned_start = at;
  values_.assign(3 * shared_owned_.size(), Real(0));
  for (std::size_t slot = 0; slot < shared_owned_.size(); ++slot) {
    const std::uint32_t i = shared_owned_[slot];
    values_[3 * slot] = particles.x[particles.at(i)] - start_[3 * (owned_start + slot)];
    values_[3 * slot + 1] = particles.y[particles.at(i)] - start_[3 * (owned_start + slot) + 1];
    values_[3 * slot + 2] = particles.z[particles.at(i)] - start_[3 * (owned_start + slot) + 2];
  }
  std::size_t offset = 0;
  for (std::size_t g = 0; g < shared_by_holder_.size(); ++g)
    for (const std::uint32_t slot : holder_slot_[g]) {
      for (int k = 0; k < 3; ++k) values_[3 * slot + k] += receive_buffer_[offset + k];
      offset += 3;
    }
  for (std::size_t slot = 0; slot < shared_owned_.size(); ++slot) {
    const std::uint32_t i = shared_owned_[slot];
    const Real w = shared_weight_[slot];
    const std::size_t s = 3 * (owned_start + slot);
    particles.x[particles.at(i)] = start_[s] + w * values_[3 * slot];
    particles.y[particles.at(i)] = start_[s + 1] + w * values_[3 * slot + 1];
    particles.z[particles.at(i)] = start_[s + 2] + w * values_[3 * slot + 2];
  }
  // Round 2: the results back to every holder.
  send_buffer_.clear();
  for (const Transfer& t : shared_by_holder_)
    for (const std::uint32_t i : t.local) {
      send_buffer_.push_back(particles.x[particles.at(i)]);
      send_buffer_.push_back(particles.y[particles.at(i)]);
      send_buffer_.push_back(particles.z[particles.at(i)]);
    }
  send_and_receive(shared_by_holder_, send_buffer_, ghosts_by_owner_, kMeans);
  offset = 0;
  for (const Transfer& t : ghosts_by_owner_)
    for (const std::uint32_t i : t.local) {
      particles.x[particles.at(i)] = receive_buffer_[offset];
      particles.y[particles.at(i)] = receive_buffer_[offset + 1];
      particles.z[particles.at(i)] = receive_buffer_[offset + 2];
      offset += 3;
    }
  statistics_.seconds_exchange +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void DistributedSolver::step() {
  solver_->step();
  if (check_finite_) {
    int finite = 1;
    for (const std::uint32_t i : owned_local_) {
      const Vector3r x = solver_->position(ParticleIndex(i));
      if (!x.allFinite()) {
        finite = 0;
        break;
      }
    }
    int all_finite = 1;
    MPI_Allreduce(&finite, &all_finite, 1, MPI_INT, MPI_MIN, communicator_);
    if (!all_finite)
      throw NumericalFailure("distributed step " +
                             std::to_string(solver_->statistics().steps) +
                             ": a position became non-finite on some rank");
  }
  if (std::isfinite(divergence_rms_)) {
    const Residual after = residual();
    if (after.rms > double(divergence_rms_))
      throw NumericalFailure("distributed step " + std::to_string(solver_->statistics().steps) +
                             ": diverged (residual RMS " + std::to_string(after.rms) +
                             " above the bound " + std::to_string(divergence_rms_) + ")");
  }
}

Residual DistributedSolver::residual() {
  const Residual local = solver_->residual();
  // Per family: constraint count, sum of squares, max; summed and maxed over the ranks.
  constexpr std::size_t F = kConstraintFamilyCount;
  std::vector<double> sums(2 * F, 0.0), maxima(F, 0.0);
  for (std::size_t f = 0; f < F; ++f) {
    const FamilyResidual& family = local.families[f];
    sums[f] = double(family.constraints);
    sums[F + f] = family.rms * family.rms * double(family.constraints);
    maxima[f] = family.max;
  }
  std::vector<double> total_sums(2 * F), total_maxima(F);
  MPI_Allreduce(sums.data(), total_sums.data(), int(2 * F), MPI_DOUBLE, MPI_SUM, communicator_);
  MPI_Allreduce(maxima.data(), total_maxima.data(), int(F), MPI_DOUBLE, MPI_MAX, communicator_);
  Residual result;
  double squares = 0;
  for (std::size_t f = 0; f < F; ++f) {
    FamilyResidual& family = result.families[f];
    family.constraints = std::size_t(total_sums[f]);
    family.max = total_maxima[f];
    family.rms = family.constraints ? std::sqrt(total_sums[F + f] / total_sums[f]) : 0.0;
    family.worst = local.families[f].worst;
    result.constraints += family.constraints;
    squares += total_sums[F + f];
    if (family.constraints && family.max > result.max) {
      result.max = family.max;
      result.worst_family = ConstraintFamily(f);
    }
  }
  result.rms = result.constraints ? std::sqrt(squares / double(result.constraints)) : 0.0;
  return result;
}

std::vector<Vector3r> DistributedSolver::gather_positions() {
  std::vector<Real> mine(3 * owned_local_.size());
  for (std::size_t i = 0; i < owned_local_.size(); ++i) {
    const Vector3r x = solver_->position(ParticleIndex(owned_local_[i]));
    mine[3 * i] = x.x();
    mine[3 * i + 1] = x.y();
    mine[3 * i + 2] = x.z();
  }
  std::vector<int> counts, displacements;
  std::vector<Real> all;
  if (rank_ == 0) {
    int offset = 0;
    for (const auto& owned : owned_of_rank_) {
      counts.push_back(int(3 * owned.size()));
      displacements.push_back(offset);
      offset += counts.back();
    }
    all.resize(std::size_t(offset));
  }
  MPI_Gatherv(mine.data(), int(mine.size()), real_type(), all.data(), counts.data(),
              displacements.data(), real_type(), 0, communicator_);
  std::vector<Vector3r> positions;
  if (rank_ != 0) return positions;
  std::size_t count = 0;
  for (const auto& owned : owned_of_rank_) count += owned.size();
  positions.resize(count);
  std::size_t at = 0;
  for (const auto& owned : owned_of_rank_)
    for (const ParticleIndex p : owned) {
      positions[p] = Vector3r(all[3 * at], all[3 * at + 1], all[3 * at + 2]);
      ++at;
    }
  return positions;
}

}  // namespace tessera
