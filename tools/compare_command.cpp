// `purkinje compare`: the compare study (studies/compare.h) on a world
// scene and an assumed version of it, its tables, images and figures
// written. Documented in docs/cli.md and docs/compare.md.

#include <array>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "cli.h"
#include "figures.h"
#include "progress.h"
#include "purkinje/models/output_file.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/studies/compare.h"
#include "purkinje/studies/simulation.h"

namespace purkinje::tools {
namespace {

namespace fs = std::filesystem;

struct CompareRequest {
  std::string world_file, assumed_file;  // the assumed version: the world's file when not given
  std::string output_dir;
  studies::CompareStudySettings settings;
  std::string camera;                       // by name; empty: the first
  std::string world_eye, assumed_eye;       // preset names or eye-model files
  std::string assumed_cornea_text;          // as given: "R,Q"
  std::vector<std::string> head_move_texts; // as given: "x,y,z" in mm
  bool no_calibration = false, no_images = false, no_figures = false, quiet = false;
  std::string sweep_text;  // as given: "NAME=FROM:TO:STEPS"
  studies::SweepSettings sweep;
};



// "a,b,c" as numbers, or a usage error naming the option and its rule.
template <std::size_t N>
std::array<double, N> numbers(const std::string& option, const std::string& text, const std::string& rule) {
  std::array<double, N> v{};
  std::istringstream in(text);
  for (std::size_t i = 0; i < N; ++i) {
    char comma = ',';
    if ((i > 0 && !(in >> comma)) || comma != ',' || !(in >> v[i]) || !std::isfinite(v[i])) {
      throw CommandError(kUsageError, option + " \"" + text + "\": " + rule);
    }
  }
  if (!in.eof()) throw CommandError(kUsageError, option + " \"" + text + "\": " + rule);
  return v;
}

// The camera --camera names (default: the first).
int camera_index(const Scene& world, const CompareRequest& request) {
  if (request.camera.empty()) return 0;
  for (std::size_t i = 0; i < world.cameras.size(); ++i) {
    if (world.cameras[i].name() == request.camera) return static_cast<int>(i);
  }
  throw CommandError(kUsageError, "--camera \"" + request.camera + "\": " + request.world_file +
                                      " has no camera of that name");
}

// The world as the options make it: WORLD as read, with --world-eye's anatomy.
Scene with_world_eye(const CompareRequest& request, const Scene& as_read) {
  return request.world_eye.empty() ? as_read : studies::with_eye_model(as_read, request.world_eye);
}

// The options both a comparison and a sweep take, into the settings.
void read_shared_options(CompareRequest& request, const Scene& world) {
  studies::CompareStudySettings& settings = request.settings;
  settings.field.camera = camera_index(world, request);
  if (request.head_move_texts.empty()) settings.calibration.head_moves = studies::default_head_moves(world);
  for (const std::string& move : request.head_move_texts) {
    settings.calibration.head_moves.push_back(numbers<3>("--head-move", move, "must be three numbers \"x,y,z\" in mm"));
  }
  settings.calibrate = !request.no_calibration;
}

// --sweep "NAME=FROM:TO:STEPS" into the sweep's settings.
void read_sweep(CompareRequest& request) {
  const std::string& text = request.sweep_text;
  const std::string rule = "must be \"NAME=FROM:TO:STEPS\", e.g. cornea_asphericity=-0.5:0:11";
  const std::size_t equals = text.find('=');
  if (equals == std::string::npos) throw CommandError(kUsageError, "--sweep \"" + text + "\": " + rule);
  request.sweep.parameter = text.substr(0, equals);
  std::istringstream in(text.substr(equals + 1));
  char colon1 = 0, colon2 = 0;
  if (!(in >> request.sweep.from >> colon1 >> request.sweep.to >> colon2 >> request.sweep.steps) || colon1 != ':' ||
      colon2 != ':' || !in.eof()) {
    throw CommandError(kUsageError, "--sweep \"" + text + "\": " + rule);
  }
}

int run_sweep(CompareRequest request) {
  read_sweep(request);
  if (!request.assumed_file.empty()) {
    throw CommandError(kUsageError, "--sweep: the assumed versions are the world with the parameter swept: no "
                                    "ASSUMED with it");
  }
  std::vector<fs::path> inputs = {request.world_file};
  if (!request.world_eye.empty()) inputs.push_back(request.world_eye);
  refuse(check_output_folder(request.output_dir, {}, studies::sweep_outputs(), inputs));
  const Scene world = with_world_eye(request, load_scene(request.world_file));
  read_shared_options(request, world);
  const studies::CompareStudySettings& settings = request.settings;
  // Settings or ends the sweep refuses are named before any work.
  try {
    studies::check_sweep(world, request.sweep);
  } catch (const std::invalid_argument& refused) {
    throw CommandError(kUsageError, "--sweep \"" + request.sweep_text + "\": " + refused.what());
  }
  studies::Sweep sweep;
  {
    Progress progress("compare --sweep", studies::sweep_steps(world, settings, request.sweep), request.quiet);
    sweep = studies::run_sweep(world, settings, request.sweep, [&] { progress.step(); });
  }
  const fs::path dir(request.output_dir);
  writing([&] { studies::write_sweep(dir, sweep); });
  const std::optional<std::string> no_figures = draw_figures_unless(request.no_figures, "sweep", dir);
  std::cout << studies::sweep_json(sweep) << "\nwrote " << (dir / "sweep.csv").string() << " and sweep.json\n"
            << (no_figures ? "figures: not drawn: " + *no_figures : std::string("figures: sweep.png; index.md")) << "\n";
  return kOk;
}

int run_compare(CompareRequest request) {
  if (!request.sweep_text.empty()) return run_sweep(std::move(request));
  studies::CompareStudySettings& settings = request.settings;
  std::vector<fs::path> inputs = {request.world_file};
  for (const std::string& input : {request.assumed_file, request.world_eye, request.assumed_eye}) {
    if (!input.empty()) inputs.push_back(input);  // an eye model by a preset's name names no file: no harm
  }
  refuse(check_output_folder(request.output_dir, {}, studies::compare_outputs(), inputs));
  const Scene as_read = load_scene(request.world_file);
  const Scene world = with_world_eye(request, as_read);
  // The assumed version starts from ASSUMED, or from WORLD as read.
  Scene assumed = request.assumed_file.empty() ? as_read : load_scene(request.assumed_file);
  if (!request.assumed_eye.empty()) assumed = studies::with_eye_model(assumed, request.assumed_eye);
  if (!request.assumed_cornea_text.empty()) {
    const auto c = numbers<2>("--assumed-cornea", request.assumed_cornea_text, "must be \"R,Q\", e.g. 7.8,0");
    try {
      assumed = studies::with_one_surface_cornea(assumed, {c[0], c[1]});
    } catch (const std::invalid_argument& refused) {
      throw CommandError(kUsageError, "--assumed-cornea \"" + request.assumed_cornea_text + "\": " + refused.what());
    }
  }
  read_shared_options(request, world);
  settings.images = !request.no_images;
  studies::CompareStudy study;
  {
    Progress progress("compare", studies::compare_steps(world, settings), request.quiet);
    study = studies::run_compare(world, assumed, settings, [&] { progress.step(); });
  }
  const fs::path dir(request.output_dir);
  const std::string text = studies::simulation_text(study.summary);
  writing([&] { studies::write_compare(dir, world, assumed, study, settings); });
  const std::optional<std::string> no_figures = draw_figures_unless(request.no_figures, "compare", dir);
  std::cout << text << "\nwrote " << (dir / "summary.txt").string() << ", summary.json, summary.csv, displacements.csv"
            << (study.gaze.empty() ? "" : ", gaze.csv")
            << (study.world_image ? ", world and assumed .png, .exr and .json" : "") << "\n"
            << (no_figures ? "figures: not drawn: " + *no_figures
                           : std::string("figures: displacements.png") + (study.gaze.empty() ? "" : ", gaze_change.png, gaze_error.png") +
                                 (study.world_image ? ", images.png, flip.gif" : "") + ", figures.json; index.md")
            << "\n";
  return kOk;
}

}  // namespace

Command add_compare_command(CLI::App& app) {
  auto request = std::make_shared<CompareRequest>();
  studies::CompareStudySettings& s = request->settings;
  CLI::App* compare = app.add_subcommand(
      "compare", "Compare a world rig with a version the tracker assumes: feature displacements, gaze cost, images");
  compare->footer(std::string("WORLD is the rig as it is; ASSUMED (default: WORLD) a version of it that\n"
                              "differs in anything (cornea, kappa, a camera's distortion, an LED moved), or\n"
                              "--assumed-eye/--assumed-cornea change its eye (--world-eye the world's); --sweep\n"
                              "runs the study over one parameter's values instead. Over a grid of gaze targets\n"
                              "both eyes fixate the same target: each glint and the pupil's displacement in\n"
                              "the image; both tracker methods calibrated on the world's exact features,\n"
                              "believing the world and believing the assumed version: the gaze change at home\n"
                              "and after head moves; both versions rendered with one seed. Writes\n"
                              "DIR/summary.txt (.json, .csv), displacements.csv, gaze.csv, world/assumed\n"
                              ".png/.exr/.json, and the figures with index.md (docs/compare.md).\n\n") +
                  kExitCodes);
  compare->add_option("WORLD", request->world_file, "Scene file: the rig as it is")->required();
  compare->add_option("ASSUMED", request->assumed_file, "Scene file: the rig as the tracker assumes it");
  compare->add_option("-o,--output", request->output_dir, "Output folder (created if missing)")->required();
  compare->add_option("--world-eye", request->world_eye,
                      "The world eye's anatomy: a preset (keratometric, le_grand, navarro) or an eye-model\n"
                      "file (JSON: a scene eye's anatomy keys); its place, gaze and pupil size kept");
  compare->add_option("--assumed-eye", request->assumed_eye,
                      "The assumed eye's anatomy, the same way (applied to ASSUMED, or to WORLD as read)");
  compare->add_option("--assumed-cornea", request->assumed_cornea_text,
                      "The assumed eye's cornea as \"R,Q\": one refracting surface of apex radius R (mm)\n"
                      "and asphericity Q with the keratometric index 1.3375 (e.g. 7.8,0: the classic sphere)");
  compare->add_option("--grid", s.field.grid, "Displacement field: N x N targets over the screen (or the cap)")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  compare->add_option("--cap", s.field.cap_deg, "Without a screen: gaze turns up to this many degrees")
      ->check(kFinite)
      ->check(CLI::Range(1e-3, 60.0))
      ->capture_default_str();
  compare->add_option("--camera", request->camera, "The camera both versions are seen by (default: the first)");
  compare->add_option("--gaze-grid", s.calibration.grid, "Gaze test targets: N x N over the screen")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  compare->add_option("--calibration-grid", s.calibration.calibration_grid,
                      "Calibration targets: N x N over the screen")
      ->check(CLI::Range(3, 16))
      ->capture_default_str();
  compare->add_option("--head-move", request->head_move_texts,
                      "A test position beside the world's, as the eye's move \"x,y,z\" in mm (repeatable;\n"
                      "default: sideways a twelfth and away a sixth of the eye's distance from the camera)");
  compare->add_option("--glint-noise", s.calibration.glint_noise_px,
                      "The glint noise (s.d., px) the tracker's reported uncertainty assumes (default 0.05)")
      ->check(kFinite)
      ->check(CLI::Range(1e-6, 10.0));
  compare->add_option("--pupil-noise", s.calibration.pupil_noise_px,
                      "The pupil noise (s.d., px) the tracker's reported uncertainty assumes (default 0.05)")
      ->check(kFinite)
      ->check(CLI::Range(1e-6, 10.0));
  compare->add_option("--samples", s.render.samples_per_pixel, "Camera rays per pixel of both renders")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  compare->add_option("--seed", s.render.seed, "Seed of both renders")->check(kSeed)->capture_default_str();
  std::string parameters;
  for (const studies::SweepParameter& p : studies::sweep_parameters()) {
    parameters += "\n  " + p.name + (p.unit.empty() ? "" : " (" + p.unit + ")") + ": " + p.meaning;
  }
  compare->add_option("--sweep", request->sweep_text,
                      "Sweep one parameter of the assumed version, \"NAME=FROM:TO:STEPS\" (e.g.\n"
                      "cornea_asphericity=-0.5:0:11); writes sweep.csv, sweep.json, sweep.png. NAME:" + parameters);
  CLI::Option* sweep = compare->get_option("--sweep");
  for (const char* alone : {"--assumed-eye", "--assumed-cornea", "--samples", "--seed"}) {
    sweep->excludes(compare->get_option(alone));  // the sweep renders no images and makes its own assumed versions
  }
  compare->add_option("--noise-frames", request->sweep.noise_frames,
                      "Sweep: renders of the world that measure the detectors' noise floor (0: none)")
      ->check(CLI::Range(0, 10000))
      ->capture_default_str();
  compare->add_flag("--no-calibration", request->no_calibration, "No calibration: displacements and images only");
  compare->add_flag("--no-images", request->no_images, "No renders: the geometric part only")->excludes(sweep);
  compare->add_flag("--no-figures", request->no_figures, "Data files only (no matplotlib)");
  compare->add_flag("--quiet", request->quiet, "No progress on standard error");
  return {compare, [request] { return run_command("compare", [&] { return run_compare(*request); }); }};
}

}  // namespace purkinje::tools
