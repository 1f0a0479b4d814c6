// Reordering a batch through a list of source constraints (the schedule, the Jacobi sets, the
// distributed solver's per-rank models): the scheduled batch's slot j holds
// constraint source[j] of the input (an empty constraint where source[j] is the padding mark),
// with its particles renamed. Generic over every family through its description
// (per_constraint_arrays, batch_wide_fields, and the particle slots or the CSR layout of
// constraint_families.hpp), so a field a family adds is carried along or the build fails.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include <tessera/core/constraint_families.hpp>

namespace tessera::detail {

template <class T>
void gather_array(AlignedVector<T>& out, const AlignedVector<T>& in,
                  std::span<const std::uint32_t> source, std::uint32_t padding) {
  out.assign(padded_size(source.size()), T{});
  for (std::size_t j = 0; j < source.size(); ++j)
    if (source[j] != padding) out[j] = in[source[j]];
}

template <class T, std::size_t K>
void gather_array(std::array<AlignedVector<T>, K>& out, const std::array<AlignedVector<T>, K>& in,
                  std::span<const std::uint32_t> source, std::uint32_t padding) {
  for (std::size_t k = 0; k < K; ++k) gather_array(out[k], in[k], source, padding);
}

/// Gathers every array of the tuple `in` into the matching one of `out`.
template <class Out, class In>
void gather_arrays(Out out, In in, std::span<const std::uint32_t> source,
                   std::uint32_t padding) {
  std::apply(
      [&](auto&... out_arrays) {
        std::apply([&](auto&... in_arrays) {
          (gather_array(out_arrays, in_arrays, source, padding), ...);
        }, in);
      },
      out);
}

/// Makes `out` the batch whose slot j holds constraint source[j] of `in` (an empty one for
/// `padding`), particles renamed by map_particle(slot k or 0, j or entry, old particle).
/// Every field of `out` is overwritten, and its arrays keep their capacity: a caller that
/// reorders fixed-arity batches into the same batch each substep allocates only when a batch
/// outgrows the last (the CSR layout still builds a list of entries). `out` is not `in`.
template <class Batch, class MapParticle>
void reorder_batch_into(Batch& out, const Batch& in, std::span<const std::uint32_t> source,
                        std::uint32_t padding, std::size_t particle_count,
                        MapParticle&& map_particle) {
  const std::size_t n = source.size();
  gather_arrays(Batch::per_constraint_arrays(out), Batch::per_constraint_arrays(in), source,
                padding);
  Batch::batch_wide_fields(out) = Batch::batch_wide_fields(in);
  if constexpr (kFixedArity<Batch>) {
    out.particles.count = n;
    out.particles.particle_count = particle_count;
    for (std::size_t k = 0; k < std::size_t(Batch::kTraits.arity); ++k) {
      auto& slot = out.particles.particle[k];
      slot.assign(padded_size(n), 0);
      for (std::size_t j = 0; j < n; ++j)
        if (source[j] != padding)
          slot[j] = map_particle(k, j, in.particles.particle[k][source[j]]);
    }
  } else {
    // The CSR layout: the entries of each cluster, in the new cluster order.
    std::vector<std::uint32_t> entry_source;
    out.count = n;
    out.particle_count = particle_count;
    out.max_cluster_size = in.max_cluster_size;
    out.offsets.assign(padded_size(n + 1), 0);
    for (std::size_t j = 0; j < n; ++j) {
      out.offsets[j] = std::uint32_t(entry_source.size());
      if (source[j] == padding) continue;
      for (std::uint32_t f = in.offsets[source[j]]; f < in.offsets[source[j] + 1]; ++f)
        entry_source.push_back(f);
    }
    std::fill(out.offsets.begin() + std::ptrdiff_t(n), out.offsets.end(),
              std::uint32_t(entry_source.size()));
    gather_arrays(Batch::per_entry_arrays(out), Batch::per_entry_arrays(in), entry_source,
                  padding);
    out.particle.assign(padded_size(entry_source.size()), 0);
    for (std::size_t e = 0; e < entry_source.size(); ++e)
      out.particle[e] = map_particle(std::size_t(0), e, in.particle[entry_source[e]]);
  }
}

/// The batch reorder_batch_into makes, new.
template <class Batch, class MapParticle>
Batch reorder_batch(const Batch& in, std::span<const std::uint32_t> source,
                    std::uint32_t padding, std::size_t particle_count,
                    MapParticle&& map_particle) {
  Batch out;
  reorder_batch_into(out, in, source, padding, particle_count,
                     std::forward<MapParticle>(map_particle));
  return out;
}

}  // namespace tessera::detail
