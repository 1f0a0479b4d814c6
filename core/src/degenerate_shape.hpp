// Scale-free tests for degenerate rest shapes: an area or a volume counts as zero when it is
// below kDegenerateTolerance times the square or the cube of the shape's longest edge, so a
// millimetre mesh is judged like a metre one (an absolute threshold rejected every triangle
// of a 1 m cloth finer than ~1000 × 1000, and every tetrahedron of a 1 cm grid).
#ifndef TESSERA_CORE_SRC_DEGENERATE_SHAPE_HPP_
#define TESSERA_CORE_SRC_DEGENERATE_SHAPE_HPP_

#include <algorithm>
#include <initializer_list>

#include <tessera/core/real.hpp>

namespace tessera::detail {

inline Real longest_edge(std::initializer_list<Vector3r> points) {
  Real longest = 0;
  for (auto a = points.begin(); a != points.end(); ++a)
    for (auto b = a + 1; b != points.end(); ++b) longest = std::max(longest, (*a - *b).norm());
  return longest;
}

/// True when a triangle with |cross product| = twice_area is flat for its longest edge.
inline bool flat_triangle(Real twice_area, Real longest) {
  return !(twice_area > kDegenerateTolerance * longest * longest);
}

/// True when a tetrahedron with |det| = six_volume is flat for its longest edge.
inline bool flat_tetrahedron(Real six_volume, Real longest) {
  return !(six_volume > kDegenerateTolerance * longest * longest * longest);
}

}  // namespace tessera::detail

#endif  // TESSERA_CORE_SRC_DEGENERATE_SHAPE_HPP_
