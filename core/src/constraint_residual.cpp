// Per-constraint residuals (see constraint_residual.hpp for each family's measure).
//
// One formula per family: the one-constraint function is the batched one
// (constraint_residuals.cpp, the family's lane formula on SIMD lanes) over [c, c + 1), so the
// two cannot drift apart. Shape matching, whose clusters do not fit lanes, is evaluated here
// one cluster at a time, with the kernel's own centre, A_pq and rotation on one lane.
#include <tessera/core/constraint_residual.hpp>

#include <cmath>

#include "kernels/shape_matching-inl.h"

namespace tessera {
namespace {

namespace lanes = HWY_NAMESPACE;
using Point = lanes::Vec3<Real>;

Point position_of(const ParticleArrays& particles, ParticleIndex i) {
  return {particles.x[i], particles.y[i], particles.z[i]};
}

template <class Batch>
Real one_constraint(const ParticleArrays& particles, const Batch& batch, std::size_t c) {
  Real residual = 0;
  constraint_residuals(particles, batch, c, c + 1, &residual);
  return residual;
}

}  // namespace

#define TESSERA_ONE_CONSTRAINT_RESIDUAL(Batch)                                              \
  Real constraint_residual(const ParticleArrays& particles, const Batch& batch,            \
                           std::size_t c) {                                                \
    return one_constraint(particles, batch, c);                                             \
  }
TESSERA_ONE_CONSTRAINT_RESIDUAL(DistanceConstraints)
TESSERA_ONE_CONSTRAINT_RESIDUAL(DihedralConstraints)
TESSERA_ONE_CONSTRAINT_RESIDUAL(VolumeConstraints)
TESSERA_ONE_CONSTRAINT_RESIDUAL(IsometricBendingConstraints)
TESSERA_ONE_CONSTRAINT_RESIDUAL(EdgePointDistanceConstraints)
TESSERA_ONE_CONSTRAINT_RESIDUAL(TrianglePointDistanceConstraints)
TESSERA_ONE_CONSTRAINT_RESIDUAL(EdgeEdgeDistanceConstraints)
TESSERA_ONE_CONSTRAINT_RESIDUAL(StrainTriangleConstraints)
TESSERA_ONE_CONSTRAINT_RESIDUAL(StrainTetraConstraints)
TESSERA_ONE_CONSTRAINT_RESIDUAL(FEMTriangleConstraints)
TESSERA_ONE_CONSTRAINT_RESIDUAL(FEMTetraConstraints)
TESSERA_ONE_CONSTRAINT_RESIDUAL(ParticleTetContacts)
#undef TESSERA_ONE_CONSTRAINT_RESIDUAL

Real constraint_residual(const ParticleArrays& particles, const ShapeMatchingConstraints& batch,
                         std::size_t c) {
  const std::size_t first = batch.offsets[c], last = batch.offsets[c + 1];
  if (last <= first) return 0;
  const auto rest_offset = [&](std::size_t e) -> Point {
    return {batch.rest_offset[0][e], batch.rest_offset[1][e], batch.rest_offset[2][e]};
  };
  // The centre and A_pq = Σ m (x − c) qᵀ as the kernel forms them.
  Real total_mass = 0;
  Point weighted = Point::zeros();
  for (std::size_t e = first; e < last; ++e) {
    total_mass += batch.mass[e];
    weighted += position_of(particles, batch.particle[e]) * batch.mass[e];
  }
  const Point centre = weighted * lanes::safe_divide(Real(1), total_mass, total_mass > 0);
  lanes::Mat3<Real> a_pq = lanes::Mat3<Real>::zeros();
  for (std::size_t e = first; e < last; ++e) {
    const Point weighted_offset =
        (position_of(particles, batch.particle[e]) - centre) * batch.mass[e];
    const Point q = rest_offset(e);
    a_pq.col[0] += weighted_offset * q.x;
    a_pq.col[1] += weighted_offset * q.y;
    a_pq.col[2] += weighted_offset * q.z;
  }
  lanes::Mat3<Real> transform;
  if (batch.allow_stretch) {
    lanes::Mat3<Real> inverse_a_qq;
    for (std::size_t j = 0; j < 3; ++j)
      inverse_a_qq.col[j] = {batch.inverse_rest_moment[3 * j][c],
                             batch.inverse_rest_moment[3 * j + 1][c],
                             batch.inverse_rest_moment[3 * j + 2][c]};
    transform = lanes::shape_matching_linear(a_pq, inverse_a_qq).T;
  } else {
    // Used also where the kernel would call the rotation undetermined (rank A_pq < 2): it is
    // a proper rotation either way, so the measure stays finite and meaningful.
    transform = lanes::shape_matching_rotation(a_pq).T;
  }
  Real goal_distance_squared = 0, rest_offset_squared = 0;
  for (std::size_t e = first; e < last; ++e) {
    const Point q = rest_offset(e);
    const Point to_goal = lanes::shape_matching_correction(
        transform, q, centre, position_of(particles, batch.particle[e]), Real(1));
    goal_distance_squared += lanes::squared_norm(to_goal);
    rest_offset_squared += lanes::squared_norm(q);
  }
  // RMS over RMS: the 1/n of both means cancels.
  if (!(rest_offset_squared > 0)) return 0;
  return std::sqrt(goal_distance_squared / rest_offset_squared);
}

}  // namespace tessera
