// The leaves' box scan of a re-box's query (leaf_scan.cpp).
#pragma once

#include <cstddef>
#include <cstdint>

#include <tessera/collision/spatial_hash.hpp>
#include <tessera/core/real.hpp>

namespace tessera::detail {

/// Of the members of leaves[0 .. leaf_count) (their fields at leaf_data + (leaf · fields +
/// field) · kBlockLanes, the box's lows from `lo_field`, its highs 3 fields on), those whose
/// box overlaps `box`, as positions b · kBlockLanes + lane into `meeting`, in order; returns
/// their count. `meeting` has room for leaf_count · kBlockLanes (LeafQuery::fit gives that
/// and more). SIMD, dispatched at run time.
std::size_t lanes_meeting_box(const Aabb& box, const Real* leaf_data, std::size_t fields,
                              std::size_t lo_field, const std::uint32_t* leaves,
                              std::size_t leaf_count, std::uint32_t* meeting);

}  // namespace tessera::detail
