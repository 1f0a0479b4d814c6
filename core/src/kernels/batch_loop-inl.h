// The loop every batched kernel of an N-particle family runs, written once:
//
//   for each chunk of W constraints in [begin, end):
//     gather the N slots' positions and inverse masses      (batch-inl.h)
//     evaluate the family's formula on the W lanes          (the caller's lambda)
//     project with PBD stiffness or XPBD compliance          (projection-inl.h)
//     store λ of the active lanes, scatter movable particles (batch-inl.h)
//
// Why: the dihedral, volume and isometric bending kernels differ only in their formula and
// rest data; sharing the loop keeps their gather/project/scatter identical (so an improvement
// to one is an improvement to all) and keeps each family's file about its formula.
#if defined(TESSERA_CORE_KERNELS_BATCH_LOOP_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_BATCH_LOOP_INL_H_
#undef TESSERA_CORE_KERNELS_BATCH_LOOP_INL_H_
#else
#define TESSERA_CORE_KERNELS_BATCH_LOOP_INL_H_
#endif

#include <cstddef>

#include <tessera/core/constraint_batch.hpp>

#include "batch-inl.h"
#include "projection-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

/// Per-constraint parameter arrays of a family that supports both semantics.
struct ProjectionParameters {
  const Real* stiffness;
  const Real* compliance;
  Real* lambda;
};

/// Projects constraints [begin, end) W at a time. evaluate(positions, i) returns the
/// ConstraintValue<RealLanes, N> of constraints i .. i+W from their N gathered positions
/// (rest data of the family is loaded by the caller's lambda at offset i).
template <int N, class Evaluate>
HWY_INLINE void project_constraint_lanes(ParticleArrays particles,
                                         const ConstraintParticles<N>& indices,
                                         const ProjectionParameters& parameters,
                                         std::size_t begin, std::size_t end,
                                         const ProjectionSettings& settings,
                                         Evaluate&& evaluate) {
  const RealTag d;
  const std::size_t lanes = hn::Lanes(d);
  const ParticleIndex* slot[N];
  for (int k = 0; k < N; ++k) slot[k] = indices.particle[std::size_t(k)].data();
  const bool compliance = settings.semantics == ConstraintSemantics::compliance;
  const RealLanes dt = hn::Set(d, settings.dt);
  for (std::size_t i = begin; i < end; i += lanes) {
    const std::size_t active_count = end - i;
    const LaneMask active = hn::FirstN(d, active_count);
    ParticleLanes gathered[N];
    Vec3<RealLanes> position[N];
    RealLanes w[N];
    for (int k = 0; k < N; ++k) {
      gathered[k] = gather_particles(particles, slot[k] + i);
      position[k] = gathered[k].position;
      w[k] = gathered[k].inverse_mass;
    }
    const ConstraintValue<RealLanes, N> value = evaluate(position, i);
    Vec3<RealLanes> corr[N];
    if (compliance) {
      RealLanes lambda = hn::LoadU(d, parameters.lambda + i);
      project_xpbd(value, w, hn::LoadU(d, parameters.compliance + i), dt, lambda, corr);
      store_active(lambda, active_count, parameters.lambda + i);
    } else {
      project_pbd(value, w, hn::LoadU(d, parameters.stiffness + i), corr);
    }
    for (int k = 0; k < N; ++k)
      scatter_corrected(particles, slot[k] + i, gathered[k], corr[k], active);
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_BATCH_LOOP_INL_H_
