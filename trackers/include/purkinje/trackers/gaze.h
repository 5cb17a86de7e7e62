#pragma once
// Gaze estimation (the calibration issue): where on a screen an eye looks,
// from one camera frame's features, by two methods, each calibrated on
// fixation targets:
//  - model-based: the glints give the cornea's centre (fit_cornea), the
//    pupil's centre seen through the cornea gives the optical axis, kappa
//    turns that into the visual axis, which meets the screen;
//  - the classic second-order polynomial from the pupil-glint vector to
//    the screen.

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "purkinje/models/camera.h"
#include "purkinje/models/illuminator.h"
#include "purkinje/models/screen.h"
#include "purkinje/models/truth.h"
#include "purkinje/trackers/glints.h"

namespace purkinje::trackers {

// One frame's features, as a tracker gives them.
struct GazeFeatures {
  std::vector<Glint> glints;  // those with their light told count
  Pixel pupil_center;         // the pupil's centre as imaged through the cornea
  // Points on the pupil's imaged outline, when the tracker has them: with
  // 5 or more, the model-based method takes the optical axis from the
  // outline (optical_axis_from_pupil_outline) instead of the centre.
  std::vector<Pixel> pupil_outline;
};

// Points around an ellipse, evenly in its parameter: a detector's pupil
// as an outline.
std::vector<Pixel> ellipse_outline(const Ellipse& ellipse, int points = 36);

// What of the pupil exact features carry: its imaged outline (the truth's
// border points) with the image of its centre; the image of the pupil's
// own centre through the cornea alone (what the centre-based model
// assumes); or the centre of the ellipse fitted to the imaged outline
// alone (what a pupil detector reports as its centre; refraction and
// perspective move it from the former).
enum class PupilFeature { outline, refracted_center, ellipse_center };

// A perfect tracker's features from a view's truth: the glints on the
// cornea, each told its light, and the pupil as chosen; nullopt when the
// pupil's chosen centre is not seen (or, for the outline, fewer than 5 of
// its points).
std::optional<GazeFeatures> exact_gaze_features(const EyeInCameraTruth& view,
                                                PupilFeature pupil = PupilFeature::outline);

// The tracker's eye for the model-based method: a spherical or conicoid
// cornea with one refracting surface, the pupil's centre on the optical
// axis.
struct GazeEyeModel {
  double cornea_radius_mm = 7.8;     // at the apex for a conicoid
  // The anterior cornea's Q (Conicoid), > -1; 0: a sphere. A conicoid's
  // glints and refraction depend on the optical axis, which the methods
  // then find together with the cornea's centre.
  double cornea_asphericity = 0;
  double pupil_depth_mm = 4.2;       // from the cornea's centre to the pupil's, along the optical axis
  double refractive_index = 1.3375;  // behind the anterior cornea
  // As EyeModel: the visual axis in the eye frame of the optical axis.
  double kappa_horizontal_rad = 0;
  double kappa_vertical_rad = 0;
};

// The visual axis for an optical axis and kappa, in the frame convention
// of purkinje's eyes (world_from_eye_rotation).
UnitVector3 visual_axis_for(const UnitVector3& optical_axis, double kappa_horizontal_rad, double kappa_vertical_rad);

// The features' noise: standard deviations of each glint's and of the
// pupil's u and v. The cornea fit weighs the glints by it, and the
// uncertainties a gaze estimate or a calibration reports come from it.
struct FeatureNoise {
  double glint_px = 0.05;  // a glint's, where it has none of its own (below)
  double pupil_px = 0.05;
  // > 0: a glint that reports its centre's standard deviation (a
  // saturated glint of BlobGlintDetector) has that times this scale, the
  // detector's own as measured against labels (add_observations); 0: all
  // glints have glint_px.
  double glint_sd_scale = 0;
};

struct ModelGaze {
  Point3 cornea_center;
  // false: cornea_center is no estimate to use (the fit's start, or a
  // conicoid's centre that did not settle with the pupil's axis)
  bool cornea_determined = false;
  // Row-major, mm^2, of the cornea's centre. With the noise given and the
  // estimate valid, from all the features' by the same propagation as
  // on_screen's: a conicoid's centre moves with the pupil's noise too,
  // through the axis its glints are fitted about. Otherwise (no noise, no
  // valid estimate, or a failed propagation) the glint fit's own, from the
  // glints' noise about a fixed axis.
  std::array<double, 9> cornea_covariance_mm2{};
  Point3 pupil_center;
  UnitVector3 optical_axis = UnitVector3::unit_z();
  UnitVector3 visual_axis = UnitVector3::unit_z();
  std::optional<ScreenPoint> on_screen;  // where the visual axis from the cornea's centre meets it
  // Row-major 2 x 2, mm^2, of on_screen (x, y) from the features' noise,
  // by first-order propagation (central differences through the method);
  // only when the noise is given.
  std::optional<std::array<double, 4>> on_screen_covariance_mm2;
  bool valid = false;                    // false: the fields above are not to be used; see warnings
  std::vector<std::string> warnings;
};

// The pupil's centre and the optical axis from the cornea's centre and the
// pupil's imaged centre: the camera ray refracted at the cornea meets the
// sphere of radius pupil_depth_mm about the centre. nullopt when the ray
// misses the cornea or that sphere.
struct OpticalAxis {
  Point3 pupil_center;
  UnitVector3 direction = UnitVector3::unit_z();
};
std::optional<OpticalAxis> optical_axis_from_pupil(const Camera& camera, const Point3& cornea_center,
                                                   const Pixel& pupil_center, const GazeEyeModel& model);

// The pupil's centre and the optical axis from the pupil's imaged outline:
// each outline point's ray, refracted at the cornea, meets the plane at
// the pupil's depth across the axis; the axis is the one through the
// centre of the circle those points make (a fixed point, found by
// iteration from `start`, or the outline's middle). Unlike the imaged
// centre, this carries no bias from refraction and perspective. nullopt
// when fewer than 5 rays meet the cornea or the iteration does not settle.
std::optional<OpticalAxis> optical_axis_from_pupil_outline(const Camera& camera, const Point3& cornea_center,
                                                           const std::vector<Pixel>& outline,
                                                           const GazeEyeModel& model,
                                                           const std::optional<UnitVector3>& start = std::nullopt);

// The whole model-based estimate for one frame. `start`: a guess of the
// cornea's centre for the glint fit. `noise` weighs the features
// (FeatureNoise's default without). With `noise` given and `propagate`
// (it costs an estimate per feature coordinate, both ways), the cornea's
// covariance and the screen point's are propagated from all the features;
// the cornea's even when the gaze misses the screen. Without, or where the estimate
// itself is not valid (the pupil's ray misses the model), the cornea's
// covariance is the glint fit's, about a fixed axis, from `noise` (or
// FeatureNoise's default); a warning says when propagation failed. Throws
// std::invalid_argument for a noise that is no deviation (glint_px and
// pupil_px finite and > 0, glint_sd_scale finite and >= 0).
ModelGaze estimate_model_gaze(const Camera& camera, const std::vector<Illuminator>& lights,
                              const GazeFeatures& features, const GazeEyeModel& model, const Screen& screen,
                              const Point3& start, const std::optional<FeatureNoise>& noise = std::nullopt,
                              bool propagate = true);

struct ModelGazeCalibrationSettings {
  bool fit_pupil_depth = false;   // with kappa
  bool fit_cornea_radius = false;  // from all frames' glints together
  // The features' noise. The cornea fit weighs each glint by it (its own
  // deviation times glint_sd_scale, or glint_px); with propagate_noise the
  // calibration's covariances come from it too.
  FeatureNoise noise{.glint_px = 0.1, .pupil_px = 0.05};  // glint_px: CorneaFitSettings::pixel_noise_px's default
  // true: the covariances of kappa (and the pupil's depth) and of the
  // centre of rotation by first-order propagation of `noise` through the
  // whole calibration (central differences: two calibrations per feature
  // coordinate). false: from the residuals' scatter, which misjudges them
  // (docs/calibration.md).
  bool propagate_noise = false;
};

struct ModelGazeCalibration {
  GazeEyeModel model;  // with the fitted values
  // Row-major covariance of (kappa horizontal, kappa vertical[, pupil
  // depth]) in rad and mm, propagated from the features' noise or from the
  // residuals' scatter (settings); empty when the targets do not
  // determine them.
  std::vector<double> covariance;
  double cornea_radius_sd_mm = 0;  // when fitted
  double rms_error_rad = 0;        // angle between the visual axes and the targets, after the fit
  std::vector<Point3> cornea_centers;  // per frame
  // The eye's centre of rotation, for a head held still: each frame's
  // cornea centre lies a fixed distance from it along its optical axis,
  // c = r + d o (linear least squares in r and d), with the s.d. of r's
  // coordinates as the covariance above. Absent when the axes are too
  // alike to place it.
  std::optional<Point3> rotation_center;
  double rotation_distance_mm = 0;  // d
  std::array<double, 3> rotation_center_sd_mm{};
  bool converged = false;
  std::vector<std::string> warnings;
};

// Calibrates kappa (and, if asked, the pupil's depth and the cornea's
// radius) from frames of the eye fixating known world points. `initial`
// gives the fixed values and the starts. Throws std::invalid_argument when
// frames and targets differ in number, there are fewer targets than
// unknowns, or settings.noise is no deviation (as estimate_model_gaze).
ModelGazeCalibration calibrate_model_gaze(const Camera& camera, const std::vector<Illuminator>& lights,
                                          const std::vector<GazeFeatures>& frames,
                                          const std::vector<Point3>& targets, const GazeEyeModel& initial,
                                          const Point3& start,
                                          const ModelGazeCalibrationSettings& settings = {});

// The classic interpolation method: the screen point as a second-order
// polynomial in the pupil-glint vector (the pupil's imaged centre less the
// mean of the glints with their light told), fitted by least squares.
class PolynomialGaze {
 public:
  // Needs at least 6 frames whose vectors are not degenerate (on one
  // conic); throws std::invalid_argument otherwise, or when frames and
  // targets differ in number.
  static PolynomialGaze calibrate(const std::vector<GazeFeatures>& frames, const std::vector<ScreenPoint>& targets);
  // nullopt when the frame has no glint with its light told.
  std::optional<ScreenPoint> estimate(const GazeFeatures& features) const;
  double rms_residual_mm() const { return rms_residual_mm_; }  // at the calibration targets

 private:
  // x and y: coefficients of 1, dx, dy, dx dy, dx^2, dy^2 (dx, dy scaled).
  std::array<double, 6> x_{}, y_{};
  double scale_px_ = 1;
  double rms_residual_mm_ = 0;
};

// The pupil-glint vector of a frame, px; nullopt without a told glint.
std::optional<Pixel> pupil_glint_vector(const GazeFeatures& features);

}  // namespace purkinje::trackers
