// Summary's printing (see summary.hpp), and the FNV-1a hash behind the tool's state_hash and
// colouring_hash: 64-bit FNV-1a over the raw bytes, printed as 16 hex digits.
#include "summary.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace tessera::cli {

std::string Summary::text(const nlohmann::ordered_json& value) {
  if (value.is_string()) return value.get<std::string>();
  if (value.is_number_float()) {
    char number[32];
    std::snprintf(number, sizeof number, "%.6g", value.get<double>());
    return number;
  }
  return value.dump();
}

void Summary::add(const std::string& key, double value) {
  if (std::isfinite(value))
    json_[key] = value;
  else
    json_[key] = std::isnan(value) ? "nan" : value > 0 ? "inf" : "-inf";
}

void Summary::print(std::ostream& out, bool as_json) const {
  if (as_json) {
    out << json_.dump() << '\n';
  } else {
    std::size_t width = 0;
    for (const auto& [key, value] : json_.items()) width = std::max(width, key.size());
    for (const auto& [key, value] : json_.items())
      out << key << std::string(width + 2 - key.size(), ' ') << text(value) << '\n';
  }
  out.flush();
}

void add_residuals(Summary& summary, const Residual& initial, const Residual& final) {
  summary.add("residual_rms_initial", initial.rms);
  summary.add("residual_rms_final", final.rms);
  summary.add("residual_max_final", final.max);
  for (std::size_t f = 0; f < kConstraintFamilyCount; ++f) {
    const FamilyResidual& family = final.families[f];
    if (family.constraints == 0) continue;
    const std::string name(family_name(ConstraintFamily(f)));
    summary.add("residual_" + name + "_rms_final", family.rms);
    summary.add("residual_" + name + "_max_final", family.max);
  }
}

}  // namespace tessera::cli
