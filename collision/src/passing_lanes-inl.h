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

#include "segment_distances.hpp"

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

/// What `query.steps` substeps of relative motion can close between the query's ball and
/// the lanes i .. i + lanes: steps ((radius + radius[k]) + √((dx² + dy²) + dz²)), the scalar
/// allowed_between's operations in its order.
template <class D>
HWY_INLINE hwy::HWY_NAMESPACE::Vec<D> AllowanceAt(D d, const detail::BlockQuery& query,
                                                  const detail::BallBatch& balls, std::size_t i) {
  namespace hn = hwy::HWY_NAMESPACE;
  const auto dx = hn::Sub(hn::Set(d, query.centre[0]), hn::LoadU(d, balls.cx + i));
  const auto dy = hn::Sub(hn::Set(d, query.centre[1]), hn::LoadU(d, balls.cy + i));
  const auto dz = hn::Sub(hn::Set(d, query.centre[2]), hn::LoadU(d, balls.cz + i));
  const auto apart = hn::Sqrt(hn::Add(hn::Add(hn::Mul(dx, dx), hn::Mul(dy, dy)), hn::Mul(dz, dz)));
  return hn::Mul(hn::Set(d, query.steps),
                 hn::Add(hn::Add(hn::Set(d, query.radius), hn::LoadU(d, balls.radius + i)), apart));
}

/// The lanes i .. i + lanes whose box overlaps `box` (faces touching meet; an empty box
/// meets nothing).
template <class D>
HWY_INLINE hwy::HWY_NAMESPACE::Mask<D> BoxesMeetAt(D d, const Aabb& box,
                                                   const detail::BoxBatch& boxes, std::size_t i) {
  namespace hn = hwy::HWY_NAMESPACE;
  auto m = hn::Le(hn::LoadU(d, boxes.lo[0] + i), hn::Set(d, box.hi[0]));
  m = hn::And(m, hn::Le(hn::Set(d, box.lo[0]), hn::LoadU(d, boxes.hi[0] + i)));
  for (int axis = 1; axis < 3; ++axis) {
    m = hn::And(m, hn::Le(hn::LoadU(d, boxes.lo[axis] + i), hn::Set(d, box.hi[axis])));
    m = hn::And(m, hn::Le(hn::Set(d, box.lo[axis]), hn::LoadU(d, boxes.hi[axis] + i)));
  }
  return m;
}

/// The lanes i .. i + lanes that may pair with the query: their box overlaps the query's,
/// they share no particle with it, and they are not all static with it.
template <class D>
HWY_INLINE hwy::HWY_NAMESPACE::Mask<D> MayPairAt(D d, const detail::BlockQuery& query,
                                                 const detail::BlockBatch& lanes, std::size_t i) {
  namespace hn = hwy::HWY_NAMESPACE;
  auto m = BoxesMeetAt(d, query.box, lanes.boxes, i);
  if (hn::AllFalse(d, m)) return m;
  const hn::RebindToUnsigned<D> du;
  const auto first = hn::BitCast(du, hn::Set(d, query.id[0])),
             second = hn::BitCast(du, hn::Set(d, query.id[1]));
  const auto id0 = hn::BitCast(du, hn::LoadU(d, lanes.topology.id[0] + i)),
             id1 = hn::BitCast(du, hn::LoadU(d, lanes.topology.id[1] + i)),
             id2 = hn::BitCast(du, hn::LoadU(d, lanes.topology.id[2] + i));
  const auto shared =
      hn::Or(hn::Or(hn::Or(hn::Eq(id0, first), hn::Eq(id1, first)), hn::Eq(id2, first)),
             hn::Or(hn::Or(hn::Eq(id0, second), hn::Eq(id1, second)), hn::Eq(id2, second)));
  m = hn::AndNot(hn::RebindMask(d, shared), m);
  if (query.all_static)
    m = hn::And(m, hn::Eq(hn::LoadU(d, lanes.topology.all_static + i), hn::Zero(d)));
  return m;
}

/// The loop of a leaf query (segments_within_leaves, triangles_within_leaves): for each met
/// leaf's vectors of lanes, the lanes that may pair, their allowance, their squared distance
/// from distance_at(d, leaf fields, i), and the passing positions b · kBlockLanes + lane.
template <std::size_t Coordinates, class DistanceAt>
HWY_INLINE std::size_t LanesWithinLeaves(Real own, const detail::BlockQuery& query,
                                         const Real* leaf_data, const std::uint32_t* leaves,
                                         std::size_t leaf_count, Real* squared, Real* allowed,
                                         std::uint32_t* within, DistanceAt&& distance_at) {
  namespace hn = hwy::HWY_NAMESPACE;
  const hn::CappedTag<Real, detail::kBlockLanes> d;
  const std::size_t width = hn::Lanes(d);
  const auto reach_own = hn::Set(d, own);
  constexpr std::size_t kFields = Coordinates + detail::kLeafTailFields;
  std::size_t found = 0;
  for (std::size_t b = 0; b < leaf_count; ++b) {
    const Real* base = leaf_data + std::size_t(leaves[b]) * kFields * detail::kBlockLanes;
    const detail::BlockBatch lanes = detail::block_lanes(base, Coordinates);
    for (std::size_t i = 0; i < detail::kBlockLanes; i += width) {
      const auto may_pair = MayPairAt(d, query, lanes, i);
      if (hn::AllFalse(d, may_pair)) continue;
      const std::size_t out = b * detail::kBlockLanes + i;
      const auto closing = AllowanceAt(d, query, lanes.balls, i);
      hn::StoreU(closing, d, allowed + out);
      const auto distance = distance_at(d, base, i);
      hn::StoreU(distance, d, squared + out);
      // within = own + (budget + allowed), the batched build's order.
      const auto reach =
          hn::Add(reach_own, hn::Add(hn::LoadU(d, lanes.balls.budget + i), closing));
      found = AppendPassing(d, hn::And(may_pair, hn::Lt(distance, hn::Mul(reach, reach))), out,
                            out + width, within, found);
    }
  }
  return found;
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif
