// Squared distances from one point to a batch of triangles, SIMD (triangle_distances.cpp).
#pragma once

#include <cstddef>
#include <cstdint>

#include <tessera/core/real.hpp>

#include "closest_distance.hpp"
#include "segment_distances.hpp"

namespace tessera::detail {

/// Triangles (a, b, c) by coordinate, `count` of them, each with a budget; every array
/// readable to `count` rounded up to a multiple of kSegmentBatchLanes (the lanes past `count`
/// are computed and ignored).
struct TriangleBatch {
  const Real *ax, *ay, *az, *bx, *by, *bz, *cx, *cy, *cz;
  const Real* budget;
  std::size_t count;
};

/// The batch's triangles k (below count) whose squared distance to p is below
/// (own + budget[k])²: their positions k written to `within` in increasing order, their
/// count returned; `squared` gets every distance. The distances are
/// squared_point_triangle_distance's bits on every target, and the comparison is the scalar
/// one (within = own + budget, squared < within · within). squared and within have the
/// padded room.
std::size_t triangles_within(const Vector3r& p, Real own, const TriangleBatch& batch,
                             Real* squared, std::uint32_t* within);

/// segments_within_leaves (segment_distances.hpp) for a point against triangles: their leaves
/// hold 9 + kLeafTailFields fields; triangles_within's bits.
std::size_t triangles_within_leaves(const Vector3r& p, Real own, const BlockQuery& query,
                                    const Real* leaf_data, const std::uint32_t* leaves,
                                    std::size_t leaf_count, Real* squared, Real* allowed,
                                    std::uint32_t* within);

}  // namespace tessera::detail
