// The purkinje command line: argument parsing and exit codes only; the
// work is done by the libraries. Documented in docs/cli.md.

#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <string>

#include "purkinje/models/labels.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/models/truth.h"

namespace {

// The project's version, as in the top-level CMakeLists.txt.
#ifndef PURKINJE_VERSION
#define PURKINJE_VERSION "0.1.0"
#endif

enum ExitCode : int { kOk = 0, kBadInput = 1, kUsageError = 2, kOutputError = 3 };

constexpr const char* kExitCodes =
    "Exit codes:\n"
    "  0  success\n"
    "  1  bad input: the scene file is missing, malformed or invalid (message on stderr)\n"
    "  2  usage error: unknown option, missing or invalid argument\n"
    "  3  output error: the output could not be written (no partial file is left)";

struct TruthRequest {
  std::string scene_file;
  std::string output_file;  // empty: standard output
  std::string format;       // empty: from the output file's extension, else json
  int pupil_points = purkinje::TruthOptions{}.pupil_border_points;
};

int run_truth(const TruthRequest& request) {
  std::string labels;
  try {
    const purkinje::Scene scene = purkinje::load_scene(request.scene_file);
    purkinje::TruthOptions options;
    options.pupil_border_points = request.pupil_points;
    const purkinje::SceneTruth truth = purkinje::compute_truth(scene, options);
    std::string format = request.format;
    if (format.empty()) {
      const bool csv_file = request.output_file.size() >= 4 &&
                            request.output_file.compare(request.output_file.size() - 4, 4, ".csv") == 0;
      format = csv_file ? "csv" : "json";
    }
    labels = format == "csv" ? purkinje::truth_to_csv(scene, truth)
                             : purkinje::truth_to_json(scene, truth);
  } catch (const std::exception& error) {
    std::cerr << "purkinje truth: error: " << error.what() << "\n";
    return kBadInput;
  }

  if (request.output_file.empty()) {
    std::cout << labels << std::flush;
    if (!std::cout) {
      std::cerr << "purkinje truth: error: cannot write to standard output\n";
      return kOutputError;
    }
    return kOk;
  }
  try {
    purkinje::write_file_atomically(request.output_file, labels);
  } catch (const std::exception& error) {
    std::cerr << "purkinje truth: error: " << error.what() << "\n";
    return kOutputError;
  }
  return kOk;
}

int run(int argc, char** argv) {
  CLI::App app{"purkinje: physically based simulator of eye-tracker cameras"};
  app.set_version_flag("--version", std::string("purkinje ") + PURKINJE_VERSION);
  app.footer(kExitCodes);
  app.require_subcommand(1);

  TruthRequest truth_request;
  CLI::App* truth = app.add_subcommand(
      "truth", "Compute the exact ground truth of a scene: glints, refracted pupil, axes");
  truth->footer(std::string("Writes JSON (default) or CSV; the fields are documented in "
                            "docs/labels.md.\n\n") +
                kExitCodes);
  truth->add_option("SCENE", truth_request.scene_file, "Scene file (JSON, see docs/scene-format.md)")
      ->required();
  truth->add_option("-o,--output", truth_request.output_file,
                    "Output file, replaced atomically (default: standard output)");
  truth->add_option("--format", truth_request.format,
                    "Output format (default: csv if the output file ends in .csv, else json)")
      ->check(CLI::IsMember({"json", "csv"}));
  truth->add_option("--pupil-points", truth_request.pupil_points,
                    "Number of pupil-border points per view")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    // --help and --version arrive here too, with exit code 0.
    return app.exit(error) == 0 ? kOk : kUsageError;
  }
  if (*truth) return run_truth(truth_request);
  return kUsageError;  // unreachable: a subcommand is required
}

}  // namespace

int main(int argc, char** argv) { return run(argc, argv); }
