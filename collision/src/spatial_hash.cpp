// The uniform grid's build (a counting sort of the boxes by cell) and its pair queries (the
// picture is in spatial_hash.hpp).
#include <tessera/collision/spatial_hash.hpp>

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <tessera/core/error.hpp>

#include "chunked_output.hpp"

namespace tessera {

void UniformGrid::build(std::span<const Aabb> boxes, Real cell_size) {
  const std::size_t n = boxes.size();
  double lowest[3] = {0, 0, 0}, highest[3] = {0, 0, 0};  // of the lower corners
  for (double& extent : largest_extent_) extent = 0;
  if (n > 0)
    for (int axis = 0; axis < 3; ++axis) lowest[axis] = highest[axis] = boxes[0].lo[axis];
  bool finite = true;
  for (const Aabb& box : boxes)
    for (int axis = 0; axis < 3; ++axis) {
      finite &= std::isfinite(box.lo[axis]) && std::isfinite(box.hi[axis]);
      lowest[axis] = std::min(lowest[axis], double(box.lo[axis]));
      highest[axis] = std::max(highest[axis], double(box.lo[axis]));
      largest_extent_[axis] =
          std::max(largest_extent_[axis], double(box.hi[axis]) - double(box.lo[axis]));
    }
  // A NaN would make the cell count undefined (and a position that diverged is the
  // solver's failure to report, not a grid to build).
  if (!finite) throw InvalidInput("collision grid: a box has a coordinate that is not finite");
  // Points only (extent 0) get a cell from the span instead.
  const double largest = std::max({largest_extent_[0], largest_extent_[1], largest_extent_[2]});
  cell_size_ = cell_size > 0 ? double(cell_size) : largest * kCellPerExtent;
  const auto cells_at = [&](double size) {
    double cells = 1;
    for (int axis = 0; axis < 3; ++axis)
      cells *= std::floor((highest[axis] - lowest[axis]) / size) + 1;
    return cells;
  };
  const double most_cells = double(kCellsPerBox * n + 64);
  if (!(cell_size_ > 0)) {
    const double span = std::max({highest[0] - lowest[0], highest[1] - lowest[1],
                                  highest[2] - lowest[2]});
    cell_size_ = span > 0 ? span / std::cbrt(most_cells) : 1;
  }
  // Spread-out boxes: grow the cell until the grid fits (each step at least 25%).
  for (double cells = cells_at(cell_size_); cells > most_cells; cells = cells_at(cell_size_))
    cell_size_ *= std::max(1.25, std::cbrt(cells / most_cells));
  inverse_cell_size_ = 1 / cell_size_;
  for (int axis = 0; axis < 3; ++axis) {
    origin_[axis] = lowest[axis];
    dims_[axis] = std::int64_t((highest[axis] - lowest[axis]) * inverse_cell_size_) + 1;
  }
  const std::size_t cells = std::size_t(dims_[0] * dims_[1] * dims_[2]);

  cell_of_box_.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i != range.end(); ++i) {
                        const Aabb& box = boxes[i];
                        cell_of_box_[i] = std::uint32_t(
                            (cell_coordinate(box.lo[2], 2) * dims_[1] +
                             cell_coordinate(box.lo[1], 1)) * dims_[0] +
                            cell_coordinate(box.lo[0], 0));
                      }
                    });

  // Counting sort, sequential: its passes over n entries and ≤ 4n + 64 cells cost less than
  // a task fan-out at cloth sizes, and the stable scatter keeps each cell in box order.
  cell_start_.assign(cells + 1, 0);
  for (std::size_t i = 0; i < n; ++i) ++cell_start_[cell_of_box_[i] + 1];
  for (std::size_t c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
  entry_index_.resize(n);
  entry_box_.resize(n);
  // cell_start_[c] serves as cell c's write cursor, then is shifted back.
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t e = cell_start_[cell_of_box_[i]]++;
    entry_index_[e] = std::uint32_t(i);
    entry_box_[e] = boxes[i];
  }
  for (std::size_t c = cells; c > 0; --c) cell_start_[c] = cell_start_[c - 1];
  cell_start_[0] = 0;
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
  for (std::size_t e = 0; e < n; ++e) box_of[entry_index_[e]] = entry_box_[e];
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
