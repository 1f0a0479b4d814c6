// Strain based dynamics (Müller, Chentanez, Kim, Macklin 2014, "Strain Based Dynamics"), the
// one formula of the strain triangle and strain tetrahedron families, over lanes.
//
// An element of Dim + 1 particles (Dim = 2: triangle, 3: tetrahedron) with the inverse rest
// edge matrix M (Dim×Dim) has F = [p1 - p0, ..., p_Dim - p0] · M, whose columns are
//   f_j = Σ_k M_kj (p_{k+1} - p0).
// Each entry of S = FᵀF is its own sub-constraint, projected with the PBD rule on the
// positions the previous ones corrected (Gauss–Seidel inside the element; project_strain
// carries F from one to the next instead of the positions, the same in exact arithmetic):
//   stretch i:  C = |f_i|² - 1,   ∂C/∂f_i = 2 f_i;
//               or normalised C = |f_i| - 1, ∂C/∂f_i = f_i / |f_i|;
//   shear i,j:  C = f_i · f_j,    ∂C/∂f_i = f_j, ∂C/∂f_j = f_i;
//               or normalised C = f̂_i · f̂_j, ∂C/∂f_i = (f̂_j - C f̂_i) / |f_i| (and i ↔ j),
// and by the chain rule ∇_{p_{k+1}} C = Σ_j M_kj ∂C/∂f_j, ∇_{p0} C = -Σ_k ∇_{p_{k+1}} C.
// Vertex order: p0 is the reference vertex. A lane whose active sub-constraint (stiffness
// ≠ 0) is degenerate (a normalised column of length ≤ kDegenerateTolerance, or a vanishing
// weighted gradient) gets zero corrections for the whole element; the other sub-constraints
// of that lane still run (on finite values) but their result is discarded.
#if defined(TESSERA_CORE_KERNELS_STRAIN_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef TESSERA_CORE_KERNELS_STRAIN_INL_H_
#undef TESSERA_CORE_KERNELS_STRAIN_INL_H_
#else
#define TESSERA_CORE_KERNELS_STRAIN_INL_H_
#endif

#include "projection-inl.h"

HWY_BEFORE_NAMESPACE();
namespace tessera {
namespace HWY_NAMESPACE {

/// Which entry of S a sub-constraint drives: first == second is a stretch, else a shear.
struct StrainEntry {
  int first;
  int second;
};

/// The Gauss–Seidel orders of the scalar API: xx, yy, xy (triangle) and xx, yy, zz, xy, xz,
/// yz (tetrahedron).
inline constexpr StrainEntry kStrainTriangleEntries[3] = {{0, 0}, {1, 1}, {0, 1}};
inline constexpr StrainEntry kStrainTetraEntries[6] = {{0, 0}, {1, 1}, {2, 2},
                                                       {0, 1}, {0, 2}, {1, 2}};

/// Column j of F.
template <int Dim, class V>
HWY_INLINE Vec3<V> strain_column(const Vec3<V> (&edge)[Dim], const V (&m)[Dim][Dim], int j) {
  Vec3<V> f = edge[0] * m[0][j];
  for (int k = 1; k < Dim; ++k) f += edge[k] * m[k][j];
  return f;
}

/// C of one sub-constraint and its derivatives ∂C/∂f_first, ∂C/∂f_second (zero for a stretch).
template <class V>
struct StrainValue {
  V C;
  Vec3<V> d_first;
  Vec3<V> d_second;
  Mask<V> valid;
};

/// C and ∂C/∂f of one sub-constraint from F's columns fa = f_first and fb = f_second.
template <class V>
HWY_INLINE StrainValue<V> strain_sub_constraint(const Vec3<V>& fa, const Vec3<V>& fb,
                                                StrainEntry entry, bool normalize_stretch,
                                                bool normalize_shear) {
  StrainValue<V> value;
  value.valid = all_lanes<V>();
  value.d_second = Vec3<V>::zeros();
  if (entry.first == entry.second) {
    if (normalize_stretch) {
      const V length = norm(fa);
      value.valid = length > splat<V>(kDegenerateTolerance);
      value.C = length - splat<V>(1.0);
      value.d_first = fa * safe_divide(splat<V>(1.0), length, value.valid);
    } else {
      value.C = squared_norm(fa) - splat<V>(1.0);
      value.d_first = fa * splat<V>(2.0);
    }
  } else {
    if (normalize_shear) {
      const V length_a = norm(fa), length_b = norm(fb);
      value.valid = mask_and(length_a > splat<V>(kDegenerateTolerance),
                             length_b > splat<V>(kDegenerateTolerance));
      const V inverse_a = safe_divide(splat<V>(1.0), length_a, value.valid);
      const V inverse_b = safe_divide(splat<V>(1.0), length_b, value.valid);
      const Vec3<V> unit_a = fa * inverse_a, unit_b = fb * inverse_b;
      value.C = dot(unit_a, unit_b);
      value.d_first = (unit_b - unit_a * value.C) * inverse_a;
      value.d_second = (unit_a - unit_b * value.C) * inverse_b;
    } else {
      value.C = dot(fa, fb);
      value.d_first = fb;
      value.d_second = fa;
    }
  }
  return value;
}

/// The chain rule's coefficients and weights: ∇_{p_i} C = Σ_a c_i^a ∂C/∂f_a with
/// c_{k+1}^a = M_ka and c_0^a = -Σ_k M_ka (returned in c0), and Q_ab = Σ_i w_i c_i^a c_i^b.
/// They make the PBD denominator of a sub-constraint a small quadratic form in its derivatives,
///   Σ_i w_i |∇_i C|² = |∂C/∂f_a|² Q_aa + 2 (∂C/∂f_a · ∂C/∂f_b) Q_ab + |∂C/∂f_b|² Q_bb,
/// and carry its step from the particles to F (project_strain), both built once per element
/// from w and M alone.
template <int Dim, class V>
HWY_INLINE void strain_chain_weights(const V (&w)[Dim + 1], const V (&m)[Dim][Dim],
                                     V (&c0)[Dim], V (&q)[Dim][Dim]) {
  V weighted_c0[Dim];
  for (int a = 0; a < Dim; ++a) {
    V sum = m[0][a];
    for (int k = 1; k < Dim; ++k) sum = sum + m[k][a];
    c0[a] = zero<V>() - sum;
    weighted_c0[a] = w[0] * c0[a];
  }
  for (int a = 0; a < Dim; ++a) {
    for (int b = a; b < Dim; ++b) {
      V sum = weighted_c0[a] * c0[b];
      for (int k = 0; k < Dim; ++k) sum = sum + w[k + 1] * m[k][a] * m[k][b];
      q[a][b] = sum;
      q[b][a] = sum;
    }
  }
}

/// Relative size below which a shear's denominator is rounding noise: 8 units of float's
/// round-off, whatever Real is (a denominator a million times below its squares is degenerate
/// in either precision).
inline constexpr double kStrainFormRoundOff = 8 * 1.1920928955078125e-07;

/// Projects the Count sub-constraints in order (entries[s] with stiffness[s]) with the PBD rule
/// (projection-inl.h) and writes the summed corrections. Returns the lanes where no active
/// sub-constraint was degenerate; every other lane gets zero corrections.
///
/// The particles are not moved between sub-constraints; F is. A sub-constraint with multiplier
/// s (D_a = ∂C/∂f_a) moves p_i by Δp_i = -s w_i Σ_a c_i^a D_a, and F is linear in the
/// particles, f_j = Σ_i c_i^j p_i, so its columns move by
///   Δf_j = Σ_i c_i^j Δp_i = -s Σ_a Q_ja D_a,
/// and the element's corrections are those of the summed steps G_a = Σ_s s D_a:
///   Δp_{k+1} = -w_{k+1} Σ_a M_ka G_a,   Δp_0 = -w_0 Σ_a c_0^a G_a.
/// In exact arithmetic this is the Gauss–Seidel over positions, each sub-constraint projected
/// on the positions the previous ones moved (StrainTetra.SubConstraintsRunInGaussSeidelOrder
/// checks it against that chain); it rounds differently, at about half the work per
/// sub-constraint: no edges, columns or particles recomputed in between.
template <int Dim, int Count, class V>
HWY_INLINE Mask<V> project_strain(const Vec3<V> (&p)[Dim + 1], const V (&w)[Dim + 1],
                                  const V (&m)[Dim][Dim], const StrainEntry (&entries)[Count],
                                  const V (&stiffness)[Count], bool normalize_stretch,
                                  bool normalize_shear, Vec3<V> (&corr)[Dim + 1]) {
  V c0[Dim], q[Dim][Dim];
  strain_chain_weights<Dim>(w, m, c0, q);
  Vec3<V> edge[Dim];
  for (int k = 0; k < Dim; ++k) edge[k] = p[k + 1] - p[0];
  Vec3<V> f[Dim], step_sum[Dim];
  for (int j = 0; j < Dim; ++j) {
    f[j] = strain_column<Dim>(edge, m, j);
    step_sum[j] = Vec3<V>::zeros();
  }
  Mask<V> ok = all_lanes<V>();
  // Unrolled, so each sub-constraint's columns a, b are constants: a rolled loop indexed M and
  // Q in stack arrays at run time (double, AVX-512).
  static_assert(Count <= 8, "HWY_UNROLL below unrolls up to 8 sub-constraints");
  HWY_UNROLL(8)
  for (int s = 0; s < Count; ++s) {
    const int a = entries[s].first, b = entries[s].second;
    const auto value = strain_sub_constraint(f[a], f[b], entries[s], normalize_stretch,
                                             normalize_shear);
    V weighted = squared_norm(value.d_first) * q[a][a];
    Mask<V> projected;
    if (a != b) {
      // The form's squares are each ≥ 0, its cross term is not: where they cancel (a shear
      // whose movable vertices' gradients vanish, Q singular by pinned vertices) the sum is
      // rounding noise of their size, and the lane counts as degenerate.
      const V squares = weighted + squared_norm(value.d_second) * q[b][b];
      const V cross = dot(value.d_first, value.d_second) * q[a][b];
      weighted = squares + (cross + cross);
      projected = mask_and(pbd_valid(value.valid, value.C, weighted),
                           weighted > squares * splat<V>(kStrainFormRoundOff));
    } else {
      projected = pbd_valid(value.valid, value.C, weighted);
    }
    const V scale = pbd_multiplier(stiffness[s], value.C, weighted, projected);
    // s D_a and s D_b on the projected lanes (a lane left out may hold a non-finite D).
    const Vec3<V> step_a = keep_if(projected, value.d_first * scale);
    step_sum[a] += step_a;
    if (a != b) {
      const Vec3<V> step_b = keep_if(projected, value.d_second * scale);
      step_sum[b] += step_b;
      for (int j = 0; j < Dim; ++j) f[j] -= step_a * q[j][a] + step_b * q[j][b];
    } else {
      for (int j = 0; j < Dim; ++j) f[j] -= step_a * q[j][a];
    }
    // A zero-stiffness sub-constraint is skipped (its step is zero whatever it computed).
    ok = mask_and(ok, mask_or(projected, stiffness[s] == zero<V>()));
  }
  // ∇_{p_{k+1}} = Σ_a M_ka G_a, ∇_{p0} = Σ_a c_0^a G_a; Δp_i = -w_i ∇_i.
  Vec3<V> gradient0 = step_sum[0] * c0[0];
  for (int a = 1; a < Dim; ++a) gradient0 += step_sum[a] * c0[a];
  corr[0] = keep_if(ok, gradient0 * (zero<V>() - w[0]));
  for (int k = 0; k < Dim; ++k) {
    Vec3<V> gradient = step_sum[0] * m[k][0];
    for (int a = 1; a < Dim; ++a) gradient += step_sum[a] * m[k][a];
    corr[k + 1] = keep_if(ok, gradient * (zero<V>() - w[k + 1]));
  }
  return ok;
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_STRAIN_INL_H_
