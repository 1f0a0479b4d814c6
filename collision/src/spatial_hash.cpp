// The spatial hash's build (a counting sort of the boxes by bucket) and its pair queries
// (the picture is in spatial_hash.hpp).
#include <tessera/collision/spatial_hash.hpp>

#include <algorithm>
#include <bit>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "chunked_output.hpp"

namespace tessera {

void SpatialHash::build(std::span<const Aabb> boxes, Real cell_size) {
  const std::size_t n = boxes.size();
  Real largest_extent = 0;
  for (const Aabb& box : boxes)
    for (int axis = 0; axis < 3; ++axis)
      largest_extent = std::max(largest_extent, box.hi[axis] - box.lo[axis]);
  // A zero cell (every box a point) would divide by zero: any positive size is correct for
  // points, and their spacing is unknown here, so 1 stands in.
  cell_size_ = std::max(cell_size, largest_extent);
  if (!(cell_size_ > 0)) cell_size_ = 1;
  inverse_cell_size_ = Real(1) / cell_size_;

  // M buckets, a power of two at least n: about one box per bucket, and a bucket is found
  // by a shift instead of a modulo.
  const std::size_t buckets = std::bit_ceil(std::max<std::size_t>(n, 2));
  bucket_shift_ = 64 - std::countr_zero(buckets);

  key_of_box_.resize(n);
  bucket_of_box_.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i != range.end(); ++i) {
                        const Aabb& box = boxes[i];
                        const std::uint64_t key =
                            cell_key(cell_coordinate(box.lo[0]), cell_coordinate(box.lo[1]),
                                     cell_coordinate(box.lo[2]));
                        key_of_box_[i] = key;
                        bucket_of_box_[i] = std::uint32_t(bucket_of(key));
                      }
                    });

  // Counting sort, sequential: its three passes over n entries cost less than a task
  // fan-out at cloth sizes, and the stable scatter keeps each bucket in box order.
  bucket_start_.assign(buckets + 1, 0);
  for (std::size_t i = 0; i < n; ++i) ++bucket_start_[bucket_of_box_[i] + 1];
  for (std::size_t b = 0; b < buckets; ++b) bucket_start_[b + 1] += bucket_start_[b];
  entry_key_.resize(n);
  entry_index_.resize(n);
  entry_box_.resize(n);
  // bucket_start_[b] serves as bucket b's write cursor, then is shifted back.
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t e = bucket_start_[bucket_of_box_[i]]++;
    entry_key_[e] = key_of_box_[i];
    entry_index_[e] = std::uint32_t(i);
    entry_box_[e] = boxes[i];
  }
  for (std::size_t b = buckets; b > 0; --b) bucket_start_[b] = bucket_start_[b - 1];
  bucket_start_[0] = 0;
}

namespace {

/// Sorts the few candidates of one query (usually under 30): insertion sort beats std::sort's
/// set-up at that size.
void sort_small(CandidatePair* first, CandidatePair* last) {
  for (CandidatePair* i = first + 1; i < last; ++i)
    for (CandidatePair* j = i; j > first && j[0].second < j[-1].second; --j) std::swap(j[0], j[-1]);
}

}  // namespace

void SpatialHash::self_pairs(std::vector<CandidatePair>& out) const {
  detail::ChunkedOutput<CandidatePair> chunks;
  const std::size_t n = size();
  // Box i's query is its own box: the entries are looked up by index, not by position.
  std::vector<Aabb> box_of(n);
  for (std::size_t e = 0; e < n; ++e) box_of[entry_index_[e]] = entry_box_[e];
  chunks.run(
      n,
      [&](std::size_t i, std::vector<CandidatePair>& buffer) {
        const std::size_t first = buffer.size();
        for_each_overlap(box_of[i], [&](std::uint32_t j) {
          if (j > i) buffer.push_back({std::uint32_t(i), j});
        });
        sort_small(buffer.data() + first, buffer.data() + buffer.size());
      },
      out);
}

void SpatialHash::query_pairs(std::span<const Aabb> queries,
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
