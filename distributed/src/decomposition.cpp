// Domain decomposition (decomposition.hpp): owners from the METIS partition, holders from the
// owned constraints, and per colour the writes each rank must pass on.
#include <tessera/distributed/decomposition.hpp>

#include <algorithm>
#include <limits>
#include <map>
#include <span>
#include <string>
#include <utility>

#include <tessera/coloring/model_graph.hpp>
#include <tessera/coloring/particle_partition.hpp>
#include <tessera/core/error.hpp>

namespace tessera {
namespace {

constexpr Rank kNoRank = std::numeric_limits<Rank>::max();

/// Every particle of every constraint, static ones included (the graph keeps only the
/// movable ones, but a rank must hold the static particles its constraints read), as CSR
/// over global constraint ids.
struct ConstraintMembers {
  std::vector<std::size_t> offsets{0};
  std::vector<ParticleIndex> particles;
  std::span<const ParticleIndex> of(std::size_t c) const {
    return {particles.data() + offsets[c], particles.data() + offsets[c + 1]};
  }
};

ConstraintMembers constraint_members(const Model& model) {
  ConstraintMembers members;
  members.offsets.reserve(model.constraints.size() + 1);
  model.constraints.for_each([&](ConstraintFamily, const auto& batch) {
    for (std::size_t i = 0; i < batch.size(); ++i) {
      if constexpr (!requires { batch.particles; }) {
        for (std::size_t e = batch.offsets[i]; e < batch.offsets[i + 1]; ++e)
          members.particles.push_back(batch.particle[e]);
      } else {
        for (const auto& slot : batch.particles.particle) members.particles.push_back(slot[i]);
      }
      members.offsets.push_back(members.particles.size());
    }
  });
  return members;
}

void check_input(const ConstraintGraph& graph, const Colouring& colouring, std::size_t ranks) {
  const std::string context = "decompose: ";
  if (ranks == 0) throw InvalidInput(context + "the rank count must be at least 1");
  if (ranks > std::size_t(kNoRank))
    throw InvalidInput(context + std::to_string(ranks) + " ranks is more than 2^32 - 1");
  if (colouring.constraint_count() != graph.constraint_count())
    throw InvalidInput(context + "the colouring has " +
                       std::to_string(colouring.constraint_count()) +
                       " constraints, the graph " + std::to_string(graph.constraint_count()));
  // Within a colour, no movable particle twice: the writer of each particle is unique.
  std::vector<ConstraintIndex> writer(graph.particle_count(),
                                      std::numeric_limits<ConstraintIndex>::max());
  std::vector<Colour> seen_in(graph.particle_count(), std::numeric_limits<Colour>::max());
  for (Colour k = 0; k < colouring.colour_count(); ++k)
    for (const ConstraintIndex c : colouring.constraints_of(k))
      for (const ParticleIndex p : graph.particles_of(c)) {
        if (!graph.is_movable(p)) continue;
        if (seen_in[p] == k && writer[p] != c)
          throw InvalidInput(context + "colour " + std::to_string(k) + " holds constraints " +
                             std::to_string(writer[p]) + " and " + std::to_string(c) +
                             ", which share movable particle " + std::to_string(p));
        seen_in[p] = k;
        writer[p] = c;
      }
}

}  // namespace

Decomposition decompose(const Model& model, const Colouring& colouring, std::size_t rank_count,
                        std::uint64_t seed) {
  const ConstraintGraph graph = constraint_graph(model);
  check_input(graph, colouring, rank_count);
  const ConstraintMembers members = constraint_members(model);
  const std::size_t particles = graph.particle_count();
  const std::size_t constraints = graph.constraint_count();
  Decomposition d;
  d.rank_count = rank_count;
  d.ranks.resize(rank_count);

  // Owners: movable particles by the partition, constraints by their smallest movable
  // particle, static particles by the first constraint that reads them.
  const ParticlePartition partition = partition_particles(graph, rank_count, seed);
  d.owner_of_particle.assign(particles, kNoRank);
  for (std::size_t p = 0; p < particles; ++p)
    if (graph.is_movable(ParticleIndex(p)))
      d.owner_of_particle[p] = partition.part_of_particle[p] == ParticlePartition::kNoPart
                                   ? 0
                                   : Rank(partition.part_of_particle[p]);
  d.owner_of_constraint.resize(constraints);
  for (std::size_t c = 0; c < constraints; ++c) {
    const auto of_c = members.of(c);
    ParticleIndex smallest_movable = std::numeric_limits<ParticleIndex>::max();
    ParticleIndex smallest = std::numeric_limits<ParticleIndex>::max();
    for (const ParticleIndex p : of_c) {
      smallest = std::min(smallest, p);
      if (graph.is_movable(p)) smallest_movable = std::min(smallest_movable, p);
    }
    const ParticleIndex by = smallest_movable != std::numeric_limits<ParticleIndex>::max()
                                 ? smallest_movable
                                 : smallest;
    Rank owner = of_c.empty() ? 0 : d.owner_of_particle[by];
    if (owner == kNoRank) owner = 0;  // only static particles, none owned yet: rank 0
    d.owner_of_constraint[c] = owner;
    for (const ParticleIndex p : of_c)
      if (d.owner_of_particle[p] == kNoRank) d.owner_of_particle[p] = owner;
  }
  for (Rank& owner : d.owner_of_particle)
    if (owner == kNoRank) owner = 0;  // a particle no constraint reads

  // Holdings: owned particles, owned constraints, ghosts.
  for (std::size_t p = 0; p < particles; ++p)
    d.ranks[d.owner_of_particle[p]].owned.push_back(ParticleIndex(p));
  for (std::size_t c = 0; c < constraints; ++c) {
    RankDomain& rank = d.ranks[d.owner_of_constraint[c]];
    rank.constraints.push_back(ConstraintIndex(c));
    for (const ParticleIndex p : members.of(c))
      if (d.owner_of_particle[p] != d.owner_of_constraint[c]) rank.ghosts.push_back(p);
  }
  // Which ranks hold each particle besides its owner (CSR over particles, ascending ranks).
  std::vector<std::uint32_t> ghost_offsets(particles + 1, 0);
  for (RankDomain& rank : d.ranks) {
    std::sort(rank.ghosts.begin(), rank.ghosts.end());
    rank.ghosts.erase(std::unique(rank.ghosts.begin(), rank.ghosts.end()), rank.ghosts.end());
    for (const ParticleIndex p : rank.ghosts) ++ghost_offsets[p + 1];
  }
  for (std::size_t p = 0; p < particles; ++p) ghost_offsets[p + 1] += ghost_offsets[p];
  std::vector<Rank> ghost_holders(ghost_offsets.back());
  {
    std::vector<std::uint32_t> next(ghost_offsets.begin(), ghost_offsets.end() - 1);
    for (Rank r = 0; r < rank_count; ++r)
      for (const ParticleIndex p : d.ranks[r].ghosts) ghost_holders[next[p]++] = r;
  }

  // Per colour: each movable particle a constraint writes goes from the constraint's owner to
  // every other holder (the particle's owner and its ghost holders). Colours are visited in
  // order and a colour's constraints in ascending id, and each list is sorted, so the plan
  // does not depend on the colouring's order within a colour.
  const std::size_t colours = colouring.colour_count();
  for (RankDomain& rank : d.ranks) {
    rank.sends.resize(colours);
    rank.receives.resize(colours);
  }
  std::vector<std::map<std::pair<Rank, Rank>, std::vector<ParticleIndex>>> flows(colours);
  for (Colour k = 0; k < colours; ++k) {
    auto& flow = flows[k];
    for (const ConstraintIndex c : colouring.constraints_of(k)) {
      const Rank writer = d.owner_of_constraint[c];
      for (const ParticleIndex p : graph.particles_of(c)) {
        if (!graph.is_movable(p)) continue;
        if (d.owner_of_particle[p] != writer) flow[{writer, d.owner_of_particle[p]}].push_back(p);
        for (std::uint32_t h = ghost_offsets[p]; h < ghost_offsets[p + 1]; ++h)
          if (ghost_holders[h] != writer) flow[{writer, ghost_holders[h]}].push_back(p);
      }
    }
    for (auto& [pair, list] : flow) {
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
      const auto [from, to] = pair;
      d.ranks[from].sends[k].push_back({to, list});
      d.ranks[to].receives[k].push_back({from, std::move(list)});
    }
  }
  // Sends are by ascending receiver already (map order); receives by ascending sender.
  for (RankDomain& rank : d.ranks) {
    for (auto& list : rank.receives)
      std::sort(list.begin(), list.end(),
                [](const RankExchange& a, const RankExchange& b) { return a.rank < b.rank; });
    for (const auto& per_colour : {&rank.sends, &rank.receives})
      for (const auto& list : *per_colour)
        for (const RankExchange& exchange : list) rank.neighbours.push_back(exchange.rank);
    std::sort(rank.neighbours.begin(), rank.neighbours.end());
    rank.neighbours.erase(std::unique(rank.neighbours.begin(), rank.neighbours.end()),
                          rank.neighbours.end());
  }
  return d;
}

}  // namespace tessera
