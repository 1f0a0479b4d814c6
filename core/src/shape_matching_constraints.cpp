// Shape-matching clusters in a CSR batch: validation and the rest data (centres, offsets,
// masses, A_qq⁻¹) at the door, then the batched kernel, compiled once per SIMD target
// (Highway foreach_target) and dispatched at run time.
//
// Lanes run over clusters: W clusters side by side, entry k of every lane's cluster at once
// (lanes whose cluster is shorter are masked). Three passes over the entries:
//   1. gather positions, inverse masses, masses and rest offsets into a scratch buffer and
//      sum the masses and mass-weighted positions (the centre),
//   2. A_pq = Σ m (x - c) qᵀ,
//   3. T from A_pq (polar rotation, or A_pq A_qq⁻¹), corrections, masked scatter.
// Lanes over points instead (one cluster at a time, horizontal sums, the polar step still
// over W clusters) was measured too: slower on the benchmark's randomly numbered particles
// (1.45 vs 1.66 M clusters/s, both without prefetch), faster when a cluster's particles are
// contiguous (6.9 vs 4.3 M/s); this layout keeps W clusters' misses in flight at once.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "shape_matching_constraints.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

#include <tessera/core/shape_matching_constraints.hpp>

#include "kernels/batch-inl.h"
#include "kernels/shape_matching-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {
namespace {

using Index32Tag = hn::Rebind<int32_t, RealTag>;  // as many lanes as Real, 32-bit

HWY_INLINE IndexLanes widen(hn::Vec<Index32Tag> index) {
#if TESSERA_DOUBLE_PRECISION
  return hn::PromoteTo(IndexTag(), index);
#else
  return index;
#endif
}

/// How many blocks of W clusters ahead the kernel prefetches particles (measured on the
/// 65,536-cluster benchmark: none 1.66 M clusters/s, one block 2.0 M/s, two 2.2–2.7 M/s).
constexpr std::size_t kPrefetchBlocks = 2;

/// Scratch rows per entry: x, y, z, inverse mass, mass, q.x, q.y, q.z.
constexpr std::size_t kScratchRows = 8;

}  // namespace

void ProjectShapeMatchingConstraints(ParticleArrays particles,
                                     ShapeMatchingConstraints& constraints, std::size_t begin,
                                     std::size_t end) {
  const RealTag d;
  const Index32Tag d32;
  const std::size_t lanes = hn::Lanes(d);
  const std::size_t max_size = constraints.max_cluster_size;
  AlignedVector<Real> scratch(kScratchRows * max_size * lanes);
  AlignedVector<ParticleIndex> scratch_index(max_size * lanes);
  const int32_t* offsets = reinterpret_cast<const int32_t*>(constraints.offsets.data());
  const int32_t* entry_particle = reinterpret_cast<const int32_t*>(constraints.particle.data());
  const RealLanes zero = hn::Zero(d);

  for (std::size_t i = begin; i < end; i += lanes) {
    const std::size_t active_count = std::min(end - i, lanes);
    const LaneMask active = hn::FirstN(d, active_count);
    const auto first = hn::LoadU(d32, offsets + i);
    const auto last = hn::LoadU(d32, offsets + i + 1);
    const auto size = hn::IfThenElseZero(hn::FirstN(d32, active_count), hn::Sub(last, first));
    const IndexLanes wide_size = widen(size);  // as wide as Real, for masks over Real lanes
    const auto last_entry = hn::Max(hn::Sub(last, hn::Set(d32, 1)), hn::Zero(d32));
    // A cluster's particles are scattered over memory (and over four arrays): fetch those
    // of a block ahead while this one computes (the kernel is bound by these misses otherwise:
    // with the particles in cluster order it runs 3x faster than on randomly numbered ones).
    if (i + kPrefetchBlocks * lanes < end) {
      const std::size_t next = i + kPrefetchBlocks * lanes;
      const std::size_t next_end = std::min(next + lanes, end);
      for (std::size_t e = constraints.offsets[next]; e < constraints.offsets[next_end]; ++e)
        prefetch_particle(particles, constraints.particle[e]);
    }
    std::size_t block_size = 0;
    for (std::size_t lane = 0; lane < active_count; ++lane)
      block_size = std::max<std::size_t>(block_size, constraints.offsets[i + lane + 1] -
                                                         constraints.offsets[i + lane]);

    // Pass 1: gather, and the mass-weighted centre.
    RealLanes total_mass = zero;
    Vec3<RealLanes> weighted = Vec3<RealLanes>::zeros();
    for (std::size_t k = 0; k < block_size; ++k) {
      const auto k32 = hn::Set(d32, int32_t(k));
      const LaneMask in_cluster = hn::RebindMask(d, hn::Lt(widen(k32), wide_size));
      const auto entry32 = hn::Min(hn::Add(first, k32), last_entry);
      const auto particle32 = hn::GatherIndex(d32, entry_particle, entry32);
      hn::StoreU(particle32, d32, reinterpret_cast<int32_t*>(scratch_index.data() + k * lanes));
      const IndexLanes particle = element_offsets(particles, widen(particle32));
      const IndexLanes entry = widen(entry32);
      Real* row = scratch.data() + k * kScratchRows * lanes;
      const RealLanes x = hn::GatherIndex(d, particles.x, particle);
      const RealLanes y = hn::GatherIndex(d, particles.y, particle);
      const RealLanes z = hn::GatherIndex(d, particles.z, particle);
      const RealLanes m = hn::IfThenElseZero(in_cluster,
                                             hn::GatherIndex(d, constraints.mass.data(), entry));
      hn::Store(x, d, row);
      hn::Store(y, d, row + lanes);
      hn::Store(z, d, row + 2 * lanes);
      hn::Store(hn::GatherIndex(d, particles.inverse_mass, particle), d, row + 3 * lanes);
      hn::Store(m, d, row + 4 * lanes);
      for (std::size_t c = 0; c < 3; ++c)
        hn::Store(hn::GatherIndex(d, constraints.rest_offset[c].data(), entry), d,
                  row + (5 + c) * lanes);
      total_mass = total_mass + m;
      weighted += Vec3<RealLanes>{x, y, z} * m;
    }
    const LaneMask has_mass = hn::And(active, total_mass > zero);
    const Vec3<RealLanes> centre =
        weighted * safe_divide(hn::Set(d, Real(1)), total_mass, has_mass);

    // Pass 2: A_pq = Σ m (x - c) qᵀ (column j = Σ m (x - c) q_j).
    Mat3<RealLanes> a_pq = Mat3<RealLanes>::zeros();
    for (std::size_t k = 0; k < block_size; ++k) {
      const Real* row = scratch.data() + k * kScratchRows * lanes;
      const Vec3<RealLanes> x = {hn::Load(d, row), hn::Load(d, row + lanes),
                                 hn::Load(d, row + 2 * lanes)};
      const Vec3<RealLanes> weighted_offset = (x - centre) * hn::Load(d, row + 4 * lanes);
      for (std::size_t j = 0; j < 3; ++j)
        a_pq.col[j] += weighted_offset * hn::Load(d, row + (5 + j) * lanes);
    }

    // Pass 3: the goal transform and the corrections.
    ShapeMatchingTransform<RealLanes> transform;
    if (constraints.allow_stretch) {
      Mat3<RealLanes> inverse_a_qq;
      for (std::size_t j = 0; j < 3; ++j)
        inverse_a_qq.col[j] = {hn::LoadU(d, constraints.inverse_rest_moment[3 * j].data() + i),
                               hn::LoadU(d, constraints.inverse_rest_moment[3 * j + 1].data() + i),
                               hn::LoadU(d, constraints.inverse_rest_moment[3 * j + 2].data() + i)};
      transform = shape_matching_linear(a_pq, inverse_a_qq);
    } else {
      transform = shape_matching_rotation(a_pq);
    }
    const LaneMask valid = hn::And(has_mass, transform.valid);
    const RealLanes stiffness = hn::LoadU(d, constraints.stiffness.data() + i);
    for (std::size_t k = 0; k < block_size; ++k) {
      const Real* row = scratch.data() + k * kScratchRows * lanes;
      const auto k32 = hn::Set(d32, int32_t(k));
      const LaneMask write = hn::And(valid, hn::RebindMask(d, hn::Lt(widen(k32), wide_size)));
      ParticleLanes p;
      p.position = {hn::Load(d, row), hn::Load(d, row + lanes), hn::Load(d, row + 2 * lanes)};
      p.inverse_mass = hn::Load(d, row + 3 * lanes);
      const Vec3<RealLanes> q = {hn::Load(d, row + 5 * lanes), hn::Load(d, row + 6 * lanes),
                                 hn::Load(d, row + 7 * lanes)};
      const Vec3<RealLanes> correction = keep_if(
          write, shape_matching_correction(transform.T, q, centre, p.position, stiffness));
      if (particles.corrected_x == nullptr) {
        scatter_corrected(particles, scratch_index.data() + k * lanes, p, correction, write);
      } else {  // redirected output: entry k of each lane's cluster
        HWY_ALIGN ParticleIndex entry[kMaxLanes];
        for (std::size_t lane = 0; lane < active_count; ++lane)
          entry[lane] = constraints.offsets[i + lane] + ParticleIndex(k);
        for (std::size_t lane = active_count; lane < lanes; ++lane) entry[lane] = 0;
        // Every entry of the cluster, valid or not (an invalid cluster's correction is
        // zero): the solver sums all of them.
        const LaneMask in_cluster = hn::RebindMask(d, hn::Lt(widen(k32), wide_size));
        ParticleArrays output = corrected_output(particles);
        scatter_corrected(output, entry, p, correction, in_cluster);
      }
    }
  }
}


}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#if HWY_ONCE

#include "sequential_loop.hpp"
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <tessera/core/position_based_dynamics.hpp>

#include "constraint_validation.hpp"

namespace tessera {

HWY_EXPORT(ProjectShapeMatchingConstraints);

namespace {

/// Relative size below which an eigenvalue of A_qq counts as zero (as in the scalar API).
constexpr Real kRankTolerance = 256 * std::numeric_limits<Real>::epsilon();
constexpr std::size_t kMaxIndex = std::size_t(std::numeric_limits<std::int32_t>::max());

}  // namespace

ShapeMatchingConstraints make_shape_matching_constraints(const ShapeMatchingInput& input) {
  const detail::ConstraintValidator validator(ShapeMatchingConstraints::kFamily,
                                              input.rest_positions.size());
  validator.check_parameter("stiffness", input.stiffness);
  if (input.inverse_masses.size() != input.rest_positions.size())
    validator.fail_input(std::to_string(input.rest_positions.size()) + " rest positions but " +
                         std::to_string(input.inverse_masses.size()) + " inverse masses");
  if (input.offsets.empty()) validator.fail_input("offsets are empty (need count + 1)");
  if (input.offsets.front() != 0) validator.fail_input("offsets do not start at 0");
  if (input.offsets.back() != input.particles.size())
    validator.fail_input("the last offset is " + std::to_string(input.offsets.back()) +
                         ", not the number of entries " + std::to_string(input.particles.size()));
  if (input.particles.size() > kMaxIndex || input.rest_positions.size() > kMaxIndex)
    validator.fail_input("more than 2^31 - 1 entries or particles");

  for (std::size_t c = 0; c + 1 < input.offsets.size(); ++c)
    if (input.offsets[c + 1] < input.offsets[c])
      validator.fail_input("offsets decrease at cluster " + std::to_string(c));

  ShapeMatchingConstraints result;
  const std::size_t n = input.offsets.size() - 1;
  const std::size_t entries = input.particles.size();
  result.count = n;
  result.particle_count = input.rest_positions.size();
  result.allow_stretch = input.allow_stretch;
  result.offsets.assign(padded_size(n + 1), std::uint32_t(entries));
  std::copy(input.offsets.begin(), input.offsets.end(), result.offsets.begin());
  result.particle.assign(padded_size(entries), 0);
  for (auto& a : result.rest_offset) a.assign(padded_size(entries), 0);
  result.mass.assign(padded_size(entries), 0);
  for (auto& a : result.rest_centre) a = detail::filled(n, 0);
  for (auto& a : result.inverse_rest_moment) a = detail::filled(n, 0);
  result.stiffness = detail::filled(n, input.stiffness);

  // last_cluster[p] = the last cluster that named particle p (finds repeats in O(entries)).
  std::vector<std::size_t> last_cluster(input.rest_positions.size(),
                                        std::numeric_limits<std::size_t>::max());
  for (std::size_t c = 0; c < n; ++c) {
    const std::size_t first = input.offsets[c], last = input.offsets[c + 1];
    if (last == first) validator.fail(c, "cluster is empty");
    result.max_cluster_size = std::max(result.max_cluster_size, last - first);
    Real heaviest = 0;
    for (std::size_t e = first; e < last; ++e) {
      const ParticleIndex p = input.particles[e];
      validator.check_index(c, p);
      if (last_cluster[p] == c) validator.fail_repeated(c, p);
      last_cluster[p] = c;
      if (!input.rest_positions[p].allFinite()) validator.fail(c, "rest position is not finite");
      validator.check_non_negative(c, "inverse mass", input.inverse_masses[p]);
      if (input.inverse_masses[p] > 0) heaviest = std::max(heaviest, 1 / input.inverse_masses[p]);
    }
    // The scalar API's masses: 1/w, static particles kShapeMatchingStaticMass × the heaviest.
    const Real static_mass =
        heaviest > 0 ? PositionBasedDynamics::kShapeMatchingStaticMass * heaviest : Real(1);
    Vector3r centre = Vector3r::Zero();
    Real total = 0;
    for (std::size_t e = first; e < last; ++e) {
      const ParticleIndex p = input.particles[e];
      const Real m = input.inverse_masses[p] > 0 ? 1 / input.inverse_masses[p] : static_mass;
      result.particle[e] = p;
      result.mass[e] = m;
      centre += m * input.rest_positions[p];
      total += m;
    }
    centre /= total;
    Eigen::Matrix<Real, 3, 3> a_qq = Eigen::Matrix<Real, 3, 3>::Zero();
    for (std::size_t e = first; e < last; ++e) {
      const Vector3r q = input.rest_positions[input.particles[e]] - centre;
      for (int k = 0; k < 3; ++k) result.rest_offset[std::size_t(k)][e] = q[k];
      a_qq += result.mass[e] * q * q.transpose();
    }
    for (int k = 0; k < 3; ++k) result.rest_centre[std::size_t(k)][c] = centre[k];

    // The rest cluster's spread: rank ≥ 2 for a rotation, 3 for a linear fit.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<Real, 3, 3>> eigen(a_qq);
    const auto& values = eigen.eigenvalues();  // ascending
    const bool spread = values[2] > kDegenerateTolerance * kDegenerateTolerance;
    if (!spread || !(values[1] > kRankTolerance * values[2]))
      validator.fail(c, "rest cluster is degenerate (all points on one line)");
    if (input.allow_stretch) {
      if (!(values[0] > kRankTolerance * values[2]))
        validator.fail(c, "rest cluster is degenerate (all points in one plane: no linear fit)");
      const Eigen::Matrix<Real, 3, 3> inverse = eigen.eigenvectors() *
                                                values.cwiseInverse().asDiagonal() *
                                                eigen.eigenvectors().transpose();
      for (int j = 0; j < 3; ++j)
        for (int r = 0; r < 3; ++r)
          result.inverse_rest_moment[std::size_t(3 * j + r)][c] = inverse(r, j);
    }
  }
  return result;
}

void project_shape_matching_constraints(ParticleArrays particles,
                                        ShapeMatchingConstraints& constraints, std::size_t begin,
                                        std::size_t end) {
  check_projection_range(ShapeMatchingConstraints::kFamily, begin, end, constraints.size(),
                         constraints.particle_count, particles);
  if (begin == end) return;
  HWY_DYNAMIC_DISPATCH(ProjectShapeMatchingConstraints)(particles, constraints, begin, end);
}

Real constraint_residual(const ParticleArrays& particles, const ShapeMatchingConstraints& batch,
                         std::size_t c) {
  const std::size_t first = batch.offsets[c], last = batch.offsets[c + 1];
  if (last <= first) return 0;
  using Point = HWY_NAMESPACE::Vec3<Real>;
  const auto position_at = [&](ParticleIndex i) -> Point {
    const std::size_t at = i * particles.stride;
    return {particles.x[at], particles.y[at], particles.z[at]};
  };
  const auto rest_offset = [&](std::size_t e) -> Point {
    return {batch.rest_offset[0][e], batch.rest_offset[1][e], batch.rest_offset[2][e]};
  };
  // The centre and A_pq = Σ m (x − c) qᵀ as the kernel forms them.
  Real total_mass = 0;
  Point weighted = Point::zeros();
  for (std::size_t e = first; e < last; ++e) {
    total_mass += batch.mass[e];
    weighted += position_at(batch.particle[e]) * batch.mass[e];
  }
  const Point centre = weighted * HWY_NAMESPACE::safe_divide(Real(1), total_mass, total_mass > 0);
  HWY_NAMESPACE::Mat3<Real> a_pq = HWY_NAMESPACE::Mat3<Real>::zeros();
  for (std::size_t e = first; e < last; ++e) {
    const Point weighted_offset =
        (position_at(batch.particle[e]) - centre) * batch.mass[e];
    const Point q = rest_offset(e);
    a_pq.col[0] += weighted_offset * q.x;
    a_pq.col[1] += weighted_offset * q.y;
    a_pq.col[2] += weighted_offset * q.z;
  }
  HWY_NAMESPACE::Mat3<Real> transform;
  if (batch.allow_stretch) {
    HWY_NAMESPACE::Mat3<Real> inverse_a_qq;
    for (std::size_t j = 0; j < 3; ++j)
      inverse_a_qq.col[j] = {batch.inverse_rest_moment[3 * j][c],
                             batch.inverse_rest_moment[3 * j + 1][c],
                             batch.inverse_rest_moment[3 * j + 2][c]};
    transform = HWY_NAMESPACE::shape_matching_linear(a_pq, inverse_a_qq).T;
  } else {
    // Used also where the kernel would call the rotation undetermined (rank A_pq < 2): it is
    // a proper rotation either way, so the measure stays finite and meaningful.
    transform = HWY_NAMESPACE::shape_matching_rotation(a_pq).T;
  }
  Real goal_distance_squared = 0, rest_offset_squared = 0;
  for (std::size_t e = first; e < last; ++e) {
    const Point q = rest_offset(e);
    const Point to_goal = HWY_NAMESPACE::shape_matching_correction(
        transform, q, centre, position_at(batch.particle[e]), Real(1));
    goal_distance_squared += HWY_NAMESPACE::squared_norm(to_goal);
    rest_offset_squared += HWY_NAMESPACE::squared_norm(q);
  }
  // RMS over RMS: the 1/n of both means cancels.
  if (!(rest_offset_squared > 0)) return 0;
  return std::sqrt(goal_distance_squared / rest_offset_squared);
}

void constraint_residuals(const ParticleArrays& particles,
                          const ShapeMatchingConstraints& batch, std::size_t begin,
                          std::size_t end, Real* out) {
  // Scalar on purpose: clusters of any size in CSR do not line up in lanes (see the top).
  for (std::size_t c = begin; c < end; ++c) out[c - begin] = constraint_residual(particles, batch, c);
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
      current[k] = detail::position_of(particles, i);
      inverse_masses[k] = particles.inverse_mass[i * particles.stride];
    }
    PositionBasedDynamics::solve_ShapeMatchingConstraint(rest_offsets, current, inverse_masses.data(), int(size),
                                       rest_centre, batch.stiffness[c], batch.allow_stretch,
                                       corrections);
    for (std::size_t k = 0; k < size; ++k)
      detail::add_correction(particles, batch.particle[first + k], inverse_masses[k], corrections[k]);
  }
}

}  // namespace tessera
#endif  // HWY_ONCE
