// ConstraintGraph: the two CSR directions, static particles left out, the lower bound, and
// validation at the door; the parallel build against a plain sequential one on random input,
// the same for 1 and 2 threads; groups by slot; the model's graph.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <tessera/coloring/model_graph.hpp>
#include <tessera/core/distance_constraints.hpp>

#include <tessera/coloring/constraint_graph.hpp>
#include <tessera/core/error.hpp>

#include "test_meshes.hpp"

namespace tessera {
namespace constraint_graph_tests {

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

/// The graph by definition, sequentially: each constraint's movable particles in order, each
/// particle's constraints by increasing id, the lower bound as the largest particle degree.
struct PlainGraph {
  std::vector<std::vector<ParticleIndex>> particles_of;
  std::vector<std::vector<ConstraintIndex>> constraints_of;
  std::size_t lower_bound = 0;
};

PlainGraph plain_graph(std::span<const Real> w, std::span<const ConstraintGroup> groups) {
  PlainGraph plain;
  plain.constraints_of.resize(w.size());
  for (const ConstraintGroup& group : groups)
    for (std::size_t i = 0; i < group.constraint_count(); ++i) {
      const auto c = static_cast<ConstraintIndex>(plain.particles_of.size());
      auto& particles = plain.particles_of.emplace_back();
      for (std::size_t k = 0; k < group.constraint_size(i); ++k) {
        const ParticleIndex p = group.particle(i, k);
        if (w[p] == 0) continue;
        particles.push_back(p);
        plain.constraints_of[p].push_back(c);
      }
    }
  for (const auto& list : plain.constraints_of) plain.lower_bound = std::max(plain.lower_bound, list.size());
  if (!plain.particles_of.empty()) plain.lower_bound = std::max<std::size_t>(plain.lower_bound, 1);
  return plain;
}

void expect_equal(const ConstraintGraph& graph, const PlainGraph& plain) {
  ASSERT_EQ(graph.constraint_count(), plain.particles_of.size());
  ASSERT_EQ(graph.particle_count(), plain.constraints_of.size());
  for (std::size_t c = 0; c < plain.particles_of.size(); ++c)
    ASSERT_EQ(as_vector(graph.particles_of(static_cast<ConstraintIndex>(c))), plain.particles_of[c])
        << "constraint " << c;
  for (std::size_t p = 0; p < plain.constraints_of.size(); ++p) {
    const auto list = graph.constraints_of(static_cast<ParticleIndex>(p));
    ASSERT_EQ(std::vector<ConstraintIndex>(list.begin(), list.end()), plain.constraints_of[p])
        << "particle " << p;
  }
  EXPECT_EQ(graph.colour_lower_bound(), plain.lower_bound);
}

/// Random input over `particles` particles, a quarter static: edges, triangles by slot,
/// tetrahedra interleaved, 6-particle stencils, and clusters of 1 to 40 particles (the large
/// ones take the sorted duplicate check). Over 16 K constraints per family, so several chunks.
struct RandomInput {
  std::vector<Real> w;
  std::vector<ParticleIndex> edges, tetrahedra, hexads, cluster_offsets{0}, clusters;
  std::array<std::vector<ParticleIndex>, 3> triangle_slots;
  std::array<std::span<const ParticleIndex>, 3> triangle_spans;
  std::vector<ConstraintGroup> groups;

  RandomInput(std::size_t particles, std::size_t per_family, std::uint64_t seed) {
    std::mt19937_64 random(seed);
    w.resize(particles);
    for (Real& x : w) x = random() % 4 == 0 ? Real(0) : Real(1);
    // k distinct particles, near one another (a mesh's constraints are local).
    const auto distinct = [&](std::size_t k) {
      std::vector<ParticleIndex> picked;
      const std::size_t base = random() % particles;
      while (picked.size() < k) {
        const auto p = static_cast<ParticleIndex>((base + random() % 64) % particles);
        if (std::find(picked.begin(), picked.end(), p) == picked.end()) picked.push_back(p);
      }
      return picked;
    };
    for (std::size_t i = 0; i < per_family; ++i) {
      for (ParticleIndex p : distinct(2)) edges.push_back(p);
      const auto t = distinct(3);
      for (std::size_t k = 0; k < 3; ++k) triangle_slots[k].push_back(t[k]);
      for (ParticleIndex p : distinct(4)) tetrahedra.push_back(p);
      for (ParticleIndex p : distinct(6)) hexads.push_back(p);
    }
    for (std::size_t i = 0; i < per_family / 8; ++i) {
      for (ParticleIndex p : distinct(1 + random() % 40)) clusters.push_back(p);
      cluster_offsets.push_back(static_cast<ParticleIndex>(clusters.size()));
    }
    for (std::size_t k = 0; k < 3; ++k) triangle_spans[k] = triangle_slots[k];
    groups = {ConstraintGroup::fixed_arity("edge", 2, edges),
              ConstraintGroup::by_slot("triangle", triangle_spans),
              ConstraintGroup::fixed_arity("tetra", 4, tetrahedra),
              ConstraintGroup::fixed_arity("hexad", 6, hexads),
              ConstraintGroup::variable_size("cluster", cluster_offsets, clusters)};
  }
};

ConstraintGraph build_on(int threads, const RandomInput& input) {
  tbb::task_arena arena(threads);
  ConstraintGraph graph;
  arena.execute([&] { graph = ConstraintGraph(input.w, input.groups); });
  return graph;
}

TEST(ConstraintGraph, ParallelBuildEqualsThePlainGraphForAnyThreadCount) {
  for (std::uint64_t seed : {1u, 2u}) {
    const RandomInput input(5000, 20000, seed);
    const PlainGraph plain = plain_graph(input.w, input.groups);
    const ConstraintGraph one = build_on(1, input);
    const ConstraintGraph two = build_on(2, input);
    expect_equal(one, plain);
    expect_equal(two, plain);
    EXPECT_EQ(as_vector(one.constraint_particles()), as_vector(two.constraint_particles()));
    EXPECT_EQ(std::vector<std::uint32_t>(one.constraint_offsets().begin(), one.constraint_offsets().end()),
              std::vector<std::uint32_t>(two.constraint_offsets().begin(), two.constraint_offsets().end()));
    EXPECT_EQ(one.movable_particle_count(),
              std::size_t(std::count_if(input.w.begin(), input.w.end(), [](Real x) { return x > 0; })));
  }
}

TEST(ConstraintGraph, ParticleListsBuiltOnceUnderConcurrentFirstUseAndSharedByCopies) {
  const RandomInput input(3000, 17000, 3);
  const PlainGraph plain = plain_graph(input.w, input.groups);
  const ConstraintGraph graph(input.w, input.groups);
  const ConstraintGraph copied_before_use = graph;
  // Many tasks ask for the lists at once: every one must see the complete lists.
  std::vector<std::size_t> degree_sum(64, 0);
  tbb::task_arena(2).execute([&] {
    tbb::parallel_for(std::size_t(0), degree_sum.size(), [&](std::size_t t) {
      for (std::size_t p = t; p < graph.particle_count(); p += degree_sum.size())
        degree_sum[t] += graph.constraints_of(static_cast<ParticleIndex>(p)).size();
    });
  });
  std::size_t total = 0;
  for (std::size_t s : degree_sum) total += s;
  EXPECT_EQ(total, graph.incidence_count());
  const ConstraintGraph copied_after_use = graph;
  EXPECT_EQ(copied_after_use.particle_constraints().data(), graph.particle_constraints().data());
  expect_equal(copied_before_use, plain);
  expect_equal(copied_after_use, plain);
  ConstraintGraph source = graph;
  const ConstraintGraph moved = std::move(source);
  expect_equal(moved, plain);
}

TEST(ConstraintGroup, BySlotEqualsInterleaved) {
  const std::vector<ParticleIndex> interleaved = {0, 1, 2, 2, 3, 4, 4, 0, 5};
  const std::vector<ParticleIndex> a = {0, 2, 4}, b = {1, 3, 0}, c = {2, 4, 5};
  const std::span<const ParticleIndex> slots[] = {a, b, c};
  const ConstraintGroup by_slot = ConstraintGroup::by_slot("triangle", slots);
  EXPECT_TRUE(by_slot.is_by_slot());
  EXPECT_TRUE(by_slot.has_fixed_arity());
  EXPECT_EQ(by_slot.arity(), 3u);
  EXPECT_EQ(by_slot.constraint_count(), 3u);
  EXPECT_EQ(by_slot.incidence_count(), 9u);
  EXPECT_EQ(by_slot.particle(1, 2), 4u);
  EXPECT_THROW(by_slot.constraint(0), InvalidInput);
  const std::vector<Real> w = {1, 1, 0, 1, 1, 1};
  const std::vector<ConstraintGroup> g1 = {ConstraintGroup::fixed_arity("triangle", 3, interleaved)};
  const std::vector<ConstraintGroup> g2 = {by_slot};
  const ConstraintGraph one(w, g1), two(w, g2);
  expect_equal(two, plain_graph(w, g1));
  EXPECT_EQ(as_vector(one.constraint_particles()), as_vector(two.constraint_particles()));

  const std::vector<ParticleIndex> shorter = {0, 1};
  const std::span<const ParticleIndex> uneven[] = {a, shorter};
  expect_invalid([&] { ConstraintGroup::by_slot("edge", uneven); }, {"slot 1 holds 2 indices"});
  expect_invalid([&] { ConstraintGroup::by_slot("edge", {}); }, {"at least one slot"});
  // Validation names the constraint as for interleaved groups.
  const std::vector<ParticleIndex> twice = {0, 1, 7}, other = {2, 1, 8};
  const std::span<const ParticleIndex> bad[] = {twice, other};
  expect_invalid([&] {
    const std::vector<ConstraintGroup> g = {ConstraintGroup::by_slot("edge", bad)};
    ConstraintGraph(std::vector<Real>(8, Real(1)), g);
  }, {"constraint group 'edge', constraint 1", "particle 1 appears twice"});
}

TEST(ConstraintGraph, FirstErrorInOrderAcrossChunks) {
  // Errors in two chunks, the later one found first by whichever thread: the message names
  // the earlier constraint.
  RandomInput input(4000, 40000, 4);
  input.tetrahedra[4 * 35000 + 1] = 4000;  // tetra 35000 (chunk 2): out of range
  input.tetrahedra[4 * 10000 + 3] = input.tetrahedra[4 * 10000];  // tetra 10000 (chunk 0): twice
  input.groups[2] = ConstraintGroup::fixed_arity("tetra", 4, input.tetrahedra);
  for (int threads : {1, 2})
    expect_invalid([&] { build_on(threads, input); },
                   {"constraint group 'tetra', constraint 10000", "appears twice"});
}

TEST(ConstraintGraph, ModelGraphEqualsInterleavedGroups) {
  // Distance constraints (stored by slot in the batch) and clusters, with a pinned particle.
  const io::ClothGrid cloth = io::make_cloth_grid(40, 30);
  std::vector<Real> w(cloth.vertex_count(), Real(1));
  w[5] = 0;
  Model model;
  model.particles = ParticleState(cloth.positions, w);
  model.constraints.distance = make_distance_constraints({cloth.edge_indices, cloth.positions});
  const ConstraintGraph from_model = constraint_graph(model);
  const std::vector<ConstraintGroup> groups = {ConstraintGroup::fixed_arity("distance", 2, cloth.edge_indices)};
  expect_equal(from_model, plain_graph(w, groups));
  EXPECT_EQ(from_model.group_name(0), "distance");
}

}  // namespace constraint_graph_tests
}  // namespace tessera
