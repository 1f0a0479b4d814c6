// Strain based dynamics (Müller, Chentanez, Kim, Macklin 2014, "Strain Based Dynamics"), the
// one formula of the strain triangle and strain tetrahedron families, over lanes.
//
// An element of Dim + 1 particles (Dim = 2: triangle, 3: tetrahedron) with the inverse rest
// edge matrix M (Dim×Dim) has F = [p1 - p0, ..., p_Dim - p0] · M, whose columns are
//   f_j = Σ_k M_kj (p_{k+1} - p0).
// Each entry of S = FᵀF is its own sub-constraint, projected with the PBD rule on the
// positions the previous ones corrected (Gauss–Seidel inside the element):
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

/// C and ∇C of one sub-constraint at positions p.
template <int Dim, class V>
HWY_INLINE ConstraintValue<V, Dim + 1> strain_sub_constraint(const Vec3<V> (&p)[Dim + 1],
                                                             const V (&m)[Dim][Dim],
                                                             StrainEntry entry,
                                                             bool normalize_stretch,
                                                             bool normalize_shear) {
  Vec3<V> edge[Dim];
  for (int k = 0; k < Dim; ++k) edge[k] = p[k + 1] - p[0];
  const Vec3<V> fa = strain_column<Dim>(edge, m, entry.first);

  ConstraintValue<V, Dim + 1> value;
  value.valid = all_lanes<V>();
  Vec3<V> d_first, d_second = Vec3<V>::zeros();
  const bool stretch = entry.first == entry.second;
  if (stretch) {
    if (normalize_stretch) {
      const V length = norm(fa);
      value.valid = length > splat<V>(kDegenerateTolerance);
      value.C = length - splat<V>(1.0);
      d_first = fa * safe_divide(splat<V>(1.0), length, value.valid);
    } else {
      value.C = squared_norm(fa) - splat<V>(1.0);
      d_first = fa * splat<V>(2.0);
    }
  } else {
    const Vec3<V> fb = strain_column<Dim>(edge, m, entry.second);
    if (normalize_shear) {
      const V length_a = norm(fa), length_b = norm(fb);
      value.valid = mask_and(length_a > splat<V>(kDegenerateTolerance),
                             length_b > splat<V>(kDegenerateTolerance));
      const V inverse_a = safe_divide(splat<V>(1.0), length_a, value.valid);
      const V inverse_b = safe_divide(splat<V>(1.0), length_b, value.valid);
      const Vec3<V> unit_a = fa * inverse_a, unit_b = fb * inverse_b;
      value.C = dot(unit_a, unit_b);
      d_first = (unit_b - unit_a * value.C) * inverse_a;
      d_second = (unit_a - unit_b * value.C) * inverse_b;
    } else {
      value.C = dot(fa, fb);
      d_first = fb;
      d_second = fa;
    }
  }

  value.gradient[0] = Vec3<V>::zeros();
  for (int k = 0; k < Dim; ++k) {
    Vec3<V> g = d_first * m[k][entry.first];
    if (!stretch) g += d_second * m[k][entry.second];
    value.gradient[k + 1] = g;
    value.gradient[0] -= g;
  }
  return value;
}

/// Projects the Count sub-constraints in order (entries[s] with stiffness[s]) and writes the
/// summed corrections. Returns the lanes where no active sub-constraint was degenerate;
/// every other lane gets zero corrections.
template <int Dim, int Count, class V>
HWY_INLINE Mask<V> project_strain(Vec3<V> (&p)[Dim + 1], const V (&w)[Dim + 1],
                                  const V (&m)[Dim][Dim], const StrainEntry (&entries)[Count],
                                  const V (&stiffness)[Count], bool normalize_stretch,
                                  bool normalize_shear, Vec3<V> (&corr)[Dim + 1]) {
  constexpr int N = Dim + 1;
  Mask<V> ok = all_lanes<V>();
  for (int i = 0; i < N; ++i) corr[i] = Vec3<V>::zeros();
  for (int s = 0; s < Count; ++s) {
    const auto value =
        strain_sub_constraint<Dim>(p, m, entries[s], normalize_stretch, normalize_shear);
    Vec3<V> step[N];
    const Mask<V> projected = project_pbd(value, w, stiffness[s], step);
    // A zero-stiffness sub-constraint is skipped (its step is zero whatever it computed).
    ok = mask_and(ok, mask_or(projected, stiffness[s] == zero<V>()));
    for (int i = 0; i < N; ++i) {
      p[i] += step[i];
      corr[i] += step[i];
    }
  }
  for (int i = 0; i < N; ++i) corr[i] = keep_if(ok, corr[i]);
  return ok;
}

}  // namespace HWY_NAMESPACE
}  // namespace tessera
HWY_AFTER_NAMESPACE();

#endif  // TESSERA_CORE_KERNELS_STRAIN_INL_H_
