// Locality post-pass: reverse Cuthill–McKee particle order and per-colour constraint order.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

#include <tessera/coloring/colouring_statistics.hpp>
#include <tessera/coloring/run_colouring.hpp>
#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/locality.hpp>

#include "test_meshes.hpp"

namespace tessera {
namespace locality_tests {

bool is_permutation_of_particles(std::span<const ParticleIndex> order, std::size_t n) {
  std::vector<ParticleIndex> sorted(order.begin(), order.end());
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < sorted.size(); ++i)
    if (sorted[i] != i) return false;
  return sorted.size() == n;
}

/// The cloth with distance + bending constraints and its particles relabelled at random, so
/// the user's numbering has no locality at all.
ConstraintGraph scrambled_cloth(std::size_t side, std::vector<ParticleIndex>& edges,
                                std::vector<ParticleIndex>& bending) {
  const io::ClothGrid cloth = io::make_cloth_grid(side, side);
  std::vector<ParticleIndex> label(cloth.vertex_count());
  std::iota(label.begin(), label.end(), ParticleIndex(0));
  std::shuffle(label.begin(), label.end(), std::mt19937(11));
  edges = cloth.edge_indices;
  bending = cloth.bending_indices;
  for (ParticleIndex& p : edges) p = label[p];
  for (ParticleIndex& p : bending) p = label[p];
  const std::vector<Real> w(cloth.vertex_count(), Real(1));
  const std::vector<ConstraintGroup> groups = {ConstraintGroup::fixed_arity("distance", 2, edges),
                                               ConstraintGroup::fixed_arity("bending", 4, bending)};
  return ConstraintGraph(w, groups);
}

TEST(ReverseCuthillMcKee, IsAPermutationWithStaticParticlesLast) {
  const ConstraintGraph graph = test::cloth_graph(12, 12, true, true);
  const std::vector<ParticleIndex> order = reverse_cuthill_mckee_order(graph);
  ASSERT_TRUE(is_permutation_of_particles(order, graph.particle_count()));
  for (std::size_t n = 0; n < order.size(); ++n)
    EXPECT_EQ(graph.is_movable(order[n]), n < graph.movable_particle_count()) << n;
  EXPECT_TRUE(is_permutation_of_particles(reverse_cuthill_mckee_order(test::empty_graph()), 3));
}

TEST(ReverseCuthillMcKee, KeepsNeighboursCloseOnAScrambledCloth) {
  std::vector<ParticleIndex> edges, bending;
  const ConstraintGraph graph = scrambled_cloth(40, edges, bending);
  const std::vector<ParticleIndex> order = reverse_cuthill_mckee_order(graph);
  std::vector<ParticleIndex> old_to_new(order.size());
  for (std::size_t n = 0; n < order.size(); ++n) old_to_new[order[n]] = static_cast<ParticleIndex>(n);
  // Bandwidth: the largest id gap across a constraint. A 40-wide grid has an optimum near 41;
  // the scrambled numbering has gaps in the hundreds.
  std::size_t before = 0, after = 0;
  for (ConstraintIndex c = 0; c < graph.constraint_count(); ++c) {
    const auto particles = graph.particles_of(c);
    const auto [lo, hi] = std::minmax_element(particles.begin(), particles.end());
    before = std::max<std::size_t>(before, *hi - *lo);
    ParticleIndex nlo = old_to_new[particles[0]], nhi = nlo;
    for (ParticleIndex p : particles) {
      nlo = std::min(nlo, old_to_new[p]);
      nhi = std::max(nhi, old_to_new[p]);
    }
    after = std::max<std::size_t>(after, nhi - nlo);
  }
  EXPECT_GT(before, 1000u);
  EXPECT_LT(after, 3 * 40u);
}

/// Reverse Cuthill–McKee as locality.hpp states it, written the plain way (whole-graph
/// neighbour sets, a comparison sort of the starts): the order the library's must equal.
std::vector<ParticleIndex> textbook_rcm(const ConstraintGraph& graph) {
  const std::size_t n = graph.particle_count();
  const auto by_degree_then_index = [&](ParticleIndex a, ParticleIndex b) {
    return std::pair(graph.particle_degree(a), a) < std::pair(graph.particle_degree(b), b);
  };
  std::vector<ParticleIndex> starts;
  for (ParticleIndex p = 0; p < n; ++p)
    if (graph.is_movable(p) && graph.particle_degree(p) > 0) starts.push_back(p);
  std::sort(starts.begin(), starts.end(), by_degree_then_index);
  std::vector<bool> placed(n, false);
  std::vector<ParticleIndex> order;
  for (ParticleIndex start : starts) {
    if (placed[start]) continue;
    placed[start] = true;
    const std::size_t first = order.size();
    order.push_back(start);
    for (std::size_t head = first; head < order.size(); ++head) {
      std::vector<ParticleIndex> next;
      for (ConstraintIndex c : graph.constraints_of(order[head]))
        for (ParticleIndex q : graph.particles_of(c))
          if (!placed[q] && std::find(next.begin(), next.end(), q) == next.end()) next.push_back(q);
      std::sort(next.begin(), next.end(), by_degree_then_index);
      for (ParticleIndex q : next) placed[q] = true;
      order.insert(order.end(), next.begin(), next.end());
    }
  }
  std::reverse(order.begin(), order.end());
  for (ParticleIndex p = 0; p < n; ++p)
    if (!placed[p]) order.push_back(p);
  return order;
}

TEST(ReverseCuthillMcKee, IsTheTextbookOrder) {
  // A scrambled cloth (one component, many equal degrees: the index breaks the ties), a
  // pinned cloth (static particles), and three components of different sizes beside a
  // particle no constraint touches: the walk's prefetches and its counting sort of the starts
  // must not change a place.
  std::vector<ParticleIndex> edges, bending;
  const ConstraintGraph scrambled = scrambled_cloth(40, edges, bending);
  EXPECT_EQ(reverse_cuthill_mckee_order(scrambled), textbook_rcm(scrambled));
  const ConstraintGraph pinned = test::cloth_graph(30, 20, true, true);
  EXPECT_EQ(reverse_cuthill_mckee_order(pinned), textbook_rcm(pinned));

  const io::ClothGrid small = io::make_cloth_grid(7, 5), large = io::make_cloth_grid(12, 9);
  std::vector<ParticleIndex> pieces;
  const auto add = [&](const std::vector<ParticleIndex>& indices, ParticleIndex offset) {
    for (ParticleIndex p : indices) pieces.push_back(p + offset);
  };
  add(large.edge_indices, 0);  // particles 0 .. 107
  add(small.edge_indices, 200);  // 200 .. 234; 108 .. 199 and 235 are touched by nothing
  add(small.edge_indices, 236);  // 236 .. 270
  std::vector<Real> inverse_masses(271, Real(1));
  inverse_masses[3] = 0;
  const std::vector<ConstraintGroup> groups = {ConstraintGroup::fixed_arity("distance", 2, pieces)};
  const ConstraintGraph split(inverse_masses, groups);
  const std::vector<ParticleIndex> order = reverse_cuthill_mckee_order(split);
  EXPECT_EQ(order, textbook_rcm(split));
  EXPECT_TRUE(is_permutation_of_particles(order, 271));
}

TEST(ImproveLocality, KeepsColoursAndSortsEachColourBySmallestNewParticle) {
  std::vector<ParticleIndex> edges, bending;
  const ConstraintGraph graph = scrambled_cloth(40, edges, bending);
  const ColouringRegistry registry = ColouringRegistry::with_builtin_strategies();
  const Colouring plain = registry.get("greedy").colour(graph, {});
  const Colouring local = improve_locality(graph, plain);
  ASSERT_TRUE(validate(graph, local).valid) << validate(graph, local).problem;
  EXPECT_TRUE(std::equal(plain.colours().begin(), plain.colours().end(), local.colours().begin(),
                         local.colours().end()));
  ASSERT_TRUE(local.renumbers_particles());
  for (std::size_t n = 0; n < graph.particle_count(); ++n)
    EXPECT_EQ(local.particle_old_to_new()[local.particle_new_to_old()[n]], n);
  for (Colour k = 0; k < local.colour_count(); ++k) {
    std::uint32_t previous = 0;
    for (ConstraintIndex c : local.constraints_of(k)) {
      std::uint32_t key = ~std::uint32_t(0);
      for (ParticleIndex p : graph.particles_of(c)) key = std::min(key, local.particle_old_to_new()[p]);
      EXPECT_GE(key, previous);
      previous = key;
    }
  }
  // Windows of 16 consecutive constraints of a colour gather from a narrow id range now.
  const double spread_before = mean_gather_spread(graph, plain);
  const double spread_after = mean_gather_spread(graph, local);
  EXPECT_GT(spread_before, 1000.0);
  EXPECT_LT(spread_after, spread_before / 10);
}

TEST(ImproveLocality, KeepsTheRenumberingAStrategyChose) {
  const ConstraintGraph graph = test::cloth_graph(40, 40, false, true);
  ColouringOptions options;
  options.particles_per_part = 200;
  const Colouring metis = ColouringRegistry::with_builtin_strategies().get("metis").colour(graph, options);
  const Colouring local = improve_locality(graph, metis);
  ASSERT_TRUE(validate(graph, local).valid);
  EXPECT_TRUE(std::equal(metis.particle_new_to_old().begin(), metis.particle_new_to_old().end(),
                         local.particle_new_to_old().begin(), local.particle_new_to_old().end()));
  EXPECT_TRUE(std::equal(metis.constraints_by_colour().begin(), metis.constraints_by_colour().end(),
                         local.constraints_by_colour().begin(), local.constraints_by_colour().end()));
}

TEST(ImproveLocality, RunsAsTheLastPostPass) {
  ColouringOptions options;
  options.balance = true;
  options.locality = true;
  const ConstraintGraph graph = test::tet_bar_graph(6, 3, 3);
  const ColouringRun run =
      run_colouring(ColouringRegistry::with_builtin_strategies().get("dsatur"), graph, options);
  EXPECT_EQ(run.statistics.strategy, "dsatur+balance+locality");
  EXPECT_TRUE(run.statistics.valid) << run.statistics.problem;
  EXPECT_TRUE(run.colouring.renumbers_particles());
  for (const test::TestMesh& mesh : test::all_test_meshes()) {
    const Colouring local = improve_locality(
        mesh.graph, ColouringRegistry::with_builtin_strategies().get("greedy").colour(mesh.graph, {}));
    EXPECT_TRUE(validate(mesh.graph, local).valid) << mesh.name;
  }
}

}  // namespace locality_tests
}  // namespace tessera
