// Building a Jacobi set (schedule.hpp), and cutting a range into work blocks: shared by the
// schedule (its Jacobi colours) and the solver (the dynamic constraints and contacts it is
// handed between steps).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include <tessera/parallel/schedule.hpp>

namespace tessera::detail {

/// Splits [begin, end) of one family into blocks (begin is aligned, so every block starts on a
/// kMaxLanes boundary): at most options.block_size constraints, and small enough that every
/// worker gets about kBlocksPerThread of them (a colour of 7,000 tetrahedra is 14 blocks of
/// 512 but must feed 64 threads). Block boundaries never change a result: the constraints of
/// a range are independent and each SIMD lane computes alone.
inline constexpr std::size_t kBlocksPerThread = 4;
inline std::size_t round_up(std::size_t n, std::size_t multiple) {
  return (n + multiple - 1) / multiple * multiple;
}
void split_into_blocks(ConstraintFamily family, std::size_t begin, std::size_t end,
                       const ScheduleOptions& options, std::vector<ScheduleBlock>& blocks);

/// build_jacobi_set's working lists, kept by a caller that rebuilds a set every substep.
struct JacobiSetScratch {
  std::vector<std::pair<ParticleIndex, std::uint32_t>> keyed;
  std::vector<std::uint8_t> real_incidence;
  std::vector<std::uint32_t> count, start;
};

/// The Jacobi set of the constraints source_of_family[f] (indices into the family's batch of
/// `sets`) over particle_count particles. Sorts each list by the constraints' smallest
/// renumbered particle, in place (the set's slot j holds source_of_family[f][j] afterwards).
/// renumber maps a particle of `sets` to the schedule's numbering; movable(p) tells whether a
/// renumbered particle can move. Built into `jacobi`, every field replaced and its arrays'
/// capacity kept (with the same scratch each time, a rebuild allocates only when the set
/// outgrows the last).
void build_jacobi_set(
    JacobiSet& jacobi, JacobiSetScratch& scratch, const ConstraintSets& sets,
    std::array<std::vector<std::uint32_t>, kConstraintFamilyCount>& source_of_family,
    std::size_t particle_count, const std::function<ParticleIndex(ParticleIndex)>& renumber,
    const std::function<bool(ParticleIndex)>& movable, const ScheduleOptions& options);
/// The same, into a new set.
JacobiSet build_jacobi_set(
    const ConstraintSets& sets,
    std::array<std::vector<std::uint32_t>, kConstraintFamilyCount>& source_of_family,
    std::size_t particle_count, const std::function<ParticleIndex(ParticleIndex)>& renumber,
    const std::function<bool(ParticleIndex)>& movable, const ScheduleOptions& options);

}  // namespace tessera::detail
