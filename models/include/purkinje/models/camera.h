#pragma once
// Pinhole camera in OpenCV conventions: camera frame +x right, +y down, +z
// forward; pixel centres at integer coordinates, (0, 0) the centre of the
// top-left pixel, so u = fx x/z + cx exactly as cv::projectPoints.
// Optional Brown-Conrady distortion with OpenCV's coefficient order.

#include <array>
#include <string>

#include "purkinje/models/geometry.h"
#include "purkinje/models/rotation.h"
#include "purkinje/models/sensor.h"

namespace purkinje {

struct Pixel {
  double u = 0, v = 0;
  bool operator==(const Pixel&) const = default;
};

struct Intrinsics {
  double fx = 0, fy = 0;  // px
  double cx = 0, cy = 0;  // px, OpenCV convention
  int width = 0, height = 0;

  // From a focal length and square pixel pitch, principal point at the
  // image centre ((width - 1) / 2, (height - 1) / 2).
  static Intrinsics from_focal_length(double focal_length_mm, double pixel_pitch_mm, int width,
                                      int height);
};

struct Distortion {
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
  bool is_zero() const { return k1 == 0 && k2 == 0 && p1 == 0 && p2 == 0 && k3 == 0; }
};

enum class ProjectionStatus { ok, behind_camera, outside_image };
const char* to_string(ProjectionStatus s);

struct Projection {
  ProjectionStatus status = ProjectionStatus::ok;
  Pixel pixel;  // valid unless behind_camera
};

class Camera {
 public:
  Camera(std::string name, const Intrinsics& intrinsics, const Distortion& distortion,
         const Pose& world_from_camera, const Sensor& sensor = {});

  const std::string& name() const { return name_; }
  const Intrinsics& intrinsics() const { return intrinsics_; }
  const Distortion& distortion() const { return distortion_; }
  const Pose& world_from_camera() const { return world_from_camera_; }
  const Pose& camera_from_world() const { return camera_from_world_; }
  const Sensor& sensor() const { return sensor_; }
  // Focal length in mm, from fx and the sensor's pixel pitch.
  double focal_length_mm() const { return intrinsics_.fx * sensor_.pixel_pitch_mm; }
  Point3 center() const;  // optical centre in the world

  // World point to pixel, distortion included. Points in the image plane
  // z = 0 or behind are behind_camera; pixels beyond [-0.5, size - 0.5]
  // are outside_image (the pixel is still filled in).
  Projection project(const Point3& world_point) const;
  // The same, with d(u, v)/d(world point) at that point (row-major 2 x 3,
  // px per mm) for fits; the derivatives are 0 when behind_camera.
  Projection project(const Point3& world_point, std::array<double, 6>& d_pixel_d_point) const;
  // Pixel to the world direction of its viewing ray (distortion removed
  // iteratively to 1e-12 px).
  UnitVector3 back_project(const Pixel& pixel) const;

  // Normalized image coordinates (x/z, y/z) to distorted ones, and back.
  void distort(double x, double y, double& xd, double& yd) const;
  void undistort(double xd, double yd, double& x, double& y) const;

 private:
  std::string name_;
  Intrinsics intrinsics_;
  Distortion distortion_;
  Pose world_from_camera_;
  Pose camera_from_world_;
  Sensor sensor_;
};

// A world pose for a camera at `position` looking at `target`, with the
// image's up (-y) as close as possible to `up`.
Pose camera_looking_at(const Point3& position, const Point3& target, const Vector3& up);

}  // namespace purkinje
