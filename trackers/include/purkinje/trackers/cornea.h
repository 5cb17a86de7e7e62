#pragma once
// The cornea from glints (the calibration issue): the centres of a
// spherical or conicoid cornea, one per frame, and optionally its radius, that put
// each light's glint where the cameras saw it. Least squares on the
// glints' pixels through the optimizer facade, with the covariance of
// every estimate under pixel noise and warnings where the glints do not
// pin the answer down.

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "purkinje/models/camera.h"
#include "purkinje/models/illuminator.h"
#include "purkinje/trackers/glints.h"

namespace purkinje::trackers {

// One glint seen: in which frame (the eye in one place), by which camera,
// of which light, and where in that camera's image.
struct GlintObservation {
  int frame = 0;
  int camera = 0;
  int light = 0;
  Pixel pixel;
  // The pixel's standard deviation along u and v, px (a detector's own,
  // see add_observations); 0: CorneaFitSettings::pixel_noise_px.
  double sd_u_px = 0, sd_v_px = 0;
};

struct CorneaFitSettings {
  // The tracker's eye model, a sphere or a conicoid: the known (apex)
  // radius, or the fit's start when fit_radius. In (0, 100).
  double cornea_radius_mm = 7.8;
  // The conicoid's Q (Conicoid), > -1; 0: a sphere. A conicoid's glints
  // depend on where its apex points: the fit then needs each frame's
  // optical axis.
  double cornea_asphericity = 0;
  bool fit_radius = false;
  // With fit_radius: > 0 adds a Gaussian prior on the radius at
  // cornea_radius_mm with this standard deviation; 0, none.
  double radius_prior_sd_mm = 0;
  double pixel_noise_px = 0.1;  // standard deviation of a glint's u and v where it has none of its own, > 0
  // An estimate whose standard deviation exceeds this is reported as
  // weakly determined (a warning); > 0.
  double max_sd_mm = 10;
  // A glint whose residual exceeds this many of its standard deviations
  // is rejected and the fit run again, the worst first, while its frame
  // keeps three or more (a glint merged with another bright spot, or one
  // whose small reported deviation misses an error); 0: none rejected.
  double reject_beyond_sd = 6;
};

struct CorneaFit {
  std::vector<Point3> centers;  // world mm, one per frame
  double cornea_radius_mm = 0;  // fitted, or the settings' when not fitted
  bool radius_fitted = false;
  // Row-major covariance of the unknowns: the frames' centres in order,
  // then the radius when fitted; mm^2. (J^T J)^-1 with J the glints'
  // pixels, each over its standard deviation, by the unknowns at the
  // estimate. Empty when the glints do not determine them.
  std::vector<double> covariance_mm2;
  double rms_residual_px = 0;  // of the glints' pixels at the estimate
  // Each glint's distance from its prediction, in input order; a rejected
  // glint's from the fit it was rejected in.
  std::vector<double> glint_residuals_px;
  // The same in each glint's own standard deviations: the hypotenuse of
  // its u and v residuals, each over its s.d.
  std::vector<double> glint_residuals_sd;
  double condition = 0;        // of J^T J (0 when not computed)
  int glints_used = 0;
  std::vector<int> rejected;  // indices into the glints given, in the order rejected
  bool converged = false;
  std::vector<std::string> warnings;  // why the estimate should not be trusted, if it should not

  bool has_covariance() const { return !covariance_mm2.empty(); }
  // The 3 x 3 block of a frame's centre (row-major); needs has_covariance().
  std::array<double, 9> center_covariance(int frame) const;
  // 0 when the radius is not fitted; needs has_covariance() otherwise.
  double radius_sd_mm() const;
};

// Fits the centres (starting at `starts`, one per frame) and, when asked,
// the radius. `optical_axes`: one per frame, held fixed, for a conicoid
// (gaze.h estimates them from the pupil); ignored for a sphere. Throws
// std::invalid_argument naming the value for settings out of range, an
// observation whose frame, camera or light the lists do not have, or a
// conicoid without its axes.
CorneaFit fit_cornea(const std::vector<Camera>& cameras, const std::vector<Illuminator>& lights,
                     const std::vector<GlintObservation>& glints, const std::vector<Point3>& starts,
                     const CorneaFitSettings& settings = {},
                     const std::vector<UnitVector3>& optical_axes = {});

// One glint as an observation. With glint_sd_scale > 0, a glint that
// reports its centre's standard deviation (Glint::centre_sd_u_px, _v_px)
// is given it times the scale; otherwise its deviations stay 0 (the fit's
// pixel_noise_px). Throws std::invalid_argument for a scale not finite
// and >= 0.
GlintObservation observation_of(const Glint& glint, int frame, int camera = 0, double glint_sd_scale = 0);

// A detector's glints in one frame of one camera, those with their light
// told (illuminator >= 0), appended to `out` as observations (observation_of). With
// glint_sd_scale > 0, a glint that reports its centre's standard
// deviation (Glint::centre_sd_u_px, _v_px) is given it times the scale
// (the detector's own, as measured against labels); the others are left
// to the fit's pixel_noise_px.
void add_observations(std::vector<GlintObservation>& out, const std::vector<Glint>& glints, int frame,
                      int camera = 0, double glint_sd_scale = 0);

// One frame from one camera: a detector's glints with their light told
// (illuminator >= 0; others are left out), `start` a guess of the centre
// (a tracker's nominal eye); the optical axis as fit_cornea's.
CorneaFit estimate_cornea_center(const Camera& camera, const std::vector<Illuminator>& lights,
                                 const std::vector<Glint>& glints, const Point3& start,
                                 const CorneaFitSettings& settings = {},
                                 const std::optional<UnitVector3>& optical_axis = std::nullopt);

}  // namespace purkinje::trackers
