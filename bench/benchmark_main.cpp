// main() of every Tessera benchmark executable: Google Benchmark's, plus the build's facts in
// the report's context (SIMD target, lanes, precision), so a result says what it measured.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <exception>

#include <tessera/core/config.hpp>
#include <tessera/core/simd.hpp>

// TESSERA_SIMD_TARGET=<name> (one of tessera::available_simd_targets(), e.g. AVX2) runs the
// benchmarks on that target instead of the best one, to compare instruction sets.
int main(int argc, char** argv) {
  if (const char* target = std::getenv("TESSERA_SIMD_TARGET")) {
    try {
      tessera::force_simd_target(target);
    } catch (const std::exception& error) {
      std::fprintf(stderr, "%s\n", error.what());
      return 2;
    }
  }
  benchmark::AddCustomContext("tessera_version", TESSERA_VERSION_STRING);
  benchmark::AddCustomContext("tessera_precision", tessera::kDoublePrecision ? "double" : "float");
  benchmark::AddCustomContext("tessera_simd_target", tessera::active_simd_target());
  benchmark::AddCustomContext("tessera_simd_lanes",
                              std::to_string(tessera::active_simd_lanes()));
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
