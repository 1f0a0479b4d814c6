// main() of every Tessera benchmark executable: Google Benchmark's, plus the build's facts in
// the report's context (SIMD target, lanes, precision), so a result says what it measured.
#include <benchmark/benchmark.h>

#include <tessera/core/config.hpp>
#include <tessera/core/simd.hpp>

int main(int argc, char** argv) {
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
