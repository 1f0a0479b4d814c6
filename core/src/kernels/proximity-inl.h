// The three proximity families (point–edge, point–triangle, edge–edge), each one formula over
// lanes: the scalar API (core/src/proximity.cpp) runs it on one lane, the batched kernels on
// W lanes. Why branch-free: the closest points of W constraints fall in different Voronoi
// regions, so every region's candidate is computed for all lanes and the right one selected;
// no lane's result depends on its neighbours.
//
// Each family first finds the closest-point parameters, then holds them fixed while
// differentiating (Müller et al. 2007, "Position Based Dynamics", whose point–triangle
// collision constraint these generalise; closest-point regions after Ericson 2005,
// "Real-Time Collision Detection", §5.1):
//
//   point–edge, particles (p, p0, p1):   q = (1 - t) p0 + t p1,  t ∈ [0, 1]
//       C = |p - q| - d0,  ∇_p C = n,  ∇_{p0} C = -(1 - t) n,  ∇_{p1} C = -t n
//   point–triangle, (p, p0, p1, p2):     q = b0 p0 + b1 p1 + b2 p2 (barycentric b)
//       C = |p - q| - d0,  ∇_p C = n,  ∇_{pi} C = -b_i n
//   edge–edge, (p0, p1, p2, p3):         a = (1 - s) p0 + s p1,  b = (1 - t) p2 + t p3
//       C = |a - b| - d0,  ∇_{p0} C = (1 - s) n,  ∇_{p1} C = s n,  ∇_{p2} C = -(1 - t) n,
//       ∇_{p3} C = -t n
// with n the unit separation (p - q or a - b). A lane is invalid (zero corrections) when the
// separation is shorter than kDegenerateTolerance (the primitives touch). The PBD stiffness is
// the compression stiffness where C < 0 and the stretch stiffness where C ≥ 0.
//
// Degenerate primitives, as the scalar API documents them: a zero-length segment is its first
// point (t = 0, s = 0); a triangle of zero area, or so thin that
// |(p1 - p0) × (p2 - p0)|² ≤ kDegenerateTolerance |p1 - p0|² |p2 - p0|², is measured to its
// edges, whose union is its longest edge (exactly so at zero area; within the sliver's width,
// at most sqrt(kDegenerateTolerance) times its edges, for a thin one); for parallel segments
// the closest pair starting from s = 0 is used.
#if defined(TESSERA_CORE_KERNELS_PROXIMITY_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_PROXIMITY_INL_H_
#undef TESSERA_CORE_KERNELS_PROXIMITY_INL_H_
#else
#define TESSERA_CORE_KERNELS_PROXIMITY_INL_H_
#endif

#include "projection-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

template <class V>
HWY_INLINE V clamp_unit(V x) {
  return clamp(x, zero<V>(), splat<V>(1.0));
}

template <class V>
HWY_INLINE V proximity_tolerance_squared() {
  return splat<V>(double(kDegenerateTolerance) * double(kDegenerateTolerance));
}

/// Parameter t ∈ [0, 1] of the point a + t (b - a) closest to p; 0 on a zero-length segment.
template <class V>
HWY_INLINE V closest_segment_parameter(const Vec3<V>& p, const Vec3<V>& a, const Vec3<V>& b) {
  const Vec3<V> edge = b - a;
  const V length_squared = squared_norm(edge);
  return clamp_unit(safe_divide(dot(p - a, edge), length_squared,
                                length_squared > proximity_tolerance_squared<V>()));
}

/// (1 - t) a + t b.
template <class V>
HWY_INLINE Vec3<V> point_on_segment(const Vec3<V>& a, const Vec3<V>& b, V t) {
  return a * (splat<V>(1.0) - t) + b * t;
}

/// Barycentric coordinates (b0, b1, b2) of a point of triangle (a, b, c).
template <class V>
struct TriangleBarycentric {
  V b0, b1, b2;
};

template <class V, class M>
HWY_INLINE TriangleBarycentric<V> select(const M& condition, const TriangleBarycentric<V>& x,
                                         const TriangleBarycentric<V>& y) {
  return {select(condition, x.b0, y.b0), select(condition, x.b1, y.b1),
          select(condition, x.b2, y.b2)};
}

template <class V>
HWY_INLINE Vec3<V> triangle_point_at(const TriangleBarycentric<V>& bary, const Vec3<V>& a,
                                     const Vec3<V>& b, const Vec3<V>& c) {
  return a * bary.b0 + b * bary.b1 + c * bary.b2;
}

/// The closest point to p of a triangle of zero area, which is its longest edge (the union of
/// its three edges). Why the longest edge and not the nearest of three: on a collinear
/// triangle the edges overlap, so two edges reach the same point with different barycentric
/// coordinates and a distance comparison would pick between them by round-off; the longest
/// edge gives the same point in every lane whatever the rounding (FMA or not). Equal lengths
/// go to the first of ab, bc, ca.
template <class V>
HWY_INLINE TriangleBarycentric<V> closest_triangle_hull_barycentric(const Vec3<V>& p,
                                                                    const Vec3<V>& a,
                                                                    const Vec3<V>& b,
                                                                    const Vec3<V>& c) {
  const V one = splat<V>(1.0), z = zero<V>();
  const V length_ab = squared_norm(b - a);
  const V length_bc = squared_norm(c - b);
  const V length_ca = squared_norm(a - c);
  const auto bc_longest = length_bc > length_ab;
  const auto ca_longest = length_ca > lane_max(length_ab, length_bc);
  const Vec3<V> start = select(ca_longest, c, select(bc_longest, b, a));
  const Vec3<V> end = select(ca_longest, a, select(bc_longest, c, b));
  const V t = closest_segment_parameter(p, start, end);
  TriangleBarycentric<V> result{one - t, t, z};
  result = select(bc_longest, TriangleBarycentric<V>{z, one - t, t}, result);
  return select(ca_longest, TriangleBarycentric<V>{t, z, one - t}, result);
}

/// Barycentric coordinates of the point of triangle (a, b, c) closest to p. Every Voronoi
/// region's candidate is evaluated and the first region (in the order vertex a, vertex b,
/// edge ab, vertex c, edge ac, edge bc, face) whose test holds is selected. A triangle of
/// zero area or too thin for face coordinates is measured to its longest edge; in the face
/// region, coordinates that round-off made slightly negative are clamped to 0.
template <class V>
HWY_INLINE TriangleBarycentric<V> closest_triangle_barycentric(const Vec3<V>& p, const Vec3<V>& a,
                                                               const Vec3<V>& b, const Vec3<V>& c) {
  const V one = splat<V>(1.0), z = zero<V>();
  const Vec3<V> ab = b - a;
  const Vec3<V> ac = c - a;
  const V twice_area_squared = squared_norm(cross(ab, ac));
  const auto proper = mask_and(
      twice_area_squared > proximity_tolerance_squared<V>(),
      twice_area_squared > splat<V>(kDegenerateTolerance) * squared_norm(ab) * squared_norm(ac));

  const Vec3<V> ap = p - a, bp = p - b, cp = p - c;
  const V d1 = dot(ab, ap), d2 = dot(ac, ap);
  const V d3 = dot(ab, bp), d4 = dot(ac, bp);
  const V d5 = dot(ab, cp), d6 = dot(ac, cp);
  const V va = d3 * d6 - d5 * d4;
  const V vb = d5 * d2 - d1 * d6;
  const V vc = d1 * d4 - d3 * d2;

  const auto at_a = mask_and(d1 <= z, d2 <= z);
  const auto at_b = mask_and(d3 >= z, d4 <= d3);
  const auto on_ab = mask_and(vc <= z, mask_and(d1 >= z, d3 <= z));
  const auto at_c = mask_and(d6 >= z, d5 <= d6);
  const auto on_ac = mask_and(vb <= z, mask_and(d2 >= z, d6 <= z));
  const V bc_from_b = d4 - d3, bc_from_c = d5 - d6;
  const auto on_bc = mask_and(va <= z, mask_and(bc_from_b >= z, bc_from_c >= z));

  // In each edge region the denominator is a sum of non-negative terms; it is positive
  // wherever the region is selected on a proper triangle.
  const V ab_denominator = d1 - d3;
  const V t_ab = safe_divide(d1, ab_denominator, ab_denominator > z);
  const V ac_denominator = d2 - d6;
  const V t_ac = safe_divide(d2, ac_denominator, ac_denominator > z);
  const V bc_denominator = bc_from_b + bc_from_c;
  const V t_bc = safe_divide(bc_from_b, bc_denominator, bc_denominator > z);
  // Face: va, vb, vc are the scaled barycentric coordinates of p's projection, positive
  // unless round-off says otherwise next to an edge.
  const V face_a = lane_max(va, z), face_b = lane_max(vb, z), face_c = lane_max(vc, z);
  const V sum = face_a + face_b + face_c;
  const auto face_defined = sum > z;
  const V inverse_sum = safe_divide(one, sum, face_defined);
  const V v = face_b * inverse_sum, w = face_c * inverse_sum;

  // Lowest priority first, so the first region that holds wins.
  TriangleBarycentric<V> result{one - v - w, v, w};
  result = select(on_bc, TriangleBarycentric<V>{z, one - t_bc, t_bc}, result);
  result = select(on_ac, TriangleBarycentric<V>{one - t_ac, z, t_ac}, result);
  result = select(at_c, TriangleBarycentric<V>{z, z, one}, result);
  result = select(on_ab, TriangleBarycentric<V>{one - t_ab, t_ab, z}, result);
  result = select(at_b, TriangleBarycentric<V>{z, one, z}, result);
  result = select(at_a, TriangleBarycentric<V>{one, z, z}, result);

  const auto in_face =
      mask_not(mask_or(mask_or(mask_or(at_a, at_b), mask_or(on_ab, at_c)), mask_or(on_ac, on_bc)));
  const auto use_hull = mask_or(mask_not(proper), mask_and(in_face, mask_not(face_defined)));
  return select(use_hull, closest_triangle_hull_barycentric(p, a, b, c), result);
}

/// Parameters (s, t) ∈ [0, 1]² of the closest points p0 + s (p1 - p0), p2 + t (p3 - p2).
template <class V>
HWY_INLINE void closest_segment_segment_parameters(const Vec3<V>& p0, const Vec3<V>& p1,
                                                   const Vec3<V>& p2, const Vec3<V>& p3, V& s,
                                                   V& t) {
  const V one = splat<V>(1.0), z = zero<V>();
  const Vec3<V> d0 = p1 - p0;
  const Vec3<V> d1 = p3 - p2;
  const Vec3<V> r = p0 - p2;
  const V a = squared_norm(d0);
  const V e = squared_norm(d1);
  const V f = dot(d1, r);
  const V c = dot(d0, r);
  const V b = dot(d0, d1);
  const auto first_is_segment = a > proximity_tolerance_squared<V>();
  const auto second_is_segment = e > proximity_tolerance_squared<V>();

  // Both proper: the stationary pair, s clamped, then t clamped with s re-solved. Parallel
  // segments (a e sin² below tolerance) start from s = 0.
  const V denominator = a * e - b * b;
  const auto crossing = denominator > splat<V>(kDegenerateTolerance) * a * e;
  const V s_general = clamp_unit(safe_divide(b * f - c * e, denominator, crossing));
  const V t_general = safe_divide(b * s_general + f, e, second_is_segment);
  const V s_at_t0 = clamp_unit(safe_divide(z - c, a, first_is_segment));
  const V s_at_t1 = clamp_unit(safe_divide(b - c, a, first_is_segment));
  const auto below = t_general < z;
  const auto above = t_general > one;
  s = select(below, s_at_t0, select(above, s_at_t1, s_general));
  t = select(below, z, select(above, one, t_general));

  // A point against a segment (or a point): the point's parameter is 0.
  s = select(second_is_segment, s, s_at_t0);
  t = select(second_is_segment, t, z);
  const V t_for_point = clamp_unit(safe_divide(f, e, second_is_segment));
  s = select(first_is_segment, s, z);
  t = select(first_is_segment, t, t_for_point);
}

/// C = |separation| - d0 and gradients weight_i · n along the unit separation n.
template <class V, int N>
HWY_INLINE ConstraintValue<V, N> separation_constraint(const Vec3<V>& separation, V rest_distance,
                                                       const V (&gradient_weights)[N]) {
  ConstraintValue<V, N> value;
  const V distance = norm(separation);
  value.valid = distance > splat<V>(kDegenerateTolerance);
  const Vec3<V> normal = separation * safe_divide(splat<V>(1.0), distance, value.valid);
  value.C = distance - rest_distance;
  for (int i = 0; i < N; ++i) value.gradient[i] = normal * gradient_weights[i];
  return value;
}

/// The compression stiffness where C < 0, the stretch stiffness elsewhere.
template <class V>
HWY_INLINE V proximity_stiffness(V C, V compression_stiffness, V stretch_stiffness) {
  return select(C < zero<V>(), compression_stiffness, stretch_stiffness);
}

/// Point p against segment p0-p1; particle order (p, p0, p1).
template <class V>
HWY_INLINE ConstraintValue<V, 3> edge_point_distance_constraint(const Vec3<V>& p, const Vec3<V>& p0,
                                                                const Vec3<V>& p1,
                                                                V rest_distance) {
  const V one = splat<V>(1.0), z = zero<V>();
  const V t = closest_segment_parameter(p, p0, p1);
  const V weights[3] = {one, z - (one - t), z - t};
  return separation_constraint<V, 3>(p - point_on_segment(p0, p1, t), rest_distance, weights);
}

/// Point p against triangle (p0, p1, p2); particle order (p, p0, p1, p2).
template <class V>
HWY_INLINE ConstraintValue<V, 4> triangle_point_distance_constraint(
    const Vec3<V>& p, const Vec3<V>& p0, const Vec3<V>& p1, const Vec3<V>& p2, V rest_distance) {
  const V z = zero<V>();
  const TriangleBarycentric<V> bary = closest_triangle_barycentric(p, p0, p1, p2);
  const V weights[4] = {splat<V>(1.0), z - bary.b0, z - bary.b1, z - bary.b2};
  return separation_constraint<V, 4>(p - triangle_point_at(bary, p0, p1, p2), rest_distance,
                                     weights);
}

/// Segment p0-p1 against segment p2-p3; particle order (p0, p1, p2, p3).
template <class V>
HWY_INLINE ConstraintValue<V, 4> edge_edge_distance_constraint(const Vec3<V>& p0, const Vec3<V>& p1,
                                                               const Vec3<V>& p2, const Vec3<V>& p3,
                                                               V rest_distance) {
  const V one = splat<V>(1.0), z = zero<V>();
  V s, t;
  closest_segment_segment_parameters(p0, p1, p2, p3, s, t);
  const V weights[4] = {one - s, s, z - (one - t), z - t};
  return separation_constraint<V, 4>(point_on_segment(p0, p1, s) - point_on_segment(p2, p3, t),
                                     rest_distance, weights);
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_PROXIMITY_INL_H_
