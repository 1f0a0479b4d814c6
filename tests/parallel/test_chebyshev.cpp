// Chebyshev acceleration of mode jacobi (SolverSettings::chebyshev, Wang 2015): it reaches a
// lower residual than plain Jacobi in the same iterations on a cloth and on a tet bar, the
// n-th iteration is exactly q̂ₙ extrapolated from the positions two iterations back with the
// documented weights, the first `delay` iterations are plain Jacobi bit for bit, any thread
// count gives bitwise the same state, static particles never move, and bad settings are
// rejected naming the setting.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <tessera/core/error.hpp>
#include <tessera/parallel/solver.hpp>

#include "scenes.hpp"
#include "test_support.hpp"

namespace tessera {
namespace chebyshev_tests {

using test::same_bits;

/// Accelerated / plain residual after 48 iterations must stay below these (see below).
constexpr double kClothRatio = 0.95;  // measured 0.915 (float)
constexpr double kBarRatio = 0.95;    // measured 0.913 (float)

SolverSettings jacobi_settings(bool chebyshev, std::size_t iterations) {
  SolverSettings settings;
  settings.mode = SolverMode::jacobi;
  settings.chebyshev = chebyshev;
  settings.iterations = iterations;
  settings.record_convergence = true;
  return settings;
}

/// The measure (distance RMS for a cloth, all-constraint RMS otherwise) after every iteration
/// of one step taken after `warmup` plain steps (so the model is deformed and moving).
std::vector<double> history(const Model& model, bool chebyshev, std::size_t iterations,
                            bool distance_measure, std::size_t warmup = 5) {
  Solver solver = test::make_solver(model, jacobi_settings(chebyshev, iterations));
  SolverSettings plain = jacobi_settings(false, iterations);
  // The same warm-up state for both: plain steps of a separate solver, copied over.
  Solver warm = test::make_solver(model, plain);
  for (std::size_t s = 0; s < warmup; ++s) warm.step();
  const auto positions = warm.positions(), velocities = warm.velocities();
  for (ParticleIndex p = 0; p < positions.size(); ++p) {
    solver.set_position(p, positions[p]);
    solver.set_velocity(p, velocities[p]);
  }
  solver.step();
  std::vector<double> result;
  for (const Residual& r : solver.last_step().history)
    result.push_back(distance_measure ? r.of(ConstraintFamily::distance).rms : r.rms);
  return result;
}

// Known answers, measured (float and double agree to the digits shown): after 48 iterations
// the accelerated residual is this fraction of plain Jacobi's. The bounds leave a margin
// for other SIMD targets; without the acceleration the ratio is 1 and both tests fail.
TEST(Chebyshev, ReachesALowerResidualThanPlainJacobiOnACloth) {
  const Model cloth = test::cloth_model(32, 32);
  const auto plain = history(cloth, false, 48, true);
  const auto accelerated = history(cloth, true, 48, true);
  ASSERT_EQ(plain.size(), 49u);
  EXPECT_EQ(plain[0], accelerated[0]);
  EXPECT_EQ(plain[1], accelerated[1]);  // iterations up to the delay are plain Jacobi
  EXPECT_EQ(plain[2], accelerated[2]);
  const double ratio = accelerated[48] / plain[48];
  std::printf("cloth: plain %.4g, chebyshev %.4g, ratio %.3f\n", plain[48], accelerated[48], ratio);
  EXPECT_LT(ratio, kClothRatio);
  // And it gets to plain Jacobi's 48-iteration residual in at most 2/3 of the iterations.
  std::size_t reached = 0;
  while (accelerated[reached] > plain[48]) ++reached;
  EXPECT_LE(reached, 32u);
}

TEST(Chebyshev, ReachesALowerResidualThanPlainJacobiOnATetBar) {
  const Model bar = test::tet_bar_model(3, 3, 12, test::BarMaterial::fem_tetra, Real(1e6));
  const auto plain = history(bar, false, 48, false);
  const auto accelerated = history(bar, true, 48, false);
  const double ratio = accelerated[48] / plain[48];
  std::printf("bar: plain %.4g, chebyshev %.4g, ratio %.3f\n", plain[48], accelerated[48], ratio);
  EXPECT_LT(ratio, kBarRatio);
  // In the XPBD residual (|C + α̃λ| / sqrt(V) for FEM, residual.hpp) the bar needs more of its
  // iterations to get there than the cloth: 41 of 48 measured.
  std::size_t reached = 0;
  while (accelerated[reached] > plain[48]) ++reached;
  EXPECT_LE(reached, 44u);
}

// One distance constraint, one movable particle, PBD semantics (no λ): the iterations are
// q̂ₙ = qₙ₋₁ + ω_J (target − qₙ₋₁) along the line, and the accelerated ones must be exactly
// qₙ = qₙ₋₂ + ωₙ (q̂ₙ − qₙ₋₂) with ω₁ = ω₂ = 1 (delay 2), ω₃ = 2 / (2 − ρ²),
// ωₙ = 4 / (4 − ρ² ωₙ₋₁).
TEST(Chebyshev, FollowsTheSemiIterativeRecurrence) {
  const std::vector<Vector3r> points = {Vector3r(0, 0, 0), Vector3r(1, 0, 0)};
  const std::vector<Vector3r> stretched = {Vector3r(0, 0, 0), Vector3r(Real(1.4), 0, 0)};
  const std::vector<ParticleIndex> edge = {0, 1};
  Model model;
  model.particles = ParticleState(stretched, std::vector<Real>{0, 1});
  model.constraints.distance = make_distance_constraints({edge, points});
  SolverSettings settings;
  settings.mode = SolverMode::jacobi;
  settings.semantics = ConstraintSemantics::stiffness;
  settings.chebyshev = true;
  settings.chebyshev_rho = Real(0.8);
  const Real omega_j = settings.jacobi_relaxation, rho2 = Real(0.64);
  std::vector<double> expected = {1.4};  // x of particle 1 after 0, 1, 2, ... iterations
  double weight = 1;
  for (int n = 1; n <= 6; ++n) {
    const double previous = expected.back();
    const double jacobi = previous + omega_j * (1 - previous);
    weight = n <= 2 ? 1 : n == 3 ? 2 / (2 - rho2) : 4 / (4 - rho2 * weight);
    expected.push_back(n <= 2 ? jacobi : expected[n - 2] + weight * (jacobi - expected[n - 2]));
  }
  for (int n = 1; n <= 6; ++n) {
    Solver solver(model, test::colour_model(model), settings);
    solver.project(std::size_t(n), settings.time_step);
    EXPECT_NEAR(solver.position(1).x(), expected[n], 1e-5) << n;
    EXPECT_EQ(solver.position(0), Vector3r::Zero());
  }
}

TEST(Chebyshev, AnyThreadCountGivesBitwiseTheSameState) {
  // 80² particles: more than one chunk of the reduction, so two threads really split it.
  const Model cloth = test::cloth_model(80, 80);
  std::vector<Vector3r> result[2];
  for (const std::size_t threads : {1, 2}) {
    SolverSettings settings = jacobi_settings(true, 12);
    settings.threads = threads;
    settings.block_size = 64;
    Solver solver = test::make_solver(cloth, settings);
    for (int s = 0; s < 5; ++s) solver.step();
    solver.project(9, settings.time_step);
    result[threads - 1] = solver.positions();
  }
  EXPECT_TRUE(same_bits(result[0], result[1]));
}

TEST(Chebyshev, StaticParticlesStayExactlyWhereTheyAre) {
  const Model models[] = {test::cloth_model(16, 16),
                          test::tet_bar_model(2, 2, 8, test::BarMaterial::fem_tetra, Real(1e5))};
  for (const Model& model : models) {
    Solver solver = test::make_solver(model, jacobi_settings(true, 16));
    for (int s = 0; s < 20; ++s) solver.step();
    solver.project(10, Real(1) / 60);
    std::size_t statics = 0;
    for (ParticleIndex p = 0; p < model.particles.size(); ++p) {
      if (model.particles.inverse_mass[p] != 0) continue;
      ++statics;
      EXPECT_EQ(solver.position(p), model.particles.position(p));
    }
    EXPECT_GT(statics, 0u);
  }
}

TEST(Chebyshev, IsAnOptionOfModeJacobiOnly) {
  EXPECT_FALSE(SolverSettings{}.chebyshev);
  // hybrid: the setting changes nothing.
  const Model cloth = test::cloth_model(12, 12);
  std::vector<Vector3r> result[2];
  for (const bool chebyshev : {false, true}) {
    SolverSettings settings = jacobi_settings(chebyshev, 10);
    settings.mode = SolverMode::hybrid;
    settings.hybrid_threshold = 60;
    Solver solver = test::make_solver(cloth, settings);
    for (int s = 0; s < 5; ++s) solver.step();
    result[chebyshev] = solver.positions();
  }
  EXPECT_TRUE(same_bits(result[0], result[1]));
}

TEST(Chebyshev, RejectsABadRhoOrDelayNamingTheSetting) {
  const Model model = test::cloth_model(4, 4);
  const Colouring colouring = test::colour_model(model);
  const auto message = [&](auto change) -> std::string {
    SolverSettings settings;
    change(settings);
    try {
      Solver(model, colouring, settings);
    } catch (const InvalidInput& error) {
      return error.what();
    }
    return "no error";
  };
  for (const Real rho : {Real(0), Real(1), Real(-0.5), Real(1.5),
                         std::numeric_limits<Real>::quiet_NaN()}) {
    const std::string text = message([&](SolverSettings& s) { s.chebyshev_rho = rho; });
    EXPECT_NE(text.find("chebyshev_rho"), std::string::npos) << text;
    EXPECT_NE(text.find("(0, 1)"), std::string::npos) << text;
  }
  EXPECT_EQ(message([](SolverSettings& s) { s.chebyshev_delay = 0; }),
            "solver settings: chebyshev_delay must be at least 1");
  EXPECT_EQ(message([](SolverSettings& s) { s.chebyshev_rho = Real(0.5); }), "no error");
}

}  // namespace chebyshev_tests
}  // namespace tessera
