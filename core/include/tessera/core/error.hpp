// The exception types of Tessera's API: bad input, and a computation that left the finite
// numbers (reported, with the state restored, instead of silently written).
#pragma once

#include <stdexcept>
#include <string>

namespace tessera {

/// Thrown when input handed to Tessera is invalid: an index out of range, a particle named
/// twice in one constraint, a non-finite value, a degenerate rest shape, an unknown name.
/// The message names what is wrong and where (the family or file, the constraint's position
/// in the input or the line number), so the caller can report it as it is.
class InvalidInput : public std::invalid_argument {
 public:
  explicit InvalidInput(const std::string& message) : std::invalid_argument(message) {}
};

/// Thrown when a step or projection produced a non-finite position or velocity from finite
/// input (extreme parameters: a velocity or compliance that overflows). The operation is
/// undone: the state is the one from before it, so the caller can change the parameters and
/// go on. The message names the particle.
class NumericalFailure : public std::runtime_error {
 public:
  explicit NumericalFailure(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace tessera
