// The solver through its public API: the four modes agree on the rest shape and reduce the
// residual, any thread count gives bitwise the same state for every mode and colouring
// strategy, static particles stay put, momentum is conserved, λ and positions map back to
// the user's numbering, kinematic particles follow the user, bad settings are rejected, and a
// long run stays finite with bounded energy.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <tessera/coloring/colouring_statistics.hpp>
#include <tessera/core/error.hpp>
#include <tessera/parallel/solver.hpp>

#include "batch_test_support.hpp"
#include "scenes.hpp"
#include "test_support.hpp"

namespace tessera {
namespace solver_tests {

using test::BarMaterial;
using test::ClothBending;

using test::make_solver;
using test::same_bits;

double max_distance(const std::vector<Vector3r>& a, const std::vector<Vector3r>& b) {
  double result = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    result = std::max(result, double((a[i] - b[i]).norm()));
  return result;
}

/// Steps of settle(): 300 (5 s); 150 in a sanitized build, where the damped models have
/// settled as far as the assertions below look (hybrid cloth 1e-3 from the sequential shape
/// against the bound 1e-2, bar 0.049 and jacobi bar 0.056 as after 300) in half the time of
/// the suite's longest test under ASan. 120 would not do (hybrid cloth 8e-3).
constexpr std::size_t kSettleSteps = test::kSanitizedBuild ? 150 : 300;

/// The shape a model settles into (heavily damped, `iterations` per step).
std::vector<Vector3r> settle(const Model& model, SolverMode mode, std::size_t iterations,
                             std::size_t steps = kSettleSteps) {
  SolverSettings settings;
  settings.mode = mode;
  settings.iterations = iterations;
  settings.velocity_damping = 5;
  settings.hybrid_threshold = 10;  // the small tail colours of these small models
  Solver solver = make_solver(model, settings);
  for (std::size_t s = 0; s < steps; ++s) solver.step();
  return solver.positions();
}

// Both models are 1 unit across. gs and hybrid agree with the sequential loop to a fraction
// of a percent; jacobi (constraint averaging) propagates corrections along stiff chains
// slowly, so on the inextensible cloth it is still ~10 % away after 100 iterations per step,
// and it closes in as iterations grow.
TEST(Solver, ModesReachTheSameRestShape) {
  const Model cloth = test::cloth_model(10, 10);
  const Model bar = test::tet_bar_model(2, 2, 10, BarMaterial::fem_tetra, Real(1e5));
  const auto cloth_reference = settle(cloth, SolverMode::sequential, 100);
  const auto bar_reference = settle(bar, SolverMode::sequential, 100);
  for (const SolverMode mode : {SolverMode::gs, SolverMode::hybrid}) {
    SCOPED_TRACE(test::mode_name(mode));
    const double cloth_distance = max_distance(settle(cloth, mode, 100), cloth_reference);
    const double bar_distance = max_distance(settle(bar, mode, 100), bar_reference);
    std::printf("%s cloth %.3g bar %.3g\n", test::mode_name(mode).c_str(), cloth_distance, bar_distance);
    EXPECT_LT(cloth_distance, 0.01);
    // hybrid: most colours of this small bar are below the threshold and go to Jacobi.
    EXPECT_LT(bar_distance, mode == SolverMode::gs ? 0.02 : 0.06);
  }
  const double bar_jacobi = max_distance(settle(bar, SolverMode::jacobi, 100), bar_reference);
  std::printf("jacobi bar %.3g\n", bar_jacobi);
  EXPECT_LT(bar_jacobi, 0.08);
  // Jacobi's convergence on the cloth is a numerical property that the plain builds check; the
  // 525 iterations x 300 steps would be half a minute of an instrumented run that looks for
  // bad accesses and races, which the runs above already cover in every mode.
  if (test::kSanitizedBuild) return;
  const double jacobi_25 = max_distance(settle(cloth, SolverMode::jacobi, 25), cloth_reference);
  const double jacobi_100 = max_distance(settle(cloth, SolverMode::jacobi, 100), cloth_reference);
  const double jacobi_400 = max_distance(settle(cloth, SolverMode::jacobi, 400), cloth_reference);
  EXPECT_LT(jacobi_100, jacobi_25);
  EXPECT_LT(jacobi_400, jacobi_100);
  std::printf("jacobi cloth %.3g %.3g %.3g\n", jacobi_25, jacobi_100, jacobi_400);
  EXPECT_LT(jacobi_400, 0.03);
}

TEST(Solver, EveryModeReducesTheResidualOverIterations) {
  for (const auto& [name, model] :
       {std::pair{"cloth", test::cloth_model(12, 12)},
        std::pair{"bar", test::tet_bar_model(2, 2, 8, BarMaterial::fem_tetra, Real(1e5))}}) {
    for (const SolverMode mode : test::kSolverModes) {
      SCOPED_TRACE(std::string(name) + " " + test::mode_name(mode));
      SolverSettings settings;
      settings.mode = mode;
      settings.iterations = 30;
      settings.record_convergence = true;
      settings.hybrid_threshold = 60;
      settings.time_step = Real(0.05);  // a long step: a large prediction error to remove
      Solver solver = make_solver(model, settings);
      solver.step();
      const auto& history = solver.last_step().history;
      ASSERT_EQ(history.size(), settings.iterations + 1);
      EXPECT_GT(history.front().rms, 0);
      EXPECT_LT(history.back().rms, 0.5 * history.front().rms);
      EXPECT_LT(history[10].rms, history[1].rms);
      EXPECT_EQ(history.front().rms, solver.last_step().residual_before.rms);
    }
  }
}

TEST(Solver, AnyThreadCountGivesBitwiseTheSameStateForEveryModeAndStrategy) {
  const Model models[] = {test::cloth_model(12, 10, ClothBending::dihedral, Real(1e-3), Real(1e-6)),
                          test::tet_bar_model(2, 2, 5, BarMaterial::fem_tetra, Real(1e5))};
  for (const Model& model : models)
    for (const SolverMode mode : test::kSolverModes)
      for (const auto strategy : ColouringRegistry::with_builtin_strategies().names()) {
        if (mode == SolverMode::sequential && strategy != "greedy") continue;
        SCOPED_TRACE(test::mode_name(mode) + " " + std::string(strategy));
        std::vector<Vector3r> result[2];
        std::uint64_t projections[2];
        for (const std::size_t threads : {1, 2}) {
          SolverSettings settings;
          settings.mode = mode;
          settings.threads = threads;
          settings.iterations = 4;
          settings.block_size = 32;  // many blocks even on small models
          settings.hybrid_threshold = 40;
          Solver solver = make_solver(model, settings, std::string(strategy).c_str());
          for (int s = 0; s < 50; ++s) solver.step();
          result[threads - 1] = solver.positions();
          projections[threads - 1] = solver.statistics().projections;
        }
        EXPECT_TRUE(same_bits(result[0], result[1]));
        EXPECT_EQ(projections[0], 50u * 4u * model.constraints.size());
        EXPECT_EQ(projections[0], projections[1]);
      }
}

// More solver threads than the machine runs at once (TBB then runs some of a phase's tasks
// after others) must neither hang nor change a bit.
TEST(Solver, MoreThreadsThanTheMachineRunsNeitherHangNorChangeTheResult) {
  const Model cloth = test::cloth_model(24, 20);
  std::vector<Vector3r> result[2];
  for (const std::size_t threads : {std::size_t(1), std::size_t(7)}) {
    SolverSettings settings;
    settings.threads = threads;
    settings.iterations = 3;
    settings.block_size = 16;  // Jacobi sets (contacts, dynamic constraints) in many blocks
    Solver solver = make_solver(cloth, settings, "stencil");
    for (int s = 0; s < 20; ++s) solver.step();
    result[threads == 1 ? 0 : 1] = solver.positions();
  }
  EXPECT_TRUE(same_bits(result[0], result[1]));
}

TEST(Solver, StaticParticlesStayExactlyWhereTheyAre) {
  const Model model = test::cloth_model(8, 8);
  for (const SolverMode mode : test::kSolverModes) {
    SCOPED_TRACE(test::mode_name(mode));
    SolverSettings settings;
    settings.mode = mode;
    Solver solver = make_solver(model, settings, "metis");
    for (int s = 0; s < 20; ++s) solver.step();
    for (ParticleIndex p = 0; p < model.particles.size(); ++p) {
      if (model.particles.inverse_mass[p] != 0) continue;
      EXPECT_EQ(solver.position(p), model.particles.position(p));
      EXPECT_EQ(solver.velocity(p), Vector3r::Zero());
    }
  }
}

TEST(Solver, GaussSeidelConservesLinearMomentumOfAFreeBody) {
  Model model = test::cloth_model(9, 7);
  std::mt19937 random(3);
  std::uniform_real_distribution<Real> jitter(-0.5, 0.5);
  for (std::size_t p = 0; p < model.particles.size(); ++p) model.particles.inverse_mass[p] = 1;
  for (const SolverMode mode : {SolverMode::gs, SolverMode::sequential}) {
    SCOPED_TRACE(test::mode_name(mode));
    SolverSettings settings;
    settings.mode = mode;
    settings.gravity = Vector3r::Zero();
    settings.threads = 2;
    Solver solver = make_solver(model, settings);
    Vector3r momentum = Vector3r::Zero();
    for (ParticleIndex p = 0; p < model.particles.size(); ++p) {
      const Vector3r v(jitter(random), jitter(random), jitter(random));
      solver.set_velocity(p, v);
      momentum += v;
    }
    for (int s = 0; s < 30; ++s) solver.step();
    Vector3r after = Vector3r::Zero();
    for (const Vector3r& v : solver.velocities()) after += v;
    EXPECT_LT((after - momentum).norm(), 1e-3 * model.particles.size());
  }
}

// Symplectic Euler over k substeps of h from x0 with v0 under g: v_k = v0 + k·g·h and
// x_k = x0 + k·h·v0 + g·h²·k(k+1)/2, through the fused pass (velocity update and the next
// prediction in one) between substeps and the separate ones around the step's last;
// damping scales each (x − x_prev)/h by (1 − d·h).
TEST(Solver, FreeParticlesFollowSymplecticEulerAcrossSubstepsAndSteps) {
  Model model;
  // Near the origin, so float's rounding of (x − x_prev)/h stays far below one substep's g·h.
  model.particles = ParticleState(std::vector<Vector3r>{Vector3r(0, 0, 0), Vector3r(1, 0, 0)},
                                  std::vector<Real>{Real(1), Real(0)});
  for (const double damping : {0.0, 0.5}) {
    SolverSettings settings;
    settings.mode = SolverMode::gs;
    settings.substeps = 7;
    settings.iterations = 2;
    settings.velocity_damping = Real(damping);
    Solver solver(model, Colouring(), settings);
    solver.set_velocity(0, Vector3r(1, 2, -3));
    const int steps = 5;
    for (int s = 0; s < steps; ++s) solver.step();
    // The same recurrence in double.
    const double h = double(settings.time_step) / double(settings.substeps);
    const double scale = 1 - damping * h;
    double x[3] = {0, 0, 0}, v[3] = {1, 2, -3};
    const double g[3] = {0, -9.81, 0};
    for (int k = 0; k < steps * int(settings.substeps); ++k)
      for (int a = 0; a < 3; ++a) {
        const double previous = x[a];
        v[a] += g[a] * h;
        x[a] += h * v[a];
        v[a] = (x[a] - previous) / h * scale;
      }
    const Vector3r p = solver.position(0), u = solver.velocity(0);
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(double(p[a]), x[a], 2e-5) << "damping " << damping << " axis " << a;
      // One substep's gravity is g·h = 0.023: a substep lost or doubled shows.
      EXPECT_NEAR(double(u[a]), v[a], 2e-3) << "damping " << damping << " axis " << a;
    }
    if (damping == 0) {
      const double t = steps * double(settings.time_step);
      const double k = steps * double(settings.substeps);
      EXPECT_NEAR(double(p.y()), 2 * t - 9.81 * h * h * k * (k + 1) / 2, 2e-5);
      EXPECT_NEAR(double(u.y()), 2 - 9.81 * t, 2e-3);
    }
    EXPECT_EQ(solver.position(1), Vector3r(1, 0, 0)) << "static";
    EXPECT_EQ(solver.velocity(1), Vector3r::Zero()) << "static";
  }
}

TEST(Solver, LambdaAndPositionsMapBackToTheUsersNumbering) {
  // Disjoint distance constraints, each stretched by its own amount: one XPBD iteration
  // gives λ = -C / (w0 + w1 + α̃) per constraint whatever the order, so a mix-up shows.
  const std::size_t n = 300;
  std::vector<Vector3r> rest(2 * n), now(2 * n);
  std::vector<ParticleIndex> pairs(2 * n);
  for (std::size_t c = 0; c < n; ++c) {
    rest[2 * c] = Vector3r(Real(c), 0, 0);
    rest[2 * c + 1] = Vector3r(Real(c), 1, 0);
    now[2 * c] = rest[2 * c];
    now[2 * c + 1] = Vector3r(Real(c), Real(1 + 0.001 * double(c + 1)), 0);
    pairs[2 * c] = ParticleIndex(2 * c + 1);  // the stretched particle first
    pairs[2 * c + 1] = ParticleIndex(2 * c);
  }
  const Real compliance = Real(1e-4), dt = Real(0.01);
  Model model;
  model.particles = ParticleState(now, std::vector<Real>(2 * n, Real(1)));
  model.constraints.distance = make_distance_constraints({pairs, rest, 1, compliance});
  for (const SolverMode mode : {SolverMode::gs, SolverMode::jacobi, SolverMode::sequential}) {
    SCOPED_TRACE(test::mode_name(mode));
    SolverSettings settings;
    settings.mode = mode;
    ColouringOptions options;
    options.locality = true;  // renumbers particles
    Solver solver = make_solver(model, settings, "random", options);
    if (mode != SolverMode::sequential) {
      EXPECT_FALSE(solver.schedule().particle_new_to_old().empty());
    }
    solver.project(1, dt);
    const auto positions = solver.positions();
    // Jacobi over-relaxes by ω (each particle here has one constraint).
    const Real omega = mode == SolverMode::jacobi ? settings.jacobi_relaxation : Real(1);
    for (std::size_t c = 0; c < n; ++c) {
      const Real stretch = Real(0.001 * double(c + 1));
      const Real expected = -omega * stretch / (2 + compliance / (dt * dt));
      EXPECT_NEAR(solver.lambda(ConstraintIndex(c)), expected, 1e-4 * std::abs(expected)) << c;
      EXPECT_EQ(positions[2 * c], solver.position(ParticleIndex(2 * c)));
      EXPECT_NEAR(positions[2 * c + 1].y() - positions[2 * c].y(), 1 + stretch + 2 * expected,
                  1e-5);
    }
  }
}

TEST(Solver, KinematicParticlesFollowTheUser) {
  const Model model = test::cloth_model(8, 8);
  SolverSettings settings;
  Solver solver = make_solver(model, settings, "dsatur");
  const ParticleIndex corner = 7 * 8;  // pinned
  ASSERT_EQ(solver.inverse_mass(corner), 0);
  for (int s = 1; s <= 30; ++s) {
    const Vector3r target = model.particles.position(corner) + Vector3r(0, Real(0.01) * s, 0);
    solver.set_position(corner, target);
    solver.step();
    EXPECT_EQ(solver.position(corner), target);
  }
  // Its neighbour was dragged up with it.
  EXPECT_GT(solver.position(corner + 1).y(), Real(0.1));
}

TEST(Solver, RejectsBadSettingsAndArguments) {
  const Model model = test::cloth_model(4, 4);
  const Colouring colouring = test::colour_model(model);
  const auto fails = [&](auto change) {
    SolverSettings settings;
    change(settings);
    EXPECT_THROW(Solver(model, colouring, settings), InvalidInput);
  };
  fails([](SolverSettings& s) { s.time_step = 0; });
  fails([](SolverSettings& s) { s.time_step = -1; });
  fails([](SolverSettings& s) { s.time_step = std::numeric_limits<Real>::quiet_NaN(); });
  fails([](SolverSettings& s) { s.substeps = 0; });
  fails([](SolverSettings& s) { s.velocity_damping = -1; });
  fails([](SolverSettings& s) { s.jacobi_relaxation = 2; });
  fails([](SolverSettings& s) { s.jacobi_relaxation = 0; });
  fails([](SolverSettings& s) { s.block_size = 0; });
  fails([](SolverSettings& s) { s.gravity.x() = std::numeric_limits<Real>::infinity(); });
  EXPECT_THROW(Solver(model, SolverSettings{}), InvalidInput);  // gs without a colouring
  const Colouring other = test::colour_model(test::cloth_model(5, 4));
  EXPECT_THROW(Solver(model, other, SolverSettings{}), InvalidInput);

  Solver solver(model, colouring, SolverSettings{});
  EXPECT_THROW(solver.position(ParticleIndex(16)), InvalidInput);
  EXPECT_THROW(solver.set_position(0, Vector3r(0, std::nan(""), 0)), InvalidInput);
  EXPECT_THROW(solver.set_velocity(99, Vector3r::Zero()), InvalidInput);
  EXPECT_THROW(solver.lambda(ConstraintIndex(model.constraints.size())), InvalidInput);
  EXPECT_THROW(solver.project(1, 0), InvalidInput);
}

/// A pinned 8×8 cloth plus three free particles that no model constraint touches.
Model cloth_with_free_particles() {
  Model model = test::cloth_model(8, 8);
  std::vector<Vector3r> positions;
  std::vector<Real> inverse_masses;
  for (std::size_t p = 0; p < model.particles.size(); ++p) {
    positions.push_back(model.particles.position(p));
    inverse_masses.push_back(model.particles.inverse_mass[p]);
  }
  for (const Vector3r& p : {Vector3r(2, 0, 0), Vector3r(2.1, 0.05, 0), Vector3r(2.1, -0.05, 0.3)}) {
    positions.push_back(p);
    inverse_masses.push_back(1);
  }
  model.particles = ParticleState(positions, inverse_masses);
  return model;
}

TEST(Solver, DynamicConstraintsAreProjectedEveryIterationAndCanBeReplaced) {
  const Model model = cloth_with_free_particles();
  const ParticleIndex point = 64, edge0 = 65, edge1 = 66;  // the free particles
  const std::vector<ParticleIndex> triple = {point, edge0, edge1};
  const Real thickness = Real(0.25);
  const auto contact = make_edge_point_distance_constraints({triple, 67, thickness, {}});
  const auto distance_to_edge = [&](const std::vector<Vector3r>& x) {
    const Vector3r a = x[edge0], b = x[edge1];
    const Real t = std::clamp((x[point] - a).dot(b - a) / (b - a).squaredNorm(), Real(0), Real(1));
    return (x[point] - (a + t * (b - a))).norm();
  };
  for (const SolverMode mode : test::kSolverModes) {
    std::vector<Vector3r> reference;  // greedy keeps the numbering, metis renumbers
    for (const char* strategy : {"greedy", "metis"}) {
      if (mode == SolverMode::sequential && std::string(strategy) != "greedy") continue;
      std::vector<Vector3r> result[2];
      for (const std::size_t threads : {1, 2}) {
        SCOPED_TRACE(test::mode_name(mode) + " " + strategy + " threads " + std::to_string(threads));
        SolverSettings settings;
        settings.mode = mode;
        settings.threads = threads;
        ColouringOptions options;
        options.locality = true;
        Solver solver = make_solver(model, settings, strategy, options);
        ConstraintSets dynamic;
        dynamic.edge_point_distance = contact;
        solver.set_dynamic_constraints(dynamic);
        EXPECT_EQ(solver.dynamic_constraint_count(), 1u);
        EXPECT_EQ(solver.residual().constraints, model.constraints.size() + 1);
        solver.project(40, settings.time_step);
        result[threads - 1] = solver.positions();
        EXPECT_NEAR(distance_to_edge(result[threads - 1]), thickness, 1e-3);
        EXPECT_EQ(solver.statistics().projections, 40u * (model.constraints.size() + 1));
        // Removing them: the free particles stay where they are.
        solver.set_dynamic_constraints({});
        EXPECT_EQ(solver.residual().constraints, model.constraints.size());
        solver.project(5, settings.time_step);
        EXPECT_EQ(solver.position(point), result[threads - 1][point]);
      }
      EXPECT_TRUE(same_bits(result[0], result[1]));
      if (reference.empty()) reference = result[0];
      for (const ParticleIndex p : triple) {
        EXPECT_LT((result[0][p] - reference[p]).norm(), 1e-5);
      }
    }
  }
}

TEST(Solver, RejectsDynamicConstraintsForMoreParticlesThanTheModel) {
  const Model model = test::cloth_model(4, 4);
  Solver solver(model, test::colour_model(model), SolverSettings{});
  const std::vector<ParticleIndex> triple = {0, 1, 20};
  ConstraintSets dynamic;
  dynamic.edge_point_distance = make_edge_point_distance_constraints({triple, 21, Real(0.1), {}});
  EXPECT_THROW(solver.set_dynamic_constraints(dynamic), InvalidInput);
}

TEST(Solver, AStepThatOverflowsIsUndoneAndReported) {
  // A time step so long that h² g overflows: the first step must throw and leave every
  // position and velocity exactly as before, in every mode.
  const Model model = test::cloth_model(6, 6);
  for (const SolverMode mode : test::kSolverModes) {
    SCOPED_TRACE(test::mode_name(mode));
    SolverSettings settings;
    settings.mode = mode;
    settings.time_step = Real(10) * std::sqrt(std::numeric_limits<Real>::max());
    Solver solver = make_solver(model, settings);
    const auto before = solver.positions();
    EXPECT_THROW(solver.step(), NumericalFailure);
    EXPECT_TRUE(same_bits(solver.positions(), before));
    for (const Vector3r& v : solver.velocities()) EXPECT_EQ(v, Vector3r::Zero());
    EXPECT_EQ(solver.statistics().steps, 0u);
    // A finite projection still works afterwards.
    solver.project(2, Real(0.01));
    for (const Vector3r& p : solver.positions()) EXPECT_TRUE(p.allFinite());
  }
}

double energy(const Solver& solver, const Vector3r& gravity) {
  double result = 0;
  const auto positions = solver.positions();
  const auto velocities = solver.velocities();
  for (ParticleIndex p = 0; p < positions.size(); ++p) {
    const Real w = solver.inverse_mass(p);
    if (w == 0) continue;
    const double m = 1.0 / double(w);
    result += 0.5 * m * double(velocities[p].squaredNorm()) - m * double(gravity.dot(positions[p]));
  }
  return result;
}

TEST(Solver, LongRunStaysFiniteWithBoundedEnergy) {
  const Model model = test::cloth_model(64, 64);
  SolverSettings settings;
  settings.substeps = 2;
  settings.iterations = 4;
  Solver solver = make_solver(model, settings);
  const double initial = energy(solver, settings.gravity);
  double highest = initial;
  // 2,000 steps; 250 in a sanitized build (see kSanitizedBuild), still every colour of
  // this 64 x 64 cloth cut into several work blocks, every step, and the energy checked 20
  // times. The soak test runs 100,000 substeps.
  const int steps = test::kSanitizedBuild ? 250 : 2000;
  for (int s = 1; s <= steps; ++s) {
    solver.step();
    if (s % (steps / 20) == 0) {
      const double e = energy(solver, settings.gravity);
      ASSERT_TRUE(std::isfinite(e)) << "step " << s;
      highest = std::max(highest, e);
    }
  }
  for (const Vector3r& p : solver.positions()) ASSERT_TRUE(p.allFinite());
  // Released from rest, the cloth can only turn potential energy into motion and lose some;
  // it never gains energy beyond rounding.
  EXPECT_LE(highest, initial + 1e-3 * std::abs(initial));
  // And it still holds together: edges stretch most at the two pinned corners, which carry
  // the whole cloth with 4 iterations per substep.
  EXPECT_LT(solver.last_step().residual_after.of(ConstraintFamily::distance).rms, 1.0);
}

TEST(SolverPhaseHook, RunsBeforeTheColoursAndAfterEachInOrderAndChangesNothingByItself) {
  // A 12² cloth in mode gs: every iteration calls the hook once before its phases and once
  // after each colour, in colour order; a hook that writes nothing leaves the state bitwise
  // that of a solver without it; another mode refuses a hook.
  const Model model = test::cloth_model(12, 12);
  SolverSettings settings;
  settings.mode = SolverMode::gs;
  settings.substeps = 2;
  settings.iterations = 3;
  Solver plain = test::make_solver(model, settings);
  Solver hooked = test::make_solver(model, settings);
  const std::size_t colours = hooked.schedule().phase_count();
  ASSERT_GT(colours, 1u);
  std::vector<std::size_t> calls;
  hooked.set_phase_hook([&](std::size_t phase, ParticleArrays particles) {
    EXPECT_EQ(particles.count, model.particles.size());
    calls.push_back(phase);
  });
  plain.step();
  hooked.step();
  std::vector<std::size_t> expected;
  for (std::size_t sweep = 0; sweep < 2 * 3; ++sweep) {
    expected.push_back(Solver::kBeforePhases);
    for (std::size_t k = 0; k < colours; ++k) expected.push_back(k);
  }
  EXPECT_EQ(calls, expected);
  EXPECT_TRUE(test::same_bits(plain.positions(), hooked.positions()));
  hooked.set_phase_hook({});
  hooked.step();
  EXPECT_EQ(calls.size(), expected.size()) << "removed";
  settings.mode = SolverMode::jacobi;
  Solver jacobi = test::make_solver(model, settings);
  EXPECT_EQ(test::error_of([&] { jacobi.set_phase_hook([](std::size_t, ParticleArrays) {}); }),
            "set_phase_hook: mode jacobi has no coloured phases between which to run it (mode "
            "gs has)");
}

}  // namespace solver_tests
}  // namespace tessera
