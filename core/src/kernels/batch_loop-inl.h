// The loop every batched kernel of an N-particle family runs, written once:
//
//   for each block of W constraints in [begin, end):
//     gather the N slots' positions and inverse masses      (batch-inl.h; for N ≤ 2 the
//                                                            next block's, this one's
//                                                            having been gathered before)
//     evaluate the family's formula on the W lanes          (the caller's lambda)
//     project with PBD stiffness or XPBD compliance          (projection-inl.h)
//     store λ of the active lanes, scatter movable particles (batch-inl.h; for N ≤ 2 the
//                                                            block before's, this one's
//                                                            held until the next block
//                                                            is projected)
//
// Why: the fixed-arity families with one stiffness (or compliance and λ) per constraint
// differ only in their formula, rest data and where their stiffness comes from; sharing the
// loop keeps their gather/project/scatter identical (so an improvement to one is an
// improvement to all) and keeps each family's file about its formula.
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
/// ConstraintValue<RealLanes, N> (or, for N = 2 with gradients ±n, the DirectionValue) of
/// constraints i .. i+W from their N gathered positions
/// (rest data of the family is loaded by the caller's lambda at offset i). With stiffness
/// semantics, stiffness_of(value, i) gives the PBD stiffness of those lanes (a family may
/// choose it from C, as the proximity families do); compliance semantics use
/// parameters.compliance and parameters.lambda.
template <int N, class Evaluate, class StiffnessOf>
HWY_INLINE void project_constraint_lanes(ParticleArrays particles,
                                         const ConstraintParticles<N>& indices,
                                         const ProjectionParameters& parameters,
                                         std::size_t begin, std::size_t end,
                                         const ProjectionSettings& settings,
                                         Evaluate&& evaluate, StiffnessOf&& stiffness_of) {
  const RealTag d;
  const std::size_t lanes = hn::Lanes(d);
  const ParticleIndex* slot[N];
  constraint_slots(indices, slot);
  const bool compliance = settings.semantics == ConstraintSemantics::compliance;
  const auto step = TimeStep<RealLanes>::of(hn::Set(d, settings.dt));
  const auto project_block = [&](std::size_t i, const Vec3<RealLanes> (&position)[N],
                                 const RealLanes (&w)[N], Vec3<RealLanes> (&corr)[N]) {
    const auto value = evaluate(position, i);
    if (compliance) {
      RealLanes lambda = settings.lambda_starts_at_zero ? hn::Zero(d)
                                                        : hn::LoadU(d, parameters.lambda + i);
      project_xpbd(value, w, hn::LoadU(d, parameters.compliance + i), step, lambda, corr);
      store_active(lambda, end - i, parameters.lambda + i);
    } else {
      project_pbd(value, w, stiffness_of(value, i), corr);
    }
  };
  // Families of one or two particles run the blocks as a pipeline of three:
  //
  //   block i + W:  gathered   ─┐
  //   block i:      projected   ├─ in one pass of the loop, in this order
  //   block i − W:  scattered  ─┘
  //
  // Why: their formula is short, but its chain from the loads through the square root and the
  // division to the scatter is long. One block at a time, the out-of-order window reaches the
  // next block's loads only late in that chain, and the scatter's stores sit behind the
  // division; issued a block earlier, the loads and their transposes overlap the chain, and
  // deferred a block, the scatter overlaps the next block's formula (docs/performance.md,
  // "The next block's particles gathered first" and "Each block scattered after the next is
  // projected": 1.14× on the distance-only cloth, though the samples waiting on the division
  // did not shrink). The block held for the scatter keeps its corrected particles only (4
  // registers a particle), not its gathered ones and their corrections (7), which spilled more.
  // It is exact: a range's constraints share no movable particle, so no block reads a particle
  // another block of the range writes, in whatever order the three run (a Jacobi set's range
  // may share particles, but its kernel writes the redirected output and never reads it, see
  // ParticleArrays). The families of three and four particles run one block at a time: they
  // measured no gain from the gather ahead and a loss from the deferred scatter (their longer
  // formulas hide the loads, and a block held costs them 12 or 16 more registers).
  if constexpr (N <= 2) {
    if (begin >= end) return;
    ParticleLanes ahead[N], held[N] = {};
    gather_constraint_particles(particles, slot, begin, end, ahead);
    // The block held for the scatter; the first pass scatters no lane of it. Why not a test
    // that skips that scatter: the distance kernel measured 2–6 % slower with one (against
    // the first block peeled by hand, which measured the same as this but repeated the loop's
    // body), and 36 % slower with the first block peeled through a lambda shared with the
    // loop (the compiler then kept the lanes in memory).
    std::size_t held_at = begin, held_count = 0;
    for (std::size_t i = begin; i < end; i += lanes) {
      Vec3<RealLanes> position[N], corr[N];
      RealLanes w[N];
      HWY_UNROLL(16)
      for (int k = 0; k < N; ++k) {
        position[k] = ahead[k].position;
        w[k] = ahead[k].inverse_mass;
      }
      if (i + lanes < end) gather_constraint_particles(particles, slot, i + lanes, end, ahead);
      project_block(i, position, w, corr);
      scatter_constraint_particles(particles, slot, held_at, held, hn::FirstN(d, held_count));
      HWY_UNROLL(16)
      for (int k = 0; k < N; ++k) held[k] = corrected_particles({position[k], w[k]}, corr[k]);
      held_at = i;
      held_count = end - i;
    }
    scatter_constraint_particles(particles, slot, held_at, held, hn::FirstN(d, held_count));
  } else {
    for (std::size_t i = begin; i < end; i += lanes) {
      ParticleLanes gathered[N];
      Vec3<RealLanes> position[N], corr[N];
      RealLanes w[N];
      gather_constraint_particles(particles, slot, i, end, gathered, position, w);
      project_block(i, position, w, corr);
      scatter_constraint_particles(particles, slot, i, gathered, corr, hn::FirstN(d, end - i));
    }
  }
}

/// The same loop for a family whose stiffness is one per-constraint array
/// (parameters.stiffness).
template <int N, class Evaluate>
HWY_INLINE void project_constraint_lanes(ParticleArrays particles,
                                         const ConstraintParticles<N>& indices,
                                         const ProjectionParameters& parameters,
                                         std::size_t begin, std::size_t end,
                                         const ProjectionSettings& settings,
                                         Evaluate&& evaluate) {
  const RealTag d;
  project_constraint_lanes<N>(
      particles, indices, parameters, begin, end, settings, evaluate,
      [&](const auto&, std::size_t i) {
        return hn::LoadU(d, parameters.stiffness + i);
      });
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_BATCH_LOOP_INL_H_
