// The purkinje command line: argument parsing and exit codes only; the
// work is done by the libraries. Documented in docs/cli.md.

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <string>

#include "purkinje/models/labels.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/models/truth.h"
#include "purkinje/renderer/image_io.h"
#include "purkinje/renderer/render.h"

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

struct RenderRequest {
  std::string scene_file;
  std::string output_dir;
  std::string camera;  // empty: every camera
  std::string mode = "fast";
  int samples = purkinje::renderer::RenderOptions{}.samples_per_pixel;
  int edge_samples = purkinje::renderer::RenderOptions{}.edge_samples_per_pixel;
  std::int64_t photons = purkinje::renderer::RenderOptions{}.reference_photons_per_light;
  std::uint64_t seed = 0;
  bool no_noise = false;
  bool glint_masks = false;
  int threads = 0;
};

// File names keep to a portable set of characters.
std::string file_stem(const std::string& scene, const std::string& camera) {
  std::string stem = scene.empty() ? "scene" : scene;
  stem += "_" + camera;
  for (char& c : stem) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '-' || c == '_' || c == '.';
    if (!ok) c = '_';
  }
  return stem;
}

int run_render(const RenderRequest& request) {
  namespace r = purkinje::renderer;
  purkinje::Scene scene;
  std::vector<int> cameras;
  r::RenderOptions options;
  try {
    scene = purkinje::load_scene(request.scene_file);
    for (int i = 0; i < static_cast<int>(scene.cameras.size()); ++i) {
      if (request.camera.empty() || scene.cameras[i].name() == request.camera) cameras.push_back(i);
    }
    if (cameras.empty()) {
      throw std::invalid_argument(request.scene_file + ": no camera named '" + request.camera + "'");
    }
  } catch (const std::exception& error) {
    std::cerr << "purkinje render: error: " << error.what() << "\n";
    return kBadInput;
  }
  options.mode = request.mode == "reference" ? r::RenderMode::reference : r::RenderMode::fast;
  options.reference_photons_per_light = request.photons;
  options.samples_per_pixel = request.samples;
  options.edge_samples_per_pixel = request.edge_samples;
  options.seed = request.seed;
  options.noise = !request.no_noise;
  options.per_light_glint_masks = request.glint_masks;
  options.threads = request.threads;

  // Every camera is rendered before anything is written, so a failure
  // leaves no file at all: all images go out in one all-or-nothing set.
  std::vector<std::string> stems;
  for (int camera : cameras) {
    const std::string stem = file_stem(scene.name, scene.cameras[camera].name());
    if (std::find(stems.begin(), stems.end(), stem) != stems.end()) {
      std::cerr << "purkinje render: error: " << request.scene_file << ": cameras '"
                << scene.cameras[camera].name() << "' and another camera would both write " << stem
                << ".*: give them names that differ in letters, digits, '-', '_' or '.'\n";
      return kBadInput;
    }
    stems.push_back(stem);
  }
  const bool terminal = isatty(STDERR_FILENO) != 0;
  std::vector<r::RenderResult> results;
  for (int camera : cameras) {
    const std::string& name = scene.cameras[camera].name();
    std::mutex progress_mutex;
    int shown = -1;
    if (terminal) {
      options.progress = [&](double fraction) {
        const std::lock_guard<std::mutex> lock(progress_mutex);
        const int percent = static_cast<int>(fraction * 100);
        if (percent <= shown) return;  // workers may report out of order
        shown = percent;
        std::fprintf(stderr, "\rrendering %s: %3d%%", name.c_str(), percent);
      };
    }
    try {
      results.push_back(r::render(scene, camera, options));
    } catch (const std::exception& error) {
      if (terminal) std::fprintf(stderr, "\n");
      std::cerr << "purkinje render: error: " << request.scene_file << ": " << error.what() << "\n";
      return kBadInput;
    }
    if (terminal) std::fprintf(stderr, "\r\033[K");
  }

  std::error_code ec;
  std::filesystem::create_directories(request.output_dir, ec);
  if (ec) {
    std::cerr << "purkinje render: error: " << request.output_dir << ": cannot create the output folder: "
              << ec.message() << "\n";
    return kOutputError;
  }
  try {
    r::FileSet files;
    std::vector<r::RenderFiles> written;
    for (std::size_t i = 0; i < results.size(); ++i) {
      written.push_back(r::add_render(files, request.output_dir, stems[i], scene, results[i], options));
    }
    files.commit();
    for (const r::RenderFiles& f : written) {
      std::cout << "wrote " << f.image.string() << ", " << f.exr.filename().string() << ", "
                << f.labels.filename().string() << "\n";
    }
  } catch (const std::exception& error) {
    std::cerr << "purkinje render: error: " << error.what() << "\n";
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

  RenderRequest render_request;
  CLI::App* render = app.add_subcommand(
      "render", "Render near-infrared camera images of a scene, with AOVs and labels");
  render->footer(std::string("For each camera, writes DIR/<scene>_<camera>.png (sensor image),\n"
                             ".exr (radiance, linear electrons, AOVs) and .json (labels; see\n"
                             "docs/labels.md and docs/rendering.md).\n\n") +
                 kExitCodes);
  render->add_option("SCENE", render_request.scene_file, "Scene file (JSON, see docs/scene-format.md)")
      ->required();
  render->add_option("-o,--output", render_request.output_dir, "Output folder (created if missing)")
      ->required();
  render->add_option("--camera", render_request.camera, "Render only the camera of this name");
  render->add_option("--mode", render_request.mode,
                     "fast, or reference: brute force, to validate fast (many times slower;\n"
                     "use --samples 256 or more)")
      ->check(CLI::IsMember({"fast", "reference"}))
      ->capture_default_str();
  render->add_option("--samples", render_request.samples, "Camera rays per pixel (one: through its centre)")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  render->add_option("--edge-samples", render_request.edge_samples,
                     "Camera rays per pixel on outlines, texture and shadow edges\n"
                     "(adaptive sampling; 0 or at most --samples: off)")
      ->check(CLI::Range(0, 1 << 20))
      ->capture_default_str();
  render->add_option("--photons", render_request.photons,
                     "Reference mode: photons per light and eye for the light through the cornea")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{1} << 30))
      ->capture_default_str();
  render->add_option("--seed", render_request.seed, "Seed of jitter and sensor noise")
      ->capture_default_str();
  render->add_flag("--no-noise", render_request.no_noise, "Leave out shot and read noise");
  render->add_flag("--glint-masks", render_request.glint_masks, "Add one glint mask per illuminator to the EXR");
  render->add_option("--threads", render_request.threads, "Worker threads (0: all); output does not depend on it")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    // --help and --version arrive here too, with exit code 0.
    return app.exit(error) == 0 ? kOk : kUsageError;
  }
  if (*truth) return run_truth(truth_request);
  if (*render) return run_render(render_request);
  return kUsageError;  // unreachable: a subcommand is required
}

}  // namespace

int main(int argc, char** argv) { return run(argc, argv); }
