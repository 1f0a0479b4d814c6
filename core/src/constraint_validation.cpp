// The out-of-line half of ConstraintValidator (constraint_validation.hpp): the fail_* paths
// that build the "<family> constraint <i>: <problem>" messages, and the checks of one value
// (finite, positive, non-negative, a batch-wide parameter) that call them.
#include "constraint_validation.hpp"

#include <sstream>

namespace tessera::detail {

void ConstraintValidator::fail(std::size_t constraint, const std::string& problem) const {
  throw InvalidInput(std::string(family_) + " constraint " + std::to_string(constraint) + ": " + problem);
}

void ConstraintValidator::fail_input(const std::string& problem) const {
  throw InvalidInput(std::string(family_) + " constraints: " + problem);
}

void ConstraintValidator::fail_out_of_range(std::size_t constraint, ParticleIndex index) const {
  fail(constraint, "particle index " + std::to_string(index) + " is out of range (" +
                       std::to_string(particle_count_) + " particles)");
}

void ConstraintValidator::fail_repeated(std::size_t constraint, ParticleIndex index) const {
  fail(constraint, "particle " + std::to_string(index) + " appears twice");
}

std::string describe(Real value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

void ConstraintValidator::check_finite(std::size_t constraint, const char* what,
                                       Real value) const {
  if (!std::isfinite(value)) fail(constraint, std::string(what) + " is not finite");
}

void ConstraintValidator::check_positive(std::size_t constraint, const char* what,
                                         Real value) const {
  check_finite(constraint, what, value);
  if (!(value > 0))
    fail(constraint, std::string(what) + " is " + describe(value) + ", must be positive");
}

void ConstraintValidator::check_non_negative(std::size_t constraint, const char* what,
                                             Real value) const {
  check_finite(constraint, what, value);
  if (value < 0)
    fail(constraint, std::string(what) + " is " + describe(value) + ", must not be negative");
}

void ConstraintValidator::check_parameter(const char* what, Real value) const {
  if (!std::isfinite(value) || value < 0)
    fail_input(std::string(what) + " is " + describe(value) + ", must be finite and ≥ 0");
}

}  // namespace tessera::detail
