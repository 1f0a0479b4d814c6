// The sequential reference loop (project_sequentially) for every constraint family:
//  1. on constraints that share no particle it gives the batched kernel's result (to
//     rounding), under each semantics the family supports, λ included;
//  2. on chains whose constraints share particles it is, bit for bit, a hand-written loop over
//     the scalar API in input order (and differs from the same loop run backwards), which is
//     the Gauss–Seidel order the solver's sequential mode promises;
//  3. static particles are never written, sub-ranges touch only their constraints, bad ranges
//     and too few particles throw InvalidInput.
// The families with fixed-size stencils run as one typed suite over a traits struct per family
// (how to make random well-shaped constraints, how to build the batch, how the batched kernel
// and the scalar API are called); shape matching (clusters of any size) and the contacts'
// classic constraintInfo have their own tests.
#include <cstring>
#include <numbers>

#include <tessera/core/error.hpp>
#include <tessera/core/position_based_dynamics.hpp>
#include <tessera/core/position_based_dynamics_extensions.hpp>
#include <tessera/core/sequential_projection.hpp>
#include <tessera/core/xpbd.hpp>

#include "batch_test_support.hpp"

namespace tessera {
namespace sequential_projection_tests {

using test::Random;
using PBD = PositionBasedDynamics;
template <int N>
using Points = std::array<Vector3r, N>;
template <int N>
using Masses = std::array<Real, N>;
template <int N>
using ConstraintSet = test::DisjointConstraintSet<N>;

constexpr Real kTimeStep = Real(1) / 120;
constexpr Real kPi = std::numbers::pi_v<Real>;

/// How a family reads ProjectionSettings::semantics.
enum class SemanticsSupport {
  pbd_and_xpbd,    // stiffness → PositionBasedDynamics, compliance → XPBD with λ
  pbd_for_both,    // no XPBD form: the PBD form under either semantics
  stiffness_only,  // no XPBD form, and compliance is refused (InvalidInput)
};

Real uniform(Random& random, double lo, double hi) { return random.uniform(Real(lo), Real(hi)); }

/// A rigid motion of the points (random rotation, translation in [-spread, spread]³).
template <std::size_t N>
std::array<Vector3r, N> rigidly_moved(Random& random, std::array<Vector3r, N> points,
                                      Real spread = 5) {
  const Matrix3r rotation = random.rotation();
  const Vector3r shift = random.vector(-spread, spread);
  for (Vector3r& p : points) p = rotation * p + shift;
  return points;
}

/// A tetrahedron well away from flat, jittered and rigidly moved.
Points<4> random_tetrahedron(Random& random) {
  Points<4> t = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(Real(0.3), 1, 0),
                 Vector3r(Real(0.3), Real(0.3), 1)};
  for (Vector3r& p : t) p += Real(0.1) * random.vector();
  return rigidly_moved(random, t);
}

/// Dihedral stencil (wings p0, p1, shared edge p2-p3) whose normals meet at `angle`.
Points<4> hinge(Real angle, Real length) {
  return {Vector3r(Real(0.4), 1, 0), Vector3r(Real(0.6), -std::cos(angle), std::sin(angle)),
          Vector3r(0, 0, 0), Vector3r(length, 0, 0)};
}

/// Per-constraint parameters are randomised after building, so a mix-up of arrays or
/// indices between the batch and the scalar call shows.
Real random_stiffness(Random& random) { return uniform(random, 0.2, 1); }
Real random_compliance(Random& random) { return uniform(random, 1e-5, 1e-3); }

// ------------------------------------------------------------------------ family traits
//
// Each traits struct gives:
//   N, Batch, kSemantics, kHasLambda
//   kChainSlot[k]        which particle of a window of N consecutive chain particles sits in
//                        slot k (so consecutive constraints of a chain share N - 1 particles)
//   random_shape(r)      the N points of one well-conditioned constraint
//   build(set, rest, r)  the batch (make_<family>_constraints), with randomised parameters
//   batched(...)         the batched kernel
//   solve(batch, c, x, w, settings, corr)   the scalar API on constraint c (λ in batch)

struct Distance {
  static constexpr int N = 2;
  using Batch = DistanceConstraints;
  static constexpr SemanticsSupport kSemantics = SemanticsSupport::pbd_and_xpbd;
  static constexpr bool kHasLambda = true;
  static constexpr std::array<int, N> kChainSlot = {0, 1};

  static Points<N> random_shape(Random& r) {
    const Vector3r a = r.vector(-5, 5);
    return {a, a + r.unit_vector() * uniform(r, 0.5, 2)};
  }
  static Batch build(const ConstraintSet<N>& set, const std::vector<Vector3r>& rest,
                     Random& r) {
    Batch batch = make_distance_constraints({set.indices, rest});
    for (std::size_t c = 0; c < set.count; ++c) {
      batch.stiffness[c] = random_stiffness(r);
      batch.compliance[c] = random_compliance(r);
    }
    return batch;
  }
  static void batched(ParticleArrays p, Batch& b, std::size_t begin, std::size_t end,
                      const ProjectionSettings& s) {
    project_distance_constraints(p, b, begin, end, s);
  }
  static void solve(Batch& b, std::size_t c, const Points<N>& x, const Masses<N>& w,
                    const ProjectionSettings& s, Points<N>& corr) {
    if (s.semantics == ConstraintSemantics::stiffness)
      PBD::solve_DistanceConstraint(x[0], w[0], x[1], w[1], b.rest_length[c], b.stiffness[c],
                                    corr[0], corr[1]);
    else
      XPBD::solve_DistanceConstraint(x[0], w[0], x[1], w[1], b.rest_length[c], b.compliance[c],
                                     s.dt, b.lambda[c], corr[0], corr[1]);
  }
};

struct Dihedral {
  static constexpr int N = 4;
  using Batch = DihedralConstraints;
  static constexpr SemanticsSupport kSemantics = SemanticsSupport::pbd_and_xpbd;
  static constexpr bool kHasLambda = true;
  // Window i..i+3: wings i and i+3, shared edge (i+1, i+2).
  static constexpr std::array<int, N> kChainSlot = {0, 3, 1, 2};

  static Points<N> random_shape(Random& r) {
    return rigidly_moved(r, hinge(uniform(r, 0.3, 2.8), uniform(r, 0.5, 2)));
  }
  static Batch build(const ConstraintSet<N>& set, const std::vector<Vector3r>& rest,
                     Random& r) {
    Batch batch = make_dihedral_constraints({set.indices, rest});
    for (std::size_t c = 0; c < set.count; ++c) {
      batch.stiffness[c] = random_stiffness(r);
      batch.compliance[c] = random_compliance(r);
    }
    return batch;
  }
  static void batched(ParticleArrays p, Batch& b, std::size_t begin, std::size_t end,
                      const ProjectionSettings& s) {
    project_dihedral_constraints(p, b, begin, end, s);
  }
  static void solve(Batch& b, std::size_t c, const Points<N>& x, const Masses<N>& w,
                    const ProjectionSettings& s, Points<N>& corr) {
    if (s.semantics == ConstraintSemantics::stiffness)
      PBD::solve_DihedralConstraint(x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3],
                                    b.rest_angle[c], b.stiffness[c], corr[0], corr[1], corr[2],
                                    corr[3]);
    else
      XPBD::solve_DihedralConstraint(x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3],
                                     b.rest_angle[c], b.compliance[c], s.dt, b.lambda[c],
                                     corr[0], corr[1], corr[2], corr[3]);
  }
};

struct Volume {
  static constexpr int N = 4;
  using Batch = VolumeConstraints;
  static constexpr SemanticsSupport kSemantics = SemanticsSupport::pbd_and_xpbd;
  static constexpr bool kHasLambda = true;
  static constexpr std::array<int, N> kChainSlot = {0, 1, 2, 3};

  static Points<N> random_shape(Random& r) { return random_tetrahedron(r); }
  static Batch build(const ConstraintSet<N>& set, const std::vector<Vector3r>& rest,
                     Random& r) {
    Batch batch = make_volume_constraints({set.indices, rest});
    for (std::size_t c = 0; c < set.count; ++c) {
      batch.stiffness[c] = random_stiffness(r);
      batch.compliance[c] = random_compliance(r);
    }
    return batch;
  }
  static void batched(ParticleArrays p, Batch& b, std::size_t begin, std::size_t end,
                      const ProjectionSettings& s) {
    project_volume_constraints(p, b, begin, end, s);
  }
  static void solve(Batch& b, std::size_t c, const Points<N>& x, const Masses<N>& w,
                    const ProjectionSettings& s, Points<N>& corr) {
    if (s.semantics == ConstraintSemantics::stiffness)
      PBD::solve_VolumeConstraint(x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3],
                                  b.rest_volume[c], b.stiffness[c], corr[0], corr[1], corr[2],
                                  corr[3]);
    else
      XPBD::solve_VolumeConstraint(x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3],
                                   b.rest_volume[c], b.compliance[c], s.dt, b.lambda[c],
                                   corr[0], corr[1], corr[2], corr[3]);
  }
};

struct IsometricBending {
  static constexpr int N = 4;
  using Batch = IsometricBendingConstraints;
  static constexpr SemanticsSupport kSemantics = SemanticsSupport::pbd_and_xpbd;
  static constexpr bool kHasLambda = true;
  static constexpr std::array<int, N> kChainSlot = {0, 3, 1, 2};

  /// A planar stencil (wings on both sides of the edge) bent by up to ±0.3 per coordinate.
  static Points<N> random_shape(Random& r) {
    Points<N> s = {Vector3r(uniform(r, -0.5, 1.5), uniform(r, 0.5, 1.5), 0),
                   Vector3r(uniform(r, -0.5, 1.5), -uniform(r, 0.5, 1.5), 0), Vector3r(0, 0, 0),
                   Vector3r(uniform(r, 0.7, 1.5), 0, 0)};
    for (Vector3r& p : s) p += Real(0.3) * r.vector();
    return rigidly_moved(r, s);
  }
  static Batch build(const ConstraintSet<N>& set, const std::vector<Vector3r>& rest,
                     Random& r) {
    Batch batch = make_isometric_bending_constraints({set.indices, rest});
    for (std::size_t c = 0; c < set.count; ++c) {
      batch.stiffness[c] = random_stiffness(r);
      batch.compliance[c] = random_compliance(r);
    }
    return batch;
  }
  static void batched(ParticleArrays p, Batch& b, std::size_t begin, std::size_t end,
                      const ProjectionSettings& s) {
    project_isometric_bending_constraints(p, b, begin, end, s);
  }
  static void solve(Batch& b, std::size_t c, const Points<N>& x, const Masses<N>& w,
                    const ProjectionSettings& s, Points<N>& corr) {
    const Matrix4r Q = b.matrix(c);
    if (s.semantics == ConstraintSemantics::stiffness)
      PBD::solve_IsometricBendingConstraint(x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3], Q,
                                            b.stiffness[c], corr[0], corr[1], corr[2], corr[3]);
    else
      XPBD::solve_IsometricBendingConstraint(x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3], Q,
                                             b.compliance[c], s.dt, b.lambda[c], corr[0],
                                             corr[1], corr[2], corr[3]);
  }
};

/// The proximity families: per-constraint rest distances in [0.2, 2.5] (so some constraints
/// are compressed, some stretched) and per-constraint compression and stretch stiffness.
template <class Batch>
void randomise_proximity(Batch& batch, std::size_t count, Random& r) {
  for (std::size_t c = 0; c < count; ++c) {
    batch.rest_distance[c] = uniform(r, 0.2, 2.5);
    batch.compression_stiffness[c] = random_stiffness(r);
    batch.stretch_stiffness[c] = random_stiffness(r);
  }
}

/// The indices of a set as proximity input (rest distances are randomised afterwards).
template <int N>
ProximityDistanceConstraintInput proximity_input(const ConstraintSet<N>& set) {
  ProximityDistanceConstraintInput input;
  input.particles = set.indices;
  input.particle_count = set.positions.size();
  return input;
}

/// A unit direction perpendicular to v.
Vector3r perpendicular(Random& r, const Vector3r& v) {
  for (;;) {
    const Vector3r u = r.unit_vector();
    const Vector3r p = u - u.dot(v) / v.squaredNorm() * v;
    if (p.norm() > Real(0.3)) return p.normalized();
  }
}

struct EdgePoint {
  static constexpr int N = 3;
  using Batch = EdgePointDistanceConstraints;
  static constexpr SemanticsSupport kSemantics = SemanticsSupport::stiffness_only;
  static constexpr bool kHasLambda = false;
  static constexpr std::array<int, N> kChainSlot = {0, 1, 2};

  /// p (slot 0) beside, before or beyond the segment p0-p1, never on it.
  static Points<N> random_shape(Random& r) {
    const Vector3r a = r.vector(-3, 3);
    const Vector3r edge = r.unit_vector() * uniform(r, 0.5, 2);
    const Vector3r p = a + uniform(r, -0.5, 1.5) * edge + uniform(r, 0.2, 1.5) * perpendicular(r, edge);
    return {p, a, a + edge};
  }
  static Batch build(const ConstraintSet<N>& set, const std::vector<Vector3r>&, Random& r) {
    Batch batch = make_edge_point_distance_constraints(proximity_input(set));
    randomise_proximity(batch, set.count, r);
    return batch;
  }
  static void batched(ParticleArrays p, Batch& b, std::size_t begin, std::size_t end,
                      const ProjectionSettings& s) {
    project_edge_point_distance_constraints(p, b, begin, end, s);
  }
  static void solve(Batch& b, std::size_t c, const Points<N>& x, const Masses<N>& w,
                    const ProjectionSettings&, Points<N>& corr) {
    PBD::solve_EdgePointDistanceConstraint(x[0], w[0], x[1], w[1], x[2], w[2], b.rest_distance[c],
                                           b.compression_stiffness[c], b.stretch_stiffness[c],
                                           corr[0], corr[1], corr[2]);
  }
};

struct TrianglePoint {
  static constexpr int N = 4;
  using Batch = TrianglePointDistanceConstraints;
  static constexpr SemanticsSupport kSemantics = SemanticsSupport::stiffness_only;
  static constexpr bool kHasLambda = false;
  static constexpr std::array<int, N> kChainSlot = {0, 1, 2, 3};

  /// p (slot 0) off the plane of a well-shaped triangle, above it or beside an edge.
  static Points<N> random_shape(Random& r) {
    const Points<3> t = rigidly_moved<3>(
        r, {Vector3r(0, 0, 0), Vector3r(uniform(r, 0.8, 1.5), 0, 0),
            Vector3r(uniform(r, 0, 1), uniform(r, 0.8, 1.5), 0)},
        3);
    const Vector3r normal = (t[1] - t[0]).cross(t[2] - t[0]).normalized();
    const Vector3r in_plane = t[0] + uniform(r, -0.3, 1) * (t[1] - t[0]) +
                              uniform(r, -0.3, 1) * (t[2] - t[0]);
    const Real side = r.integer(0, 1) == 0 ? Real(-1) : Real(1);
    return {in_plane + side * uniform(r, 0.2, 1.5) * normal, t[0], t[1], t[2]};
  }
  static Batch build(const ConstraintSet<N>& set, const std::vector<Vector3r>&, Random& r) {
    Batch batch = make_triangle_point_distance_constraints(proximity_input(set));
    randomise_proximity(batch, set.count, r);
    return batch;
  }
  static void batched(ParticleArrays p, Batch& b, std::size_t begin, std::size_t end,
                      const ProjectionSettings& s) {
    project_triangle_point_distance_constraints(p, b, begin, end, s);
  }
  static void solve(Batch& b, std::size_t c, const Points<N>& x, const Masses<N>& w,
                    const ProjectionSettings&, Points<N>& corr) {
    PBD::solve_TrianglePointDistanceConstraint(
        x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3], b.rest_distance[c],
        b.compression_stiffness[c], b.stretch_stiffness[c], corr[0], corr[1], corr[2], corr[3]);
  }
};

struct EdgeEdge {
  static constexpr int N = 4;
  using Batch = EdgeEdgeDistanceConstraints;
  static constexpr SemanticsSupport kSemantics = SemanticsSupport::stiffness_only;
  static constexpr bool kHasLambda = false;
  static constexpr std::array<int, N> kChainSlot = {0, 1, 2, 3};

  /// Two skew segments (p0-p1, p2-p3) at a distance in [0.2, 1.5].
  static Points<N> random_shape(Random& r) {
    const Vector3r a = r.vector(-3, 3);
    const Vector3r u = r.unit_vector();
    const Vector3r v = perpendicular(r, u);
    const Vector3r gap = u.cross(v).normalized() * uniform(r, 0.2, 1.5);
    const Vector3r b = a + gap + uniform(r, -0.8, 0.8) * u;
    const Vector3r direction = (v + uniform(r, -0.5, 0.5) * u).normalized();
    return {a - uniform(r, 0.3, 1) * u, a + uniform(r, 0.3, 1) * u,
            b - uniform(r, 0.3, 1) * direction, b + uniform(r, 0.3, 1) * direction};
  }
  static Batch build(const ConstraintSet<N>& set, const std::vector<Vector3r>&, Random& r) {
    Batch batch = make_edge_edge_distance_constraints(proximity_input(set));
    randomise_proximity(batch, set.count, r);
    return batch;
  }
  static void batched(ParticleArrays p, Batch& b, std::size_t begin, std::size_t end,
                      const ProjectionSettings& s) {
    project_edge_edge_distance_constraints(p, b, begin, end, s);
  }
  static void solve(Batch& b, std::size_t c, const Points<N>& x, const Masses<N>& w,
                    const ProjectionSettings&, Points<N>& corr) {
    PBD::solve_EdgeEdgeDistanceConstraint(
        x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3], b.rest_distance[c],
        b.compression_stiffness[c], b.stretch_stiffness[c], corr[0], corr[1], corr[2], corr[3]);
  }
};

struct StrainTriangle {
  static constexpr int N = 3;
  using Batch = StrainTriangleConstraints;
  static constexpr SemanticsSupport kSemantics = SemanticsSupport::pbd_for_both;
  static constexpr bool kHasLambda = false;
  static constexpr std::array<int, N> kChainSlot = {0, 1, 2};

  /// Roughly in the xy plane (the family's rest frame ignores z), never thin there.
  static Points<N> random_shape(Random& r) {
    const Vector3r a = r.vector(-5, 5);
    const Vector3r u(uniform(r, 0.6, 2), uniform(r, -0.3, 0.3), uniform(r, -1, 1));
    const Vector3r v(uniform(r, -0.3, 0.3), uniform(r, 0.6, 2), uniform(r, -1, 1));
    return {a, a + u, a + v};
  }
  static Batch build(const ConstraintSet<N>& set, const std::vector<Vector3r>& rest,
                     Random& r) {
    StrainTriangleConstraintInput input;
    input.particles = set.indices;
    input.rest_positions = rest;
    input.normalize_stretch = true;  // the two switches differ, so a swap shows
    input.normalize_shear = false;
    Batch batch = make_strain_triangle_constraints(input);
    for (std::size_t c = 0; c < set.count; ++c) {
      batch.xx_stiffness[c] = random_stiffness(r);
      batch.yy_stiffness[c] = random_stiffness(r);
      batch.xy_stiffness[c] = random_stiffness(r);
    }
    return batch;
  }
  static void batched(ParticleArrays p, Batch& b, std::size_t begin, std::size_t end,
                      const ProjectionSettings& s) {
    project_strain_triangle_constraints(p, b, begin, end, s);
  }
  static void solve(Batch& b, std::size_t c, const Points<N>& x, const Masses<N>& w,
                    const ProjectionSettings&, Points<N>& corr) {
    Matrix2r rest_inverse;
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j) rest_inverse(k, j) = b.rest_inverse[std::size_t(2 * k + j)][c];
    PBD::solve_StrainTriangleConstraint(x[0], w[0], x[1], w[1], x[2], w[2], rest_inverse,
                                        b.xx_stiffness[c], b.yy_stiffness[c], b.xy_stiffness[c],
                                        b.normalize_stretch, b.normalize_shear, corr[0], corr[1],
                                        corr[2]);
  }
};

struct StrainTetra {
  static constexpr int N = 4;
  using Batch = StrainTetraConstraints;
  static constexpr SemanticsSupport kSemantics = SemanticsSupport::pbd_for_both;
  static constexpr bool kHasLambda = false;
  static constexpr std::array<int, N> kChainSlot = {0, 1, 2, 3};

  static Points<N> random_shape(Random& r) { return random_tetrahedron(r); }
  static Batch build(const ConstraintSet<N>& set, const std::vector<Vector3r>& rest,
                     Random& r) {
    StrainTetraConstraintInput input;
    input.particles = set.indices;
    input.rest_positions = rest;
    input.normalize_stretch = false;
    input.normalize_shear = true;
    Batch batch = make_strain_tetra_constraints(input);
    for (std::size_t c = 0; c < set.count; ++c) {
      for (std::size_t axis = 0; axis < 3; ++axis) {
        batch.stretch_stiffness[axis][c] = random_stiffness(r);
        batch.shear_stiffness[axis][c] = random_stiffness(r);
      }
    }
    return batch;
  }
  static void batched(ParticleArrays p, Batch& b, std::size_t begin, std::size_t end,
                      const ProjectionSettings& s) {
    project_strain_tetra_constraints(p, b, begin, end, s);
  }
  static void solve(Batch& b, std::size_t c, const Points<N>& x, const Masses<N>& w,
                    const ProjectionSettings&, Points<N>& corr) {
    Matrix3r rest_inverse;
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j) rest_inverse(k, j) = b.rest_inverse[std::size_t(3 * k + j)][c];
    const Vector3r stretch(b.stretch_stiffness[0][c], b.stretch_stiffness[1][c],
                           b.stretch_stiffness[2][c]);
    const Vector3r shear(b.shear_stiffness[0][c], b.shear_stiffness[1][c],
                         b.shear_stiffness[2][c]);
    PBD::solve_StrainTetraConstraint(x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3],
                                     rest_inverse, stretch, shear, b.normalize_stretch,
                                     b.normalize_shear, corr[0], corr[1], corr[2], corr[3]);
  }
};

struct FEMTriangle {
  static constexpr int N = 3;
  using Batch = FEMTriangleConstraints;
  static constexpr SemanticsSupport kSemantics = SemanticsSupport::pbd_for_both;
  static constexpr bool kHasLambda = false;
  static constexpr std::array<int, N> kChainSlot = {0, 1, 2};

  static Points<N> random_shape(Random& r) {
    return rigidly_moved<3>(r, {Vector3r(0, 0, 0), Vector3r(uniform(r, 0.8, 1.5), 0, 0),
                                Vector3r(uniform(r, -0.2, 1), uniform(r, 0.8, 1.5), 0)});
  }
  /// A positive definite orthotropic material per constraint (E in [1, 2], ν in [0.1, 0.3]).
  static Batch build(const ConstraintSet<N>& set, const std::vector<Vector3r>& rest,
                     Random& r) {
    FEMTriangleConstraintInput input;
    input.particles = set.indices;
    input.rest_positions = rest;
    Batch batch = make_fem_triangle_constraints(input);
    for (std::size_t c = 0; c < set.count; ++c) {
      batch.youngs_modulus_x[c] = uniform(r, 1, 2);
      batch.youngs_modulus_y[c] = uniform(r, 1, 2);
      batch.youngs_modulus_shear[c] = uniform(r, 0.3, 1);
      batch.poisson_ratio_xy[c] = uniform(r, 0.1, 0.3);
      batch.poisson_ratio_yx[c] = uniform(r, 0.1, 0.3);
    }
    return batch;
  }
  static void batched(ParticleArrays p, Batch& b, std::size_t begin, std::size_t end,
                      const ProjectionSettings& s) {
    project_fem_triangle_constraints(p, b, begin, end, s);
  }
  static void solve(Batch& b, std::size_t c, const Points<N>& x, const Masses<N>& w,
                    const ProjectionSettings&, Points<N>& corr) {
    Matrix2r rest_inverse;
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j) rest_inverse(k, j) = b.rest_inverse[std::size_t(2 * k + j)][c];
    PBD::solve_FEMTriangleConstraint(x[0], w[0], x[1], w[1], x[2], w[2], b.area[c], rest_inverse,
                                     b.youngs_modulus_x[c], b.youngs_modulus_y[c],
                                     b.youngs_modulus_shear[c], b.poisson_ratio_xy[c],
                                     b.poisson_ratio_yx[c], corr[0], corr[1], corr[2]);
  }
};

struct FEMTetra {
  static constexpr int N = 4;
  using Batch = FEMTetraConstraints;
  static constexpr SemanticsSupport kSemantics = SemanticsSupport::pbd_and_xpbd;
  static constexpr bool kHasLambda = true;
  static constexpr std::array<int, N> kChainSlot = {0, 1, 2, 3};

  static Points<N> random_shape(Random& r) { return random_tetrahedron(r); }
  /// E in [5e3, 2e4] (compliance 1/E: α̃ of order 1 at dt = 1/120), ν in [0.1, 0.45].
  static Batch build(const ConstraintSet<N>& set, const std::vector<Vector3r>& rest,
                     Random& r) {
    FEMTetraConstraintInput input;
    input.particles = set.indices;
    input.rest_positions = rest;
    Batch batch = make_fem_tetra_constraints(input);
    for (std::size_t c = 0; c < set.count; ++c) {
      batch.youngs_modulus[c] = uniform(r, 5e3, 2e4);
      batch.compliance[c] = 1 / batch.youngs_modulus[c];
      batch.poisson_ratio[c] = uniform(r, 0.1, 0.45);
    }
    return batch;
  }
  static void batched(ParticleArrays p, Batch& b, std::size_t begin, std::size_t end,
                      const ProjectionSettings& s) {
    project_fem_tetra_constraints(p, b, begin, end, s);
  }
  static void solve(Batch& b, std::size_t c, const Points<N>& x, const Masses<N>& w,
                    const ProjectionSettings& s, Points<N>& corr) {
    Matrix3r rest_inverse;
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j) rest_inverse(k, j) = b.rest_inverse[std::size_t(3 * k + j)][c];
    if (s.semantics == ConstraintSemantics::stiffness)
      PBD::solve_FEMTetraConstraint(x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3], b.volume[c],
                                    rest_inverse, b.youngs_modulus[c], b.poisson_ratio[c],
                                    b.handle_inversion, corr[0], corr[1], corr[2], corr[3]);
    else
      XPBD::solve_FEMTetraConstraint(x[0], w[0], x[1], w[1], x[2], w[2], x[3], w[3],
                                     b.volume[c], rest_inverse, b.poisson_ratio[c],
                                     b.compliance[c], b.handle_inversion, s.dt, b.lambda[c],
                                     corr[0], corr[1], corr[2], corr[3]);
  }
};

/// The contact's constraintInfo as the batch stores it (the seed's layout).
Matrix3r contact_info(const ParticleTetContacts& b, std::size_t c) {
  Matrix3r info = Matrix3r::Zero();
  for (std::size_t k = 0; k < 3; ++k) {
    info(int(k), 0) = b.normal[k][c];
    info(int(k), 1) = b.tangent[k][c];
  }
  info(0, 2) = b.effective_mass[c];
  info(1, 2) = b.max_tangential_impulse[c];
  info(2, 2) = b.normal_speed[c];
  return info;
}

/// Tethers: reaches between 0.6 and 1.4 of the rest lengths, so a chain has stretched and
/// slack ones.
struct Tether {
  static constexpr int N = 2;
  using Batch = TetherConstraints;
  static constexpr SemanticsSupport kSemantics = SemanticsSupport::pbd_and_xpbd;
  static constexpr bool kHasLambda = true;
  static constexpr std::array<int, N> kChainSlot = {0, 1};

  static Points<N> random_shape(Random& r) { return Distance::random_shape(r); }
  static Batch build(const ConstraintSet<N>& set, const std::vector<Vector3r>& rest,
                     Random& r) {
    Batch batch = make_tether_constraints({set.indices, rest});
    for (std::size_t c = 0; c < set.count; ++c) {
      batch.max_distance[c] *= uniform(r, 0.6, 1.4);
      batch.stiffness[c] = random_stiffness(r);
      batch.compliance[c] = random_compliance(r);
    }
    return batch;
  }
  static void batched(ParticleArrays p, Batch& b, std::size_t begin, std::size_t end,
                      const ProjectionSettings& s) {
    project_tether_constraints(p, b, begin, end, s);
  }
  static void solve(Batch& b, std::size_t c, const Points<N>& x, const Masses<N>& w,
                    const ProjectionSettings& s, Points<N>& corr) {
    if (s.semantics == ConstraintSemantics::stiffness)
      PositionBasedDynamicsExtensions::solve_TetherConstraint(
          x[0], w[0], x[1], w[1], b.max_distance[c], b.stiffness[c], corr[0], corr[1]);
    else
      XPBDExtensions::solve_TetherConstraint(x[0], w[0], x[1], w[1], b.max_distance[c],
                                             b.compliance[c], s.dt, b.lambda[c], corr[0],
                                             corr[1]);
  }
};

struct Contact {
  static constexpr int N = 5;
  using Batch = ParticleTetContacts;
  static constexpr SemanticsSupport kSemantics = SemanticsSupport::pbd_for_both;
  static constexpr bool kHasLambda = true;
  static constexpr std::array<int, N> kChainSlot = {0, 1, 2, 3, 4};

  /// A particle (slot 0) near the top face of a jittered unit tet (slots 1..4).
  static Points<N> random_shape(Random& r) {
    const Vector3r origin = r.vector(-5, 5);
    Points<N> p = {Vector3r::Zero(), origin, origin + Vector3r(1, 0, 0),
                   origin + Vector3r(0, 1, 0), origin + Vector3r(0, 0, 1)};
    for (std::size_t k = 1; k < 5; ++k) p[k] += Real(0.05) * r.vector();
    p[0] = origin + Vector3r(Real(0.2), Real(0.2), uniform(r, -0.1, 0.4));
    return p;
  }
  /// Random velocities (for init_), barycentric coordinates in [0.1, 0.3]³ and a unit normal
  /// near the direction from the particle to its contact point, so most contacts push.
  static Batch build(const ConstraintSet<N>& set, const std::vector<Vector3r>&, Random& r) {
    ParticleState state(set.positions, set.inverse_masses);
    for (std::size_t i = 0; i < set.positions.size(); ++i) {
      const Vector3r v = r.vector(-2, 2);
      state.velocity_x[i] = v.x();
      state.velocity_y[i] = v.y();
      state.velocity_z[i] = v.z();
    }
    std::vector<Vector3r> barycentric, normals;
    for (std::size_t c = 0; c < set.count; ++c) {
      const Vector3r b(uniform(r, 0.1, 0.3), uniform(r, 0.1, 0.3), uniform(r, 0.1, 0.3));
      const Points<N> x = set.points(c);
      const Vector3r contact = (1 - b.sum()) * x[1] + b[0] * x[2] + b[1] * x[3] + b[2] * x[4];
      Vector3r towards = contact - x[0];
      towards = towards.norm() > Real(0.05) ? Vector3r(towards.normalized()) : r.unit_vector();
      barycentric.push_back(b);
      normals.push_back((towards + Real(0.5) * r.unit_vector()).normalized());
    }
    return make_particle_tet_contacts({set.indices, barycentric, normals, Real(0.4)}, state);
  }
  static void batched(ParticleArrays p, Batch& b, std::size_t begin, std::size_t end,
                      const ProjectionSettings&) {
    project_particle_tet_contacts(p, b, begin, end);
  }
  static void solve(Batch& b, std::size_t c, const Points<N>& x, const Masses<N>& w,
                    const ProjectionSettings&, Points<N>& corr) {
    Matrix3r info = contact_info(b, c);
    const Vector3r bary(b.barycentric[0][c], b.barycentric[1][c], b.barycentric[2][c]);
    PBD::solve_ParticleTetContactConstraint(w[0], x[0], w.data() + 1, x.data() + 1, bary, info,
                                            b.lambda[c], corr[0], corr.data() + 1);
  }
};

/// Collider contacts: one particle each, a random plane through a point up to 0.3 above it
/// (so most push) and its rest position as the anchor (so friction has sliding to act on).
/// A chain puts two contacts on each particle (two colliders meeting at it): one-particle
/// constraints share particles no other way.
struct ColliderContact {
  static constexpr int N = 1;
  using Batch = ColliderContacts;
  static constexpr SemanticsSupport kSemantics = SemanticsSupport::pbd_for_both;
  static constexpr bool kHasLambda = true;
  static constexpr std::array<int, N> kChainSlot = {0};
  static constexpr std::size_t kConstraintsPerParticle = 2;

  static Points<N> random_shape(Random& r) { return {r.vector(-5, 5)}; }
  static Batch build(const ConstraintSet<N>& set, const std::vector<Vector3r>& rest,
                     Random& r) {
    std::vector<Vector3r> normals, anchors;
    std::vector<Real> offsets, speeds;
    for (std::size_t c = 0; c < set.count; ++c) {
      const Vector3r n = r.unit_vector();
      normals.push_back(n);
      offsets.push_back(n.dot(set.points(c)[0]) + uniform(r, -0.05, 0.3));
      anchors.push_back(rest[set.indices[c]]);
      speeds.push_back(uniform(r, -2, 1));
    }
    Batch batch = make_collider_contacts(
        {set.indices, set.positions.size(), normals, offsets, anchors, speeds});
    for (std::size_t c = 0; c < set.count; ++c) {
      batch.static_friction[c] = uniform(r, 0, 1);
      batch.dynamic_friction[c] = uniform(r, 0, 1) * batch.static_friction[c];
    }
    return batch;
  }
  static void batched(ParticleArrays p, Batch& b, std::size_t begin, std::size_t end,
                      const ProjectionSettings&) {
    project_collider_contacts(p, b, begin, end);
  }
  static void solve(Batch& b, std::size_t c, const Points<N>& x, const Masses<N>& w,
                    const ProjectionSettings&, Points<N>& corr) {
    PositionBasedDynamicsExtensions::solve_ColliderContactConstraint(
        x[0], w[0], Vector3r(b.normal[0][c], b.normal[1][c], b.normal[2][c]), b.offset[c],
        Vector3r(b.anchor[0][c], b.anchor[1][c], b.anchor[2][c]), b.static_friction[c],
        b.dynamic_friction[c], b.lambda[c], corr[0]);
  }
};

// ----------------------------------------------------------------------------- helpers

template <class F>
std::vector<ConstraintSemantics> semantics_of() {
  if (F::kSemantics == SemanticsSupport::stiffness_only) return {ConstraintSemantics::stiffness};
  return {ConstraintSemantics::stiffness, ConstraintSemantics::compliance};
}

std::vector<Vector3r> positions_of(const ParticleState& state) {
  std::vector<Vector3r> p(state.size());
  for (std::size_t i = 0; i < state.size(); ++i) p[i] = state.position(i);
  return p;
}

/// Every particle moved by up to `amount` per coordinate.
std::vector<Vector3r> perturbed(std::vector<Vector3r> points, Random& random, Real amount) {
  for (Vector3r& p : points) p += amount * random.vector();
  return points;
}

/// A chain of `count` constraints along a helix: constraint c uses the N consecutive particles
/// from s = c / constraints_per_particle<F>() (slot k ← particle s + kChainSlot[k]), so
/// neighbours share N - 1 particles (or, one per particle, all of them).
/// Every seventh particle is static, and the first sits at x = -0 (a write of +0 to it would
/// show in its sign bit). `rest` receives rest positions on a slightly different helix.
Vector3r helix(std::size_t i) {
  const Real t = Real(2) * Real(i);
  return Vector3r(std::cos(t), std::sin(t), Real(0.35) * Real(i));
}

/// How many consecutive constraints of a chain start at the same particle: 1, or the family's
/// kConstraintsPerParticle (a one-particle family shares particles only that way).
template <class F>
constexpr std::size_t constraints_per_particle() {
  if constexpr (requires { F::kConstraintsPerParticle; })
    return F::kConstraintsPerParticle;
  else
    return 1;
}

template <class F>
ConstraintSet<F::N> make_chain(Random& random, std::size_t count, std::vector<Vector3r>& rest) {
  constexpr std::size_t N = std::size_t(F::N);
  ConstraintSet<F::N> chain;
  chain.count = count;
  const std::size_t particles = count + N - 1;
  rest.clear();
  for (std::size_t i = 0; i < particles; ++i) {
    chain.positions.push_back(Real(1.1) * helix(i) + Real(0.05) * random.vector());
    chain.inverse_masses.push_back(i % 7 == 0 ? Real(0) : random.inverse_mass());
    rest.push_back(helix(i) + Real(0.05) * random.vector());
  }
  chain.positions[0].x() = -Real(0);
  for (std::size_t c = 0; c < count; ++c)
    for (std::size_t k = 0; k < N; ++k)
      chain.indices.push_back(
          ParticleIndex(c / constraints_per_particle<F>() + std::size_t(F::kChainSlot[k])));
  return chain;
}

/// The hand-written reference: the scalar API on constraints [begin, end) one after another
/// (backwards when `reverse`), each correction added to its particle (movable only) before
/// the next constraint reads the positions.
template <class F>
void scalar_loop(typename F::Batch& batch, const ConstraintSet<F::N>& set, std::size_t begin,
                 std::size_t end, const ProjectionSettings& settings,
                 std::vector<Vector3r>& x, bool reverse = false) {
  constexpr std::size_t N = std::size_t(F::N);
  for (std::size_t n = begin; n < end; ++n) {
    const std::size_t c = reverse ? end - 1 - (n - begin) : n;
    Points<F::N> p;
    Masses<F::N> w;
    for (std::size_t k = 0; k < N; ++k) {
      p[k] = x[set.indices[N * c + k]];
      w[k] = set.inverse_masses[set.indices[N * c + k]];
    }
    Points<F::N> corr;
    F::solve(batch, c, p, w, settings, corr);
    for (std::size_t k = 0; k < N; ++k)
      if (w[k] > 0) x[set.indices[N * c + k]] += corr[k];
  }
}

/// Makes particles movable until every constraint has two movable ones. A constraint with
/// a single movable particle can have a nearly vanishing gradient there (e.g. a normalised
/// strain shear), and then one PBD step moves it hundreds of units: both paths follow the
/// formula, but that step amplifies their rounding difference beyond any fixed tolerance.
/// Particles shared between constraints (the shared static ones) are left static.
template <int N>
void at_least_two_movable(ConstraintSet<N>& set, Random& random) {
  std::vector<int> uses(set.positions.size(), 0);
  for (ParticleIndex i : set.indices) ++uses[i];
  for (std::size_t c = 0; c < set.count; ++c) {
    const ParticleIndex* i = &set.indices[std::size_t(N) * c];
    int movable = 0;
    for (int k = 0; k < N; ++k) movable += set.inverse_masses[i[k]] > 0 ? 1 : 0;
    for (int k = 0; k < N && movable < 2; ++k) {
      if (set.inverse_masses[i[k]] == 0 && uses[i[k]] == 1) {
        set.inverse_masses[i[k]] = random.inverse_mass();
        ++movable;
      }
    }
  }
}

template <class Batch>
void fill_lambda(Batch& batch, std::size_t count, Real value) {
  std::fill(batch.lambda.begin(), batch.lambda.begin() + long(count), value);
}

/// Bitwise equality of one particle's coordinates (tells -0 from +0).
bool same_bits(const ParticleState& state, std::size_t i, const Vector3r& expected) {
  const Real now[3] = {state.x[i], state.y[i], state.z[i]};
  const Real then[3] = {expected.x(), expected.y(), expected.z()};
  return std::memcmp(now, then, sizeof now) == 0;
}

// ------------------------------------------------------------------------ the typed suite

template <class F>
class SequentialProjection : public ::testing::Test {};

using Families = ::testing::Types<Distance, Dihedral, Volume, IsometricBending, EdgePoint,
                                  TrianglePoint, EdgeEdge, StrainTriangle, StrainTetra,
                                  FEMTriangle, FEMTetra, Contact, Tether, ColliderContact>;

class FamilyNames {
 public:
  template <class F>
  static std::string GetName(int) {
    if (std::is_same_v<F, Distance>) return "Distance";
    if (std::is_same_v<F, Dihedral>) return "Dihedral";
    if (std::is_same_v<F, Volume>) return "Volume";
    if (std::is_same_v<F, IsometricBending>) return "IsometricBending";
    if (std::is_same_v<F, EdgePoint>) return "EdgePointDistance";
    if (std::is_same_v<F, TrianglePoint>) return "TrianglePointDistance";
    if (std::is_same_v<F, EdgeEdge>) return "EdgeEdgeDistance";
    if (std::is_same_v<F, StrainTriangle>) return "StrainTriangle";
    if (std::is_same_v<F, StrainTetra>) return "StrainTetra";
    if (std::is_same_v<F, FEMTriangle>) return "FEMTriangle";
    if (std::is_same_v<F, FEMTetra>) return "FEMTetra";
    if (std::is_same_v<F, Tether>) return "Tether";
    if (std::is_same_v<F, ColliderContact>) return "ColliderContact";
    return "ParticleTetContact";
  }
};

TYPED_TEST_SUITE(SequentialProjection, Families, FamilyNames);

/// 1. Constraints that share no movable particle: the sequential loop and the batched kernel
/// evaluate the same formula on the same positions, so they agree to rounding (positions and
/// λ), on every SIMD target the batched kernel has; λ outside the range is untouched.
TYPED_TEST(SequentialProjection, MatchesTheBatchedKernelOnConstraintsSharingNoParticle) {
  using F = TypeParam;
  test::for_each_simd_target([](const std::string&) {
    for (unsigned seed = 1; seed <= 4; ++seed) {
      Random random(seed);
      const std::size_t count = std::size_t(random.integer(1, 200));
      auto set = test::make_disjoint_constraints<F::N>(random, count, Real(0.2), F::random_shape);
      at_least_two_movable(set, random);
      const std::vector<Vector3r> rest = perturbed(set.positions, random, Real(0.15));
      const typename F::Batch built = F::build(set, rest, random);
      const auto [begin, end] = test::random_range(random, count);
      for (const ConstraintSemantics semantics : semantics_of<F>()) {
        SCOPED_TRACE(semantics == ConstraintSemantics::stiffness ? "stiffness" : "compliance");
        const ProjectionSettings settings{semantics, kTimeStep};
        typename F::Batch sequential = built, batched = built;
        if constexpr (F::kHasLambda) {
          fill_lambda(sequential, count, Real(0.25));
          fill_lambda(batched, count, Real(0.25));
        }
        ParticleState by_sequence(set.positions, set.inverse_masses), by_batch = by_sequence;
        project_sequentially(ParticleArrays::of(by_sequence), sequential, begin, end, settings);
        F::batched(ParticleArrays::of(by_batch), batched, begin, end, settings);
        EXPECT_TRUE(test::positions_match(by_sequence, positions_of(by_batch), 10));
        if constexpr (F::kHasLambda) {
          for (std::size_t c = 0; c < count; ++c) {
            if (c >= begin && c < end) {
              EXPECT_NEAR(sequential.lambda[c], batched.lambda[c],
                          test::kBatchTolerance * (1 + std::abs(batched.lambda[c])))
                  << "constraint " << c;
            } else {
              EXPECT_EQ(sequential.lambda[c], Real(0.25)) << "λ outside the range changed";
            }
          }
        }
      }
    }
  });
}

/// 2. A chain whose neighbours share N - 1 particles: the sequential loop is exactly the
/// scalar API called in input order with each correction applied at once (bitwise, positions
/// and λ, over two sweeps of the whole chain and of a sub-range); the same loop run backwards
/// ends elsewhere, so the comparison does see the order. Particles of constraints outside the
/// sub-range keep their bits.
TYPED_TEST(SequentialProjection, SharedParticlesFollowTheScalarApiInInputOrder) {
  using F = TypeParam;
  constexpr std::size_t N = std::size_t(F::N);
  Random random(11);
  const std::size_t count = 40;
  std::vector<Vector3r> rest;
  const auto chain = make_chain<F>(random, count, rest);
  const typename F::Batch built = F::build(chain, rest, random);
  for (const auto& [begin, end] :
       {std::pair<std::size_t, std::size_t>{0, count}, std::pair<std::size_t, std::size_t>{7, 29}}) {
    for (const ConstraintSemantics semantics : semantics_of<F>()) {
      SCOPED_TRACE((semantics == ConstraintSemantics::stiffness ? "stiffness, range " :
                                                                  "compliance, range ") +
                   std::to_string(begin) + ".." + std::to_string(end));
      const ProjectionSettings settings{semantics, kTimeStep};
      typename F::Batch sequential = built, reference = built, backwards = built;
      if constexpr (F::kHasLambda) {
        fill_lambda(sequential, count, Real(0.25));
        fill_lambda(reference, count, Real(0.25));
        fill_lambda(backwards, count, Real(0.25));
      }
      ParticleState state(chain.positions, chain.inverse_masses);
      std::vector<Vector3r> expected = chain.positions, reversed = chain.positions;
      for (int sweep = 0; sweep < 2; ++sweep) {
        project_sequentially(ParticleArrays::of(state), sequential, begin, end, settings);
        scalar_loop<F>(reference, chain, begin, end, settings, expected);
        scalar_loop<F>(backwards, chain, begin, end, settings, reversed, true);
      }
      bool moved = false, order_matters = false;
      for (std::size_t i = 0; i < expected.size(); ++i) {
        EXPECT_TRUE(same_bits(state, i, expected[i]))
            << "particle " << i << ": " << state.position(i).transpose() << " vs "
            << expected[i].transpose();
        moved = moved || expected[i] != chain.positions[i];
        order_matters = order_matters || reversed[i] != expected[i];
      }
      EXPECT_TRUE(moved) << "the chain was already satisfied: the test shows nothing";
      EXPECT_TRUE(order_matters) << "input order and reverse order agree: the test shows nothing";
      // Only particles of constraints [begin, end) may have moved.
      std::vector<bool> in_range(expected.size(), false);
      for (std::size_t c = begin; c < end; ++c)
        for (std::size_t k = 0; k < N; ++k) in_range[chain.indices[N * c + k]] = true;
      for (std::size_t i = 0; i < expected.size(); ++i)
        if (!in_range[i]) {
          EXPECT_TRUE(same_bits(state, i, chain.positions[i])) << i;
        }
      if constexpr (F::kHasLambda) {
        for (std::size_t c = 0; c < count; ++c) {
          EXPECT_EQ(std::memcmp(&sequential.lambda[c], &reference.lambda[c], sizeof(Real)), 0)
              << "λ of constraint " << c;
          if (c < begin || c >= end) {
            EXPECT_EQ(sequential.lambda[c], Real(0.25));
          }
        }
      }
    }
  }
  // Families without an XPBD form use their PBD form under either semantics.
  if constexpr (F::kSemantics == SemanticsSupport::pbd_for_both) {
    typename F::Batch stiff = built, compliant = built;
    ParticleState a(chain.positions, chain.inverse_masses), b = a;
    project_sequentially(ParticleArrays::of(a), stiff, 0, count,
                         {ConstraintSemantics::stiffness, kTimeStep});
    project_sequentially(ParticleArrays::of(b), compliant, 0, count,
                         {ConstraintSemantics::compliance, kTimeStep});
    EXPECT_TRUE(test::same_bits(a, b));
  }
}

/// 3a. Static particles keep their exact bits (including the -0 of the first) through three
/// sweeps under every semantics.
TYPED_TEST(SequentialProjection, StaticParticlesAreNeverWritten) {
  using F = TypeParam;
  Random random(5);
  std::vector<Vector3r> rest;
  const auto chain = make_chain<F>(random, 30, rest);
  typename F::Batch batch = F::build(chain, rest, random);
  ParticleState state(chain.positions, chain.inverse_masses);
  for (int sweep = 0; sweep < 3; ++sweep)
    for (const ConstraintSemantics semantics : semantics_of<F>())
      project_sequentially(ParticleArrays::of(state), batch, 0, 30, {semantics, kTimeStep});
  bool moved = false;
  for (std::size_t i = 0; i < chain.positions.size(); ++i) {
    if (chain.inverse_masses[i] == 0) {
      EXPECT_TRUE(same_bits(state, i, chain.positions[i])) << "static particle " << i;
    } else {
      moved = moved || state.position(i) != chain.positions[i];
    }
  }
  EXPECT_TRUE(std::signbit(state.x[0]));
  EXPECT_TRUE(moved);
}

/// 3b. An empty range writes nothing; a range outside the batch, a reversed range and
/// particle arrays with fewer particles than the batch was built for throw InvalidInput;
/// the proximity families refuse compliance semantics as their batched kernels do.
TYPED_TEST(SequentialProjection, EmptyAndBadRangesAreHandledAtTheDoor) {
  using F = TypeParam;
  Random random(3);
  std::vector<Vector3r> rest;
  const auto chain = make_chain<F>(random, 10, rest);
  typename F::Batch batch = F::build(chain, rest, random);
  ParticleState state(chain.positions, chain.inverse_masses);
  const ParticleState before = state;
  const ProjectionSettings settings{};
  project_sequentially(ParticleArrays::of(state), batch, 4, 4, settings);
  project_sequentially(ParticleArrays::of(state), batch, 10, 10, settings);
  EXPECT_TRUE(test::same_bits(state, before));
  EXPECT_THROW(project_sequentially(ParticleArrays::of(state), batch, 0, 11, settings),
               InvalidInput);
  EXPECT_THROW(project_sequentially(ParticleArrays::of(state), batch, 6, 5, settings),
               InvalidInput);
  ParticleArrays too_few = ParticleArrays::of(state);
  too_few.count = chain.positions.size() - 1;
  EXPECT_THROW(project_sequentially(too_few, batch, 0, 10, settings), InvalidInput);
  if constexpr (F::kSemantics == SemanticsSupport::stiffness_only) {
    const ProjectionSettings compliance{ConstraintSemantics::compliance, kTimeStep};
    EXPECT_THROW(project_sequentially(ParticleArrays::of(state), batch, 0, 10, compliance),
                 InvalidInput);
    EXPECT_THROW(F::batched(ParticleArrays::of(state), batch, 0, 10, compliance), InvalidInput);
  }
  EXPECT_TRUE(test::same_bits(state, before));
}

// ------------------------------------------------------------------- contacts: constraintInfo

/// The constraintInfo the loop rebuilds from the batch is the one the classic library keeps
/// from init_ParticleTetContactConstraint: the sequential loop equals the classic loop over
/// init_'s matrices (to rounding: the batch's init runs on SIMD lanes).
TEST(SequentialProjectionContacts, EqualsTheClassicLoopOverInitConstraintInfo) {
  Random random(21);
  std::vector<Vector3r> rest;
  const auto chain = make_chain<Contact>(random, 30, rest);
  ParticleState state(chain.positions, chain.inverse_masses);
  std::vector<Vector3r> velocities;
  for (std::size_t i = 0; i < chain.positions.size(); ++i) {
    velocities.push_back(random.vector(-2, 2));
    state.velocity_x[i] = velocities.back().x();
    state.velocity_y[i] = velocities.back().y();
    state.velocity_z[i] = velocities.back().z();
  }
  std::vector<Vector3r> barycentric, normals;
  for (std::size_t c = 0; c < 30; ++c) {
    barycentric.emplace_back(uniform(random, 0.1, 0.3), uniform(random, 0.1, 0.3),
                             uniform(random, 0.1, 0.3));
    normals.push_back(random.unit_vector());
  }
  ParticleTetContacts contacts =
      make_particle_tet_contacts({chain.indices, barycentric, normals, Real(0.3)}, state);
  // The classic loop: init_ once per contact, then solve_ with that matrix and its own λ.
  std::vector<Matrix3r> info(30);
  std::vector<Real> lambda(30, 0);
  for (std::size_t c = 0; c < 30; ++c) {
    Real w[4];
    Vector3r x[4], v[4];
    const ParticleIndex* i = &chain.indices[5 * c];
    for (int k = 0; k < 4; ++k) {
      w[k] = chain.inverse_masses[i[k + 1]];
      x[k] = chain.positions[i[k + 1]];
      v[k] = velocities[i[k + 1]];
    }
    PBD::init_ParticleTetContactConstraint(chain.inverse_masses[i[0]], chain.positions[i[0]],
                                           velocities[i[0]], w, x, v, barycentric[c], normals[c],
                                           info[c]);
  }
  std::vector<Vector3r> expected = chain.positions;
  for (int sweep = 0; sweep < 2; ++sweep) {
    project_sequentially(ParticleArrays::of(state), contacts, 0, 30);
    for (std::size_t c = 0; c < 30; ++c) {
      const ParticleIndex* i = &chain.indices[5 * c];
      Real w[4];
      Vector3r x[4], corr[4], corr0;
      for (int k = 0; k < 4; ++k) {
        w[k] = chain.inverse_masses[i[k + 1]];
        x[k] = expected[i[k + 1]];
      }
      const Real w0 = chain.inverse_masses[i[0]];
      PBD::solve_ParticleTetContactConstraint(w0, expected[i[0]], w, x, barycentric[c], info[c],
                                              lambda[c], corr0, corr);
      if (w0 > 0) expected[i[0]] += corr0;
      for (int k = 0; k < 4; ++k)
        if (w[k] > 0) expected[i[k + 1]] += corr[k];
    }
  }
  EXPECT_TRUE(test::positions_match(state, expected, 10));
  for (std::size_t c = 0; c < 30; ++c)
    EXPECT_NEAR(contacts.lambda[c], lambda[c], test::kBatchTolerance * (1 + lambda[c])) << c;
}

// -------------------------------------------------------------------------- shape matching

/// Clusters in CSR form, with their rest and current positions.
struct ClusterScene {
  std::vector<Vector3r> rest, current;
  std::vector<Real> inverse_masses;
  std::vector<std::uint32_t> offsets = {0};
  std::vector<ParticleIndex> particles;

  std::size_t count() const { return offsets.size() - 1; }
  void close_cluster() { offsets.push_back(std::uint32_t(particles.size())); }
};

/// Disjoint clusters of 6..20 particles, each moved rigidly (plus noise, plus a stretch when
/// allow_stretch) from its rest shape; about one cluster in three has one static particle.
/// (Not more: two static particles weigh 1000 times a movable one each and make A_pq so
/// ill-conditioned that float rounding alone moves both paths' results by ~1e-4.)
ClusterScene disjoint_clusters(Random& random, std::size_t count, bool allow_stretch) {
  ClusterScene scene;
  for (std::size_t c = 0; c < count; ++c) {
    const Vector3r centre = random.vector(-5, 5);
    const Matrix3r rotation = random.rotation();
    Matrix3r deformation = rotation;
    if (allow_stretch)
      deformation = rotation * Matrix3r(Vector3r(uniform(random, 0.8, 1.2),
                                                 uniform(random, 0.8, 1.2), 1)
                                            .asDiagonal());
    const Vector3r shift = random.vector(-1, 1);
    const int size = random.integer(6, 20);
    const int static_slot = random.uniform(0, 1) < Real(0.35) ? random.integer(0, size - 1) : -1;
    for (int k = 0; k < size; ++k) {
      const Vector3r x0 = centre + random.vector(-1, 1);
      scene.particles.push_back(ParticleIndex(scene.rest.size()));
      scene.rest.push_back(x0);
      scene.current.push_back(deformation * (x0 - centre) + centre + shift +
                              Real(0.1) * random.vector());
      scene.inverse_masses.push_back(k == static_slot ? Real(0) : random.inverse_mass());
    }
    scene.close_cluster();
  }
  return scene;
}

/// Overlapping clusters along a strip: cluster c holds particles 3c .. 3c+7, so neighbours
/// share five particles; every seventh particle is static, the first at x = -0.
ClusterScene overlapping_clusters(Random& random, std::size_t count) {
  ClusterScene scene;
  const std::size_t particle_count = 3 * count + 5;
  const Matrix3r twist = Eigen::AngleAxis<Real>(Real(0.3), Vector3r::UnitX()).toRotationMatrix();
  for (std::size_t i = 0; i < particle_count; ++i) {
    const Vector3r x0(Real(0.4) * Real(i), uniform(random, -1, 1), uniform(random, -1, 1));
    scene.rest.push_back(x0);
    scene.current.push_back(twist * x0 + Real(0.1) * random.vector());
    scene.inverse_masses.push_back(i % 7 == 0 ? Real(0) : random.inverse_mass());
  }
  scene.current[0].x() = -Real(0);
  for (std::size_t c = 0; c < count; ++c) {
    for (std::size_t k = 0; k < 8; ++k) scene.particles.push_back(ParticleIndex(3 * c + k));
    scene.close_cluster();
  }
  return scene;
}

ShapeMatchingConstraints build_clusters(const ClusterScene& scene, bool allow_stretch,
                                        Random& random) {
  ShapeMatchingConstraints batch = make_shape_matching_constraints(
      {scene.offsets, scene.particles, scene.rest, scene.inverse_masses, 1, allow_stretch});
  for (std::size_t c = 0; c < scene.count(); ++c) batch.stiffness[c] = random_stiffness(random);
  return batch;
}

/// The scalar API cluster by cluster on `x`. With `classic`, the classic library's arguments:
/// the rest positions themselves and restCm from init_ShapeMatchingConstraint; otherwise the
/// batch's rest offsets with restCm = 0 (what project_sequentially passes).
void scalar_cluster_loop(const ClusterScene& scene, const ShapeMatchingConstraints& batch,
                         std::size_t begin, std::size_t end, std::vector<Vector3r>& x,
                         bool classic) {
  for (std::size_t c = begin; c < end; ++c) {
    std::vector<Vector3r> x0, xc, corr;
    std::vector<Real> w;
    for (std::size_t e = scene.offsets[c]; e < scene.offsets[c + 1]; ++e) {
      const ParticleIndex p = scene.particles[e];
      x0.push_back(classic ? scene.rest[p]
                           : Vector3r(batch.rest_offset[0][e], batch.rest_offset[1][e],
                                      batch.rest_offset[2][e]));
      xc.push_back(x[p]);
      w.push_back(scene.inverse_masses[p]);
    }
    const int n = int(x0.size());
    corr.resize(x0.size());
    Vector3r rest_centre = Vector3r::Zero();
    if (classic) PBD::init_ShapeMatchingConstraint(x0.data(), w.data(), n, rest_centre);
    PBD::solve_ShapeMatchingConstraint(x0.data(), xc.data(), w.data(), n, rest_centre,
                                       batch.stiffness[c], batch.allow_stretch, corr.data());
    for (std::size_t k = 0; k < x0.size(); ++k)
      if (w[k] > 0) x[scene.particles[scene.offsets[c] + k]] += corr[k];
  }
}

/// 1. Disjoint clusters, rigid and with stretch: the batched kernel's result (its rotation
/// comes from a polar iteration, the scalar API's from an SVD: equal to rounding), on every
/// SIMD target; and a single cluster against the classic init_ + solve_ with the original
/// rest positions.
TEST(SequentialProjectionShapeMatching, MatchesTheBatchedKernelOnDisjointClusters) {
  test::for_each_simd_target([](const std::string&) {
    for (const bool allow_stretch : {false, true}) {
      for (unsigned seed = 1; seed <= 4; ++seed) {
        Random random(seed + (allow_stretch ? 50u : 0u));
        const std::size_t count = std::size_t(random.integer(1, 80));
        const ClusterScene scene = disjoint_clusters(random, count, allow_stretch);
        const ShapeMatchingConstraints batch = build_clusters(scene, allow_stretch, random);
        const auto [begin, end] = test::random_range(random, count);
        ParticleState by_sequence(scene.current, scene.inverse_masses), by_batch = by_sequence;
        project_sequentially(ParticleArrays::of(by_sequence), batch, begin, end);
        ShapeMatchingConstraints batched = batch;
        project_shape_matching_constraints(ParticleArrays::of(by_batch), batched, begin, end);
        EXPECT_TRUE(test::positions_match(by_sequence, positions_of(by_batch), 10))
            << "stretch " << allow_stretch << ", seed " << seed;
      }
    }
  });
}

TEST(SequentialProjectionShapeMatching, OneClusterMatchesTheClassicInitAndSolve) {
  for (const bool allow_stretch : {false, true}) {
    for (unsigned seed = 1; seed <= 10; ++seed) {
      Random random(seed + 200);
      const ClusterScene scene = disjoint_clusters(random, 1, allow_stretch);
      const ShapeMatchingConstraints batch = build_clusters(scene, allow_stretch, random);
      ParticleState state(scene.current, scene.inverse_masses);
      project_sequentially(ParticleArrays::of(state), batch, 0, 1);
      std::vector<Vector3r> expected = scene.current;
      scalar_cluster_loop(scene, batch, 0, 1, expected, true);
      EXPECT_TRUE(test::positions_match(state, expected, 10)) << "stretch " << allow_stretch;
    }
  }
}

/// 2. Overlapping clusters: bitwise the scalar API in input order (the loop's own arguments),
/// different backwards, and to rounding the classic library's loop (rest positions and
/// init_'s restCm); only particles of the range's clusters move, static ones never.
TEST(SequentialProjectionShapeMatching, OverlappingClustersFollowTheScalarApiInInputOrder) {
  for (const bool allow_stretch : {false, true}) {
    Random random(allow_stretch ? 9 : 8);
    const std::size_t count = 20;
    const ClusterScene scene = overlapping_clusters(random, count);
    const ShapeMatchingConstraints batch = build_clusters(scene, allow_stretch, random);
    for (const auto& [begin, end] : {std::pair<std::size_t, std::size_t>{0, count},
                                     std::pair<std::size_t, std::size_t>{5, 13}}) {
      ParticleState state(scene.current, scene.inverse_masses);
      std::vector<Vector3r> expected = scene.current, classic = scene.current;
      for (int sweep = 0; sweep < 2; ++sweep) {
        project_sequentially(ParticleArrays::of(state), batch, begin, end);
        scalar_cluster_loop(scene, batch, begin, end, expected, false);
        scalar_cluster_loop(scene, batch, begin, end, classic, true);
      }
      std::vector<Vector3r> backwards = scene.current;
      for (int sweep = 0; sweep < 2; ++sweep)
        for (std::size_t c = end; c-- > begin;)
          scalar_cluster_loop(scene, batch, c, c + 1, backwards, false);
      std::vector<bool> in_range(scene.rest.size(), false);
      for (std::size_t e = scene.offsets[begin]; e < scene.offsets[end]; ++e)
        in_range[scene.particles[e]] = true;
      bool order_matters = false;
      for (std::size_t i = 0; i < expected.size(); ++i) {
        EXPECT_TRUE(same_bits(state, i, expected[i])) << "particle " << i;
        if (!in_range[i] || scene.inverse_masses[i] == 0) {
          EXPECT_TRUE(same_bits(state, i, scene.current[i])) << "particle " << i;
        }
        order_matters = order_matters || backwards[i] != expected[i];
      }
      EXPECT_TRUE(order_matters) << "input order and reverse order agree: the test shows nothing";
      EXPECT_TRUE(test::positions_match(state, classic, 10));
      EXPECT_TRUE(std::signbit(state.x[0]));
    }
  }
}

/// 3. Empty and bad ranges, too few particles.
TEST(SequentialProjectionShapeMatching, EmptyAndBadRangesAreHandledAtTheDoor) {
  Random random(4);
  const ClusterScene scene = overlapping_clusters(random, 6);
  const ShapeMatchingConstraints batch = build_clusters(scene, false, random);
  ParticleState state(scene.current, scene.inverse_masses);
  const ParticleState before = state;
  project_sequentially(ParticleArrays::of(state), batch, 3, 3);
  EXPECT_TRUE(test::same_bits(state, before));
  EXPECT_THROW(project_sequentially(ParticleArrays::of(state), batch, 0, 7), InvalidInput);
  EXPECT_THROW(project_sequentially(ParticleArrays::of(state), batch, 4, 2), InvalidInput);
  ParticleArrays too_few = ParticleArrays::of(state);
  too_few.count = scene.rest.size() - 1;
  EXPECT_THROW(project_sequentially(too_few, batch, 0, 6), InvalidInput);
  EXPECT_TRUE(test::same_bits(state, before));
}

}  // namespace sequential_projection_tests
}  // namespace tessera
