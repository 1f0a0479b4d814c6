// Squared distances from one segment to many (the edge–edge pairs of a self-collision
// build), a vector of segments at a time: compiled once per SIMD target (Highway
// foreach_target) and dispatched at run time. The same closest-point rule as
// squared_segment_distance (closest_distance.hpp; Ericson §5.1.9), its branches as lane
// selects:
//
//   d1 = q1 − p1, d2 = q2 − p2, r = p1 − p2;  a = d1·d1, e = d2·d2, b = d1·d2, c = d1·r, f = d2·r
//   s = clamp((b f − c e) / (a e − b²), 0, 1)   (0 for parallel segments)
//   t = (b s + f) / e;  t < 0: t = 0, s = clamp(−c / a);  t > 1: t = 1, s = clamp((b − c) / a)
//   (e ≈ 0: t = 0, s = clamp(−c / a))
//   distance² = |p1 + s d1 − p2 − t d2|²
//
// Each lane computes the scalar function's operations in its order (dot products summed
// x + (y + z), detail::dot3; true divisions), and the module is compiled without floating-point
// contraction (no fused multiply–add on one side and not the other): the same bits as
// squared_segment_distance on every target, so a batch finds exactly the scalar rule's
// candidates (tests/collision/test_self_collision.cpp checks it on every target the machine
// runs, nearly parallel segments included: there an FMA had moved the closest points by
// 5·10⁻⁴ of the length).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "segment_distances.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include "passing_lanes-inl.h"
#include "segment_distances.hpp"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

/// The squared distances from segment (p1, p1 + d1) to the batch's segments i .. i + lanes.
template <class D, class V>
HWY_INLINE V SquaredDistancesAt(D d, const detail::SegmentBatch& batch, std::size_t i, V p1x,
                                V p1y, V p1z, V d1x, V d1y, V d1z, V a) {
  const auto zero = hn::Zero(d), one = hn::Set(d, Real(1));
  const auto tiny = hn::Set(d, kDegenerateTolerance * kDegenerateTolerance);
  const auto clamp01 = [&](V v) { return hn::Min(hn::Max(v, zero), one); };
  // Eigen's order for a 3-vector's dot product and squared norm: x + (y + z).
  const auto dot = [](V ax, V ay, V az, V bx, V by, V bz) {
    return hn::Add(hn::Mul(ax, bx), hn::Add(hn::Mul(ay, by), hn::Mul(az, bz)));
  };
  const auto p2x = hn::LoadU(d, batch.px + i), p2y = hn::LoadU(d, batch.py + i),
             p2z = hn::LoadU(d, batch.pz + i);
  const auto d2x = hn::Sub(hn::LoadU(d, batch.qx + i), p2x),
             d2y = hn::Sub(hn::LoadU(d, batch.qy + i), p2y),
             d2z = hn::Sub(hn::LoadU(d, batch.qz + i), p2z);
  const auto rx = hn::Sub(p1x, p2x), ry = hn::Sub(p1y, p2y), rz = hn::Sub(p1z, p2z);
  const auto e = dot(d2x, d2y, d2z, d2x, d2y, d2z);
  const auto f = dot(d2x, d2y, d2z, rx, ry, rz);
  const auto c = dot(d1x, d1y, d1z, rx, ry, rz);
  const auto b = dot(d1x, d1y, d1z, d2x, d2y, d2z);
  const auto denominator = hn::Sub(hn::Mul(a, e), hn::Mul(b, b));
  // The lanes that do not take a branch compute it anyway (a 0/0 there is discarded).
  const auto s_free = hn::IfThenElseZero(
      hn::Gt(denominator, zero),
      clamp01(hn::Div(hn::Sub(hn::Mul(b, f), hn::Mul(c, e)), denominator)));
  const auto t_free = hn::Div(hn::Add(hn::Mul(b, s_free), f), e);
  const auto s_at_0 = clamp01(hn::Div(hn::Neg(c), a));
  const auto s_at_1 = clamp01(hn::Div(hn::Sub(b, c), a));
  const auto below = hn::Lt(t_free, zero), above = hn::Gt(t_free, one);
  auto s = hn::IfThenElse(below, s_at_0, hn::IfThenElse(above, s_at_1, s_free));
  auto t = hn::IfThenElse(below, zero, hn::IfThenElse(above, one, t_free));
  // A point-like second segment: the first's point nearest p2.
  const auto point_like = hn::Le(e, tiny);
  s = hn::IfThenElse(point_like, s_at_0, s);
  t = hn::IfThenElseZero(hn::Not(point_like), t);
  // (p1 + s d1) − (p2 + t d2), as the scalar rule writes it.
  const auto gx = hn::Sub(hn::Add(p1x, hn::Mul(s, d1x)), hn::Add(p2x, hn::Mul(t, d2x)));
  const auto gy = hn::Sub(hn::Add(p1y, hn::Mul(s, d1y)), hn::Add(p2y, hn::Mul(t, d2y)));
  const auto gz = hn::Sub(hn::Add(p1z, hn::Mul(s, d1z)), hn::Add(p2z, hn::Mul(t, d2z)));
  return dot(gx, gy, gz, gx, gy, gz);
}

/// Runs `each(i, squared)` on every vector of the batch: the first segment's lanes set once.
template <class Each>
HWY_INLINE void ForEachVector(const Vector3r& p1, const Vector3r& q1,
                              const detail::SegmentBatch& batch, Each&& each) {
  // At most kSegmentBatchLanes lanes: the callers pad to that.
  const hn::CappedTag<Real, detail::kSegmentBatchLanes> d;
  const std::size_t lanes = hn::Lanes(d);
  const auto p1x = hn::Set(d, p1.x()), p1y = hn::Set(d, p1.y()), p1z = hn::Set(d, p1.z());
  const Vector3r d1s = q1 - p1;
  const auto d1x = hn::Set(d, d1s.x()), d1y = hn::Set(d, d1s.y()), d1z = hn::Set(d, d1s.z());
  const auto a = hn::Set(d, detail::dot3(d1s, d1s));
  for (std::size_t i = 0; i < batch.count; i += lanes)
    each(d, i, SquaredDistancesAt(d, batch, i, p1x, p1y, p1z, d1x, d1y, d1z, a));
}

void SquaredSegmentDistances(const Vector3r& p1, const Vector3r& q1,
                             const detail::SegmentBatch& batch, Real* out) {
  ForEachVector(p1, q1, batch,
                [&](auto d, std::size_t i, auto squared) { hn::StoreU(squared, d, out + i); });
}

std::size_t SegmentsWithin(const Vector3r& p1, const Vector3r& q1, Real own,
                           const detail::SegmentBatch& batch, const Real* budget, Real* squared,
                           std::uint32_t* within) {
  std::size_t found = 0;
  ForEachVector(p1, q1, batch, [&](auto d, std::size_t i, auto distance) {
    hn::StoreU(distance, d, squared + i);
    // within = own + budget, compared as within · within (own = reach + the edge's budget,
    // budget = the other's plus the allowance).
    const auto reach = hn::Add(hn::Set(d, own), hn::LoadU(d, budget + i));
    found = AppendPassing(d, hn::Lt(distance, hn::Mul(reach, reach)), i, batch.count, within,
                          found);
  });
  return found;
}

std::size_t SegmentPairsWithin(const detail::SegmentBatch& first,
                               const detail::SegmentBatch& second, const Real* within,
                               std::uint32_t* passing) {
  const hn::CappedTag<Real, detail::kSegmentBatchLanes> d;
  const std::size_t lanes = hn::Lanes(d);
  std::size_t found = 0;
  for (std::size_t i = 0; i < first.count; i += lanes) {
    // Lane k: first's segment k against second's (p1, d1 = q1 − p1 and a = d1·d1 as the
    // scalar rule computes them).
    const auto p1x = hn::LoadU(d, first.px + i), p1y = hn::LoadU(d, first.py + i),
               p1z = hn::LoadU(d, first.pz + i);
    const auto d1x = hn::Sub(hn::LoadU(d, first.qx + i), p1x),
               d1y = hn::Sub(hn::LoadU(d, first.qy + i), p1y),
               d1z = hn::Sub(hn::LoadU(d, first.qz + i), p1z);
    const auto a = hn::Add(hn::Mul(d1x, d1x), hn::Add(hn::Mul(d1y, d1y), hn::Mul(d1z, d1z)));
    const auto distance = SquaredDistancesAt(d, second, i, p1x, p1y, p1z, d1x, d1y, d1z, a);
    const auto limit = hn::LoadU(d, within + i);
    found = AppendPassing(d, hn::Lt(distance, hn::Mul(limit, limit)), i, first.count, passing,
                          found);
  }
  return found;
}

std::size_t SegmentsWithinLeaves(const Vector3r& p1, const Vector3r& q1, Real own,
                                 const detail::BlockQuery& query, const Real* leaf_data,
                                 const std::uint32_t* leaves, std::size_t leaf_count,
                                 Real* squared, Real* allowed, std::uint32_t* within) {
  const hn::CappedTag<Real, detail::kBlockLanes> d;
  const auto p1x = hn::Set(d, p1.x()), p1y = hn::Set(d, p1.y()), p1z = hn::Set(d, p1.z());
  const Vector3r d1s = q1 - p1;
  const auto d1x = hn::Set(d, d1s.x()), d1y = hn::Set(d, d1s.y()), d1z = hn::Set(d, d1s.z());
  const auto a = hn::Set(d, detail::dot3(d1s, d1s));
  return LanesWithinLeaves<6>(
      own, query, leaf_data, leaves, leaf_count, squared, allowed, within,
      [&](auto tag, const Real* base, std::size_t i) {
        const auto at = [&](std::size_t field) { return base + field * detail::kBlockLanes; };
        const detail::SegmentBatch segments{at(0), at(1), at(2), at(3), at(4), at(5),
                                            detail::kBlockLanes};
        return SquaredDistancesAt(tag, segments, i, p1x, p1y, p1z, d1x, d1y, d1z, a);
      });
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace tessera::detail {

HWY_EXPORT(SquaredSegmentDistances);
HWY_EXPORT(SegmentsWithin);
HWY_EXPORT(SegmentPairsWithin);
HWY_EXPORT(SegmentsWithinLeaves);

void squared_segment_distances(const Vector3r& p1, const Vector3r& q1, const SegmentBatch& batch,
                               Real* out) {
  HWY_DYNAMIC_DISPATCH(SquaredSegmentDistances)(p1, q1, batch, out);
}

std::size_t segments_within(const Vector3r& p1, const Vector3r& q1, Real own,
                            const SegmentBatch& batch, const Real* budget, Real* squared,
                            std::uint32_t* within) {
  return HWY_DYNAMIC_DISPATCH(SegmentsWithin)(p1, q1, own, batch, budget, squared, within);
}

std::size_t segment_pairs_within(const SegmentBatch& first, const SegmentBatch& second,
                                 const Real* within, std::uint32_t* passing) {
  return HWY_DYNAMIC_DISPATCH(SegmentPairsWithin)(first, second, within, passing);
}

std::size_t segments_within_leaves(const Vector3r& p1, const Vector3r& q1, Real own,
                                   const BlockQuery& query, const Real* leaf_data,
                                   const std::uint32_t* leaves, std::size_t leaf_count,
                                   Real* squared, Real* allowed, std::uint32_t* within) {
  return HWY_DYNAMIC_DISPATCH(SegmentsWithinLeaves)(p1, q1, own, query, leaf_data, leaves,
                                                    leaf_count, squared, allowed, within);
}

}  // namespace tessera::detail
#endif
