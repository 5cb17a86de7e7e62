#pragma once
// The subcommands that read images and score detectors (`purkinje track`,
// `purkinje score`) and calibrate gaze (`purkinje calibrate`): argument
// parsing stays in purkinje.cpp.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "purkinje/studies/calibration.h"

namespace purkinje::tools {

enum ExitCode : int { kOk = 0, kBadInput = 1, kUsageError = 2, kOutputError = 3 };

struct ScoreOutput {
  std::vector<std::string> inputs;  // labels files, images beside their labels, or folders of them
  std::string output_dir;
  int overlays = 10;               // the worst this many images, drawn
  double match_radius_px = 5;
  double min_pupil_overlap = 0.5;  // a pupil's ellipse, when given, must overlap the label's this much
  bool quiet = false;  // no progress on stderr
};

struct TrackRequest : ScoreOutput {
  std::string scene_file;  // the tracker's rig and nominal eye, for glint identity (empty: none)
};

struct ScoreRequest : ScoreOutput {
  std::string detections_file;
  double min_confidence = 0;  // pupils reported less confident are left out
};

struct CalibrateRequest : studies::CalibrationSettings {
  std::string scene_file;  // with a screen; its eye is the one followed
  std::string output_dir;
  bool quiet = false;  // no progress on stderr
};

int run_track(const TrackRequest& request);
int run_calibrate(const CalibrateRequest& request);
int run_score(const ScoreRequest& request);

}  // namespace purkinje::tools
