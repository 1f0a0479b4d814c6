// How far one constraint is from being satisfied, per family: the numbers the solver reports
// as the residual (RMS and max per family, before and after a run).
//
// Why one function per family: each family's raw C has its own units (metres, cubic metres,
// radians, energy), and a family's RMS must be comparable from one iteration to the next and
// between scenes of different size. So every overload returns a normalised violation ≥ 0 at the
// current positions, dimensionless wherever the family has a natural reference (rest length, rest
// volume, rest distance, the identity strain, the rest cluster size); the comment of each family's
// overload (in its header, <family>_constraints.hpp) names its measure and units. Where the
// family's lane formula (core/src/kernels/<family>-inl.h) gives C, the residual is evaluated
// through it on one lane, so it is the violation the kernel itself sees.
//
// Every function is finite for finite positions, also for degenerate configurations (all
// particles at one point, a zero-length edge...): each comment says what such a configuration
// reads. Preconditions (not checked, as in every hot loop): c < batch.size(), and `particles`
// holds the particles the batch was built for.
#pragma once

#include <cstddef>

#include <tessera/core/constraint_families.hpp>
#include <tessera/core/particle_state.hpp>
#include <tessera/core/real.hpp>

namespace tessera {

// constraint_residuals(particles, batch, begin, end, out), one overload per family (declared
// with the family): the residual of constraints [begin, end), W at a time on the active SIMD
// target (the family's lane formula instantiated on Highway vectors, as the batched
// projection kernels run it), written to out[c − begin] for each c. Nothing outside
// out[0, end − begin) is written. Shape matching (clusters of any size) evaluates its
// clusters one at a time. Preconditions (not checked): begin ≤ end ≤ batch.size().
//
// xpbd_residuals(particles, batch, begin, end, dt, out), one overload per family with an XPBD
// form (kTraits.xpbd): the same measure of C + α̃λ instead of C, α̃ = compliance / dt² with the
// batch's compliance and λ (the residual of the equation XPBD solves, Macklin, Müller,
// Chentanez 2016, eq. 11); equal to constraint_residuals where α = 0 or λ = 0.

/// The residual of constraint c alone: constraint_residuals over [c, c + 1), so the two
/// cannot drift apart (shape matching has its own overload, which its batched form loops).
template <class Batch>
  requires requires(const ParticleArrays& p, const Batch& b, Real* out) {
    constraint_residuals(p, b, std::size_t(0), std::size_t(1), out);
  }
Real constraint_residual(const ParticleArrays& particles, const Batch& batch, std::size_t c) {
  Real residual = 0;
  constraint_residuals(particles, batch, c, c + 1, &residual);
  return residual;
}

}  // namespace tessera
