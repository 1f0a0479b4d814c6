// Proximity constraints C = |a - b| - d0 between the closest points a, b of two primitives:
// point–edge, point–triangle and edge–edge. Used to keep a cloth thickness, to resolve
// self-collisions and to attach points to surfaces. The closest-point parameters (edge
// parameter, barycentric coordinates) are found first and then held fixed, so each family is
// one formula: C and the gradients ±weight · n along the unit separation n.
//
// compressionStiffness applies when C < 0 (closer than d0), stretchStiffness when C ≥ 0.
#include <algorithm>
#include <array>

#include <Eigen/Geometry>

#include <tessera/core/position_based_dynamics.hpp>

#include "projection.hpp"

namespace tessera {
namespace {

constexpr Real kToleranceSquared = kDegenerateTolerance * kDegenerateTolerance;

Real clamp01(Real value) { return std::clamp(value, Real(0), Real(1)); }

/// Parameter t ∈ [0, 1] of the point of segment a + t (b - a) closest to p. A zero-length
/// segment is the point a (t = 0).
Real closest_segment_parameter(const Vector3r& p, const Vector3r& a, const Vector3r& b) {
  const Vector3r edge = b - a;
  const Real length_squared = edge.squaredNorm();
  if (!(length_squared > kToleranceSquared)) return 0;
  return clamp01((p - a).dot(edge) / length_squared);
}

/// Barycentric coordinates of the point closest to p on the three edges of triangle (a, b, c).
Vector3r closest_triangle_edge_barycentric(const Vector3r& p, const Vector3r& a,
                                           const Vector3r& b, const Vector3r& c) {
  const Real t_ab = closest_segment_parameter(p, a, b);
  const Real t_bc = closest_segment_parameter(p, b, c);
  const Real t_ca = closest_segment_parameter(p, c, a);
  const std::array<Vector3r, 3> candidates = {Vector3r(1 - t_ab, t_ab, 0),
                                              Vector3r(0, 1 - t_bc, t_bc),
                                              Vector3r(t_ca, 0, 1 - t_ca)};
  Vector3r best = candidates[0];
  Real best_distance = (p - (a * best[0] + b * best[1] + c * best[2])).squaredNorm();
  for (int k = 1; k < 3; ++k) {
    const Vector3r& bary = candidates[k];
    const Real distance = (p - (a * bary[0] + b * bary[1] + c * bary[2])).squaredNorm();
    if (distance < best_distance) {
      best_distance = distance;
      best = bary;
    }
  }
  return best;
}

/// Barycentric coordinates (b0, b1, b2) of the point of triangle (a, b, c) closest to p, by
/// the Voronoi regions of its vertices, edges and face. A triangle of zero area (or so thin
/// that its face coordinates would be mostly round-off) is treated as its three edges.
Vector3r closest_triangle_barycentric(const Vector3r& p, const Vector3r& a, const Vector3r& b,
                                      const Vector3r& c) {
  const Vector3r ab = b - a;
  const Vector3r ac = c - a;
  const Real twice_area_squared = ab.cross(ac).squaredNorm();
  if (!(twice_area_squared > kToleranceSquared) ||
      !(twice_area_squared > kDegenerateTolerance * ab.squaredNorm() * ac.squaredNorm()))
    return closest_triangle_edge_barycentric(p, a, b, c);

  const Vector3r ap = p - a;
  const Real d1 = ab.dot(ap);
  const Real d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return Vector3r(1, 0, 0);  // vertex a

  const Vector3r bp = p - b;
  const Real d3 = ab.dot(bp);
  const Real d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return Vector3r(0, 1, 0);  // vertex b

  const Real vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {  // edge ab
    const Real t = d1 / (d1 - d3);
    return Vector3r(1 - t, t, 0);
  }

  const Vector3r cp = p - c;
  const Real d5 = ab.dot(cp);
  const Real d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return Vector3r(0, 0, 1);  // vertex c

  const Real vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {  // edge ac
    const Real t = d2 / (d2 - d6);
    return Vector3r(1 - t, 0, t);
  }

  const Real va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {  // edge bc
    const Real t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return Vector3r(0, 1 - t, t);
  }

  // Face: va, vb, vc are the (scaled) barycentric coordinates of p's projection, all
  // positive unless round-off on a thin triangle says otherwise.
  if (!(va >= 0 && vb >= 0 && vc >= 0 && va + vb + vc > 0))
    return closest_triangle_edge_barycentric(p, a, b, c);
  const Real inverse_sum = 1 / (va + vb + vc);
  const Real v = vb * inverse_sum;
  const Real w = vc * inverse_sum;
  return Vector3r(1 - v - w, v, w);
}

/// Parameters (s, t) ∈ [0, 1]² of the closest points p0 + s (p1 - p0) and p2 + t (p3 - p2) of
/// two segments. Zero-length segments are points; for parallel segments one closest pair of
/// the overlap is chosen (starting from s = 0).
void closest_segment_segment_parameters(const Vector3r& p0, const Vector3r& p1,
                                        const Vector3r& p2, const Vector3r& p3, Real& s,
                                        Real& t) {
  const Vector3r d0 = p1 - p0;
  const Vector3r d1 = p3 - p2;
  const Vector3r r = p0 - p2;
  const Real a = d0.squaredNorm();
  const Real e = d1.squaredNorm();
  const Real f = d1.dot(r);
  const bool first_is_point = !(a > kToleranceSquared);
  const bool second_is_point = !(e > kToleranceSquared);
  if (first_is_point && second_is_point) {
    s = t = 0;
    return;
  }
  if (first_is_point) {
    s = 0;
    t = clamp01(f / e);
    return;
  }
  const Real c = d0.dot(r);
  if (second_is_point) {
    t = 0;
    s = clamp01(-c / a);
    return;
  }
  const Real b = d0.dot(d1);
  const Real denominator = a * e - b * b;  // a e sin² of the angle between the segments
  // Parallel (up to round-off): any s gives a closest t; start from s = 0.
  s = denominator > kDegenerateTolerance * a * e ? clamp01((b * f - c * e) / denominator)
                                                 : Real(0);
  t = (b * s + f) / e;
  if (t < 0) {
    t = 0;
    s = clamp01(-c / a);
  } else if (t > 1) {
    t = 1;
    s = clamp01((b - c) / a);
  }
}

/// Shared tail of the three families: C = |separation| - d0 with the unit separation n, the
/// gradients weight_i · n, and the stiffness chosen by the sign of C.
template <int N>
bool project_separation(const Vector3r& separation, Real rest_distance,
                        const std::array<Real, N>& gradient_weights,
                        const std::array<Real, N>& inverse_masses, Real compression_stiffness,
                        Real stretch_stiffness, Vector3r* const (&corr)[N]) {
  const Real distance = separation.norm();
  if (!(distance > kDegenerateTolerance)) {
    detail::zero_corrections<N>(corr);
    return false;
  }
  const Vector3r normal = separation / distance;
  const Real C = distance - rest_distance;
  detail::Gradients<N> grad;
  for (int i = 0; i < N; ++i) grad[i] = gradient_weights[i] * normal;
  const Real stiffness = C < 0 ? compression_stiffness : stretch_stiffness;
  return detail::project_pbd<N>(C, grad, inverse_masses, stiffness, corr);
}

}  // namespace

bool PositionBasedDynamics::solve_EdgePointDistanceConstraint(
    const Vector3r& p, Real invMass, const Vector3r& p0, Real invMass0, const Vector3r& p1,
    Real invMass1, const Real restDist, const Real compressionStiffness,
    const Real stretchStiffness, Vector3r& corr, Vector3r& corr0, Vector3r& corr1) {
  Vector3r* const corrections[3] = {&corr, &corr0, &corr1};
  const Real t = closest_segment_parameter(p, p0, p1);
  const Vector3r closest = (1 - t) * p0 + t * p1;
  return project_separation<3>(p - closest, restDist, {1, -(1 - t), -t},
                               {invMass, invMass0, invMass1}, compressionStiffness,
                               stretchStiffness, corrections);
}

bool PositionBasedDynamics::solve_TrianglePointDistanceConstraint(
    const Vector3r& p, Real invMass, const Vector3r& p0, Real invMass0, const Vector3r& p1,
    Real invMass1, const Vector3r& p2, Real invMass2, const Real restDist,
    const Real compressionStiffness, const Real stretchStiffness, Vector3r& corr,
    Vector3r& corr0, Vector3r& corr1, Vector3r& corr2) {
  Vector3r* const corrections[4] = {&corr, &corr0, &corr1, &corr2};
  const Vector3r bary = closest_triangle_barycentric(p, p0, p1, p2);
  const Vector3r closest = bary[0] * p0 + bary[1] * p1 + bary[2] * p2;
  return project_separation<4>(p - closest, restDist, {1, -bary[0], -bary[1], -bary[2]},
                               {invMass, invMass0, invMass1, invMass2}, compressionStiffness,
                               stretchStiffness, corrections);
}

bool PositionBasedDynamics::solve_EdgeEdgeDistanceConstraint(
    const Vector3r& p0, Real invMass0, const Vector3r& p1, Real invMass1, const Vector3r& p2,
    Real invMass2, const Vector3r& p3, Real invMass3, const Real restDist,
    const Real compressionStiffness, const Real stretchStiffness, Vector3r& corr0,
    Vector3r& corr1, Vector3r& corr2, Vector3r& corr3) {
  Vector3r* const corrections[4] = {&corr0, &corr1, &corr2, &corr3};
  Real s = 0, t = 0;
  closest_segment_segment_parameters(p0, p1, p2, p3, s, t);
  const Vector3r closest_first = (1 - s) * p0 + s * p1;
  const Vector3r closest_second = (1 - t) * p2 + t * p3;
  return project_separation<4>(closest_first - closest_second, restDist,
                               {1 - s, s, -(1 - t), -t},
                               {invMass0, invMass1, invMass2, invMass3}, compressionStiffness,
                               stretchStiffness, corrections);
}

}  // namespace tessera
