// `tessera color`: every (or one) colouring strategy on one scene, side by side: colours
// against the lower bound, colour sizes and balance, time, validity, and a hash of the colour
// of every constraint so runs with different thread counts can be compared.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>

#include <nlohmann/json.hpp>
#include <oneapi/tbb/task_arena.h>

#include <tessera/coloring/run_colouring.hpp>
#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/model_graph.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/fingerprint.hpp>
#include <tessera/parallel/threads.hpp>

#include "commands.hpp"
#include "option_checks.hpp"
#include "summary.hpp"

namespace tessera::cli {

CLI::App* add_color_command(CLI::App& app, ColorOptions& options) {
  CLI::App* command = app.add_subcommand(
      "color", "Colour a scene's constraint graph with one or every strategy and compare them");
  add_scene_options(*command, options.scene);
  command->add_option("--strategy", options.strategy, "a strategy name, or all")
      ->capture_default_str();
  command->add_option("--threads", options.threads,
                      "worker threads (default: every hardware thread; the colouring is the same "
                      "for any count)")
      ->check(integer_from(1, 4096));
  command->add_option("--seed", options.seed, "seed of the randomised strategies")
      ->capture_default_str();
  command->add_flag("--balance", options.balance, "run the balance pass after each strategy");
  command->add_flag("--locality", options.locality, "run the locality pass after each strategy");
  command->add_flag("--json", options.json, "print a JSON array, one object per strategy");
  return command;
}

int color_command(const ColorOptions& options) {
  const ColouringRegistry registry = ColouringRegistry::with_builtin_strategies();
  std::vector<std::string> names;
  if (options.strategy == "all") {
    for (std::string_view name : registry.names()) names.emplace_back(name);
  } else {
    registry.get(options.strategy);  // throws, listing the names, when unknown
    names.push_back(options.strategy);
  }
  const io::SceneDescription description = describe_scene(options.scene);
  const io::Scene scene = io::build_scene(description);
  if (scene.model.constraints.size() == 0)
    throw InvalidInput("scene '" + description.name + "' has no constraints");
  const auto graph_start = std::chrono::steady_clock::now();
  const ConstraintGraph graph = constraint_graph(scene.model);
  const double seconds_graph =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - graph_start).count();

  tbb::task_arena arena(int(worker_threads(options.threads.value_or(0))));
  const ColouringOptions colouring_options{
      .seed = options.seed, .balance = options.balance, .locality = options.locality};
  nlohmann::ordered_json results = nlohmann::ordered_json::array();
  for (const std::string& name : names) {
    ColouringRun run;
    arena.execute([&] { run = run_colouring(registry.get(name), graph, colouring_options); });
    const ColouringStatistics& s = run.statistics;
    const auto colours = run.colouring.colours();
    nlohmann::ordered_json entry;
    entry["strategy"] = name;
    entry["colours"] = s.colours;
    entry["lower_bound"] = s.lower_bound;
    entry["colours_per_lower_bound"] = s.colours_per_lower_bound;
    entry["largest"] = s.largest;
    entry["smallest"] = s.smallest;
    entry["mean"] = s.mean;
    entry["balance"] = s.balance;
    entry["size_ratio"] = s.size_ratio;
    entry["seconds"] = s.seconds;
    entry["valid"] = s.valid;
    if (!s.valid) entry["problem"] = s.problem;
    entry["colouring_hash"] = colouring_hash(colours);
    entry["sizes"] = s.sizes;
    results.push_back(std::move(entry));
  }

  if (options.json) {
    std::cout << results.dump() << '\n';
  } else {
    std::printf("scene %s: %zu particles, %zu constraints, lower bound %zu colours; graph %.3g s, "
                "%zu threads\n",
                description.name.c_str(), scene.model.particles.size(), graph.constraint_count(),
                graph.colour_lower_bound(), seconds_graph,
                std::size_t(arena.max_concurrency()));
    std::printf("%-16s %7s %8s %8s %9s %9s %8s %9s %9s  %s\n", "strategy", "colours",
                "/bound", "largest", "smallest", "balance", "lg/sm", "seconds", "valid", "hash");
    for (const auto& entry : results)
      std::printf("%-16s %7zu %8.3f %8zu %9zu %9.3f %8.3f %9.4f %9s  %s\n",
                  entry["strategy"].get<std::string>().c_str(), entry["colours"].get<std::size_t>(),
                  entry["colours_per_lower_bound"].get<double>(), entry["largest"].get<std::size_t>(),
                  entry["smallest"].get<std::size_t>(), entry["balance"].get<double>(),
                  entry["size_ratio"].get<double>(), entry["seconds"].get<double>(),
                  entry["valid"].get<bool>() ? "yes" : "NO",
                  entry["colouring_hash"].get<std::string>().c_str());
    std::fflush(stdout);
  }
  for (const auto& entry : results)
    if (!entry["valid"].get<bool>()) return 1;
  return 0;
}

}  // namespace tessera::cli
