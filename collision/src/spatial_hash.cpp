// The uniform grid's build (a counting sort of the boxes by cell) and its pair queries (the
// picture is in spatial_hash.hpp).
#include <tessera/collision/spatial_hash.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <tessera/core/error.hpp>

#include "chunked_output.hpp"

namespace tessera {

void UniformGrid::build(std::span<const Aabb> boxes, Real cell_size) {
  const std::size_t n = boxes.size();
  // The scan compares box indices as 32-bit signed lanes (grid_scan.cpp).
  if (n > std::size_t(std::numeric_limits<std::int32_t>::max()))
    throw InvalidInput("collision grid: " + std::to_string(n) + " boxes, more than 2^31 - 1");
  const auto largest_extent = [](const Aabb& box) {
    return std::max({double(box.hi[0]) - double(box.lo[0]), double(box.hi[1]) - double(box.lo[1]),
                     double(box.hi[2]) - double(box.lo[2])});
  };
  double extent_sum = 0;
  for (const Aabb& box : boxes) {
    // A NaN would make the cell count undefined (and a position that diverged is the
    // solver's failure to report, not a grid to build).
    for (int axis = 0; axis < 3; ++axis)
      if (!std::isfinite(box.lo[axis]) || !std::isfinite(box.hi[axis]))
        throw InvalidInput("collision grid: a box has a coordinate that is not finite");
    extent_sum += largest_extent(box);
  }
  const double large = kLargeBoxPerMean * extent_sum / double(std::max<std::size_t>(n, 1));
  // Every buffer sized for all n boxes in either level: which boxes count as large moves
  // from build to build, and a settled run must not allocate when it does.
  for (auto& members : members_) members.clear(), members.reserve(n);
  for (Level& level : levels_) {
    level.grid_size = n;
    level.cell_start.reserve(kCellsPerBox * n + 64 + 1);
    level.entry_index.reserve(n + Level::kPadding);
    for (int axis = 0; axis < 3; ++axis)
      level.entry_lo[axis].reserve(n + Level::kPadding),
          level.entry_hi[axis].reserve(n + Level::kPadding);
  }
  cell_of_box_.reserve(n);
  for (std::size_t i = 0; i < n; ++i)
    members_[largest_extent(boxes[i]) > large ? 1 : 0].push_back(std::uint32_t(i));
  for (int l = 0; l < 2; ++l) build_level(levels_[l], boxes, members_[l], cell_size);
}

void UniformGrid::build_level(Level& level, std::span<const Aabb> boxes,
                              std::span<const std::uint32_t> members, Real cell_size) {
  const std::size_t n = members.size();
  double lowest[3] = {0, 0, 0}, highest[3] = {0, 0, 0};  // of the lower corners
  for (double& extent : level.largest_extent) extent = 0;
  if (n > 0)
    for (int axis = 0; axis < 3; ++axis) lowest[axis] = highest[axis] = boxes[members[0]].lo[axis];
  for (const std::uint32_t i : members)
    for (int axis = 0; axis < 3; ++axis) {
      const Aabb& box = boxes[i];
      lowest[axis] = std::min(lowest[axis], double(box.lo[axis]));
      highest[axis] = std::max(highest[axis], double(box.lo[axis]));
      level.largest_extent[axis] =
          std::max(level.largest_extent[axis], double(box.hi[axis]) - double(box.lo[axis]));
    }
  // Points only (extent 0) get a cell from the span instead.
  const double largest =
      std::max({level.largest_extent[0], level.largest_extent[1], level.largest_extent[2]});
  double size = cell_size > 0 ? double(cell_size) : largest * kCellPerExtent;
  const auto cells_at = [&](double at) {
    double cells = 1;
    for (int axis = 0; axis < 3; ++axis) cells *= std::floor((highest[axis] - lowest[axis]) / at) + 1;
    return cells;
  };
  const double most_cells = double(kCellsPerBox * n + 64);
  if (!(size > 0)) {
    const double span = std::max({highest[0] - lowest[0], highest[1] - lowest[1],
                                  highest[2] - lowest[2]});
    size = span > 0 ? span / std::cbrt(most_cells) : 1;
  }
  // Spread-out boxes: grow the cell until the grid fits (each step at least 25%).
  for (double cells = cells_at(size); cells > most_cells; cells = cells_at(size))
    size *= std::max(1.25, std::cbrt(cells / most_cells));
  level.cell_size = size;
  level.inverse_cell_size = 1 / size;
  for (int axis = 0; axis < 3; ++axis) {
    level.origin[axis] = lowest[axis];
    level.dims[axis] = std::int64_t((highest[axis] - lowest[axis]) * level.inverse_cell_size) + 1;
  }
  const std::size_t cells = std::size_t(level.dims[0] * level.dims[1] * level.dims[2]);

  cell_of_box_.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t k = range.begin(); k != range.end(); ++k) {
                        const Aabb& box = boxes[members[k]];
                        cell_of_box_[k] = std::uint32_t(
                            (level.cell_coordinate(box.lo[2], 2) * level.dims[1] +
                             level.cell_coordinate(box.lo[1], 1)) * level.dims[0] +
                            level.cell_coordinate(box.lo[0], 0));
                      }
                    });

  // Counting sort, sequential: its passes over n entries and ≤ 4n + 64 cells cost less than
  // a task fan-out at cloth sizes, and the stable scatter keeps each cell in box order.
  std::vector<std::uint32_t>& start = level.cell_start;
  start.assign(cells + 1, 0);
  for (std::size_t k = 0; k < n; ++k) ++start[cell_of_box_[k] + 1];
  for (std::size_t c = 0; c < cells; ++c) start[c + 1] += start[c];
  level.count = n;
  level.entry_index.assign(n + Level::kPadding, 0);
  for (int axis = 0; axis < 3; ++axis) {
    // The padding overlaps nothing: lo above every coordinate, hi below.
    level.entry_lo[axis].assign(n + Level::kPadding, std::numeric_limits<Real>::max());
    level.entry_hi[axis].assign(n + Level::kPadding, std::numeric_limits<Real>::lowest());
  }
  // start[c] serves as cell c's write cursor, then is shifted back.
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t e = start[cell_of_box_[k]]++;
    const Aabb& box = boxes[members[k]];
    level.entry_index[e] = members[k];
    for (int axis = 0; axis < 3; ++axis)
      level.entry_lo[axis][e] = box.lo[axis], level.entry_hi[axis][e] = box.hi[axis];
  }
  for (std::size_t c = cells; c > 0; --c) start[c] = start[c - 1];
  start[0] = 0;
}

namespace {

/// Sorts the few candidates of one query (usually under 30): insertion sort beats std::sort's
/// set-up at that size.
void sort_small(CandidatePair* first, CandidatePair* last) {
  for (CandidatePair* i = first + 1; i < last; ++i)
    for (CandidatePair* j = i; j > first && j[0].second < j[-1].second; --j) std::swap(j[0], j[-1]);
}

}  // namespace

void UniformGrid::self_pairs(std::vector<CandidatePair>& out) const {
  detail::ChunkedOutput<CandidatePair> chunks;
  const std::size_t n = size();
  // Box i's query is its own box: the entries are looked up by index, not by position.
  std::vector<Aabb> box_of(n);
  for (const Level& level : levels_)
    for (std::size_t e = 0; e < level.count; ++e)
      box_of[level.entry_index[e]] = {
          {level.entry_lo[0][e], level.entry_lo[1][e], level.entry_lo[2][e]},
          {level.entry_hi[0][e], level.entry_hi[1][e], level.entry_hi[2][e]}};
  chunks.run(
      n,
      [&](std::size_t i, std::vector<CandidatePair>& buffer) {
        const std::size_t first = buffer.size();
        for_each_overlap_above(box_of[i], std::uint32_t(i), [&](std::uint32_t j) {
          buffer.push_back({std::uint32_t(i), j});
        });
        sort_small(buffer.data() + first, buffer.data() + buffer.size());
      },
      out);
}

void UniformGrid::query_pairs(std::span<const Aabb> queries,
                              std::vector<CandidatePair>& out) const {
  detail::ChunkedOutput<CandidatePair> chunks;
  chunks.run(
      queries.size(),
      [&](std::size_t q, std::vector<CandidatePair>& buffer) {
        const std::size_t first = buffer.size();
        for_each_overlap(queries[q],
                         [&](std::uint32_t j) { buffer.push_back({std::uint32_t(q), j}); });
        sort_small(buffer.data() + first, buffer.data() + buffer.size());
      },
      out);
}

}  // namespace tessera
