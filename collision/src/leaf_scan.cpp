// A re-box's query against the build's leaves (self_collision.cpp, rebox): of the met leaves'
// members, those whose box of the build overlaps the query's box, a vector of lanes at a time,
// compiled once per SIMD target (Highway foreach_target) and dispatched at run time.
//
//   met leaf b:   lo x │ lo y │ lo z │ hi x │ hi y │ hi z      (kBlockLanes lanes each)
//   per vector:   lo ≤ q.hi and q.lo ≤ hi on x, y, z  ──►  mask  ──►  b · kBlockLanes + lane
//
// Why: tested lane by lane, each member branched on its box (most met lanes meet nothing, and
// which ones is not predictable); that loop was most of a re-box's edge queries.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "leaf_scan.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include "leaf_scan.hpp"
#include "passing_lanes-inl.h"
#include "segment_distances.hpp"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

std::size_t LanesMeetingBox(const Aabb& box, const Real* leaf_data, std::size_t fields,
                            std::size_t lo_field, const std::uint32_t* leaves,
                            std::size_t leaf_count, std::uint32_t* meeting) {
  const hn::CappedTag<Real, detail::kBlockLanes> d;
  const std::size_t width = hn::Lanes(d);
  constexpr std::size_t L = detail::kBlockLanes;
  std::size_t found = 0;
  for (std::size_t b = 0; b < leaf_count; ++b) {
    const Real* lo = leaf_data + (std::size_t(leaves[b]) * fields + lo_field) * L;
    const Real* hi = lo + (detail::kLeafHi - detail::kLeafLo) * L;
    const detail::BoxBatch boxes{{lo, lo + L, lo + 2 * L}, {hi, hi + L, hi + 2 * L}};
    for (std::size_t i = 0; i < L; i += width) {
      const std::size_t out = b * L + i;
      found = AppendPassing(d, BoxesMeetAt(d, box, boxes, i), out, out + width, meeting, found);
    }
  }
  return found;
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace tessera::detail {

HWY_EXPORT(LanesMeetingBox);

std::size_t lanes_meeting_box(const Aabb& box, const Real* leaf_data, std::size_t fields,
                              std::size_t lo_field, const std::uint32_t* leaves,
                              std::size_t leaf_count, std::uint32_t* meeting) {
  return HWY_DYNAMIC_DISPATCH(LanesMeetingBox)(box, leaf_data, fields, lo_field, leaves,
                                               leaf_count, meeting);
}

}  // namespace tessera::detail
#endif
