// `purkinje calibrate`: the calibration study (studies/calibration.h) on a
// scene file, its tables and gaze map written. Documented in docs/cli.md
// and docs/calibration.md.

#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>

#include "commands.h"
#include "output_checks.h"
#include "progress.h"
#include "purkinje/models/output_file.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/studies/calibration.h"
#include "purkinje/studies/simulation.h"
#include "purkinje/trackers/image_file.h"

namespace purkinje::tools {

namespace fs = std::filesystem;

int run_calibrate(const CalibrateRequest& request) {
  if (const auto refusal = check_output_folder(request.output_dir, {},
                                               {"calibration.txt", "calibration.json", "frames.csv", "gaze_error.png"},
                                               {request.scene_file})) {
    std::cerr << "purkinje calibrate: error: " << refusal->message << "\n";
    return refusal->exit_code;
  }
  Scene rig;
  studies::CalibrationStudy study;
  try {
    rig = load_scene(request.scene_file);
    studies::check_calibration_rig(rig, request.scene_file, request);
    Progress progress("calibrate: frames", studies::calibration_frames(request), request.quiet);
    study = studies::run_calibration(rig, request, [&] { progress.step(); });
  } catch (const std::exception& error) {
    std::cerr << "purkinje calibrate: error: " << error.what() << "\n";
    return kBadInput;
  }

  const fs::path dir(request.output_dir);
  const std::string text = studies::simulation_text(study.runs);
  try {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw std::runtime_error(dir.string() + ": cannot create the output folder: " + ec.message());
    write_file_atomically(dir / "calibration.txt", text);
    write_file_atomically(dir / "calibration.json", studies::simulation_json(study.runs));
    write_file_atomically(dir / "frames.csv", study.frames_csv);
    trackers::write_gaze_map(dir / "gaze_error.png", *rig.screen, {"model-based", "polynomial"}, study.panels);
  } catch (const std::exception& error) {
    std::cerr << "purkinje calibrate: error: " << error.what() << "\n";
    return kOutputError;
  }
  std::cout << text << "\nwrote " << (dir / "calibration.txt").string()
            << ", calibration.json, frames.csv and gaze_error.png\n";
  return kOk;
}

}  // namespace purkinje::tools
