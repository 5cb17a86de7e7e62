#pragma once
// The calibration study (`purkinje calibrate`; docs/calibration.md): the
// rig's eye fixates targets on its screen; each frame is rendered and
// read by purkinje's tracker (tracker.h); the model-based method and the
// polynomial are calibrated on a grid of targets at the eye's place, then
// estimate gaze over a finer grid there and after the head moves; every
// estimate is scored against the scene's truth.

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "purkinje/models/scene.h"
#include "purkinje/studies/simulation.h"
#include "purkinje/trackers/gaze.h"
#include "purkinje/trackers/image_file.h"

namespace purkinje::studies {

struct CalibrationSettings {
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
  std::uint64_t seed = 1;  // of the first frame's render; each next frame the next
  // Features from the labels instead of images: each frame's glints and
  // pupil ellipse exactly where the scene puts them (no render, no
  // detector, no noise frames). The uncertainties then assume the given
  // glint and pupil noise, or FeatureNoise's defaults; the errors are the
  // models' alone. What the compare study's geometric part runs.
  bool exact_features = false;
  // false: no uncertainty propagated from the feature noise to the
  // calibration and the estimates (each takes a dozen solves more); the
  // calibration's from its residuals' scatter, no shares within 3 s.d.
  // The compare study's baseline, whose uncertainty it does not report.
  bool propagate_uncertainty = true;
  // The rig as the tracker believes it (the compare study's assumed
  // version): its camera, lights, screen and eye (the eye's anatomy and
  // where it sits; tracker_cornea still overrides the cornea), while the
  // frames are rendered from the rig itself and scored against its truth.
  // Absent: the tracker believes the rig as it is.
  std::optional<Scene> tracker_rig;
};

// Throws std::invalid_argument for settings out of their ranges (naming
// the setting, its value and the range) or a tracker rig whose cameras and
// lights are not the rig's in number, and std::runtime_error, naming
// `rig_file`, for a rig the study cannot calibrate: no screen, fewer than
// two lights, other than one eye, or (with no tracker cornea given) an eye
// whose cornea is no ellipsoid (the tracker rig's is checked alike).
void check_calibration_rig(const Scene& rig, const std::string& rig_file, const CalibrationSettings& settings);

// The detectors' noise on renders of the rig: its eye at its place
// fixating `frames` targets uniform over the screen (drawn from `seed`, the
// renders seeded from it on), read by purkinje's tracker; the RMS of the
// errors against the labels per axis (px), clipped as the cornea fit
// rejects glints, as calibrate's noise frames measure it. Throws
// std::invalid_argument for a rig without a screen or one eye, or frames
// outside 1 to 10000.
struct DetectorNoise {
  double glint_px = 0, pupil_px = 0;  // 0: nothing measured
  int frames = 0, glint_errors = 0, pupil_errors = 0;
};
DetectorNoise measure_detector_noise(const Scene& rig, int frames, std::uint64_t seed,
                                     const std::function<void()>& step = {});

// How many frames run_calibration renders (for progress; with exact
// features, how many it computes).
std::size_t calibration_frames(const CalibrationSettings& settings);

// One head position's gaze: the screen's targets, where the eye's cornea
// centre truly was for each, and where each method put each (nullopt: no
// estimate).
struct GazePanel {
  std::string title;
  std::vector<ScreenPoint> targets;
  std::vector<Point3> cornea_centers;
  std::array<std::vector<std::optional<ScreenPoint>>, 2> estimates;  // model-based, polynomial
};

struct CalibrationStudy {
  // Per method, the calibration's results, then per head position the
  // test frames' gaze and cornea errors (every partial result kept).
  std::vector<SimulationRun> runs;
  std::string frames_csv;  // a row per test frame
  std::vector<GazePanel> panels;  // per head position
};

// The study on a rig check_calibration_rig accepts, `step` called after
// each rendered frame. Throws std::runtime_error when the detectors find
// the features in fewer than six calibration frames or the model-based
// calibration fails (with its warnings), and for failures while scoring
// ("while scoring: ..."); what the renderer, the detectors and the
// calibrations throw (std::invalid_argument for settings out of range)
// passes through.
CalibrationStudy run_calibration(const Scene& rig, const CalibrationSettings& settings,
                                 const std::function<void()>& step = {});

}  // namespace purkinje::studies
