// Statistics and validation.
//
// validate() runs two passes, each in parallel over fixed chunks, and reports the first
// problem in a fixed order, so its answer does not depend on the thread count:
//
//   lists      chunks of the flat colour lists: each entry in range, in the colour colour_of
//              names, and listed once (an atomic flag per constraint; a second setter saw it)
//   particles  chunks of particles: no two of a movable particle's constraints (its incidence
//              list) share a colour
//
// The particle pass reads each particle's constraints in id order, so colour_of is read in a
// few forward streams; walking the colours instead read it, the particle lists and a
// per-particle stamp in no order at all (0.3 s of the 1024² cloth's start-up). It needs the
// graph's particle → constraint direction, which it builds if nothing has yet (the locality
// pass, which `tessera run` runs first, builds it too).
#include <tessera/coloring/colouring_statistics.hpp>

#include <algorithm>
#include <atomic>
#include <limits>
#include <memory>
#include <span>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

namespace tessera {
namespace {

constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
/// Entries (lists) or particles per chunk: fixed, so the chunks are the same on any machine.
constexpr std::size_t kValidateChunk = std::size_t(1) << 14;

/// The first problem of each kind a pass found: a position in the flat lists, a constraint
/// or a particle; kNone when there was none. Combined by taking the smaller of each.
struct Findings {
  std::size_t out_of_range = kNone;  // position in the lists
  std::size_t wrong_colour = kNone;  // position in the lists
  std::size_t listed_twice = kNone;  // constraint
  std::size_t shared = kNone;        // particle
  static Findings smaller(Findings a, const Findings& b) {
    a.out_of_range = std::min(a.out_of_range, b.out_of_range);
    a.wrong_colour = std::min(a.wrong_colour, b.wrong_colour);
    a.listed_twice = std::min(a.listed_twice, b.listed_twice);
    a.shared = std::min(a.shared, b.shared);
    return a;
  }
};

template <class Body>
Findings reduce_chunks(std::size_t count, Body&& body) {
  const std::size_t chunks = (count + kValidateChunk - 1) / kValidateChunk;
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, chunks, 1), Findings{},
      [&](const tbb::blocked_range<std::size_t>& r, Findings found) {
        for (std::size_t chunk = r.begin(); chunk != r.end(); ++chunk)
          body(chunk * kValidateChunk, std::min(count, (chunk + 1) * kValidateChunk), found);
        return found;
      },
      Findings::smaller);
}

/// The colour whose list holds flat position i.
Colour colour_at(std::span<const std::uint32_t> offsets, std::size_t i) {
  return Colour(std::upper_bound(offsets.begin(), offsets.end(), i) - offsets.begin() - 1);
}

}  // namespace

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
  for (Colour k = 0; k < colouring.colour_count(); ++k)
    if (colouring.colour_size(k) == 0) return fail("colour " + std::to_string(k) + " is empty");

  // Lists. Colouring's constructors build the lists from colour_of, so these checks guard
  // against a Colouring put together some other way; no public path reaches them.
  const std::span<const ConstraintIndex> listed_in_order = colouring.constraints_by_colour();
  const std::span<const Colour> colour_of = colouring.colours();
  const auto listed = std::make_unique<std::atomic<std::uint8_t>[]>(count);  // zeroed
  const Findings lists = reduce_chunks(
      listed_in_order.size(), [&](std::size_t begin, std::size_t end, Findings& found) {
        Colour k = colour_at(offsets, begin);
        for (std::size_t i = begin; i < end; ++i) {
          while (i >= offsets[k + 1]) ++k;
          const ConstraintIndex c = listed_in_order[i];
          if (c >= count) {
            found.out_of_range = std::min(found.out_of_range, i);
            continue;
          }
          if (listed[c].exchange(1, std::memory_order_relaxed) != 0)
            found.listed_twice = std::min<std::size_t>(found.listed_twice, c);
          if (colour_of[c] != k) found.wrong_colour = std::min(found.wrong_colour, i);
        }
      });
  if (lists.out_of_range != kNone) {
    const std::size_t i = lists.out_of_range;
    return fail("colour " + std::to_string(colour_at(offsets, i)) + " lists constraint " +
                std::to_string(listed_in_order[i]) + ", out of range");
  }
  if (lists.listed_twice != kNone)
    return fail(graph.describe_constraint(ConstraintIndex(lists.listed_twice)) +
                " is listed twice");
  if (lists.wrong_colour != kNone) {
    const std::size_t i = lists.wrong_colour;
    const ConstraintIndex c = listed_in_order[i];
    return fail(graph.describe_constraint(c) + " is listed in colour " +
                std::to_string(colour_at(offsets, i)) + " but has colour " +
                std::to_string(colour_of[c]));
  }

  // Particles: the constraints of a movable particle in id order, their colours distinct.
  const std::span<const std::uint32_t> incidence_offsets = graph.particle_offsets();
  const std::span<const ConstraintIndex> incidence = graph.particle_constraints();
  // The first pair (in incidence order) of p's constraints with one colour: for the message,
  // once.
  const auto first_clash = [&](std::size_t p) -> std::pair<ConstraintIndex, ConstraintIndex> {
    const std::uint32_t first = incidence_offsets[p], last = incidence_offsets[p + 1];
    for (std::uint32_t i = first + 1; i < last; ++i)
      for (std::uint32_t j = first; j < i; ++j)
        if (colour_of[incidence[i]] == colour_of[incidence[j]]) return {incidence[j], incidence[i]};
    return {0, 0};
  };
  const Findings particles = reduce_chunks(
      graph.particle_count(), [&](std::size_t begin, std::size_t end, Findings& found) {
        // `found` holds what this body found in its earlier ranges, all of lower particles
        // (parallel_reduce hands a body the ranges to its right only), so after a clash there
        // is nothing lower left to find here.
        if (found.shared != kNone) return;
        std::vector<Colour> colours;  // a particle's colours, when one is 64 or more
        for (std::size_t p = begin; p < end; ++p) {
          const std::uint32_t first = incidence_offsets[p], last = incidence_offsets[p + 1];
          // Colours below 64 (nearly always) as bits of a mask; else sorted and compared.
          std::uint64_t seen = 0;
          bool clash = false, wide = false;
          for (std::uint32_t i = first; i < last && !clash && !wide; ++i) {
            const Colour k = colour_of[incidence[i]];
            wide = k >= 64;
            clash = !wide && ((seen >> k) & 1u);
            seen |= wide ? 0 : std::uint64_t(1) << k;
          }
          if (wide) {
            colours.clear();
            for (std::uint32_t i = first; i < last; ++i) colours.push_back(colour_of[incidence[i]]);
            std::sort(colours.begin(), colours.end());
            clash = std::adjacent_find(colours.begin(), colours.end()) != colours.end();
          }
          if (clash) {
            found.shared = p;
            return;
          }
        }
      });
  if (particles.shared != kNone) {
    const std::size_t p = particles.shared;
    const auto [a, b] = first_clash(p);
    return fail("colour " + std::to_string(colour_of[a]) + ": " + graph.describe_constraint(a) +
                " and " + graph.describe_constraint(b) + " share movable particle " +
                std::to_string(p));
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
