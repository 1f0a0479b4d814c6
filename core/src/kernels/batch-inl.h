// Gather and scatter between the particle arrays and W lanes of one constraint slot.
//
//   particle[slot][i .. i+W)  ──load──►  index lanes  ──gather──►  x, y, z, w lanes
//   formula (lane_math / projection)  ──►  correction lanes
//   for each active lane with w > 0:  x[index] = x + Δx
//
// Two layouts (ParticleArrays): separate arrays are read with one hardware gather per
// coordinate (four cache lines per particle); interleaved particles (x y z w in 16 bytes)
// are read with one 128-bit load per lane and transposed in registers:
//
//   lane:   0  1  2  3  4 …                 quad m holds lanes m, m+4, m+8, m+12:
//   load:  [x y z w] per lane ─► q0 = [L0 |L4 |L8 |L12]   q1 = [L1 |L5 |L9 |L13] …
//   unpack lo/hi (q0,q1), (q2,q3), then shuffle halves ─► X = [x0 x1 … x15], Y, Z, W
//
// and written back by the inverse transpose, one 128-bit store per movable lane (in double,
// 256-bit loads and stores of 32-byte particles). On Zen 4, whose AVX-512 gathers and
// scatters are slow, and on AVX2 machines, this is what the sweep's speed rests on.
//
// The scatter is masked: a static particle (w = 0) may appear in several lanes or threads at
// once, and it must never be written, not even with its own value. AVX-512 has a masked
// scatter instruction; elsewhere it is a loop over the set bits of the write mask. Per-constraint outputs (λ)
// are stored with full vectors only when the whole chunk is active, else lane by lane, so a
// kernel never writes an element outside its [begin, end).
#if defined(TESSERA_CORE_KERNELS_BATCH_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_BATCH_INL_H_
#undef TESSERA_CORE_KERNELS_BATCH_INL_H_
#else
#define TESSERA_CORE_KERNELS_BATCH_INL_H_
#endif

#include <algorithm>
#include <cstdint>
#include <utility>

#include <tessera/core/constraint_batch.hpp>
#include <tessera/core/particle_state.hpp>
#include <tessera/core/simd.hpp>

#include "lane_math-inl.h"

// AVX-512 of any flavour (AVX3, and AVX3_DL, which a -march=native build on Zen 4 or Ice Lake
// and later compiles for): the intrinsics below need only AVX-512F.
#ifndef TESSERA_TARGET_AVX512
#define TESSERA_TARGET_AVX512 (HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX3)
#endif

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

/// Particle indices scaled to element offsets in either layout (ParticleArrays::stride).
HWY_INLINE IndexLanes element_offsets(const ParticleArrays& particles, IndexLanes index) {
  return particles.interleaved() ? hn::ShiftLeft<2>(index) : index;
}

/// One slot's particles for W lanes: where they are, and how heavy.
struct ParticleLanes {
  Vec3<RealLanes> position;
  RealLanes inverse_mass;
};

#if TESSERA_TARGET_AVX512 && !TESSERA_DOUBLE_PRECISION
/// Lanes m, m+4, m+8, m+12's particles, one per 128-bit block.
template <int M>
HWY_INLINE __m512 load_particle_quad(const Real* xyzw, const ParticleIndex* indices) {
  __m512 q = _mm512_castps128_ps512(_mm_load_ps(xyzw + 4 * std::size_t(indices[M])));
  q = _mm512_insertf32x4(q, _mm_load_ps(xyzw + 4 * std::size_t(indices[M + 4])), 1);
  q = _mm512_insertf32x4(q, _mm_load_ps(xyzw + 4 * std::size_t(indices[M + 8])), 2);
  return _mm512_insertf32x4(q, _mm_load_ps(xyzw + 4 * std::size_t(indices[M + 12])), 3);
}
#elif TESSERA_TARGET_AVX512 && TESSERA_DOUBLE_PRECISION
/// Double: lanes A and B's particles (32 bytes each), one per 256-bit half.
template <int A, int B>
HWY_INLINE __m512d load_particle_pair(const Real* xyzw, const ParticleIndex* indices) {
  const __m512d q = _mm512_castpd256_pd512(_mm256_load_pd(xyzw + 4 * std::size_t(indices[A])));
  return _mm512_insertf64x4(q, _mm256_load_pd(xyzw + 4 * std::size_t(indices[B])), 1);
}
#elif HWY_TARGET == HWY_AVX2 && TESSERA_DOUBLE_PRECISION
/// Double on AVX2: lane L's particle, a whole 256-bit register.
template <int L>
HWY_INLINE __m256d load_particle(const Real* xyzw, const ParticleIndex* indices) {
  return _mm256_load_pd(xyzw + 4 * std::size_t(indices[L]));
}
#elif HWY_TARGET == HWY_AVX2 && !TESSERA_DOUBLE_PRECISION
/// Lanes m and m+4's particles, one per 128-bit block.
template <int M>
HWY_INLINE __m256 load_particle_quad(const Real* xyzw, const ParticleIndex* indices) {
  const __m256 q = _mm256_castps128_ps256(_mm_load_ps(xyzw + 4 * std::size_t(indices[M])));
  return _mm256_insertf128_ps(q, _mm_load_ps(xyzw + 4 * std::size_t(indices[M + 4])), 1);
}
#endif

/// The interleaved layout's gather (see the top of this file).
HWY_INLINE ParticleLanes gather_interleaved(const Real* xyzw, const ParticleIndex* indices) {
  [[maybe_unused]] const RealTag d;  // the transposing paths need no tag
#if TESSERA_TARGET_AVX512 && !TESSERA_DOUBLE_PRECISION
  const __m512 q0 = load_particle_quad<0>(xyzw, indices), q1 = load_particle_quad<1>(xyzw, indices);
  const __m512 q2 = load_particle_quad<2>(xyzw, indices), q3 = load_particle_quad<3>(xyzw, indices);
  const __m512 t0 = _mm512_unpacklo_ps(q0, q1), t1 = _mm512_unpackhi_ps(q0, q1);
  const __m512 t2 = _mm512_unpacklo_ps(q2, q3), t3 = _mm512_unpackhi_ps(q2, q3);
  return {{RealLanes{_mm512_shuffle_ps(t0, t2, 0x44)}, RealLanes{_mm512_shuffle_ps(t0, t2, 0xEE)},
           RealLanes{_mm512_shuffle_ps(t1, t3, 0x44)}},
          RealLanes{_mm512_shuffle_ps(t1, t3, 0xEE)}};
#elif TESSERA_TARGET_AVX512 && TESSERA_DOUBLE_PRECISION
  // Pairs [L0|L2], [L1|L3], [L4|L6], [L5|L7]; unpacks give [x x | z z] and [y y | w w] per
  // half, and 128-bit block shuffles put lanes 0 .. 7 in order.
  const __m512d q0 = load_particle_pair<0, 2>(xyzw, indices);
  const __m512d q1 = load_particle_pair<1, 3>(xyzw, indices);
  const __m512d q2 = load_particle_pair<4, 6>(xyzw, indices);
  const __m512d q3 = load_particle_pair<5, 7>(xyzw, indices);
  const __m512d t0 = _mm512_unpacklo_pd(q0, q1), t1 = _mm512_unpackhi_pd(q0, q1);
  const __m512d t2 = _mm512_unpacklo_pd(q2, q3), t3 = _mm512_unpackhi_pd(q2, q3);
  return {{RealLanes{_mm512_shuffle_f64x2(t0, t2, 0x88)}, RealLanes{_mm512_shuffle_f64x2(t1, t3, 0x88)},
           RealLanes{_mm512_shuffle_f64x2(t0, t2, 0xDD)}},
          RealLanes{_mm512_shuffle_f64x2(t1, t3, 0xDD)}};
#elif HWY_TARGET == HWY_AVX2 && !TESSERA_DOUBLE_PRECISION
  const __m256 q0 = load_particle_quad<0>(xyzw, indices), q1 = load_particle_quad<1>(xyzw, indices);
  const __m256 q2 = load_particle_quad<2>(xyzw, indices), q3 = load_particle_quad<3>(xyzw, indices);
  const __m256 t0 = _mm256_unpacklo_ps(q0, q1), t1 = _mm256_unpackhi_ps(q0, q1);
  const __m256 t2 = _mm256_unpacklo_ps(q2, q3), t3 = _mm256_unpackhi_ps(q2, q3);
  return {{RealLanes{_mm256_shuffle_ps(t0, t2, 0x44)}, RealLanes{_mm256_shuffle_ps(t0, t2, 0xEE)},
           RealLanes{_mm256_shuffle_ps(t1, t3, 0x44)}},
          RealLanes{_mm256_shuffle_ps(t1, t3, 0xEE)}};
#elif HWY_TARGET == HWY_AVX2 && TESSERA_DOUBLE_PRECISION
  // Four particles [x y z w]; unpacks give [x0 x1 | z0 z1] and [y0 y1 | w0 w1] (and lanes 2, 3
  // likewise), and 128-bit block permutes join the halves.
  const __m256d p0 = load_particle<0>(xyzw, indices), p1 = load_particle<1>(xyzw, indices);
  const __m256d p2 = load_particle<2>(xyzw, indices), p3 = load_particle<3>(xyzw, indices);
  const __m256d t0 = _mm256_unpacklo_pd(p0, p1), t1 = _mm256_unpackhi_pd(p0, p1);
  const __m256d t2 = _mm256_unpacklo_pd(p2, p3), t3 = _mm256_unpackhi_pd(p2, p3);
  return {{RealLanes{_mm256_permute2f128_pd(t0, t2, 0x20)},
           RealLanes{_mm256_permute2f128_pd(t1, t3, 0x20)},
           RealLanes{_mm256_permute2f128_pd(t0, t2, 0x31)}},
          RealLanes{_mm256_permute2f128_pd(t1, t3, 0x31)}};
#else
  // Other targets: four gathers with the index scaled to 4 per particle.
  const IndexLanes index = hn::ShiftLeft<2>(load_particle_indices(indices));
  return {{hn::GatherIndex(d, xyzw, index), hn::GatherIndex(d, xyzw + 1, index),
           hn::GatherIndex(d, xyzw + 2, index)},
          hn::GatherIndex(d, xyzw + 3, index)};
#endif
}

/// `indices` when all W lanes are active, else a copy in `scratch` whose lanes at and past
/// `active` name lane 0's particle. Why: the lanes past a range's end hold padding or the next
/// block's constraints, whose particles another thread may be writing in this very phase;
/// loading them would be a data race even though their values are discarded (ThreadSanitizer
/// sees the interleaved layout's loads, not the hardware gathers, and found it). Lane 0's
/// particle is this range's own (or static).
HWY_INLINE const ParticleIndex* active_indices(const ParticleIndex* indices, std::size_t active,
                                               ParticleIndex (&scratch)[kMaxLanes]) {
  const std::size_t lanes = hn::Lanes(RealTag());
  if (active >= lanes) return indices;
  for (std::size_t lane = 0; lane < lanes; ++lane)
    scratch[lane] = indices[lane < active ? lane : 0];
  return scratch;
}

/// The particles of W lanes, of which the first `active` are used (active ≥ 1).
HWY_INLINE ParticleLanes gather_particles(const ParticleArrays& particles,
                                          const ParticleIndex* lane_indices,
                                          std::size_t active) {
  const RealTag d;
  HWY_ALIGN ParticleIndex scratch[kMaxLanes];
  const ParticleIndex* indices = active_indices(lane_indices, active, scratch);
  if (particles.interleaved()) return gather_interleaved(particles.x, indices);
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

#if (TESSERA_TARGET_AVX512 || HWY_TARGET == HWY_AVX2) && !TESSERA_DOUBLE_PRECISION
/// Stores lane L = 4k + m (block k of quad m) when bit L of `bits` is set.
template <int L, class Quad>
HWY_INLINE void store_particle_lane(Real* xyzw, const ParticleIndex* indices,
                                    const Quad (&quad)[4], std::uint32_t bits) {
  if (!((bits >> L) & 1u)) return;
  Real* to = xyzw + 4 * std::size_t(indices[L]);
#if TESSERA_TARGET_AVX512
  _mm_store_ps(to, _mm512_extractf32x4_ps(quad[L % 4], L / 4));
#else
  _mm_store_ps(to, _mm256_extractf128_ps(quad[L % 4], L / 4));
#endif
}

template <class Quad, int... L>
HWY_INLINE void store_particle_lanes(Real* xyzw, const ParticleIndex* indices,
                                     const Quad (&quad)[4], std::uint32_t bits,
                                     std::integer_sequence<int, L...>) {
  (store_particle_lane<L>(xyzw, indices, quad, bits), ...);
}
#endif

#if TESSERA_TARGET_AVX512 && TESSERA_DOUBLE_PRECISION
/// Stores lane L (half (L >> 1) & 1 of pair (L & 1) + 2 (L >> 2)) when bit L of `bits` is set.
template <int L>
HWY_INLINE void store_particle_pair_lane(Real* xyzw, const ParticleIndex* indices,
                                         const __m512d (&pair)[4], std::uint32_t bits) {
  if (!((bits >> L) & 1u)) return;
  _mm256_store_pd(xyzw + 4 * std::size_t(indices[L]),
                  _mm512_extractf64x4_pd(pair[(L & 1) + 2 * (L >> 2)], (L >> 1) & 1));
}

template <int... L>
HWY_INLINE void store_particle_pairs(Real* xyzw, const ParticleIndex* indices,
                                     const __m512d (&pair)[4], std::uint32_t bits,
                                     std::integer_sequence<int, L...>) {
  (store_particle_pair_lane<L>(xyzw, indices, pair, bits), ...);
}
#endif

/// The portable scatter, for either layout: lane after lane of `write`, x, y, z stored at the
/// particle's place (ParticleArrays::stride).
HWY_INLINE void scatter_lane_by_lane(const ParticleArrays& particles, const ParticleIndex* indices,
                                     RealLanes x, RealLanes y, RealLanes z,
                                     const LaneMask& write) {
  const RealTag d;
  std::uint64_t bits = mask_bits(write);
  if (bits == 0) return;
  HWY_ALIGN Real x_lanes[kMaxLanes], y_lanes[kMaxLanes], z_lanes[kMaxLanes];
  hn::Store(x, d, x_lanes);
  hn::Store(y, d, y_lanes);
  hn::Store(z, d, z_lanes);
  while (bits != 0) {
    const int lane = __builtin_ctzll(bits);
    const std::size_t at = std::size_t(indices[lane]) * particles.stride;
    particles.x[at] = x_lanes[lane];
    particles.y[at] = y_lanes[lane];
    particles.z[at] = z_lanes[lane];
    bits &= bits - 1;
  }
}

/// The interleaved layout's scatter: the inverse transpose, one whole-particle store per lane
/// of `write` (w is stored back unchanged); lane by lane on targets without a transpose.
HWY_INLINE void scatter_interleaved(const ParticleArrays& particles, const ParticleIndex* indices,
                                    RealLanes x, RealLanes y, RealLanes z, RealLanes w,
                                    const LaneMask& write) {
  Real* const xyzw = particles.x;
#if TESSERA_TARGET_AVX512 && !TESSERA_DOUBLE_PRECISION
  const std::uint32_t bits = std::uint32_t(write.raw);
  if (bits == 0) return;
  const __m512 t0 = _mm512_unpacklo_ps(x.raw, y.raw), t1 = _mm512_unpackhi_ps(x.raw, y.raw);
  const __m512 t2 = _mm512_unpacklo_ps(z.raw, w.raw), t3 = _mm512_unpackhi_ps(z.raw, w.raw);
  const __m512 quad[4] = {_mm512_shuffle_ps(t0, t2, 0x44), _mm512_shuffle_ps(t0, t2, 0xEE),
                          _mm512_shuffle_ps(t1, t3, 0x44), _mm512_shuffle_ps(t1, t3, 0xEE)};
  store_particle_lanes(xyzw, indices, quad, bits, std::make_integer_sequence<int, 16>());
#elif TESSERA_TARGET_AVX512 && TESSERA_DOUBLE_PRECISION
  const std::uint32_t bits = std::uint32_t(write.raw);
  if (bits == 0) return;
  // The inverse of the gather's transpose: pairs [L0|L2], [L1|L3], [L4|L6], [L5|L7].
  const __m512i low = _mm512_setr_epi64(0, 1, 8, 9, 2, 3, 10, 11);
  const __m512i high = _mm512_setr_epi64(4, 5, 12, 13, 6, 7, 14, 15);
  const __m512d t0 = _mm512_permutex2var_pd(x.raw, low, z.raw);
  const __m512d t2 = _mm512_permutex2var_pd(x.raw, high, z.raw);
  const __m512d t1 = _mm512_permutex2var_pd(y.raw, low, w.raw);
  const __m512d t3 = _mm512_permutex2var_pd(y.raw, high, w.raw);
  const __m512d pair[4] = {_mm512_unpacklo_pd(t0, t1), _mm512_unpackhi_pd(t0, t1),
                           _mm512_unpacklo_pd(t2, t3), _mm512_unpackhi_pd(t2, t3)};
  store_particle_pairs(xyzw, indices, pair, bits, std::make_integer_sequence<int, 8>());
#elif HWY_TARGET == HWY_AVX2 && !TESSERA_DOUBLE_PRECISION
  const std::uint32_t bits = std::uint32_t(mask_bits(write));
  if (bits == 0) return;
  const __m256 t0 = _mm256_unpacklo_ps(x.raw, y.raw), t1 = _mm256_unpackhi_ps(x.raw, y.raw);
  const __m256 t2 = _mm256_unpacklo_ps(z.raw, w.raw), t3 = _mm256_unpackhi_ps(z.raw, w.raw);
  const __m256 quad[4] = {_mm256_shuffle_ps(t0, t2, 0x44), _mm256_shuffle_ps(t0, t2, 0xEE),
                          _mm256_shuffle_ps(t1, t3, 0x44), _mm256_shuffle_ps(t1, t3, 0xEE)};
  store_particle_lanes(xyzw, indices, quad, bits, std::make_integer_sequence<int, 8>());
#elif HWY_TARGET == HWY_AVX2 && TESSERA_DOUBLE_PRECISION
  const std::uint32_t bits = std::uint32_t(mask_bits(write));
  if (bits == 0) return;
  // The inverse of the gather's transpose.
  const __m256d a0 = _mm256_permute2f128_pd(x.raw, z.raw, 0x20);
  const __m256d a2 = _mm256_permute2f128_pd(x.raw, z.raw, 0x31);
  const __m256d b0 = _mm256_permute2f128_pd(y.raw, w.raw, 0x20);
  const __m256d b2 = _mm256_permute2f128_pd(y.raw, w.raw, 0x31);
  const __m256d particle[4] = {_mm256_unpacklo_pd(a0, b0), _mm256_unpackhi_pd(a0, b0),
                               _mm256_unpacklo_pd(a2, b2), _mm256_unpackhi_pd(a2, b2)};
  if (bits & 1u) _mm256_store_pd(xyzw + 4 * std::size_t(indices[0]), particle[0]);
  if (bits & 2u) _mm256_store_pd(xyzw + 4 * std::size_t(indices[1]), particle[1]);
  if (bits & 4u) _mm256_store_pd(xyzw + 4 * std::size_t(indices[2]), particle[2]);
  if (bits & 8u) _mm256_store_pd(xyzw + 4 * std::size_t(indices[3]), particle[3]);
#else
  (void)xyzw;
  (void)w;
  scatter_lane_by_lane(particles, indices, x, y, z, write);
#endif
}

/// The lanes' particles moved by `correction` (w unchanged).
HWY_INLINE ParticleLanes corrected_particles(const ParticleLanes& lanes,
                                             const Vec3<RealLanes>& correction) {
  return {lanes.position + correction, lanes.inverse_mass};
}

/// x[index] = position for the active lanes whose particle is movable.
/// On AVX-512 in the separate layout this is a masked hardware scatter (measured 8 % faster
/// than the scalar loop on a two-particle kernel); the intrinsics stay here, in the one place
/// that scatters.
HWY_INLINE void scatter_particles(ParticleArrays& particles, const ParticleIndex* indices,
                                  const ParticleLanes& lanes, const LaneMask& active) {
  const RealTag d;
  const LaneMask write = hn::And(active, lanes.inverse_mass > hn::Zero(d));
  const Vec3<RealLanes>& p = lanes.position;
  if (particles.interleaved())
    return scatter_interleaved(particles, indices, p.x, p.y, p.z, lanes.inverse_mass, write);
#if TESSERA_TARGET_AVX512 && TESSERA_DOUBLE_PRECISION
  const __m256i index = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(indices));
  _mm512_mask_i32scatter_pd(particles.x, write.raw, index, p.x.raw, 8);
  _mm512_mask_i32scatter_pd(particles.y, write.raw, index, p.y.raw, 8);
  _mm512_mask_i32scatter_pd(particles.z, write.raw, index, p.z.raw, 8);
#elif TESSERA_TARGET_AVX512
  const __m512i index = _mm512_loadu_si512(indices);
  _mm512_mask_i32scatter_ps(particles.x, write.raw, index, p.x.raw, 4);
  _mm512_mask_i32scatter_ps(particles.y, write.raw, index, p.y.raw, 4);
  _mm512_mask_i32scatter_ps(particles.z, write.raw, index, p.z.raw, 4);
#else
  scatter_lane_by_lane(particles, indices, p.x, p.y, p.z, write);
#endif
}

/// x[index] = position + correction for the active lanes whose particle is movable.
HWY_INLINE void scatter_corrected(ParticleArrays& particles, const ParticleIndex* indices,
                                  const ParticleLanes& lanes, const Vec3<RealLanes>& correction,
                                  const LaneMask& active) {
  scatter_particles(particles, indices, corrected_particles(lanes, correction), active);
}

/// The index arrays of the N slots of an N-particle family.
template <int N>
HWY_INLINE void constraint_slots(const ConstraintParticles<N>& indices,
                                 const ParticleIndex* (&slot)[N]) {
  for (int k = 0; k < N; ++k) slot[k] = indices.particle[std::size_t(k)].data();
}

/// Asks the caches for particle `index`: its one line in the interleaved layout, its line of
/// each of the four arrays in the separate one.
HWY_INLINE void prefetch_particle(const ParticleArrays& particles, std::size_t index) {
  const std::size_t at = index * particles.stride;
  __builtin_prefetch(particles.x + at);
  if (!particles.interleaved()) {
    __builtin_prefetch(particles.y + at);
    __builtin_prefetch(particles.z + at);
    __builtin_prefetch(particles.inverse_mass + at);
  }
}

/// Asks the caches for the N particles of constraints i .. min(i + W, end) ahead of their
/// gather. A kernel whose formula is long (hundreds of instructions per W constraints) keeps
/// the out-of-order window from reaching the next block's loads, so each block's gathers
/// would otherwise wait for its particles' misses in turn.
template <int N>
HWY_INLINE void prefetch_constraint_particles(const ParticleArrays& particles,
                                              const ParticleIndex* const* slot, std::size_t i,
                                              std::size_t end) {
  const std::size_t count = std::min(end - i, hn::Lanes(RealTag()));
  for (int k = 0; k < N; ++k)
    for (std::size_t lane = 0; lane < count; ++lane)
      prefetch_particle(particles, slot[k][i + lane]);
}

/// Gathers the N particles of constraints i .. i+W, slot by slot: gathered keeps what the
/// scatter needs, position and w are the formula's inputs. With PrefetchBlocks > 0 it first
/// asks for the particles of the block that many blocks ahead (prefetch_constraint_particles;
/// a kernel sets it where it measured a gain).
template <int N, std::size_t PrefetchBlocks = 0>
HWY_INLINE void gather_constraint_particles(const ParticleArrays& particles,
                                            const ParticleIndex* const* slot, std::size_t i,
                                            std::size_t end, ParticleLanes (&gathered)[N],
                                            Vec3<RealLanes> (&position)[N],
                                            RealLanes (&w)[N]) {
  if constexpr (PrefetchBlocks > 0) {
    const std::size_t ahead = i + PrefetchBlocks * hn::Lanes(RealTag());
    if (ahead < end) prefetch_constraint_particles<N>(particles, slot, ahead, end);
  }
  // Unrolled so the N slots' lanes stay in registers (a rolled loop kept them in stack
  // arrays: seven 512-bit stores and reloads per slot on the distance kernel).
  HWY_UNROLL(16)
  for (int k = 0; k < N; ++k) {
    gathered[k] = gather_particles(particles, slot[k] + i, end - i);
    position[k] = gathered[k].position;
    w[k] = gathered[k].inverse_mass;
  }
}

/// The same without the separate position and w views.
template <int N>
HWY_INLINE void gather_constraint_particles(const ParticleArrays& particles,
                                            const ParticleIndex* const* slot, std::size_t i,
                                            std::size_t end, ParticleLanes (&gathered)[N]) {
  HWY_UNROLL(16)
  for (int k = 0; k < N; ++k) gathered[k] = gather_particles(particles, slot[k] + i, end - i);
}

/// The redirected output of ParticleArrays (corrected_x/y/z) seen as particle arrays, so the
/// same scatter can write it.
HWY_INLINE ParticleArrays corrected_output(const ParticleArrays& particles) {
  return {particles.corrected_x, particles.corrected_y, particles.corrected_z,
          particles.inverse_mass, particles.count};
}

/// Slot `slot` of constraints i .. i+W into the redirected output: consecutive elements, so a
/// masked vector store per coordinate (active lanes whose particle is movable).
HWY_INLINE void store_particles(const ParticleArrays& particles, std::size_t slot, std::size_t i,
                                const ParticleLanes& lanes, const LaneMask& active) {
  const RealTag d;
  const LaneMask write = hn::And(active, lanes.inverse_mass > hn::Zero(d));
  const std::size_t at = slot * particles.corrected_stride + i;
  hn::BlendedStore(lanes.position.x, write, d, particles.corrected_x + at);
  hn::BlendedStore(lanes.position.y, write, d, particles.corrected_y + at);
  hn::BlendedStore(lanes.position.z, write, d, particles.corrected_z + at);
}

HWY_INLINE void store_corrected(const ParticleArrays& particles, std::size_t slot, std::size_t i,
                                const ParticleLanes& lanes, const Vec3<RealLanes>& correction,
                                const LaneMask& active) {
  store_particles(particles, slot, i, corrected_particles(lanes, correction), active);
}

/// Scatters the movable particles of the active lanes of constraints i .. i+W, already
/// corrected (or stores them in the redirected output, see ParticleArrays).
template <int N>
HWY_INLINE void scatter_constraint_particles(ParticleArrays& particles,
                                             const ParticleIndex* const* slot, std::size_t i,
                                             const ParticleLanes (&corrected)[N],
                                             const LaneMask& active) {
  if (particles.corrected_x != nullptr) {
    HWY_UNROLL(16)
    for (int k = 0; k < N; ++k) store_particles(particles, std::size_t(k), i, corrected[k], active);
    return;
  }
  HWY_UNROLL(16)
  for (int k = 0; k < N; ++k) scatter_particles(particles, slot[k] + i, corrected[k], active);
}

/// The same for particles and their corrections.
template <int N>
HWY_INLINE void scatter_constraint_particles(ParticleArrays& particles,
                                             const ParticleIndex* const* slot, std::size_t i,
                                             const ParticleLanes (&gathered)[N],
                                             const Vec3<RealLanes> (&corr)[N],
                                             const LaneMask& active) {
  ParticleLanes corrected[N];
  HWY_UNROLL(16)
  for (int k = 0; k < N; ++k) corrected[k] = corrected_particles(gathered[k], corr[k]);
  scatter_constraint_particles(particles, slot, i, corrected, active);
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
