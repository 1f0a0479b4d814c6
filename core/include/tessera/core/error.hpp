// The one exception type of Tessera's API.
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

}  // namespace tessera
