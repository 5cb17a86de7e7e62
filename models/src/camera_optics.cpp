#include "purkinje/models/camera_optics.h"

#include <cmath>

#include "purkinje/models/check.h"

namespace purkinje {

double aperture_diameter_mm(const Camera& camera) {
  check::require_positive("sensor.f_number", camera.sensor().f_number);
  return camera.focal_length_mm() / camera.sensor().f_number;
}

PointSpread point_spread(const Camera& camera, double depth_mm) {
  const Sensor& sensor = camera.sensor();
  check::require_non_negative("sensor.psf_sigma_px", sensor.psf_sigma_px);
  check::require_positive("depth_mm", depth_mm);
  PointSpread psf;
  psf.sigma_px = sensor.psf_sigma_px;
  psf.defocus_radius_px = 0;
  if (!sensor.focus_distance_mm) return psf;
  check::require_positive("sensor.pixel_pitch_mm", sensor.pixel_pitch_mm);
  const double f = camera.focal_length_mm();
  const double focus = *sensor.focus_distance_mm;
  if (!(std::isfinite(focus) && focus > f)) {
    check::fail("sensor.focus_distance_mm", focus,
                "must be finite and beyond the focal length " + check::format_number(f) + " mm");
  }
  // Thin lens: the sensor sits at the image distance of the focus plane; a
  // point at depth z converges before or after it, leaving a blur circle of
  // diameter A f |z - z_f| / (z (z_f - f)).
  const double blur_diameter_mm =
      aperture_diameter_mm(camera) * f * std::abs(depth_mm - focus) / (depth_mm * (focus - f));
  psf.defocus_radius_px = blur_diameter_mm / 2 / sensor.pixel_pitch_mm;
  return psf;
}

}  // namespace purkinje
