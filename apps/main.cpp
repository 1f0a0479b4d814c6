// tessera: the command-line tool. Parses the command line with CLI11, runs the chosen
// subcommand, and turns every failure into one line on stderr:
//   exit 0  success (also --help, --version)
//   exit 2  bad input: unknown option or subcommand, bad value, unknown strategy or mode,
//           unreadable or malformed file (tessera::InvalidInput)
//   exit 1  anything else: a numerical failure of the solver (the state is left as it was
//           before the failing step), out of memory, an internal error
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <cstdio>
#include <exception>
#include <new>
#include <string>

#include <CLI/CLI.hpp>

#include <tessera/core/config.hpp>
#include <tessera/core/error.hpp>

#include "commands.hpp"

namespace tessera::cli {

void print_error(const std::string& command, std::string message) {
  for (char& c : message)
    if (c == '\n' || c == '\r') c = ' ';
  while (!message.empty() && message.back() == ' ') message.pop_back();
  std::fprintf(stderr, "tessera%s%s: %s\n", command.empty() ? "" : " ", command.c_str(),
               message.c_str());
  std::fflush(stderr);
}

void release_freed_memory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

}  // namespace tessera::cli

int main(int argc, char** argv) {
  using namespace tessera::cli;
  // Building a scene's colouring and schedule allocates and frees large temporaries. glibc
  // serves blocks above its mmap threshold with fresh mappings, so each one is returned on free
  // and faulted in, zeroed, again on the next: on the 40x40x160 strain bar that was 0.5 s of the
  // 0.95 s the colouring and schedule took. The tool keeps freed memory in its heap instead
  // (peak resident memory unchanged) and hands it back once the scene is built
  // (release_freed_memory). A hint: the tool runs the same if glibc refuses it.
#if defined(__GLIBC__)
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
  CLI::App app{"Tessera: Position Based Dynamics constraints solved in parallel on multicore CPUs",
               "tessera"};
  app.require_subcommand(1);
  app.set_version_flag("--version", TESSERA_VERSION_STRING);
  RunOptions run;
  ColorOptions color;
  InfoOptions info;
  CLI::App* run_app = add_run_command(app, run);
  CLI::App* color_app = add_color_command(app, color);
  CLI::App* info_app = add_info_command(app, info);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& request) {
    return app.exit(request);
  } catch (const CLI::CallForAllHelp& request) {
    return app.exit(request);
  } catch (const CLI::CallForVersion& request) {
    return app.exit(request);
  } catch (const CLI::ParseError& error) {
    std::string message = error.what();
    if (dynamic_cast<const CLI::RequiredError*>(&error) && app.get_subcommands().empty())
      message = argc > 1 && argv[1][0] != '-'
                    ? "unknown subcommand '" + std::string(argv[1]) + "' (known: run, color, info)"
                    : "a subcommand is needed: run, color or info (see tessera --help)";
    const auto selected = app.get_subcommands();
    print_error(selected.empty() ? "" : selected.front()->get_name(), message);
    return 2;
  }

  const std::string command = app.get_subcommands().front()->get_name();
  try {
    if (run_app->parsed()) return run_command(run);
    if (color_app->parsed()) return color_command(color);
    if (info_app->parsed()) return info_command(info);
    print_error("", "no subcommand");
    return 2;
  } catch (const tessera::InvalidInput& error) {
    print_error(command, error.what());
    return 2;
  } catch (const tessera::NumericalFailure& error) {
    print_error(command, error.what());
    return 1;
  } catch (const std::bad_alloc&) {
    print_error(command, "out of memory");
    return 1;
  } catch (const std::exception& error) {
    print_error(command, std::string("internal error: ") + error.what());
    return 1;
  }
}
