#include "purkinje/models/eye.h"
#include "purkinje/models/check.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace purkinje {
namespace {

// Depth from the apex of a conicoid at radial distance r; nullopt-like -1
// beyond the surface's reach (never reached for validated models).
double conicoid_depth(const Conicoid& s, double r) {
  const double disc = s.radius_mm * s.radius_mm - (1.0 + s.asphericity) * r * r;
  if (disc < 0) return -1.0;
  // r^2 / (R + sqrt(disc)) is the cancellation-free root of the conic.
  return r * r / (s.radius_mm + std::sqrt(disc));
}

// The visual axis in the eye frame.
Vector3 visual_axis_in_eye(const EyeModel& m) {
  const double h = m.kappa_horizontal_rad, v = m.kappa_vertical_rad;
  return {std::sin(h) * std::cos(v), std::sin(v), std::cos(h) * std::cos(v)};
}

// The optical axis whose eye frame maps the model's visual axis onto `visual`.
// The frame depends smoothly on the optical axis, so fixed-point iteration
// on the small kappa rotation converges in a few steps.
UnitVector3 optical_axis_for_visual_axis(const EyeModel& m, const UnitVector3& visual) {
  const Vector3 v_eye = visual_axis_in_eye(m);
  UnitVector3 o = visual;
  for (int i = 0; i < 100; ++i) {
    const UnitVector3 v_now = UnitVector3::normalize(world_from_eye_rotation(o) * v_eye);
    const Vector3 axis = cross(v_now, visual);
    const double angle = angle_between(v_now, visual);
    if (angle < 1e-15) return o;
    o = rotate(o, UnitVector3::normalize(axis), angle);
  }
  return o;
}

// Radius of the eyeball's shell (the sclera's sphere and the limbal band
// that joins it to the cornea's edge, as the renderer builds them) in the
// plane `depth_mm` behind the anterior apex; 0 where the plane misses it.
double shell_radius_mm(const EyeModel& m, double depth_mm) {
  // Heights above the centre of rotation: the plane's, the limbus plane's,
  // and the seam where the sphere meets the band (the band is a cylinder
  // of the limbus's radius where the sphere is narrower than the limbus
  // below the limbus plane, else an annulus in that plane).
  const double h = m.rotation_center_depth_mm - depth_mm;
  const double h_limbus = m.rotation_center_depth_mm - m.limbus_depth_mm();
  const double h_seam = m.rotation_center_depth_mm - m.sclera_seam_depth_mm();
  const double R = m.sclera_radius_mm;
  if (h <= h_seam) return std::abs(h) < R ? std::sqrt(R * R - h * h) : 0.0;
  return h <= h_limbus ? m.limbus_radius_mm : 0.0;
}

}  // namespace

double EyeModel::limbus_depth_mm() const { return conicoid_depth(anterior_cornea, limbus_radius_mm); }

double EyeModel::sclera_seam_depth_mm() const {
  // Heights above the centre of rotation.
  const double h_limbus = rotation_center_depth_mm - limbus_depth_mm();
  const double R = sclera_radius_mm, r = limbus_radius_mm;
  if (R >= r && std::sqrt(R * R - r * r) < h_limbus) return rotation_center_depth_mm - std::sqrt(R * R - r * r);
  return limbus_depth_mm();
}

double EyeModel::iris_outer_radius_mm() const {
  if (posterior_cornea && iris_depth_mm > limbus_depth_mm()) {
    // x^2 + y^2 = 2 R w - (1 + Q) w^2 on the posterior surface, w below its apex.
    const Conicoid& back = posterior_cornea->surface;
    const double w = iris_depth_mm - posterior_cornea->thickness_mm;
    return std::sqrt(std::max(0.0, 2 * back.radius_mm * w - (1 + back.asphericity) * w * w));
  }
  return std::max(iris_radius_mm, shell_radius_mm(*this, iris_depth_mm));
}

UnitVector3 optical_axis_from_yaw_pitch(double yaw, double pitch) {
  return UnitVector3::normalize(
      {std::sin(yaw) * std::cos(pitch), -std::sin(pitch), -std::cos(yaw) * std::cos(pitch)});
}

Rotation world_from_eye_rotation(const UnitVector3& o) {
  Vector3 ref{1, 0, 0};
  if (std::abs(o.x()) > 1.0 - 1e-6) ref = {0, 1, 0};
  const UnitVector3 x = UnitVector3::normalize(ref - o.vector() * dot(ref, o));
  const UnitVector3 y = UnitVector3::normalize(cross(o, x));
  return Rotation::from_columns(x, y, o);
}

Eye::Eye(EyeModel model, const Pose& world_from_eye)
    : model_(std::move(model)), world_from_eye_(world_from_eye),
      eye_from_world_(world_from_eye.inverse()) {}

Eye Eye::at_time(double t_s) const {
  if (t_s == 0 || motion_.still()) return *this;
  const UnitVector3 o = optical_axis();
  const double pitch = std::asin(std::clamp(-o.y(), -1.0, 1.0)), yaw = std::atan2(o.x(), -o.z());
  constexpr double kRadPerDeg = std::numbers::pi / 180;
  const UnitVector3 turned = optical_axis_from_yaw_pitch(yaw + motion_.yaw_deg_s * kRadPerDeg * t_s,
                                                         pitch + motion_.pitch_deg_s * kRadPerDeg * t_s);
  // The shortest rotation from the axis to the turned one, about the centre
  // of rotation: the eye keeps its own twist (a varied eye's frame need
  // not be world_from_eye_rotation's), and nothing flips where that
  // frame's reference axis would.
  const Vector3 across = cross(o, turned);
  const double sine = across.norm();
  if (!(sine > 0)) return *this;
  const Rotation turn = Rotation::from_axis_angle(UnitVector3::normalize(across), std::atan2(sine, dot(o, turned)));
  const Vector3 center = rotation_center().from_origin();
  Eye eye(model_, Pose(turn, center - turn * center) * world_from_eye_);
  eye.appearance_ = appearance_;
  eye.motion_ = motion_;
  return eye;
}

Eye Eye::with_cornea_center(EyeModel model, const Point3& c, const UnitVector3& o) {
  return Eye(std::move(model), Pose(world_from_eye_rotation(o), c.from_origin()));
}

Eye Eye::with_rotation_center(EyeModel model, const Point3& rc, const UnitVector3& o) {
  // The rotation centre sits at z = R - depth in the eye frame.
  const double back = model.rotation_center_depth_mm - model.anterior_cornea.radius_mm;
  return with_cornea_center(std::move(model), rc + o.vector() * back, o);
}

Eye Eye::fixating_from_cornea_center(EyeModel model, const Point3& c, const Point3& target) {
  auto visual = UnitVector3::try_normalize(target - c);
  if (!visual) throw std::invalid_argument("gaze target coincides with the cornea centre");
  const UnitVector3 o = optical_axis_for_visual_axis(model, *visual);
  return with_cornea_center(std::move(model), c, o);
}

Eye Eye::with_visual_axis(EyeModel model, const Point3& rc, const UnitVector3& visual_axis) {
  const UnitVector3 o = optical_axis_for_visual_axis(model, visual_axis);
  return with_rotation_center(std::move(model), rc, o);
}

Eye Eye::fixating(EyeModel model, const Point3& rc, const Point3& target) {
  const double back = model.rotation_center_depth_mm - model.anterior_cornea.radius_mm;
  // The cornea centre moves with the eye; a target closer than twice the
  // rotation radius has no stable fixation for this model.
  if (distance(target, rc) <= 2.0 * std::abs(back) + model.anterior_cornea.radius_mm) {
    throw std::invalid_argument("gaze target is " + check::format_number(distance(target, rc)) +
                                " mm from the centre of rotation: too close to fixate");
  }
  UnitVector3 o = UnitVector3::normalize(target - rc);
  for (int i = 0; i < 200; ++i) {
    const Point3 c = rc + o.vector() * back;
    const UnitVector3 next =
        optical_axis_for_visual_axis(model, UnitVector3::normalize(target - c));
    const double change = angle_between(next, o);
    o = next;
    if (change < 1e-15) break;
  }
  return with_cornea_center(std::move(model), rc + o.vector() * back, o);
}

Point3 Eye::cornea_center() const { return world_from_eye_ * Point3::origin(); }

Point3 Eye::rotation_center() const {
  return world_from_eye_ *
         Point3{0, 0, model_.anterior_cornea.radius_mm - model_.rotation_center_depth_mm};
}

Point3 Eye::corneal_apex() const {
  return world_from_eye_ * Point3{0, 0, model_.anterior_cornea.radius_mm};
}

UnitVector3 Eye::optical_axis() const { return world_from_eye_.rotation().column(2); }

UnitVector3 Eye::visual_axis() const {
  return UnitVector3::normalize(world_from_eye_ * visual_axis_in_eye(model_));
}

Point3 Eye::pupil_center() const {
  return world_from_eye_ * Point3{model_.pupil_decentration_x_mm, model_.pupil_decentration_y_mm,
                                  model_.anterior_cornea.radius_mm - model_.iris_depth_mm};
}

Point3 Eye::pupil_border_point(double angle) const {
  const double r = model_.pupil_radius_mm;
  return world_from_eye_ * Point3{model_.pupil_decentration_x_mm + r * std::cos(angle),
                                  model_.pupil_decentration_y_mm + r * std::sin(angle),
                                  model_.anterior_cornea.radius_mm - model_.iris_depth_mm};
}

bool Eye::on_cap(const Point3& world_point) const {
  const Point3 p = eye_from_world_ * world_point;
  return model_.anterior_cornea.radius_mm - p.z < model_.limbus_depth_mm();
}

bool Eye::cap_crosses(const Point3& from, const Point3& to) const {
  // Eye frame: the cap is x^2 + y^2 + k w^2 - 2 R w = 0 for depths
  // 0 <= w = R - z <= limbus depth; along p(t) = a + t d a quadratic in t.
  const Point3 a = eye_from_world_ * from;
  const Vector3 d = eye_from_world_ * to - a;
  const double R = model_.anterior_cornea.radius_mm, k = 1.0 + model_.anterior_cornea.asphericity;
  const double w0 = R - a.z, dw = -d.z;
  const double qa = d.x * d.x + d.y * d.y + k * dw * dw;
  const double qb = 2 * (a.x * d.x + a.y * d.y + k * w0 * dw - R * dw);
  const double qc = a.x * a.x + a.y * a.y + k * w0 * w0 - 2 * R * w0;
  // Both ends trimmed as the ray tracer trims its segments.
  const double trim = 1e-6 + 1e-9 / std::max(d.norm(), 1e-300);
  const auto crosses_at = [&](double t) {
    if (!(t > trim && t < 1 - trim)) return false;
    const double w = w0 + t * dw;
    return w >= 0 && w <= model_.limbus_depth_mm();
  };
  if (std::abs(qa) < 1e-300) return qb != 0 && crosses_at(-qc / qb);
  const double disc = qb * qb - 4 * qa * qc;
  if (disc < 0) return false;
  // The numerically stable pair of roots.
  const double q = -0.5 * (qb + std::copysign(std::sqrt(disc), qb));
  const double t1 = q / qa, t2 = q != 0 ? qc / q : t1;
  return crosses_at(t1) || crosses_at(t2);
}

}  // namespace purkinje
