// Per-constraint residuals (see constraint_residual.hpp for each family's measure).
//
// "One formula per family": wherever a family's lane formula gives C, the residual evaluates
// that formula on one lane (V = Real), exactly as the scalar API does (the kernels are
// included without foreach_target, for the single static target), and only normalises the
// result. The Green strain norm of the four strain/FEM families has no lane formula of its
// own; it is built from the kernels' deformation gradient and, for tetrahedra, the FEM
// kernel's strain ε.
#include <tessera/core/constraint_residual.hpp>

#include <cmath>

#include "kernels/dihedral-inl.h"
#include "kernels/distance-inl.h"
#include "kernels/fem-inl.h"
#include "kernels/isometric_bending-inl.h"
#include "kernels/particle_tet_contact-inl.h"
#include "kernels/proximity-inl.h"
#include "kernels/shape_matching-inl.h"
#include "kernels/strain-inl.h"
#include "kernels/volume-inl.h"

namespace tessera {
namespace {

namespace lanes = HWY_NAMESPACE;
using Point = lanes::Vec3<Real>;

Point position_of(const ParticleArrays& particles, ParticleIndex i) {
  return {particles.x[i], particles.y[i], particles.z[i]};
}

/// The positions of constraint c's N particles, slot by slot.
template <int N>
void gather(const ParticleArrays& particles, const ConstraintParticles<N>& indices,
            std::size_t c, Point (&p)[N]) {
  for (std::size_t k = 0; k < std::size_t(N); ++k)
    p[k] = position_of(particles, indices.particle[k][c]);
}

/// |C| / |reference|, or |C| where the reference is zero.
Real relative(Real C, Real reference) {
  const Real scale = std::abs(reference);
  return scale > 0 ? std::abs(C) / scale : std::abs(C);
}

/// The Dim×Dim inverse rest matrix m[k][j] = invRestMat(k, j), stored in rest_inverse[Dim k + j].
template <int Dim, std::size_t Entries>
void rest_inverse_of(const std::array<AlignedVector<Real>, Entries>& rest_inverse,
                     std::size_t c, Real (&m)[Dim][Dim]) {
  static_assert(Entries == std::size_t(Dim * Dim));
  for (int k = 0; k < Dim; ++k)
    for (int j = 0; j < Dim; ++j) m[k][j] = rest_inverse[std::size_t(Dim * k + j)][c];
}

/// ‖½ (FᵀF − I)‖_F of a triangle's F = [f0, f1] (3×2): the entries as the FEM triangle
/// kernel forms them (ε_xx, ε_yy, ε_xy), the off-diagonal one counted twice.
Real triangle_green_strain_norm(const Point (&p)[3], const Real (&m)[2][2]) {
  const Point edge[2] = {p[1] - p[0], p[2] - p[0]};
  const Point f0 = lanes::strain_column<2>(edge, m, 0);
  const Point f1 = lanes::strain_column<2>(edge, m, 1);
  const Real strain_xx = Real(0.5) * (lanes::dot(f0, f0) - 1);
  const Real strain_yy = Real(0.5) * (lanes::dot(f1, f1) - 1);
  const Real strain_xy = Real(0.5) * lanes::dot(f0, f1);
  return std::sqrt(strain_xx * strain_xx + strain_yy * strain_yy +
                   2 * strain_xy * strain_xy);
}

/// ‖ε‖_F of a tetrahedron, F = [p1 − p0, p2 − p0, p3 − p0] · M and ε = ½ (FᵀF − I) as the
/// FEM tetrahedron kernel computes them (its St. Venant–Kirchhoff evaluation with no
/// material: only the strain is used).
Real tetra_green_strain_norm(const Point (&p)[4], const Real (&m)[3][3]) {
  lanes::Mat3<Real> rest_inverse;
  for (int j = 0; j < 3; ++j) rest_inverse.col[j] = {m[0][j], m[1][j], m[2][j]};
  const lanes::Mat3<Real> F = lanes::deformation_gradient(p, rest_inverse);
  const lanes::Mat3<Real> strain = lanes::green_strain_material<Real>(F, 0, 0, 0).strain;
  return std::sqrt(lanes::double_contraction(strain, strain));
}

}  // namespace

Real constraint_residual(const ParticleArrays& particles, const DistanceConstraints& batch,
                         std::size_t c) {
  Point p[2];
  gather(particles, batch.particles, c, p);
  const Real rest_length = batch.rest_length[c];
  return relative(lanes::distance_constraint<Real>(p[0], p[1], rest_length).C, rest_length);
}

Real constraint_residual(const ParticleArrays& particles, const DihedralConstraints& batch,
                         std::size_t c) {
  Point p[4];
  gather(particles, batch.particles, c, p);
  return std::abs(lanes::dihedral_constraint<Real>(p[0], p[1], p[2], p[3], batch.rest_angle[c]).C);
}

Real constraint_residual(const ParticleArrays& particles, const VolumeConstraints& batch,
                         std::size_t c) {
  Point p[4];
  gather(particles, batch.particles, c, p);
  const Real rest_volume = batch.rest_volume[c];
  return relative(lanes::volume_constraint<Real>(p[0], p[1], p[2], p[3], rest_volume).C,
                  rest_volume);
}

Real constraint_residual(const ParticleArrays& particles,
                         const IsometricBendingConstraints& batch, std::size_t c) {
  Point p[4];
  gather(particles, batch.particles, c, p);
  const Real k[4] = {batch.factor[0][c], batch.factor[1][c], batch.factor[2][c],
                     batch.factor[3][c]};
  // C = ½ |u|² ≥ 0, so |u| = sqrt(2C).
  return std::sqrt(2 * lanes::isometric_bending_constraint<Real>(p, k).C);
}

Real constraint_residual(const ParticleArrays& particles,
                         const EdgePointDistanceConstraints& batch, std::size_t c) {
  Point p[3];
  gather(particles, batch.particles, c, p);
  const Real rest = batch.rest_distance[c];
  return relative(lanes::edge_point_distance_constraint<Real>(p[0], p[1], p[2], rest).C, rest);
}

Real constraint_residual(const ParticleArrays& particles,
                         const TrianglePointDistanceConstraints& batch, std::size_t c) {
  Point p[4];
  gather(particles, batch.particles, c, p);
  const Real rest = batch.rest_distance[c];
  return relative(
      lanes::triangle_point_distance_constraint<Real>(p[0], p[1], p[2], p[3], rest).C, rest);
}

Real constraint_residual(const ParticleArrays& particles,
                         const EdgeEdgeDistanceConstraints& batch, std::size_t c) {
  Point p[4];
  gather(particles, batch.particles, c, p);
  const Real rest = batch.rest_distance[c];
  return relative(lanes::edge_edge_distance_constraint<Real>(p[0], p[1], p[2], p[3], rest).C,
                  rest);
}

Real constraint_residual(const ParticleArrays& particles,
                         const StrainTriangleConstraints& batch, std::size_t c) {
  Point p[3];
  gather(particles, batch.particles, c, p);
  Real m[2][2];
  rest_inverse_of<2>(batch.rest_inverse, c, m);
  return triangle_green_strain_norm(p, m);
}

Real constraint_residual(const ParticleArrays& particles, const StrainTetraConstraints& batch,
                         std::size_t c) {
  Point p[4];
  gather(particles, batch.particles, c, p);
  Real m[3][3];
  rest_inverse_of<3>(batch.rest_inverse, c, m);
  return tetra_green_strain_norm(p, m);
}

Real constraint_residual(const ParticleArrays& particles, const FEMTriangleConstraints& batch,
                         std::size_t c) {
  Point p[3];
  gather(particles, batch.particles, c, p);
  Real m[2][2];
  rest_inverse_of<2>(batch.rest_inverse, c, m);
  return triangle_green_strain_norm(p, m);
}

Real constraint_residual(const ParticleArrays& particles, const FEMTetraConstraints& batch,
                         std::size_t c) {
  Point p[4];
  gather(particles, batch.particles, c, p);
  Real m[3][3];
  rest_inverse_of<3>(batch.rest_inverse, c, m);
  return tetra_green_strain_norm(p, m);
}

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

Real constraint_residual(const ParticleArrays& particles, const ParticleTetContacts& batch,
                         std::size_t c) {
  Point p[5];
  gather(particles, batch.particles, c, p);
  const Point tet[4] = {p[1], p[2], p[3], p[4]};
  const Point bary = {batch.barycentric[0][c], batch.barycentric[1][c], batch.barycentric[2][c]};
  const Point normal = {batch.normal[0][c], batch.normal[1][c], batch.normal[2][c]};
  // The kernel forms C inside its position solve only. From λ = 0 with a unit effective mass
  // that solve accumulates λ' = max(0 − C · 1, 0) = max(0, −C), the penetration depth, and
  // with zero inverse masses its corrections (discarded here) are zero.
  const Real no_mass[4] = {0, 0, 0, 0};
  Real penetration = 0;
  lanes::contact_position_solve<Real>(0, no_mass, p[0], tet, bary, normal, 1, penetration);
  return penetration;
}

}  // namespace tessera
