// Finite-element constraints (Bender, Koschier, Charrier, Weber 2014, "Position-Based
// Simulation of Continuous Materials"), the one formula of the FEM triangle and FEM
// tetrahedron families, over lanes. The constraint is the element's elastic energy and its
// gradient the energy gradient, so one PBD step is a Newton step towards zero energy.
//
// Tetrahedron (p0 the reference vertex x1, M = invRestMat, V0 = rest volume):
//   F = [p1 - p0, p2 - p0, p3 - p0] · M,   ε = ½ (FᵀF - I),
//   St. Venant–Kirchhoff: S = 2μ ε + λ tr(ε) I,  P = F S,  E = V0 (μ ε:ε + ½ λ tr(ε)²),
//   ∇E: H = V0 P Mᵀ,  ∇_{p1,p2,p3} E = columns of H,  ∇_{p0} E = -(sum of the columns).
//   Inversion-robust (Irving et al. 2004, when handleInversion and det F ≤ 0.2):
//   F = U F̂ Vᵀ (svd3-inl.h, U and V rotations, the sign of det F on the smallest value),
//   σ̂_i clamped below at kInversionMinStretch, the material evaluated on the diagonal:
//   ε̂_i = ½(σ̂_i² - 1), P̂_i = σ̂_i (2μ ε̂_i + λ tr ε̂),  ε = V ε̂ Vᵀ,  P = U P̂ Vᵀ.
//   PBD: C = E with the Lamé parameters of (Young's modulus, ν), stiffness 1.
//   XPBD: C = sqrt(2 V0 ψ₁) with ψ₁ the density for Young's modulus 1, ∇C = V0 ∇ψ₁ / C and
//   compliance 1/E (Macklin et al. 2016).
// Triangle (plane stress, orthotropic, M = 2×2 invRestMat of the triangle's own frame):
//   F = [p1 - p0, p2 - p0] · M (3×2), ε = ½ (FᵀF - I),
//   [S_xx, S_yy, S_xy] = [[c_xx, c_xy, 0], [c_xy, c_yy, 0], [0, 0, G]] [ε_xx, ε_yy, 2ε_xy],
//   c_xx = E_x/(1 - ν_xyν_yx), c_yy = E_y/(1 - ν_xyν_yx), c_xy = ½(ν_yx E_x + ν_xy E_y)/(1 - ν_xyν_yx),
//   C = A ½ (ε_xx S_xx + ε_yy S_yy + 2 ε_xy S_xy),  H = A F S Mᵀ (3×2),
//   ∇_{p1}, ∇_{p2} = columns of H,  ∇_{p0} = -(∇_{p1} + ∇_{p2}).
// At the rest shape (every |ε_ij| ≤ kDegenerateTolerance; XPBD: C ≤ kDegenerateTolerance·√V0)
// there is nothing to project: zero corrections, and the lane counts as projected.
#if defined(TESSERA_CORE_KERNELS_FEM_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_FEM_INL_H_
#undef TESSERA_CORE_KERNELS_FEM_INL_H_
#else
#define TESSERA_CORE_KERNELS_FEM_INL_H_
#endif

#include <tessera/core/position_based_dynamics.hpp>

#include "projection-inl.h"
#include "svd3-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

/// Largest |a_ij| of a symmetric matrix.
template <class V>
HWY_INLINE V largest_symmetric_entry(const Mat3<V>& a) {
  const V diagonal = lane_max(lane_abs(a.col[0].x), lane_max(lane_abs(a.col[1].y), lane_abs(a.col[2].z)));
  const V off = lane_max(lane_abs(a.col[1].x), lane_max(lane_abs(a.col[2].x), lane_abs(a.col[2].y)));
  return lane_max(diagonal, off);
}

/// F = [p1 - p0, p2 - p0, p3 - p0] · M.
template <class V>
HWY_INLINE Mat3<V> deformation_gradient(const Vec3<V> (&p)[4], const Mat3<V>& rest_inverse) {
  const Mat3<V> edges{{p[1] - p[0], p[2] - p[0], p[3] - p[0]}};
  return edges * rest_inverse;
}

/// Strain ε, first Piola–Kirchhoff stress P and energy of one material evaluation.
template <class V>
struct GreenStrainMaterial {
  Mat3<V> strain;
  Mat3<V> stress;
  V energy;
};

/// St. Venant–Kirchhoff on F (PositionBasedDynamics::computeGreenStrainAndPiolaStress).
template <class V>
HWY_INLINE GreenStrainMaterial<V> green_strain_material(const Mat3<V>& F, V volume, V mu,
                                                        V lambda) {
  const V half = splat<V>(0.5);
  Mat3<V> strain = (F.transposed() * F - Mat3<V>::identity()) * half;
  const V trace = strain.trace();
  const V lambda_trace = lambda * trace;
  Mat3<V> second_piola = strain * (splat<V>(2.0) * mu);
  second_piola.col[0].x = second_piola.col[0].x + lambda_trace;
  second_piola.col[1].y = second_piola.col[1].y + lambda_trace;
  second_piola.col[2].z = second_piola.col[2].z + lambda_trace;
  const V energy =
      volume * (mu * double_contraction(strain, strain) + half * lambda_trace * trace);
  return {strain, F * second_piola, energy};
}

/// The inversion-robust material on F (Irving et al. 2004) with the lane SVD.
template <class V>
HWY_INLINE GreenStrainMaterial<V> green_strain_material_inversion(const Mat3<V>& F, V volume,
                                                                  V mu, V lambda) {
  const Svd3<V> svd = svd3(F);
  const V clamp = splat<V>(PositionBasedDynamics::kInversionMinStretch);
  const V half = splat<V>(0.5), one = splat<V>(1.0), two_mu = splat<V>(2.0) * mu;
  const V s[3] = {lane_max(svd.sigma.x, clamp), lane_max(svd.sigma.y, clamp),
                  lane_max(svd.sigma.z, clamp)};
  V strain[3], first_piola[3];
  for (int i = 0; i < 3; ++i) strain[i] = half * (s[i] * s[i] - one);
  const V trace = strain[0] + strain[1] + strain[2];
  const V lambda_trace = lambda * trace;
  for (int i = 0; i < 3; ++i) first_piola[i] = s[i] * (two_mu * strain[i] + lambda_trace);
  // V diag(d) Vᵀ and U diag(d) Vᵀ, column j = Σ_i d_i a_i (v_i)_j.
  GreenStrainMaterial<V> result;
  for (int j = 0; j < 3; ++j) {
    const V vj[3] = {svd.v(j, 0), svd.v(j, 1), svd.v(j, 2)};
    result.strain.col[j] = svd.v.col[0] * (strain[0] * vj[0]) + svd.v.col[1] * (strain[1] * vj[1]) +
                           svd.v.col[2] * (strain[2] * vj[2]);
    result.stress.col[j] = svd.u.col[0] * (first_piola[0] * vj[0]) +
                           svd.u.col[1] * (first_piola[1] * vj[1]) +
                           svd.u.col[2] * (first_piola[2] * vj[2]);
  }
  result.energy = volume * (mu * (strain[0] * strain[0] + strain[1] * strain[1] +
                                  strain[2] * strain[2]) +
                            half * lambda_trace * trace);
  return result;
}

/// ∇E of the four vertices from P (PositionBasedDynamics::computeGradCGreen).
template <class V>
HWY_INLINE void green_strain_gradient(V volume, const Mat3<V>& rest_inverse,
                                      const Mat3<V>& stress, Vec3<V> (&gradient)[4]) {
  const Mat3<V> H = (stress * volume) * rest_inverse.transposed();
  gradient[1] = H.col[0];
  gradient[2] = H.col[1];
  gradient[3] = H.col[2];
  gradient[0] = -(gradient[1] + gradient[2] + gradient[3]);
}

/// The element's energy, gradient and largest |ε_ij|, with the material switch of
/// solve_FEMTetraConstraint. The robust material is only evaluated when some lane needs it.
template <class V>
struct TetraEnergy {
  V energy;
  Vec3<V> gradient[4];
  V largest_strain;
};

template <class V>
HWY_INLINE TetraEnergy<V> fem_tetra_energy(const Vec3<V> (&p)[4], V volume,
                                           const Mat3<V>& rest_inverse, V mu, V lambda,
                                           bool handle_inversion) {
  const Mat3<V> F = deformation_gradient(p, rest_inverse);
  GreenStrainMaterial<V> material = green_strain_material(F, volume, mu, lambda);
  if (handle_inversion) {
    const Mask<V> inverted =
        F.determinant() <= splat<V>(PositionBasedDynamics::kInversionDeterminantThreshold);
    if (any_lane<V>(inverted)) {
      const GreenStrainMaterial<V> robust = green_strain_material_inversion(F, volume, mu, lambda);
      for (int j = 0; j < 3; ++j) {
        material.strain.col[j] = select(inverted, robust.strain.col[j], material.strain.col[j]);
        material.stress.col[j] = select(inverted, robust.stress.col[j], material.stress.col[j]);
      }
      material.energy = select(inverted, robust.energy, material.energy);
    }
  }
  TetraEnergy<V> result;
  result.energy = material.energy;
  result.largest_strain = largest_symmetric_entry(material.strain);
  green_strain_gradient(volume, rest_inverse, material.stress, result.gradient);
  return result;
}

/// ν ∈ (-1, 0.5).
template <class V>
HWY_INLINE Mask<V> valid_poisson_ratio(V nu) {
  return mask_and(nu > splat<V>(-1.0), nu < splat<V>(0.5));
}

/// Lamé parameters of (E, ν) for lanes with a valid ν (0 elsewhere).
template <class V>
HWY_INLINE void lame_parameters(V youngs_modulus, V nu, const Mask<V>& valid, V& mu, V& lambda) {
  const V one = splat<V>(1.0);
  mu = safe_divide(youngs_modulus, splat<V>(2.0) * (one + nu), valid);
  lambda = safe_divide(youngs_modulus * nu, (one + nu) * (one - splat<V>(2.0) * nu), valid);
}

/// PBD FEM tetrahedron. Returns the lanes that were projected or are at rest (and have a
/// valid material); every other lane gets zero corrections.
template <class V>
HWY_INLINE Mask<V> fem_tetra_pbd(const Vec3<V> (&p)[4], const V (&w)[4], V volume,
                                 const Mat3<V>& rest_inverse, V youngs_modulus, V nu,
                                 bool handle_inversion, Vec3<V> (&corr)[4]) {
  const Mask<V> material_valid = mask_and(youngs_modulus > zero<V>(), valid_poisson_ratio(nu));
  V mu, lambda;
  lame_parameters(youngs_modulus, nu, material_valid, mu, lambda);
  const TetraEnergy<V> element =
      fem_tetra_energy(p, volume, rest_inverse, mu, lambda, handle_inversion);
  const Mask<V> at_rest = element.largest_strain <= splat<V>(kDegenerateTolerance);
  ConstraintValue<V, 4> value;
  value.C = element.energy;
  for (int i = 0; i < 4; ++i) value.gradient[i] = element.gradient[i];
  value.valid = mask_and(material_valid, mask_not(at_rest));
  const Mask<V> projected = project_pbd(value, w, splat<V>(1.0), corr);
  return mask_or(projected, mask_and(material_valid, at_rest));
}

/// XPBD FEM tetrahedron (λ updated in the projected lanes only). step is the loop's
/// TimeStep::of(dt), made once per loop over batches. C = sqrt(2E) with E = V0 ψ₁ and
/// ∇C = ∇E / C, projected in its energy form (projection-inl.h, EnergyValue), which keeps 1/C
/// off the path from E to the corrections.
template <class V>
HWY_INLINE Mask<V> fem_tetra_xpbd(const Vec3<V> (&p)[4], const V (&w)[4], V volume,
                                  const Mat3<V>& rest_inverse, V nu, V compliance,
                                  const TimeStep<V>& step, bool handle_inversion,
                                  V& lambda_xpbd, Vec3<V> (&corr)[4]) {
  const Mask<V> material_valid = mask_and(valid_poisson_ratio(nu), volume > zero<V>());
  V mu, lambda;
  lame_parameters(splat<V>(1.0), nu, material_valid, mu, lambda);
  const TetraEnergy<V> element =
      fem_tetra_energy(p, volume, rest_inverse, mu, lambda, handle_inversion);
  EnergyValue<V, 4> value;
  // ψ₁ ≥ 0 for a valid ν; the clamp only absorbs round-off.
  value.squared_C = splat<V>(2.0) * lane_max(element.energy, zero<V>());
  for (int i = 0; i < 4; ++i) value.energy_gradient[i] = element.gradient[i];
  // At rest when ψ₁ ≤ tol²/2, i.e. 2E ≤ tol² V0: C = sqrt(2 V0 ψ₁) scales with sqrt(V0), so
  // a test on C alone would leave a millimetre element unprojected up to strains of a few
  // per cent in float. A NaN energy (NaN positions) is neither moving nor at rest.
  const Mask<V> moving = value.squared_C > degenerate_denominator<V>() * volume;
  const Mask<V> at_rest = mask_and(is_finite(element.energy), mask_not(moving));
  value.valid = mask_and(material_valid, moving);
  const Mask<V> projected = project_xpbd(value, w, compliance, step, lambda_xpbd, corr);
  return mask_or(projected,
                 mask_and(mask_and(material_valid, at_rest), xpbd_inputs_valid(step, compliance)));
}

/// PBD FEM triangle (orthotropic plane stress), m[k][j] = invRestMat(k, j). Returns the lanes
/// that were projected or are at rest with a positive definite material.
template <class V>
HWY_INLINE Mask<V> fem_triangle_pbd(const Vec3<V> (&p)[3], const V (&w)[3], V area,
                                    const V (&m)[2][2], V youngs_x, V youngs_y, V youngs_shear,
                                    V poisson_xy, V poisson_yx, Vec3<V> (&corr)[3]) {
  const V one = splat<V>(1.0), half = splat<V>(0.5);
  const V one_minus_product = one - poisson_xy * poisson_yx;
  const Mask<V> product_below_one = one_minus_product > zero<V>();
  const V c_xx = safe_divide(youngs_x, one_minus_product, product_below_one);
  const V c_yy = safe_divide(youngs_y, one_minus_product, product_below_one);
  const V c_xy = safe_divide(half * (poisson_yx * youngs_x + poisson_xy * youngs_y),
                             one_minus_product, product_below_one);
  const V c_shear = youngs_shear;
  const Mask<V> positive_definite = mask_and(
      mask_and(mask_and(youngs_x > zero<V>(), youngs_y > zero<V>()),
               mask_and(youngs_shear > zero<V>(), product_below_one)),
      c_xx * c_yy - c_xy * c_xy > zero<V>());

  const Vec3<V> e1 = p[1] - p[0], e2 = p[2] - p[0];
  const Vec3<V> f0 = e1 * m[0][0] + e2 * m[1][0];
  const Vec3<V> f1 = e1 * m[0][1] + e2 * m[1][1];
  const V strain_xx = half * (dot(f0, f0) - one);
  const V strain_yy = half * (dot(f1, f1) - one);
  const V strain_xy = half * dot(f0, f1);
  const Mask<V> at_rest =
      lane_max(lane_abs(strain_xx), lane_max(lane_abs(strain_yy), lane_abs(strain_xy))) <=
      splat<V>(kDegenerateTolerance);

  const V stress_xx = c_xx * strain_xx + c_xy * strain_yy;
  const V stress_yy = c_xy * strain_xx + c_yy * strain_yy;
  const V stress_xy = c_shear * splat<V>(2.0) * strain_xy;
  ConstraintValue<V, 3> value;
  value.C = area * half *
            (strain_xx * stress_xx + strain_yy * stress_yy +
             splat<V>(2.0) * strain_xy * stress_xy);
  // F S (3×2), then H = A (F S) Mᵀ: column j = A Σ_k (F S)_k M_jk.
  const Vec3<V> fs0 = f0 * stress_xx + f1 * stress_xy;
  const Vec3<V> fs1 = f0 * stress_xy + f1 * stress_yy;
  value.gradient[1] = (fs0 * m[0][0] + fs1 * m[0][1]) * area;
  value.gradient[2] = (fs0 * m[1][0] + fs1 * m[1][1]) * area;
  value.gradient[0] = -(value.gradient[1] + value.gradient[2]);
  value.valid = mask_and(positive_definite, mask_not(at_rest));
  const Mask<V> projected = project_pbd(value, w, one, corr);
  return mask_or(projected, mask_and(positive_definite, at_rest));
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_FEM_INL_H_
