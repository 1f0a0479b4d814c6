// Colouring strategies behind one interface, and a registry that finds them by name, so a
// tool can list and compare them and users can plug in their own.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <tessera/coloring/colouring.hpp>
#include <tessera/coloring/constraint_graph.hpp>

namespace tessera {

/// Knobs shared by the strategies; each strategy reads the ones it documents.
struct ColouringOptions {
  /// Seed of the randomised strategies (random priorities, METIS). Same seed, same colouring,
  /// for any thread count.
  std::uint64_t seed = 1;
  /// metis, blocks: movable particles per part; 0 takes kDefaultParticlesPerPart
  /// (particle_partition.hpp, which records the measurement behind it).
  std::size_t particles_per_part = 0;
  /// Rounds of iterated greedy (Culberson) in the reduction pass; each round recolours the
  /// constraints first-fit, colour class by colour class, which never adds a colour.
  std::size_t reduction_rounds = 24;
  /// Post-passes applied by run_colouring after any strategy: reduction, balance, locality.
  bool reduce = false;
  bool balance = false;
  /// Last post-pass: improve_locality (particles renumbered by reverse Cuthill–McKee unless
  /// the strategy renumbered them, each colour's constraints by smallest new particle).
  bool locality = false;
};

/// A way of colouring a constraint graph. Implementations must be deterministic: the same
/// graph and options give the same colouring on every run and for any number of TBB threads.
/// Parallel strategies run in the caller's TBB arena.
class ColouringStrategy {
 public:
  virtual ~ColouringStrategy() = default;
  /// Short unique name used by the registry and the tool ("greedy", "dsatur", ...).
  virtual std::string_view name() const = 0;
  /// One line saying what the strategy does, for listings.
  virtual std::string_view description() const = 0;
  /// Whether its colourings have parts (Colouring::has_parts) sized by
  /// ColouringOptions::particles_per_part: the part strategies, metis and blocks.
  virtual bool makes_parts() const { return false; }
  /// Colours every constraint of the graph so that constraints sharing a movable particle
  /// get different colours.
  virtual Colouring colour(const ConstraintGraph& graph, const ColouringOptions& options) const = 0;
};

/// Strategies by name, in the order they were added.
class ColouringRegistry {
 public:
  /// An empty registry.
  ColouringRegistry() = default;
  /// A registry holding Tessera's built-in strategies: greedy, largest-first, smallest-last,
  /// dsatur, stencil, iterated-greedy, random, metis, blocks.
  static ColouringRegistry with_builtin_strategies();

  /// Adds a strategy; throws tessera::InvalidInput if the name is empty or already taken.
  void add(std::shared_ptr<const ColouringStrategy> strategy);
  /// The strategy called `name`; throws tessera::InvalidInput listing the known names if
  /// there is none.
  const ColouringStrategy& get(std::string_view name) const;
  bool contains(std::string_view name) const;
  std::vector<std::string_view> names() const;
  std::size_t size() const { return strategies_.size(); }

 private:
  std::vector<std::shared_ptr<const ColouringStrategy>> strategies_;
};

/// The built-in strategies, one factory each (the registry holds one of every kind).
std::shared_ptr<const ColouringStrategy> make_greedy_strategy();
std::shared_ptr<const ColouringStrategy> make_largest_first_strategy();
std::shared_ptr<const ColouringStrategy> make_smallest_last_strategy();
std::shared_ptr<const ColouringStrategy> make_dsatur_strategy();
std::shared_ptr<const ColouringStrategy> make_stencil_strategy();
std::shared_ptr<const ColouringStrategy> make_iterated_greedy_strategy();
std::shared_ptr<const ColouringStrategy> make_random_strategy();
std::shared_ptr<const ColouringStrategy> make_metis_strategy();
std::shared_ptr<const ColouringStrategy> make_blocks_strategy();

}  // namespace tessera
