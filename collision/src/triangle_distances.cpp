// Squared distances from one point to many triangles (the vertex–triangle pairs of a
// self-collision build), a vector of triangles at a time: compiled once per SIMD target
// (Highway foreach_target) and dispatched at run time. The same closest-point rule as
// closest_point_on_triangle (closest_distance.hpp; Ericson §5.1.5), by Voronoi regions:
//
//   ab = b − a, ac = c − a;  d1 = ab·(p − a), d2 = ac·(p − a), d3 = ab·(p − b), d4 = ac·(p − b),
//   d5 = ab·(p − c), d6 = ac·(p − c);  vc = d1 d4 − d3 d2, vb = d5 d2 − d1 d6, va = d3 d6 − d5 d4
//
//   region     when                                  closest point
//   vertex a   d1 ≤ 0, d2 ≤ 0                         a
//   vertex b   d3 ≥ 0, d4 ≤ d3                        b
//   edge ab    vc ≤ 0, d1 ≥ 0, d3 ≤ 0                 a + d1 / (d1 − d3) ab
//   vertex c   d6 ≥ 0, d5 ≤ d6                        c
//   edge ac    vb ≤ 0, d2 ≥ 0, d6 ≤ 0                 a + d2 / (d2 − d6) ac
//   edge bc    va ≤ 0, d4 − d3 ≥ 0, d5 − d6 ≥ 0       b + (d4 − d3) / ((d4 − d3) + (d5 − d6)) (c − b)
//   face       otherwise                             a + vb / (va + vb + vc) ab + vc / (…) ac
//
// The scalar rule takes the first region that holds; each lane computes every region's point
// with the scalar operations in their order and selects the first that holds (the others'
// divisions by zero are discarded). Without floating-point contraction (the module's flag)
// the lanes give the scalar bits on every target (tests/collision/test_self_collision.cpp).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "triangle_distances.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include "passing_lanes-inl.h"
#include "triangle_distances.hpp"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

/// The squared distances from p to the batch's triangles i .. i + lanes.
template <class D, class V = hn::Vec<D>>
HWY_INLINE V SquaredTriangleDistancesAt(D d, const detail::TriangleBatch& batch, std::size_t i,
                                        V px, V py, V pz) {
  const V zero = hn::Zero(d);
  // x + (y + z), as dot3.
  const auto dot = [](V ax, V ay, V az, V bx, V by, V bz) {
    return hn::Add(hn::Mul(ax, bx), hn::Add(hn::Mul(ay, by), hn::Mul(az, bz)));
  };
  {
    const V ax = hn::LoadU(d, batch.ax + i), ay = hn::LoadU(d, batch.ay + i),
            az = hn::LoadU(d, batch.az + i);
    const V bx = hn::LoadU(d, batch.bx + i), by = hn::LoadU(d, batch.by + i),
            bz = hn::LoadU(d, batch.bz + i);
    const V cx = hn::LoadU(d, batch.cx + i), cy = hn::LoadU(d, batch.cy + i),
            cz = hn::LoadU(d, batch.cz + i);
    const V abx = hn::Sub(bx, ax), aby = hn::Sub(by, ay), abz = hn::Sub(bz, az);
    const V acx = hn::Sub(cx, ax), acy = hn::Sub(cy, ay), acz = hn::Sub(cz, az);
    const V apx = hn::Sub(px, ax), apy = hn::Sub(py, ay), apz = hn::Sub(pz, az);
    const V d1 = dot(abx, aby, abz, apx, apy, apz), d2 = dot(acx, acy, acz, apx, apy, apz);
    const V bpx = hn::Sub(px, bx), bpy = hn::Sub(py, by), bpz = hn::Sub(pz, bz);
    const V d3 = dot(abx, aby, abz, bpx, bpy, bpz), d4 = dot(acx, acy, acz, bpx, bpy, bpz);
    const V vc = hn::Sub(hn::Mul(d1, d4), hn::Mul(d3, d2));
    const V cpx = hn::Sub(px, cx), cpy = hn::Sub(py, cy), cpz = hn::Sub(pz, cz);
    const V d5 = dot(abx, aby, abz, cpx, cpy, cpz), d6 = dot(acx, acy, acz, cpx, cpy, cpz);
    const V vb = hn::Sub(hn::Mul(d5, d2), hn::Mul(d1, d6));
    const V va = hn::Sub(hn::Mul(d3, d6), hn::Mul(d5, d4));
    const V d43 = hn::Sub(d4, d3), d56 = hn::Sub(d5, d6);
    const auto at_a = hn::And(hn::Le(d1, zero), hn::Le(d2, zero));
    const auto at_b = hn::And(hn::Ge(d3, zero), hn::Le(d4, d3));
    const auto on_ab = hn::And(hn::Le(vc, zero), hn::And(hn::Ge(d1, zero), hn::Le(d3, zero)));
    const auto at_c = hn::And(hn::Ge(d6, zero), hn::Le(d5, d6));
    const auto on_ac = hn::And(hn::Le(vb, zero), hn::And(hn::Ge(d2, zero), hn::Le(d6, zero)));
    const auto on_bc = hn::And(hn::Le(va, zero), hn::And(hn::Ge(d43, zero), hn::Ge(d56, zero)));
    // The face, then each region over it in the reverse of the scalar rule's order, so the
    // first region that holds is the one left.
    const V denominator = hn::Add(hn::Add(va, vb), vc);
    const V v = hn::Div(vb, denominator), w = hn::Div(vc, denominator);
    V qx = hn::Add(hn::Add(ax, hn::Mul(v, abx)), hn::Mul(w, acx));
    V qy = hn::Add(hn::Add(ay, hn::Mul(v, aby)), hn::Mul(w, acy));
    V qz = hn::Add(hn::Add(az, hn::Mul(v, abz)), hn::Mul(w, acz));
    const V t_bc = hn::Div(d43, hn::Add(d43, d56));
    qx = hn::IfThenElse(on_bc, hn::Add(bx, hn::Mul(t_bc, hn::Sub(cx, bx))), qx);
    qy = hn::IfThenElse(on_bc, hn::Add(by, hn::Mul(t_bc, hn::Sub(cy, by))), qy);
    qz = hn::IfThenElse(on_bc, hn::Add(bz, hn::Mul(t_bc, hn::Sub(cz, bz))), qz);
    const V t_ac = hn::Div(d2, hn::Sub(d2, d6));
    qx = hn::IfThenElse(on_ac, hn::Add(ax, hn::Mul(t_ac, acx)), qx);
    qy = hn::IfThenElse(on_ac, hn::Add(ay, hn::Mul(t_ac, acy)), qy);
    qz = hn::IfThenElse(on_ac, hn::Add(az, hn::Mul(t_ac, acz)), qz);
    qx = hn::IfThenElse(at_c, cx, qx), qy = hn::IfThenElse(at_c, cy, qy),
    qz = hn::IfThenElse(at_c, cz, qz);
    const V t_ab = hn::Div(d1, hn::Sub(d1, d3));
    qx = hn::IfThenElse(on_ab, hn::Add(ax, hn::Mul(t_ab, abx)), qx);
    qy = hn::IfThenElse(on_ab, hn::Add(ay, hn::Mul(t_ab, aby)), qy);
    qz = hn::IfThenElse(on_ab, hn::Add(az, hn::Mul(t_ab, abz)), qz);
    qx = hn::IfThenElse(at_b, bx, qx), qy = hn::IfThenElse(at_b, by, qy),
    qz = hn::IfThenElse(at_b, bz, qz);
    qx = hn::IfThenElse(at_a, ax, qx), qy = hn::IfThenElse(at_a, ay, qy),
    qz = hn::IfThenElse(at_a, az, qz);
    const V gx = hn::Sub(px, qx), gy = hn::Sub(py, qy), gz = hn::Sub(pz, qz);
    return dot(gx, gy, gz, gx, gy, gz);
  }
}

std::size_t TrianglesWithin(const Vector3r& p, Real own, const detail::TriangleBatch& batch,
                            Real* squared, std::uint32_t* within) {
  const hn::CappedTag<Real, detail::kSegmentBatchLanes> d;
  const std::size_t lanes = hn::Lanes(d);
  const auto px = hn::Set(d, p.x()), py = hn::Set(d, p.y()), pz = hn::Set(d, p.z());
  const auto reach_own = hn::Set(d, own);
  std::size_t found = 0;
  for (std::size_t i = 0; i < batch.count; i += lanes) {
    const auto distance = SquaredTriangleDistancesAt(d, batch, i, px, py, pz);
    hn::StoreU(distance, d, squared + i);
    const auto reach = hn::Add(reach_own, hn::LoadU(d, batch.budget + i));
    found = AppendPassing(d, hn::Lt(distance, hn::Mul(reach, reach)), i, batch.count, within,
                          found);
  }
  return found;
}

std::size_t TrianglesWithinLeaves(const Vector3r& p, Real own, const detail::BlockQuery& query,
                                  const Real* leaf_data, const std::uint32_t* leaves,
                                  std::size_t leaf_count, Real* squared, Real* allowed,
                                  std::uint32_t* within) {
  const hn::CappedTag<Real, detail::kBlockLanes> d;
  const auto px = hn::Set(d, p.x()), py = hn::Set(d, p.y()), pz = hn::Set(d, p.z());
  return LanesWithinLeaves<9>(
      own, query, leaf_data, leaves, leaf_count, squared, allowed, within,
      [&](auto tag, const Real* base, std::size_t i) {
        const auto at = [&](std::size_t field) { return base + field * detail::kBlockLanes; };
        const detail::TriangleBatch triangles{at(0), at(1), at(2), at(3), at(4), at(5),
                                              at(6), at(7), at(8), nullptr, detail::kBlockLanes};
        return SquaredTriangleDistancesAt(tag, triangles, i, px, py, pz);
      });
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace tessera::detail {

HWY_EXPORT(TrianglesWithin);
HWY_EXPORT(TrianglesWithinLeaves);

std::size_t triangles_within(const Vector3r& p, Real own, const TriangleBatch& batch,
                             Real* squared, std::uint32_t* within) {
  return HWY_DYNAMIC_DISPATCH(TrianglesWithin)(p, own, batch, squared, within);
}

std::size_t triangles_within_leaves(const Vector3r& p, Real own, const BlockQuery& query,
                                    const Real* leaf_data, const std::uint32_t* leaves,
                                    std::size_t leaf_count, Real* squared, Real* allowed,
                                    std::uint32_t* within) {
  return HWY_DYNAMIC_DISPATCH(TrianglesWithinLeaves)(p, own, query, leaf_data, leaves,
                                                     leaf_count, squared, allowed, within);
}

}  // namespace tessera::detail
#endif
