// Shared helpers of the test suite: seeded random input, rigid motions, finite-difference
// gradients, and the invariant checks every kernel test makes (momentum, static particles,
// corrections along the inverse-mass-weighted gradient, finiteness).
//
// Tolerances follow Real: tests run in both precisions, so they compare against
// kTolerance-style constants from here instead of literals.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <random>
#include <span>
#include <vector>

#include <tessera/core/real.hpp>

namespace tessera::test {

/// True in a build instrumented by AddressSanitizer or ThreadSanitizer (scripts/sanitize,
/// scripts/tsan). Long-running tests shorten their loops there: the instrumented code runs
/// 5-20 times slower, and what those builds look for (a bad access, a race) shows in the
/// first steps as surely as in the ten-thousandth; the full lengths run in the plain builds.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
inline constexpr bool kSanitizedBuild = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
inline constexpr bool kSanitizedBuild = true;
#else
inline constexpr bool kSanitizedBuild = false;
#endif
#else
inline constexpr bool kSanitizedBuild = false;
#endif

/// Round-off scale of Real: about 1e-7 for float, 1e-16 for double.
inline constexpr Real kEpsilon = std::numeric_limits<Real>::epsilon();
/// Relative tolerance for results that should agree "to round-off" after a few dozen flops.
inline constexpr Real kRoundOff = kDoublePrecision ? Real(1e-11) : Real(2e-4);
/// Central-difference step and the tolerance of a finite-difference gradient check
/// (truncation error h² plus cancellation ε/h, relative to the gradient's scale).
inline constexpr Real kFiniteDifferenceStep = kDoublePrecision ? Real(1e-6) : Real(2e-3);
inline constexpr Real kFiniteDifferenceTolerance = kDoublePrecision ? Real(1e-6) : Real(2e-2);

/// A deterministic random source for test input.
class Random {
 public:
  explicit Random(unsigned seed = 12345) : engine_(seed) {}

  Real uniform(Real lo, Real hi) { return std::uniform_real_distribution<Real>(lo, hi)(engine_); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(engine_); }
  Vector3r vector(Real lo = -1, Real hi = 1) {
    return Vector3r(uniform(lo, hi), uniform(lo, hi), uniform(lo, hi));
  }
  Vector3r unit_vector() {
    for (;;) {
      const Vector3r v = vector();
      const Real n = v.norm();
      if (n > Real(0.1) && n <= 1) return v / n;
    }
  }
  /// A uniformly random rotation.
  Matrix3r rotation() {
    const Eigen::Quaternion<Real> q(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1),
                                    uniform(-1, 1));
    return q.normalized().toRotationMatrix();
  }
  /// An inverse mass in [0.5, 2].
  Real inverse_mass() { return uniform(Real(0.5), Real(2)); }

 private:
  std::mt19937 engine_;
};

/// Central-difference gradient of a scalar function of N points.
template <int N, class F>
std::array<Vector3r, N> numeric_gradient(F&& f, const std::array<Vector3r, N>& x,
                                         Real h = kFiniteDifferenceStep) {
  std::array<Vector3r, N> grad;
  for (int i = 0; i < N; ++i) {
    for (int k = 0; k < 3; ++k) {
      std::array<Vector3r, N> plus = x, minus = x;
      plus[i][k] += h;
      minus[i][k] -= h;
      grad[i][k] = (f(plus) - f(minus)) / (2 * h);
    }
  }
  return grad;
}

/// Largest |v| over a set of vectors.
template <class Vectors>
Real max_norm(const Vectors& v) {
  Real m = 0;
  for (const auto& x : v) m = std::max(m, Real(x.norm()));
  return m;
}

/// Every component finite.
template <class Vectors>
::testing::AssertionResult all_finite(const Vectors& v) {
  for (std::size_t i = 0; i < std::size(v); ++i)
    if (!v[i].allFinite())
      return ::testing::AssertionFailure() << "entry " << i << " is not finite: "
                                           << v[i].transpose();
  return ::testing::AssertionSuccess();
}

/// Σ m_i Δp_i = 0 over the movable particles (all w_i > 0), relative to Σ m_i |Δp_i|.
template <std::size_t N>
::testing::AssertionResult conserves_linear_momentum(const std::array<Vector3r, N>& corr,
                                                     const std::array<Real, N>& inv_mass,
                                                     Real tolerance = kRoundOff) {
  Vector3r momentum = Vector3r::Zero();
  Real scale = 0;
  for (std::size_t i = 0; i < N; ++i) {
    momentum += corr[i] / inv_mass[i];
    scale += corr[i].norm() / inv_mass[i];
  }
  if (momentum.norm() <= tolerance * std::max(scale, Real(1e-30)) + kEpsilon)
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "Σ m Δp = " << momentum.transpose()
                                       << " (scale " << scale << ")";
}

/// Σ m_i (x_i - c) × Δp_i = 0 (c the centre of mass), to first order: the check allows an
/// error proportional to |Δp|² since rigid invariance only makes the linearised change
/// torque-free.
template <std::size_t N>
::testing::AssertionResult conserves_angular_momentum(const std::array<Vector3r, N>& x,
                                                      const std::array<Vector3r, N>& corr,
                                                      const std::array<Real, N>& inv_mass,
                                                      Real tolerance = kRoundOff) {
  Vector3r centre = Vector3r::Zero();
  Real mass = 0;
  for (std::size_t i = 0; i < N; ++i) {
    centre += x[i] / inv_mass[i];
    mass += 1 / inv_mass[i];
  }
  centre /= mass;
  Vector3r torque = Vector3r::Zero();
  Real scale = 0;
  for (std::size_t i = 0; i < N; ++i) {
    torque += (x[i] - centre).cross(corr[i]) / inv_mass[i];
    scale += (x[i] - centre).norm() * corr[i].norm() / inv_mass[i];
  }
  if (torque.norm() <= tolerance * std::max(scale, Real(1e-30)) + kEpsilon)
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "Σ m (x - c) × Δp = " << torque.transpose()
                                       << " (scale " << scale << ")";
}

/// Δp_i = -s · w_i · g_i for one scalar s shared by all particles, where g is a reference
/// gradient (typically from numeric_gradient). Fits s by least squares and checks the
/// residual relative to |Δp|; also returns success for all-zero corrections only when
/// allow_zero is set.
template <std::size_t N>
::testing::AssertionResult along_weighted_gradient(const std::array<Vector3r, N>& corr,
                                                   const std::array<Real, N>& inv_mass,
                                                   const std::array<Vector3r, N>& grad,
                                                   Real tolerance = kFiniteDifferenceTolerance,
                                                   Real* fitted_scale = nullptr) {
  Real num = 0, den = 0, corr_scale = 0;
  for (std::size_t i = 0; i < N; ++i) {
    const Vector3r d = inv_mass[i] * grad[i];
    num += -corr[i].dot(d);
    den += d.squaredNorm();
    corr_scale += corr[i].squaredNorm();
  }
  if (den == 0 || corr_scale == 0)
    return ::testing::AssertionFailure() << "zero gradient or zero correction";
  const Real s = num / den;
  if (fitted_scale) *fitted_scale = s;
  Real residual = 0;
  for (std::size_t i = 0; i < N; ++i)
    residual += (corr[i] + s * inv_mass[i] * grad[i]).squaredNorm();
  if (std::sqrt(residual) <= tolerance * std::sqrt(corr_scale))
    return ::testing::AssertionSuccess();
  ::testing::AssertionResult failure = ::testing::AssertionFailure();
  failure << "corrections are not along -w∇C: relative residual "
          << std::sqrt(residual / corr_scale) << "\n";
  for (std::size_t i = 0; i < N; ++i)
    failure << "  corr[" << i << "] = " << corr[i].transpose() << "   -s w ∇C = "
            << (-s * inv_mass[i] * grad[i]).transpose() << "\n";
  return failure;
}

/// Apply a rigid motion x ↦ R x + t to every point.
template <std::size_t N>
std::array<Vector3r, N> transformed(const std::array<Vector3r, N>& x, const Matrix3r& R,
                                    const Vector3r& t) {
  std::array<Vector3r, N> y;
  for (std::size_t i = 0; i < N; ++i) y[i] = R * x[i] + t;
  return y;
}

/// |a - b| ≤ tolerance · max(1, |a|, |b|), componentwise over the vector.
inline ::testing::AssertionResult near_relative(const Vector3r& a, const Vector3r& b,
                                                Real tolerance = kRoundOff) {
  const Real scale = std::max({Real(1), a.norm(), b.norm()});
  if ((a - b).norm() <= tolerance * scale) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << a.transpose() << " vs " << b.transpose()
                                       << " (|diff| " << (a - b).norm() << ")";
}

/// N points near a degenerate configuration, for "never NaN" checks: pattern 0 puts them all
/// near one point, 1 near a line, 2 near a plane; each is displaced from the exact degenerate
/// shape by at most `scale` per component (scale 0 gives the exact degenerate shape).
template <std::size_t N>
std::array<Vector3r, N> near_degenerate_points(Random& random, int pattern, Real scale) {
  const Vector3r origin = random.vector();
  const Vector3r u = random.unit_vector(), v = random.unit_vector();
  std::array<Vector3r, N> x;
  for (auto& p : x) {
    p = origin;
    if (pattern >= 1) p += random.uniform(-1, 1) * u;
    if (pattern >= 2) p += random.uniform(-1, 1) * v;
    p += scale * random.vector();
  }
  return x;
}

/// Inverse masses for the near-degenerate checks: about one in four static.
template <std::size_t N>
std::array<Real, N> masses_with_static(Random& random) {
  std::array<Real, N> w;
  for (Real& m : w) m = random.integer(0, 3) == 0 ? Real(0) : random.inverse_mass();
  return w;
}

inline constexpr std::array<Real, 6> kNearDegenerateScales = {
    0, Real(1e-9), Real(1e-7), Real(1e-5), Real(1e-3), Real(1e-1)};

/// Finite corrections, and all of them zero when the kernel reports false.
template <std::size_t N>
::testing::AssertionResult finite_or_rejected(bool ok, const std::array<Vector3r, N>& corr) {
  if (!all_finite(corr)) return all_finite(corr);
  if (!ok && max_norm(corr) != 0)
    return ::testing::AssertionFailure() << "false with a non-zero correction";
  return ::testing::AssertionSuccess();
}

/// A PBD correction of a constraint with value C = f(x) - rest is Δp_i = -s w_i ∇_i C with
/// s = stiffness · C / Σ_j w_j |∇_j C|²: checks that corr lies along the weighted gradient of
/// f (central differences) and that its step length is that s.
template <std::size_t N, class F>
void expect_pbd_step(F&& f, const std::array<Vector3r, N>& x, const std::array<Real, N>& w,
                     const std::array<Vector3r, N>& corr, Real C, Real stiffness) {
  const auto grad = numeric_gradient<int(N)>(f, x);
  Real fitted = 0;
  EXPECT_TRUE(along_weighted_gradient(corr, w, grad, kFiniteDifferenceTolerance, &fitted));
  Real weighted = 0;
  for (std::size_t i = 0; i < N; ++i) weighted += w[i] * grad[i].squaredNorm();
  const Real expected = stiffness * C / weighted;
  EXPECT_NEAR(fitted, expected, kFiniteDifferenceTolerance * std::abs(expected) + kRoundOff);
}

/// What a scalar solve reports: whether it projected, and the N corrections.
template <std::size_t N>
struct ScalarProjection {
  bool ok = false;
  std::array<Vector3r, N> corr;
};

/// The points moved by their corrections, x_i + corr_i.
template <std::size_t N>
std::array<Vector3r, N> applied(const std::array<Vector3r, N>& x,
                                const std::array<Vector3r, N>& corr) {
  std::array<Vector3r, N> y;
  for (std::size_t i = 0; i < N; ++i) y[i] = x[i] + corr[i];
  return y;
}

/// PBD invariants on random input (seed, `trials` trials): with x = make_points(random),
/// w = make_masses(random), rest = random_rest(random) and a stiffness in [0.2, 1],
/// project(x, w, rest, stiffness) succeeds with finite corrections that conserve linear and
/// angular momentum and are the PBD step of the constraint function f (C = f(x) - rest); under
/// a random rigid motion f is unchanged (within 50 kRoundOff) and the corrections rotate with
/// it (within motion_tolerance).
template <std::size_t N, class MakePoints, class MakeMasses, class RandomRest, class F,
          class Project>
void expect_pbd_invariants_on_random_input(unsigned seed, int trials, MakePoints&& make_points,
                                           MakeMasses&& make_masses, RandomRest&& random_rest,
                                           F&& f, Project&& project, Real motion_tolerance) {
  Random random(seed);
  for (int trial = 0; trial < trials; ++trial) {
    const std::array<Vector3r, N> x = make_points(random);
    const std::array<Real, N> w = make_masses(random);
    const Real rest = random_rest(random);
    const Real stiffness = random.uniform(Real(0.2), Real(1));
    const auto r = project(x, w, rest, stiffness);
    ASSERT_TRUE(r.ok);
    ASSERT_TRUE(all_finite(r.corr));
    EXPECT_TRUE(conserves_linear_momentum(r.corr, w));
    EXPECT_TRUE(conserves_angular_momentum(x, r.corr, w));

    expect_pbd_step(f, x, w, r.corr, f(x) - rest, stiffness);

    const Matrix3r R = random.rotation();
    const Vector3r t = random.vector(-5, 5);
    const std::array<Vector3r, N> y = transformed(x, R, t);
    EXPECT_NEAR(f(y), f(x), 50 * kRoundOff);
    const auto moved = project(y, w, rest, stiffness);
    ASSERT_TRUE(moved.ok);
    for (std::size_t i = 0; i < N; ++i)
      EXPECT_TRUE(near_relative(moved.corr[i], R * r.corr[i], motion_tolerance));
  }
}

/// A static particle is never moved (seed, `trials` trials): with x = make_points(random) and
/// w = make_masses(random) but w[trial % N] = 0, project(x, w, rest, 1) succeeds and leaves
/// that particle's correction exactly zero.
template <std::size_t N, class MakePoints, class MakeMasses, class Project>
void expect_static_particle_never_moved(unsigned seed, int trials, MakePoints&& make_points,
                                        MakeMasses&& make_masses, Real rest, Project&& project) {
  Random random(seed);
  for (int trial = 0; trial < trials; ++trial) {
    const std::array<Vector3r, N> x = make_points(random);
    std::array<Real, N> w = make_masses(random);
    w[std::size_t(trial) % N] = 0;
    const auto r = project(x, w, rest, 1);
    ASSERT_TRUE(r.ok);
    EXPECT_EQ(r.corr[std::size_t(trial) % N], Vector3r::Zero());
  }
}

/// XPBD with zero compliance is PBD with stiffness 1 (seed, `trials` trials): with
/// x = make_points(random) and w = make_masses(random), project_xpbd(x, w, rest, 0, 0.01, λ = 0)
/// succeeds with the corrections of project(x, w, rest, 1) to round-off.
template <std::size_t N, class MakePoints, class MakeMasses, class Project, class ProjectXpbd>
void expect_zero_compliance_equals_pbd(unsigned seed, int trials, MakePoints&& make_points,
                                       MakeMasses&& make_masses, Real rest, Project&& project,
                                       ProjectXpbd&& project_xpbd) {
  Random random(seed);
  for (int trial = 0; trial < trials; ++trial) {
    const std::array<Vector3r, N> x = make_points(random);
    const std::array<Real, N> w = make_masses(random);
    Real lambda = 0;
    const auto xpbd = project_xpbd(x, w, rest, 0, Real(0.01), lambda);
    const auto pbd = project(x, w, rest, 1);
    ASSERT_TRUE(xpbd.ok);
    for (std::size_t i = 0; i < N; ++i) EXPECT_TRUE(near_relative(xpbd.corr[i], pbd.corr[i]));
  }
}

/// Near-degenerate input never gives NaN (seed, 300 trials): N points near one point (pattern
/// trial % patterns: 0 a point, 1 a line, 2 a plane) at each of kNearDegenerateScales, masses
/// with static particles and rest = random_rest(random); project(x, w, rest, 1) and
/// project_xpbd(x, w, rest, 1e-6, 0.01, λ = 0) give finite corrections, all zero when they
/// report false, and a finite λ.
template <std::size_t N, class RandomRest, class Project, class ProjectXpbd>
void expect_near_degenerate_input_stays_finite(unsigned seed, int patterns,
                                               RandomRest&& random_rest, Project&& project,
                                               ProjectXpbd&& project_xpbd) {
  Random random(seed);
  for (int trial = 0; trial < 300; ++trial) {
    const Real scale = kNearDegenerateScales[std::size_t(trial) % kNearDegenerateScales.size()];
    const std::array<Vector3r, N> x = near_degenerate_points<N>(random, trial % patterns, scale);
    const std::array<Real, N> w = masses_with_static<N>(random);
    const Real rest = random_rest(random);
    const auto r = project(x, w, rest, 1);
    EXPECT_TRUE(finite_or_rejected(r.ok, r.corr)) << "scale " << scale;
    Real lambda = 0;
    const auto soft = project_xpbd(x, w, rest, Real(1e-6), Real(0.01), lambda);
    EXPECT_TRUE(finite_or_rejected(soft.ok, soft.corr)) << "scale " << scale;
    EXPECT_TRUE(std::isfinite(lambda));
  }
}

}  // namespace tessera::test
