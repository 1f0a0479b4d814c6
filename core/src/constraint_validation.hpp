// Validation at the door: every make_<family>_constraints function checks its plain input here
// before building SoA batches, so the hot loops never check anything. Messages name the
// family, the constraint's position in the input and the problem, e.g.
//   "<family> constraint 17: particle index 99 is out of range (50 particles)".
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <string>

#include <tessera/core/constraint_batch.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/simd.hpp>

namespace tessera::detail {

class ConstraintValidator {
 public:
  /// `family` is a family's kFamily (a string literal); kept as a pointer, so a validator
  /// costs no allocation (the collision stage builds its contact batches every substep).
  ConstraintValidator(const char* family, std::size_t particle_count)
      : family_(family), particle_count_(particle_count) {}

  const char* family() const { return family_; }
  std::size_t particle_count() const { return particle_count_; }

  /// Throws InvalidInput "<family> constraint <index>: <problem>".
  [[noreturn]] void fail(std::size_t constraint, const std::string& problem) const;
  /// Throws InvalidInput "<family> constraints: <problem>" (about the input as a whole).
  [[noreturn]] void fail_input(const std::string& problem) const;

  /// A finite value (and, with `positive`, one above zero; with `non_negative`, ≥ 0).
  void check_finite(std::size_t constraint, const char* what, Real value) const;
  void check_positive(std::size_t constraint, const char* what, Real value) const;
  void check_non_negative(std::size_t constraint, const char* what, Real value) const;
  /// A finite parameter shared by every constraint of the input, ≥ 0.
  void check_parameter(const char* what, Real value) const;

  /// Splits a flat index list (N per constraint) into padded per-slot arrays, checking the
  /// length, that every index is in range and that no constraint names a particle twice.
  template <int N>
  ConstraintParticles<N> particles(std::span<const ParticleIndex> flat) const {
    ConstraintParticles<N> result;
    fill_particles(result, flat);
    return result;
  }
  /// The same into `result`, whose slot arrays keep their capacity.
  template <int N>
  void fill_particles(ConstraintParticles<N>& result, std::span<const ParticleIndex> flat) const {
    if (flat.size() % N != 0)
      fail_input(std::to_string(flat.size()) + " particle indices is not a multiple of " +
                 std::to_string(N));
    result.count = flat.size() / N;
    result.particle_count = particle_count_;
    for (auto& slot : result.particle) slot.assign(padded_size(result.count), 0);
    for (std::size_t c = 0; c < result.count; ++c) {
      for (int k = 0; k < N; ++k) {
        const ParticleIndex index = flat[c * N + k];
        check_index(c, index);
        for (int j = 0; j < k; ++j)
          if (flat[c * N + j] == index) fail_repeated(c, index);
        result.particle[k][c] = index;
      }
    }
  }

  /// The rest positions of constraint c's N particles, each checked to be finite.
  template <int N>
  std::array<Vector3r, N> rest_points(const ConstraintParticles<N>& particles,
                                      std::span<const Vector3r> rest_positions,
                                      std::size_t c) const {
    std::array<Vector3r, N> p;
    for (std::size_t k = 0; k < std::size_t(N); ++k) {
      p[k] = rest_positions[particles.particle[k][c]];
      if (!p[k].allFinite()) fail(c, "rest position is not finite");
    }
    return p;
  }

  void check_index(std::size_t constraint, ParticleIndex index) const {
    if (index >= particle_count_) fail_out_of_range(constraint, index);
  }
  [[noreturn]] void fail_out_of_range(std::size_t constraint, ParticleIndex index) const;
  [[noreturn]] void fail_repeated(std::size_t constraint, ParticleIndex index) const;

 private:
  const char* family_;
  std::size_t particle_count_;
};

/// A value as the validation messages print it (e.g. "-1", "nan", "inf").
std::string describe(Real value);

/// Makes `out` n values all equal to value, padded with zeros (its capacity is kept).
inline void fill(AlignedVector<Real>& out, std::size_t n, Real value) {
  out.assign(padded_size(n), Real(0));
  std::fill(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(n), value);
}

/// A padded copy of n values all equal to value.
inline AlignedVector<Real> filled(std::size_t n, Real value) {
  AlignedVector<Real> result;
  fill(result, n, value);
  return result;
}

}  // namespace tessera::detail
