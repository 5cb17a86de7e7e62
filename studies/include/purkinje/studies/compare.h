#pragma once
// Comparing eye models (the compare issue): a rig in two versions, the
// world (what is) and the assumed (what a tracker believes: another
// cornea, an LED moved, a lens distortion...). Over a grid of gaze
// targets, each eye fixates the same target in its own version of the
// rig; where each feature lands in the image in both versions, and how
// far it moved, is the displacement field (the geometric part: exact
// labels, no images). The study adds what the difference costs a
// tracker (calibrated on the world's frames, believing either version) and
// both versions' images. Documented in docs/compare.md.

#include <array>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "purkinje/models/scene.h"
#include "purkinje/models/truth.h"
#include "purkinje/renderer/render.h"
#include "purkinje/studies/calibration.h"
#include "purkinje/studies/simulation.h"

namespace purkinje::studies {

struct CompareSettings {
  // Targets: grid x grid cell centres over the world's screen; without a
  // screen, gaze directions on a grid in yaw and pitch within cap_deg of
  // the world eye's own visual axis.
  int grid = 9;
  double cap_deg = 15;
  int camera = 0;  // the camera both versions are seen by
  int pupil_border_points = 36;
};

// One feature at one target, in both versions: its status, and its
// pixel where the feature is in the image (status ok or outside_image).
struct FeaturePair {
  std::string feature;  // "glint.<illuminator name>", "pupil_center" (seen through the cornea), "pupil_ellipse"
  PathStatus world_status = PathStatus::no_solution, assumed_status = PathStatus::no_solution;
  std::optional<Pixel> world, assumed;
  // pupil_ellipse only: the fitted ellipses (nullopt: too few border points).
  std::optional<Ellipse> world_ellipse, assumed_ellipse;
  // assumed - world, px, when both pixels exist.
  std::optional<Pixel> displacement() const;
};

struct FieldPoint {
  // The target: on the screen (mm from its top-left corner), or the gaze
  // turn (deg, yaw toward +x and pitch up) from the eye's own visual axis.
  double x = 0, y = 0;
  std::vector<FeaturePair> features;  // each light's glint, then the pupil's centre and ellipse
};

struct DisplacementField {
  bool on_screen = true;  // targets are screen points (mm); else gaze turns (deg)
  std::vector<FieldPoint> points;  // row by row
};

// Throws std::invalid_argument naming the rule for versions that cannot
// be compared: other than one eye each, different numbers of cameras or
// lights, a camera index out of range, settings out of range.
DisplacementField displacement_field(const Scene& world, const Scene& assumed, const CompareSettings& settings = {});

// A row per target and feature: target, feature, both statuses and
// pixels, the displacement and its length, and the ellipses' centres and
// semi-axes (pupil_ellipse); empty cells where a value does not exist.
std::string displacement_csv(const DisplacementField& field);

// The scene with each eye's cornea one refracting surface, `anterior`,
// with the keratometric index 1.3375 behind it (the classic tracker's
// cornea), each eye's rotation centre, optical axis and appearance kept.
// Throws std::invalid_argument for R outside (0, 100) mm, Q outside
// (-1, 10), or an eye the anatomy rules then refuse (naming the rule).
Scene with_one_surface_cornea(const Scene& scene, const Conicoid& anterior);

// The scene with its eye's anatomy from `model`: an eye-model preset's
// name (eye_model_preset_names) or a JSON file holding the anatomy keys of
// a scene file's eye (docs/scene-format.md: model, cornea,
// posterior_cornea, aqueous_index, iris, pupil, rotation_center_depth_mm,
// sclera_radius_mm, kappa_deg), read by the scene reader. The eye keeps
// its centre of rotation, optical axis, appearance, lids and head, and
// its pupil's radius unless the file gives "pupil". Throws SceneError
// naming the file (or the preset's name), the key and the rule, for a
// file that cannot be read, keys that are not anatomy, or an anatomy the
// reader refuses; std::invalid_argument for a scene without one eye.
Scene with_eye_model(const Scene& scene, const std::string& model);

struct CompareStudySettings {
  CompareSettings field;
  // What the difference costs a tracker (when the world has a screen and
  // two or more lights): both methods calibrated on the world's frames,
  // once believing the world (the baseline: the methods' own errors) and
  // once believing the assumed version (its eye, camera, lights and
  // screen); the difference between the two is the discrepancy's cost.
  // Its tracker_rig is set by the study; exact_features is the default
  // (the geometric part: no render), grid 9, no head moves (see
  // default_head_moves).
  bool calibrate = true;
  CalibrationSettings calibration = default_calibration();
  // Both versions rendered by the field's camera with these options (the
  // same seed: the same noise where nothing changed).
  bool images = true;
  renderer::RenderOptions render;

  static CalibrationSettings default_calibration();
};

// One target at one head position by one method: its estimate believing
// each version, and the angle between them at the eye (what the
// discrepancy moves gaze by).
struct GazeChange {
  std::string position, method;
  ScreenPoint target;
  std::optional<ScreenPoint> baseline, assumed;
  std::optional<double> baseline_error_deg, assumed_error_deg, change_deg;
};

struct CompareStudy {
  DisplacementField field;
  // Present when the study calibrated (else `calibration_skipped` says why).
  std::optional<CalibrationStudy> baseline, assumed;
  std::vector<GazeChange> gaze;
  std::string calibration_skipped;
  // Present when the study rendered.
  std::optional<renderer::RenderResult> world_image, assumed_image;
  // Every number the figures show, summarized: per feature its
  // displacements, per head position and method the gaze errors (both
  // versions, and the change), the cornea's errors and the share within
  // the reported uncertainty, the images' difference; then both
  // calibrations' own results. simulation_text/json/csv write it.
  std::vector<SimulationRun> summary;
};

// The study. Throws std::invalid_argument as displacement_field and
// check_calibration_rig do (the calibration settings' ranges, the tracker
// rig's numbers) and for images of cameras of different sizes;
// std::runtime_error, naming "the world" or "the assumed version", for an
// eye whose cornea the tracker cannot take (check_calibration_rig); what
// the renderer and the calibration throw passes through. Calibration is
// skipped, and `calibration_skipped` says why, only for a world without a
// screen or without two lights. `step` is called after each render (two)
// and each calibration frame.
CompareStudy run_compare(const Scene& world, const Scene& assumed, const CompareStudySettings& settings = {},
                         const std::function<void()>& step = {});

// Head moves that keep a rig's eye in its camera's view: along the first
// camera's x by a twelfth of the eye's distance from it (two significant
// digits), and along its optical axis, away, by twice that (50 and 100 mm
// for a remote tracker at 600 mm, 2.5 and 5 mm for a headset's 30 mm);
// none without an eye or a camera.
std::vector<std::array<double, 3>> default_head_moves(const Scene& world);

// How many steps run_compare takes (for progress).
std::size_t compare_steps(const Scene& world, const CompareStudySettings& settings);

// The files write_compare writes, and those purkinje.figures adds: what
// an output check names.
std::vector<std::string> compare_outputs();

// Writes the study into `dir` all-or-nothing (models/output_file.h):
// summary.txt, .json and .csv, displacements.csv, gaze.csv (when it
// calibrated), and both versions' world/assumed .png, .exr and .json (when
// it rendered; `settings` as run). Throws OutputError naming the file.
// (Its own source file: the renderer's image files need OpenImageIO,
// which the study itself does not.)
void write_compare(const std::filesystem::path& dir, const Scene& world, const Scene& assumed,
                   const CompareStudy& study, const CompareStudySettings& settings);

// One parameter of the assumed version swept: each value's assumed
// version is the world with that parameter changed (with_parameter), and
// the study runs on it without images. Beside the curves, the noise floor:
// the detectors' noise measured on renders of the world
// (measure_detector_noise), and the model-based gaze s.d. the tracker
// reports at home with that noise (the median).
struct SweepParameter {
  std::string name, unit, meaning;
};
// The parameters a sweep can change, in order.
const std::vector<SweepParameter>& sweep_parameters();

// The world with `parameter` at `value`: an eye parameter is the assumed
// eye's value itself (its rotation centre, optical axis and appearance
// kept); led_offset_x/y/z move the first light by `value` mm from where
// the world has it. Throws std::invalid_argument naming the parameter and
// the value for an unknown parameter (listing the known) or a value the
// eye's anatomy refuses (with its rule).
Scene with_parameter(const Scene& world, const std::string& parameter, double value);

struct SweepSettings {
  std::string parameter;
  double from = 0, to = 0;
  int steps = 11;          // values from `from` to `to`, evenly spaced, both included
  int noise_frames = 16;   // renders measuring the detectors' noise floor (0: none; needs a screen)
  std::uint64_t seed = 1;  // of the noise frames' targets and renders
};

struct Sweep {
  std::string parameter, unit;
  std::vector<double> values;
  std::vector<std::vector<SimulationRun>> summaries;  // per value, run_compare's summary
  std::optional<DetectorNoise> noise;                 // nullopt: not measured
  std::optional<double> gaze_noise_deg;               // the reported model-based gaze s.d. at home, median
};

// Throws std::invalid_argument naming the rule for sweep settings out of
// range (steps 2 to 1000, two different finite ends, noise frames 0 to
// 10000) and for ends with_parameter refuses: before any work.
void check_sweep(const Scene& world, const SweepSettings& sweep);

// The sweep: `settings` for each value's study (images are left out; the
// feature noise its uncertainty assumes is the measured one, unless
// settings.calibration gives it). Throws std::invalid_argument for
// settings out of range, as with_parameter does, and as run_compare does.
Sweep run_sweep(const Scene& world, const CompareStudySettings& settings, const SweepSettings& sweep,
                const std::function<void()>& step = {});
std::size_t sweep_steps(const Scene& world, const CompareStudySettings& settings, const SweepSettings& sweep);

// A row per value, subject and quantity: `value,subject,quantity,mean,rms,max,unit`,
// subjects the features (displacement, px) and "METHOD, POSITION" (gaze
// change, deg; the model-based cornea depth error, mm, and share within
// 3 s.d. in depth, %).
std::string sweep_csv(const Sweep& sweep);
// The parameter, its unit and meaning, the values and the noise floor, as JSON.
std::string sweep_json(const Sweep& sweep);
// The files write_sweep writes, and those purkinje.figures adds.
std::vector<std::string> sweep_outputs();
// sweep.csv and sweep.json into `dir`, all-or-nothing.
void write_sweep(const std::filesystem::path& dir, const Sweep& sweep);

// A row per head position, method and target: the target, both estimates,
// both errors and the change (deg); empty cells where there is none.
std::string gaze_change_csv(const std::vector<GazeChange>& gaze);

}  // namespace purkinje::studies
