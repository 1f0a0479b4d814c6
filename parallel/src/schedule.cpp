// Building the colour-major layout (see schedule.hpp for the picture): per family, a list
// of source constraints per scheduled slot (kPadding for the gaps that align each colour to
// kMaxLanes), then every per-constraint array is gathered through that list and every
// particle index mapped to its new number (coloured batches) or its private incidence
// (the Jacobi set).
#include <tessera/parallel/schedule.hpp>

#include <algorithm>
#include <functional>
#include <limits>
#include <string>
#include <tuple>
#include <utility>

#include <tessera/core/error.hpp>
#include <tessera/core/simd.hpp>
#include <tessera/parallel/threads.hpp>

#include "constraint_family.hpp"
#include "jacobi_set_builder.hpp"

namespace tessera {

namespace {

constexpr std::uint32_t kPadding = std::numeric_limits<std::uint32_t>::max();
constexpr std::uint32_t kJacobiBit = 0x80000000u;

std::size_t round_up(std::size_t n, std::size_t multiple) {
  return (n + multiple - 1) / multiple * multiple;
}

template <class T>
void gather_array(AlignedVector<T>& out, const AlignedVector<T>& in,
                  std::span<const std::uint32_t> source) {
  out.assign(padded_size(source.size()), T{});
  for (std::size_t j = 0; j < source.size(); ++j)
    if (source[j] != kPadding) out[j] = in[source[j]];
}

template <class T, std::size_t K>
void gather_array(std::array<AlignedVector<T>, K>& out, const std::array<AlignedVector<T>, K>& in,
                  std::span<const std::uint32_t> source) {
  for (std::size_t k = 0; k < K; ++k) gather_array(out[k], in[k], source);
}

/// The batch whose slot j holds constraint source[j] of `in` (an empty constraint for
/// kPadding), particles renamed by map_particle(slot k or entry, j, old particle).
template <class Batch, class MapParticle>
Batch reorder(const Batch& in, std::span<const std::uint32_t> source,
              std::size_t particle_count, MapParticle&& map_particle) {
  Batch out;
  const std::size_t n = source.size();
  auto& in_mutable = const_cast<Batch&>(in);  // per_constraint_arrays hands out references
  std::apply(
      [&](auto&... out_arrays) {
        std::apply([&](auto&... in_arrays) { (gather_array(out_arrays, in_arrays, source), ...); },
                   detail::per_constraint_arrays(in_mutable));
      },
      detail::per_constraint_arrays(out));
  if constexpr (detail::arity_of<Batch>() == 0) {
    out.count = n;
    out.particle_count = particle_count;
    out.max_cluster_size = in.max_cluster_size;
    out.allow_stretch = in.allow_stretch;
    std::size_t entries = 0;
    for (const std::uint32_t s : source)
      if (s != kPadding) entries += in.offsets[s + 1] - in.offsets[s];
    out.offsets.assign(padded_size(n + 1), std::uint32_t(entries));
    out.particle.assign(padded_size(entries), 0);
    for (auto& a : out.rest_offset) a.assign(padded_size(entries), 0);
    out.mass.assign(padded_size(entries), 0);
    std::uint32_t e = 0;
    for (std::size_t j = 0; j < n; ++j) {
      out.offsets[j] = e;
      if (source[j] == kPadding) continue;
      for (std::uint32_t f = in.offsets[source[j]]; f < in.offsets[source[j] + 1]; ++f, ++e) {
        out.particle[e] = map_particle(std::size_t(0), std::size_t(e), in.particle[f]);
        for (std::size_t k = 0; k < 3; ++k) out.rest_offset[k][e] = in.rest_offset[k][f];
        out.mass[e] = in.mass[f];
      }
    }
  } else {
    constexpr std::size_t N = detail::arity_of<Batch>();
    out.particles.count = n;
    out.particles.particle_count = particle_count;
    for (std::size_t k = 0; k < N; ++k) {
      auto& slot = out.particles.particle[k];
      slot.assign(padded_size(n), 0);
      for (std::size_t j = 0; j < n; ++j)
        if (source[j] != kPadding)
          slot[j] = map_particle(k, j, in.particles.particle[k][source[j]]);
    }
    if constexpr (requires { out.handle_inversion; }) out.handle_inversion = in.handle_inversion;
    if constexpr (requires { out.normalize_stretch; }) {
      out.normalize_stretch = in.normalize_stretch;
      out.normalize_shear = in.normalize_shear;
    }
  }
  return out;
}

/// Splits [begin, end) of one family into blocks (begin is aligned, so every block starts on a
/// kMaxLanes boundary): at most block_size constraints, and small enough that every worker
/// gets about kBlocksPerThread of them (a colour of 7,000 tetrahedra is 14 blocks of 512 but
/// must feed 64 threads). Block boundaries never change a result: the constraints of a range
/// are independent and each SIMD lane computes alone.
constexpr std::size_t kBlocksPerThread = 4;
void split_into_blocks(ConstraintFamily family, std::size_t begin, std::size_t end,
                       const ScheduleOptions& options, std::vector<ScheduleBlock>& blocks) {
  const std::size_t per_thread =
      (end - begin + kBlocksPerThread * options.threads - 1) / (kBlocksPerThread * options.threads);
  const std::size_t block_size =
      std::clamp(round_up(per_thread, kMaxLanes), kMaxLanes, options.block_size);
  for (std::size_t b = begin; b < end; b += block_size)
    blocks.push_back({family, std::uint32_t(b), std::uint32_t(std::min(end, b + block_size))});
}

/// Incidences of a family in the Jacobi set: slot k of constraint j is base + k·stride + j
/// (a vector of W constraints reads W consecutive incidences); shape-matching entry e is
/// base + e.
struct IncidenceLayout {
  std::size_t base = 0;
  std::size_t stride = 0;
  std::size_t size = 0;
};

}  // namespace

namespace detail {

JacobiSet build_jacobi_set(
    const ConstraintSets& sets,
    std::array<std::vector<std::uint32_t>, kConstraintFamilyCount>& source_of_family,
    std::size_t particle_count, const std::function<ParticleIndex(ParticleIndex)>& renumber,
    const std::function<bool(ParticleIndex)>& movable, const ScheduleOptions& options) {
  JacobiSet jacobi;
  // The constraints are projected all at once, so their order is free: sort them by their
  // smallest (renumbered) particle. Then the incidences of neighbouring particles lie close
  // together in every slot array, and the per-particle sums read memory almost in order (in
  // colour order they jumped across the whole set).
  sets.for_each([&](ConstraintFamily family, const auto& batch) {
    using Batch = std::decay_t<decltype(batch)>;
    auto& source = source_of_family[std::size_t(family)];
    if (source.empty()) return;
    std::vector<std::pair<ParticleIndex, std::uint32_t>> keyed(source.size());
    for (std::size_t j = 0; j < source.size(); ++j) {
      ParticleIndex smallest = std::numeric_limits<ParticleIndex>::max();
      if constexpr (detail::arity_of<Batch>() == 0) {
        for (auto e = batch.offsets[source[j]]; e < batch.offsets[source[j] + 1]; ++e)
          smallest = std::min(smallest, renumber(batch.particle[e]));
      } else {
        for (const auto& slot : batch.particles.particle)
          smallest = std::min(smallest, renumber(slot[source[j]]));
      }
      keyed[j] = {smallest, source[j]};
    }
    std::sort(keyed.begin(), keyed.end());
    for (std::size_t j = 0; j < source.size(); ++j) source[j] = keyed[j].second;
  });

  // Incidences family by family.
  std::array<IncidenceLayout, kConstraintFamilyCount> layout;
  std::size_t incidences = 0;
  sets.for_each([&](ConstraintFamily family, const auto& batch) {
    using Batch = std::decay_t<decltype(batch)>;
    const auto& source = source_of_family[std::size_t(family)];
    IncidenceLayout& l = layout[std::size_t(family)];
    l.base = incidences;
    if constexpr (detail::arity_of<Batch>() == 0) {
      std::size_t entries = 0;
      for (const std::uint32_t s : source) entries += batch.offsets[s + 1] - batch.offsets[s];
      l.size = padded_size(entries);
    } else {
      l.stride = padded_size(source.size());
      l.size = source.empty() ? 0 : l.stride * detail::arity_of<Batch>();
    }
    incidences += l.size;
  });
  jacobi.incidence_count = padded_size(incidences);
  jacobi.incidence_particle.assign(jacobi.incidence_count, 0);
  std::vector<std::uint8_t> real_incidence(jacobi.incidence_count, 0);
  jacobi.constraints.for_each([&](ConstraintFamily family, auto& batch) {
    const auto& source = source_of_family[std::size_t(family)];
    const IncidenceLayout& l = layout[std::size_t(family)];
    jacobi.incidence_base[std::size_t(family)] = l.base;
    jacobi.incidence_stride[std::size_t(family)] = l.stride;
    const auto renumber_and_record = [&](std::size_t k, std::size_t j, ParticleIndex p) {
      const std::size_t incidence = l.base + k * l.stride + j;
      jacobi.incidence_particle[incidence] = renumber(p);
      real_incidence[incidence] = 1;
      return renumber(p);
    };
    batch = reorder(detail::same_family(sets, batch), source, particle_count, renumber_and_record);
    split_into_blocks(family, 0, source.size(), options, jacobi.blocks);
    jacobi.constraint_count += source.size();
  });

  // Each movable particle's incidences, ascending (counting sort by particle).
  std::vector<std::uint32_t> count(particle_count + 1, 0);
  for (std::size_t i = 0; i < jacobi.incidence_count; ++i)
    if (real_incidence[i] && movable(jacobi.incidence_particle[i]))
      ++count[jacobi.incidence_particle[i] + 1];
  for (std::size_t p = 0; p < particle_count; ++p)
    if (count[p + 1] != 0) jacobi.particles.push_back(ParticleIndex(p));
  std::vector<std::uint32_t> start(particle_count + 1, 0);
  for (std::size_t p = 0; p < particle_count; ++p) start[p + 1] = start[p] + count[p + 1];
  jacobi.particle_incidences.resize(start[particle_count]);
  jacobi.particle_offsets.reserve(jacobi.particles.size() + 1);
  for (const ParticleIndex p : jacobi.particles) jacobi.particle_offsets.push_back(start[p]);
  jacobi.particle_offsets.push_back(start[particle_count]);
  for (std::size_t i = 0; i < jacobi.incidence_count; ++i)
    if (real_incidence[i] && movable(jacobi.incidence_particle[i]))
      jacobi.particle_incidences[start[jacobi.incidence_particle[i]]++] = std::uint32_t(i);

  // λ shares: the mean count over each constraint's movable incidences.
  jacobi.constraints.for_each([&](ConstraintFamily family, auto& batch) {
    if (detail::lambda_of(batch) == nullptr || batch.size() == 0) return;
    constexpr std::size_t N = detail::arity_of<std::decay_t<decltype(batch)>>();
    if constexpr (N != 0) {
      auto& share = jacobi.lambda_share[std::size_t(family)];
      share.assign(padded_size(batch.size()), 0);
      for (std::size_t j = 0; j < batch.size(); ++j) {
        std::size_t movable_particles = 0, incidences_there = 0;
        for (std::size_t k = 0; k < N; ++k) {
          const ParticleIndex p = batch.particles.particle[k][j];
          if (!movable(p)) continue;
          ++movable_particles;
          incidences_there += count[p + 1];
        }
        if (incidences_there != 0)
          share[j] = Real(double(movable_particles) / double(incidences_there));
      }
    }
  });
  return jacobi;
}

}  // namespace detail

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
  for (const SolverMode mode :
       {SolverMode::gs, SolverMode::jacobi, SolverMode::hybrid, SolverMode::sequential})
    if (solver_mode_name(mode) == name) return mode;
  throw InvalidInput("unknown solver mode '" + std::string(name) +
                     "' (known: gs, jacobi, hybrid, sequential)");
}

Schedule::Schedule(const Model& model, const Colouring* colouring, const ScheduleOptions& options)
    : options_(options) {
  if (options_.block_size == 0)
    throw InvalidInput("schedule: block size must be at least 1 constraint");
  options_.block_size = round_up(options_.block_size, kMaxLanes);
  options_.threads = worker_threads(options_.threads);
  const auto sizes = model.constraints.sizes();
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f)
    family_first_[f + 1] = family_first_[f] + ConstraintIndex(sizes[f]);
  const std::size_t total = family_first_.back();
  location_.assign(total, 0);
  const std::size_t particle_count = model.particles.size();

  if (options_.mode == SolverMode::sequential) {
    coloured_ = model.constraints;
    for (std::size_t f = 0; f < kConstraintFamilyCount; ++f) {
      if (sizes[f] != 0)
        ranges_[f].push_back({ConstraintFamily(f), 0, std::uint32_t(sizes[f])});
      for (std::size_t i = 0; i < sizes[f]; ++i)
        location_[family_first_[f] + i] = std::uint32_t(i);
    }
    return;
  }
  if (colouring == nullptr)
    throw InvalidInput("schedule: mode " + std::string(solver_mode_name(options_.mode)) +
                       " needs a colouring");
  if (colouring->constraint_count() != total)
    throw InvalidInput("schedule: the colouring colours " +
                       std::to_string(colouring->constraint_count()) +
                       " constraints, the model has " + std::to_string(total));
  if (colouring->renumbers_particles()) {
    if (colouring->particle_new_to_old().size() != particle_count)
      throw InvalidInput("schedule: the colouring renumbers " +
                         std::to_string(colouring->particle_new_to_old().size()) +
                         " particles, the model has " + std::to_string(particle_count));
    new_to_old_.assign(colouring->particle_new_to_old().begin(),
                       colouring->particle_new_to_old().end());
    old_to_new_.assign(colouring->particle_old_to_new().begin(),
                       colouring->particle_old_to_new().end());
  }

  // Which slot each constraint takes, family by family.
  std::array<std::vector<std::uint32_t>, kConstraintFamilyCount> coloured_source, jacobi_source;
  std::array<std::vector<std::uint32_t>, kConstraintFamilyCount> members;
  const auto family_of = [&](ConstraintIndex c) {
    std::size_t f = 0;
    while (c >= family_first_[f + 1]) ++f;
    return f;
  };
  phase_offsets_.push_back(0);
  for (Colour k = 0; k < colouring->colour_count(); ++k) {
    const auto colour = colouring->constraints_of(k);
    const bool to_jacobi = options_.mode == SolverMode::jacobi ||
                           (options_.mode == SolverMode::hybrid &&
                            colour.size() < options_.hybrid_threshold);
    for (auto& m : members) m.clear();
    for (const ConstraintIndex c : colour) {
      const std::size_t f = family_of(c);
      members[f].push_back(c - family_first_[f]);
    }
    for (std::size_t f = 0; f < kConstraintFamilyCount; ++f) {
      if (members[f].empty()) continue;
      auto& source = to_jacobi ? jacobi_source[f] : coloured_source[f];
      if (!to_jacobi) source.resize(round_up(source.size(), kMaxLanes), kPadding);
      const std::size_t begin = source.size();
      // Jacobi slots are known only once build_jacobi_set has sorted the set (below).
      for (const std::uint32_t local : members[f]) {
        if (!to_jacobi) location_[family_first_[f] + local] = std::uint32_t(source.size());
        source.push_back(local);
      }
      if (to_jacobi) continue;
      const std::size_t end = source.size();
      ranges_[f].push_back({ConstraintFamily(f), std::uint32_t(begin), std::uint32_t(end)});
      split_into_blocks(ConstraintFamily(f), begin, end, options_, blocks_);
    }
    if (!to_jacobi) {
      phase_offsets_.push_back(blocks_.size());
      phase_sizes_.push_back(colour.size());
    }
  }
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f)
    if (std::max(coloured_source[f].size(), jacobi_source[f].size()) >= kJacobiBit / 2)
      throw InvalidInput("schedule: more than 2^30 constraints in one family");

  // The coloured batches.
  const auto renumber = [&](std::size_t, std::size_t, ParticleIndex p) {
    return scheduled_particle(p);
  };
  coloured_.for_each([&](ConstraintFamily family, auto& batch) {
    const auto& input = detail::same_family(model.constraints, batch);
    batch = reorder(input, coloured_source[std::size_t(family)], particle_count, renumber);
  });

  // The Jacobi set (sorts each family's list, see build_jacobi_set).
  jacobi_ = detail::build_jacobi_set(
      model.constraints, jacobi_source, particle_count,
      [&](ParticleIndex p) { return scheduled_particle(p); },
      [&](ParticleIndex scheduled) {
        return model.particles.inverse_mass[user_particle(scheduled)] > 0;
      },
      options_);
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f)
    for (std::size_t j = 0; j < jacobi_source[f].size(); ++j)
      location_[family_first_[f] + jacobi_source[f][j]] = std::uint32_t(j) | kJacobiBit;
}

ConstraintLocation Schedule::locate(ConstraintIndex user_constraint) const {
  if (user_constraint >= location_.size())
    throw InvalidInput("constraint " + std::to_string(user_constraint) +
                       " does not exist (the schedule has " + std::to_string(location_.size()) +
                       ")");
  std::size_t f = 0;
  while (user_constraint >= family_first_[f + 1]) ++f;
  const std::uint32_t slot = location_[user_constraint];
  return {(slot & kJacobiBit) != 0, ConstraintFamily(f), slot & ~kJacobiBit};
}

}  // namespace tessera
