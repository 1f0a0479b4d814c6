// The scalar kernel API: one constraint projection per call, with the names, parameter order
// and meaning of the PositionBasedDynamics API (shared/spec/PositionBasedDynamics-API.txt).
// Where results differ from the reference implementation of that API, and what a porting
// user changes, is in docs/differences-from-pbd.md.
//
// Every solve_ function computes position corrections and never moves the particles itself:
// the caller adds corr_i to p_i. Shared conventions, unless a function says otherwise:
//
//  * Projection (Müller et al. 2007, "Position Based Dynamics", eq. 8-10): for a constraint
//    C(p_0..p_n) with gradients ∇_i C, the correction of particle i is
//        Δp_i = -k · s · w_i · ∇_i C,   s = C / Σ_j w_j |∇_j C|²,
//    where w_i is the inverse mass and k ∈ [0, 1] the stiffness. With k = 1 this is one
//    Newton step on C along the inverse-mass-weighted gradient.
//  * A particle with inverse mass 0 is static: its correction is exactly zero.
//  * Degenerate input (coincident points, zero-length edge, zero-area triangle, a flat
//    tetrahedron for the strain and FEM families, every particle static, Σ_j w_j |∇_j C|²
//    below kDegenerateTolerance²) makes the function return false with every correction set
//    to zero. Exceptions, documented at the function: the volume constraint inflates a flat
//    tetrahedron that still has a proper face, and a satisfied constraint whose gradient
//    vanishes there (isometric bending of a flat stencil, FEM at rest) returns true with zero
//    corrections. No function turns finite input into NaN or Inf.
//  * Return value: true when corrections were computed (they may be zero because the
//    constraint is satisfied), false when the configuration is degenerate or the constraint is
//    inactive. Every output correction is written on every call, also when false is returned.
//  * The mass-weighted corrections sum to zero (linear momentum is kept) and, to first order,
//    carry no angular momentum, because every C here is invariant under rigid motion.
#pragma once

#include <tessera/core/real.hpp>

namespace tessera {

class PositionBasedDynamics {
 public:
  // ---------------------------------------------------------------------------------------
  /// Distance constraint (Müller et al. 2007):
  ///   C(p0, p1) = |p0 - p1| - l0,   ∇_{p0} C = n = (p0 - p1)/|p0 - p1|,  ∇_{p1} C = -n.
  /// Degenerate when p0 and p1 coincide (the reference returns true there; see
  /// docs/differences-from-pbd.md, C6).
  static bool solve_DistanceConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                       Real invMass1, const Real restLength,
                                       const Real stiffness, Vector3r& corr0, Vector3r& corr1);

  // ---------------------------------------------------------------------------------------
  /// Dihedral bending constraint (Müller et al. 2007, appendix; gradients of the dihedral
  /// angle from Bridson, Marino, Fedkiw 2003).
  /// Vertex order: p2-p3 is the shared edge, p0 and p1 are the wing vertices; the triangles
  /// are (p0, p2, p3) and (p1, p3, p2), with normals
  ///   n1 = (p2 - p0) × (p3 - p0),   n2 = (p3 - p1) × (p2 - p1).
  ///   C = acos(n̂1 · n̂2) - φ0,   φ = acos(n̂1 · n̂2) ∈ [0, π]  (0 when the stencil is flat).
  /// ∇C is the gradient of the unsigned angle φ (the signed-angle gradients of Bridson et al.
  /// with the sign of (n1 × n2) · (p3 - p2)). φ is evaluated as |atan2((n1 × n2) · ê, n1 · n2)|
  /// (the same angle, accurate near 0 and π), and the gradient has no 1/sin φ factor, so flat
  /// and fully folded stencils give finite corrections. Where the sign is zero (φ = 0 or π) it
  /// is taken as +1: a flat stencil with φ0 > 0 buckles deterministically. Degenerate when the
  /// edge has zero length or a triangle has zero area.
  /// Differs from the reference: true when only the edge is movable, φ accurate near π
  /// (docs/differences-from-pbd.md, C6 and C7).
  static bool solve_DihedralConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                       Real invMass1, const Vector3r& p2, Real invMass2,
                                       const Vector3r& p3, Real invMass3, const Real restAngle,
                                       const Real stiffness, Vector3r& corr0, Vector3r& corr1,
                                       Vector3r& corr2, Vector3r& corr3);

  // ---------------------------------------------------------------------------------------
  /// Tetrahedron volume constraint (Müller et al. 2007):
  ///   C = (1/6) ((p1 - p0) × (p2 - p0)) · (p3 - p0) - V0   (signed volume: positive when
  ///   p3 lies on the side of triangle (p0, p1, p2) its right-handed normal points to),
  ///   ∇_{p1} C = (p2 - p0) × (p3 - p0) / 6,  ∇_{p2} C = (p3 - p0) × (p1 - p0) / 6,
  ///   ∇_{p3} C = (p1 - p0) × (p2 - p0) / 6,  ∇_{p0} C = -(∇_{p1} + ∇_{p2} + ∇_{p3}).
  /// Degenerate only when Σ w_i |∇_i C|² vanishes (all four points on one line, or every
  /// particle static): a flat tetrahedron with a proper face is projected (inflated to V0).
  /// Differs from the reference, whose ∇C lacks the 1/6: its step is 1/6 of this one
  /// (docs/differences-from-pbd.md, B1).
  static bool solve_VolumeConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                     Real invMass1, const Vector3r& p2, Real invMass2,
                                     const Vector3r& p3, Real invMass3, const Real restVolume,
                                     const Real stiffness, Vector3r& corr0, Vector3r& corr1,
                                     Vector3r& corr2, Vector3r& corr3);

  // ---------------------------------------------------------------------------------------
  /// Point–edge distance: q = (1 - t) p0 + t p1 is the closest point of segment p0-p1 to p
  /// (t clamped to [0, 1], held fixed while differentiating), n = (p - q)/|p - q|,
  ///   C = |p - q| - d0,   ∇_p C = n,  ∇_{p0} C = -(1 - t) n,  ∇_{p1} C = -t n.
  /// compressionStiffness applies when C < 0, stretchStiffness when C ≥ 0.
  /// A zero-length segment counts as the point p0 (t = 0). Degenerate when p lies on the
  /// segment. Differs from the reference, which measures t from p1
  /// (docs/differences-from-pbd.md, B2).
  static bool solve_EdgePointDistanceConstraint(const Vector3r& p, Real invMass,
                                                const Vector3r& p0, Real invMass0,
                                                const Vector3r& p1, Real invMass1,
                                                const Real restDist,
                                                const Real compressionStiffness,
                                                const Real stretchStiffness, Vector3r& corr,
                                                Vector3r& corr0, Vector3r& corr1);

  /// Point–triangle distance: q = b0 p0 + b1 p1 + b2 p2 is the closest point of triangle
  /// (p0, p1, p2) to p (barycentric b held fixed while differentiating), n = (p - q)/|p - q|,
  ///   C = |p - q| - d0,   ∇_p C = n,  ∇_{pi} C = -b_i n.
  /// Stiffness as for the point–edge constraint. A triangle of zero area (or so thin that
  /// |(p1 - p0) × (p2 - p0)|² ≤ kDegenerateTolerance |p1 - p0|² |p2 - p0|²) is measured to its
  /// longest edge (for zero area the longest edge covers the other two, so the closest point
  /// is exact; the choice does not depend on rounding). Degenerate when p lies on the
  /// triangle. Differs from the reference, which picks the edge by the first negative
  /// barycentric coordinate (docs/differences-from-pbd.md, B3).
  static bool solve_TrianglePointDistanceConstraint(
      const Vector3r& p, Real invMass, const Vector3r& p0, Real invMass0, const Vector3r& p1,
      Real invMass1, const Vector3r& p2, Real invMass2, const Real restDist,
      const Real compressionStiffness, const Real stretchStiffness, Vector3r& corr,
      Vector3r& corr0, Vector3r& corr1, Vector3r& corr2);

  /// Edge–edge distance between segments p0-p1 and p2-p3: a = (1 - s) p0 + s p1 and
  /// b = (1 - t) p2 + t p3 are the closest points (s, t clamped to [0, 1], held fixed while
  /// differentiating), n = (a - b)/|a - b|,
  ///   C = |a - b| - d0,  ∇_{p0} C = (1 - s) n, ∇_{p1} C = s n, ∇_{p2} C = -(1 - t) n,
  ///   ∇_{p3} C = -t n.
  /// Stiffness as for the point–edge constraint. A zero-length segment counts as its first
  /// point (s = 0 or t = 0); for parallel segments one closest pair of the overlap is used.
  /// Degenerate when the segments touch. Differs from the reference, which clamps s and t
  /// independently (docs/differences-from-pbd.md, B4).
  static bool solve_EdgeEdgeDistanceConstraint(const Vector3r& p0, Real invMass0,
                                               const Vector3r& p1, Real invMass1,
                                               const Vector3r& p2, Real invMass2,
                                               const Vector3r& p3, Real invMass3,
                                               const Real restDist,
                                               const Real compressionStiffness,
                                               const Real stretchStiffness, Vector3r& corr0,
                                               Vector3r& corr1, Vector3r& corr2,
                                               Vector3r& corr3);

  // ---------------------------------------------------------------------------------------
  /// Isometric bending (Bergou et al. 2006, "A Quadratic Bending Model for Inextensible
  /// Surfaces"). Vertex order as for the dihedral constraint: p2-p3 is the shared edge, the
  /// triangles are (p0, p2, p3) and (p1, p3, p2). With the cotangent weights of the stencil's
  /// rest shape the discrete Laplacian row is K ∈ R⁴ (indexed p0..p3) and
  ///   Q = 3 / (A0 + A1) · K Kᵀ   (A0, A1 the rest triangle areas),
  /// symmetric positive semi-definite, each row summing to zero, and K·x = 0 for the
  /// coordinates of any planar configuration. Q is indexed in parameter order p0, p1, p2, p3.
  /// Returns false for a degenerate rest stencil (zero-length edge, zero-area triangle).
  /// Differs from the reference: Q(i, j) = -2 Q_ref(π(i), π(j)), π(p0..p3) = (2, 3, 0, 1)
  /// (docs/differences-from-pbd.md, C1).
  static bool init_IsometricBendingConstraint(const Vector3r& p0, const Vector3r& p1,
                                              const Vector3r& p2, const Vector3r& p3,
                                              Matrix4r& Q);

  /// C = ½ Σ_ij Q_ij p_i · p_j  (≥ 0, zero when the stencil is flat),  ∇_{pi} C = Σ_j Q_ij p_j.
  /// Q must come from init_IsometricBendingConstraint: it has rank one, Q = k kᵀ, and both are
  /// evaluated through its factor as C = ½ |u|², ∇_{pi} C = k_i u with u = Σ_j k_j p_j, so a
  /// stencil flat up to rounding moves by rounding only. A stencil with ∇C = 0 (flat for its
  /// Q) satisfies the constraint: zero corrections and true. False (zero corrections) when
  /// every particle is static. A Q built by the reference (negative semi-definite) counts as
  /// flat here: recompute it (docs/differences-from-pbd.md, C1).
  static bool solve_IsometricBendingConstraint(const Vector3r& p0, Real invMass0,
                                               const Vector3r& p1, Real invMass1,
                                               const Vector3r& p2, Real invMass2,
                                               const Vector3r& p3, Real invMass3,
                                               const Matrix4r& Q, const Real stiffness,
                                               Vector3r& corr0, Vector3r& corr1,
                                               Vector3r& corr2, Vector3r& corr3);

  // ---------------------------------------------------------------------------------------
  /// Shape matching (Müller et al. 2005, "Meshless Deformations Based on Shape Matching").
  /// Particle weights are masses m_i = 1/w_i; a static particle (w_i = 0) weighs
  /// kShapeMatchingStaticMass times the heaviest movable one, so the goal shape stays anchored
  /// to it. restCm = Σ m_i x0_i / Σ m_i. Returns false for numPoints < 1 or null arrays.
  static bool init_ShapeMatchingConstraint(const Vector3r x0[], const Real invMasses[],
                                           const int numPoints, Vector3r& restCm);

  /// With q_i = x0_i - restCm, c = Σ m_i x_i / Σ m_i and A_pq = Σ m_i (x_i - c) q_iᵀ:
  ///  * allowStretch = false: T = R, the rotation of the polar decomposition A_pq = R S
  ///    (reflections are removed, det R = +1);
  ///  * allowStretch = true: T = A_pq A_qq⁻¹ with A_qq = Σ m_i q_i q_iᵀ, the best-fitting
  ///    linear map, so an affine deformation is matched exactly.
  /// corr_i = k (T q_i + c - x_i) for movable particles, 0 for static ones; *rot (if not null)
  /// receives T. The mass-weighted corrections carry no linear and no angular momentum.
  /// Returns false (and zero corrections, *rot = identity) for numPoints < 1, null arrays,
  /// every particle static, or when T is undetermined: without allowStretch when A_pq has
  /// rank < 2 (every current or rest point on one line; a planar cluster is fine), with
  /// allowStretch when A_qq is singular (rest points coplanar). Rank is judged relative to
  /// the largest singular value / eigenvalue.
  /// Differs from the reference: A_qq⁻¹ with allowStretch, static particles untouched,
  /// det R = +1 (docs/differences-from-pbd.md, B5).
  static bool solve_ShapeMatchingConstraint(const Vector3r x0[], const Vector3r x[],
                                            const Real invMasses[], const int numPoints,
                                            const Vector3r& restCm, const Real stiffness,
                                            const bool allowStretch, Vector3r corr[],
                                            Matrix3r* rot = nullptr);

  /// Weight of a static particle in shape matching, relative to the heaviest movable one.
  static constexpr Real kShapeMatchingStaticMass = Real(1000);

  // ---------------------------------------------------------------------------------------
  /// Strain based dynamics for a triangle (Müller et al. 2014, "Strain Based Dynamics").
  /// The rest triangle is taken in the xy plane (z is ignored):
  ///   D = [p1 - p0, p2 - p0] (2×2, x and y rows),   invRestMat = D⁻¹.
  /// Returns false (invRestMat = 0) when the rest triangle's area in the xy plane,
  /// ½ |det D|, is at most kDegenerateTolerance.
  static bool init_StrainTriangleConstraint(const Vector3r& p0, const Vector3r& p1,
                                            const Vector3r& p2, Matrix2r& invRestMat);

  /// F = [p1 - p0, p2 - p0] · invRestMat (3×2), f_i its columns, S = FᵀF (the Green–St-Venant
  /// strain is ½(S - I)). Three sub-constraints are projected one after the other, each on the
  /// positions already corrected by the previous ones (Gauss–Seidel, order xx, yy, xy):
  ///   stretch i ∈ {x, y}: C = |f_i|² - 1, or |f_i| - 1 when normalizeStretch;
  ///   shear:              C = f_0 · f_1,   or f_0 · f_1 / (|f_0| |f_1|) when normalizeShear;
  /// with stiffness xxStiffness, yyStiffness, xyStiffness. corr_i is the sum of the three.
  /// A sub-constraint with stiffness 0 is skipped. Returns false with every correction zero
  /// when an active sub-constraint is degenerate (a normalized column of length ≤
  /// kDegenerateTolerance, or a vanishing weighted gradient, e.g. the triangle collapsed to
  /// a point or every particle static).
  /// Differs from the reference's order xx, xy, yy (docs/differences-from-pbd.md, C2).
  static bool solve_StrainTriangleConstraint(const Vector3r& p0, Real invMass0,
                                             const Vector3r& p1, Real invMass1,
                                             const Vector3r& p2, Real invMass2,
                                             const Matrix2r& invRestMat, const Real xxStiffness,
                                             const Real yyStiffness, const Real xyStiffness,
                                             const bool normalizeStretch,
                                             const bool normalizeShear, Vector3r& corr0,
                                             Vector3r& corr1, Vector3r& corr2);

  /// D = [p1 - p0, p2 - p0, p3 - p0],  invRestMat = D⁻¹. Returns false (invRestMat = 0) for a
  /// flat rest tetrahedron, |det D| / 6 ≤ kDegenerateTolerance (either orientation of a
  /// non-flat one is accepted).
  static bool init_StrainTetraConstraint(const Vector3r& p0, const Vector3r& p1,
                                         const Vector3r& p2, const Vector3r& p3,
                                         Matrix3r& invRestMat);

  /// F = [p1 - p0, p2 - p0, p3 - p0] · invRestMat, f_i its columns. Six sub-constraints in
  /// Gauss–Seidel order: stretch xx, yy, zz (C = |f_i|² - 1, or |f_i| - 1 normalized) with
  /// stretchStiffness[i], then shear xy, xz, yz (C = f_i · f_j, or normalized by |f_i||f_j|)
  /// with shearStiffness[0], [1], [2]. Zero stiffness and degenerate cases as for the
  /// triangle. Differs from the reference's order xx, xy, yy, xz, yz, zz
  /// (docs/differences-from-pbd.md, C2).
  static bool solve_StrainTetraConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                          Real invMass1, const Vector3r& p2, Real invMass2,
                                          const Vector3r& p3, Real invMass3,
                                          const Matrix3r& invRestMat,
                                          const Vector3r& stretchStiffness,
                                          const Vector3r& shearStiffness,
                                          const bool normalizeStretch, const bool normalizeShear,
                                          Vector3r& corr0, Vector3r& corr1, Vector3r& corr2,
                                          Vector3r& corr3);

  // ---------------------------------------------------------------------------------------
  /// Gradient of the strain energy of a tetrahedron with respect to its four vertices, from
  /// the first Piola–Kirchhoff stress sigma = P (Bender et al. 2014, eq. 14):
  ///   H = restVolume · sigma · invRestMatᵀ,   J[1..3] = columns 0..2 of H,
  ///   J[0] = -(J[1] + J[2] + J[3]).
  /// Vertex order as in computeGreenStrainAndPiolaStress: J[k] belongs to x_{k+1}. The
  /// reference implementation uses x4 as reference vertex (docs/differences-from-pbd.md, C3).
  static void computeGradCGreen(Real restVolume, const Matrix3r& invRestMat,
                                const Matrix3r& sigma, Vector3r* J);

  /// St. Venant–Kirchhoff material on a tetrahedron (x1, x2, x3, x4), x1 the reference vertex:
  ///   F = [x2 - x1, x3 - x1, x4 - x1] · invRestMat,   epsilon = ½ (FᵀF - I),
  ///   S = 2 mu epsilon + lambda tr(epsilon) I,  sigma = P = F S,
  ///   energy = restVolume · (mu epsilon:epsilon + ½ lambda tr(epsilon)²).
  /// The reference implementation uses x4 as reference vertex (docs/differences-from-pbd.md, C3).
  static void computeGreenStrainAndPiolaStress(const Vector3r& x1, const Vector3r& x2,
                                               const Vector3r& x3, const Vector3r& x4,
                                               const Matrix3r& invRestMat,
                                               const Real restVolume, const Real mu,
                                               const Real lambda, Matrix3r& epsilon,
                                               Matrix3r& sigma, Real& energy);

  /// The same material made robust to inversion (Irving et al. 2004, "Invertible Finite
  /// Elements For Robust Simulation of Large Deformation"): F = U F̂ Vᵀ with U, V rotations
  /// (the sign of det F moves onto the smallest singular value), each singular value clamped
  /// below at kInversionMinStretch; epsilon, S and the energy are evaluated on F̂ and
  ///   epsilon = V ε̂ Vᵀ,   sigma = U (F̂ Ŝ) Vᵀ.
  /// For an uninverted F whose singular values are all above the clamp it equals
  /// computeGreenStrainAndPiolaStress. The reference returns epsilon = U ε̂ Vᵀ, not
  /// symmetric (docs/differences-from-pbd.md, B6).
  static void computeGreenStrainAndPiolaStressInversion(
      const Vector3r& x1, const Vector3r& x2, const Vector3r& x3, const Vector3r& x4,
      const Matrix3r& invRestMat, const Real restVolume, const Real mu, const Real lambda,
      Matrix3r& epsilon, Matrix3r& sigma, Real& energy);

  /// Lower clamp of the singular values of F in the inversion-robust material.
  static constexpr Real kInversionMinStretch = Real(0.577);

  // ---------------------------------------------------------------------------------------
  /// FEM triangle with an orthotropic St. Venant–Kirchhoff material in plane stress (Bender,
  /// Koschier, Charrier, Weber 2014, "Position-Based Simulation of Continuous Materials").
  /// The rest triangle is mapped to its own plane by the orthonormal frame
  ///   a = (p1 - p0)/|p1 - p0|,  b = n̂ × a,  n = (p1 - p0) × (p2 - p0),
  /// D = [[a·(p1 - p0), a·(p2 - p0)], [b·(p1 - p0), b·(p2 - p0)]], invRestMat = D⁻¹ and
  /// area = ½ |n|. The material x axis is the rest edge p0→p1. Returns false (area = 0,
  /// invRestMat = 0) when the rest area is at most kDegenerateTolerance. The reference starts
  /// at p2 with x perpendicular to p0p1 (docs/differences-from-pbd.md, C3).
  static bool init_FEMTriangleConstraint(const Vector3r& p0, const Vector3r& p1,
                                         const Vector3r& p2, Real& area, Matrix2r& invRestMat);

  /// F = [p1 - p0, p2 - p0] · invRestMat (3×2), ε = ½ (FᵀF - I), Voigt stress
  ///   [S_xx, S_yy, S_xy] = C [ε_xx, ε_yy, 2 ε_xy]  with the plane-stress orthotropic
  ///   C = [[E_x, ν_yx E_x, 0], [ν_xy E_y, E_y, 0], [0, 0, G]] / (1 - ν_xy ν_yx) (G not divided),
  ///   symmetrised (its off-diagonal pair averaged) so that the stress is the energy's
  ///   gradient; the pair is equal already for a consistent material (ν_yx E_x = ν_xy E_y).
  /// C = energy = area · ½ (ε_xx S_xx + ε_yy S_yy + 2 ε_xy S_xy),
  /// ∇ from H = area · F S · invRestMatᵀ: ∇_{p1} = H col 0, ∇_{p2} = H col 1,
  /// ∇_{p0} = -(∇_{p1} + ∇_{p2}); projected as a PBD constraint with stiffness 1.
  /// At the rest shape (every |ε_ij| ≤ kDegenerateTolerance) the energy and its gradient
  /// vanish: zero corrections, true. Returns false when the gradient is degenerate (e.g. the
  /// triangle collapsed to a point, every particle static) or the material is not positive
  /// definite (a non-positive E_x, E_y or G, ν_xy ν_yx ≥ 1, or a symmetrised 2×2 normal block
  /// with non-positive determinant). The reference's S_xy is G ε_xy, and its x and y axes are
  /// swapped (docs/differences-from-pbd.md, B7 and C3).
  static bool solve_FEMTriangleConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                          Real invMass1, const Vector3r& p2, Real invMass2,
                                          const Real& area, const Matrix2r& invRestMat,
                                          const Real youngsModulusX, const Real youngsModulusY,
                                          const Real youngsModulusShear,
                                          const Real poissonRatioXY, const Real poissonRatioYX,
                                          Vector3r& corr0, Vector3r& corr1, Vector3r& corr2);

  /// D = [p1 - p0, p2 - p0, p3 - p0], invRestMat = D⁻¹, volume = |det D| / 6. Returns false
  /// (volume = 0, invRestMat = 0) for a flat rest tetrahedron, volume ≤ kDegenerateTolerance.
  /// The reference implementation uses p3 as reference vertex (docs/differences-from-pbd.md, C3).
  static bool init_FEMTetraConstraint(const Vector3r& p0, const Vector3r& p1,
                                      const Vector3r& p2, const Vector3r& p3, Real& volume,
                                      Matrix3r& invRestMat);

  /// St. Venant–Kirchhoff tetrahedron (Bender et al. 2014): Lamé parameters
  ///   mu = E / (2 (1 + ν)),  lambda = E ν / ((1 + ν)(1 - 2ν)),
  /// C = energy of computeGreenStrainAndPiolaStress (…Inversion when handleInversion is set
  /// and det F ≤ 0.2, i.e. the tetrahedron is inverted or nearly flat), ∇C from
  /// computeGradCGreen, projected as a PBD constraint with stiffness 1. Vertex order: p0 is
  /// the reference vertex x1. At the rest shape (every |ε_ij| ≤ kDegenerateTolerance) the
  /// corrections are zero and true is returned. Returns false for E ≤ 0, ν ∉ (-1, 0.5), or a
  /// degenerate gradient (e.g. collapsed to a point without handleInversion, every particle
  /// static). E and restVolume scale C and ∇C alike, so they cancel in the PBD step.
  /// Differs from the reference in the inversion switch, E = 0 and the ν range
  /// (docs/differences-from-pbd.md, B8, C4 and C6).
  static bool solve_FEMTetraConstraint(const Vector3r& p0, Real invMass0, const Vector3r& p1,
                                       Real invMass1, const Vector3r& p2, Real invMass2,
                                       const Vector3r& p3, Real invMass3, const Real restVolume,
                                       const Matrix3r& invRestMat, const Real youngsModulus,
                                       const Real poissonRatio, const bool handleInversion,
                                       Vector3r& corr0, Vector3r& corr1, Vector3r& corr2,
                                       Vector3r& corr3);

  /// det F at or below which solve_FEMTetraConstraint switches to the inversion-robust
  /// material when handleInversion is set.
  static constexpr Real kInversionDeterminantThreshold = Real(0.2);

  // ---------------------------------------------------------------------------------------
  /// Contact between particle x0 and the point of tetrahedron (x[0..3]) with barycentric
  /// coordinates bary = (b1, b2, b3) with respect to x[1], x[2], x[3]; b0 = 1 - b1 - b2 - b3
  /// weighs x[0]. The contact point on the tet is c = Σ b_i x[i]; normal is the unit contact
  /// normal, pointing from the tet towards the particle. With the relative velocity
  /// u = v0 - Σ b_i v[i] and its tangential part u_t = u - (u·n) n:
  ///   constraintInfo.col(0) = normal,
  ///   constraintInfo.col(1) = u_t / |u_t| (zero when u_t vanishes),
  ///   (0,2) = 1 / (nᵀ K n) with K = (w0 + Σ b_i² w_i) I the inverse effective mass,
  ///   (1,2) = |u_t| / (tᵀ K t), the impulse that stops the tangential motion,
  ///   (2,2) = u · n, the relative normal velocity at initialisation;
  /// the remaining entries are 0.
  /// Returns false (constraintInfo = 0) when both sides are static (w0 + Σ b_i² w_i ≤
  /// kDegenerateTolerance) or normal is not a unit vector (| |n|² - 1 | > 1e-4).
  static bool init_ParticleTetContactConstraint(
      const Real invMass0, const Vector3r& x0, const Vector3r& v0, const Real invMass[],
      const Vector3r x[], const Vector3r v[], const Vector3r& bary, const Vector3r& normal,
      Eigen::Matrix<Real, 3, 3, Eigen::DontAlign>& constraintInfo);

  /// Non-penetration C = n · (x0 - c) ≥ 0 as an inequality with an accumulated multiplier:
  ///   Δλ = -C / (nᵀ K n),   λ ← max(λ + Δλ, 0)  (applying only the clamped change),
  ///   corr0 = w0 Δλ n,  corr[i] = -w_i b_i Δλ n.
  /// lambda accumulates over the iterations of one step (start it at 0). A separated contact
  /// (C > 0 and λ = 0) gives zero corrections and returns true. Returns false (zero
  /// corrections, λ unchanged) when constraintInfo(0, 2) is not positive, i.e. init_ failed.
  /// The reference is two-sided and ignores x[3]'s inverse mass in its early-out
  /// (docs/differences-from-pbd.md, B9 and C5).
  static bool solve_ParticleTetContactConstraint(
      const Real invMass0, const Vector3r& x0, const Real invMass[], const Vector3r x[],
      const Vector3r& bary, Eigen::Matrix<Real, 3, 3, Eigen::DontAlign>& constraintInfo,
      Real& lambda, Vector3r& corr0, Vector3r corr[]);

  /// Coulomb friction after the velocity update. lambda is the normal impulse of the
  /// position solve per unit time (its accumulated λ divided by the substep dt). With u_t the
  /// current tangential relative velocity (as in init_), the tangential impulse is
  ///   p = min(|u_t| / (tᵀ K t), frictionCoeff · lambda),  t = u_t / |u_t|,
  ///   corr_v0 = -w0 p t,  corr_v[i] = w_i b_i p t.
  /// Returns false (zero corrections) when there is no tangential motion (|u_t| ≤
  /// kDegenerateTolerance), no normal impulse (frictionCoeff · lambda ≤ 0) or both sides are
  /// static. constraintInfo is only read (its normal column). The reference uses the
  /// velocities from init_ instead (docs/differences-from-pbd.md, C5).
  static bool velocitySolve_ParticleTetContactConstraint(
      const Real invMass0, const Vector3r& x0, const Vector3r& v0, const Real invMass[],
      const Vector3r x[], const Vector3r v[], const Vector3r& bary, const Real lambda,
      const Real frictionCoeff, Eigen::Matrix<Real, 3, 3, Eigen::DontAlign>& constraintInfo,
      Vector3r& corr_v0, Vector3r corr_v[]);
};

}  // namespace tessera
