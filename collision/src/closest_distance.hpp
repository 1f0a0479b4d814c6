// Squared distances between the primitives of a mesh, after Ericson, Real-Time Collision
// Detection §5.1.5 (point–triangle, by Voronoi regions) and §5.1.9 (segment–segment). The
// self-contacts need only the distance (their kernels find their own closest points); the
// solid contacts also take the closest point on a face.
#pragma once

#include <algorithm>

#include <tessera/core/real.hpp>

namespace tessera::detail {

/// u·v summed as x + (y + z), written out: the batched distances (segment_distances.cpp,
/// triangle_distances.cpp) sum in this order to give these bits. (Eigen's dot() sums a float
/// 3-vector so, but pairs a double one's lanes.)
inline Real dot3(const Vector3r& u, const Vector3r& v) {
  return u.x() * v.x() + (u.y() * v.y() + u.z() * v.z());
}

/// The point of triangle (a, b, c) closest to p. (triangle_distances.cpp computes the same
/// bits a vector at a time: change both together.)
inline Vector3r closest_point_on_triangle(const Vector3r& p, const Vector3r& a, const Vector3r& b,
                                          const Vector3r& c) {
  const Vector3r ab = b - a, ac = c - a, ap = p - a;
  const Real d1 = dot3(ab, ap), d2 = dot3(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;  // vertex a
  const Vector3r bp = p - b;
  const Real d3 = dot3(ab, bp), d4 = dot3(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;  // vertex b
  const Real vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;  // edge ab
  const Vector3r cp = p - c;
  const Real d5 = dot3(ab, cp), d6 = dot3(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;  // vertex c
  const Real vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;  // edge ac
  const Real va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)  // edge bc
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  // Inside the face. A degenerate (zero-area) triangle never gets here: one of the edge or
  // vertex regions above takes every point.
  const Real denominator = va + vb + vc;
  return a + (vb / denominator) * ab + (vc / denominator) * ac;
}

inline Real squared_point_triangle_distance(const Vector3r& p, const Vector3r& a,
                                            const Vector3r& b, const Vector3r& c) {
  const Vector3r gap = p - closest_point_on_triangle(p, a, b, c);
  return dot3(gap, gap);
}

inline Real squared_segment_distance(const Vector3r& p1, const Vector3r& q1, const Vector3r& p2,
                                     const Vector3r& q2) {
  const Vector3r d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const Real a = dot3(d1, d1), e = dot3(d2, d2), f = dot3(d2, r);
  const Real tiny = kDegenerateTolerance * kDegenerateTolerance;
  Real s = 0, t = 0;
  if (a <= tiny && e <= tiny) return dot3(r, r);
  if (a <= tiny) {
    t = std::clamp(f / e, Real(0), Real(1));
  } else {
    const Real c = dot3(d1, r);
    if (e <= tiny) {
      s = std::clamp(-c / a, Real(0), Real(1));
    } else {
      const Real b = dot3(d1, d2), denominator = a * e - b * b;
      // Parallel segments (denominator 0): any s works, take 0.
      s = denominator > 0 ? std::clamp((b * f - c * e) / denominator, Real(0), Real(1)) : 0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, Real(0), Real(1));
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, Real(0), Real(1));
      }
    }
  }
  const Vector3r gap = p1 + s * d1 - (p2 + t * d2);
  return dot3(gap, gap);
}

}  // namespace tessera::detail
