// Squared distances from one segment to a batch of segments, SIMD (segment_distances.cpp).
#pragma once

#include <cstddef>
#include <cstdint>

#include <tessera/core/real.hpp>

#include "closest_distance.hpp"

namespace tessera::detail {

/// Segments (p, q) by coordinate, `count` of them; every array readable to `count` rounded
/// up to a multiple of kSegmentBatchLanes (the lanes past `count` are computed and ignored).
struct SegmentBatch {
  const Real *px, *py, *pz, *qx, *qy, *qz;
  std::size_t count;
};
/// The widest vector the dispatch may pick, in lanes of Real (AVX-512 float).
inline constexpr std::size_t kSegmentBatchLanes = 16;
/// `count` rounded up to a multiple of kSegmentBatchLanes: the room a batch's arrays need.
constexpr std::size_t padded_to_lanes(std::size_t count) {
  return (count + kSegmentBatchLanes - 1) / kSegmentBatchLanes * kSegmentBatchLanes;
}

/// out[k] = the squared distance between segment (p1, q1) and the batch's segment k, for k
/// below count rounded up to the lanes (out has that room). p1 ≠ q1 (not point-like: the
/// caller measures a point-like first segment with squared_segment_distance).
void squared_segment_distances(const Vector3r& p1, const Vector3r& q1, const SegmentBatch& batch,
                               Real* out);

/// The batch's segments k (below count) with squared distance to (p1, q1) below
/// (own + budget[k])²: their positions k written to `within` in increasing order, their count
/// returned; `squared` gets every distance as squared_segment_distances writes them. The
/// comparison is the scalar one (within = own + budget, squared < within · within), so the
/// same segments pass on every target. budget, squared and within have the padded room.
std::size_t segments_within(const Vector3r& p1, const Vector3r& q1, Real own,
                            const SegmentBatch& batch, const Real* budget, Real* squared,
                            std::uint32_t* within);

/// The pairs k (below first.count; second.count the same) whose segments first k and second
/// k are closer than within[k]: squared_segment_distance(p1, q1, p2, q2) < within[k]², with
/// its bits (first's segments not point-like). Their positions k go to `passing` in
/// increasing order; returns how many. Every array has the padded room.
std::size_t segment_pairs_within(const SegmentBatch& first, const SegmentBatch& second,
                                 const Real* within, std::uint32_t* passing);

}  // namespace tessera::detail
