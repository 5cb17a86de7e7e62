// `purkinje render`: a scene's cameras, or a resumable set of variations
// of its eye, rendered to images and labels (studies/render_set.h).
// Documented in docs/cli.md and docs/rendering.md.

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <iostream>
#include <memory>
#include <mutex>
#include <numbers>
#include <string>

#include "cli.h"
#include "progress.h"
#include "purkinje/models/check.h"
#include "purkinje/studies/render_set.h"

namespace purkinje::tools {
namespace {

struct RenderRequest {
  studies::RenderSetRequest set;
  std::string mode = "fast";
  std::string pixel_filter = "box";
  bool no_noise = false;
  bool quiet = false;  // no progress on stderr
  double max_gaze_deg = 30;
};

// One camera's progress as a redrawn line on a terminal.
class CameraProgress {
 public:
  void show(const std::string& camera, double fraction) {
    const std::lock_guard<std::mutex> lock(mutex_);
    const int percent = static_cast<int>(fraction * 100);
    if (camera != camera_) shown_ = -1;
    camera_ = camera;
    if (percent <= shown_) return;  // workers may report out of order
    shown_ = percent;
    std::fprintf(stderr, "\rrendering %s: %3d%%", camera.c_str(), percent);
  }
  void clear() {
    const std::lock_guard<std::mutex> lock(mutex_);
    std::fprintf(stderr, "\r\033[K");
    camera_.clear();
  }

 private:
  std::mutex mutex_;
  std::string camera_;
  int shown_ = -1;
};

int run_render(RenderRequest request) {
  if (request.set.resume && request.set.variations == 0) {
    throw CommandError(kUsageError, "--resume continues a --variations run: give --variations N");
  }
  studies::RenderSetRequest& set = request.set;
  if (set.variation_range.min_pupil_radius_mm > set.variation_range.max_pupil_radius_mm) {
    throw CommandError(kUsageError, "--min-pupil-mm " + check::format_number(set.variation_range.min_pupil_radius_mm) +
                                        " is above --max-pupil-mm " +
                                        check::format_number(set.variation_range.max_pupil_radius_mm));
  }
  set.variation_range.max_gaze_turn_rad = request.max_gaze_deg * (std::numbers::pi / 180);
  set.options.mode = request.mode == "reference" ? renderer::RenderMode::reference : renderer::RenderMode::fast;
  set.options.noise = !request.no_noise;
  set.options.pixel_filter.kind = *renderer::pixel_filter_kind(request.pixel_filter);  // checked by CLI11

  const studies::RenderPlan plan = studies::plan_render_set(set);
  refuse(check_output_folder(set.output_dir, {}, studies::render_set_outputs(plan), {set.scene_file}));

  CameraProgress camera_progress;
  Progress progress("render", plan.variations.size(), request.quiet || plan.variations.empty());
  studies::RenderSetHooks hooks;
  if (!request.quiet && isatty(STDERR_FILENO) != 0) {
    hooks.camera_progress = [&](const std::string& camera, double f) { camera_progress.show(camera, f); };
    hooks.camera_done = [&] { camera_progress.clear(); };
  }
  hooks.unit_done = [&] { progress.step(); };
  hooks.wrote = [](const renderer::RenderFiles& f) {
    std::cout << "wrote " << f.image.string() << ", " << f.exr.filename().string() << ", "
              << f.labels.filename().string() << "\n";
  };
  const studies::RenderSetOutcome outcome = studies::render_set(plan, hooks);
  if (set.resume) {
    std::cout << "resumed: " << outcome.resumed << " of " << plan.variations.size() << " variations were complete\n";
  }
  if (!outcome.index_file.empty()) std::cout << "wrote " << outcome.index_file.string() << "\n";
  return kOk;
}

}  // namespace

Command add_render_command(CLI::App& app) {
  auto request = std::make_shared<RenderRequest>();
  studies::RenderSetRequest& set = request->set;
  renderer::RenderOptions& options = set.options;
  CLI::App* render = app.add_subcommand("render", "Render near-infrared camera images of a scene, with AOVs and labels");
  render->footer(std::string("For each camera, writes DIR/<scene>_<camera>.png (sensor image),\n"
                             ".exr (radiance, linear electrons, AOVs) and .json (labels; see\n"
                             "docs/labels.md and docs/rendering.md).\n\n") +
                 kExitCodes);
  render->add_option("SCENE", set.scene_file, "Scene file (JSON, see docs/scene-format.md)")->required();
  render->add_option("-o,--output", set.output_dir, "Output folder (created if missing)")->required();
  render->add_option("--camera", set.camera, "Render only the camera of this name");
  render->add_option("--mode", request->mode,
                     "fast, or reference: brute force, to validate fast (many times slower;\n"
                     "use --samples 256 or more)")
      ->check(CLI::IsMember({"fast", "reference"}))
      ->capture_default_str();
  render->add_option("--samples", options.samples_per_pixel, "Camera rays per pixel (one: through its centre)")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  render->add_option("--edge-samples", options.edge_samples_per_pixel,
                     "Camera rays per pixel on outlines, texture and shadow edges\n"
                     "(adaptive sampling; 0 or at most --samples: off)")
      ->check(CLI::Range(0, 1 << 20))
      ->capture_default_str();
  render->add_option("--photons", options.reference_photons_per_light,
                     "Reference mode: photons per light and eye for the light through the cornea")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{1} << 30))
      ->capture_default_str();
  render->add_option("--pixel-filter", request->pixel_filter,
                     "How a pixel weighs the image about its centre: box (its own square),\n"
                     "gaussian or blackman-harris (for comparing with other renderers)")
      ->check(CLI::IsMember(renderer::pixel_filter_names()))
      ->capture_default_str();
  render->add_option("--pixel-filter-width", options.pixel_filter.width_px,
                     "Width of the pixel filter's square of support, px (0: box 1, the others 3)")
      ->check(CLI::Validator(
          [](const std::string& text) -> std::string {
            double w = -1;
            if (!CLI::detail::lexical_cast(text, w) || !renderer::pixel_filter_width_allowed(w)) {
              return std::string(renderer::kPixelFilterWidthRule) + ", not " + text;
            }
            return {};
          },
          "0 or [0.25, 16]"))
      ->capture_default_str();
  render->add_option("--seed", options.seed, "Seed of jitter and sensor noise")->check(kSeed)->capture_default_str();
  render->add_flag("--no-noise", request->no_noise, "Leave out shot and read noise");
  render->add_flag("--glint-masks", options.per_light_glint_masks, "Add one glint mask per illuminator to the EXR");
  render->add_option("--threads", options.threads, "Worker threads (0: all); output does not depend on it")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  render->add_option("--variations", set.variations,
                     "Render this many variations of the scene: its first eye turned about its\n"
                     "centre of rotation and its pupil resized, at random (0: the scene as it is)")
      ->check(CLI::Range(0, 10000000))
      ->capture_default_str();
  render->add_flag("--quiet", request->quiet, "No progress on standard error");
  render->add_flag("--resume", set.resume,
                   "Continue a killed --variations run in the same folder with the same options:\n"
                   "complete variations are kept, the rest rendered again (the same bytes as one run)");
  render->add_option("--variation-seed", set.variation_seed, "Seed of the variations' draws")
      ->check(kSeed)
      ->capture_default_str();
  render->add_option("--max-gaze-deg", request->max_gaze_deg,
                     "Variations: gaze uniform over the cap within this angle of the scene's")
      ->check(kFinite)
      ->check(CLI::Range(0.0, 90.0))
      ->capture_default_str();
  render->add_option("--min-pupil-mm", set.variation_range.min_pupil_radius_mm, "Variations: smallest pupil radius")
      ->check(kFinite)
      ->check(CLI::Range(0.1, 10.0))
      ->capture_default_str();
  render->add_option("--max-pupil-mm", set.variation_range.max_pupil_radius_mm, "Variations: largest pupil radius")
      ->check(kFinite)
      ->check(CLI::Range(0.1, 10.0))
      ->capture_default_str();
  return {render, [request] { return run_command("render", [&] { return run_render(*request); }); }};
}

}  // namespace purkinje::tools
