// Running several coloured phases in one parallel region, with static shares.
//
// Why: a parallel_for per colour costs a fork and a join per colour (TBB wakes its workers,
// hands out the range, waits for the last one): about 15 % of a 2-thread cloth substep with 20
// colours. Here the threads enter once per iteration and meet at a spin barrier between
// colours. Each thread keeps the same share of every phase each time (as static_partitioner
// does), so its particles stay in its cache; the earlier try that let threads claim blocks
// dynamically lost that and was slower.
//
//   thread t:  phase 0 share t │ wait for phase 0 │ phase 1 share t │ wait ... │ phase P-1 share t
//              (a share is run by whoever claims it first: its owner, or a thread that has
//              waited past kHelpAfterSpins for it, so the region finishes even when TBB runs
//              fewer threads than shares, e.g. more threads asked for than the machine has)
//
// Waiting: spin (the other threads arrive within microseconds), then run what nobody has
// claimed, then sleep on the phase's count (a futex, std::atomic::wait) until the phase
// is done. The sleep is for a busy machine: a thread the OS has descheduled in the middle of
// its share holds the phase for a whole time slice, and a waiter that kept spinning or
// yielding took the core it needed. Measured in docs/performance.md, "The phase region on a
// busy machine". (The spins are counted in pauses, whose length varies by CPU, about 10 to 150
// cycles; on a CPU without a pause instruction each spin is a yield.)
//
// A share's blocks are one colour's: no two touch the same movable particle, so who runs a
// share does not change a bit of the result, and the phases run strictly in order. A share is
// the same slice of each of the phase's families (for_share_of_phase, below).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <thread>

#include <tessera/parallel/schedule.hpp>

#if defined(__x86_64__) || defined(_M_X64)
#include <immintrin.h>
#endif

namespace tessera::detail {

/// Pauses before a waiting thread runs a share nobody has claimed yet: about 10–100 µs by CPU
/// (a pause is some 10 to 150 cycles), well past the microseconds threads that run take to
/// arrive, short against a thread that never comes.
inline constexpr std::uint32_t kHelpAfterSpins = 2048;
/// Pauses before a waiting thread, having run what nobody claimed, sleeps until the phase is
/// done: the share it waits for is running, or its thread has been
/// descheduled. Long enough that a waiter on an idle machine rarely sleeps (a wake-up costs
/// the finishing thread a futex call and the waiter tens of microseconds).
inline constexpr std::uint32_t kSleepAfterSpins = 4 * kHelpAfterSpins;

inline void spin_pause() {
#if defined(__x86_64__) || defined(_M_X64)
  _mm_pause();
#else
  std::this_thread::yield();
#endif
}

/// The claims and completion counts of one region's phases × shares.
class PhaseRegion {
 public:
  PhaseRegion() = default;
  PhaseRegion(std::size_t phases, std::size_t shares) { reset(phases, shares); }

  /// Ready for a region of phases × shares, nothing claimed or done; allocates only when the
  /// region is larger than any before (the solver keeps one and resets it per iteration).
  /// Not while a region runs.
  void reset(std::size_t phases, std::size_t shares) {
    if (phases * shares > claimed_capacity_) {
      claimed_ = std::make_unique<std::atomic<std::uint8_t>[]>(phases * shares);
      claimed_capacity_ = phases * shares;
    }
    if (phases > done_capacity_) {
      done_ = std::make_unique<std::atomic<std::uint32_t>[]>(phases);
      done_capacity_ = phases;
    }
    phases_ = phases;
    shares_ = shares;
    waits_.long_waits.store(0, std::memory_order_relaxed);
    waits_.sleeps.store(0, std::memory_order_relaxed);
    for (std::size_t i = 0; i < phases * shares; ++i) claimed_[i].store(0, std::memory_order_relaxed);
    for (std::size_t k = 0; k < phases; ++k) done_[k].store(0, std::memory_order_relaxed);
  }

  /// The waits since reset() that lasted kHelpAfterSpins (a thread late, absent or
  /// descheduled): what a region one thread runs alone avoids after the first.
  std::size_t long_waits() const { return waits_.long_waits.load(std::memory_order_relaxed); }
  /// The waits since reset() that slept (kSleepAfterSpins).
  std::size_t sleeps() const { return waits_.sleeps.load(std::memory_order_relaxed); }

  /// Thread `share`'s part of the region: run_share(phase, share) for every share it claims.
  /// A thread that had to run another's share (its thread was late or absent: TBB gave the
  /// region fewer threads than shares, or the OS descheduled one) runs the unclaimed shares
  /// of the next phase right after its own, without waiting first, until it finds them
  /// claimed by their owners: so a region that one thread runs alone costs no wait per phase.
  /// Share 0's thread starts a region the way it ended the last one (alone or not): a region
  /// run by one thread alone, region after region, then waits for nobody at all.
  template <class RunShare>
  void run(std::size_t share, RunShare&& run_share) {
    if (phases_ == 0) return;
    bool alone = share == 0 && waits_.alone_at_end.load(std::memory_order_relaxed);
    for (std::size_t k = 0; k < phases_; ++k) {
      if (k != 0 && wait_for(k - 1, run_share)) alone = true;
      run_if_claimed(k, share, run_share);
      if (alone) alone = run_unclaimed(k, run_share);
    }
    if (wait_for(phases_ - 1, run_share)) alone = true;
    if (share == 0) waits_.alone_at_end.store(alone, std::memory_order_relaxed);
  }

 private:
  /// Runs every share of `phase` nobody has claimed; whether there was one.
  template <class RunShare>
  bool run_unclaimed(std::size_t phase, RunShare& run_share) {
    bool ran = false;
    for (std::size_t s = 0; s < shares_; ++s) ran |= run_if_claimed(phase, s, run_share);
    return ran;
  }

  /// Runs share `share` of `phase` if nobody has claimed it; whether it did.
  template <class RunShare>
  bool run_if_claimed(std::size_t phase, std::size_t share, RunShare& run_share) {
    if (claimed_[phase * shares_ + share].exchange(1, std::memory_order_acq_rel) != 0)
      return false;
    // Counted done even if it throws, so no thread waits for it forever (the exception then
    // leaves the parallel_for).
    struct Done {
      std::atomic<std::uint32_t>& count;
      std::atomic<std::uint32_t>& sleepers;
      std::size_t shares;
      ~Done() {
        // Sequentially consistent with the sleeper's count and re-check (wait_for): either
        // the last share's thread sees the sleeper and wakes it, or the sleeper sees the
        // phase done. (A sleeper waits for the last share only: every share was claimed
        // before it slept, so there is nothing left for it to take over.)
        if (count.fetch_add(1, std::memory_order_seq_cst) + 1 == shares &&
            sleepers.load(std::memory_order_seq_cst) != 0)
          count.notify_all();
      }
    } done{done_[phase], waits_.sleepers, shares_};
    run_share(phase, share);
    return true;
  }

  /// Until every share of `phase` is done: spins; after kHelpAfterSpins runs the unclaimed
  /// ones; after kSleepAfterSpins sleeps until the phase is done. Whether it ran a share.
  template <class RunShare>
  bool wait_for(std::size_t phase, RunShare& run_share) {
    std::uint32_t spins = 0;
    bool helped = false;
    std::atomic<std::uint32_t>& done = done_[phase];
    for (std::uint32_t seen; (seen = done.load(std::memory_order_acquire)) != shares_;) {
      if (++spins < kHelpAfterSpins) {
        spin_pause();
        continue;
      }
      if (spins == kHelpAfterSpins) {
        waits_.long_waits.fetch_add(1, std::memory_order_relaxed);
        helped = run_unclaimed(phase, run_share);
      }
      if (spins < kSleepAfterSpins) {
        spin_pause();
        continue;
      }
      // Every share is claimed (above); sleep until the count moves from `seen`.
      waits_.sleeps.fetch_add(1, std::memory_order_relaxed);
      waits_.sleepers.fetch_add(1, std::memory_order_seq_cst);
      seen = done.load(std::memory_order_seq_cst);
      if (seen != shares_) done.wait(seen, std::memory_order_seq_cst);
      waits_.sleepers.fetch_sub(1, std::memory_order_seq_cst);
    }
    return helped;
  }

  /// What waiting writes, on a cache line of its own (away from the fields every share
  /// reads): the threads asleep in wait_for (read by each phase's last share), whether share
  /// 0's thread ran other shares at the end of the last region (a hint only: who runs a share
  /// never changes the result), and the counts for tests.
  struct alignas(64) Waits {
    std::atomic<std::uint32_t> sleepers{0};
    std::atomic<bool> alone_at_end{false};
    std::atomic<std::size_t> long_waits{0}, sleeps{0};
  };
  Waits waits_;
  std::size_t phases_ = 0, shares_ = 0;
  std::size_t claimed_capacity_ = 0, done_capacity_ = 0;
  std::unique_ptr<std::atomic<std::uint8_t>[]> claimed_;
  std::unique_ptr<std::atomic<std::uint32_t>[]> done_;
};

/// Share `share` of `shares` of a coloured phase: body(family, begin, end) for the same slice
/// of each family's constraints, cut at lane multiples. A colour's phase holds each family as
/// one block (Schedule::append_group, colour_contacts), so a slice is one kernel call; runs
/// of contiguous blocks of one family are joined all the same. Why per
/// family: cutting the phase's block list by count gave one thread a mixed phase's distance
/// blocks and the other its dihedral blocks, which cost 2.3 times as much each, and the first
/// waited at every barrier (the spin was 13 % of a 2-thread cloth profile; the 20×20×80 FEM
/// bar went from 244 to 305 M projections/s on 2 threads with this cut).
template <class Body>
void for_share_of_phase(std::span<const ScheduleBlock> blocks, std::size_t share,
                        std::size_t shares, Body&& body) {
  for (std::size_t b = 0; b < blocks.size();) {
    std::size_t e = b + 1;
    while (e < blocks.size() && blocks[e].family == blocks[b].family &&
           blocks[e].begin == blocks[e - 1].end)
      ++e;
    const std::size_t first = blocks[b].begin, count = blocks[e - 1].end - first;
    // The nearest lane multiple to the even cut (the last share ends at the run's end).
    const auto cut = [&](std::size_t s) {
      if (s == shares) return first + count;
      return first + std::min(count, (count * s / shares + kMaxLanes / 2) / kMaxLanes * kMaxLanes);
    };
    const std::size_t begin = cut(share), end = cut(share + 1);
    if (begin < end) body(blocks[b].family, begin, end);
    b = e;
  }
}

}  // namespace tessera::detail
