#include "purkinje/models/eye_variation.h"

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "purkinje/models/check.h"
#include "purkinje/models/rotation.h"

namespace purkinje {

namespace {

// Uniform in [0, 1) from 53 bits of the generator: the same numbers with
// any standard library (std::uniform_real_distribution is not specified).
double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

}  // namespace

std::vector<EyeVariation> random_eye_variations(std::uint64_t seed, int count, const EyeVariationRange& range) {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("EyeVariationRange: " + what); };
  if (!(range.max_gaze_turn_rad >= 0 && range.max_gaze_turn_rad <= std::numbers::pi / 2)) {
    fail("max_gaze_turn_rad = " + check::format_number(range.max_gaze_turn_rad) + ": must be in [0, pi/2]");
  }
  if (!(range.min_pupil_radius_mm > 0 && range.max_pupil_radius_mm >= range.min_pupil_radius_mm)) {
    fail("min_pupil_radius_mm = " + check::format_number(range.min_pupil_radius_mm) + ", max_pupil_radius_mm = " +
         check::format_number(range.max_pupil_radius_mm) + ": must satisfy 0 < min <= max");
  }
  if (count < 0) throw std::invalid_argument("random_eye_variations: count = " + std::to_string(count) + ": must be >= 0");
  std::mt19937_64 rng(seed);
  std::vector<EyeVariation> out;
  out.reserve(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) {
    EyeVariation v;
    // Uniform over the spherical cap: cos(turn) uniform in [cos max, 1].
    v.gaze_turn_rad = std::acos(1 - uniform01(rng) * (1 - std::cos(range.max_gaze_turn_rad)));
    v.turn_direction_rad = 2 * std::numbers::pi * uniform01(rng);
    v.pupil_radius_mm =
        range.min_pupil_radius_mm + (range.max_pupil_radius_mm - range.min_pupil_radius_mm) * uniform01(rng);
    out.push_back(v);
  }
  return out;
}

Scene with_eye_variation(const Scene& scene, const EyeVariation& v, int eye_index) {
  if (eye_index < 0 || eye_index >= static_cast<int>(scene.eyes.size())) {
    throw std::out_of_range("with_eye_variation: eye " + std::to_string(eye_index) + " of a scene with " +
                            std::to_string(scene.eyes.size()) + " eyes");
  }
  const Eye& eye = scene.eyes[eye_index];
  const EyeModel& m = eye.model();
  const auto fail = [](const std::string& what) { throw std::invalid_argument("EyeVariation: " + what); };
  if (!std::isfinite(v.gaze_turn_rad) || !std::isfinite(v.turn_direction_rad)) {
    fail("gaze_turn_rad = " + check::format_number(v.gaze_turn_rad) + ", turn_direction_rad = " +
         check::format_number(v.turn_direction_rad) + ": must be finite");
  }
  // The scene file's rule: the pupil's edge, decentred, within the iris.
  const double decentration = std::hypot(m.pupil_decentration_x_mm, m.pupil_decentration_y_mm);
  if (!(v.pupil_radius_mm > 0 && v.pupil_radius_mm + decentration < m.iris_radius_mm)) {
    fail("pupil_radius_mm = " + check::format_number(v.pupil_radius_mm) + ": must be > 0 and, with the pupil's " +
         check::format_number(decentration) + " mm decentration, < the iris's radius (" +
         check::format_number(m.iris_radius_mm) + " mm)");
  }
  const UnitVector3 gaze = eye.visual_axis();
  const UnitVector3 up = UnitVector3::normalize(eye.appearance().head_up.vector() -
                                                gaze.vector() * dot(eye.appearance().head_up, gaze));
  const UnitVector3 side = UnitVector3::normalize(cross(up, gaze));
  const UnitVector3 toward =
      UnitVector3::normalize(up * std::cos(v.turn_direction_rad) + side * std::sin(v.turn_direction_rad));
  // Turning by t about gaze x toward carries the gaze toward `toward`.
  const Rotation turn = Rotation::from_axis_angle(UnitVector3::normalize(cross(gaze, toward)), v.gaze_turn_rad);
  const Vector3 center = eye.rotation_center().from_origin();
  const Pose about_rotation_center(turn, center - turn * center);
  EyeModel model = eye.model();
  model.pupil_radius_mm = v.pupil_radius_mm;
  Eye turned(model, about_rotation_center * eye.world_from_eye());
  turned.set_appearance(eye.appearance());
  turned.set_motion(eye.motion());
  Scene out = scene;
  out.eyes[eye_index] = turned;
  return out;
}

}  // namespace purkinje
