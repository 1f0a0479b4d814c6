// `tessera run`: build a scene, colour it, step the solver frame by frame (writing frames when
// asked), and print what it measured as aligned "key  value" lines or one JSON object.
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>

#include <nlohmann/json.hpp>
#include <oneapi/tbb/task_arena.h>

#include <tessera/coloring/run_colouring.hpp>
#include <tessera/coloring/colouring_strategy.hpp>
#include <tessera/coloring/model_graph.hpp>
#include <tessera/coloring/particle_partition.hpp>
#include <tessera/collision/self_intersections.hpp>
#include <tessera/collision/solid_contacts.hpp>
#include <tessera/core/error.hpp>
#include <tessera/core/fingerprint.hpp>
#include <tessera/parallel/solver.hpp>
#include <tessera/parallel/threads.hpp>

#include "commands.hpp"
#ifdef TESSERA_MPI
#include "distributed_run.hpp"
#endif
#include "frame_output.hpp"
#include "option_checks.hpp"
#include "progress_bar.hpp"
#include "solver_settings.hpp"
#include "summary.hpp"

namespace tessera::cli {
namespace {

/// The scene's settings with the command line's overrides.
io::SimulationSettings simulation_of(const io::SceneDescription& scene, const RunOptions& options) {
  io::SimulationSettings simulation = scene.simulation;
  if (options.frames) simulation.frames = *options.frames;
  if (options.substeps) simulation.substeps = *options.substeps;
  if (options.iterations) simulation.iterations = *options.iterations;
  if (options.threads) simulation.threads = *options.threads;
  if (options.time_step) simulation.time_step = Real(*options.time_step);
  if (options.velocity_damping) simulation.velocity_damping = Real(*options.velocity_damping);
  if (options.chebyshev) {
    if (*options.chebyshev != "on" && *options.chebyshev != "off")
      throw InvalidInput("--chebyshev: unknown value '" + *options.chebyshev + "' (known: on, off)");
    simulation.chebyshev = *options.chebyshev == "on";
  }
  if (options.chebyshev_rho) simulation.chebyshev_rho = Real(*options.chebyshev_rho);
  if (options.strategy) simulation.strategy = *options.strategy;
  if (options.mode) simulation.mode = *options.mode;
  if (options.sequential_order) simulation.sequential_order = *options.sequential_order;
  if (options.contact_scheduling) simulation.contact_scheduling = *options.contact_scheduling;
  if (options.divergence_rms) simulation.divergence_rms = Real(*options.divergence_rms);
  return simulation;
}

}  // namespace

CLI::App* add_run_command(CLI::App& app, RunOptions& options) {
  CLI::App* command = app.add_subcommand(
      "run", "Simulate a scene and print a summary (with no SCENE: the default cloth)");
  add_scene_options(*command, options.scene);
  command->add_option("--frames", options.frames, "time steps to simulate (default 60)")
      ->check(integer_from(0, std::size_t(1) << 31));
  command->add_option("--substeps", options.substeps, "substeps per frame (default: the scene's; 32, the cloth scenes " +
                          std::to_string(io::kClothSubsteps) + ")")
      ->check(integer_from(1, std::size_t(1) << 20));
  command->add_option("--iterations", options.iterations, "projection sweeps per substep (default 1)")
      ->check(integer_from(1, std::size_t(1) << 20));
  command->add_option("--dt", options.time_step, "seconds per frame (default 1/60)")
      ->check(finite_number_above(0, false, "seconds"));
  command->add_option("--damping", options.velocity_damping, "velocity damping per second (default 0)")
      ->check(finite_number_above(0, true, "1/seconds"));
  command->add_option("--threads", options.threads, "worker threads (default: every hardware thread)")
      ->check(integer_from(1, 4096));
  command->add_option("--strategy", options.strategy,
                      "colouring strategy (default stencil; `tessera info` lists them)");
  command->add_option("--mode", options.mode, "gs, jacobi, hybrid or sequential (default gs)");
  command->add_option("--sequential-order", options.sequential_order,
                      "mode sequential: groups (the reference library's greedy groups one after "
                      "another, default) or input");
  command->add_option("--contact-scheduling", options.contact_scheduling,
                      "modes gs and hybrid: jacobi (the contacts as one Jacobi set) or coloured "
                      "(first-fit, swept Gauss-Seidel after the model's constraints) (default coloured)");
  command->add_option("--particle-layout", options.particle_layout,
                      "how the sweeps hold the particles: interleaved (x, y, z, w per particle, "
                      "default) or separate (an array per coordinate); the same results");
  command->add_option("--sweep-order", options.sweep_order,
                      "modes gs and hybrid: colour-major (colour after colour), part-major (each "
                      "part's colours on one worker while its particles stay in cache, the parts "
                      "in parallel; the parts of --strategy metis or blocks, or runs of the "
                      "colouring's particle order) or auto (part-major from " +
                          std::to_string(kPartMajorFromParts) +
                          " parts up, the default; the summary names the order chosen)");
  command->add_option("--particles-per-part", options.particles_per_part,
                      "movable particles per part of strategies metis and blocks (default " +
                          std::to_string(kDefaultParticlesPerPart) +
                          "), or per run of a part-major sweep of another strategy (default " +
                          std::to_string(kDefaultParticlesPerRun) + ")")
      ->check(CLI::PositiveNumber);
  command->add_option("--divergence-rms", options.divergence_rms,
                      "a step that ends with an RMS residual above this fails (default 10; inf "
                      "turns the check off)")
      ->check(positive_number_or_inf());
  command->add_option("--chebyshev", options.chebyshev,
                      "on or off: Chebyshev acceleration of mode jacobi's iterations (default off)");
  command->add_option("--chebyshev-rho", options.chebyshev_rho,
                      "the Chebyshev acceleration's spectral radius estimate, in (0, 1) "
                      "(default 0.9)")
      ->check(finite_number_between(0, 1));
  command->add_flag("--balance", options.balance, "run the colouring's balance pass");
  command->add_option("--out", options.out,
                      "write every frame as DIR/frame_NNNNN.vtu plus DIR/frames.pvd (DIR is "
                      "created if its parent exists)");
  command->add_flag("--obj", options.write_obj, "with --out: also DIR/frame_NNNNN.obj");
  command->add_flag("--json", options.json, "print the summary as one JSON object");
  command->add_option("--distributed", options.distributed,
                      "exact or block: split the run over the ranks mpirun starts (mpirun -np N "
                      "tessera run ... --distributed exact); exact gives the positions of one "
                      "process, block exchanges once per iteration instead of once per colour");
  return command;
}

int run_command(const RunOptions& options) {
  if (options.distributed) {
#ifdef TESSERA_MPI
    // Every check runs on every rank, inside the collective agreement on failures.
    return run_distributed(options, [&] {
      if (options.write_obj && !options.out) throw InvalidInput("--obj needs --out DIR");
      RunSetup setup;
      setup.description = describe_scene(options.scene);
      setup.simulation = simulation_of(setup.description, options);
      setup.settings = solver_settings(setup.simulation);
      if (options.particle_layout)
        setup.settings.particle_layout = parse_particle_layout(*options.particle_layout);
      if (options.sweep_order &&
          parse_sweep_order(*options.sweep_order) == SweepOrder::part_major)
        throw InvalidInput("--sweep-order part-major: a distributed run exchanges its ghosts "
                           "between colours, which part-major does not keep apart");
      return setup;
    });
#else
    throw InvalidInput("--distributed: this build has no MPI (configure with TESSERA_MPI=ON, "
                       "Open MPI installed: scripts/setup)");
#endif
  }
  const auto start = std::chrono::steady_clock::now();
  if (options.write_obj && !options.out) throw InvalidInput("--obj needs --out DIR");
  const io::SceneDescription description = describe_scene(options.scene);
  const io::SimulationSettings simulation = simulation_of(description, options);
  // Names are checked before the (possibly large) scene is built.
  SolverSettings settings = solver_settings(simulation);
  if (options.particle_layout)
    settings.particle_layout = parse_particle_layout(*options.particle_layout);
  if (options.sweep_order) settings.sweep_order = parse_sweep_order(*options.sweep_order);
  const ColouringRegistry registry = ColouringRegistry::with_builtin_strategies();
  const ColouringStrategy& strategy = registry.get(simulation.strategy);
  if (options.particles_per_part && !strategy.makes_parts()) {
    if (settings.mode != SolverMode::gs && settings.mode != SolverMode::hybrid)
      throw InvalidInput("--particles-per-part: sizes the runs of a part-major sweep, which "
                         "mode " + std::string(solver_mode_name(settings.mode)) +
                         " does not run (modes gs and hybrid do; strategy " +
                         simulation.strategy + " has no parts)");
    if (settings.sweep_order == SweepOrder::colour_major) {
      std::string with_parts;
      for (const std::string_view name : registry.names())
        if (registry.get(name).makes_parts())
          with_parts += (with_parts.empty() ? "" : " or ") + std::string(name);
      throw InvalidInput("--particles-per-part: needs a strategy with parts (" + with_parts +
                         ") or --sweep-order part-major or auto (strategy " +
                         simulation.strategy + " has none)");
    }
    settings.particles_per_part = *options.particles_per_part;
  }

  io::Scene scene = io::build_scene(description);
  const std::size_t constraints = scene.model.constraints.size();
  if (constraints == 0) throw InvalidInput("scene '" + description.name + "' has no constraints");

  // Colouring, in an arena of the solver's thread count (its result does not depend on it).
  const auto colouring_start = std::chrono::steady_clock::now();
  const ConstraintGraph graph = constraint_graph(scene.model);
  tbb::task_arena arena(int(worker_threads(settings.threads)));
  std::optional<ColouringRun> colouring;
  if (settings.mode != SolverMode::sequential)
    arena.execute([&] {
      colouring = run_colouring(strategy, graph,
                                ColouringOptions{.particles_per_part =
                                                     options.particles_per_part.value_or(0),
                                                 .balance = options.balance,
                                                 .locality = true});
    });
  if (colouring && !colouring->statistics.valid)
    throw std::logic_error("strategy " + simulation.strategy + " gave an invalid colouring: " +
                           colouring->statistics.problem);
  const double seconds_coloring = seconds_since(colouring_start);

  std::optional<FrameOutput> output;
  if (options.out)
    output.emplace(*options.out, scene, colouring ? &colouring->colouring : nullptr,
                   options.write_obj);

  const std::size_t particles = scene.model.particles.size();
  const std::size_t pinned = scene.pinned.size();
  const io::CollisionDescription& contacts = description.collisions;
  std::optional<CollisionSettings> collisions;
  if (contacts.enabled()) collisions = collision_settings(scene);
  Solver solver = colouring ? Solver(std::move(scene.model), colouring->colouring, settings)
                            : Solver(std::move(scene.model), settings);
  // Self-collision works on the surface; a solid's boundary faces get particle–tet contacts.
  const auto when_self = [&](const std::vector<io::VertexIndex>& elements) {
    return contacts.self_collision ? std::span<const std::uint32_t>(elements)
                                   : std::span<const std::uint32_t>();
  };
  if (collisions)
    solver.set_collisions(*collisions, when_self(scene.surface_triangles),
                          when_self(scene.mesh.tetrahedra));
  release_freed_memory();

  if (output)
    output->write(0, 0.0, solver.positions(),
                  collisions ? std::vector<Real>(particles, Real(0)) : std::vector<Real>());
  Residual initial, final;
  if (simulation.frames == 0) initial = final = solver.residual();
  {
    ProgressBar progress(simulation.frames, "frames");
    for (std::size_t frame = 1; frame <= simulation.frames; ++frame) {
      solver.step();
      if (frame == 1) initial = solver.last_step().residual_before;
      if (output)
        output->write(frame, double(frame) * double(simulation.time_step), solver.positions(),
                      collisions ? contacts_per_particle(solver) : std::vector<Real>());
      progress.update(frame);
    }
  }
  if (simulation.frames > 0) final = solver.last_step().residual_after;

  const SolverStatistics& statistics = solver.statistics();
  Summary summary;
  summary.add("scene", description.name);
  summary.add("particles", particles);
  summary.add("pinned", pinned);
  summary.add("constraints", constraints);
  summary.add("colours", colouring ? colouring->statistics.colours : 0);
  summary.add("colour_lower_bound", graph.colour_lower_bound());
  summary.add("strategy", colouring ? simulation.strategy : std::string("none"));
  summary.add("mode", std::string(solver_mode_name(settings.mode)));
  summary.add("particle_layout", std::string(particle_layout_name(settings.particle_layout)));
  // The order swept (auto: the one it chose).
  const SweepOrder swept = solver.schedule().options().sweep_order;
  summary.add("sweep_order", std::string(sweep_order_name(swept)));
  // The parts the sweep ran (part-major: the colouring's, or runs of its particle order);
  // colour-major: the colouring's, which it does not use.
  std::size_t parts = statistics.part_count;
  if (swept != SweepOrder::part_major && colouring)
    parts = colouring->colouring.part_count();
  summary.add("parts", parts);
  // Of the constraints, those the parts sweep (the rest cross parts: the colour phases).
  summary.add("part_constraints", statistics.part_constraints);
  summary.add("threads", statistics.threads);
  summary.add("frames", simulation.frames);
  summary.add("substeps", simulation.substeps);
  summary.add("iterations", simulation.iterations);
  summary.add("time_step", double(simulation.time_step));
  summary.add("seconds_coloring", seconds_coloring);
  summary.add("seconds_schedule", statistics.seconds_schedule);
  summary.add("seconds_stepping", statistics.seconds_stepping);
  summary.add("seconds_projection", statistics.seconds_projection);
  summary.add("projections", statistics.projections);
  summary.add("projections_per_second",
              statistics.seconds_projection > 0 ? double(statistics.projections) / statistics.seconds_projection : 0.0);
  summary.add("steps_in_one_region", statistics.steps_in_one_region);
  add_residuals(summary, initial, final);
  // Where the largest residual is, in the model's numbering (Model::constraint_id), so a user
  // can look at the constraint that limits the run.
  if (final.constraints != 0) {
    const FamilyResidual& worst = final.of(final.worst_family);
    summary.add("residual_worst", std::string(family_name(final.worst_family)) +
                                      (worst.worst_is_contact    ? " contact "
                                       : worst.worst_is_dynamic ? " dynamic constraint "
                                                                : " constraint ") +
                                      std::to_string(worst.worst));
  }
  if (const CollisionStage* stage = solver.collisions()) {
    const CollisionStatistics& found = stage->statistics();
    const std::vector<Vector3r> positions = solver.positions();
    summary.add("contacts_mean", found.contacts_mean());
    summary.add("contacts_max", found.contacts_max);
    summary.add("seconds_collision", found.seconds_detection);
    if (stage->settings().self_collision)
    {
      summary.add("self_collision_detections", found.self_detections);
      summary.add("self_collision_reboxes", found.self_reboxes);
      // seconds_collision's self-collision part, by what each substep did.
      summary.add("seconds_self_collision_built", found.seconds_self_built);
      summary.add("seconds_self_collision_reboxed", found.seconds_self_reboxed);
      summary.add("seconds_self_collision_refined", found.seconds_self_refined);
    }
    // What ran: modes jacobi and sequential keep their own way whatever the setting says.
    const SolverMode mode = solver.settings().mode;
    const bool coloured = solver.settings().contact_scheduling == ContactScheduling::coloured &&
                          (mode == SolverMode::gs || mode == SolverMode::hybrid);
    summary.add("contact_scheduling", mode == SolverMode::sequential ? std::string("sequential")
                                      : coloured ? std::string("coloured")
                                                 : std::string("jacobi"));
    summary.add("seconds_contact_scheduling", statistics.seconds_contact_scheduling);
    if (coloured && statistics.contact_substeps != 0) {
      summary.add("contact_colours_mean", double(statistics.contact_colours_total) /
                                              double(statistics.contact_substeps));
      summary.add("contact_colours_max", statistics.contact_colours_max);
      summary.add("contacts_overflowed", statistics.contacts_overflowed);
    }
    // The deepest point inside a collider or inside another solid body.
    summary.add("penetration_max",
                double(std::max(penetration_depth(stage->settings().colliders, positions),
                                solid_penetration_depth(positions, scene.mesh.tetrahedra))));
    summary.add("self_intersections",
                count_self_intersections(positions, scene.surface_triangles));
  }
  summary.add("state_hash", state_hash(solver.positions()));
  if (output) {
    summary.add("output", output->folder().string());
    summary.add("files_written", output->files_written());
  }
  summary.add("seconds_total", seconds_since(start));
  summary.print(std::cout, options.json);
  return 0;
}

}  // namespace tessera::cli
