// The true lanes of a mask as positions, for the batched distances (segment_distances.cpp,
// triangle_distances.cpp): included once per SIMD target (Highway's per-target include
// guard).
#if defined(TESSERA_COLLISION_PASSING_LANES_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_COLLISION_PASSING_LANES_INL_H_
#undef TESSERA_COLLISION_PASSING_LANES_INL_H_
#else
#define TESSERA_COLLISION_PASSING_LANES_INL_H_
#endif

#include <cstddef>
#include <cstdint>

#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

/// Appends to `passing` (from position `found`) the positions i + k of the true lanes k of
/// `mask` below `count` (past it: padding, dropped), in order, without a branch per lane;
/// returns the new count. `passing` has room to i + lanes. At most 64 lanes.
template <class D, class M>
HWY_INLINE std::size_t AppendPassing(D d, M mask, std::size_t i, std::size_t count,
                                     std::uint32_t* passing, std::size_t found) {
  std::uint8_t bytes[8] = {};
  hwy::HWY_NAMESPACE::StoreMaskBits(d, mask, bytes);
  std::uint64_t bits = 0;
  for (int k = 0; k < 8; ++k) bits |= std::uint64_t(bytes[k]) << (8 * k);
  while (bits != 0) {
    const std::size_t k = i + std::size_t(__builtin_ctzll(bits));
    bits &= bits - 1;
    passing[found] = std::uint32_t(k);
    found += k < count;
  }
  return found;
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif
