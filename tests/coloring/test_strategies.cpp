// Every strategy on every test mesh: valid colourings, known optima, determinism across
// thread counts, the registry, and the post-passes.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <utility>

#include <tbb/task_arena.h>

#include <tessera/coloring/colouring_statistics.hpp>
#include <tessera/coloring/run_colouring.hpp>
#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/particle_partition.hpp>
#include <tessera/coloring/refinement.hpp>
#include <tessera/core/error.hpp>

#include "test_meshes.hpp"

namespace tessera {
namespace strategies_tests {

const ColouringRegistry& registry() {
  static const ColouringRegistry instance = ColouringRegistry::with_builtin_strategies();
  return instance;
}

const std::vector<test::TestMesh>& meshes() {
  static const std::vector<test::TestMesh> instance = test::all_test_meshes();
  return instance;
}

Colouring colour_with_threads(std::string_view strategy, const ConstraintGraph& graph, int threads,
                              const ColouringOptions& options = {}) {
  tbb::task_arena arena(threads);
  return arena.execute([&] { return registry().get(strategy).colour(graph, options); });
}

class EveryStrategy : public ::testing::TestWithParam<std::string> {};

TEST_P(EveryStrategy, GivesValidColouringsOnEveryMesh) {
  for (const test::TestMesh& mesh : meshes()) {
    SCOPED_TRACE(mesh.name);
    const Colouring colouring = registry().get(GetParam()).colour(mesh.graph, {});
    const ColouringValidation check = validate(mesh.graph, colouring);
    EXPECT_TRUE(check.valid) << check.problem;
    EXPECT_EQ(colouring.constraint_count(), mesh.graph.constraint_count());
    EXPECT_GE(colouring.colour_count(), mesh.graph.colour_lower_bound());
    if (colouring.renumbers_particles()) {
      ASSERT_EQ(colouring.particle_new_to_old().size(), mesh.graph.particle_count());
      for (std::size_t n = 0; n < mesh.graph.particle_count(); ++n)
        EXPECT_EQ(colouring.particle_old_to_new()[colouring.particle_new_to_old()[n]], n);
    }
  }
}

TEST_P(EveryStrategy, PostPassesKeepColouringsValidAndNeverAddColours) {
  for (const test::TestMesh& mesh : meshes()) {
    SCOPED_TRACE(mesh.name);
    const Colouring plain = registry().get(GetParam()).colour(mesh.graph, {});
    const Colouring reduced = reduce_colours(mesh.graph, plain, {});
    const Colouring balanced = balance_colours(mesh.graph, reduced);
    EXPECT_TRUE(validate(mesh.graph, reduced).valid) << validate(mesh.graph, reduced).problem;
    EXPECT_TRUE(validate(mesh.graph, balanced).valid) << validate(mesh.graph, balanced).problem;
    EXPECT_LE(reduced.colour_count(), plain.colour_count());
    EXPECT_EQ(balanced.colour_count(), reduced.colour_count());
    EXPECT_EQ(reduced.renumbers_particles(), plain.renumbers_particles());
    const Colouring balanced_plain = balance_colours(mesh.graph, plain);
    EXPECT_TRUE(validate(mesh.graph, balanced_plain).valid) << validate(mesh.graph, balanced_plain).problem;
    EXPECT_EQ(balanced_plain.colour_count(), plain.colour_count());
  }
}

TEST_P(EveryStrategy, ConstraintsSharingOnlyStaticParticlesGetOneColour) {
  for (const ConstraintGraph& graph : {test::pinned_star_graph(16), test::isolated_graph(30)}) {
    const Colouring colouring = registry().get(GetParam()).colour(graph, {});
    EXPECT_EQ(colouring.colour_count(), 1u);
  }
}

TEST_P(EveryStrategy, EmptyAndSingleConstraint) {
  EXPECT_EQ(registry().get(GetParam()).colour(test::empty_graph(), {}).colour_count(), 0u);
  const Colouring one = registry().get(GetParam()).colour(test::single_constraint_graph(), {});
  EXPECT_EQ(one.colour_count(), 1u);
  EXPECT_EQ(one.colour_size(0), 1u);
}

TEST_P(EveryStrategy, SameColouringForOneAndTwoThreadsAndRepeatedRuns) {
  const ConstraintGraph graph = test::cloth_graph(40, 30, true);
  ColouringOptions options;
  options.particles_per_part = 150;  // several METIS parts
  const Colouring one = colour_with_threads(GetParam(), graph, 1, options);
  const Colouring two = colour_with_threads(GetParam(), graph, 2, options);
  const Colouring again = colour_with_threads(GetParam(), graph, 2, options);
  const auto same = [](const Colouring& a, const Colouring& b) {
    return std::equal(a.colours().begin(), a.colours().end(), b.colours().begin(), b.colours().end()) &&
           std::equal(a.constraints_by_colour().begin(), a.constraints_by_colour().end(),
                      b.constraints_by_colour().begin(), b.constraints_by_colour().end()) &&
           std::equal(a.particle_new_to_old().begin(), a.particle_new_to_old().end(),
                      b.particle_new_to_old().begin(), b.particle_new_to_old().end());
  };
  EXPECT_TRUE(same(one, two));
  EXPECT_TRUE(same(two, again));
}

INSTANTIATE_TEST_SUITE_P(Coloring, EveryStrategy,
                         ::testing::Values("greedy", "largest-first", "smallest-last", "dsatur",
                                           "stencil", "iterated-greedy", "random", "metis",
                                           "blocks"),
                         [](const auto& parameter) {
                           std::string name = parameter.param;
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

TEST(KnownOptima, TriangulatedGridDistanceConstraintsNeedExactlySixColours) {
  const ConstraintGraph graph = test::cloth_graph(24, 20, false);
  ASSERT_EQ(graph.colour_lower_bound(), 6u);
  std::size_t best = ~std::size_t(0);
  std::string best_name;
  for (std::string_view name : registry().names()) {
    const std::size_t colours = registry().get(name).colour(graph, {}).colour_count();
    EXPECT_GE(colours, 6u) << name;
    if (colours < best) best = colours, best_name = name;
  }
  EXPECT_EQ(best, 6u) << "best strategy " << best_name;
}

TEST(KnownOptima, IteratedGreedyReachesTheBoundOnTheClothWhateverTheOrder) {
  // Shuffle the edges: first-fit in this order needs more than 6 colours; reduction does not.
  const io::ClothGrid cloth = io::make_cloth_grid(24, 20);
  std::vector<ParticleIndex> edges = cloth.edge_indices;
  const std::size_t count = edges.size() / 2;
  std::mt19937 random(2024);
  for (std::size_t i = count; i > 1; --i) {
    const std::size_t j = std::uniform_int_distribution<std::size_t>(0, i - 1)(random);
    std::swap(edges[2 * (i - 1)], edges[2 * j]);
    std::swap(edges[2 * (i - 1) + 1], edges[2 * j + 1]);
  }
  const std::vector<Real> w(cloth.vertex_count(), Real(1));
  const std::vector<ConstraintGroup> groups = {ConstraintGroup::fixed_arity("distance", 2, edges)};
  const ConstraintGraph graph(w, groups);
  EXPECT_GT(registry().get("greedy").colour(graph, {}).colour_count(), 6u);
  const Colouring colouring = registry().get("iterated-greedy").colour(graph, {});
  EXPECT_TRUE(validate(graph, colouring).valid);
  EXPECT_EQ(colouring.colour_count(), 6u);
}

/// The plain first-fit the greedy strategy must reproduce: each constraint in id order takes
/// the smallest colour none of its neighbours (constraints sharing a movable particle) has.
std::vector<Colour> reference_first_fit(const ConstraintGraph& graph) {
  std::vector<Colour> colours(graph.constraint_count(), 0);
  for (ConstraintIndex c = 0; c < graph.constraint_count(); ++c) {
    std::set<Colour> taken;
    for (const ParticleIndex p : graph.particles_of(c))
      for (const ConstraintIndex n : graph.constraints_of(p))
        if (n < c) taken.insert(colours[n]);
    Colour k = 0;
    while (taken.count(k)) ++k;
    colours[c] = k;
  }
  return colours;
}

TEST(GreedyStrategy, IsExactlyFirstFitInInputOrderAlsoPast64Colours) {
  // A star of 100 edges at one hub needs 100 colours: the one-word fast path hands over to
  // the general loop at the 65th.
  std::vector<ParticleIndex> star;
  for (ParticleIndex arm = 1; arm <= 100; ++arm) star.insert(star.end(), {0, arm});
  const std::vector<Real> star_masses(101, Real(1));
  const std::vector<ConstraintGroup> star_groups = {ConstraintGroup::fixed_arity("star", 2, star)};
  std::vector<ConstraintGraph> graphs;
  graphs.push_back(ConstraintGraph(star_masses, star_groups));
  graphs.push_back(test::cloth_graph(30, 20, true));
  graphs.push_back(test::tet_bar_graph(3, 4, 5));
  // The same star after one unrelated edge: the hand-over happens at an odd constraint.
  std::vector<ParticleIndex> shifted_star = {101, 102};
  shifted_star.insert(shifted_star.end(), star.begin(), star.end());
  const std::vector<Real> shifted_masses(103, Real(1));
  const std::vector<ConstraintGroup> shifted_groups = {ConstraintGroup::fixed_arity("star", 2, shifted_star)};
  graphs.push_back(ConstraintGraph(shifted_masses, shifted_groups));
  for (const test::TestMesh& mesh : meshes()) graphs.push_back(mesh.graph);
  for (const ConstraintGraph& graph : graphs) {
    const Colouring greedy = registry().get("greedy").colour(graph, {});
    const auto expected = reference_first_fit(graph);
    ASSERT_TRUE(std::equal(expected.begin(), expected.end(), greedy.colours().begin(),
                           greedy.colours().end()));
  }
  EXPECT_EQ(registry().get("greedy").colour(graphs[0], {}).colour_count(), 100u);
}

/// The cloth's distance and bending constraints with both groups shuffled (seeded).
ConstraintGraph shuffled_cloth_with_bending(std::size_t columns, std::size_t rows, unsigned seed,
                                            std::vector<ParticleIndex>& edges,
                                            std::vector<ParticleIndex>& bending) {
  const io::ClothGrid cloth = io::make_cloth_grid(columns, rows);
  edges = cloth.edge_indices;
  bending = cloth.bending_indices;
  std::mt19937 random(seed);
  const auto shuffle = [&](std::vector<ParticleIndex>& indices, std::size_t arity) {
    for (std::size_t i = indices.size() / arity; i > 1; --i) {
      const std::size_t j = std::uniform_int_distribution<std::size_t>(0, i - 1)(random);
      for (std::size_t k = 0; k < arity; ++k) std::swap(indices[(i - 1) * arity + k], indices[j * arity + k]);
    }
  };
  shuffle(edges, 2);
  shuffle(bending, 4);
  const std::vector<Real> w(cloth.vertex_count(), Real(1));
  const std::vector<ConstraintGroup> groups = {ConstraintGroup::fixed_arity("distance", 2, edges),
                                               ConstraintGroup::fixed_arity("bending", 4, bending)};
  return ConstraintGraph(w, groups);
}

TEST(KnownOptima, StencilOrderReachesTheBoundOnTheClothWithBendingWhateverTheOrder) {
  // 18 = 6 distance + 12 bending constraints at an interior vertex; reaching it needs every
  // colour to be an exact cover of the interior vertices, which first-fit in degree-based
  // orders does not find (they stop at 20).
  std::vector<ParticleIndex> edges, bending;
  for (unsigned seed : {1u, 2u}) {
    const ConstraintGraph graph = shuffled_cloth_with_bending(30, 26, seed, edges, bending);
    ASSERT_EQ(graph.colour_lower_bound(), 18u);
    const Colouring stencil = registry().get("stencil").colour(graph, {});
    EXPECT_TRUE(validate(graph, stencil).valid) << validate(graph, stencil).problem;
    EXPECT_EQ(stencil.colour_count(), 18u);
    EXPECT_EQ(registry().get("iterated-greedy").colour(graph, {}).colour_count(), 18u);
    EXPECT_GT(registry().get("smallest-last").colour(graph, {}).colour_count(), 18u);
  }
}

TEST(KnownOptima, StencilOrderDoesNotDependOnTheConstraintOrder) {
  // Same constraints in two orders: the same constraints (as particle tuples) share colours.
  std::vector<ParticleIndex> edges1, bending1, edges2, bending2;
  const ConstraintGraph first = shuffled_cloth_with_bending(12, 10, 7, edges1, bending1);
  const ConstraintGraph second = shuffled_cloth_with_bending(12, 10, 8, edges2, bending2);
  const Colouring a = registry().get("stencil").colour(first, {});
  const Colouring b = registry().get("stencil").colour(second, {});
  std::map<std::vector<ParticleIndex>, Colour> colour_of_tuple;
  for (ConstraintIndex c = 0; c < first.constraint_count(); ++c) {
    const auto particles = first.particles_of(c);
    colour_of_tuple[{particles.begin(), particles.end()}] = a.colour_of(c);
  }
  for (ConstraintIndex c = 0; c < second.constraint_count(); ++c) {
    const auto particles = second.particles_of(c);
    EXPECT_EQ(colour_of_tuple.at({particles.begin(), particles.end()}), b.colour_of(c));
  }
}

TEST(RandomStrategy, DifferentSeedsGiveDifferentValidColourings) {
  const ConstraintGraph graph = test::cloth_graph(30, 30, true);
  ColouringOptions a, b;
  a.seed = 1;
  b.seed = 2;
  const Colouring first = registry().get("random").colour(graph, a);
  const Colouring second = registry().get("random").colour(graph, b);
  EXPECT_TRUE(validate(graph, first).valid);
  EXPECT_TRUE(validate(graph, second).valid);
  EXPECT_FALSE(std::equal(first.colours().begin(), first.colours().end(), second.colours().begin()));
}

TEST(MetisStrategy, RenumbersParticlesPartByPartAndListsColoursByPart) {
  const ConstraintGraph graph = test::cloth_graph(40, 40, false, true);
  ColouringOptions options;
  options.particles_per_part = 200;
  const Colouring colouring = registry().get("metis").colour(graph, options);
  ASSERT_TRUE(colouring.renumbers_particles());
  // Static particles (the pinned top row) come last.
  for (std::size_t n = 0; n < graph.particle_count(); ++n)
    EXPECT_EQ(graph.is_movable(colouring.particle_new_to_old()[n]), n < graph.movable_particle_count());
  // Locality: in every colour, constraints listed next to each other mostly touch particles
  // whose new numbers are close, unlike the user's numbering would after a shuffle. Measure the
  // mean spread of new particle ids over windows of 16 scheduled constraints.
  double spread = 0;
  std::size_t windows = 0;
  for (Colour k = 0; k < colouring.colour_count(); ++k) {
    const auto members = colouring.constraints_of(k);
    for (std::size_t start = 0; start + 16 <= members.size(); start += 16) {
      ParticleIndex lo = ~ParticleIndex(0), hi = 0;
      for (std::size_t i = start; i < start + 16; ++i)
        for (ParticleIndex p : graph.particles_of(members[i])) {
          lo = std::min(lo, colouring.particle_old_to_new()[p]);
          hi = std::max(hi, colouring.particle_old_to_new()[p]);
        }
      spread += hi - lo;
      ++windows;
    }
  }
  ASSERT_GT(windows, 0u);
  EXPECT_LT(spread / windows, 2.0 * options.particles_per_part);
}

TEST(MetisStrategy, DefaultPartSizeIsTheMeasuredConstant) {
  // 90,000 movable particles: more than one part of the default size (both part strategies).
  const ConstraintGraph graph = test::cloth_graph(300, 300, false);
  ASSERT_GT(graph.movable_particle_count(), kDefaultParticlesPerPart);
  ColouringOptions by_default, explicit_size;
  explicit_size.particles_per_part = kDefaultParticlesPerPart;
  for (const char* strategy : {"metis", "blocks"}) {
    const Colouring a = registry().get(strategy).colour(graph, by_default);
    const Colouring b = registry().get(strategy).colour(graph, explicit_size);
    EXPECT_TRUE(validate(graph, a).valid) << strategy;
    EXPECT_EQ(a.part_count(), 2u) << strategy;
    EXPECT_TRUE(std::equal(a.colours().begin(), a.colours().end(), b.colours().begin()))
        << strategy;
    EXPECT_TRUE(std::equal(a.particle_new_to_old().begin(), a.particle_new_to_old().end(),
                           b.particle_new_to_old().begin()))
        << strategy;
  }
}

TEST(BlocksStrategy, PartsAreRunsOfTheNumberingStaticParticlesLast) {
  // A 40 × 40 cloth with its first row (particles 0–39) pinned: 1,560 movable particles in
  // parts of 200 at most are 8 runs of consecutive indices, renumbered part by part in
  // their own order, the static particles after them.
  const io::ClothGrid cloth = io::make_cloth_grid(40, 40);
  std::vector<Real> inverse_masses(cloth.vertex_count(), Real(1));
  for (std::size_t i = 0; i < 40; ++i) inverse_masses[i] = 0;
  const std::vector<ConstraintGroup> groups = {
      ConstraintGroup::fixed_arity("distance", 2, cloth.edge_indices),
      ConstraintGroup::fixed_arity("bending", 4, cloth.bending_indices)};
  const ConstraintGraph graph(inverse_masses, groups);
  ColouringOptions options;
  options.particles_per_part = 200;
  const Colouring colouring = registry().get("blocks").colour(graph, options);
  EXPECT_TRUE(validate(graph, colouring).valid);
  ASSERT_TRUE(colouring.has_parts());
  ASSERT_EQ(colouring.part_count(), 8u);
  // New numbers: the movable particles 40, 41, … first and in order, then 0–39.
  for (std::size_t p = 0; p < graph.particle_count(); ++p)
    EXPECT_EQ(colouring.particle_old_to_new()[p], p < 40 ? 1560 + p : p - 40) << "particle " << p;
  // Each interior constraint's part: the same for all its particles, never decreasing along
  // the numbering, and no part with more than 195 particles (1,560 / 8).
  std::vector<std::uint32_t> part_of_particle(graph.particle_count(), ~std::uint32_t(0));
  std::size_t interior = 0;
  for (std::size_t c = 0; c < graph.constraint_count(); ++c) {
    const std::uint32_t part = colouring.part_of_constraint()[c];
    if (part == colouring.part_count()) continue;
    ++interior;
    for (ParticleIndex p : graph.particles_of(static_cast<ConstraintIndex>(c))) {
      EXPECT_TRUE(part_of_particle[p] == ~std::uint32_t(0) || part_of_particle[p] == part)
          << "particle " << p << " in two parts";
      part_of_particle[p] = part;
    }
  }
  std::vector<std::size_t> sizes(colouring.part_count(), 0);
  std::uint32_t last = 0;
  for (std::size_t p = 40; p < graph.particle_count(); ++p) {
    if (part_of_particle[p] == ~std::uint32_t(0)) continue;  // only in crossing constraints
    EXPECT_GE(part_of_particle[p], last) << "particle " << p;
    last = part_of_particle[p];
    ++sizes[last];
  }
  for (const std::size_t size : sizes) EXPECT_LE(size, 195u);
  // Runs of 195 particles are about 5 rows of the cloth: most constraints are inside one.
  EXPECT_GT(interior, graph.constraint_count() / 2);
}

TEST(ParticlePartition, RunsFollowTheGivenOrderAndStaticParticlesCrossNothing) {
  // A chain 0–1–…–9 of distance constraints (i, i+1), particle 0 static, taken in reverse
  // order: the 9 movable particles 9, 8, …, 1 in 3 runs {9, 8, 7}, {6, 5, 4}, {3, 2, 1}.
  std::vector<Real> inverse_masses(10, Real(1));
  inverse_masses[0] = 0;
  std::vector<std::uint32_t> links;
  for (std::uint32_t i = 0; i < 9; ++i) links.insert(links.end(), {i, i + 1});
  const std::vector<ConstraintGroup> groups = {ConstraintGroup::fixed_arity("distance", 2, links)};
  const ConstraintGraph graph(inverse_masses, groups);
  std::vector<ParticleIndex> reversed(10);
  for (std::size_t n = 0; n < 10; ++n) reversed[n] = ParticleIndex(9 - n);
  const ParticlePartition partition = partition_particles_in_runs(graph, reversed, 3);
  ASSERT_EQ(partition.part_count, 3u);
  const std::uint32_t none = ParticlePartition::kNoPart;
  EXPECT_EQ(partition.part_of_particle,
            (std::vector<std::uint32_t>{none, 2, 2, 2, 1, 1, 1, 0, 0, 0}));
  // Constraint (0, 1) touches only particle 1 of the movable ones: interior to part 2, as
  // a sweep only reads the static particle 0. (3, 4) and (6, 7) join two runs: crossing (3).
  EXPECT_EQ(constraint_parts(graph, partition),
            (std::vector<std::uint32_t>{2, 2, 2, 3, 1, 1, 3, 0, 0}));
  // The identity order gives blocks' runs.
  std::vector<ParticleIndex> identity(10);
  for (std::size_t n = 0; n < 10; ++n) identity[n] = ParticleIndex(n);
  EXPECT_EQ(partition_particles_in_runs(graph, identity, 3).part_of_particle,
            partition_particles_in_blocks(graph, 3).part_of_particle);
  // An order that is not a permutation of the particles.
  const auto expect_error = [&](std::vector<ParticleIndex> order, const std::string& words) {
    try {
      partition_particles_in_runs(graph, order, 3);
      FAIL() << "no error; expected one naming " << words;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  expect_error({0, 1, 2}, "the order lists 3 particles, the graph has 10");
  std::vector<ParticleIndex> twice = identity;
  twice[7] = 2;
  expect_error(twice, "position 7 of the order names particle 2, listed before");
  std::vector<ParticleIndex> past = identity;
  past[4] = 10;
  expect_error(past, "names particle 10, past the 10 particles");
  // A partition that does not fit the graph, or leaves a movable particle out.
  const auto expect_parts_error = [&](const ParticlePartition& bad, const std::string& words) {
    try {
      constraint_parts(graph, bad);
      FAIL() << "no error; expected one naming " << words;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  ParticlePartition short_one = partition;
  short_one.part_of_particle.pop_back();
  expect_parts_error(short_one, "the partition is of 9 particles, the graph has 10");
  ParticlePartition left_out = partition;
  left_out.part_of_particle[5] = ParticlePartition::kNoPart;
  expect_parts_error(left_out, "movable particle 5 is in no part");
  ParticlePartition past_count = partition;
  past_count.part_of_particle[5] = 3;
  expect_parts_error(past_count, "movable particle 5 is in part 3 of 3");
}

TEST(Balance, EvensOutColourSizesWithoutAddingColours) {
  const ConstraintGraph graph = test::tet_bar_graph(16, 6, 6);
  const Colouring greedy = registry().get("greedy").colour(graph, {});
  const ColouringStatistics before = compute_statistics(graph, greedy);
  const Colouring balanced = balance_colours(graph, greedy);
  const ColouringStatistics after = compute_statistics(graph, balanced);
  ASSERT_TRUE(after.valid) << after.problem;
  EXPECT_EQ(after.colours, before.colours);
  EXPECT_GT(before.size_ratio, 2.0);
  EXPECT_LT(after.size_ratio, before.size_ratio);
  EXPECT_LE(after.size_ratio, 1.1) << format_statistics(after);
}

std::size_t squared_size_sum(const Colouring& colouring) {
  std::size_t sum = 0;
  for (Colour k = 0; k < colouring.colour_count(); ++k) sum += colouring.colour_size(k) * colouring.colour_size(k);
  return sum;
}

TEST(Balance, ReachesTenPercentNearTheLowerBound) {
  // The stencil colouring of a tet bar is close to the lower bound with colours of pure
  // tetrahedra (covering nearly every particle) and of pure edges: no constraint can move on
  // its own, only by ejecting the constraints that block it (direct moves and short Kempe
  // chains stopped at 1.5 here).
  const ConstraintGraph graph = test::tet_bar_graph(30, 12, 12);
  const Colouring stencil = registry().get("stencil").colour(graph, {});
  const ColouringStatistics before = compute_statistics(graph, stencil);
  ASSERT_LE(before.colours, graph.colour_lower_bound() + 3);
  const Colouring balanced = balance_colours(graph, stencil);
  const ColouringStatistics after = compute_statistics(graph, balanced);
  ASSERT_TRUE(after.valid) << after.problem;
  EXPECT_EQ(after.colours, before.colours);
  EXPECT_LE(after.size_ratio, 1.1) << format_statistics(after);
  EXPECT_LT(squared_size_sum(balanced), squared_size_sum(stencil));
}

TEST(Balance, KempeSwapsFinishWhereEjectionsStall) {
  // First-fit on a distance + bending cloth repeats one pattern everywhere: edge colours are
  // large, bending colours near-perfect covers, and no constraint fits a smaller colour even
  // after ejecting its blockers (ejections alone stopped at 1.33). The iterated-greedy tet
  // bar at one above the lower bound stalls the same way (1.20). Small Kempe swaps between a
  // large and a small colour still fit and finish the job.
  const ConstraintGraph cloth = test::cloth_graph(48, 48, true);
  const ConstraintGraph bar = test::tet_bar_graph(30, 12, 12);
  for (const auto& [graph, strategy] : {std::pair<const ConstraintGraph&, const char*>{cloth, "greedy"},
                                        std::pair<const ConstraintGraph&, const char*>{bar, "iterated-greedy"}}) {
    const Colouring input = registry().get(strategy).colour(graph, {});
    const ColouringStatistics before = compute_statistics(graph, input);
    ASSERT_GT(before.size_ratio, 1.1) << strategy;
    const Colouring balanced = balance_colours(graph, input);
    const ColouringStatistics after = compute_statistics(graph, balanced);
    ASSERT_TRUE(after.valid) << strategy << ": " << after.problem;
    EXPECT_EQ(after.colours, before.colours) << strategy;
    EXPECT_LE(after.size_ratio, 1.1) << strategy << "\n" << format_statistics(after);
    EXPECT_LT(squared_size_sum(balanced), squared_size_sum(input)) << strategy;
  }
}

TEST(Balance, KeepsForcedSizesAtTheLowerBound) {
  // Distance + bending on the uniform cloth at its lower bound (18): each colour is an exact
  // cover of the interior particles, so edge colours hold twice as many constraints as
  // bending colours and only a few constraints at the border can move. The pass must stay
  // valid, keep the count and stop (it does, early, once a block of a sweep moves nothing).
  const ConstraintGraph graph = test::cloth_graph(40, 40, true);
  const Colouring stencil = registry().get("stencil").colour(graph, {});
  ASSERT_EQ(stencil.colour_count(), graph.colour_lower_bound());
  const Colouring balanced = balance_colours(graph, stencil);
  EXPECT_TRUE(validate(graph, balanced).valid);
  EXPECT_EQ(balanced.colour_count(), stencil.colour_count());
  EXPECT_LE(squared_size_sum(balanced), squared_size_sum(stencil));
}

TEST(Balance, IsDeterministicAndKeepsScheduleOrder) {
  const ConstraintGraph graph = test::tet_bar_graph(12, 5, 5);
  const Colouring greedy = registry().get("greedy").colour(graph, {});
  const Colouring first = balance_colours(graph, greedy);
  const Colouring second = balance_colours(graph, greedy);
  EXPECT_TRUE(std::equal(first.colours().begin(), first.colours().end(), second.colours().begin()));
  // Within each colour, constraints keep the relative order they had in the input schedule.
  std::vector<std::size_t> position(graph.constraint_count());
  for (std::size_t i = 0; i < greedy.constraints_by_colour().size(); ++i)
    position[greedy.constraints_by_colour()[i]] = i;
  for (Colour k = 0; k < first.colour_count(); ++k) {
    const auto members = first.constraints_of(k);
    for (std::size_t i = 1; i < members.size(); ++i)
      EXPECT_LT(position[members[i - 1]], position[members[i]]);
  }
}

TEST(Balance, HandlesManyColoursWithDirectMovesOnly) {
  // 400 independent constraints in 151 colours, one holding 250: too many colours for the
  // particle × colour table, so only direct moves run, which suffice here.
  const ConstraintGraph graph = test::isolated_graph(400);
  std::vector<Colour> colours(graph.constraint_count());
  for (std::size_t c = 0; c < colours.size(); ++c) colours[c] = static_cast<Colour>(std::min<std::size_t>(c, 150));
  const Colouring skewed = Colouring::from_colours(colours);
  const Colouring balanced = balance_colours(graph, skewed);
  const ColouringStatistics after = compute_statistics(graph, balanced);
  EXPECT_TRUE(after.valid) << after.problem;
  EXPECT_EQ(after.colours, skewed.colour_count());
  EXPECT_LE(after.largest, after.smallest + 1);
}

TEST(Reduce, RemovesColoursAndNeverAddsAny) {
  const ConstraintGraph graph = test::cloth_graph(20, 20, false);
  const Colouring random = registry().get("random").colour(graph, {});
  ASSERT_GT(random.colour_count(), 7u);
  const Colouring reduced = reduce_colours(graph, random, {});
  EXPECT_TRUE(validate(graph, reduced).valid);
  EXPECT_LT(reduced.colour_count(), random.colour_count());
  EXPECT_GE(reduced.colour_count(), 6u);
  ColouringOptions none;
  none.reduction_rounds = 0;
  EXPECT_LE(reduce_colours(graph, random, none).colour_count(), random.colour_count());
}

TEST(RunColouring, AppliesPostPassesAndReportsStatistics) {
  const ConstraintGraph graph = test::tet_bar_graph(6, 3, 3);
  ColouringOptions options;
  options.reduce = true;
  options.balance = true;
  const ColouringRun run = run_colouring(registry().get("greedy"), graph, options);
  EXPECT_EQ(run.statistics.strategy, "greedy+reduce+balance");
  EXPECT_TRUE(run.statistics.valid);
  EXPECT_EQ(run.statistics.colours, run.colouring.colour_count());
  EXPECT_EQ(run.statistics.lower_bound, graph.colour_lower_bound());
  EXPECT_GE(run.statistics.seconds, 0.0);
}

class NamedOnly final : public ColouringStrategy {
 public:
  std::string_view name() const override { return "one-colour-per-constraint"; }
  std::string_view description() const override { return "every constraint alone"; }
  Colouring colour(const ConstraintGraph& graph, const ColouringOptions&) const override {
    std::vector<Colour> colours(graph.constraint_count());
    for (std::size_t c = 0; c < colours.size(); ++c) colours[c] = static_cast<Colour>(c);
    return Colouring::from_colours(std::move(colours));
  }
};

TEST(Registry, ListsBuiltinsFindsByNameAndTakesUserStrategies) {
  ColouringRegistry registry = ColouringRegistry::with_builtin_strategies();
  const std::vector<std::string_view> names = registry.names();
  for (const char* expected : {"greedy", "largest-first", "smallest-last", "dsatur", "stencil",
                               "iterated-greedy", "random", "metis", "blocks"})
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
  EXPECT_THROW(registry.get("no-such-strategy"), InvalidInput);
  EXPECT_THROW(registry.add(make_greedy_strategy()), InvalidInput);
  registry.add(std::make_shared<NamedOnly>());
  const ConstraintGraph graph = test::cloth_graph(4, 4, false);
  EXPECT_EQ(registry.get("one-colour-per-constraint").colour(graph, {}).colour_count(),
            graph.constraint_count());
  EXPECT_TRUE(registry.contains("one-colour-per-constraint"));
}

// The stencil order by its definition, slowly: constraints by (rank of their shape class,
// smallest movable particle, id), then plain first-fit. The shape hash is colour_masks.hpp's
// mix_hash chain (equal-sized classes are ranked by it, so the reference needs the same one).
std::uint64_t reference_mix(std::uint64_t seed, std::uint64_t value) {
  std::uint64_t z = seed * 0x9E3779B97F4A7C15ull + value + 0x632BE59BD9B4E019ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

std::vector<Colour> reference_stencil_colours(const ConstraintGraph& graph) {
  const std::size_t count = graph.constraint_count();
  std::vector<std::uint64_t> shape(count);
  std::vector<ParticleIndex> anchor(count, 0);
  std::vector<std::size_t> arity(count);
  std::map<std::uint64_t, std::pair<std::size_t, std::size_t>> classes;  // shape -> size, arity
  for (std::size_t c = 0; c < count; ++c) {
    const auto span = graph.particles_of(static_cast<ConstraintIndex>(c));
    std::vector<ParticleIndex> sorted(span.begin(), span.end());
    std::sort(sorted.begin(), sorted.end());
    shape[c] = reference_mix(0x5EED, sorted.size());
    for (std::size_t i = 1; i < sorted.size(); ++i) shape[c] = reference_mix(shape[c], sorted[i] - sorted[0]);
    if (!sorted.empty()) anchor[c] = sorted[0];
    arity[c] = sorted.size();
    auto& entry = classes[shape[c]];
    ++entry.first;
    entry.second = sorted.size();
  }
  // Rank key: larger arity first; a class of 64 or more by size (larger first) then shape; the
  // others of one arity together after them.
  const auto rank_key = [&](std::uint64_t h) {
    const auto [size, a] = classes.at(h);
    const bool pattern = size >= 64;
    return std::make_tuple(~a, pattern ? ~size : ~std::size_t(0), pattern ? h : 0);
  };
  std::vector<ConstraintIndex> order(count);
  std::iota(order.begin(), order.end(), ConstraintIndex(0));
  std::sort(order.begin(), order.end(), [&](ConstraintIndex a, ConstraintIndex b) {
    return std::make_tuple(rank_key(shape[a]), anchor[a], a) < std::make_tuple(rank_key(shape[b]), anchor[b], b);
  });
  std::vector<std::set<Colour>> taken(graph.particle_count());
  std::vector<Colour> colours(count, 0);
  for (ConstraintIndex c : order) {
    Colour k = 0;
    const auto particles = graph.particles_of(c);
    while (std::any_of(particles.begin(), particles.end(), [&](ParticleIndex p) { return taken[p].count(k) > 0; })) ++k;
    for (ParticleIndex p : particles) taken[p].insert(k);
    colours[c] = k;
  }
  return colours;
}

/// Shapes the stencil order keys by their hash, not packed: several five-particle shapes of 100
/// constraints each, and two-particle shapes whose offset is past 2^20, 64 of each. Classes
/// of one arity and size are ranked by their hashes, so these pin down that ranking.
ConstraintGraph hashed_shapes_graph() {
  std::vector<ParticleIndex> five, far;
  const std::vector<std::vector<ParticleIndex>> offsets = {
      {0, 1, 2, 3, 4}, {0, 1, 2, 3, 5}, {0, 2, 3, 5, 8}, {0, 1, 4, 6, 7}, {0, 3, 4, 5, 9}};
  for (std::size_t shape = 0; shape < offsets.size(); ++shape)
    for (ParticleIndex p = 0; p < 100; ++p)
      for (const ParticleIndex o : offsets[shape])
        five.push_back(ParticleIndex(200 * shape) + p + o);
  constexpr ParticleIndex kFar = ParticleIndex(1) << 20;
  for (ParticleIndex p = 0; p < 64; ++p)
    for (const ParticleIndex o : {kFar + 1, kFar + 2, kFar + 3})
      far.insert(far.end(), {ParticleIndex(2000 + 3 * p), ParticleIndex(2000 + 3 * p + o)});
  const std::vector<Real> inverse_masses(std::size_t(kFar) + 2300, Real(1));
  const std::vector<ConstraintGroup> groups = {ConstraintGroup::fixed_arity("five", 5, five),
                                               ConstraintGroup::fixed_arity("far", 2, far)};
  return ConstraintGraph(inverse_masses, groups);
}

TEST(Stencil, EqualsFirstFitInRankAnchorIdOrderForAnyThreadCount) {
  std::vector<std::pair<std::string, ConstraintGraph>> graphs;
  for (const auto& mesh : meshes()) graphs.emplace_back(mesh.name, ConstraintGraph(mesh.graph));
  // Several chunks of the parallel passes (64 K constraints), in mesh order and shuffled (the
  // shuffled runs are not in anchor order, so they take the radix sort).
  graphs.emplace_back("cloth 150x150", test::cloth_graph(150, 150, true));
  std::vector<ParticleIndex> edges, bending;
  graphs.emplace_back("shuffled cloth 120x120", shuffled_cloth_with_bending(120, 120, 7, edges, bending));
  graphs.emplace_back("tet bar 30x8x8", test::tet_bar_graph(30, 8, 8));
  graphs.emplace_back("hashed shapes", hashed_shapes_graph());
  for (const auto& [name, graph] : graphs) {
    const std::vector<Colour> expected = reference_stencil_colours(graph);
    for (int threads : {1, 2}) {
      const Colouring colouring = colour_with_threads("stencil", graph, threads);
      EXPECT_TRUE(std::equal(expected.begin(), expected.end(), colouring.colours().begin(),
                             colouring.colours().end()))
          << name << ", " << threads << " threads";
    }
  }
}

}  // namespace strategies_tests
}  // namespace tessera
