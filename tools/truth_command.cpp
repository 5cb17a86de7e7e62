// `purkinje truth`: a scene's exact ground truth as JSON or CSV.
// Documented in docs/cli.md and docs/labels.md.

#include <iostream>
#include <memory>
#include <string>

#include "cli.h"
#include "purkinje/models/labels.h"
#include "purkinje/models/output_file.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/models/truth.h"

namespace purkinje::tools {
namespace {

struct TruthRequest {
  std::string scene_file;
  std::string output_file;  // empty: standard output
  std::string format;       // empty: from the output file's extension, else json
  int pupil_points = TruthOptions{}.pupil_border_points;
};

int run_truth(const TruthRequest& request) {
  if (!request.output_file.empty()) refuse(check_output_file(request.output_file, {request.scene_file}));
  const Scene scene = load_scene(request.scene_file);
  TruthOptions options;
  options.pupil_border_points = request.pupil_points;
  const SceneTruth truth = compute_truth(scene, options);
  std::string format = request.format;
  if (format.empty()) format = request.output_file.ends_with(".csv") ? "csv" : "json";
  const std::string labels = format == "csv" ? truth_to_csv(scene, truth) : truth_to_json(scene, truth);

  if (request.output_file.empty()) {
    std::cout << labels << std::flush;
    if (!std::cout) throw OutputError("cannot write to standard output");
  } else {
    write_file_atomically(request.output_file, labels);
  }
  return kOk;
}

}  // namespace

Command add_truth_command(CLI::App& app) {
  auto request = std::make_shared<TruthRequest>();
  CLI::App* truth =
      app.add_subcommand("truth", "Compute the exact ground truth of a scene: glints, refracted pupil, axes");
  truth->footer(std::string("Writes JSON (default) or CSV; the fields are documented in docs/labels.md.\n\n") +
                kExitCodes);
  truth->add_option("SCENE", request->scene_file, "Scene file (JSON, see docs/scene-format.md)")->required();
  truth->add_option("-o,--output", request->output_file, "Output file, replaced atomically (default: standard output)");
  truth->add_option("--format", request->format,
                    "Output format (default: csv if the output file ends in .csv, else json)")
      ->check(CLI::IsMember({"json", "csv"}));
  truth->add_option("--pupil-points", request->pupil_points, "Number of pupil-border points per view")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  return {truth, [request] { return run_command("truth", [&] { return run_truth(*request); }); }};
}

}  // namespace purkinje::tools
