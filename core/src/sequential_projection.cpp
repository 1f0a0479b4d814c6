// The sequential reference solver loop (see sequential_projection.hpp): for each constraint of
// [begin, end) in order, copy its particles out of the SoA arrays, call the scalar API on the
// batch's stored parameters, add the corrections to the movable particles, go on.
//
// What: one small driver (project_in_order) shared by every fixed-size family, which gathers,
// calls the family's solve lambda and applies; shape matching (clusters of any size) and the
// contacts (their own argument shapes) have their own loops. Why this shape: each family's
// overload is then only its mapping from batch arrays to scalar-API arguments, which is the
// part that has to match the batched kernel; no heap allocation per constraint (shape
// matching uses one buffer per call).
#include <tessera/core/sequential_projection.hpp>

#include <array>
#include <string>
#include <vector>

#include <tessera/core/error.hpp>
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/xpbd.hpp>

namespace tessera {
namespace {

/// The particles of one constraint, copied out of the SoA arrays.
template <int N>
struct ConstraintStencil {
  ParticleIndex index[N];
  Vector3r position[N];
  Real inverse_mass[N];
};

Vector3r position_of(const ParticleArrays& particles, ParticleIndex i) {
  return Vector3r(particles.x[i], particles.y[i], particles.z[i]);
}

/// Adds a correction to particle i when it is movable; a static particle is never written.
void add_correction(const ParticleArrays& particles, ParticleIndex i, Real inverse_mass,
                    const Vector3r& correction) {
  if (!(inverse_mass > 0)) return;
  particles.x[i] += correction.x();
  particles.y[i] += correction.y();
  particles.z[i] += correction.z();
}

template <int N>
ConstraintStencil<N> gather_stencil(const ParticleArrays& particles,
                                    const ConstraintParticles<N>& slots, std::size_t c) {
  ConstraintStencil<N> stencil;
  for (int k = 0; k < N; ++k) {
    const ParticleIndex i = slots.particle[std::size_t(k)][c];
    stencil.index[k] = i;
    stencil.position[k] = position_of(particles, i);
    stencil.inverse_mass[k] = particles.inverse_mass[i];
  }
  return stencil;
}

/// The loop itself: solve(c, stencil, corr) calls the scalar API on constraint c and writes
/// its N corrections, which are applied before constraint c + 1 is gathered.
template <int N, class Solve>
void project_in_order(const ParticleArrays& particles, const ConstraintParticles<N>& slots,
                      std::size_t begin, std::size_t end, Solve&& solve) {
  for (std::size_t c = begin; c < end; ++c) {
    const ConstraintStencil<N> s = gather_stencil<N>(particles, slots, c);
    Vector3r corr[N];
    solve(c, s, corr);
    for (int k = 0; k < N; ++k) add_correction(particles, s.index[k], s.inverse_mass[k], corr[k]);
  }
}

bool uses_compliance(const ProjectionSettings& settings) {
  return settings.semantics == ConstraintSemantics::compliance;
}

/// invRestMat(k, j) from rest_inverse[Dim k + j] (the layout of the strain and FEM batches).
template <int Dim, std::size_t Entries>
Eigen::Matrix<Real, Dim, Dim, Eigen::DontAlign> rest_inverse_of(
    const std::array<AlignedVector<Real>, Entries>& rest_inverse, std::size_t c) {
  static_assert(Entries == std::size_t(Dim * Dim));
  Eigen::Matrix<Real, Dim, Dim, Eigen::DontAlign> m;
  for (int k = 0; k < Dim; ++k)
    for (int j = 0; j < Dim; ++j) m(k, j) = rest_inverse[std::size_t(Dim * k + j)][c];
  return m;
}

/// The checks of the proximity entry points: range, particle count, stiffness semantics.
template <class Constraints>
void check_proximity_call(const ParticleArrays& particles, const Constraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings) {
  check_projection_range(Constraints::kFamily, begin, end, batch.size(),
                         batch.particles.particle_count, particles);
  if (uses_compliance(settings))
    throw InvalidInput(std::string(Constraints::kFamily) +
                       " constraints: only stiffness semantics are supported (no XPBD form)");
}

}  // namespace

using PBD = PositionBasedDynamics;

void project_sequentially(ParticleArrays particles, DistanceConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings) {
  check_projection_range(DistanceConstraints::kFamily, begin, end, batch.size(),
                         batch.particles.particle_count, particles);
  if (uses_compliance(settings)) {
    project_in_order<2>(particles, batch.particles, begin, end,
                        [&](std::size_t c, const ConstraintStencil<2>& s, Vector3r(&corr)[2]) {
                          XPBD::solve_DistanceConstraint(
                              s.position[0], s.inverse_mass[0], s.position[1],
                              s.inverse_mass[1], batch.rest_length[c], batch.compliance[c],
                              settings.dt, batch.lambda[c], corr[0], corr[1]);
                        });
  } else {
    project_in_order<2>(particles, batch.particles, begin, end,
                        [&](std::size_t c, const ConstraintStencil<2>& s, Vector3r(&corr)[2]) {
                          PBD::solve_DistanceConstraint(
                              s.position[0], s.inverse_mass[0], s.position[1],
                              s.inverse_mass[1], batch.rest_length[c], batch.stiffness[c],
                              corr[0], corr[1]);
                        });
  }
}

void project_sequentially(ParticleArrays particles, DihedralConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings) {
  check_projection_range(DihedralConstraints::kFamily, begin, end, batch.size(),
                         batch.particles.particle_count, particles);
  if (uses_compliance(settings)) {
    project_in_order<4>(
        particles, batch.particles, begin, end,
        [&](std::size_t c, const ConstraintStencil<4>& s, Vector3r(&corr)[4]) {
          XPBD::solve_DihedralConstraint(
              s.position[0], s.inverse_mass[0], s.position[1], s.inverse_mass[1], s.position[2],
              s.inverse_mass[2], s.position[3], s.inverse_mass[3], batch.rest_angle[c],
              batch.compliance[c], settings.dt, batch.lambda[c], corr[0], corr[1], corr[2],
              corr[3]);
        });
  } else {
    project_in_order<4>(
        particles, batch.particles, begin, end,
        [&](std::size_t c, const ConstraintStencil<4>& s, Vector3r(&corr)[4]) {
          PBD::solve_DihedralConstraint(s.position[0], s.inverse_mass[0], s.position[1],
                                        s.inverse_mass[1], s.position[2], s.inverse_mass[2],
                                        s.position[3], s.inverse_mass[3], batch.rest_angle[c],
                                        batch.stiffness[c], corr[0], corr[1], corr[2], corr[3]);
        });
  }
}

void project_sequentially(ParticleArrays particles, VolumeConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings) {
  check_projection_range(VolumeConstraints::kFamily, begin, end, batch.size(),
                         batch.particles.particle_count, particles);
  if (uses_compliance(settings)) {
    project_in_order<4>(
        particles, batch.particles, begin, end,
        [&](std::size_t c, const ConstraintStencil<4>& s, Vector3r(&corr)[4]) {
          XPBD::solve_VolumeConstraint(
              s.position[0], s.inverse_mass[0], s.position[1], s.inverse_mass[1], s.position[2],
              s.inverse_mass[2], s.position[3], s.inverse_mass[3], batch.rest_volume[c],
              batch.compliance[c], settings.dt, batch.lambda[c], corr[0], corr[1], corr[2],
              corr[3]);
        });
  } else {
    project_in_order<4>(
        particles, batch.particles, begin, end,
        [&](std::size_t c, const ConstraintStencil<4>& s, Vector3r(&corr)[4]) {
          PBD::solve_VolumeConstraint(s.position[0], s.inverse_mass[0], s.position[1],
                                      s.inverse_mass[1], s.position[2], s.inverse_mass[2],
                                      s.position[3], s.inverse_mass[3], batch.rest_volume[c],
                                      batch.stiffness[c], corr[0], corr[1], corr[2], corr[3]);
        });
  }
}

void project_sequentially(ParticleArrays particles, IsometricBendingConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings) {
  check_projection_range(IsometricBendingConstraints::kFamily, begin, end, batch.size(),
                         batch.particles.particle_count, particles);
  if (uses_compliance(settings)) {
    project_in_order<4>(
        particles, batch.particles, begin, end,
        [&](std::size_t c, const ConstraintStencil<4>& s, Vector3r(&corr)[4]) {
          XPBD::solve_IsometricBendingConstraint(
              s.position[0], s.inverse_mass[0], s.position[1], s.inverse_mass[1], s.position[2],
              s.inverse_mass[2], s.position[3], s.inverse_mass[3], batch.matrix(c),
              batch.compliance[c], settings.dt, batch.lambda[c], corr[0], corr[1], corr[2],
              corr[3]);
        });
  } else {
    project_in_order<4>(
        particles, batch.particles, begin, end,
        [&](std::size_t c, const ConstraintStencil<4>& s, Vector3r(&corr)[4]) {
          PBD::solve_IsometricBendingConstraint(
              s.position[0], s.inverse_mass[0], s.position[1], s.inverse_mass[1], s.position[2],
              s.inverse_mass[2], s.position[3], s.inverse_mass[3], batch.matrix(c),
              batch.stiffness[c], corr[0], corr[1], corr[2], corr[3]);
        });
  }
}

void project_sequentially(ParticleArrays particles, const EdgePointDistanceConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings) {
  check_proximity_call(particles, batch, begin, end, settings);
  project_in_order<3>(particles, batch.particles, begin, end,
                      [&](std::size_t c, const ConstraintStencil<3>& s, Vector3r(&corr)[3]) {
                        PBD::solve_EdgePointDistanceConstraint(
                            s.position[0], s.inverse_mass[0], s.position[1], s.inverse_mass[1],
                            s.position[2], s.inverse_mass[2], batch.rest_distance[c],
                            batch.compression_stiffness[c], batch.stretch_stiffness[c],
                            corr[0], corr[1], corr[2]);
                      });
}

void project_sequentially(ParticleArrays particles,
                          const TrianglePointDistanceConstraints& batch, std::size_t begin,
                          std::size_t end, const ProjectionSettings& settings) {
  check_proximity_call(particles, batch, begin, end, settings);
  project_in_order<4>(particles, batch.particles, begin, end,
                      [&](std::size_t c, const ConstraintStencil<4>& s, Vector3r(&corr)[4]) {
                        PBD::solve_TrianglePointDistanceConstraint(
                            s.position[0], s.inverse_mass[0], s.position[1], s.inverse_mass[1],
                            s.position[2], s.inverse_mass[2], s.position[3], s.inverse_mass[3],
                            batch.rest_distance[c], batch.compression_stiffness[c],
                            batch.stretch_stiffness[c], corr[0], corr[1], corr[2], corr[3]);
                      });
}

void project_sequentially(ParticleArrays particles, const EdgeEdgeDistanceConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings) {
  check_proximity_call(particles, batch, begin, end, settings);
  project_in_order<4>(particles, batch.particles, begin, end,
                      [&](std::size_t c, const ConstraintStencil<4>& s, Vector3r(&corr)[4]) {
                        PBD::solve_EdgeEdgeDistanceConstraint(
                            s.position[0], s.inverse_mass[0], s.position[1], s.inverse_mass[1],
                            s.position[2], s.inverse_mass[2], s.position[3], s.inverse_mass[3],
                            batch.rest_distance[c], batch.compression_stiffness[c],
                            batch.stretch_stiffness[c], corr[0], corr[1], corr[2], corr[3]);
                      });
}

void project_sequentially(ParticleArrays particles, const StrainTriangleConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& /*settings: PBD form only*/) {
  check_projection_range(StrainTriangleConstraints::kFamily, begin, end, batch.size(),
                         batch.particles.particle_count, particles);
  project_in_order<3>(particles, batch.particles, begin, end,
                      [&](std::size_t c, const ConstraintStencil<3>& s, Vector3r(&corr)[3]) {
                        PBD::solve_StrainTriangleConstraint(
                            s.position[0], s.inverse_mass[0], s.position[1], s.inverse_mass[1],
                            s.position[2], s.inverse_mass[2],
                            rest_inverse_of<2>(batch.rest_inverse, c), batch.xx_stiffness[c],
                            batch.yy_stiffness[c], batch.xy_stiffness[c],
                            batch.normalize_stretch, batch.normalize_shear, corr[0], corr[1],
                            corr[2]);
                      });
}

void project_sequentially(ParticleArrays particles, const StrainTetraConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& /*settings: PBD form only*/) {
  check_projection_range(StrainTetraConstraints::kFamily, begin, end, batch.size(),
                         batch.particles.particle_count, particles);
  project_in_order<4>(
      particles, batch.particles, begin, end,
      [&](std::size_t c, const ConstraintStencil<4>& s, Vector3r(&corr)[4]) {
        const Vector3r stretch(batch.stretch_stiffness[0][c], batch.stretch_stiffness[1][c],
                               batch.stretch_stiffness[2][c]);
        const Vector3r shear(batch.shear_stiffness[0][c], batch.shear_stiffness[1][c],
                             batch.shear_stiffness[2][c]);
        PBD::solve_StrainTetraConstraint(
            s.position[0], s.inverse_mass[0], s.position[1], s.inverse_mass[1], s.position[2],
            s.inverse_mass[2], s.position[3], s.inverse_mass[3],
            rest_inverse_of<3>(batch.rest_inverse, c), stretch, shear, batch.normalize_stretch,
            batch.normalize_shear, corr[0], corr[1], corr[2], corr[3]);
      });
}

void project_sequentially(ParticleArrays particles, const FEMTriangleConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& /*settings: PBD form only*/) {
  check_projection_range(FEMTriangleConstraints::kFamily, begin, end, batch.size(),
                         batch.particles.particle_count, particles);
  project_in_order<3>(particles, batch.particles, begin, end,
                      [&](std::size_t c, const ConstraintStencil<3>& s, Vector3r(&corr)[3]) {
                        PBD::solve_FEMTriangleConstraint(
                            s.position[0], s.inverse_mass[0], s.position[1], s.inverse_mass[1],
                            s.position[2], s.inverse_mass[2], batch.area[c],
                            rest_inverse_of<2>(batch.rest_inverse, c), batch.youngs_modulus_x[c],
                            batch.youngs_modulus_y[c], batch.youngs_modulus_shear[c],
                            batch.poisson_ratio_xy[c], batch.poisson_ratio_yx[c], corr[0],
                            corr[1], corr[2]);
                      });
}

void project_sequentially(ParticleArrays particles, FEMTetraConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& settings) {
  check_projection_range(FEMTetraConstraints::kFamily, begin, end, batch.size(),
                         batch.particles.particle_count, particles);
  if (uses_compliance(settings)) {
    project_in_order<4>(
        particles, batch.particles, begin, end,
        [&](std::size_t c, const ConstraintStencil<4>& s, Vector3r(&corr)[4]) {
          XPBD::solve_FEMTetraConstraint(
              s.position[0], s.inverse_mass[0], s.position[1], s.inverse_mass[1], s.position[2],
              s.inverse_mass[2], s.position[3], s.inverse_mass[3], batch.volume[c],
              rest_inverse_of<3>(batch.rest_inverse, c), batch.poisson_ratio[c],
              batch.compliance[c], batch.handle_inversion, settings.dt, batch.lambda[c],
              corr[0], corr[1], corr[2], corr[3]);
        });
  } else {
    project_in_order<4>(
        particles, batch.particles, begin, end,
        [&](std::size_t c, const ConstraintStencil<4>& s, Vector3r(&corr)[4]) {
          PBD::solve_FEMTetraConstraint(
              s.position[0], s.inverse_mass[0], s.position[1], s.inverse_mass[1], s.position[2],
              s.inverse_mass[2], s.position[3], s.inverse_mass[3], batch.volume[c],
              rest_inverse_of<3>(batch.rest_inverse, c), batch.youngs_modulus[c],
              batch.poisson_ratio[c], batch.handle_inversion, corr[0], corr[1], corr[2],
              corr[3]);
        });
  }
}

void project_sequentially(ParticleArrays particles, const ShapeMatchingConstraints& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& /*settings: PBD form only*/) {
  check_projection_range(ShapeMatchingConstraints::kFamily, begin, end, batch.size(),
                         batch.particle_count, particles);
  if (begin == end) return;
  // One buffer per call, sized for the largest cluster: rest offsets, current positions and
  // corrections (three blocks of Vector3r), and the inverse masses.
  const std::size_t capacity = batch.max_cluster_size;
  std::vector<Vector3r> points(3 * capacity);
  std::vector<Real> inverse_masses(capacity);
  Vector3r* const rest_offsets = points.data();
  Vector3r* const current = rest_offsets + capacity;
  Vector3r* const corrections = current + capacity;
  const Vector3r rest_centre = Vector3r::Zero();  // x0 holds q = x0 - c0 already
  for (std::size_t c = begin; c < end; ++c) {
    const std::size_t first = batch.offsets[c];
    const std::size_t size = batch.offsets[c + 1] - first;
    for (std::size_t k = 0; k < size; ++k) {
      const std::size_t e = first + k;
      const ParticleIndex i = batch.particle[e];
      rest_offsets[k] =
          Vector3r(batch.rest_offset[0][e], batch.rest_offset[1][e], batch.rest_offset[2][e]);
      current[k] = position_of(particles, i);
      inverse_masses[k] = particles.inverse_mass[i];
    }
    PBD::solve_ShapeMatchingConstraint(rest_offsets, current, inverse_masses.data(), int(size),
                                       rest_centre, batch.stiffness[c], batch.allow_stretch,
                                       corrections);
    for (std::size_t k = 0; k < size; ++k)
      add_correction(particles, batch.particle[first + k], inverse_masses[k], corrections[k]);
  }
}

void project_sequentially(ParticleArrays particles, ParticleTetContacts& batch,
                          std::size_t begin, std::size_t end,
                          const ProjectionSettings& /*settings: the contact's own rule*/) {
  check_projection_range(ParticleTetContacts::kFamily, begin, end, batch.size(),
                         batch.particles.particle_count, particles);
  // Slot 0 is the particle, slots 1..4 the tet's x[0..3].
  project_in_order<5>(
      particles, batch.particles, begin, end,
      [&](std::size_t c, const ConstraintStencil<5>& s, Vector3r(&corr)[5]) {
        Matrix3r constraint_info = Matrix3r::Zero();
        for (int k = 0; k < 3; ++k) {
          constraint_info(k, 0) = batch.normal[std::size_t(k)][c];
          constraint_info(k, 1) = batch.tangent[std::size_t(k)][c];
        }
        constraint_info(0, 2) = batch.effective_mass[c];
        constraint_info(1, 2) = batch.max_tangential_impulse[c];
        constraint_info(2, 2) = batch.normal_speed[c];
        const Vector3r barycentric(batch.barycentric[0][c], batch.barycentric[1][c],
                                   batch.barycentric[2][c]);
        PBD::solve_ParticleTetContactConstraint(s.inverse_mass[0], s.position[0],
                                                s.inverse_mass + 1, s.position + 1, barycentric,
                                                constraint_info, batch.lambda[c], corr[0],
                                                corr + 1);
      });
}

}  // namespace tessera
