// Coloured phases run back to back in one parallel region, without a fork and join per phase.
//
// Why: a colour of the 256² cloth is ~20 k constraints, 25-30 µs of work on 2 threads, and a
// tbb::parallel_for per phase costs its spawn, the other worker's wake-up and the join (TBB's
// waits were about 15 % of a 2-thread profile of the default run, 20 phases per substep).
// Instead each thread of one region walks the phases in order, claims chunks of the phase's
// blocks from a shared counter, and counts the blocks it finished; it enters phase k + 1 only
// when phase k's count is complete:
//
//   phase k:   [claim ▸ project ▸ done += n] ... until claimed = blocks
//              wait until done = blocks (acquire: every write of phase k is visible)
//   phase k+1: ...
//
// Deadlock-free whatever the number of threads that actually join (TBB may run the region's
// tasks one after another): a thread only waits for blocks another running thread claimed.
// Deterministic: a phase's blocks share no movable particle, so who projects a block and in
// which order does not change a bit.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <thread>
#include <vector>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace tessera::detail {

class PhaseProgress {
 public:
  /// Counters for `phases` phases, all at zero.
  void reset(std::size_t phases) {
    if (counters_.size() < phases) counters_ = std::vector<Counters>(phases);
    for (std::size_t k = 0; k < phases; ++k) {
      counters_[k].claimed.store(0, std::memory_order_relaxed);
      counters_[k].done.store(0, std::memory_order_relaxed);
    }
  }

  /// Claims up to `chunk` of phase k's `blocks` blocks: [first, first + count), count 0 when
  /// every block is claimed.
  std::uint32_t claim(std::size_t k, std::uint32_t chunk, std::uint32_t blocks,
                      std::uint32_t& count) {
    const std::uint32_t first = counters_[k].claimed.fetch_add(chunk, std::memory_order_relaxed);
    count = first >= blocks ? 0 : (blocks - first < chunk ? blocks - first : chunk);
    return first;
  }

  void finished(std::size_t k, std::uint32_t count) {
    counters_[k].done.fetch_add(count, std::memory_order_release);
  }

  /// Returns once phase k's `blocks` blocks are all finished.
  void wait(std::size_t k, std::uint32_t blocks) const {
    for (std::uint32_t spins = 0; counters_[k].done.load(std::memory_order_acquire) < blocks;) {
#if defined(__x86_64__) || defined(__i386__)
      _mm_pause();
#endif
      if (++spins >= (1u << 14)) {  // the owner of the last block may have been descheduled
        std::this_thread::yield();
        spins = 0;
      }
    }
  }

 private:
  struct alignas(64) Counters {  // one cache line each: claims of one phase, not two
    std::atomic<std::uint32_t> claimed{0};
    std::atomic<std::uint32_t> done{0};
  };
  std::vector<Counters> counters_;
};

}  // namespace tessera::detail
