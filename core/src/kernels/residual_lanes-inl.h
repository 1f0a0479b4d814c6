// The loop every batched residual of an N-particle family runs (constraint_residual.hpp):
// gather the positions of W constraints (no inverse masses), evaluate the family's residual
// on the lanes, store the active lanes. Each family's file supplies only its measure, built
// from the same lane formula its projection kernel runs, so a residual is the violation the
// kernel itself sees. Lanes past the end read padding (particle 0, zero rest data): their
// branch-free formulas compute a discarded value and never trap; store_active never writes
// past out[end − begin).
#if defined(TESSERA_CORE_KERNELS_RESIDUAL_LANES_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_RESIDUAL_LANES_INL_H_
#undef TESSERA_CORE_KERNELS_RESIDUAL_LANES_INL_H_
#else
#define TESSERA_CORE_KERNELS_RESIDUAL_LANES_INL_H_
#endif

#include <cstddef>

#include <tessera/core/constraint_batch.hpp>

#include "batch-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

/// The positions of the N slots of constraints i .. i+W (inverse masses are not needed).
template <int N>
HWY_INLINE void gather_positions(const ParticleArrays& particles,
                                 const ParticleIndex* const* slot, std::size_t i,
                                 std::size_t end, Vec3<RealLanes> (&p)[N]) {
  const RealTag d;
  HWY_UNROLL(16)  // the slots' lanes stay in registers (see gather_constraint_particles)
  for (int k = 0; k < N; ++k) {
    if (particles.interleaved()) {
      HWY_ALIGN ParticleIndex scratch[kMaxLanes];
      p[k] = gather_interleaved(particles.x, active_indices(slot[k] + i, end - i, scratch)).position;
      continue;
    }
    const IndexLanes index = load_particle_indices(slot[k] + i);
    p[k] = {hn::GatherIndex(d, particles.x, index), hn::GatherIndex(d, particles.y, index),
            hn::GatherIndex(d, particles.z, index)};
  }
}

/// out[c − begin] = residual(positions, c) for c in [begin, end), W at a time; residual
/// returns the lanes of constraints i .. i+W from their gathered positions.
template <int N, class Residual>
HWY_INLINE void residual_lanes(const ParticleArrays& particles,
                               const ConstraintParticles<N>& indices, std::size_t begin,
                               std::size_t end, Real* out, Residual&& residual) {
  const RealTag d;
  const std::size_t lanes = hn::Lanes(d);
  const ParticleIndex* slot[N];
  constraint_slots(indices, slot);
  for (std::size_t i = begin; i < end; i += lanes) {
    Vec3<RealLanes> p[N];
    gather_positions<N>(particles, slot, i, end, p);
    store_active(residual(p, i), end - i, out + (i - begin));
  }
}

HWY_INLINE RealLanes load(const Real* values, std::size_t i) {
  return hn::LoadU(RealTag(), values + i);
}

/// C + α̃λ on the lanes of constraints i .. i+W, α̃ = compliance × inverse_dt2 as the
/// projection makes it (projection-inl.h, scaled_compliance): the XPBD residual (Macklin,
/// Müller, Chentanez 2016, eq. 11), what a compliant solve drives to zero; C itself when
/// inverse_dt2 is 0 and for hard constraints (α = 0, whatever inverse_dt2).
HWY_INLINE RealLanes xpbd_residual(RealLanes C, const Real* compliance, const Real* lambda,
                                   std::size_t i, Real inverse_dt2) {
  if (inverse_dt2 == 0) return C;
  const RealLanes alpha = load(compliance, i);
  const RealLanes alpha_tilde = select(alpha == zero<RealLanes>(), zero<RealLanes>(),
                                       alpha * hn::Set(RealTag(), inverse_dt2));
  return C + alpha_tilde * load(lambda, i);
}

/// |C| / |reference|, or |C| where the reference is zero (constraint_residual.cpp's relative).
HWY_INLINE RealLanes relative(RealLanes C, RealLanes reference) {
  const RealLanes scale = lane_abs(reference);
  return lane_abs(C) / select(scale > zero<RealLanes>(), scale, splat<RealLanes>(1.0));
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_RESIDUAL_LANES_INL_H_
