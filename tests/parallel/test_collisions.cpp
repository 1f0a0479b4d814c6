// The solver with a collision stage (Solver::set_collisions): contacts remade every substep
// from the predicted positions, projected as a Jacobi set of their own. Known answers: a cloth
// dropped on a sphere and a plane ends outside both (no deeper than the thickness) with
// static particles untouched; Coulomb friction holds a block on a slope steeper-than-μ and
// lets it slide on a shallower-than-μ one the other way round; restitution bounces a falling
// particle back to e² of its height; every thread count and mode gives the same contacts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <tessera/collision/self_intersections.hpp>
#include <tessera/collision/solid_contacts.hpp>
#include <tessera/io/generators.hpp>
#include <tessera/io/scenes.hpp>
#include <tessera/core/error.hpp>
#include <tessera/parallel/solver.hpp>

#include "scenes.hpp"

namespace tessera {
namespace collisions_tests {

using test::make_solver;
using test::same_bits;

/// A free n × n cloth 1 m wide at y = 0, above a sphere of radius 0.25 whose top is 0.1 m
/// below it, and the ground at y = −0.6 (the tool's drape scene, smaller).
struct Drape {
  std::size_t n;
  Model model;
  std::vector<std::uint32_t> triangles;
  CollisionSettings collisions;

  explicit Drape(std::size_t vertices) : n(vertices) {
    io::ClothGrid grid = io::make_cloth_grid(n, n, Real(1) / Real(n - 1));
    for (Vector3r& p : grid.positions) p = Vector3r(p.x(), 0, p.y());
    model.particles =
        ParticleState(grid.positions, std::vector<Real>(grid.vertex_count(), Real(1)));
    model.constraints.distance =
        make_distance_constraints({grid.edge_indices, grid.positions, Real(1), Real(0)});
    model.constraints.dihedral = make_dihedral_constraints(
        {grid.bending_indices, grid.positions, Real(1), Real(1e-3)});
    triangles.assign(grid.triangle_indices.begin(), grid.triangle_indices.end());
    collisions.colliders = {SphereCollider{kCentre, kRadius},
                            PlaneCollider{Vector3r(0, 1, 0), kGround}};
    collisions.thickness = Real(0.005);
    collisions.self_collision = true;
  }

  static inline const Vector3r kCentre = Vector3r(Real(0.5), Real(-0.35), Real(0.5));
  static constexpr Real kRadius = Real(0.25);
  static constexpr Real kGround = Real(-0.6);
};

SolverSettings drape_settings(SolverMode mode, std::size_t threads) {
  SolverSettings settings;
  settings.mode = mode;
  settings.threads = threads;
  settings.substeps = 16;
  settings.iterations = 1;
  return settings;
}

/// The deepest any particle is inside the sphere or below the ground, in metres (0: none).
Real deepest(const std::vector<Vector3r>& positions) {
  Real depth = 0;
  for (const Vector3r& p : positions) {
    depth = std::max(depth, Drape::kRadius - (p - Drape::kCentre).norm());
    depth = std::max(depth, Drape::kGround - p.y());
  }
  return depth;
}

TEST(Collisions, ADrapedClothEndsOutsideTheSphereAndTheGroundWithoutIntersectingItself) {
  Drape drape(20);
  Solver solver = make_solver(drape.model, drape_settings(SolverMode::gs, 2));
  solver.set_collisions(drape.collisions, drape.triangles);
  for (int frame = 0; frame < 45; ++frame) solver.step();
  const std::vector<Vector3r> positions = solver.positions();
  // On the sphere: the middle of the cloth rests on its top, a thickness above it.
  const Vector3r middle = positions[(drape.n / 2) * drape.n + drape.n / 2];
  EXPECT_NEAR((middle - Drape::kCentre).norm(), Drape::kRadius + drape.collisions.thickness,
              Real(0.01));
  EXPECT_LE(deepest(positions), Real(1e-3));
  EXPECT_EQ(count_self_intersections(positions, drape.triangles), 0u);
  const CollisionStatistics& found = solver.collisions()->statistics();
  EXPECT_EQ(found.substeps, 45u * 16u);
  // The cap of the sphere under the cloth: a few dozen of its 400 particles.
  EXPECT_GE(found.collider_contacts, 4u) << "the cloth lies on the sphere";
  EXPECT_GT(found.contacts_max, drape.n / 2);
  EXPECT_GE(found.contacts_max, found.contacts());
  EXPECT_GT(found.seconds_detection, 0);
  // Without the stage the same cloth falls through the sphere.
  Solver falling = make_solver(drape.model, drape_settings(SolverMode::gs, 2));
  for (int frame = 0; frame < 45; ++frame) falling.step();
  EXPECT_GT(deepest(falling.positions()), Real(0.1));
}

TEST(Collisions, EveryThreadCountGivesTheSameStateAndEveryModeStaysOutside) {
  Drape drape(12);
  for (const SolverMode mode : test::kSolverModes)
  for (const ContactScheduling scheduling : {ContactScheduling::jacobi, ContactScheduling::coloured}) {
    std::vector<Vector3r> first;
    for (const std::size_t threads : {1u, 2u}) {
      SolverSettings settings = drape_settings(mode, threads);
      settings.contact_scheduling = scheduling;
      Solver solver = make_solver(drape.model, settings);
      solver.set_collisions(drape.collisions, drape.triangles);
      for (int frame = 0; frame < 30; ++frame) solver.step();
      const auto positions = solver.positions();
      EXPECT_LE(deepest(positions), Real(2e-3)) << test::mode_name(mode);
      if (first.empty()) first = positions;
      else EXPECT_TRUE(same_bits(first, positions)) << test::mode_name(mode);
    }
  }
}

/// Two FEM blocks of 4 cm cells: a slab of 5 × 2 × 5 cells (20 × 8 × 20 cm) lying on the
/// ground (y = 0) a thickness above it, and a bar of 2 × 2 × 5 cells crosswise over it,
/// tilted 0.2 rad about its long axis, dropped from 5 cm above the slab (the tool's pile
/// scene, smaller; the slab is wide so the bar lands and stays on it whatever way it rolls).
struct TwoBlockPile {
  Model model;
  std::vector<std::uint32_t> tetrahedra, surface;
  CollisionSettings collisions;
  std::size_t slab_vertices = 0;
  static constexpr Real kThickness = Real(0.004);
  static constexpr Real kSlabTop = Real(0.08) + kThickness;

  TwoBlockPile() {
    const io::TetrahedralBar slab = io::make_tetrahedral_bar(5, 2, 5, Real(0.04));
    const io::TetrahedralBar bar = io::make_tetrahedral_bar(2, 2, 5, Real(0.04));
    std::vector<Vector3r> positions;
    for (const Vector3r& rest : slab.positions)
      positions.push_back(rest + Vector3r(Real(-0.1), kThickness, Real(-0.1)));
    tetrahedra.assign(slab.tetrahedron_indices.begin(), slab.tetrahedron_indices.end());
    slab_vertices = positions.size();
    const Real c = std::cos(Real(0.2)), s = std::sin(Real(0.2));
    for (const Vector3r& rest : bar.positions) {
      const Vector3r local = rest - Vector3r(Real(0.04), Real(0.04), Real(0.1));
      const Vector3r tilted(c * local.x() - s * local.y(), s * local.x() + c * local.y(),
                            local.z());
      positions.push_back(Vector3r(tilted.z(), tilted.y(), -tilted.x()) +
                          Vector3r(0, kSlabTop + Real(0.05) + Real(0.06), 0));
    }
    for (const auto v : bar.tetrahedron_indices)
      tetrahedra.push_back(std::uint32_t(slab_vertices) + v);
    model = io::make_solid(positions, tetrahedra, {});
    surface = io::boundary_triangles(tetrahedra);
    collisions.colliders = {PlaneCollider{Vector3r(0, 1, 0), 0}};
    collisions.thickness = kThickness;
    collisions.self_collision = true;
  }

  /// Kinetic plus gravitational potential energy (g = 9.81 along −y).
  Real energy(const Solver& solver) const {
    const std::vector<Vector3r> x = solver.positions(), v = solver.velocities();
    Real total = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      const Real mass = 1 / model.particles.inverse_mass[i];
      total += mass * (Real(9.81) * x[i].y() + v[i].squaredNorm() / 2);
    }
    return total;
  }
};

TEST(Collisions, ABlockDroppedOnABlockRestsOnItWithoutPenetrationTheSameOnAnyThreadCount) {
  const TwoBlockPile pile;
  for (const ContactScheduling scheduling : {ContactScheduling::jacobi, ContactScheduling::coloured}) {
  SCOPED_TRACE(std::string(contact_scheduling_name(scheduling)));
  std::vector<Vector3r> first;
  for (const std::size_t threads : {1u, 2u}) {
    SolverSettings settings = drape_settings(SolverMode::gs, threads);
    settings.contact_scheduling = scheduling;
    Solver solver = make_solver(pile.model, settings);
    solver.set_collisions(pile.collisions, pile.surface, pile.tetrahedra);
    const Real start_energy = pile.energy(solver);
    std::size_t solid_contacts = 0;
    Real highest_energy = start_energy;
    for (int frame = 0; frame < 45; ++frame) {
      solver.step();
      solid_contacts = std::max(solid_contacts, solver.collisions()->statistics().particle_tet_contacts);
      highest_energy = std::max(highest_energy, pile.energy(solver));
    }
    EXPECT_GT(solid_contacts, 0u) << "the blocks met through particle–tet contacts";
    // The contacts never add energy (the drop is 5 cm: 0.5 kg × g × 0.05 = 0.25 J to lose).
    EXPECT_LE(highest_energy, start_energy + Real(1e-3));
    EXPECT_LT(pile.energy(solver), start_energy - Real(0.1));
    const std::vector<Vector3r> positions = solver.positions();
    EXPECT_LE(solid_penetration_depth(positions, pile.tetrahedra), TwoBlockPile::kThickness);
    EXPECT_EQ(count_self_intersections(positions, pile.surface), 0u);
    // The bar rests on the slab (whose top is 8 cm up), not on the ground.
    Real lowest_bar = positions.back().y();
    for (std::size_t i = pile.slab_vertices; i < positions.size(); ++i)
      lowest_bar = std::min(lowest_bar, positions[i].y());
    EXPECT_GT(lowest_bar, TwoBlockPile::kSlabTop - TwoBlockPile::kThickness);
    EXPECT_LT(lowest_bar, TwoBlockPile::kSlabTop + 3 * TwoBlockPile::kThickness);
    for (const Vector3r& p : positions) EXPECT_GE(p.y(), -Real(1e-4)) << "above the ground";
    if (first.empty()) first = positions;
    else EXPECT_TRUE(same_bits(first, positions)) << "1 and 2 threads";
    if (scheduling == ContactScheduling::coloured) {
      EXPECT_GT(solver.statistics().contact_colours_max, 1u) << "contacts sharing particles";
      EXPECT_EQ(solver.statistics().contacts_overflowed, 0u);
    }
  }
  }
}

/// Two free 12 × 12 cloths 1 m wide: one lying on the ground (y = 0) a thickness above it,
/// the other 4 cm above, shifted by half a cell, falling onto it; both sliding along x at
/// 2 m/s on a frictionless ground (so every particle moves 2 mm per substep).
struct TwoLayers {
  static constexpr std::size_t n = 12;
  Model model;
  std::vector<std::uint32_t> triangles;
  CollisionSettings collisions;

  TwoLayers() {
    const Real h = Real(1) / Real(n - 1);
    const io::ClothGrid grid = io::make_cloth_grid(n, n, h);
    std::vector<Vector3r> positions;
    std::vector<ParticleIndex> edges;
    for (int layer = 0; layer < 2; ++layer) {
      const std::uint32_t first = std::uint32_t(positions.size());
      for (const Vector3r& p : grid.positions)
        positions.push_back(layer == 0 ? Vector3r(p.x(), Real(0.005), p.y())
                                       : Vector3r(p.x() + h / 2, Real(0.045), p.y() + h / 2));
      for (const auto v : grid.triangle_indices) triangles.push_back(first + v);
      for (const auto v : grid.edge_indices) edges.push_back(first + v);
    }
    model.particles = ParticleState(positions, std::vector<Real>(positions.size(), Real(1)));
    model.constraints.distance = make_distance_constraints({edges, positions, Real(1), Real(0)});
    collisions.colliders = {PlaneCollider{Vector3r(0, 1, 0), 0}};
    collisions.thickness = Real(0.005);
    collisions.static_friction = collisions.dynamic_friction = 0;
    collisions.self_collision = true;
  }
};

TEST(Collisions, SelfContactsOfABuildReusedUntilAParticleOutrunsItAreThoseOfABuildEverySubstep) {
  // The grids built at most every 4th (or 16th) substep, sooner when a particle leaves the
  // room the last build gave it, each substep testing the candidates at its own positions:
  // the same contacts in every substep as a build every substep, so the same final state,
  // bit for bit, with fewer builds.
  const TwoLayers layers;
  const auto run = [&](std::size_t interval, std::size_t threads) {
    CollisionSettings collisions = layers.collisions;
    collisions.self_collision_interval = interval;
    Solver solver = make_solver(layers.model, drape_settings(SolverMode::gs, threads));
    solver.set_collisions(collisions, layers.triangles);
    for (std::size_t i = 0; i < layers.model.particles.size(); ++i)
      solver.set_velocity(ParticleIndex(i), Vector3r(2, 0, 0));
    double self_contacts = 0;
    for (int frame = 0; frame < 30; ++frame) {
      solver.step();
      const CollisionStatistics& found = solver.collisions()->statistics();
      self_contacts += double(found.vertex_triangle_contacts + found.edge_edge_contacts);
    }
    const std::uint64_t builds = solver.collisions()->statistics().self_detections;
    return std::tuple(solver.positions(), self_contacts / 30, builds);
  };
  const auto [every, every_contacts, every_builds] = run(1, 2);
  const auto [fourth, fourth_contacts, fourth_builds] = run(4, 2);
  const auto [sixteenth, sixteenth_contacts, sixteenth_builds] = run(16, 2);
  EXPECT_TRUE(same_bits(fourth, every)) << "every 4th against every substep";
  EXPECT_TRUE(same_bits(sixteenth, every)) << "every 16th against every substep";
  EXPECT_EQ(fourth_contacts, every_contacts);
  EXPECT_EQ(sixteenth_contacts, every_contacts);
  EXPECT_LT(fourth_builds, every_builds / 3) << "a build at most every 4th substep, sooner when a particle outruns it";
  EXPECT_LT(sixteenth_builds, fourth_builds);
  EXPECT_GT(every_contacts, 100);
  EXPECT_EQ(count_self_intersections(fourth, layers.triangles), 0u);
  // The upper cloth on the lower, a thickness above it, except its last row and column: they
  // overhang the lower cloth by half a cell and, contacts swept Gauss–Seidel (the default
  // ContactScheduling::coloured), drape down to the ground beside it (a Jacobi set's averaged
  // pushes held them up, and left the rest 0.3 mm closer than the thickness).
  const std::size_t half = fourth.size() / 2, n = layers.n;
  for (std::size_t i = 0; i < half; ++i) {
    EXPECT_GE(fourth[i].y(), Real(0.004)) << "on the ground";
    EXPECT_GE(fourth[half + i].y(), Real(0.004)) << "on the ground";
    if (i % n != n - 1 && i / n != n - 1) {
      EXPECT_GE(fourth[half + i].y(), fourth[i].y() + Real(0.0045)) << "the upper cloth on the lower";
    }
  }
  EXPECT_TRUE(same_bits(fourth, std::get<0>(run(4, 1)))) << "1 and 2 threads";
}

/// A solver of one free particle at `start` (mode gs, default gravity).
Solver one_particle(const Vector3r& start, std::size_t substeps, std::size_t iterations) {
  Model model;
  model.particles = ParticleState(std::vector<Vector3r>{start}, std::vector<Real>{Real(1)});
  SolverSettings settings;
  settings.mode = SolverMode::gs;
  settings.substeps = substeps;
  settings.iterations = iterations;
  return make_solver(model, settings);
}

/// A particle resting on a plane tilted by θ about z (normal (−sin θ, cos θ, 0)), with
/// static friction μs = μk = μ; how far it moves in one second from rest.
Real slide(Real theta, Real mu) {
  const Vector3r normal(-std::sin(theta), std::cos(theta), 0);
  const Real thickness = Real(0.001);
  // Resting on the plane through the origin, a thickness above it.
  const std::vector<Vector3r> start = {normal * thickness};
  Solver solver = one_particle(start[0], 20, 2);
  CollisionSettings collisions;
  collisions.colliders = {PlaneCollider{normal, 0}};
  collisions.thickness = thickness;
  collisions.static_friction = collisions.dynamic_friction = mu;
  solver.set_collisions(collisions, {});
  for (int frame = 0; frame < 60; ++frame) solver.step();
  const Vector3r moved = solver.position(0) - start[0];
  EXPECT_NEAR(normal.dot(solver.position(0)), thickness, Real(1e-4)) << "stays on the plane";
  return moved.norm();
}

TEST(Collisions, StaticFrictionHoldsBelowItsAngleAndLetsGoAboveIt) {
  const Real theta = Real(0.3);  // tan θ = 0.309
  EXPECT_LT(slide(theta, Real(0.4)), Real(1e-4)) << "μ > tan θ: stays put";
  // μ < tan θ: slides with a = g (sin θ − μ cos θ), about 0.5 a t² in one second.
  const Real mu = Real(0.2);
  const Real a = Real(9.81) * (std::sin(theta) - mu * std::cos(theta));
  EXPECT_NEAR(slide(theta, mu), Real(0.5) * a, Real(0.15) * Real(0.5) * a);
  // No friction: the whole of g sin θ.
  const Real free = Real(0.5) * Real(9.81) * std::sin(theta);
  EXPECT_NEAR(slide(theta, 0), free, Real(0.1) * free);
}

/// The highest point a particle dropped from 1 m above the ground reaches after its first
/// bounce, with restitution e.
Real bounce(Real e) {
  Solver solver = one_particle(Vector3r(0, 1, 0), 40, 1);
  CollisionSettings collisions;
  collisions.colliders = {PlaneCollider{Vector3r(0, 1, 0), 0}};
  collisions.thickness = 0;
  collisions.restitution = e;
  collisions.static_friction = collisions.dynamic_friction = 0;
  solver.set_collisions(collisions, {});
  bool bounced = false;
  Real highest = 0;
  for (int frame = 0; frame < 150; ++frame) {
    solver.step();
    const Real vy = solver.velocity(0).y(), y = solver.position(0).y();
    if (!bounced && vy > 0) bounced = true;
    if (bounced) highest = std::max(highest, y);
    if (bounced && vy < 0) break;
  }
  EXPECT_GE(solver.position(0).y(), Real(-1e-4));
  return highest;
}

TEST(Collisions, RestitutionBouncesToESquaredOfTheHeight) {
  EXPECT_NEAR(bounce(Real(0.5)), Real(0.25), Real(0.03));
  EXPECT_NEAR(bounce(Real(0.8)), Real(0.64), Real(0.04));
  EXPECT_LT(bounce(0), Real(0.01)) << "e = 0: it stays down";
}

TEST(Collisions, StaticParticlesNeverMoveAndBadSettingsAreErrors) {
  Drape drape(8);
  // Pin the cloth's middle inside the sphere: contacts never move it.
  const std::size_t middle = (drape.n / 2) * drape.n + drape.n / 2;
  drape.model.particles.inverse_mass[middle] = 0;
  drape.model.particles.set_position(middle, Drape::kCentre);
  Solver solver = make_solver(drape.model, drape_settings(SolverMode::jacobi, 2));
  solver.set_collisions(drape.collisions, drape.triangles);
  for (int frame = 0; frame < 10; ++frame) solver.step();
  EXPECT_EQ(solver.position(ParticleIndex(middle)), Drape::kCentre);

  const auto error = [&](CollisionSettings settings, std::vector<std::uint32_t> triangles) {
    try {
      solver.set_collisions(std::move(settings), triangles);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CollisionSettings bad = drape.collisions;
  bad.thickness = -1;
  EXPECT_NE(error(bad, drape.triangles).find("thickness"), std::string::npos);
  bad = drape.collisions;
  bad.static_friction = -0.5;
  EXPECT_NE(error(bad, drape.triangles).find("static friction"), std::string::npos);
  bad = drape.collisions;
  bad.restitution = 2;
  EXPECT_NE(error(bad, drape.triangles).find("restitution"), std::string::npos);
  bad = drape.collisions;
  bad.thickness = 0;
  EXPECT_NE(error(bad, drape.triangles).find("self-collision needs a positive thickness"),
            std::string::npos);
  EXPECT_EQ(error(drape.collisions, {0, 1, 999}),
            "collisions: surface triangle 0 names particle 999, the model has 64");
  EXPECT_EQ(error(drape.collisions, {0, 1}),
            "collisions: the surface has 2 triangle indices, not a multiple of 3");
  EXPECT_EQ(error(drape.collisions, {}), "no error");
  try {
    solver.set_collisions(drape.collisions, drape.triangles, std::vector<std::uint32_t>{0, 1, 2, 64});
    ADD_FAILURE() << "no error";
  } catch (const InvalidInput& e) {
    EXPECT_STREQ(e.what(), "collisions: tetrahedron 0 names particle 64, the model has 64");
  }
  // Clearing the stage drops the contacts.
  solver.clear_collisions();
  EXPECT_EQ(solver.collisions(), nullptr);
  EXPECT_EQ(solver.contacts().size(), 0u);
}

}  // namespace collisions_tests
}  // namespace tessera
