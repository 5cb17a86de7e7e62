#include "tracker_optics.h"

#include <algorithm>

#include "purkinje/renderer/sensor_model.h"

namespace purkinje::tools {

trackers::BlobGlintSettings glint_settings_for(const Camera& camera, const std::vector<Illuminator>& lights,
                                               const Point3& nominal_cornea) {
  trackers::BlobGlintSettings settings;
  const double depth = (camera.camera_from_world() * nominal_cornea).z;
  const bool points =
      std::all_of(lights.begin(), lights.end(), [](const Illuminator& l) { return l.emitter_diameter_mm == 0; });
  if (depth > camera.focal_length_mm() && points) {
    const renderer::PointSpread spread = renderer::point_spread(camera, depth);
    // The detector refuses a told width outside [0.1, 10] px; left at 0 it estimates its own.
    if (spread.defocus_radius_px == 0 && spread.sigma_px >= 0.1 && spread.sigma_px <= 10) {
      settings.spot_sigma_px = spread.sigma_px;
    }
  }
  const Sensor& sensor = camera.sensor();
  if (sensor.gain > 0) settings.full_scale_e = sensor.full_well_e / sensor.gain;
  settings.read_noise_e = sensor.read_noise_e;
  return settings;
}

}  // namespace purkinje::tools
