// `tessera info`: what this build is and what the machine offers it.
#include <iostream>
#include <thread>

#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/core/config.hpp>
#include <tessera/core/real.hpp>
#include <tessera/core/simd.hpp>
#include <tessera/parallel/schedule.hpp>
#include <tessera/parallel/threads.hpp>

#include "commands.hpp"
#include "summary.hpp"

namespace tessera::cli {

CLI::App* add_info_command(CLI::App& app, InfoOptions& options) {
  CLI::App* command = app.add_subcommand(
      "info", "Version, build type, precision, SIMD target, threads, strategies and modes");
  command->add_flag("--json", options.json, "print one JSON object");
  return command;
}

int info_command(const InfoOptions& options) {
  Summary summary;
  summary.add("version", std::string(TESSERA_VERSION_STRING));
  summary.add("build_type", std::string(TESSERA_BUILD_TYPE));
  summary.add("precision", std::string(sizeof(Real) == sizeof(double) ? "double" : "float"));
  summary.add("simd_target", active_simd_target());
  summary.add("simd_targets_available", available_simd_targets());
  summary.add("threads_available", worker_threads(0));  // what no --threads takes
  summary.add("hardware_threads", std::size_t(std::thread::hardware_concurrency()));
  const ColouringRegistry registry = ColouringRegistry::with_builtin_strategies();
  std::vector<std::string> strategies;
  for (std::string_view name : registry.names()) strategies.emplace_back(name);
  summary.add("strategies", strategies);
  std::vector<std::string> modes;
  for (SolverMode mode : {SolverMode::gs, SolverMode::jacobi, SolverMode::hybrid, SolverMode::sequential})
    modes.emplace_back(solver_mode_name(mode));
  summary.add("modes", modes);
  if (options.json) {
    summary.print(std::cout, true);
    return 0;
  }
  summary.print(std::cout, false);
  std::cout << "\nstrategies:\n";
  for (std::string_view name : registry.names())
    std::cout << "  " << name << std::string(name.size() < 16 ? 16 - name.size() : 1, ' ')
              << registry.get(name).description() << '\n';
  return 0;
}

}  // namespace tessera::cli
