// Gather and scatter between the SoA particle arrays and W lanes of one constraint slot.
//
//   particle[slot][i .. i+W)  ──load──►  index lanes  ──gather──►  x, y, z, w lanes
//   formula (lane_math / projection)  ──►  correction lanes
//   for each active lane with w > 0:  x[index] = x + Δx  (scalar stores)
//
// The scatter is a loop over the set bits of the write mask with scalar stores, not a vector
// scatter of every lane: a static particle (w = 0) may appear in several lanes or threads at
// once, and it must never be written, not even with its own value. Per-constraint outputs (λ)
// are stored with full vectors only when the whole chunk is active, else lane by lane, so a
// kernel never writes an element outside its [begin, end).
#if defined(TESSERA_CORE_KERNELS_BATCH_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_BATCH_INL_H_
#undef TESSERA_CORE_KERNELS_BATCH_INL_H_
#else
#define TESSERA_CORE_KERNELS_BATCH_INL_H_
#endif

#include <cstdint>

#include <tessera/core/particle_state.hpp>
#include <tessera/core/simd.hpp>

#include "lane_math-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

using RealTag = hn::ScalableTag<Real>;
using RealLanes = hn::Vec<RealTag>;
using IndexTag = hn::RebindToSigned<RealTag>;
using IndexLanes = hn::Vec<IndexTag>;
using LaneMask = hn::Mask<RealTag>;

/// W particle indices starting at `indices`, widened to the gather index type.
HWY_INLINE IndexLanes load_particle_indices(const ParticleIndex* indices) {
  const IndexTag di;
#if TESSERA_DOUBLE_PRECISION
  const hn::Rebind<int32_t, RealTag> d32;  // half as wide as the double lanes
  return hn::PromoteTo(di, hn::LoadU(d32, reinterpret_cast<const int32_t*>(indices)));
#else
  return hn::BitCast(di, hn::LoadU(hn::RebindToUnsigned<RealTag>(), indices));
#endif
}

/// One slot's particles for W lanes: where they are, and how heavy.
struct ParticleLanes {
  Vec3<RealLanes> position;
  RealLanes inverse_mass;
};

HWY_INLINE ParticleLanes gather_particles(const ParticleArrays& particles,
                                          const ParticleIndex* indices) {
  const RealTag d;
  const IndexLanes index = load_particle_indices(indices);
  return {{hn::GatherIndex(d, particles.x, index), hn::GatherIndex(d, particles.y, index),
           hn::GatherIndex(d, particles.z, index)},
          hn::GatherIndex(d, particles.inverse_mass, index)};
}

/// Bit i set for each lane i where the mask is true.
HWY_INLINE std::uint64_t mask_bits(const LaneMask& mask) {
  const RealTag d;
  std::uint8_t bytes[8] = {};
  hn::StoreMaskBits(d, mask, bytes);
  std::uint64_t bits = 0;
  for (int b = 0; b < 8; ++b) bits |= std::uint64_t(bytes[b]) << (8 * b);
  return bits;
}

/// x[index] = position + correction for the active lanes whose particle is movable.
HWY_INLINE void scatter_corrected(ParticleArrays& particles, const ParticleIndex* indices,
                                  const ParticleLanes& lanes, const Vec3<RealLanes>& correction,
                                  const LaneMask& active) {
  const RealTag d;
  std::uint64_t bits = mask_bits(hn::And(active, lanes.inverse_mass > hn::Zero(d)));
  if (bits == 0) return;
  HWY_ALIGN Real x[kMaxLanes], y[kMaxLanes], z[kMaxLanes];
  hn::Store(lanes.position.x + correction.x, d, x);
  hn::Store(lanes.position.y + correction.y, d, y);
  hn::Store(lanes.position.z + correction.z, d, z);
  while (bits != 0) {
    const int lane = __builtin_ctzll(bits);
    const ParticleIndex p = indices[lane];
    particles.x[p] = x[lane];
    particles.y[p] = y[lane];
    particles.z[p] = z[lane];
    bits &= bits - 1;
  }
}

/// Stores the active lanes of value to out[0 .. W): one vector store when every lane is
/// active, else lane by lane (never touching an inactive element).
HWY_INLINE void store_active(RealLanes value, std::size_t active_count, Real* out) {
  const RealTag d;
  if (active_count >= hn::Lanes(d)) {
    hn::StoreU(value, d, out);
    return;
  }
  HWY_ALIGN Real lanes[kMaxLanes];
  hn::Store(value, d, lanes);
  for (std::size_t lane = 0; lane < active_count; ++lane) out[lane] = lanes[lane];
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_BATCH_INL_H_
