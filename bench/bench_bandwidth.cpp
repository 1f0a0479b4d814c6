// Memory-bandwidth probe of the throughput report: a STREAM-like triad a[i] = b[i] + s·c[i]
// over three arrays far larger than the caches, on 1 thread and on every hardware thread, so
// the report can put the machine's own limit beside the solver's throughput.
//
// bandwidth/triad/threads:<T>: bytes_per_second counts 3 × sizeof(double) per element (read
// b and c, write a), as STREAM does; the write-allocate read of `a` that a cache may add is
// not counted, so the figure is the bandwidth a streaming kernel can use. The arrays are
// doubles, kTriadElements of them each (3 × 256 MiB by default, well past any last-level
// cache), touched first by the threads that use them. TESSERA_TRIAD_MIB=<MiB per array>
// changes the size. Threads run in a tbb::task_arena of T workers over a static partition, so
// each worker streams the same slice in every sweep.
#include <benchmark/benchmark.h>

#include <cstddef>
#include <cstdlib>
#include <memory>
#include <string>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/partitioner.h>
#include <oneapi/tbb/task_arena.h>

namespace {

constexpr std::size_t kDefaultMiBPerArray = 256;

std::size_t triad_elements() {
  std::size_t mib = kDefaultMiBPerArray;
  if (const char* value = std::getenv("TESSERA_TRIAD_MIB"))
    if (const long parsed = std::strtol(value, nullptr, 10); parsed > 0) mib = std::size_t(parsed);
  return mib * 1024 * 1024 / sizeof(double);
}

/// Runs body(begin, end) over [0, count) on the arena's workers, the same slice per worker
/// every call.
template <class Body>
void for_slices(tbb::task_arena& arena, std::size_t count, Body&& body) {
  arena.execute([&] {
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, count, 1 << 16),
        [&](const tbb::blocked_range<std::size_t>& range) { body(range.begin(), range.end()); },
        tbb::static_partitioner());
  });
}

void BM_Triad(benchmark::State& state) {
  const int threads = int(state.range(0));
  const std::size_t count = triad_elements();
  tbb::task_arena arena(threads);
  // Not value-initialised: the first touch happens below, on the workers that stream them.
  std::unique_ptr<double[]> a(new double[count]), b(new double[count]), c(new double[count]);
  for_slices(arena, count, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      a[i] = 0;
      b[i] = 1;
      c[i] = 2;
    }
  });
  const double scalar = 3;
  double* out = a.get();
  const double* in_b = b.get();
  const double* in_c = c.get();
  for (auto _ : state) {
    for_slices(arena, count, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) out[i] = in_b[i] + scalar * in_c[i];
    });
    benchmark::ClobberMemory();
  }
  benchmark::DoNotOptimize(a[count / 2]);
  state.SetBytesProcessed(std::int64_t(state.iterations()) *
                          std::int64_t(3 * sizeof(double) * count));
  state.counters["array_mib"] = double(count * sizeof(double)) / (1024.0 * 1024.0);
}

const int kRegistered = [] {
  const int all_threads = tbb::info::default_concurrency();
  auto* b = benchmark::RegisterBenchmark("bandwidth/triad", BM_Triad);
  b->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond)->Arg(1);
  if (all_threads > 1) b->Arg(all_threads);
  return 0;
}();

}  // namespace
