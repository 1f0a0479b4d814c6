// Building a Jacobi set (schedule.hpp): shared by the schedule (its Jacobi colours) and the
// solver (the dynamic constraints it is handed between steps).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include <tessera/parallel/schedule.hpp>

namespace tessera::detail {

/// The Jacobi set of the constraints source_of_family[f] (indices into the family's batch of
/// `sets`) over particle_count particles. Sorts each list by the constraints' smallest
/// renumbered particle, in place (the set's slot j holds source_of_family[f][j] afterwards).
/// renumber maps a particle of `sets` to the schedule's numbering; movable(p) tells whether a
/// renumbered particle can move.
JacobiSet build_jacobi_set(
    const ConstraintSets& sets,
    std::array<std::vector<std::uint32_t>, kConstraintFamilyCount>& source_of_family,
    std::size_t particle_count, const std::function<ParticleIndex(ParticleIndex)>& renumber,
    const std::function<bool(ParticleIndex)>& movable, const ScheduleOptions& options);

}  // namespace tessera::detail
