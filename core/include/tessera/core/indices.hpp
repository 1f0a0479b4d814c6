// The index types every module shares: a particle's position in the particle arrays (a mesh
// vertex is a particle) and a constraint's position in the global constraint numbering.
#pragma once

#include <cstdint>

namespace tessera {

using ParticleIndex = std::uint32_t;
using ConstraintIndex = std::uint32_t;

}  // namespace tessera
