// Squared distances from one segment to a batch of segments, SIMD (segment_distances.cpp).
#pragma once

#include <cstddef>
#include <bit>
#include <type_traits>
#include <cstdint>

#include <tessera/collision/spatial_hash.hpp>
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

/// Velocity balls (centre, radius) and base budgets by coordinate, readable as the batch
/// they go with.
struct BallBatch {
  const Real *cx, *cy, *cz, *radius, *budget;
};
/// Boxes by coordinate (lower x, y, z, upper x, y, z), readable as the batch they go with.
struct BoxBatch {
  const Real* lo[3];
  const Real* hi[3];
};
/// Particle indices as the bits of a Real lane (compared as integers, never computed with):
/// up to three per lane (a triangle's corners; an edge's second repeated), and 1 where all of
/// a lane's particles are static.
struct TopologyBatch {
  const Real* id[3];
  const Real* all_static;
};
inline Real id_lane(std::uint32_t id) {
  using Bits = std::conditional_t<sizeof(Real) == sizeof(std::uint32_t), std::uint32_t,
                                  std::uint64_t>;
  return std::bit_cast<Real>(Bits(id));
}
/// What a block's lanes carry beyond their coordinates.
struct BlockBatch {
  BallBatch balls;
  BoxBatch boxes;
  TopologyBatch topology;
};
/// The querying primitive: its velocity ball, the substeps its relative motion is allowed
/// for, its box, its particles (a vertex's repeated) and whether all are static.
struct BlockQuery {
  Real centre[3];
  Real radius;
  Real steps;
  Aabb box;
  Real id[2];
  bool all_static;
};
/// The lanes of a block (primitive_leaves.hpp: a leaf's members): a field's block is one
/// 64-byte cache line and one vector of the widest target (AVX-512). Measured against 8 in
/// float (docs/performance.md, "Leaves of a cache line"): a build takes 25–32 % less time on
/// AVX-512 and the same on AVX2 (two vectors a block).
inline constexpr std::size_t kBlockLanes = 64 / sizeof(Real);
/// A leaf's fields, each a block of kBlockLanes lanes (primitive_leaves.hpp): its members'
/// coordinates (segments p, q; triangles a, b, c; x, y, z each), then these.
enum LeafField : std::size_t {
  kLeafBudget,
  kLeafCentre,                     // x, y, z of the velocity ball's centre
  kLeafRadius = kLeafCentre + 3,   // the ball's radius
  kLeafLo,                         // the member's box
  kLeafHi = kLeafLo + 3,
  kLeafIds = kLeafHi + 3,          // its particles, id_lane (an edge's second repeated)
  kLeafStatic = kLeafIds + 3,      // 1 where all are static
  kLeafTailFields
};
/// The lanes of leaf data `base` whose coordinates take `coordinates` fields.
inline BlockBatch block_lanes(const Real* base, std::size_t coordinates) {
  const auto at = [&](std::size_t field) { return base + (coordinates + field) * kBlockLanes; };
  return {{at(kLeafCentre), at(kLeafCentre + 1), at(kLeafCentre + 2), at(kLeafRadius),
           at(kLeafBudget)},
          {{at(kLeafLo), at(kLeafLo + 1), at(kLeafLo + 2)},
           {at(kLeafHi), at(kLeafHi + 1), at(kLeafHi + 2)}},
          {{at(kLeafIds), at(kLeafIds + 1), at(kLeafIds + 2)}, at(kLeafStatic)}};
}
/// The pairs of a primitive and the members of some leaves that can be a contact's
/// candidates. The leaves' fields are at leaf_data + (leaf · (6 + kLeafTailFields) + field) ·
/// kBlockLanes, for each leaf of leaves[0 .. leaf_count). A member is tested when its box
/// overlaps the query's (a vector with none is skipped), it shares no particle with it and is
/// not all static with it; it passes when its squared distance is below
/// (own + (budget[k] + allowed[k]))², allowed[k] = steps ((radius + radius[k]) +
/// √((dx² + dy²) + dz²)), d = centre − centre[k] (what the two primitives' relative motion
/// may close over `steps` substeps, allowed_between's operations in its order). The passing
/// positions b · kBlockLanes + lane go to `within` in order; `squared` and `allowed` are
/// written at the positions of the vectors measured. The distances are segments_within's
/// bits.
std::size_t segments_within_leaves(const Vector3r& p1, const Vector3r& q1, Real own,
                                   const BlockQuery& query, const Real* leaf_data,
                                   const std::uint32_t* leaves, std::size_t leaf_count,
                                   Real* squared, Real* allowed, std::uint32_t* within);

}  // namespace tessera::detail
