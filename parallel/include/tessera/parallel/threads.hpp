// What a thread count of 0 means, decided in one place: every hardware thread TBB reports for
// this process (tbb::info::default_concurrency(), which follows the CPU affinity mask). The
// solver (SolverSettings::threads), the schedule (ScheduleOptions::threads) and the tool's
// colouring arenas all ask worker_threads, so "0" cannot mean one thing in one place and
// another elsewhere. Any count gives bitwise the same results; only the speed changes.
#pragma once

#include <cstddef>

#include <oneapi/tbb/info.h>

namespace tessera {

/// `requested` when it is at least 1; for 0, every hardware thread TBB reports. Never 0.
inline std::size_t worker_threads(std::size_t requested) {
  return requested != 0 ? requested : std::size_t(tbb::info::default_concurrency());
}

}  // namespace tessera
