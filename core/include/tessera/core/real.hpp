// Real, the fixed-size Eigen types of the kernel API, and the tolerances kernels use to
// recognise degenerate configurations.
//
// Real is float by default and double when Tessera is built with -DTESSERA_DOUBLE=ON
// (see tessera/core/config.hpp). The fixed-size types are unaligned (Eigen::DontAlign) so an
// embedder can keep them in any struct or container without alignment rules.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products and rotations on Vector3r, for every user
#include <limits>
#include <type_traits>

#include <tessera/core/config.hpp>

namespace tessera {

#if TESSERA_DOUBLE_PRECISION
using Real = double;
#else
using Real = float;
#endif

using Vector2r = Eigen::Matrix<Real, 2, 1, Eigen::DontAlign>;
using Vector3r = Eigen::Matrix<Real, 3, 1, Eigen::DontAlign>;
using Vector4r = Eigen::Matrix<Real, 4, 1, Eigen::DontAlign>;
using Matrix2r = Eigen::Matrix<Real, 2, 2, Eigen::DontAlign>;
using Matrix3r = Eigen::Matrix<Real, 3, 3, Eigen::DontAlign>;
using Matrix4r = Eigen::Matrix<Real, 4, 4, Eigen::DontAlign>;

/// Below this, a length, area or volume measure (or a sum of squared gradient norms) counts
/// as zero and the kernel reports a degenerate configuration instead of dividing by it.
/// Kernels compare squared quantities against its square where that avoids a sqrt.
inline constexpr Real kDegenerateTolerance =
    std::is_same_v<Real, float> ? Real(1e-6) : Real(1e-12);

/// True when this build's Real is double.
inline constexpr bool kDoublePrecision = std::is_same_v<Real, double>;

}  // namespace tessera
