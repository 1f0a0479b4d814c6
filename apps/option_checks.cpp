// The option validators of option_checks.hpp. Each parses the text itself (digits only for
// integers, strtod for numbers) so that the message can quote what the user typed.
#include "option_checks.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace tessera::cli {
namespace {

/// The whole text as a number (strtod's forms, "inf" included); false for anything else.
bool read_number(const std::string& text, double& value) {
  char* end = nullptr;
  errno = 0;
  value = std::strtod(text.c_str(), &end);
  return end != text.c_str() && *end == '\0' && errno == 0;
}

}  // namespace

CLI::Validator integer_from(std::size_t low, std::size_t high) {
  const std::string wanted = "must be an integer from " + std::to_string(low) + " to " + std::to_string(high);
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        const bool digits = !text.empty() && text.size() <= 19 &&
                            text.find_first_not_of("0123456789") == std::string::npos;
        if (!digits) return wanted + ", not '" + text + "'";
        const unsigned long long value = std::strtoull(text.c_str(), nullptr, 10);
        if (value < low || value > high) return wanted + ", not '" + text + "'";
        return {};
      },
      "INT");
}

CLI::Validator finite_number_above(double low, bool low_inclusive, const std::string& unit) {
  std::string wanted = unit.empty() ? "must be a finite number" : "must be a finite number of " + unit;
  const bool zero = low == 0;
  wanted += zero ? (low_inclusive ? " (0 or more)" : " above 0")
                 : (low_inclusive ? " of at least " : " above ") + std::to_string(low);
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double value = 0;
        const bool number = read_number(text, value) && std::isfinite(value);
        if (!number || !(low_inclusive ? value >= low : value > low))
          return wanted + ", not '" + text + "'";
        return {};
      },
      "NUMBER");
}

CLI::Validator positive_number_or_inf() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double value = 0;
        const bool number = read_number(text, value) && !std::isnan(value);
        if (!number || !(value > 0)) return "must be a number above 0 or inf, not '" + text + "'";
        return {};
      },
      "NUMBER|inf");
}

CLI::Validator finite_number_between(double low, double high) {
  std::ostringstream range;
  range << "must be a number in (" << low << ", " << high << ")";
  const std::string wanted = range.str();
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double value = 0;
        const bool number = read_number(text, value) && std::isfinite(value);
        if (!number || !(value > low && value < high)) return wanted + ", not '" + text + "'";
        return {};
      },
      "NUMBER");
}

}  // namespace tessera::cli
