// Fingerprints of results: 64-bit FNV-1a hashes of a colouring (the colour of every constraint)
// and of a state (every position, x y z per particle in the user's numbering), printed as 16
// hex digits. The tool prints them (`colouring_hash`, `state_hash`) and the Python module
// computes the same ones, so runs on different thread counts, builds or front ends compare by
// one string: equal hashes mean bitwise equal results.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <span>
#include <string>

#include <tessera/core/real.hpp>

namespace tessera {

/// 64-bit FNV-1a of a byte range, continuing from `hash`.
inline std::uint64_t fnv1a(const void* data, std::size_t size,
                           std::uint64_t hash = 14695981039346656037ull) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= bytes[i];
    hash *= 1099511628211ull;
  }
  return hash;
}

/// 16 lowercase hex digits.
inline std::string hex(std::uint64_t value) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
  return text;
}

/// The hash of a colouring's colour per constraint (Colouring::colours()), in hex.
inline std::string colouring_hash(std::span<const std::uint32_t> colours) {
  return hex(fnv1a(colours.data(), colours.size_bytes()));
}

/// The hash of positions (the Real bytes of x y z of particle 0, then particle 1, ...), in hex.
inline std::string state_hash(std::span<const Vector3r> positions) {
  std::uint64_t hash = fnv1a(nullptr, 0);
  for (const Vector3r& p : positions) {
    const Real xyz[3] = {p.x(), p.y(), p.z()};
    hash = fnv1a(xyz, sizeof xyz, hash);
  }
  return hex(hash);
}

}  // namespace tessera
