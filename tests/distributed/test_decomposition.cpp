// The domain decomposition (decomposition.hpp): its ownership invariants, and its exchange
// plan carried out in one process with one copy of the particles per rank. Each copy holds
// only its rank's particles (the rest are NaN, so reading a particle a rank does not hold
// would show), each rank projects only its constraints, colour by colour, and after each
// colour the planned positions are copied from the sender's copy to the receiver's. The
// owners' copies must then be bitwise the positions of one process sweeping the same
// colouring: the exactness the MPI transport will rely on.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <tessera/coloring/model_graph.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/sequential_projection.hpp>
#include <tessera/distributed/decomposition.hpp>

#include "scenes.hpp"
#include "batch_test_support.hpp"

namespace tessera {
namespace {

struct Located {
  ConstraintFamily family;
  std::size_t index;
};

std::vector<Located> locate(const Model& model) {
  std::vector<Located> located(model.constraints.size());
  model.constraints.for_each([&](ConstraintFamily family, const auto& batch) {
    for (std::size_t i = 0; i < batch.size(); ++i)
      located[model.constraint_id(family, i)] = {family, i};
  });
  return located;
}

/// Every particle of constraint `at`, static ones included.
std::vector<ParticleIndex> members_of(const Model& model, Located at) {
  std::vector<ParticleIndex> members;
  model.constraints.for_each([&](ConstraintFamily family, const auto& batch) {
    if (family != at.family) return;
    if constexpr (requires { batch.particles; })
      for (const auto& slot : batch.particles.particle) members.push_back(slot[at.index]);
  });
  return members;
}

/// One constraint by the scalar API (the sequential reference's projection).
void project_one(ParticleState& state, ConstraintSets& sets, Located at,
                 const ProjectionSettings& settings) {
  sets.for_each([&](ConstraintFamily family, auto& batch) {
    if (family == at.family)
      project_sequentially(ParticleArrays::of(state), batch, at.index, at.index + 1, settings);
  });
}

/// A model whose constraints are violated: positions jittered by up to `amount`.
Model jittered(Model model, Real amount, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> jitter(-1, 1);
  for (std::size_t p = 0; p < model.particles.size(); ++p) {
    if (!(model.particles.inverse_mass[p] > 0)) continue;
    model.particles.x[p] += amount * Real(jitter(random));
    model.particles.y[p] += amount * Real(jitter(random));
    model.particles.z[p] += amount * Real(jitter(random));
  }
  return model;
}

/// `sweeps` sweeps of the colouring in one process.
ParticleState sweep_in_one_process(const Model& model, const Colouring& colouring,
                                   const std::vector<Located>& located, std::size_t sweeps,
                                   const ProjectionSettings& settings) {
  ParticleState state = model.particles;
  ConstraintSets sets = model.constraints;
  for (std::size_t s = 0; s < sweeps; ++s)
    for (Colour k = 0; k < colouring.colour_count(); ++k)
      for (const ConstraintIndex c : colouring.constraints_of(k))
        project_one(state, sets, located[c], settings);
  return state;
}

/// The same sweeps by the ranks of `d`, each on its own copy, exchanging as planned.
std::vector<ParticleState> sweep_by_ranks(const Model& model, const Colouring& colouring,
                                          const Decomposition& d,
                                          const std::vector<Located>& located,
                                          std::size_t sweeps, const ProjectionSettings& settings) {
  constexpr Real kNotHeld = std::numeric_limits<Real>::quiet_NaN();
  std::vector<ParticleState> copies(d.rank_count, model.particles);
  std::vector<ConstraintSets> sets(d.rank_count, model.constraints);
  for (Rank r = 0; r < d.rank_count; ++r) {
    std::vector<bool> held(model.particles.size(), false);
    for (const ParticleIndex p : d.ranks[r].owned) held[p] = true;
    for (const ParticleIndex p : d.ranks[r].ghosts) held[p] = true;
    for (std::size_t p = 0; p < held.size(); ++p)
      if (!held[p]) copies[r].x[p] = copies[r].y[p] = copies[r].z[p] = kNotHeld;
  }
  std::vector<std::vector<bool>> mine(d.rank_count,
                                      std::vector<bool>(model.constraints.size(), false));
  for (Rank r = 0; r < d.rank_count; ++r)
    for (const ConstraintIndex c : d.ranks[r].constraints) mine[r][c] = true;
  for (std::size_t s = 0; s < sweeps; ++s)
    for (Colour k = 0; k < colouring.colour_count(); ++k) {
      for (Rank r = 0; r < d.rank_count; ++r)
        for (const ConstraintIndex c : colouring.constraints_of(k))
          if (mine[r][c]) project_one(copies[r], sets[r], located[c], settings);
      for (Rank r = 0; r < d.rank_count; ++r)
        for (const RankExchange& send : d.ranks[r].sends[k])
          for (const ParticleIndex p : send.particles) {
            copies[send.rank].x[p] = copies[r].x[p];
            copies[send.rank].y[p] = copies[r].y[p];
            copies[send.rank].z[p] = copies[r].z[p];
          }
    }
  return copies;
}

bool same_bits(Real a, Real b) { return std::memcmp(&a, &b, sizeof(Real)) == 0; }

void expect_exact(const Model& model, const char* strategy, std::size_t ranks) {
  SCOPED_TRACE(std::to_string(ranks) + " ranks, " + strategy);
  const Colouring colouring = test::colour_model(model, strategy);
  const ConstraintGraph graph = constraint_graph(model);
  const Decomposition d = decompose(model, colouring, ranks);
  const std::vector<Located> located = locate(model);
  const ProjectionSettings settings{ConstraintSemantics::compliance, Real(1) / Real(600)};
  constexpr std::size_t kSweeps = 3;
  const ParticleState one = sweep_in_one_process(model, colouring, located, kSweeps, settings);
  const std::vector<ParticleState> copies =
      sweep_by_ranks(model, colouring, d, located, kSweeps, settings);
  std::size_t moved = 0, differ = 0;
  for (std::size_t p = 0; p < model.particles.size(); ++p) {
    const ParticleState& owner = copies[d.owner_of_particle[p]];
    moved += !same_bits(one.x[p], model.particles.x[p]);
    differ += !same_bits(owner.x[p], one.x[p]) || !same_bits(owner.y[p], one.y[p]) ||
              !same_bits(owner.z[p], one.z[p]);
  }
  EXPECT_GT(moved, model.particles.size() / 2) << "the sweeps do something";
  EXPECT_EQ(differ, 0u) << "particles whose owner's copy is not one process's answer";
  // Every holder's copy of a particle is the answer too (ghosts are current).
  for (Rank r = 0; r < ranks; ++r)
    for (const ParticleIndex p : d.ranks[r].ghosts)
      if (graph.is_movable(p)) {
        ASSERT_TRUE(same_bits(copies[r].x[p], one.x[p])) << "rank " << r << ", ghost " << p;
      }
}

TEST(Decomposition, RanksFollowingThePlanComputeBitwiseWhatOneProcessDoes) {
  const Model cloth = jittered(test::cloth_model(24, 20), Real(0.01), 7);
  for (const std::size_t ranks : {1, 2, 3, 5}) expect_exact(cloth, "greedy", ranks);
  expect_exact(cloth, "stencil", 4);
  const Model bar = jittered(test::tet_bar_model(3, 3, 8), Real(0.005), 11);
  for (const std::size_t ranks : {2, 3}) expect_exact(bar, "greedy", ranks);
}

TEST(Decomposition, WithoutTheExchangesTheRanksDisagree) {
  // The same emulation with the sends dropped: the ranks' answers go stale, so the test above
  // checks the plan, not only that each rank projects its own constraints.
  const Model cloth = jittered(test::cloth_model(16, 16), Real(0.01), 3);
  const Colouring colouring = test::colour_model(cloth, "greedy");
  const ConstraintGraph graph = constraint_graph(cloth);
  Decomposition d = decompose(cloth, colouring, 3);
  const std::vector<Located> located = locate(cloth);
  const ProjectionSettings settings{ConstraintSemantics::compliance, Real(1) / Real(600)};
  const ParticleState one = sweep_in_one_process(cloth, colouring, located, 2, settings);
  for (RankDomain& rank : d.ranks)
    for (auto& sends : rank.sends) sends.clear();
  const auto copies = sweep_by_ranks(cloth, colouring, d, located, 2, settings);
  std::size_t differ = 0;
  for (std::size_t p = 0; p < cloth.particles.size(); ++p)
    differ += !same_bits(copies[d.owner_of_particle[p]].x[p], one.x[p]);
  EXPECT_GT(differ, 0u);
}

TEST(Decomposition, EveryParticleAndConstraintHasOneOwnerAndGhostsAreWhatOwnedConstraintsRead) {
  const Model cloth = test::cloth_model(30, 30);
  const ConstraintGraph graph = constraint_graph(cloth);
  const Colouring colouring = test::colour_model(cloth, "greedy");
  const std::vector<Located> located = locate(cloth);
  for (const std::size_t ranks : {1, 2, 4, 7}) {
    SCOPED_TRACE(std::to_string(ranks) + " ranks");
    const Decomposition d = decompose(cloth, colouring, ranks);
    ASSERT_EQ(d.ranks.size(), ranks);
    std::vector<int> owned_times(graph.particle_count(), 0);
    std::size_t constraints = 0, movable_min = graph.particle_count(), movable_max = 0;
    for (Rank r = 0; r < ranks; ++r) {
      const RankDomain& rank = d.ranks[r];
      EXPECT_TRUE(std::is_sorted(rank.owned.begin(), rank.owned.end()));
      EXPECT_TRUE(std::is_sorted(rank.ghosts.begin(), rank.ghosts.end()));
      EXPECT_TRUE(std::is_sorted(rank.constraints.begin(), rank.constraints.end()));
      std::size_t movable = 0;
      for (const ParticleIndex p : rank.owned) {
        ++owned_times[p];
        EXPECT_EQ(d.owner_of_particle[p], r);
        movable += graph.is_movable(p);
      }
      movable_min = std::min(movable_min, movable);
      movable_max = std::max(movable_max, movable);
      // Ghosts: exactly the particles its constraints touch that it does not own, the static
      // pins included.
      std::vector<ParticleIndex> read;
      for (const ConstraintIndex c : rank.constraints) {
        EXPECT_EQ(d.owner_of_constraint[c], r);
        ++constraints;
        for (const ParticleIndex p : members_of(cloth, located[c]))
          if (d.owner_of_particle[p] != r) read.push_back(p);
        // Owned by the owner of its smallest movable particle.
        ParticleIndex smallest = ~ParticleIndex(0);
        for (const ParticleIndex p : graph.particles_of(c))
          if (graph.is_movable(p)) smallest = std::min(smallest, p);
        EXPECT_EQ(d.owner_of_particle[smallest], r) << "constraint " << c;
      }
      std::sort(read.begin(), read.end());
      read.erase(std::unique(read.begin(), read.end()), read.end());
      EXPECT_EQ(rank.ghosts, read);
      if (ranks == 1) {
        EXPECT_TRUE(rank.ghosts.empty() && rank.neighbours.empty());
      }
      // Receives mirror sends.
      for (Colour k = 0; k < colouring.colour_count(); ++k)
        for (const RankExchange& send : rank.sends[k]) {
          EXPECT_NE(send.rank, r);
          const auto& theirs = d.ranks[send.rank].receives[k];
          const auto match = std::find_if(theirs.begin(), theirs.end(),
                                          [&](const RankExchange& e) { return e.rank == r; });
          ASSERT_NE(match, theirs.end());
          EXPECT_EQ(match->particles, send.particles);
          EXPECT_TRUE(std::binary_search(rank.neighbours.begin(), rank.neighbours.end(),
                                         send.rank));
          for (const ParticleIndex p : send.particles) EXPECT_TRUE(graph.is_movable(p));
        }
    }
    for (std::size_t p = 0; p < graph.particle_count(); ++p)
      EXPECT_EQ(owned_times[p], 1) << "particle " << p;
    EXPECT_EQ(constraints, graph.constraint_count());
    // METIS balances the movable particles (within its default 3 % and rounding).
    EXPECT_LE(double(movable_max), 1.1 * double(movable_min) + 2);
    // The same plan every time (every rank computes it for itself).
    const Decomposition again = decompose(cloth, colouring, ranks);
    EXPECT_EQ(again.owner_of_particle, d.owner_of_particle);
    EXPECT_EQ(again.owner_of_constraint, d.owner_of_constraint);
  }
}

TEST(Decomposition, BadInputIsNamed) {
  const Model cloth = test::cloth_model(4, 4);
  const ConstraintGraph graph = constraint_graph(cloth);
  const Colouring colouring = test::colour_model(cloth, "greedy");
  EXPECT_EQ(test::error_of([&] { decompose(cloth, colouring, 0); }),
            "decompose: the rank count must be at least 1");
  const Colouring other = test::colour_model(test::cloth_model(5, 4), "greedy");
  EXPECT_EQ(test::error_of([&] { decompose(cloth, other, 2); }),
            "decompose: the colouring has " + std::to_string(other.constraint_count()) +
                " constraints, the graph " + std::to_string(graph.constraint_count()));
  // One colour for everything: constraints 0 and 1 share a movable particle.
  const Colouring one_colour =
      Colouring::from_colours(std::vector<Colour>(graph.constraint_count(), 0));
  const std::string error = test::error_of([&] { decompose(cloth, one_colour, 2); });
  EXPECT_EQ(error.rfind("decompose: colour 0 holds constraints ", 0), 0u) << error;
  EXPECT_NE(error.find(", which share movable particle "), std::string::npos) << error;
}

}  // namespace
}  // namespace tessera
