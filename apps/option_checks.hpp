// Checks of numeric option values with messages that say what is wanted and what was given
// ("--threads: must be an integer from 1 to 4096, not '0'"), used instead of CLI11's range
// checks, whose messages print doubles with six decimals and call "abc" out of range.
#pragma once

#include <cstddef>
#include <string>

#include <CLI/CLI.hpp>

namespace tessera::cli {

/// An integer in [low, high].
CLI::Validator integer_from(std::size_t low, std::size_t high);
/// A finite number above `low` (or at least `low` when `low_inclusive`), in `unit`.
CLI::Validator finite_number_above(double low, bool low_inclusive, const std::string& unit);
/// A number above 0, or "inf".
CLI::Validator positive_number_or_inf();
/// A finite number strictly between `low` and `high`.
CLI::Validator finite_number_between(double low, double high);

}  // namespace tessera::cli
