// ConstraintGraph: the two CSR directions, static particles left out, the lower bound, and
// validation at the door.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <tessera/coloring/constraint_graph.hpp>
#include <tessera/core/error.hpp>

#include "test_meshes.hpp"

namespace tessera {
namespace {

std::vector<ParticleIndex> as_vector(std::span<const ParticleIndex> s) { return {s.begin(), s.end()}; }

TEST(ConstraintGraph, BothDirectionsOverMixedGroupsWithoutStaticParticles) {
  // Particles 0..5; particle 2 is static.
  const std::vector<Real> w = {1, 1, 0, 1, 1, 1};
  const std::vector<ParticleIndex> edges = {0, 1, 1, 2, 2, 3};
  const std::vector<ParticleIndex> offsets = {0, 3, 5};
  const std::vector<ParticleIndex> clusters = {3, 4, 5, 5, 0};
  const std::vector<ConstraintGroup> groups = {
      ConstraintGroup::fixed_arity("distance", 2, edges),
      ConstraintGroup::variable_size("cluster", offsets, clusters)};
  const ConstraintGraph graph(w, groups);

  EXPECT_EQ(graph.particle_count(), 6u);
  EXPECT_EQ(graph.movable_particle_count(), 5u);
  EXPECT_EQ(graph.constraint_count(), 5u);
  EXPECT_EQ(graph.incidence_count(), 9u);  // 11 indices, two name static particle 2
  EXPECT_EQ(as_vector(graph.particles_of(0)), (std::vector<ParticleIndex>{0, 1}));
  EXPECT_EQ(as_vector(graph.particles_of(1)), (std::vector<ParticleIndex>{1}));
  EXPECT_EQ(as_vector(graph.particles_of(2)), (std::vector<ParticleIndex>{3}));
  EXPECT_EQ(as_vector(graph.particles_of(3)), (std::vector<ParticleIndex>{3, 4, 5}));
  EXPECT_EQ(as_vector(graph.particles_of(4)), (std::vector<ParticleIndex>{5, 0}));
  EXPECT_EQ(as_vector(graph.constraints_of(0)), (std::vector<ConstraintIndex>{0, 4}));
  EXPECT_EQ(as_vector(graph.constraints_of(1)), (std::vector<ConstraintIndex>{0, 1}));
  EXPECT_TRUE(graph.constraints_of(2).empty());
  EXPECT_EQ(as_vector(graph.constraints_of(3)), (std::vector<ConstraintIndex>{2, 3}));
  EXPECT_EQ(as_vector(graph.constraints_of(5)), (std::vector<ConstraintIndex>{3, 4}));
  EXPECT_EQ(graph.colour_lower_bound(), 2u);

  EXPECT_EQ(graph.group_count(), 2u);
  EXPECT_EQ(graph.group_of(2), 0u);
  EXPECT_EQ(graph.group_of(3), 1u);
  EXPECT_EQ(graph.describe_constraint(4), "constraint group 'cluster', constraint 1");
}

TEST(ConstraintGraph, LowerBoundOfTheCloth) {
  // Uniform diagonals: interior vertices have 6 edges; with bending each vertex is an edge end
  // of 6 stencils and the wing of 6 more.
  EXPECT_EQ(test::cloth_graph(10, 10, false).colour_lower_bound(), 6u);
  EXPECT_EQ(test::cloth_graph(10, 10, true).colour_lower_bound(), 18u);
  EXPECT_EQ(test::empty_graph().colour_lower_bound(), 0u);
  EXPECT_EQ(test::single_constraint_graph().colour_lower_bound(), 1u);
  // Only static particles shared: every movable particle sees one constraint.
  EXPECT_EQ(test::pinned_star_graph(7).colour_lower_bound(), 1u);
}

TEST(ConstraintGraph, EmptyGroupsAndNoGroups) {
  const std::vector<Real> w = {1, 1};
  const ConstraintGraph none(w, {});
  EXPECT_EQ(none.constraint_count(), 0u);
  EXPECT_EQ(none.particle_count(), 2u);
  const ConstraintGraph default_constructed;
  EXPECT_EQ(default_constructed.constraint_count(), 0u);
}

/// Expects InvalidInput whose message contains every fragment.
template <class F>
void expect_invalid(F&& f, std::initializer_list<std::string> fragments) {
  try {
    f();
    ADD_FAILURE() << "no exception";
  } catch (const InvalidInput& e) {
    for (const std::string& fragment : fragments)
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos)
          << "message '" << e.what() << "' lacks '" << fragment << "'";
  }
}

TEST(ConstraintGraph, RejectsBadInputNamingGroupConstraintAndProblem) {
  const std::vector<Real> w(50, Real(1));
  const std::vector<ParticleIndex> good = {0, 1, 2, 3};
  std::vector<ParticleIndex> out_of_range(36, 3);
  for (std::size_t i = 0; i < out_of_range.size(); ++i) out_of_range[i] = static_cast<ParticleIndex>(i);
  out_of_range[35] = 99;  // constraint 17, second index
  expect_invalid([&] {
    const std::vector<ConstraintGroup> g = {ConstraintGroup::fixed_arity("bending", 4, good),
                                            ConstraintGroup::fixed_arity("distance", 2, out_of_range)};
    ConstraintGraph(w, g);
  }, {"constraint group 'distance', constraint 17", "particle index 99 out of range [0, 50)"});

  const std::vector<ParticleIndex> twice = {0, 1, 2, 3, 4, 5, 6, 5};
  expect_invalid([&] {
    const std::vector<ConstraintGroup> g = {ConstraintGroup::fixed_arity("tetra", 4, twice)};
    ConstraintGraph(w, g);
  }, {"constraint group 'tetra', constraint 1", "particle 5 appears twice"});

  // A particle named twice is an error even when it is static.
  std::vector<Real> pinned(w);
  pinned[7] = 0;
  const std::vector<ParticleIndex> twice_static = {7, 7};
  expect_invalid([&] {
    const std::vector<ConstraintGroup> g = {ConstraintGroup::fixed_arity("distance", 2, twice_static)};
    ConstraintGraph(pinned, g);
  }, {"constraint 0", "appears twice"});

  const std::vector<ParticleIndex> cluster_offsets = {0, 2, 5};
  const std::vector<ParticleIndex> cluster_twice = {0, 1, 8, 9, 8};
  expect_invalid([&] {
    const std::vector<ConstraintGroup> g = {
        ConstraintGroup::variable_size("cluster", cluster_offsets, cluster_twice)};
    ConstraintGraph(w, g);
  }, {"constraint group 'cluster', constraint 1", "particle 8 appears twice"});

  std::vector<Real> negative(w);
  negative[3] = -1;
  expect_invalid([&] {
    const std::vector<ConstraintGroup> g = {ConstraintGroup::fixed_arity("distance", 2, good)};
    ConstraintGraph(negative, g);
  }, {"particle 3", "negative"});
  std::vector<Real> nan(w);
  nan[4] = std::numeric_limits<Real>::quiet_NaN();
  expect_invalid([&] { ConstraintGraph(nan, {}); }, {"particle 4", "not finite"});
  std::vector<Real> infinite(w);
  infinite[5] = std::numeric_limits<Real>::infinity();
  expect_invalid([&] { ConstraintGraph(infinite, {}); }, {"particle 5", "not finite"});
}

TEST(ConstraintGroup, RejectsMalformedShapes) {
  const std::vector<ParticleIndex> five = {0, 1, 2, 3, 4};
  EXPECT_THROW(ConstraintGroup::fixed_arity("distance", 2, five), InvalidInput);
  EXPECT_THROW(ConstraintGroup::fixed_arity("distance", 0, five), InvalidInput);
  const std::vector<ParticleIndex> decreasing = {0, 3, 2, 5};
  EXPECT_THROW(ConstraintGroup::variable_size("cluster", decreasing, five), InvalidInput);
  const std::vector<ParticleIndex> short_end = {0, 2, 4};
  EXPECT_THROW(ConstraintGroup::variable_size("cluster", short_end, five), InvalidInput);
  const std::vector<ParticleIndex> late_start = {1, 5};
  EXPECT_THROW(ConstraintGroup::variable_size("cluster", late_start, five), InvalidInput);
  const std::vector<ParticleIndex> no_offsets;
  EXPECT_THROW(ConstraintGroup::variable_size("cluster", no_offsets, five), InvalidInput);
}

}  // namespace
}  // namespace tessera
