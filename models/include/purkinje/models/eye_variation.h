#pragma once
// Eyes turned and pupils resized about a scene's own: the random sweeps
// that the bars are measured on, and the variety of a data set. Draws are
// reproducible from their seed with any standard library.

#include <cstdint>
#include <numbers>
#include <vector>

#include "purkinje/models/scene.h"

namespace purkinje {

struct EyeVariation {
  double gaze_turn_rad = 0;       // between the scene's gaze (visual axis) and this one
  double turn_direction_rad = 0;  // which way: 0 toward the head's up, pi/2 toward up x gaze
  double pupil_radius_mm = 0;
};

struct EyeVariationRange {
  double max_gaze_turn_rad = 30 * std::numbers::pi / 180;  // in [0, pi/2]
  double min_pupil_radius_mm = 1;                           // 0 < min <= max
  double max_pupil_radius_mm = 4;
};

// `count` variations: gaze directions uniform over the spherical cap within
// the range's turn of the scene's gaze, pupil radii uniform in the range.
// Throws std::invalid_argument for a range out of bounds or a negative
// count, naming the field, its value and the rule.
std::vector<EyeVariation> random_eye_variations(std::uint64_t seed, int count, const EyeVariationRange& range = {});

// The scene with its eye `eye` turned rigidly about its centre of rotation
// (about an axis perpendicular to the gaze: Listing's law with the scene's
// gaze as the primary position) and its pupil resized; the lids follow the
// turned eye (appearance.h), everything else is unchanged. Throws
// std::out_of_range for an eye the scene does not have, and
// std::invalid_argument for a turn that is not finite or a pupil that is
// not within the iris (as the scene file's rule), naming the field.
Scene with_eye_variation(const Scene& scene, const EyeVariation& variation, int eye = 0);

}  // namespace purkinje
