// `purkinje calibrate`: the calibration study (studies/calibration.h) on a
// scene file, its tables and gaze map written. Documented in docs/cli.md
// and docs/calibration.md.

#include <array>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli.h"
#include "figures.h"
#include "progress.h"
#include "purkinje/models/output_file.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/studies/calibration.h"
#include "purkinje/studies/simulation.h"

namespace purkinje::tools {
namespace {

namespace fs = std::filesystem;

struct CalibrateRequest : studies::CalibrationSettings {
  std::string scene_file;  // with a screen; its eye is the one followed
  std::string output_dir;
  bool quiet = false;  // no progress on stderr
  bool no_figures = false;
  std::vector<std::string> head_move_texts;  // as given: "x,y,z" in mm
  std::string tracker_cornea_text;           // as given: "R,Q"
};

// The options given as text, read into the settings.
void read_text_options(CalibrateRequest& request) {
  for (const std::string& move : request.head_move_texts) {
    std::array<double, 3> m{};
    char comma1 = 0, comma2 = 0;
    std::istringstream in(move);
    if (!(in >> m[0] >> comma1 >> m[1] >> comma2 >> m[2]) || comma1 != ',' || comma2 != ',' || !in.eof() ||
        !std::isfinite(m[0]) || !std::isfinite(m[1]) || !std::isfinite(m[2])) {
      throw CommandError(kUsageError, "--head-move \"" + move + "\": must be three numbers \"x,y,z\" in mm");
    }
    request.head_moves.push_back(m);
  }
  if (!request.tracker_cornea_text.empty()) {
    std::array<double, 2> c{};
    char comma = 0;
    std::istringstream in(request.tracker_cornea_text);
    if (!(in >> c[0] >> comma >> c[1]) || comma != ',' || !in.eof() || !(c[0] > 0 && c[0] < 100) ||
        !(c[1] > -1 && c[1] < 10)) {
      throw CommandError(kUsageError, "--tracker-cornea \"" + request.tracker_cornea_text +
                                          "\": must be \"R,Q\" with the apex radius R in (0, 100) mm and the "
                                          "asphericity Q in (-1, 10)");
    }
    request.tracker_cornea = c;
  }
}

int run_calibrate(CalibrateRequest request) {
  read_text_options(request);
  refuse(check_output_folder(request.output_dir, {},
                             {"calibration.txt", "calibration.json", "calibration.csv", "frames.csv", "gaze_error.png",
                              "figures.json"},
                             {request.scene_file}));
  const Scene rig = load_scene(request.scene_file);
  studies::check_calibration_rig(rig, request.scene_file, request);
  studies::CalibrationStudy study;
  {
    Progress progress("calibrate: frames", studies::calibration_frames(request), request.quiet);
    study = studies::run_calibration(rig, request, [&] { progress.step(); });
  }
  const fs::path dir(request.output_dir);
  const std::string text = studies::simulation_text(study.runs);
  writing([&] {
    create_output_folder(dir);
    write_file_atomically(dir / "calibration.txt", text);
    write_file_atomically(dir / "calibration.json", studies::simulation_json(study.runs));
    write_file_atomically(dir / "calibration.csv", studies::simulation_csv(study.runs));
    write_file_atomically(dir / "frames.csv", study.frames_csv);
    studies::remove_stale_outputs(dir, {"gaze_error.png", "figures.json"});  // drawn anew, or not at all
  });
  const std::optional<std::string> no_figures = draw_figures_unless(request.no_figures, "calibration", dir);
  std::cout << text << "\nwrote " << (dir / "calibration.txt").string()
            << ", calibration.json, calibration.csv, frames.csv\n"
            << (no_figures ? "figures: not drawn: " + *no_figures : std::string("figures: gaze_error.png, figures.json"))
            << "\n";
  return kOk;
}

}  // namespace

Command add_calibrate_command(CLI::App& app) {
  auto request = std::make_shared<CalibrateRequest>();
  CLI::App* calibrate = app.add_subcommand(
      "calibrate", "Render the eye fixating targets on the scene's screen, detect, calibrate gaze, score");
  calibrate->footer(std::string("The scene needs a \"screen\" (docs/scene-format.md). Its eye fixates a\n"
                                "calibration grid, then a test grid at its own place and at each head move;\n"
                                "each frame is rendered and read by purkinje's detectors. The model-based method\n"
                                "and the second-order polynomial are calibrated and scored against the truth.\n"
                                "Writes DIR/calibration.txt, calibration.json, calibration.csv, frames.csv, and\n"
                                "gaze_error.png with figures.json (docs/calibration.md).\n\n") +
                    kExitCodes);
  calibrate->add_option("SCENE", request->scene_file, "Scene file with a screen")->required();
  calibrate->add_option("-o,--output", request->output_dir, "Output folder (created if missing)")->required();
  calibrate->add_option("--grid", request->grid, "Test targets: N x N over the screen")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  calibrate->add_option("--calibration-grid", request->calibration_grid, "Calibration targets: N x N over the screen")
      ->check(CLI::Range(3, 16))
      ->capture_default_str();
  calibrate->add_option("--head-move", request->head_move_texts,
                        "A test position beside the scene's, as the eye's move \"x,y,z\" in mm (repeatable),\n"
                        "e.g. --head-move 100,0,0 --head-move 0,0,100");
  calibrate->add_option("--tracker-cornea", request->tracker_cornea_text,
                        "The tracker's cornea as \"R,Q\": apex radius (mm) and asphericity, e.g. 7.8,0 for\n"
                        "the classic sphere (default: the scene eye's own, the correct model)");
  calibrate->add_flag("--fit-radius", request->fit_radius, "Fit the cornea's radius from all calibration frames' glints");
  calibrate->add_flag("--fit-pupil-depth", request->fit_pupil_depth,
                      "Fit the pupil's depth behind the cornea's centre with kappa");
  calibrate->add_option("--glint-noise", request->glint_noise_px,
                        "The glint detector's noise (s.d., px) the uncertainties assume\n"
                        "(default: measured against the noise frames' labels)")
      ->check(kFinite)
      ->check(CLI::Range(1e-6, 10.0));
  calibrate->add_option("--pupil-noise", request->pupil_noise_px,
                        "The pupil detector's noise (s.d., px) the uncertainties assume\n"
                        "(default: measured against the noise frames' labels)")
      ->check(kFinite)
      ->check(CLI::Range(1e-6, 10.0));
  calibrate->add_option("--noise-frames", request->noise_frames,
                        "Frames at random targets that only measure the detectors' noise (0: the calibration frames)")
      ->check(CLI::Range(0, 10000))
      ->capture_default_str();
  calibrate->add_flag("--no-figures", request->no_figures, "Data files only (no matplotlib)");
  calibrate->add_flag("--quiet", request->quiet, "No progress on standard error");
  calibrate->add_option("--seed", request->seed, "Render seed of the first frame")->check(kSeed)->capture_default_str();
  return {calibrate, [request] { return run_command("calibrate", [&] { return run_calibrate(*request); }); }};
}

}  // namespace purkinje::tools
