// The solver's stages: what one iteration (and one velocity update) runs, as a plain list
// built once per mode by the schedule and extended by the solver with its dynamic
// constraints; one dispatcher (Solver::run_stage) runs any stage.
//
//   gs          coloured phase 0 │ coloured phase 1 │ ... │ (dynamic: Jacobi projection │ reduction)
//   gs, part-major: part sweep (every part's interior colours) │ crossing phase 0 │ ... │ (dynamic ...)
//   jacobi      Jacobi projection │ Jacobi reduction │ (dynamic ...)
//   hybrid      coloured phases of the large colours │ Jacobi projection │ reduction │ (dynamic ...)
//   sequential  sequential sweep (every family range in input order) │ (dynamic: sequential sweep)
//   then, with a collision stage, the substep's contacts like the dynamic constraints, or
//   (ContactScheduling::coloured) their colours one phase each after the dynamic
//   constraints, then the overflow's Jacobi set
//   after the velocity update: a velocity pass per phase (or set) holding a family with a
//   velocity solve (kTraits.velocity_pass), none otherwise
//
// A stage names a set of batches and a range of that set's blocks (ScheduleBlock: family,
// [begin, end) of its batch).
#pragma once

#include <cstdint>

namespace tessera {

enum class StageKind : std::uint8_t {
  /// The blocks run in parallel through the batched kernels (one colour: no shared particle).
  coloured_phase,
  /// The blocks run in parallel, each constraint's corrected positions stored in its
  /// incidences instead of the particles.
  jacobi_projection,
  /// Every particle of the set moves by ω times the mean of its incidences' corrections.
  jacobi_reduction,
  /// One thread, block after block, constraint after constraint, through the scalar API.
  sequential_sweep,
  /// The velocity solve of the blocks' families that have one (in parallel for a coloured
  /// set, one block after another otherwise: a Jacobi set's constraints may share particles).
  velocity_pass,
  /// Parts [first_block, last_block) of the schedule (Schedule::part_blocks) in parallel, each
  /// part's blocks (its interior constraints, colour after colour) one after another on one
  /// worker (SweepOrder::part_major).
  part_sweep,
  /// The velocity solve of part_sweep's blocks, part by part the same way.
  part_velocity_pass,
};

/// Which batches a stage works on.
enum class StageSet : std::uint8_t {
  /// The schedule's coloured batches (mode sequential: the model's batches in input order).
  coloured,
  /// The schedule's Jacobi set.
  jacobi,
  /// The solver's dynamic constraints (Solver::set_dynamic_constraints).
  dynamic,
  /// The contacts the collision stage made for this substep (Solver::set_collisions) that run
  /// as a Jacobi set (ContactScheduling::jacobi, or the overflow of the coloured one).
  contacts,
  /// The substep's contacts coloured among themselves (ContactScheduling::coloured): the
  /// blocks of one contact colour.
  contact_colours,
};

struct Stage {
  StageKind kind;
  StageSet set;
  /// Blocks [first_block, last_block) of the set (unused by jacobi_reduction; parts for
  /// part_sweep and part_velocity_pass).
  std::uint32_t first_block;
  std::uint32_t last_block;
};

}  // namespace tessera
