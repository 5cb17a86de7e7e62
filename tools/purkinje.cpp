// The purkinje command line: each subcommand's file (cli.h) parses its
// options and calls a study; this file registers them, names a mistyped
// subcommand or option, and turns what escapes into an exit code.
// Documented in docs/cli.md.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <exception>
#include <iostream>
#include <new>
#include <string>
#include <vector>

#include "cli.h"
#include "purkinje/models/output_file.h"
#include "purkinje/models/spelling.h"
#include "purkinje/models/version.h"
#include "purkinje/renderer/ray_tracer.h"

namespace {

using namespace purkinje::tools;

// The version, and the instruction set Embree's kernels will use: what a
// benchmark figure or a bug report needs beside it.
std::string version_text() {
  std::string embree;
  try {
    const purkinje::renderer::EmbreeDevice device = purkinje::renderer::embree_device();
    embree = "isa " + device.isa + " (the CPU's best: " + purkinje::renderer::cpu_isa() + ")";
  } catch (const std::exception& error) {
    embree = error.what();
  }
  return std::string("purkinje ") + purkinje::version() + "\nembree: " + embree;
}

// A mistyped subcommand would only get CLI11's "A subcommand is required".
bool unknown_subcommand(const CLI::App& app, int argc, char** argv) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) names.push_back(sub->get_name());
  if (argc < 2 || argv[1][0] == '-' || std::find(names.begin(), names.end(), argv[1]) != names.end()) return false;
  std::cerr << "purkinje: unknown subcommand '" << argv[1] << "'";
  if (const auto meant = purkinje::closest_match(argv[1], names)) std::cerr << "; did you mean '" << *meant << "'?";
  std::cerr << " (subcommands:";
  for (const std::string& name : names) std::cerr << ' ' << name;
  std::cerr << ")\n";
  return true;
}

// A mistyped option: the one meant, beside CLI11's own message.
void suggest_options(const CLI::App& app) {
  for (const CLI::App* sub : app.get_subcommands()) {
    std::vector<std::string> long_names;
    for (const CLI::Option* option : sub->get_options()) {
      for (const std::string& name : option->get_lnames()) long_names.push_back("--" + name);
    }
    for (const std::string& extra : sub->remaining()) {
      if (!extra.starts_with("--")) continue;
      const std::string typed = extra.substr(0, extra.find('='));
      if (const auto meant = purkinje::closest_match(typed, long_names)) {
        std::cerr << "purkinje " << sub->get_name() << ": unknown option " << typed << "; did you mean " << *meant
                  << "?\n";
      }
    }
  }
}

int run(int argc, char** argv) {
  CLI::App app{"purkinje: physically based simulator of eye-tracker cameras"};
  app.set_version_flag("--version", version_text());
  app.footer(kExitCodes);
  app.require_subcommand(1);
  const std::vector<Command> commands = {add_truth_command(app), add_render_command(app), add_track_command(app),
                                         add_score_command(app), add_calibrate_command(app),
                                         add_compare_command(app),
                                         add_generate_command(app), add_merge_command(app)};
  if (unknown_subcommand(app, argc, argv)) return kUsageError;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    suggest_options(app);
    // --help and --version arrive here too, with exit code 0.
    return app.exit(error) == 0 ? kOk : kUsageError;
  }
  for (const Command& command : commands) {
    if (*command.app) return command.run();
  }
  return kUsageError;  // unreachable: a subcommand is required
}

}  // namespace

// No exception leaves main: the commands catch what their inputs and
// outputs throw; what is left (memory exhausted, a bug) still gets a line
// and an exit code instead of std::terminate's abort.
int main(int argc, char** argv) {
  purkinje::remove_temporaries_on_signals();
  try {
    return run(argc, argv);
  } catch (const std::bad_alloc&) {
    std::cerr << "purkinje: error: out of memory\n";
  } catch (const std::exception& error) {
    std::cerr << "purkinje: internal error: " << error.what() << "\n";
  } catch (...) {
    std::cerr << "purkinje: internal error: an unknown exception\n";
  }
  return kBadInput;
}
