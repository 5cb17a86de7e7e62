#pragma once
// Ground truth for a scene, per camera and eye: glints, the refracted pupil
// and the eye's axes, as the camera sees them.

#include <vector>

#include "purkinje/models/camera.h"
#include "purkinje/models/scene.h"
#include "purkinje/models/specular.h"

namespace purkinje {

struct Ellipse {
  Pixel center;
  double semi_axis_1_px = 0;  // along angle_rad
  double semi_axis_2_px = 0;
  double angle_rad = 0;       // of semi-axis 1 from +u toward +v, in (-pi/2, pi/2]
};

struct GlintTruth {
  int illuminator = 0;
  PathStatus status = PathStatus::no_solution;
  Pixel pixel;               // valid when status is ok or outside_image
  Reflection reflection;     // 3D point, normal, directions, incidence, on_cap
};

struct PupilBorderPointTruth {
  double angle_rad = 0;      // around the pupil, from eye +x toward eye +y
  Point3 border_point;       // the 3D point on the pupil's edge
  PathStatus status = PathStatus::no_solution;
  Pixel pixel;
  Refraction refraction;
};

struct PupilTruth {
  std::vector<PupilBorderPointTruth> border;
  bool ellipse_valid = false;  // needs at least 6 border points with status ok
  // Fitted (Halir-Flusser) to the ok border pixels of compute_truth. The
  // renderer's visibility check marks points a lid hides occluded after the
  // fit and keeps this ellipse: it stays the whole pupil's.
  Ellipse ellipse;
  // The pupil centre seen through the cornea (its own refracted path).
  PathStatus refracted_center_status = PathStatus::no_solution;
  Pixel refracted_center;
  Refraction refracted_center_path;
  // The pupil centre projected straight, without the cornea.
  Projection unrefracted_center;
};

struct EyeInCameraTruth {
  int camera = 0;
  int eye = 0;
  std::vector<GlintTruth> glints;  // one per illuminator, in scene order
  PupilTruth pupil;
  Projection cornea_center;
  Projection rotation_center;
};

struct EyeTruth {
  Point3 cornea_center;
  Point3 rotation_center;
  Point3 pupil_center;
  UnitVector3 optical_axis = UnitVector3::unit_z();
  UnitVector3 visual_axis = UnitVector3::unit_z();
  double cornea_radius_mm = 0;
  double pupil_radius_mm = 0;
};

struct SceneTruth {
  std::vector<EyeTruth> eyes;
  std::vector<EyeInCameraTruth> views;  // camera-major: (camera 0, eye 0), (camera 0, eye 1), ...
};

struct TruthOptions {
  int pupil_border_points = 36;
};

SceneTruth compute_truth(const Scene& scene, const TruthOptions& options = {});

// Image of a point inside the eye seen through the cornea by `camera`.
struct RefractedImage {
  PathStatus status = PathStatus::no_solution;
  Pixel pixel;
  Refraction path;
};
RefractedImage image_through_cornea(const Eye& eye, const Camera& camera, const Point3& inner);

// Direct least-squares ellipse fit (Halir and Flusser 1998). Needs at least
// 6 points not on a conic degenerate; nullopt otherwise.
std::optional<Ellipse> fit_ellipse(const std::vector<Pixel>& points);

}  // namespace purkinje
