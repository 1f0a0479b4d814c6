// The number of self-intersections of a triangle mesh: pairs of triangles that share no
// vertex and meet. The run summary reports it; a drape that ends above 0 has cloth passing
// through itself, which no contact will undo (the distance kernels are unsigned).
//
//   T1 ╲    ╱            non-coplanar: T1 and T2 meet iff an edge of one meets the other
//   ────╳──╱── T2                      (the ends of T1 ∩ T2 lie on their edges)
//        ╲╱              coplanar:     an edge of one crosses an edge of the other in the
//                                      plane, or a corner of one lies inside the other
//
// Why orientation signs (Guigue–Devillers style) and not Möller's interval test: every
// decision is the sign of a 3×3 (or 2×2) determinant of coordinate differences, computed in
// double with Shewchuk's static error bound. A sign the bound cannot certify counts as 0,
// and 0 counts as touching: the count can only err towards reporting an intersection, never
// towards missing one, so a drape counted at 0 is clean.
//
// Only pairs whose boxes overlap are tested (the grid of spatial_hash.hpp): O(n) on a cloth, not O(n²).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include <Eigen/Core>

#include <tessera/core/real.hpp>

namespace tessera {

/// Pairs of triangles (three indices each into `positions`) that share no vertex and
/// intersect or touch. Parallel (TBB). Throws InvalidInput for an index out of range or an
/// index count that is not a multiple of 3.
std::size_t count_self_intersections(std::span<const Vector3r> positions,
                                     std::span<const std::uint32_t> triangles);

/// Whether triangles (a0, a1, a2) and (b0, b1, b2) intersect or touch (see above). Degenerate
/// triangles (collinear corners) are handled as the segments they are.
bool triangles_intersect(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1,
                         const Eigen::Vector3d& a2, const Eigen::Vector3d& b0,
                         const Eigen::Vector3d& b1, const Eigen::Vector3d& b2);

}  // namespace tessera
