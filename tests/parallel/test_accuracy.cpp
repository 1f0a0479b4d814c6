// What the accuracy issue promised, checked on the solver:
//  * mode sequential sweeps the reference library's greedy groups and does not diverge where
//    the input order does (a 64² cloth at 16 substeps × 1 iteration; a 128² cloth with
//    dihedral bending over 60 frames), and its order is an option;
//  * divergence is a failure: a step whose RMS residual ends above the bound throws
//    NumericalFailure naming the family and constraint, the state from before kept;
//  * residuals name their worst constraint in the user's numbering;
//  * tethers on a hanging cloth: the edges at the pins stop stretching, and a solver with
//    tethers is bitwise the same for any thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <tessera/core/error.hpp>
#include <tessera/core/long_range_attachments.hpp>
#include <tessera/io/generators.hpp>

#include "scenes.hpp"
#include "test_support.hpp"

namespace tessera {
namespace accuracy_tests {

using test::make_solver;

/// The default scene's settings: 16 substeps × `iterations` of a 60 Hz frame.
SolverSettings frame_settings(SolverMode mode, std::size_t iterations) {
  SolverSettings settings;
  settings.mode = mode;
  settings.substeps = 16;
  settings.iterations = iterations;
  settings.divergence_rms = std::numeric_limits<Real>::infinity();  // measured, not refused
  return settings;
}

double rms_after(Solver& solver, int frames) {
  for (int f = 0; f < frames; ++f) solver.step();
  return solver.last_step().residual_after.rms;
}

TEST(SequentialOrder, GroupsStayBoundedWhereTheInputOrderDiverges) {
  // 64² distance-only cloth, 16 substeps × 1 iteration, 30 frames. Input order: the sweep
  // runs along each row edge after edge, and in float the cloth's residual grows without
  // bound. In double the same input order needs longer to run away (RMS 0.36 after 30
  // frames, above 2 within 60: robustness.ErrorCatalogue.DivergenceBoundAndADivergedStep),
  // and the groups order ends at 0.92 here: under 1 in both precisions.
  const Model model = test::cloth_model(64, 64, test::ClothBending::none);
  SolverSettings settings = frame_settings(SolverMode::sequential, 1);
  settings.sequential_order = SequentialOrder::input;
  Solver input(model, settings);
  const double input_rms = rms_after(input, 30);
  settings.sequential_order = SequentialOrder::groups;
  Solver groups(model, settings);
  const double groups_rms = rms_after(groups, 30);
  EXPECT_LT(groups_rms, 1.0);
  if (!kDoublePrecision) {
    EXPECT_GT(input_rms, 10 * groups_rms) << "the divergence this order fixes";
  }
}

TEST(SequentialOrder, DihedralClothStaysBoundedOverSixtyFrames) {
  // The case: a 128² cloth with dihedral bending, 60 frames of 16 × 2, sequential
  // (4.0e5 RMS in input order). Sanitized builds run a 64² cloth for 20 frames.
  const std::size_t n = test::kSanitizedBuild ? 64 : 128;
  const Model model = test::cloth_model(n, n);
  Solver solver(model, frame_settings(SolverMode::sequential, 2));
  EXPECT_LT(rms_after(solver, test::kSanitizedBuild ? 20 : 60), 1.0);
}

TEST(SequentialOrder, GroupsAreTheGreedyColoursSweptInOrder) {
  const Model model = test::cloth_model(12, 9);
  SolverSettings settings;
  settings.mode = SolverMode::sequential;
  const Solver solver(model, settings);
  const Colouring greedy = test::colour_model(model, "greedy");
  EXPECT_EQ(solver.schedule().phase_count(), greedy.colour_count());
  // Every constraint sits in its greedy group, the groups in colour order.
  for (Colour k = 0; k < greedy.colour_count(); ++k)
    for (const ConstraintIndex c : greedy.constraints_of(k)) {
      const ConstraintLocation where = solver.schedule().locate(c);
      const auto phase = solver.schedule().phase_blocks(k);
      EXPECT_TRUE(std::any_of(phase.begin(), phase.end(), [&](const ScheduleBlock& b) {
        return b.family == where.family && where.slot >= b.begin && where.slot < b.end;
      })) << "constraint " << c << " of group " << k;
    }
  settings.sequential_order = SequentialOrder::input;
  EXPECT_EQ(Solver(model, settings).schedule().phase_count(), 0u) << "input order: one sweep";
  EXPECT_EQ(parse_sequential_order("input"), SequentialOrder::input);
  EXPECT_THROW(parse_sequential_order("random"), InvalidInput);
}

TEST(Divergence, AStepBeyondTheBoundIsUndoneAndNamesTheWorstConstraint) {
  // Input order at 16 × 1 diverges (above); a bound of 2 catches it on the way.
  const Model model = test::cloth_model(64, 64, test::ClothBending::none);
  SolverSettings settings = frame_settings(SolverMode::sequential, 1);
  settings.sequential_order = SequentialOrder::input;
  settings.divergence_rms = 2;
  Solver solver(model, settings);
  std::vector<Vector3r> before;
  std::string message;
  for (int frame = 0; frame < 200 && message.empty(); ++frame) {
    before = solver.positions();
    try {
      solver.step();
    } catch (const NumericalFailure& failure) {
      message = failure.what();
    }
  }
  ASSERT_FALSE(message.empty()) << "never diverged";
  EXPECT_TRUE(test::same_bits(solver.positions(), before)) << "the state before is kept";
  EXPECT_NE(message.find("diverged: residual RMS"), std::string::npos) << message;
  EXPECT_NE(message.find("exceeds the bound 2"), std::string::npos) << message;
  EXPECT_NE(message.find("distance constraint "), std::string::npos) << message;
}

TEST(Divergence, FreeFallAndOrdinaryRunsAreNotDivergence) {
  // Nothing pinned: the cloth falls freely for a second, constraints satisfied.
  Model model = test::cloth_model(16, 16);
  std::fill(model.particles.inverse_mass.begin(), model.particles.inverse_mass.end(), Real(1));
  SolverSettings settings;
  settings.substeps = 4;
  settings.iterations = 2;
  Solver solver = make_solver(model, settings);
  for (int f = 0; f < 60; ++f) ASSERT_NO_THROW(solver.step());
  EXPECT_LT(solver.last_step().residual_after.rms, 1e-3);
  settings.divergence_rms = 0;
  EXPECT_THROW(make_solver(model, settings), InvalidInput);
  settings.divergence_rms = std::numeric_limits<Real>::quiet_NaN();
  EXPECT_THROW(make_solver(model, settings), InvalidInput);
}

TEST(Residual, NamesTheWorstConstraintInTheUsersNumbering) {
  const Model model = test::cloth_model(10, 10);
  for (const SolverMode mode : test::kSolverModes) {
    SCOPED_TRACE(test::mode_name(mode));
    SolverSettings settings;
    settings.mode = mode;
    Solver solver = make_solver(model, settings, "dsatur", {.locality = true});
    // Stretch one edge far more than anything else: particle 44 moves 1 m up.
    solver.set_position(44, solver.position(44) + Vector3r(0, 1, 0));
    const Residual residual = solver.residual();
    EXPECT_EQ(residual.worst_family, ConstraintFamily::distance);
    const FamilyResidual& distance = residual.of(ConstraintFamily::distance);
    EXPECT_FALSE(distance.worst_is_dynamic);
    const std::size_t c = distance.worst;
    ASSERT_LT(c, model.constraints.distance.size());
    const auto& slots = model.constraints.distance.particles.particle;
    EXPECT_TRUE(slots[0][c] == 44 || slots[1][c] == 44) << "constraint " << c;
  }
}

/// A cloth of n² with tethers to its `attachments` nearest of the two pinned corners.
Model tethered_cloth(std::size_t n, std::size_t attachments = 1) {
  Model model = test::cloth_model(n, n);
  const io::ClothGrid grid = io::make_cloth_grid(n, n, Real(1) / Real(n - 1));
  std::vector<Vector3r> rest;
  for (std::size_t p = 0; p < model.particles.size(); ++p) rest.push_back(model.particles.position(p));
  model.constraints.tether = make_long_range_attachments(
      rest, std::span(model.particles.inverse_mass.data(), model.particles.size()),
      grid.edge_indices, {.attachments = attachments});
  return model;
}

TEST(Tethers, HoldTheHangingClothNearItsRestLength) {
  // 48² cloth, 30 frames of 16 × 1 gs: without tethers the edges at the pins stretch by
  // several times their length; with them the whole cloth stays within a few per cent.
  SolverSettings settings = frame_settings(SolverMode::gs, 1);
  Solver loose = make_solver(test::cloth_model(48, 48), settings);
  Solver tethered = make_solver(tethered_cloth(48), settings);
  for (int f = 0; f < 30; ++f) {
    loose.step();
    tethered.step();
  }
  const double loose_max = loose.last_step().residual_after.of(ConstraintFamily::distance).max;
  const FamilyResidual& edges = tethered.last_step().residual_after.of(ConstraintFamily::distance);
  EXPECT_GT(loose_max, 0.5);
  EXPECT_LT(edges.max, loose_max / 5);
  EXPECT_EQ(tethered.statistics().constraints_per_family[std::size_t(ConstraintFamily::tether)],
            48u * 48u - 2u);
}

TEST(Tethers, TwoAttachmentsKeepTheSpanBetweenThePinsFromStretching) {
  // The 48² cloth hangs from two corners of one edge, exactly that edge's length apart: the
  // edge carries the cloth's weight and can only sag by stretching. Tethered to its nearest
  // pin alone, the middle of the span may sag within its reach of that pin; tethered to both,
  // it is held on the straight span (long_range_attachments.hpp, "How many attachments").
  constexpr std::size_t kSide = 48;
  const SolverSettings settings = frame_settings(SolverMode::gs, 1);
  const auto span_stretch = [&](std::size_t attachments) {
    const Model model = tethered_cloth(kSide, attachments);
    std::vector<std::size_t> pins;
    for (std::size_t p = 0; p < model.particles.size(); ++p)
      if (model.particles.inverse_mass[p] == 0) pins.push_back(p);
    EXPECT_EQ(pins.size(), 2u);
    EXPECT_EQ(pins[0] / kSide, pins[1] / kSide) << "both pins on one row";
    Solver solver = make_solver(model, settings);
    for (int f = 0; f < 30; ++f) solver.step();
    const auto x = solver.positions();
    double worst = 0;
    for (std::size_t p = pins[0]; p < pins[1]; ++p)
      worst = std::max(worst, double((x[p + 1] - x[p]).norm()) * double(kSide - 1) - 1);
    return worst;
  };
  const double one = span_stretch(1), two = span_stretch(2);
  EXPECT_GT(one, 0.05) << "one tether each: the span sags and stretches";
  EXPECT_LT(two, one / 2.5) << "two: " << two << ", one: " << one;
}

TEST(Tethers, AnyThreadCountAndEveryModeGiveBitwiseTheSameState) {
  const Model model = tethered_cloth(24);
  for (const SolverMode mode : test::kSolverModes) {
    SCOPED_TRACE(test::mode_name(mode));
    SolverSettings settings = frame_settings(mode, 2);
    settings.threads = 1;
    Solver one = make_solver(model, settings, "stencil");
    settings.threads = 2;
    Solver two = make_solver(model, settings, "stencil");
    for (int f = 0; f < 5; ++f) {
      one.step();
      two.step();
    }
    EXPECT_TRUE(test::same_bits(one.positions(), two.positions()));
  }
}

}  // namespace accuracy_tests
}  // namespace tessera
