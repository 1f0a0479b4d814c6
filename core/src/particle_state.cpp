// ParticleState's constructors (particle_state.hpp): every array allocated at the padded size
// and zeroed, so padding particles are static at the origin; the validating constructor checks
// each position and inverse mass before copying it in.
#include <tessera/core/error.hpp>
#include <tessera/core/particle_state.hpp>

#include <cmath>
#include <string>

namespace tessera {

ParticleState::ParticleState(std::size_t n) : count_(n) {
  const std::size_t padded = padded_size(n);
  for (AlignedVector<Real>* array : {&x, &y, &z, &inverse_mass, &previous_x, &previous_y,
                                     &previous_z, &velocity_x, &velocity_y, &velocity_z})
    array->assign(padded, Real(0));
}

ParticleState::ParticleState(std::span<const Vector3r> positions,
                             std::span<const Real> inverse_masses)
    : ParticleState(positions.size()) {
  if (inverse_masses.size() != positions.size())
    throw InvalidInput("particles: " + std::to_string(positions.size()) + " positions but " +
                       std::to_string(inverse_masses.size()) + " inverse masses");
  for (std::size_t i = 0; i < positions.size(); ++i) {
    if (!positions[i].allFinite())
      throw InvalidInput("particle " + std::to_string(i) + ": position is not finite");
    if (!std::isfinite(inverse_masses[i]) || inverse_masses[i] < 0)
      throw InvalidInput("particle " + std::to_string(i) + ": inverse mass " +
                         std::to_string(inverse_masses[i]) + " must be finite and ≥ 0");
    set_position(i, positions[i]);
    previous_x[i] = x[i];
    previous_y[i] = y[i];
    previous_z[i] = z[i];
    inverse_mass[i] = inverse_masses[i];
  }
}

void interleave_particles(const ParticleState& state, Real* xyzw, std::size_t first,
                          std::size_t last) {
  for (std::size_t i = first; i < last; ++i) {
    xyzw[4 * i] = state.x[i];
    xyzw[4 * i + 1] = state.y[i];
    xyzw[4 * i + 2] = state.z[i];
    xyzw[4 * i + 3] = state.inverse_mass[i];
  }
}

void deinterleave_positions(const Real* xyzw, ParticleState& state, std::size_t first,
                            std::size_t last) {
  for (std::size_t i = first; i < last; ++i) {
    state.x[i] = xyzw[4 * i];
    state.y[i] = xyzw[4 * i + 1];
    state.z[i] = xyzw[4 * i + 2];
  }
}

}  // namespace tessera
