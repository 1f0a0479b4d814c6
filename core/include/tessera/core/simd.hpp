// Which SIMD instruction set the batched kernels run on.
//
// The default build compiles every batched kernel for several x86 targets (AVX-512, AVX2,
// SSE4 and a portable 128-bit emulation) with Highway's foreach_target, and picks the best
// one the running CPU supports on the first call (runtime dispatch). CMake's TESSERA_SIMD
// option can instead pin one target at build time (see the README's design notes).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <tessera/core/real.hpp>

namespace tessera {

/// The lane count of the widest vector any target uses (16 floats or 8 doubles in 512 bits).
inline constexpr std::size_t kMaxLanes = 64 / sizeof(Real);

/// Storage size of an SoA array of n elements: enough that a kernel may load a full vector
/// of kMaxLanes elements starting at any element i < n, rounded up to a whole number of
/// vectors. The elements past n are padding that the kernels load but never use.
constexpr std::size_t padded_size(std::size_t n) {
  return (n + 2 * kMaxLanes - 1) / kMaxLanes * kMaxLanes;
}

/// The SIMD targets this build has kernels for and the running CPU supports, best first
/// (e.g. {"AVX3", "AVX2", "SSE4", "EMU128"}; Highway calls AVX-512 "AVX3").
std::vector<std::string> available_simd_targets();

/// The target the batched kernels dispatch to now.
std::string active_simd_target();

/// Lanes per vector of Real on the active target.
std::size_t active_simd_lanes();

/// Restricts dispatch to the named target (one of available_simd_targets()), for tests and
/// benchmarks that compare targets; an empty name restores the best one. Not thread-safe:
/// call it while no kernel runs. Throws InvalidInput for a name that is not available.
void force_simd_target(const std::string& name);

}  // namespace tessera
