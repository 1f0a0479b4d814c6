// The tool's subcommands. Each adds itself to the CLI11 application with its options bound to
// a struct, and is run after parsing; a command returns the process exit code and throws
// tessera::InvalidInput for bad input (main turns that into one line on stderr, exit code 2).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "scene_options.hpp"

namespace tessera::cli {

/// `tessera run [SCENE]`: simulate and print a summary.
struct RunOptions {
  SceneOptions scene;
  std::optional<std::size_t> frames, substeps, iterations, threads;
  std::optional<double> time_step, velocity_damping, divergence_rms, chebyshev_rho;
  std::optional<std::string> strategy, mode, sequential_order, out, chebyshev, contact_scheduling;
  std::optional<std::string> distributed, particle_layout, sweep_order;
  std::optional<std::size_t> particles_per_part;
  bool write_obj = false;
  bool balance = false;
  bool json = false;
};
CLI::App* add_run_command(CLI::App& app, RunOptions& options);
int run_command(const RunOptions& options);

/// `tessera color [SCENE]`: colouring statistics of one or every strategy.
struct ColorOptions {
  SceneOptions scene;
  std::string strategy = "all";
  std::optional<std::size_t> threads;
  std::uint64_t seed = 1;
  bool balance = false;
  bool locality = false;
  bool json = false;
};
CLI::App* add_color_command(CLI::App& app, ColorOptions& options);
int color_command(const ColorOptions& options);

/// `tessera info`: version, build, precision, SIMD, threads, strategies and modes.
struct InfoOptions {
  bool json = false;
};
CLI::App* add_info_command(CLI::App& app, InfoOptions& options);
int info_command(const InfoOptions& options);

/// Prints "tessera[ <command>]: <message>" as exactly one line on stderr (every failure).
void print_error(const std::string& command, std::string message);

/// While a scene is built, freed memory stays in the heap for the next temporary (set in
/// main); once it is built, this hands what is free back to the system.
void release_freed_memory();

}  // namespace tessera::cli
