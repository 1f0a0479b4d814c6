// Numerical robustness: the solver under heavily compressed and inverted elements, extreme
// stiffness and compliance, tiny and huge time steps, coordinates far from the origin and
// all-static models, in every mode. The promise checked throughout (Solver::step, with
// SolverSettings::check_finite on, the default): a step either leaves every position and
// velocity finite, or throws NumericalFailure and leaves them bit for bit as they were
// before it. The API never hands NaN back to the user.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/core/error.hpp>
#include <tessera/parallel/solver.hpp>

#include "scenes.hpp"

namespace tessera {
namespace numerics_tests {

using test::make_solver;
using test::same_bits;

bool all_finite(const std::vector<Vector3r>& points) {
  return std::all_of(points.begin(), points.end(), [](const Vector3r& p) { return p.allFinite(); });
}

/// Steps `steps` times checking the promise after each; returns how many steps threw
/// NumericalFailure (each of which must have left positions and velocities untouched).
/// These tests probe what stays finite under extreme parameters, where constraints end
/// violated far beyond any physical state; the divergence check (parallel.SequentialOrder,
/// robustness.ErrorCatalogue.DivergenceBoundAndADivergedStep) would refuse those steps first.
constexpr Real kUnchecked = std::numeric_limits<Real>::infinity();

int step_checked(Solver& solver, int steps) {
  int failures = 0;
  for (int s = 0; s < steps; ++s) {
    const auto positions = solver.positions();
    const auto velocities = solver.velocities();
    try {
      solver.step();
    } catch (const NumericalFailure&) {
      ++failures;
      EXPECT_TRUE(same_bits(solver.positions(), positions)) << "step " << s;
      EXPECT_TRUE(same_bits(solver.velocities(), velocities)) << "step " << s;
      continue;
    }
    EXPECT_TRUE(all_finite(solver.positions())) << "step " << s;
    EXPECT_TRUE(all_finite(solver.velocities())) << "step " << s;
  }
  return failures;
}

/// Signed volumes of the bar's tetrahedra at the solver's positions.
std::vector<Real> signed_volumes(const Solver& solver, const std::vector<ParticleIndex>& tets) {
  std::vector<Real> result;
  const auto x = solver.positions();
  for (std::size_t t = 0; t + 3 < tets.size(); t += 4) {
    const Vector3r a = x[tets[t]];
    result.push_back((x[tets[t + 1]] - a).dot((x[tets[t + 2]] - a).cross(x[tets[t + 3]] - a)) / 6);
  }
  return result;
}

// ---- inversion --------------------------------------------------------------------------

TEST(Numerics, InvertedAndCompressedTetrahedraRecoverWithHandleInversion) {
  // A 2 x 2 x 4 FEM bar (handle_inversion on) fixed at z = 0: every movable vertex mirrored
  // through the fixed end (z → −z/2: every element inverted and compressed to half its
  // height), or squashed to 5 % of its height. It must come back: no inverted element left,
  // every position finite, every step normal.
  const io::TetrahedralBar bar = io::make_tetrahedral_bar(2, 2, 4, Real(0.1));
  const Model model = test::tet_bar_model(2, 2, 4, test::BarMaterial::fem_tetra);
  ASSERT_TRUE(model.constraints.fem_tetra.handle_inversion);
  for (const bool mirror : {true, false}) {
    for (const SolverMode mode : test::kSolverModes) {
      SCOPED_TRACE(test::mode_name(mode) + (mirror ? " mirrored" : " squashed"));
      SolverSettings settings;
      settings.mode = mode;
      settings.gravity = Vector3r::Zero();
      settings.substeps = 4;
      settings.velocity_damping = 1;
      Solver solver = make_solver(model, settings);
      for (ParticleIndex v = 0; v < solver.particle_count(); ++v) {
        if (solver.inverse_mass(v) == 0) continue;
        Vector3r p = solver.position(v);
        p.z() = mirror ? -p.z() / 2 : p.z() / 20;
        solver.set_position(v, p);
      }
      const auto before = signed_volumes(solver, bar.tetrahedron_indices);
      if (mirror) {
        EXPECT_TRUE(std::all_of(before.begin(), before.end(), [](Real v) { return v < 0; }));
      }
      EXPECT_EQ(step_checked(solver, 300), 0);
      const auto after = signed_volumes(solver, bar.tetrahedron_indices);
      EXPECT_TRUE(std::all_of(after.begin(), after.end(), [](Real v) { return v > 0; }));
      // Back to about its rest length (0.4) along z.
      Real top = 0;
      for (const Vector3r& p : solver.positions()) top = std::max(top, p.z());
      EXPECT_NEAR(top, Real(0.4), Real(0.05));
    }
  }
}

// ---- extreme parameters ------------------------------------------------------------------

TEST(Numerics, ExtremeComplianceStaysFinite) {
  // XPBD compliance 0 (rigid), 1e-12 and 1e12 (no resistance: free fall) on a cloth's
  // distance and bending constraints.
  for (const Real compliance : {Real(0), Real(1e-12), Real(1e12)}) {
    const Model model = test::cloth_model(6, 6, test::ClothBending::dihedral, compliance, compliance);
    for (const SolverMode mode : test::kSolverModes) {
      SCOPED_TRACE(test::mode_name(mode) + " compliance " + std::to_string(compliance));
      SolverSettings settings;
      settings.mode = mode;
      Solver solver = make_solver(model, settings);
      EXPECT_EQ(step_checked(solver, 60), 0);
      // Rigid: the edges keep their length; no resistance: the free corner falls freely.
      const auto x = solver.positions();
      const Real fallen = model.particles.position(0).y() - x[0].y();
      if (compliance == Real(1e12)) {
        EXPECT_NEAR(fallen, Real(0.5 * 9.81), Real(0.1));
      } else {
        EXPECT_LT(fallen, Real(1.1));
      }
    }
  }
}

TEST(Numerics, ExtremeStiffnessAndYoungsModulusStayFinite) {
  for (const Real youngs_modulus : {Real(1e-12), Real(1e12)}) {
    const Model model = test::tet_bar_model(2, 2, 4, test::BarMaterial::fem_tetra, youngs_modulus);
    for (const SolverMode mode : test::kSolverModes) {
      SCOPED_TRACE(test::mode_name(mode) + " E " + std::to_string(youngs_modulus));
      SolverSettings settings;
      settings.divergence_rms = kUnchecked;
      settings.mode = mode;
      Solver solver = make_solver(model, settings);
      EXPECT_EQ(step_checked(solver, 60), 0);
    }
  }
  // PBD stiffness semantics with stiffness 0, 1e-12, 1 and 1e12 (far outside the meaningful
  // [0, 1]: overshoots every projection). Either finite or refused, never NaN.
  for (const Real stiffness : {Real(0), Real(1e-12), Real(1), Real(1e12)}) {
    Model model = test::cloth_model(6, 6);
    std::fill(model.constraints.distance.stiffness.begin(),
              model.constraints.distance.stiffness.end(), stiffness);
    std::fill(model.constraints.dihedral.stiffness.begin(),
              model.constraints.dihedral.stiffness.end(), stiffness);
    for (const SolverMode mode : test::kSolverModes) {
      SCOPED_TRACE(test::mode_name(mode) + " stiffness " + std::to_string(stiffness));
      SolverSettings settings;
      settings.divergence_rms = kUnchecked;
      settings.mode = mode;
      settings.semantics = ConstraintSemantics::stiffness;
      Solver solver = make_solver(model, settings);
      const int failures = step_checked(solver, 60);
      if (stiffness <= 1) {
        EXPECT_EQ(failures, 0);
      }
    }
  }
}

// ---- time steps ---------------------------------------------------------------------------

TEST(Numerics, TinyAndHugeTimeSteps) {
  const Model cloth = test::cloth_model(6, 6);
  const Model bar = test::tet_bar_model(2, 2, 4);
  for (const Real dt : {Real(1e-9), Real(1e-6), Real(1), Real(100)}) {
    for (const Model* model : {&cloth, &bar}) {
      for (const SolverMode mode : test::kSolverModes) {
        SCOPED_TRACE(test::mode_name(mode) + " dt " + std::to_string(dt));
        SolverSettings settings;
      settings.divergence_rms = kUnchecked;
        settings.mode = mode;
        settings.time_step = dt;
        Solver solver = make_solver(*model, settings);
        EXPECT_EQ(step_checked(solver, 20), 0);
        if (dt <= Real(1e-6)) {
          // Nothing can move further than g t² in 20 tiny steps.
          Real moved = 0;
          const auto x = solver.positions();
          for (ParticleIndex p = 0; p < x.size(); ++p)
            moved = std::max(moved, (x[p] - model->particles.position(p)).norm());
          EXPECT_LT(moved, Real(1e-6));
        }
      }
    }
  }
}

TEST(Numerics, OverflowingTimeStepIsRefusedNotWritten) {
  // h·g overflows: each of several steps is refused, and a refused step changes nothing.
  const Model model = test::cloth_model(6, 6);
  for (const SolverMode mode : test::kSolverModes) {
    SCOPED_TRACE(test::mode_name(mode));
    SolverSettings settings;
    settings.mode = mode;
    settings.time_step = std::numeric_limits<Real>::max() / 4;
    Solver solver = make_solver(model, settings);
    const auto start = solver.positions();
    EXPECT_EQ(step_checked(solver, 3), 3);
    EXPECT_TRUE(same_bits(solver.positions(), start));
    EXPECT_EQ(solver.statistics().steps, 0u);
  }
}

TEST(Numerics, RunawayVelocityIsRefusedWhenItOverflows) {
  // A particle thrown at half the largest float per second: its constraints cannot hold it
  // (the kernels skip corrections they cannot compute), it flies off with finite positions
  // until a step would take it past the largest float; that step, and every one after it, is
  // refused and changes nothing.
  const Model model = test::cloth_model(6, 6);
  const Vector3r thrown(std::numeric_limits<Real>::max() / 2, 0, 0);
  for (const SolverMode mode : test::kSolverModes) {
    SCOPED_TRACE(test::mode_name(mode));
    SolverSettings settings;
      settings.divergence_rms = kUnchecked;
    settings.mode = mode;
    settings.time_step = Real(1);
    Solver solver = make_solver(model, settings);
    solver.set_velocity(0, thrown);
    EXPECT_GE(step_checked(solver, 5), 1);
    EXPECT_GE(std::abs(solver.position(0).x()), std::numeric_limits<Real>::max() / 4);
    // The user can repair the state and go on: a projection right away (it keeps the XPBD
    // multipliers from before it, so must not find the refused step's) and steps.
    for (ParticleIndex p = 0; p < solver.particle_count(); ++p) {
      solver.set_position(p, model.particles.position(p));
      solver.set_velocity(p, Vector3r::Zero());
    }
    EXPECT_NO_THROW(solver.project(3, Real(1) / Real(60)));
    EXPECT_TRUE(all_finite(solver.positions()));
    EXPECT_EQ(step_checked(solver, 10), 0);
  }
}

TEST(Numerics, WithoutCheckFiniteTheSameStepWritesNonFiniteValues) {
  // The control for the tests above: with the check off, an overflowing step does write
  // non-finite positions, so it is check_finite that keeps them from the user.
  const Model model = test::cloth_model(6, 6);
  SolverSettings settings;
  settings.check_finite = false;
  settings.time_step = std::numeric_limits<Real>::max() / 4;
  Solver solver = make_solver(model, settings);
  solver.step();
  EXPECT_FALSE(all_finite(solver.positions()));
}

TEST(Numerics, GreedyColouringOfConstraintsWithoutMovableParticles) {
  // Regression (found by AllParticlesStaticNeverMove under UBSan): the greedy colouring's
  // prefetch read the particle 16 constraints ahead even when that constraint, being all
  // static, had no entry in the graph: one past the end of the graph's particle array, or a
  // load through its null data() when no constraint has a movable particle.
  for (const std::size_t movable : {0, 1}) {
    Model model = test::cloth_model(6, 6);
    std::vector<Real> masses(model.particles.size(), Real(0));
    if (movable) masses[0] = 1;  // only the first constraints have an entry
    std::vector<Vector3r> positions;
    for (std::size_t i = 0; i < model.particles.size(); ++i)
      positions.push_back(model.particles.position(i));
    model.particles = ParticleState(positions, masses);
    ASSERT_GT(model.constraints.size(), 16u);
    const Colouring colouring = test::colour_model(model, "greedy");
    EXPECT_EQ(colouring.constraint_count(), model.constraints.size());
  }
}

TEST(Numerics, ProjectionThatOverflowsIsRefused) {
  const Model model = test::cloth_model(6, 6);
  for (const SolverMode mode : test::kSolverModes) {
    SCOPED_TRACE(test::mode_name(mode));
    SolverSettings settings;
    settings.mode = mode;
    Solver solver = make_solver(model, settings);
    solver.set_position(7, Vector3r(std::numeric_limits<Real>::max() / 2, 0, 0));
    const auto before = solver.positions();
    try {
      solver.project(5, Real(1) / Real(60));
      EXPECT_TRUE(all_finite(solver.positions()));
    } catch (const NumericalFailure&) {
      EXPECT_TRUE(same_bits(solver.positions(), before));
    }
  }
}

// ---- coordinates far from the origin ------------------------------------------------------

TEST(Numerics, CoordinatesAroundAMillion) {
  // The cloth and the bar moved to (1e6, 1e6, 1e6): float keeps ~0.06 of absolute precision
  // there, so shapes are coarse, but nothing may blow up or turn NaN.
  for (const bool use_bar : {false, true}) {
    Model model = use_bar ? test::tet_bar_model(2, 2, 4) : test::cloth_model(6, 6);
    std::vector<Vector3r> positions;
    std::vector<Real> masses;
    for (std::size_t i = 0; i < model.particles.size(); ++i) {
      positions.push_back(model.particles.position(i) + Vector3r::Constant(Real(1e6)));
      masses.push_back(model.particles.inverse_mass[i]);
    }
    const Model far = use_bar ? [&] {
      Model m;
      m.particles = ParticleState(positions, masses);
      const io::TetrahedralBar b = io::make_tetrahedral_bar(2, 2, 4, Real(0.1));
      // Rest shapes measured far away too; the offset makes the tetrahedra coarser (edges
      // rounded to float at 1e6) but keeps them non-flat.
      m.constraints.volume = make_volume_constraints({b.tetrahedron_indices, positions});
      m.constraints.distance = make_distance_constraints({b.edge_indices, positions});
      return m;
    }() : [&] {
      Model m = model;
      m.particles = ParticleState(positions, masses);
      return m;
    }();
    for (const SolverMode mode : test::kSolverModes) {
      SCOPED_TRACE(test::mode_name(mode) + (use_bar ? " bar" : " cloth"));
      SolverSettings settings;
      settings.mode = mode;
      Solver solver = make_solver(far, settings);
      EXPECT_EQ(step_checked(solver, 60), 0);
      Real moved = 0;
      const auto x = solver.positions();
      for (ParticleIndex p = 0; p < x.size(); ++p)
        moved = std::max(moved, (x[p] - positions[p]).norm());
      EXPECT_LT(moved, Real(10));
    }
  }
}

// ---- nothing movable ----------------------------------------------------------------------

TEST(Numerics, AllParticlesStaticNeverMove) {
  for (const bool use_bar : {false, true}) {
    Model model = use_bar ? test::tet_bar_model(2, 2, 4) : test::cloth_model(6, 6);
    std::vector<Vector3r> positions;
    for (std::size_t i = 0; i < model.particles.size(); ++i)
      positions.push_back(model.particles.position(i));
    // Stretched out of the rest shape, so every constraint would move them if it could.
    for (Vector3r& p : positions) p *= Real(1.5);
    model.particles = ParticleState(positions, std::vector<Real>(positions.size(), Real(0)));
    for (const SolverMode mode : test::kSolverModes) {
      SCOPED_TRACE(test::mode_name(mode) + (use_bar ? " bar" : " cloth"));
      SolverSettings settings;
      settings.mode = mode;
      Solver solver = make_solver(model, settings);
      EXPECT_EQ(step_checked(solver, 20), 0);
      EXPECT_TRUE(same_bits(solver.positions(), positions));
      for (const Vector3r& v : solver.velocities()) EXPECT_EQ(v, Vector3r::Zero());
    }
  }
}

}  // namespace numerics_tests
}  // namespace tessera
