// The result of a colouring strategy: a colour per constraint, the same information grouped
// by colour (CSR, the form the schedule stage consumes), and, when a strategy renumbers
// particles for locality, the permutation both ways so results map back to the user's
// particle numbering.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <tessera/coloring/constraint_graph.hpp>

namespace tessera {

/// Index of a colour: colours are 0, 1, ..., colour_count() - 1, none empty.
using Colour = std::uint32_t;

class Colouring {
 public:
  Colouring() = default;

  /// Groups constraints by colour. Colours must be dense (every value below the largest used
  /// at least once); within a colour, constraints are listed by increasing id. Throws
  /// tessera::InvalidInput if a colour in the range is unused.
  static Colouring from_colours(std::vector<Colour> colour_of_constraint);

  /// As from_colours, but lists the constraints of each colour in the order given by
  /// `constraint_order` (a permutation of all constraint ids): the member of colour k that
  /// comes first in constraint_order is listed first.
  static Colouring from_colours(std::vector<Colour> colour_of_constraint,
                                std::span<const ConstraintIndex> constraint_order);

  std::size_t constraint_count() const { return colour_of_.size(); }
  std::size_t colour_count() const { return offsets_.empty() ? 0 : offsets_.size() - 1; }
  Colour colour_of(ConstraintIndex c) const { return colour_of_[c]; }
  std::span<const Colour> colours() const { return colour_of_; }

  /// The constraints of colour k, in schedule order.
  std::span<const ConstraintIndex> constraints_of(Colour k) const {
    return {constraints_by_colour_.data() + offsets_[k],
            constraints_by_colour_.data() + offsets_[k + 1]};
  }
  std::size_t colour_size(Colour k) const { return offsets_[k + 1] - offsets_[k]; }
  /// CSR: colour_offsets()[k] .. colour_offsets()[k+1] index constraints_by_colour().
  std::span<const std::uint32_t> colour_offsets() const { return offsets_; }
  std::span<const ConstraintIndex> constraints_by_colour() const { return constraints_by_colour_; }

  /// Particle renumbering chosen by the strategy (both empty when it keeps the user's
  /// numbering): new_to_old[n] is the user's index of new particle n, old_to_new its inverse.
  bool renumbers_particles() const { return !particle_new_to_old_.empty(); }
  std::span<const ParticleIndex> particle_new_to_old() const { return particle_new_to_old_; }
  std::span<const ParticleIndex> particle_old_to_new() const { return particle_old_to_new_; }
  /// Sets the particle permutation (new_to_old must be a permutation of 0..n-1; throws
  /// tessera::InvalidInput otherwise).
  void set_particle_order(std::vector<ParticleIndex> new_to_old);

  /// Parts (strategies metis and blocks; none for the others): a part's interior constraints touch
  /// no movable particle outside the part, so different parts can be swept at the same time while
  /// each sweeps its own colours one after another (SweepOrder::part_major);
  /// part_of_constraint()[c] is c's part, or part_count() for a crossing constraint (touching
  /// several parts, or no movable particle). The schedule checks the claim against the model.
  bool has_parts() const { return has_parts_; }
  std::size_t part_count() const { return part_count_; }
  std::span<const std::uint32_t> part_of_constraint() const { return part_of_constraint_; }
  /// Sets the parts (one entry per constraint, each at most part_count; throws
  /// tessera::InvalidInput otherwise).
  void set_parts(std::vector<std::uint32_t> part_of_constraint, std::size_t part_count);

 private:
  std::vector<Colour> colour_of_;
  std::vector<std::uint32_t> offsets_;
  std::vector<ConstraintIndex> constraints_by_colour_;
  std::vector<ParticleIndex> particle_new_to_old_;
  std::vector<ParticleIndex> particle_old_to_new_;
  std::vector<std::uint32_t> part_of_constraint_;
  std::size_t part_count_ = 0;
  bool has_parts_ = false;  // set_parts was called (a model may have no constraints)
};

}  // namespace tessera
