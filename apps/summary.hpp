// A command's results as ordered key/value pairs, printed either as aligned "key  value"
// lines for people or as one JSON object for scripts (same keys, same order).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <ostream>
#include <string>

#include <nlohmann/json.hpp>

#include <tessera/parallel/residual.hpp>

namespace tessera::cli {

/// Wall seconds from `start` to now: the summary's seconds_* figures.
inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

class Summary {
 public:
  template <class Value>
  void add(const std::string& key, const Value& value) {
    json_[key] = value;
  }
  /// A number; one that is not finite is written as the string "inf", "-inf" or "nan" (JSON
  /// has no such numbers and would print null).
  void add(const std::string& key, double value);
  const nlohmann::ordered_json& json() const { return json_; }

  /// JSON: one line. Text: one line per key, values aligned; numbers with 6 significant digits.
  void print(std::ostream& out, bool as_json) const;

  /// A value as the text form prints it.
  static std::string text(const nlohmann::ordered_json& value);

 private:
  nlohmann::ordered_json json_ = nlohmann::ordered_json::object();
};

/// residual_rms_initial, residual_rms_final, residual_max_final, then the final RMS and max
/// of every family the run has (residual_<family>_rms_final, ..._max_final).
void add_residuals(Summary& summary, const Residual& initial, const Residual& final);

}  // namespace tessera::cli
