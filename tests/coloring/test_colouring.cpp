// Colouring (CSR by colour, particle permutation), validate() and the statistics.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>

#include <tbb/task_arena.h>

#include <tessera/coloring/colouring.hpp>
#include <tessera/coloring/colouring_statistics.hpp>
#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/locality.hpp>
#include <tessera/core/error.hpp>

#include "test_meshes.hpp"

namespace tessera {
namespace colouring_tests {

TEST(Colouring, GroupsConstraintsByColourInIdOrderOrAGivenOrder) {
  const Colouring c = Colouring::from_colours({1, 0, 1, 2, 0});
  ASSERT_EQ(c.colour_count(), 3u);
  EXPECT_EQ(std::vector<ConstraintIndex>(c.constraints_of(0).begin(), c.constraints_of(0).end()),
            (std::vector<ConstraintIndex>{1, 4}));
  EXPECT_EQ(std::vector<ConstraintIndex>(c.constraints_of(1).begin(), c.constraints_of(1).end()),
            (std::vector<ConstraintIndex>{0, 2}));
  EXPECT_EQ(c.colour_size(2), 1u);
  const std::vector<ConstraintIndex> order = {4, 3, 2, 1, 0};
  const Colouring r = Colouring::from_colours({1, 0, 1, 2, 0}, order);
  EXPECT_EQ(std::vector<ConstraintIndex>(r.constraints_of(0).begin(), r.constraints_of(0).end()),
            (std::vector<ConstraintIndex>{4, 1}));
  EXPECT_THROW(Colouring::from_colours({0, 2}), InvalidInput);  // colour 1 unused
  const std::vector<ConstraintIndex> not_a_permutation = {0, 0, 1, 2, 3};
  EXPECT_THROW(Colouring::from_colours({1, 0, 1, 2, 0}, not_a_permutation), InvalidInput);
}

TEST(Colouring, ParticlePermutationBothWays) {
  Colouring c = Colouring::from_colours({0});
  EXPECT_FALSE(c.renumbers_particles());
  c.set_particle_order({2, 0, 1});
  EXPECT_TRUE(c.renumbers_particles());
  EXPECT_EQ(c.particle_old_to_new()[2], 0u);
  EXPECT_EQ(c.particle_old_to_new()[0], 1u);
  EXPECT_THROW(c.set_particle_order({0, 0, 1}), InvalidInput);
  EXPECT_THROW(c.set_particle_order({0, 3, 1}), InvalidInput);
}

TEST(Validate, FindsTwoConstraintsOfOneColourSharingAMovableParticle) {
  const ConstraintGraph graph = test::cloth_graph(3, 3, false);  // 16 edges
  std::vector<Colour> all_distinct(graph.constraint_count());
  for (std::size_t c = 0; c < all_distinct.size(); ++c) all_distinct[c] = static_cast<Colour>(c);
  EXPECT_TRUE(validate(graph, Colouring::from_colours(all_distinct)).valid);

  // Edges 0 (0-1) and 1 (0-3) share particle 0.
  std::vector<Colour> clash = all_distinct;
  clash[1] = 0;
  for (std::size_t c = 2; c < clash.size(); ++c) clash[c] = static_cast<Colour>(c - 1);
  const ColouringValidation check = validate(graph, Colouring::from_colours(clash));
  EXPECT_FALSE(check.valid);
  EXPECT_NE(check.problem.find("share movable particle 0"), std::string::npos) << check.problem;
  EXPECT_NE(check.problem.find("constraint group 'distance', constraint 1"), std::string::npos);

  EXPECT_FALSE(validate(graph, Colouring::from_colours({0, 1})).valid);  // wrong size
}

TEST(Validate, FindsAClashDeepInALongColour) {
  // A clash far into a colour of thousands, in the particle order improve_locality gives it,
  // is found and named.
  const ConstraintGraph graph = test::cloth_graph(60, 60, true);
  const Colouring plain =
      ColouringRegistry::with_builtin_strategies().get("greedy").colour(graph, {});
  const Colouring local = improve_locality(graph, plain);
  ASSERT_TRUE(validate(graph, local).valid);
  ASSERT_GT(local.colour_size(0), 1000u);
  // A constraint two thirds into colour 0, and one of another colour sharing a particle.
  const ConstraintIndex deep = local.constraints_of(0)[local.colour_size(0) * 2 / 3];
  const ParticleIndex shared = graph.particles_of(deep)[0];
  ConstraintIndex other = deep;
  for (ConstraintIndex c : graph.constraints_of(shared))
    if (local.colour_of(c) != 0) other = c;
  ASSERT_NE(other, deep);
  std::vector<Colour> clash(local.colours().begin(), local.colours().end());
  clash[other] = 0;
  const Colouring broken = Colouring::from_colours(clash, local.constraints_by_colour());
  const ColouringValidation check = validate(graph, broken);
  EXPECT_FALSE(check.valid);
  EXPECT_NE(check.problem.find("colour 0: "), std::string::npos) << check.problem;
  EXPECT_NE(check.problem.find("share movable particle"), std::string::npos) << check.problem;
}

/// Colours renumbered densely in their order (a colour left empty by a move disappears).
std::vector<Colour> compacted(std::vector<Colour> colours) {
  std::vector<Colour> sorted = colours;
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  for (Colour& k : colours)
    k = Colour(std::lower_bound(sorted.begin(), sorted.end(), k) - sorted.begin());
  return colours;
}

/// The lowest movable particle two constraints of one colour share, by brute force.
std::size_t lowest_shared_particle(const ConstraintGraph& graph, std::span<const Colour> colours) {
  for (std::size_t p = 0; p < graph.particle_count(); ++p) {
    const auto constraints = graph.constraints_of(ParticleIndex(p));
    for (std::size_t i = 0; i < constraints.size(); ++i)
      for (std::size_t j = 0; j < i; ++j)
        if (colours[constraints[i]] == colours[constraints[j]]) return p;
  }
  return graph.particle_count();
}

TEST(Validate, NamesTheLowestSharedParticleOnAnyThreadCount) {
  // Clashes far apart in a 160 × 160 cloth (25,600 particles: two of the check's chunks of
  // 16,384): the message names the lowest particle shared, the same on 1, 2 and 4 threads.
  const ConstraintGraph graph = test::cloth_graph(160, 160, true);
  const Colouring plain =
      ColouringRegistry::with_builtin_strategies().get("greedy").colour(graph, {});
  std::vector<Colour> clash(plain.colours().begin(), plain.colours().end());
  for (const ParticleIndex p : {ParticleIndex(20000), ParticleIndex(5000), ParticleIndex(17000)}) {
    const auto constraints = graph.constraints_of(p);
    clash[constraints[1]] = clash[constraints[0]];
  }
  const Colouring broken = Colouring::from_colours(compacted(clash));
  const std::size_t expected = lowest_shared_particle(graph, broken.colours());
  ASSERT_LE(expected, 5000u);
  for (const int threads : {1, 2, 4}) {
    const ColouringValidation check =
        tbb::task_arena(threads).execute([&] { return validate(graph, broken); });
    EXPECT_FALSE(check.valid);
    EXPECT_TRUE(check.problem.ends_with("share movable particle " + std::to_string(expected)))
        << threads << " threads: " << check.problem;
  }
}

TEST(Validate, FindsAClashAmongColoursPastSixtyFour) {
  // Every constraint of a small cloth in its own colour (more than 64 colours), then two that
  // share a particle put in one: found and named, as below 64.
  const ConstraintGraph graph = test::cloth_graph(8, 8, true);
  std::vector<Colour> own(graph.constraint_count());
  for (std::size_t c = 0; c < own.size(); ++c) own[c] = Colour(c);
  ASSERT_GT(own.size(), 100u);
  EXPECT_TRUE(validate(graph, Colouring::from_colours(own)).valid);
  const auto constraints = graph.constraints_of(ParticleIndex(45));
  ASSERT_GE(constraints.size(), 2u);
  std::vector<Colour> clash = own;
  clash[constraints.back()] = clash[constraints.front()];
  const Colouring broken = Colouring::from_colours(compacted(clash));
  ASSERT_GT(broken.colour_of(constraints.front()), 64u);
  const ColouringValidation check = validate(graph, broken);
  EXPECT_FALSE(check.valid);
  EXPECT_TRUE(check.problem.ends_with(
      "share movable particle " + std::to_string(lowest_shared_particle(graph, broken.colours()))))
      << check.problem;
}

TEST(Validate, SharingAStaticParticleIsNoConflict) {
  const ConstraintGraph graph = test::pinned_star_graph(5);
  EXPECT_TRUE(validate(graph, Colouring::from_colours({0, 0, 0, 0, 0})).valid);
}

TEST(Statistics, SizesBalanceAndLowerBound) {
  const ConstraintGraph graph = test::cloth_graph(3, 3, false);  // 16 edges, lower bound 6
  std::vector<Colour> colours(16);
  for (std::size_t c = 0; c < 16; ++c) colours[c] = static_cast<Colour>(c < 10 ? c % 8 : c - 8);
  // Colours 0..7: sizes 0,1 → 2 each; 2..7 → 2 (c and c+8 for c<2... ) computed below.
  const Colouring colouring = Colouring::from_colours(colours);
  const ColouringStatistics s = compute_statistics(graph, colouring, "hand made", 0.5);
  EXPECT_EQ(s.strategy, "hand made");
  EXPECT_EQ(s.constraints, 16u);
  EXPECT_EQ(s.colours, colouring.colour_count());
  std::size_t total = 0;
  for (std::size_t size : s.sizes) total += size;
  EXPECT_EQ(total, 16u);
  EXPECT_EQ(s.largest, *std::max_element(s.sizes.begin(), s.sizes.end()));
  EXPECT_EQ(s.smallest, *std::min_element(s.sizes.begin(), s.sizes.end()));
  EXPECT_DOUBLE_EQ(s.mean, 16.0 / s.colours);
  EXPECT_DOUBLE_EQ(s.balance, s.largest / s.mean);
  EXPECT_EQ(s.lower_bound, 6u);
  EXPECT_DOUBLE_EQ(s.colours_per_lower_bound, s.colours / 6.0);
  EXPECT_DOUBLE_EQ(s.seconds, 0.5);
  EXPECT_EQ(s.valid, validate(graph, colouring).valid);
  const std::string text = format_statistics(s);
  for (const char* key : {"strategy: hand made", "colours: ", "sizes: ", "largest: ", "smallest: ",
                          "balance: ", "lower_bound: 6", "colours/lower_bound: ", "seconds: ", "valid: "})
    EXPECT_NE(text.find(key), std::string::npos) << key;
}

TEST(Colouring, LargeInputGroupedInParallelAsSequentially) {
  // Over 256 K constraints with few colours: the parallel grouping. Every colour's list must be
  // its constraints by increasing id, for 1 and 2 threads; an empty colour is still refused.
  std::mt19937 random(5);
  std::vector<Colour> colours(300000);
  for (Colour& k : colours) k = static_cast<Colour>(random() % 19);
  std::vector<std::vector<ConstraintIndex>> expected(19);
  for (std::size_t c = 0; c < colours.size(); ++c) expected[colours[c]].push_back(static_cast<ConstraintIndex>(c));
  for (int threads : {1, 2}) {
    const Colouring colouring =
        tbb::task_arena(threads).execute([&] { return Colouring::from_colours(colours); });
    ASSERT_EQ(colouring.colour_count(), 19u);
    for (Colour k = 0; k < 19; ++k) {
      const auto list = colouring.constraints_of(k);
      EXPECT_EQ(std::vector<ConstraintIndex>(list.begin(), list.end()), expected[k]) << "colour " << k;
    }
  }
  for (Colour& k : colours) if (k == 7) k = 3;
  EXPECT_THROW(Colouring::from_colours(colours), InvalidInput);
}

}  // namespace colouring_tests
}  // namespace tessera
