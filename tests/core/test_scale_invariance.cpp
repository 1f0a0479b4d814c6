// Degenerate rest shapes are judged relative to their size: a well-shaped triangle,
// tetrahedron or bending stencil shrunk to millimetres (a 1 m cloth of 1000 × 1000 cells, a
// 1 cm tetrahedral grid) is accepted by every init function and batch builder, and the
// dihedral kernel projects it exactly as the metre-sized one, scaled. A genuinely flat shape
// is still rejected at every scale.
#include <gtest/gtest.h>

#include <array>
#include <vector>

#include <tessera/core/dihedral_constraints.hpp>
#include <tessera/core/fem_tetra_constraints.hpp>
#include <tessera/core/isometric_bending_constraints.hpp>
#include <tessera/core/position_based_dynamics.hpp>

namespace tessera {
namespace scale_invariance_tests {

using PBD = PositionBasedDynamics;

// A bending stencil (p0, p1 wings; p2-p3 shared edge), a tetrahedron and a triangle.
const std::array<Vector3r, 4> kStencil = {Vector3r(0.5, -0.8, 0.1), Vector3r(0.4, 0.9, -0.2),
                                          Vector3r(0, 0, 0), Vector3r(1, 0, 0)};
const std::array<Vector3r, 4> kTet = {Vector3r(0, 0, 0), Vector3r(1, 0, 0), Vector3r(0, 1, 0),
                                      Vector3r(0, 0, 1)};

std::array<Vector3r, 4> scaled(const std::array<Vector3r, 4>& p, Real s) {
  return {p[0] * s, p[1] * s, p[2] * s, p[3] * s};
}

constexpr Real kScales[] = {Real(1), Real(1e-3), Real(1e3)};

TEST(ScaleInvariance, InitFunctionsAcceptSmallWellShapedElements) {
  for (const Real s : kScales) {
    SCOPED_TRACE(s);
    const auto t = scaled(kTet, s);
    const auto b = scaled(kStencil, s);
    Real area = 0, volume = 0;
    Matrix2r inverse2;
    Matrix3r inverse3;
    Matrix4r Q;
    EXPECT_TRUE(PBD::init_FEMTriangleConstraint(t[0], t[1], t[2], area, inverse2));
    EXPECT_NEAR(area, Real(0.5) * s * s, Real(1e-5) * s * s);
    EXPECT_TRUE(PBD::init_FEMTetraConstraint(t[0], t[1], t[2], t[3], volume, inverse3));
    EXPECT_TRUE(PBD::init_StrainTriangleConstraint(t[0], t[1], t[2], inverse2));
    EXPECT_TRUE(PBD::init_StrainTetraConstraint(t[0], t[1], t[2], t[3], inverse3));
    EXPECT_TRUE(PBD::init_IsometricBendingConstraint(b[0], b[1], b[2], b[3], Q));
  }
}

TEST(ScaleInvariance, FlatElementsAreRejectedAtEveryScale) {
  for (const Real s : kScales) {
    SCOPED_TRACE(s);
    // The fourth vertex in the plane of the first three; the third on the line of the first two.
    const auto t = scaled({kTet[0], kTet[1], kTet[2], Vector3r(0.3, 0.3, 0)}, s);
    const auto line = scaled({kTet[0], kTet[1], Vector3r(0.5, 0, 0), kTet[3]}, s);
    Real area = 0, volume = 0;
    Matrix2r inverse2;
    Matrix3r inverse3;
    Matrix4r Q;
    EXPECT_FALSE(PBD::init_FEMTetraConstraint(t[0], t[1], t[2], t[3], volume, inverse3));
    EXPECT_FALSE(PBD::init_StrainTetraConstraint(t[0], t[1], t[2], t[3], inverse3));
    EXPECT_FALSE(PBD::init_FEMTriangleConstraint(line[0], line[1], line[2], area, inverse2));
    EXPECT_FALSE(PBD::init_StrainTriangleConstraint(line[0], line[1], line[2], inverse2));
    const auto folded = scaled({Vector3r(0.5, 0, 0), kStencil[1], kStencil[2], kStencil[3]}, s);
    EXPECT_FALSE(PBD::init_IsometricBendingConstraint(folded[0], folded[1], folded[2], folded[3], Q));
  }
}

TEST(ScaleInvariance, BatchBuildersAcceptSmallElements) {
  const std::vector<ParticleIndex> four = {0, 1, 2, 3};
  for (const Real s : kScales) {
    SCOPED_TRACE(s);
    const auto b = scaled(kStencil, s);
    const auto t = scaled(kTet, s);
    const std::vector<Vector3r> stencil(b.begin(), b.end()), tet(t.begin(), t.end());
    EXPECT_NO_THROW(make_dihedral_constraints({four, stencil}));
    EXPECT_NO_THROW(make_isometric_bending_constraints({four, stencil}));
    EXPECT_NO_THROW(make_fem_tetra_constraints({four, tet}));
  }
}

TEST(ScaleInvariance, DihedralCorrectionsScaleWithTheStencil) {
  const Real rest_angle = Real(0.3);
  std::array<Vector3r, 4> reference_corrections;
  for (const Real s : kScales) {
    SCOPED_TRACE(s);
    const auto p = scaled(kStencil, s);
    std::array<Vector3r, 4> corr;
    ASSERT_TRUE(PBD::solve_DihedralConstraint(p[0], 1, p[1], 1, p[2], 1, p[3], 1, rest_angle,
                                              Real(0.5), corr[0], corr[1], corr[2], corr[3]));
    if (s == 1) reference_corrections = corr;
    for (int k = 0; k < 4; ++k) {
      EXPECT_GT(corr[k].norm(), 0);
      EXPECT_LT((corr[k] - reference_corrections[k] * s).norm(),
                Real(1e-4) * s * reference_corrections[k].norm());
    }
  }
}

}  // namespace scale_invariance_tests
}  // namespace tessera
