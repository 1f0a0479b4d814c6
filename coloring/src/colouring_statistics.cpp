// Statistics and validation. validate() stamps each movable particle with the colour that
// last used it while walking the colours one after another, so a second use within one colour
// is seen in O(1): one pass over the incidences.
#include <tessera/coloring/colouring_statistics.hpp>

#include <algorithm>
#include <limits>
#include <span>
#include <sstream>
#include <string>
#include <utility>

namespace tessera {

ColouringValidation validate(const ConstraintGraph& graph, const Colouring& colouring) {
  auto fail = [](std::string problem) { return ColouringValidation{false, std::move(problem)}; };
  const std::size_t count = graph.constraint_count();
  if (colouring.constraint_count() != count)
    return fail("colouring has " + std::to_string(colouring.constraint_count()) +
                " constraints, the graph " + std::to_string(count));
  const auto offsets = colouring.colour_offsets();
  if (count > 0 && (offsets.empty() || offsets.back() != count))
    return fail("colour lists hold " + std::to_string(offsets.empty() ? 0 : offsets.back()) +
                " constraints, expected " + std::to_string(count));
  if (colouring.renumbers_particles() && colouring.particle_new_to_old().size() != graph.particle_count())
    return fail("particle permutation has " + std::to_string(colouring.particle_new_to_old().size()) +
                " entries, the graph " + std::to_string(graph.particle_count()) + " particles");

  std::vector<std::uint8_t> listed(count, 0);
  constexpr std::uint32_t kUnused = std::numeric_limits<std::uint32_t>::max();
  // Per particle: the last constraint that used it, and that constraint's colour (side by
  // side: one cache line per particle visited).
  struct LastUse {
    std::uint32_t constraint = kUnused;
    Colour colour = 0;
  };
  std::vector<LastUse> last_use(graph.particle_count());
  const std::span<const std::uint32_t> member_offsets = graph.constraint_offsets();
  const std::span<const ParticleIndex> members = graph.constraint_particles();
  const std::span<const Colour> colour_of = colouring.colours();
  // A colour lists its constraints in particle order (improve_locality), so their ids, and
  // with them listed[], colour_of[] and the particle lists, are read in no order: 0.3 s of the
  // 1024² cloth's start-up, waiting on memory. The ids ahead are known, so their entries are
  // prefetched: the flat arrays and the list's offset kAhead places ahead, the list itself
  // half as far, and its particles' last use a quarter as far.
  constexpr std::size_t kAhead = 32;
  for (Colour k = 0; k < colouring.colour_count(); ++k) {
    if (colouring.colour_size(k) == 0) return fail("colour " + std::to_string(k) + " is empty");
    const std::span<const ConstraintIndex> listed_in_k = colouring.constraints_of(k);
    for (std::size_t i = 0; i < listed_in_k.size(); ++i) {
      if (i + kAhead < listed_in_k.size()) {
        const ConstraintIndex ahead = listed_in_k[i + kAhead];
        if (ahead < count) {
          __builtin_prefetch(&member_offsets[ahead]);
          __builtin_prefetch(&listed[ahead]);
          __builtin_prefetch(&colour_of[ahead]);
        }
      }
      if (i + kAhead / 2 < listed_in_k.size()) {
        const ConstraintIndex ahead = listed_in_k[i + kAhead / 2];
        if (ahead < count) __builtin_prefetch(&members[member_offsets[ahead]]);
      }
      if (i + kAhead / 4 < listed_in_k.size()) {
        const ConstraintIndex ahead = listed_in_k[i + kAhead / 4];
        if (ahead < count)
          for (std::uint32_t m = member_offsets[ahead]; m < member_offsets[ahead + 1]; ++m)
            __builtin_prefetch(&last_use[members[m]]);
      }
      const ConstraintIndex c = listed_in_k[i];
      if (c >= count) return fail("colour " + std::to_string(k) + " lists constraint " + std::to_string(c) + ", out of range");
      if (listed[c]) return fail(graph.describe_constraint(c) + " is listed twice");
      listed[c] = 1;
      if (colouring.colour_of(c) != k)
        return fail(graph.describe_constraint(c) + " is listed in colour " + std::to_string(k) +
                    " but has colour " + std::to_string(colouring.colour_of(c)));
      for (ParticleIndex p : graph.particles_of(c)) {
        LastUse& last = last_use[p];
        if (last.constraint != kUnused && last.colour == k)
          return fail("colour " + std::to_string(k) + ": " + graph.describe_constraint(last.constraint) +
                      " and " + graph.describe_constraint(c) + " share movable particle " +
                      std::to_string(p));
        last = {c, k};
      }
    }
  }
  return {};
}

ColouringStatistics compute_statistics(const ConstraintGraph& graph, const Colouring& colouring,
                                       std::string strategy, double seconds) {
  ColouringStatistics s;
  s.strategy = std::move(strategy);
  s.constraints = colouring.constraint_count();
  s.colours = colouring.colour_count();
  s.sizes.resize(s.colours);
  for (Colour k = 0; k < s.colours; ++k) s.sizes[k] = colouring.colour_size(k);
  if (!s.sizes.empty()) {
    s.largest = *std::max_element(s.sizes.begin(), s.sizes.end());
    s.smallest = *std::min_element(s.sizes.begin(), s.sizes.end());
    s.mean = double(s.constraints) / double(s.colours);
    s.balance = double(s.largest) / s.mean;
    s.size_ratio = double(s.largest) / double(s.smallest);
  }
  s.lower_bound = graph.colour_lower_bound();
  s.colours_per_lower_bound = s.lower_bound > 0 ? double(s.colours) / double(s.lower_bound) : 0;
  s.seconds = seconds;
  const ColouringValidation check = validate(graph, colouring);
  s.valid = check.valid;
  s.problem = check.problem;
  return s;
}

std::string format_statistics(const ColouringStatistics& s) {
  std::ostringstream out;
  out << "strategy: " << s.strategy << "\n"
      << "constraints: " << s.constraints << "\n"
      << "colours: " << s.colours << "\n"
      << "sizes:";
  for (std::size_t size : s.sizes) out << ' ' << size;
  out << "\n"
      << "largest: " << s.largest << "\n"
      << "smallest: " << s.smallest << "\n"
      << "mean: " << s.mean << "\n"
      << "balance: " << s.balance << "\n"
      << "largest/smallest: " << s.size_ratio << "\n"
      << "lower_bound: " << s.lower_bound << "\n"
      << "colours/lower_bound: " << s.colours_per_lower_bound << "\n"
      << "seconds: " << s.seconds << "\n"
      << "valid: " << (s.valid ? "yes" : "no: " + s.problem) << "\n";
  return out.str();
}

}  // namespace tessera
