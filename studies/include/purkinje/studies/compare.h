#pragma once
// Comparing eye models (the compare issue): a rig in two versions, the
// world (what is) and the assumed (what a tracker believes: another
// cornea, an LED moved, a lens distortion...). Over a grid of gaze
// targets, each eye fixates the same target in its own version of the
// rig; where each feature lands in the image in both versions, and how
// far it moved, is the displacement field (the geometric part: exact
// labels, no images). Documented in docs/compare.md (to come).

#include <optional>
#include <string>
#include <vector>

#include "purkinje/models/scene.h"
#include "purkinje/models/truth.h"

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

}  // namespace purkinje::studies
