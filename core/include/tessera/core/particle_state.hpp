// Particle state in structure-of-arrays form: the layout the batched kernels gather from.
//
//   x[0..n)  y[0..n)  z[0..n)  inverse_mass[0..n)        ← kernels read and write these
//   previous_x/y/z, velocity_x/y/z                        ← time stepping (XPBD) only
//
// One array per coordinate, each 64-byte aligned and padded (padded_size), so a kernel loads
// W lanes of one coordinate with one gather and a time-stepping loop runs over whole vectors.
// Padding particles have inverse mass 0 and sit at the origin. An inverse mass of 0 makes a
// particle static: no kernel ever writes it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include <tessera/core/aligned_vector.hpp>
#include <tessera/core/indices.hpp>
#include <tessera/core/real.hpp>
#include <tessera/core/simd.hpp>

namespace tessera {

class ParticleState {
 public:
  ParticleState() = default;
  /// n particles at the origin, all static.
  explicit ParticleState(std::size_t n);
  /// Particles at the given positions with the given inverse masses (0 = static), at rest.
  /// Throws InvalidInput when the sizes differ, a position is not finite, or an inverse mass
  /// is negative or not finite; the message names the particle.
  ParticleState(std::span<const Vector3r> positions, std::span<const Real> inverse_masses);

  std::size_t size() const { return count_; }

  Vector3r position(std::size_t i) const { return Vector3r(x[i], y[i], z[i]); }
  void set_position(std::size_t i, const Vector3r& p) {
    x[i] = p.x();
    y[i] = p.y();
    z[i] = p.z();
  }
  Vector3r velocity(std::size_t i) const {
    return Vector3r(velocity_x[i], velocity_y[i], velocity_z[i]);
  }

  AlignedVector<Real> x, y, z;
  AlignedVector<Real> inverse_mass;
  AlignedVector<Real> previous_x, previous_y, previous_z;
  AlignedVector<Real> velocity_x, velocity_y, velocity_z;

 private:
  std::size_t count_ = 0;
};

/// What a batched kernel reads and writes of the particles: raw pointers, so kernels stay
/// free of container types. The arrays hold at least `count` particles. Particle i's
/// coordinates and inverse mass are x[i·stride], y[i·stride], z[i·stride] and
/// inverse_mass[i·stride], in one of two layouts:
///
///   stride 1, separate arrays (ParticleState's own):  x x x …  y y y …  z z z …  w w w …
///   stride 4, interleaved (of_interleaved):           x y z w  x y z w  x y z w  …
///
/// The interleaved layout puts a particle in 16 bytes (float; 32 in double) of one cache
/// line, so a kernel loads it with one vector load and transposes in registers instead of
/// four hardware gathers touching four lines (batch-inl.h). The solver sweeps in it
/// (SolverSettings::particle_layout) and keeps ParticleState separate.
struct ParticleArrays {
  Real* x;
  Real* y;
  Real* z;
  const Real* inverse_mass;
  std::size_t count;
  /// Redirected output (the solver's Jacobi sweeps): when corrected_x is set, a position
  /// kernel leaves x, y, z untouched and stores the corrected position of slot k of
  /// constraint c at corrected_x[k * corrected_stride + c] (y, z alike; a shape-matching
  /// cluster's entry e at corrected_x[e]), for its movable particles only. The arrays must
  /// hold every slot of the constraints projected; constraints projected together may then
  /// share particles, since each writes only its own slots.
  Real* corrected_x = nullptr;
  Real* corrected_y = nullptr;
  Real* corrected_z = nullptr;
  std::size_t corrected_stride = 0;
  /// 1 (separate arrays) or 4 (interleaved: y = x + 1, z = x + 2, inverse_mass = x + 3).
  std::size_t stride = 1;

  bool interleaved() const { return stride != 1; }
  /// Where particle i's values are in x, y, z and inverse_mass.
  std::size_t at(std::size_t i) const { return i * stride; }

  static ParticleArrays of(ParticleState& state) {
    return {state.x.data(), state.y.data(), state.z.data(), state.inverse_mass.data(),
            state.size()};
  }
  /// n particles stored x, y, z, w at xyzw[4i .. 4i + 4); xyzw is 16-byte aligned (32 in
  /// double) and holds 4n values.
  static ParticleArrays of_interleaved(Real* xyzw, std::size_t n) {
    ParticleArrays arrays{xyzw, xyzw + 1, xyzw + 2, xyzw + 3, n};
    arrays.stride = 4;
    return arrays;
  }
};

/// Copies positions and inverse masses of particles [first, last) from a state into the
/// interleaved array xyzw (4 values per particle), and back (positions only).
void interleave_particles(const ParticleState& state, Real* xyzw, std::size_t first,
                          std::size_t last);
void deinterleave_positions(const Real* xyzw, ParticleState& state, std::size_t first,
                            std::size_t last);

/// The velocity arrays of a state, in the form the velocity passes of the contact families
/// read and write (x, y, z are the velocity components; inverse masses as for positions).
inline ParticleArrays velocity_arrays_of(ParticleState& state) {
  return {state.velocity_x.data(), state.velocity_y.data(), state.velocity_z.data(),
          state.inverse_mass.data(), state.size()};
}

}  // namespace tessera
