#include "purkinje/models/camera.h"
#include "purkinje/models/check.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace purkinje {

namespace {

std::string describe(const Point3& p) {
  using check::format_number;
  return "(" + format_number(p.x) + ", " + format_number(p.y) + ", " + format_number(p.z) + ")";
}

std::string describe(const Vector3& v) { return describe(Point3::origin() + v); }

void require_positive(const std::string& what, double value) {
  if (!(value > 0) || !std::isfinite(value)) check::fail(what, value, "must be > 0 and finite");
}

// Distortion and its 2x2 Jacobian d(xd, yd)/d(x, y), for Newton's method.
struct DistortedPoint {
  double xd, yd;
  double dxd_dx, dxd_dy, dyd_dx, dyd_dy;
};

DistortedPoint distort_with_jacobian(const Distortion& d, double x, double y) {
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
  const double dradial_dr2 = d.k1 + r2 * (2 * d.k2 + 3 * r2 * d.k3);
  DistortedPoint p{};
  p.xd = x * radial + 2 * d.p1 * x * y + d.p2 * (r2 + 2 * x * x);
  p.yd = y * radial + d.p1 * (r2 + 2 * y * y) + 2 * d.p2 * x * y;
  p.dxd_dx = radial + 2 * x * x * dradial_dr2 + 2 * d.p1 * y + 6 * d.p2 * x;
  p.dxd_dy = 2 * x * y * dradial_dr2 + 2 * d.p1 * x + 2 * d.p2 * y;
  p.dyd_dx = p.dxd_dy;  // the model's Jacobian is symmetric
  p.dyd_dy = radial + 2 * y * y * dradial_dr2 + 6 * d.p1 * y + 2 * d.p2 * x;
  return p;
}

}  // namespace

Intrinsics Intrinsics::from_focal_length(double focal_length_mm, double pixel_pitch_mm, int width,
                                         int height) {
  require_positive("focal_length_mm", focal_length_mm);
  require_positive("pixel_pitch_mm", pixel_pitch_mm);
  require_positive("width_px", width);
  require_positive("height_px", height);
  Intrinsics in;
  in.fx = in.fy = focal_length_mm / pixel_pitch_mm;
  // Pixel centres are at integers, so the image centre lies between the
  // middle pixels for even sizes.
  in.cx = (width - 1) / 2.0;
  in.cy = (height - 1) / 2.0;
  in.width = width;
  in.height = height;
  return in;
}

const char* to_string(ProjectionStatus s) {
  switch (s) {
    case ProjectionStatus::ok: return "ok";
    case ProjectionStatus::behind_camera: return "behind_camera";
    case ProjectionStatus::outside_image: return "outside_image";
  }
  return "unknown";
}

Camera::Camera(std::string name, const Intrinsics& intrinsics, const Distortion& distortion,
               const Pose& world_from_camera, const Sensor& sensor)
    : name_(std::move(name)),
      intrinsics_(intrinsics),
      distortion_(distortion),
      world_from_camera_(world_from_camera),
      camera_from_world_(world_from_camera.inverse()),
      sensor_(sensor) {
  const std::string prefix = "camera '" + name_ + "': intrinsics.";
  require_positive(prefix + "fx", intrinsics.fx);
  require_positive(prefix + "fy", intrinsics.fy);
  require_positive(prefix + "width", intrinsics.width);
  require_positive(prefix + "height", intrinsics.height);
}

Point3 Camera::center() const { return Point3::origin() + world_from_camera_.translation(); }

Projection Camera::project(const Point3& world_point) const {
  const Point3 p = camera_from_world_ * world_point;
  Projection out;
  if (!(p.z > 0)) {
    out.status = ProjectionStatus::behind_camera;
    return out;
  }
  double xd = 0, yd = 0;
  distort(p.x / p.z, p.y / p.z, xd, yd);
  out.pixel = {intrinsics_.fx * xd + intrinsics_.cx, intrinsics_.fy * yd + intrinsics_.cy};
  // Pixel (0, 0) covers [-0.5, 0.5]^2, so the sensor spans [-0.5, size - 0.5].
  const bool inside = out.pixel.u >= -0.5 && out.pixel.u <= intrinsics_.width - 0.5 &&
                      out.pixel.v >= -0.5 && out.pixel.v <= intrinsics_.height - 0.5;
  out.status = inside ? ProjectionStatus::ok : ProjectionStatus::outside_image;
  return out;
}

Projection Camera::project(const Point3& world_point, std::array<double, 6>& d_pixel_d_point) const {
  d_pixel_d_point.fill(0);
  const Projection out = project(world_point);
  if (out.status == ProjectionStatus::behind_camera) return out;
  const Point3 p = camera_from_world_ * world_point;
  const double x = p.x / p.z, y = p.y / p.z;
  const DistortedPoint d = distort_with_jacobian(distortion_, x, y);
  // d(x, y)/d(camera point), then through the rotation to world.
  const double dx[3] = {1 / p.z, 0, -x / p.z};
  const double dy[3] = {0, 1 / p.z, -y / p.z};
  const Rotation& r = camera_from_world_.rotation();
  for (int k = 0; k < 3; ++k) {
    double dx_dk = 0, dy_dk = 0;
    for (int i = 0; i < 3; ++i) {
      dx_dk += dx[i] * r(i, k);
      dy_dk += dy[i] * r(i, k);
    }
    d_pixel_d_point[k] = intrinsics_.fx * (d.dxd_dx * dx_dk + d.dxd_dy * dy_dk);
    d_pixel_d_point[3 + k] = intrinsics_.fy * (d.dyd_dx * dx_dk + d.dyd_dy * dy_dk);
  }
  return out;
}

UnitVector3 Camera::back_project(const Pixel& pixel) const {
  const double xd = (pixel.u - intrinsics_.cx) / intrinsics_.fx;
  const double yd = (pixel.v - intrinsics_.cy) / intrinsics_.fy;
  double x = xd, y = yd;
  if (!distortion_.is_zero()) undistort(xd, yd, x, y);  // a call per camera ray saved
  const Vector3 ray_in_camera{x, y, 1};
  return world_from_camera_ * UnitVector3::from_normalized_unchecked(ray_in_camera /
                                                                     ray_in_camera.norm());
}

void Camera::distort(double x, double y, double& xd, double& yd) const {
  const DistortedPoint p = distort_with_jacobian(distortion_, x, y);
  xd = p.xd;
  yd = p.yd;
}

void Camera::undistort(double xd, double yd, double& x, double& y) const {
  x = xd;
  y = yd;
  if (distortion_.is_zero() || !std::isfinite(xd) || !std::isfinite(yd)) return;

  // Newton's method on distort(x, y) = (xd, yd), with a backtracking step so
  // that a strongly distorting lens cannot throw the iterate away. The error
  // is measured in pixels so that the 1e-12 px target is independent of fx.
  const auto pixel_error = [&](const DistortedPoint& p) {
    return std::hypot(intrinsics_.fx * (p.xd - xd), intrinsics_.fy * (p.yd - yd));
  };
  DistortedPoint current = distort_with_jacobian(distortion_, x, y);
  double error = pixel_error(current);
  constexpr double tolerance_px = 1e-12;
  constexpr int max_iterations = 50;
  for (int iteration = 0; iteration < max_iterations && error > tolerance_px; ++iteration) {
    const double det = current.dxd_dx * current.dyd_dy - current.dxd_dy * current.dyd_dx;
    if (!std::isfinite(det) || det == 0) break;
    const double rx = current.xd - xd, ry = current.yd - yd;
    const double step_x = (current.dyd_dy * rx - current.dxd_dy * ry) / det;
    const double step_y = (current.dxd_dx * ry - current.dyd_dx * rx) / det;

    bool improved = false;
    for (double scale = 1; scale > 1e-6; scale *= 0.5) {
      const double trial_x = x - scale * step_x, trial_y = y - scale * step_y;
      const DistortedPoint trial = distort_with_jacobian(distortion_, trial_x, trial_y);
      const double trial_error = pixel_error(trial);
      if (trial_error < error) {
        x = trial_x;
        y = trial_y;
        current = trial;
        error = trial_error;
        improved = true;
        break;
      }
    }
    // No decrease at all: the iterate is at the rounding floor (or at a fold
    // of the lens model); keep the best point found, which is finite.
    if (!improved) break;
  }
}

Pose camera_looking_at(const Point3& position, const Point3& target, const Vector3& up) {
  if (!position.is_finite() || !target.is_finite() || !up.is_finite()) {
    throw std::invalid_argument("camera_looking_at: position " + describe(position) +
                                ", target " + describe(target) + ", up " + describe(up) +
                                ": must all be finite");
  }
  const Vector3 view = target - position;
  const double view_length = view.norm();
  if (view_length == 0) {
    throw std::invalid_argument("camera_looking_at: target " + describe(target) +
                                " equals position " + describe(position) +
                                ": the camera must look at a distinct point");
  }
  const Vector3 z = view / view_length;
  // Image up is camera -y, so camera +y is -up with its component along the
  // view removed.
  const Vector3 down = -(up - dot(up, z) * z);
  const double up_length = up.norm();
  if (up_length == 0 || down.norm() <= 1e-9 * up_length) {
    throw std::invalid_argument("camera_looking_at: up " + describe(up) +
                                " is zero or parallel to the view direction " + describe(z) +
                                ": it must have a component across the view");
  }
  const UnitVector3 y_axis = UnitVector3::normalize(down);
  const UnitVector3 z_axis = UnitVector3::normalize(z);
  const UnitVector3 x_axis = UnitVector3::normalize(cross(y_axis, z_axis));
  return Pose(Rotation::from_columns(x_axis, y_axis, z_axis), position.from_origin());
}

}  // namespace purkinje
