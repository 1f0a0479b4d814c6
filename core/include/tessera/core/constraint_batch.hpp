// What every constraint family's batch data has in common, and how a batch is projected.
//
// A family's constraints are stored structure-of-arrays: particle[slot][c] is the particle in
// slot `slot` of constraint c, and each rest value or parameter is one array indexed by c.
// All arrays are padded (padded_size) so a kernel can load W consecutive constraints from any
// position. A batched kernel projects a range [begin, end) of one family; the constraints of
// one range must not share a movable particle (a colour of the colouring stage guarantees
// it), because W of them are gathered, corrected and scattered at once, and the kernels of
// two-particle families overlap neighbouring blocks (kernels/batch_loop-inl.h).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>

#include <tessera/core/error.hpp>

#include <tessera/core/aligned_vector.hpp>
#include <tessera/core/particle_state.hpp>
#include <tessera/core/real.hpp>

namespace tessera {

/// Which parameter a projection uses: PBD stiffness k ∈ [0, 1] (Müller et al. 2007) or XPBD
/// compliance α with the accumulated multiplier λ (Macklin et al. 2016).
enum class ConstraintSemantics { stiffness, compliance };

struct ProjectionSettings {
  ConstraintSemantics semantics = ConstraintSemantics::stiffness;
  /// The (sub)step's time step, used by compliance semantics (α̃ = α / dt²).
  Real dt = Real(1) / Real(60);
  /// The multipliers λ of [begin, end) start this projection at 0: the kernel neither reads
  /// nor needs them reset, and stores them as usual. A solver's first iteration of a substep
  /// sets it rather than resetting λ in a pass of its own. The batched kernel
  /// (project_constraints) of every family with λ honours it; project_sequentially does not
  /// read it.
  bool lambda_starts_at_zero = false;
};

/// How the tool draws a family's constraint as a cell of its frames (VTK): which slots make it.
enum class CellShape : std::uint8_t {
  none,         ///< not drawn
  segment,      ///< a line through slots 0 and 1
  hinge,        ///< a line through slots 2 and 3 (a bending stencil's shared edge)
  triangle,     ///< slots 0, 1, 2
  tetrahedron,  ///< slots 0, 1, 2, 3
};

/// What a constraint family is and can do, stated once in its batch type as
/// `static constexpr FamilyTraits kTraits` next to its arrays (and `kFamily`, its name in
/// messages). constraint_families.hpp checks
/// it against the batch (a capability without its arrays, or arrays without the capability,
/// is a compile error) and every generic piece (schedule, solver, residuals, output) reads it.
struct FamilyTraits {
  /// Particles per constraint (ConstraintParticles<arity>), or 0 for a family whose
  /// constraints have any number of particles (a CSR layout: shape matching).
  int arity;
  /// Has an XPBD compliance form (arrays `compliance` and `lambda`) and is projected with the
  /// semantics the caller asks for; otherwise its PBD form runs under either semantics.
  bool xpbd;
  /// Keeps a multiplier per constraint (array `lambda`) that the solver resets every substep.
  bool multiplier;
  /// Has a velocity solve after each substep's velocity update (solve_velocity_constraints).
  bool velocity_pass;
  /// How frames draw it.
  CellShape cell;
};

/// The particle indices of N-particle constraints, one padded array per slot.
template <int N>
struct ConstraintParticles {
  static constexpr int kParticlesPerConstraint = N;
  /// Number of constraints.
  std::size_t count = 0;
  /// Number of particles the indices were validated against: a ParticleArrays projected with
  /// these constraints must hold at least this many.
  std::size_t particle_count = 0;
  std::array<AlignedVector<ParticleIndex>, N> particle;
};

/// Checks, once per call and not per constraint, that [begin, end) lies within a family of
/// `count` constraints built for at most particles.count particles. Throws InvalidInput.
inline void check_projection_range(const char* family, std::size_t begin, std::size_t end,
                                   std::size_t count, std::size_t particle_count,
                                   const ParticleArrays& particles) {
  if (begin > end || end > count)
    throw InvalidInput(std::string(family) + " constraints: range [" + std::to_string(begin) +
                       ", " + std::to_string(end) + ") is outside [0, " +
                       std::to_string(count) + ")");
  if (particles.count < particle_count)
    throw InvalidInput(std::string(family) + " constraints: built for " +
                       std::to_string(particle_count) + " particles, projected on " +
                       std::to_string(particles.count));
}

namespace detail {

/// 1/dt², the factor from compliance α to α̃ = α/dt² (0 for dt ≤ 0: no compliance term).
inline Real inverse_squared(Real dt) { return dt > 0 ? Real(1) / (dt * dt) : Real(0); }

/// How project_sequentially takes a batch: by reference where it accumulates a multiplier,
/// by const reference otherwise.
template <class Batch>
using SequentialBatch =
    std::conditional_t<Batch::kTraits.multiplier, Batch&, const Batch&>;

/// The family's batched kernel under the one signature generic code calls (a kernel that
/// needs no settings is called without them).
template <class Kernel, class Batch>
void call_batched_kernel(Kernel&& kernel, ParticleArrays particles, Batch& batch,
                         std::size_t begin, std::size_t end, const ProjectionSettings& settings) {
  if constexpr (std::is_invocable_v<Kernel, ParticleArrays, Batch&, std::size_t, std::size_t,
                                    const ProjectionSettings&>)
    kernel(particles, batch, begin, end, settings);
  else
    kernel(particles, batch, begin, end);
}

}  // namespace detail

/// Declares a family's entry points under the names generic code calls, overloaded on the
/// batch type (constraint_families.hpp): project_constraints (the batched kernel),
/// project_sequentially (the scalar API one constraint after another, defined in the family's
/// .cpp; sequential_projection.hpp) and constraint_residuals (the batched residual, defined
/// there too; constraint_residual.hpp). The family's header says, above it, which scalar-API
/// function and arguments the sequential form maps to and what its residual measures.
#define TESSERA_FAMILY_ENTRY_POINTS(Batch, batched_kernel)                                  \
  inline void project_constraints(ParticleArrays particles, Batch& batch, std::size_t begin, \
                                  std::size_t end, const ProjectionSettings& settings) {     \
    detail::call_batched_kernel(batched_kernel, particles, batch, begin, end, settings);     \
  }                                                                                          \
  void project_sequentially(ParticleArrays particles, detail::SequentialBatch<Batch> batch,  \
                            std::size_t begin, std::size_t end,                              \
                            const ProjectionSettings& settings = {});                        \
  void constraint_residuals(const ParticleArrays& particles, const Batch& batch,             \
                            std::size_t begin, std::size_t end, Real* out);

/// Declares an XPBD family's xpbd_residuals (constraint_residual.hpp): its residual measure of
/// C + α̃λ, α̃ = compliance / dt², instead of C.
#define TESSERA_XPBD_RESIDUAL_ENTRY_POINT(Batch)                                         \
  void xpbd_residuals(const ParticleArrays& particles, const Batch& batch, std::size_t begin, \
                      std::size_t end, Real dt, Real* out);

}  // namespace tessera
