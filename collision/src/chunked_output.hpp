// Parallel loops whose output does not depend on the thread count: the items are cut into
// fixed chunks (not into one range per thread), each chunk appends to its own buffer, and the
// buffers are concatenated in chunk order. The buffers are kept between calls, so a detection
// per substep allocates only while its output grows.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace tessera::detail {

/// Items per chunk: large enough to amortise a task, small enough to balance 2-64 threads on
/// a 128² cloth.
inline constexpr std::size_t kCollisionChunk = 512;

template <class T>
class ChunkedOutput {
 public:
  /// Runs produce(item, buffer) for every item in [0, count), chunks of `chunk` items in
  /// parallel, and writes the buffers in chunk order to `out` (overwritten).
  template <class Produce>
  void run(std::size_t count, Produce&& produce, std::vector<T>& out,
           std::size_t chunk = kCollisionChunk) {
    run_chunks(
        count,
        [&](std::size_t begin, std::size_t end, std::vector<T>& buffer) {
          for (std::size_t item = begin; item < end; ++item) produce(item, buffer);
        },
        out, chunk);
  }
  /// The same with produce(begin, end, buffer) called once per chunk [begin, end): for a
  /// body that works on a chunk's items together (a vector at a time).
  template <class ProduceChunk>
  void run_chunks(std::size_t count, ProduceChunk&& produce, std::vector<T>& out,
                  std::size_t chunk = kCollisionChunk) {
    const std::size_t chunks = (count + chunk - 1) / chunk;
    if (buffers_.size() < chunks) buffers_.resize(chunks);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t c = range.begin(); c != range.end(); ++c) {
                          std::vector<T>& buffer = buffers_[c];
                          buffer.clear();
                          produce(c * chunk, std::min(count, (c + 1) * chunk), buffer);
                        }
                      });
    std::size_t total = 0;
    for (std::size_t c = 0; c < chunks; ++c) total += buffers_[c].size();
    out.resize(total);
    std::vector<std::size_t>& offset = offsets_;
    offset.assign(chunks + 1, 0);
    for (std::size_t c = 0; c < chunks; ++c) offset[c + 1] = offset[c] + buffers_[c].size();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 16),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t c = range.begin(); c != range.end(); ++c)
                          std::copy(buffers_[c].begin(), buffers_[c].end(),
                                    out.begin() + std::ptrdiff_t(offset[c]));
                      });
  }

 private:
  std::vector<std::vector<T>> buffers_;
  std::vector<std::size_t> offsets_;
};

}  // namespace tessera::detail
