// Triangle–triangle intersection by orientation signs, and the count over a mesh (the
// reasoning is in self_intersections.hpp). Every predicate returns -1, 0 or +1; 0 where the
// floating-point value is within Shewchuk's error bound of zero (the sign is unknown).
#include <tessera/collision/self_intersections.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <tessera/collision/spatial_hash.hpp>
#include <tessera/core/error.hpp>

namespace tessera {

namespace {

using Point = Eigen::Vector3d;
using Point2 = Eigen::Vector2d;

constexpr double kEpsilon = std::numeric_limits<double>::epsilon() / 2;  // 2^-53
// Shewchuk, "Adaptive precision floating-point arithmetic and fast robust geometric
// predicates" (1997): the first-stage error bounds of orient2d and orient3d.
constexpr double kOrient2dBound = (3.0 + 16.0 * kEpsilon) * kEpsilon;
constexpr double kOrient3dBound = (7.0 + 56.0 * kEpsilon) * kEpsilon;

int sign_within(double value, double bound) {
  if (value > bound) return 1;
  if (value < -bound) return -1;
  return 0;
}

/// Sign of det[a − d, b − d, c − d]: which side of plane (a, b, c) d lies on.
int orient3d(const Point& a, const Point& b, const Point& c, const Point& d) {
  const Point ad = a - d, bd = b - d, cd = c - d;
  const double bc_yz = bd.y() * cd.z(), cb_yz = cd.y() * bd.z();
  const double ca_yz = cd.y() * ad.z(), ac_yz = ad.y() * cd.z();
  const double ab_yz = ad.y() * bd.z(), ba_yz = bd.y() * ad.z();
  const double det = ad.x() * (bc_yz - cb_yz) + bd.x() * (ca_yz - ac_yz) +
                     cd.x() * (ab_yz - ba_yz);
  const double permanent = (std::abs(bc_yz) + std::abs(cb_yz)) * std::abs(ad.x()) +
                           (std::abs(ca_yz) + std::abs(ac_yz)) * std::abs(bd.x()) +
                           (std::abs(ab_yz) + std::abs(ba_yz)) * std::abs(cd.x());
  return sign_within(det, kOrient3dBound * permanent);
}

int orient2d(const Point2& a, const Point2& b, const Point2& c) {
  const double left = (a.x() - c.x()) * (b.y() - c.y());
  const double right = (a.y() - c.y()) * (b.x() - c.x());
  return sign_within(left - right, kOrient2dBound * (std::abs(left) + std::abs(right)));
}

/// p lies in the bounding box of segment (a, b): with p on their line, on the segment.
bool within_box(const Point2& p, const Point2& a, const Point2& b) {
  return std::min(a.x(), b.x()) <= p.x() && p.x() <= std::max(a.x(), b.x()) &&
         std::min(a.y(), b.y()) <= p.y() && p.y() <= std::max(a.y(), b.y());
}

bool segments_meet_2d(const Point2& p, const Point2& q, const Point2& r, const Point2& s) {
  const int d1 = orient2d(r, s, p), d2 = orient2d(r, s, q);
  const int d3 = orient2d(p, q, r), d4 = orient2d(p, q, s);
  if (d1 * d2 < 0 && d3 * d4 < 0) return true;
  return (d1 == 0 && within_box(p, r, s)) || (d2 == 0 && within_box(q, r, s)) ||
         (d3 == 0 && within_box(r, p, q)) || (d4 == 0 && within_box(s, p, q));
}

/// p inside or on the boundary of a non-degenerate triangle.
bool point_in_triangle_2d(const Point2& p, const std::array<Point2, 3>& t) {
  const int s0 = orient2d(t[0], t[1], p), s1 = orient2d(t[1], t[2], p),
            s2 = orient2d(t[2], t[0], p);
  return (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0);
}

/// Drops the axis along which the plane of `t` is steepest: the projection keeps incidence
/// within that plane and is the best conditioned of the three.
int dropped_axis(const std::array<Point, 3>& t) {
  const Point normal = (t[1] - t[0]).cross(t[2] - t[0]).cwiseAbs();
  if (normal.x() >= normal.y() && normal.x() >= normal.z()) return 0;
  return normal.y() >= normal.z() ? 1 : 2;
}

Point2 project(const Point& p, int dropped) {
  return dropped == 0 ? Point2(p.y(), p.z())
                      : (dropped == 1 ? Point2(p.z(), p.x()) : Point2(p.x(), p.y()));
}

std::array<Point2, 3> project(const std::array<Point, 3>& t, int dropped) {
  return {project(t[0], dropped), project(t[1], dropped), project(t[2], dropped)};
}

/// Corners on one line: collinear in all three coordinate projections.
bool degenerate(const std::array<Point, 3>& t) {
  for (int dropped = 0; dropped < 3; ++dropped) {
    const auto p = project(t, dropped);
    if (orient2d(p[0], p[1], p[2]) != 0) return false;
  }
  return true;
}

/// Segment (p, q) against a non-degenerate triangle: through its plane and inside its edges.
bool segment_meets_triangle(const Point& p, const Point& q, const std::array<Point, 3>& t) {
  const int sp = orient3d(t[0], t[1], t[2], p), sq = orient3d(t[0], t[1], t[2], q);
  if (sp * sq > 0) return false;
  if (sp == 0 && sq == 0) {  // the segment lies in the plane
    const int dropped = dropped_axis(t);
    const auto t2 = project(t, dropped);
    const Point2 p2 = project(p, dropped), q2 = project(q, dropped);
    return point_in_triangle_2d(p2, t2) || segments_meet_2d(p2, q2, t2[0], t2[1]) ||
           segments_meet_2d(p2, q2, t2[1], t2[2]) || segments_meet_2d(p2, q2, t2[2], t2[0]);
  }
  // The line (p, q) passes through the triangle where the three edge volumes agree.
  const int o0 = orient3d(p, q, t[0], t[1]), o1 = orient3d(p, q, t[1], t[2]),
            o2 = orient3d(p, q, t[2], t[0]);
  return (o0 >= 0 && o1 >= 0 && o2 >= 0) || (o0 <= 0 && o1 <= 0 && o2 <= 0);
}

double squared_segment_gap(const Point& p1, const Point& q1, const Point& p2, const Point& q2) {
  const Point d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (a == 0 && e == 0) return r.squaredNorm();
  if (a == 0) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e == 0) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denominator = a * e - b * b;
      s = denominator > 0 ? std::clamp((b * f - c * e) / denominator, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) t = 0, s = std::clamp(-c / a, 0.0, 1.0);
      else if (t > 1) t = 1, s = std::clamp((b - c) / a, 0.0, 1.0);
    }
  }
  return (p1 + s * d1 - (p2 + t * d2)).squaredNorm();
}

bool intersect(const std::array<Point, 3>& a, const std::array<Point, 3>& b) {
  const bool a_flat = degenerate(a), b_flat = degenerate(b);
  if (a_flat && b_flat) {
    // Two segments (or points) in space: rare enough for the plain distance, in double.
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (squared_segment_gap(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]) == 0) return true;
    return false;
  }
  if (a_flat || b_flat) {  // a degenerate triangle is the union of its edges
    const auto& segment = a_flat ? a : b;
    const auto& triangle = a_flat ? b : a;
    for (int i = 0; i < 3; ++i)
      if (segment_meets_triangle(segment[i], segment[(i + 1) % 3], triangle)) return true;
    return false;
  }
  int b_side[3], a_side[3];
  for (int i = 0; i < 3; ++i) b_side[i] = orient3d(a[0], a[1], a[2], b[i]);
  if (b_side[0] == b_side[1] && b_side[1] == b_side[2] && b_side[0] != 0) return false;
  for (int i = 0; i < 3; ++i) a_side[i] = orient3d(b[0], b[1], b[2], a[i]);
  if (a_side[0] == a_side[1] && a_side[1] == a_side[2] && a_side[0] != 0) return false;
  if (b_side[0] == 0 && b_side[1] == 0 && b_side[2] == 0) {  // coplanar
    const int dropped = dropped_axis(a);
    const auto a2 = project(a, dropped), b2 = project(b, dropped);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (segments_meet_2d(a2[i], a2[(i + 1) % 3], b2[j], b2[(j + 1) % 3])) return true;
    return point_in_triangle_2d(a2[0], b2) || point_in_triangle_2d(b2[0], a2);
  }
  for (int i = 0; i < 3; ++i)
    if (segment_meets_triangle(a[i], a[(i + 1) % 3], b) ||
        segment_meets_triangle(b[i], b[(i + 1) % 3], a))
      return true;
  return false;
}

}  // namespace

bool triangles_intersect(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1,
                         const Eigen::Vector3d& a2, const Eigen::Vector3d& b0,
                         const Eigen::Vector3d& b1, const Eigen::Vector3d& b2) {
  return intersect({a0, a1, a2}, {b0, b1, b2});
}

std::size_t count_self_intersections(std::span<const Vector3r> positions,
                                     std::span<const std::uint32_t> triangles) {
  if (triangles.size() % 3 != 0)
    throw InvalidInput("count_self_intersections: " + std::to_string(triangles.size()) +
                       " triangle indices are not a multiple of 3");
  for (std::size_t k = 0; k < triangles.size(); ++k)
    if (triangles[k] >= positions.size())
      throw InvalidInput("count_self_intersections: triangle " + std::to_string(k / 3) +
                         " names particle " + std::to_string(triangles[k]) + " of " +
                         std::to_string(positions.size()));
  const std::size_t n = triangles.size() / 3;
  std::vector<Aabb> boxes(n);
  for (std::size_t t = 0; t < n; ++t) {
    const Vector3r& p0 = positions[triangles[3 * t]];
    const Vector3r lo = p0.cwiseMin(positions[triangles[3 * t + 1]])
                            .cwiseMin(positions[triangles[3 * t + 2]]);
    const Vector3r hi = p0.cwiseMax(positions[triangles[3 * t + 1]])
                            .cwiseMax(positions[triangles[3 * t + 2]]);
    boxes[t] = {{lo.x(), lo.y(), lo.z()}, {hi.x(), hi.y(), hi.z()}};
  }
  UniformGrid grid;
  grid.build(boxes);
  const auto corners = [&](std::size_t t) {
    return std::array<Point, 3>{positions[triangles[3 * t]].cast<double>(),
                                positions[triangles[3 * t + 1]].cast<double>(),
                                positions[triangles[3 * t + 2]].cast<double>()};
  };
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, 512), std::size_t(0),
      [&](const tbb::blocked_range<std::size_t>& range, std::size_t count) {
        for (std::size_t t = range.begin(); t != range.end(); ++t) {
          const std::uint32_t* v = triangles.data() + 3 * t;
          const auto a = corners(t);
          grid.for_each_overlap_above(boxes[t], std::uint32_t(t), [&](std::uint32_t u) {
            const std::uint32_t* w = triangles.data() + 3 * std::size_t(u);
            for (int i = 0; i < 3; ++i)
              for (int j = 0; j < 3; ++j)
                if (v[i] == w[j]) return;  // adjacent: they share a corner by construction
            if (intersect(a, corners(u))) ++count;
          });
        }
        return count;
      },
      std::plus<>());
}

}  // namespace tessera
