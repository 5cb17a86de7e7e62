#pragma once
// The subcommands that read images and score detectors (`purkinje track`,
// `purkinje score`) and calibrate gaze (`purkinje calibrate`): argument
// parsing stays in purkinje.cpp.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "purkinje/trackers/gaze.h"

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

struct CalibrateRequest {
  std::string scene_file;  // with a screen; its eye is the one followed
  std::string output_dir;
  int grid = 8;              // test targets: grid x grid over the screen, at each head position
  int calibration_grid = 3;  // calibration targets, at the scene's eye position
  std::vector<std::array<double, 3>> head_moves;  // mm, test positions beside the scene's
  // The tracker's anterior cornea: apex radius (mm) and asphericity Q;
  // absent: the scene eye's.
  std::optional<std::array<double, 2>> tracker_cornea;
  bool fit_radius = false;
  bool fit_pupil_depth = false;
  // The detectors' noise (s.d., px) the reported uncertainties assume;
  // absent: measured against the labels of the noise frames (below).
  std::optional<double> glint_noise_px, pupil_noise_px;
  // Frames of the eye at its place fixating random screen points, rendered
  // only to measure the detectors' noise against their labels; 0: the
  // calibration frames serve (nine measure a deviation to about 12%).
  int noise_frames = 64;
  std::uint64_t seed = 1;       // of the first frame's render; each next frame the next
  bool quiet = false;           // no progress on stderr
};

int run_track(const TrackRequest& request);
int run_calibrate(const CalibrateRequest& request);
int run_score(const ScoreRequest& request);

}  // namespace purkinje::tools
