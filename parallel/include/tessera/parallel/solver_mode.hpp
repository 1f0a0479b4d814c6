// How the solver projects the constraints each iteration: the modes, their names, and the
// stages each one runs (stage.hpp). A mode is a choice of layout (what the schedule colours,
// what goes to a Jacobi set) plus the stage list built from it; adding one means a value here
// and one stage-list builder (Schedule::build_stages).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

namespace tessera {

enum class SolverMode : std::uint8_t {
  /// Coloured Gauss–Seidel: colour after colour, each colour in parallel.
  gs,
  /// Jacobi with constraint averaging: every constraint from the same positions, then
  /// x += ω · (sum of corrections) / (count) per particle.
  jacobi,
  /// gs for the colours with at least hybrid_threshold constraints, one Jacobi phase for the
  /// smaller ones after them.
  hybrid,
  /// The classic PBD loop and reference: one thread, the scalar API per constraint, in the
  /// order SequentialOrder says; no colouring needed.
  sequential,
};

/// The order mode sequential projects the constraints in.
enum class SequentialOrder : std::uint8_t {
  /// The reference PBD library's: constraints put in groups first-fit in global id order
  /// (each joins the first group none of whose constraints shares a movable particle with it:
  /// Tessera's `greedy` colouring), the groups swept one after another, each group's
  /// constraints family by family in id order. The reference's own grouping also lets a
  /// static particle separate two constraints; that changes which group a constraint joins,
  /// not the kind of order. Stable: a cloth swept in input order (row by row, edge after
  /// edge along a row) diverges at 16 substeps × 2 iterations where this order does not.
  groups,
  /// Global id order (family after family, each in its input order).
  input,
};

/// "groups", "input".
std::string_view sequential_order_name(SequentialOrder order);
/// The order of that name; throws InvalidInput listing the names for any other.
SequentialOrder parse_sequential_order(std::string_view name);

/// How the solver schedules the contacts the collision stage finds each substep (modes gs
/// and hybrid; mode jacobi keeps them in a Jacobi set, mode sequential sweeps them in order).
enum class ContactScheduling : std::uint8_t {
  /// One Jacobi set of their own after the model's constraints: every contact from the same
  /// positions, each particle moved by the mean of its contacts' corrections.
  jacobi,
  /// Coloured among themselves (contact_colouring.hpp): each contact, first-fit, takes the
  /// first colour none of its movable particles' contacts took, and the colours run as
  /// Gauss–Seidel phases after the model's constraints; contacts that find none of the 64
  /// colours go to a Jacobi set (the overflow).
  coloured,
};

/// "jacobi", "coloured".
std::string_view contact_scheduling_name(ContactScheduling scheduling);
/// The scheduling of that name; throws InvalidInput listing the names for any other.
ContactScheduling parse_contact_scheduling(std::string_view name);

/// How the solver holds the particles while it sweeps (ParticleArrays): the sweeps of a step
/// or a project() call read and write a copy of x, y, z and the inverse mass, made before the
/// first iteration and copied back after the last; the result is bitwise the same either way.
enum class ParticleLayout : std::uint8_t {
  /// The state's own arrays, one per coordinate: a particle costs a gather per coordinate.
  separate,
  /// x, y, z, w in 16 bytes (32 in double) per particle: one 128-bit load per particle and
  /// lane, transposed in registers (batch-inl.h). See kDefaultParticleLayout.
  interleaved,
};

/// "separate", "interleaved".
std::string_view particle_layout_name(ParticleLayout layout);
/// The layout of that name; throws InvalidInput listing the names for any other.
ParticleLayout parse_particle_layout(std::string_view name);

/// The order a gs (or hybrid) iteration sweeps the coloured constraints in.
enum class SweepOrder : std::uint8_t {
  /// Colour after colour, each colour's blocks in parallel: a barrier per colour, and every
  /// colour reaches across the whole particle array.
  colour_major,
  /// Part after part (the colouring's parts, strategies metis and blocks, or runs of its
  /// particle order: SolverSettings::particles_per_part), the parts in parallel:
  /// each worker sweeps every colour of its parts' interior constraints while those particles stay
  /// in its cache, then the crossing constraints colour after colour as in colour_major. One
  /// barrier for all the interior work; a different Gauss–Seidel order (interior before crossing),
  /// the same for any thread count. In mode hybrid the threshold applies to each colour's crossing
  /// constraints: the small ones go to the Jacobi set, the parts never do.
  part_major,
  /// part_major when the sweep would have at least kPartMajorFromParts parts (the colouring's,
  /// or its runs), colour_major otherwise (and in modes jacobi and sequential): a scene whose
  /// particles outgrow a core's cache is swept part by part, a smaller one colour by colour.
  /// Decided by the scene and settings alone, never by the thread count or the machine, so the
  /// results stay the same for any thread count. The default; Schedule::options() and the
  /// tool's summary name the order it chose.
  automatic,
};

/// A sweep set to SweepOrder::automatic is part-major from this many parts up. Measured on
/// the 512² to 1024² cloths and the tet bars (docs/performance.md, "The sweep order chosen by
/// the scene"): with runs of kDefaultParticlesPerRun, 16 parts (a 512² cloth, 4 MB of float
/// particles, within the last-level cache) swept equally in either order, 36 parts (768²) and
/// 64 (1024²) up to twice as fast part-major. 32 parts also keep 32 workers busy in the
/// parts' one phase.
inline constexpr std::size_t kPartMajorFromParts = 32;

/// The size of the runs a part-major sweep makes of a colouring without parts, in movable
/// particles, when SolverSettings::particles_per_part is 0: 256 KiB of interleaved float
/// particles (512 KiB double), within a core's L2 with room for the constraints streamed
/// through it. On the 1024² cloth runs of 16,384 swept as fast as runs of 65,536 in double
/// and up to 1.3 times faster in float (docs/performance.md, "The sweep order chosen by the
/// scene"), and give four times the parts to share among workers.
inline constexpr std::size_t kDefaultParticlesPerRun = 16384;

/// "colour-major", "part-major", "auto".
std::string_view sweep_order_name(SweepOrder order);
/// The order of that name; throws InvalidInput listing the names for any other.
SweepOrder parse_sweep_order(std::string_view name);

/// Every mode, in declaration order.
inline constexpr SolverMode kSolverModes[] = {SolverMode::gs, SolverMode::jacobi,
                                              SolverMode::hybrid, SolverMode::sequential};

/// "gs", "jacobi", "hybrid", "sequential".
std::string_view solver_mode_name(SolverMode mode);
/// The mode of that name; throws InvalidInput listing the names for any other.
SolverMode parse_solver_mode(std::string_view name);

}  // namespace tessera
