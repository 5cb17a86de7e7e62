#pragma once
// The cornea's centre from glints (the calibration issue, first part): the
// centre of a spherical cornea of known radius that puts each light's
// glint where the camera saw it, by least squares on the glints' pixels
// through the specular-path solver, with its covariance under pixel noise
// and a warning where the glints do not pin it down.

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "purkinje/models/camera.h"
#include "purkinje/models/illuminator.h"
#include "purkinje/trackers/glints.h"

namespace purkinje::trackers {

struct CorneaCenterSettings {
  double cornea_radius_mm = 7.8;  // the tracker's eye model: a sphere, > 0
  double pixel_noise_px = 0.1;    // standard deviation of a glint's u and v, > 0, for the covariance
  // A problem whose normal matrix is worse conditioned than this is called
  // degenerate: the centre moves far along some direction for a small
  // change of the glints.
  double max_condition = 1e8;
};

struct CorneaCenterEstimate {
  Point3 center;  // world, mm
  // Row-major, mm^2: (J^T J)^-1 times the pixel noise's variance, J the
  // glints' pixels by the centre at the estimate; absent when the glints
  // do not determine the centre (fewer than two).
  std::optional<std::array<double, 9>> covariance_mm2;
  double rms_residual_px = 0;  // of the glints' pixels at the estimate
  double condition = 0;        // of J^T J (0 when undetermined)
  int glints_used = 0;
  bool converged = false;
  std::vector<std::string> warnings;  // why the estimate should not be trusted, if it should not
};

// `glints` with their light told (illuminator >= 0; others are left out),
// `start` a guess of the centre (a tracker's nominal eye). Throws
// std::invalid_argument for settings out of range or a light index the
// list does not have.
CorneaCenterEstimate estimate_cornea_center(const Camera& camera, const std::vector<Illuminator>& lights,
                                            const std::vector<Glint>& glints, const Point3& start,
                                            const CorneaCenterSettings& settings = {});

}  // namespace purkinje::trackers
