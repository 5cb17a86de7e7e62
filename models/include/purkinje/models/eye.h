#pragma once
// The eye: anatomy (EyeModel, no pose) and a posed Eye in the world.
//
// Eye frame: origin at the anterior cornea's centre of curvature (the
// "cornea centre"), +z along the optical axis pointing out of the eye
// toward the corneal apex, +x = the world +x made perpendicular to the
// optical axis, +y = z cross x. For an eye looking down the world's -z
// axis (toward a camera at the origin looking along +z), eye +x is world +x
// and eye +y is world -y ("up" in OpenCV's y-down frame).

#include <optional>
#include <string>
#include <vector>

#include "purkinje/models/appearance.h"
#include "purkinje/models/geometry.h"
#include "purkinje/models/rotation.h"

namespace purkinje {

// Surface of revolution x^2 + y^2 + (1 + Q) w^2 - 2 R w = 0, w measured
// from the apex into the eye. Q = 0 is a sphere, -1 < Q < 0 a prolate
// ellipsoid (flattening toward the periphery, as real corneas), Q = -1 a
// paraboloid, Q < -1 a hyperboloid.
struct Conicoid {
  double radius_mm = 7.8;    // radius of curvature at the apex
  double asphericity = 0.0;  // Q
  bool is_sphere() const { return asphericity == 0.0; }
};

struct PosteriorCornea {
  Conicoid surface{6.5, 0.0};
  double thickness_mm = 0.55;  // apex to apex along the optical axis
  double cornea_index = 1.376;
};

struct EyeModel {
  std::string name = "custom";
  Conicoid anterior_cornea{7.8, 0.0};
  // Absent: one refracting surface, aqueous_index is then the index of the
  // whole eye behind the anterior cornea (keratometric 1.3375 by default).
  std::optional<PosteriorCornea> posterior_cornea;
  double aqueous_index = 1.3375;
  double limbus_radius_mm = 5.9;     // radius of the corneal cap's border
  double iris_depth_mm = 3.6;        // anterior apex to iris plane, along the optical axis
  double iris_radius_mm = 5.9;       // outer border of the iris
  double pupil_radius_mm = 2.0;
  double pupil_decentration_x_mm = 0.0;  // pupil centre in the iris plane, eye frame
  double pupil_decentration_y_mm = 0.0;
  double rotation_center_depth_mm = 13.5;  // anterior apex to centre of rotation
  double sclera_radius_mm = 12.0;          // sphere centred on the centre of rotation
  // Visual axis relative to the optical axis, in the eye frame: positive
  // horizontal toward eye +x, positive vertical toward eye +y (up).
  double kappa_horizontal_rad = 0.0;
  double kappa_vertical_rad = 0.0;

  // Depth (along the optical axis, from the anterior apex) of the limbus plane.
  double limbus_depth_mm() const;
  // Depth of the seam behind which the eyeball is the sclera's sphere: the
  // limbus plane, or deeper where the sphere is narrower than the limbus
  // there (a limbal band of the limbus's radius joins them).
  double sclera_seam_depth_mm() const;
  // How far from the axis the iris reaches in the traced eye. In a
  // two-surface eye whose iris lies behind the limbus plane, the posterior
  // cornea runs down to the iris plane (the chamber angle, at the iris
  // root): the iris ends where it meets it, and what lies beyond, inside the
  // corneoscleral shell, is opaque tissue. Otherwise the iris reaches out
  // to the sclera, so that no gap opens between them.
  double iris_outer_radius_mm() const;
};

// Presets; values and sources in docs/eye-models.md.
EyeModel keratometric_eye();  // one surface, n = 1.3375, sphere R = 7.8
EyeModel le_grand_eye();      // two spherical surfaces (7.8 / 6.5 mm, 1.3771 / 1.3374)
EyeModel navarro_eye();       // two aspheric surfaces (Q = -0.26 / 0), Navarro 1985
// Looks a preset up by name ("keratometric", "le_grand", "navarro").
std::optional<EyeModel> eye_model_preset(const std::string& name);
// The names eye_model_preset knows, in that order.
const std::vector<std::string>& eye_model_preset_names();

// A rule of an eye model's anatomy that the model breaks: the key as the
// scene format names it under an eye ("cornea.limbus_radius_mm"), its value
// as check::format_number writes it, and the rule.
struct AnatomyProblem {
  std::string key;
  std::string value;
  std::string rule;
};
// The first rule `m` breaks, or nothing: sizes positive and finite, a
// single-valued corneal cap out to the limbus, a posterior cornea behind
// the anterior one everywhere inside the limbus and starting in front of
// its plane, iris within the limbus and pupil within the iris, the pupil
// behind the cornea's inner surface, and a sclera that reaches the
// limbus from a centre of rotation behind it. The scene reader reports
// it at the eye's key; the renderer refuses an eye built in code with it.
std::optional<AnatomyProblem> anatomy_problem(const EyeModel& m);

// Optical axis from yaw and pitch in world coordinates (radians): yaw = pitch
// = 0 looks along world -z; yaw > 0 turns toward +x; pitch > 0 turns up (-y).
// o = (sin yaw cos pitch, -sin pitch, -cos yaw cos pitch).
UnitVector3 optical_axis_from_yaw_pitch(double yaw_rad, double pitch_rad);

// How an eye turns during an exposure (a saccade's motion blur): the yaw
// and pitch of its optical axis (optical_axis_from_yaw_pitch's angles)
// change at these rates, about its centre of rotation. The eye's pose is
// the one at mid-exposure.
struct EyeMotion {
  double yaw_deg_s = 0, pitch_deg_s = 0;
  bool still() const { return yaw_deg_s == 0 && pitch_deg_s == 0; }
};

class Eye {
 public:
  Eye(EyeModel model, const Pose& world_from_eye);

  // Cornea centre at `cornea_center`, optical axis `optical_axis`.
  static Eye with_cornea_center(EyeModel model, const Point3& cornea_center,
                                const UnitVector3& optical_axis);
  // Centre of rotation at `rotation_center`, optical axis `optical_axis`.
  static Eye with_rotation_center(EyeModel model, const Point3& rotation_center,
                                  const UnitVector3& optical_axis);
  // The eye rotated about `rotation_center` so that its visual axis (from
  // the cornea centre, kappa applied) passes through `target`. Throws
  // std::invalid_argument when the target is too close to be fixated.
  static Eye fixating(EyeModel model, const Point3& rotation_center, const Point3& target);
  // As above, with the cornea centre held at `cornea_center`.
  static Eye fixating_from_cornea_center(EyeModel model, const Point3& cornea_center,
                                         const Point3& target);
  // The eye rotated about `rotation_center` so that its visual axis (kappa
  // applied) points along `visual_axis`; eye +x is kept perpendicular to
  // the world's y (world_from_eye_rotation).
  static Eye with_visual_axis(EyeModel model, const Point3& rotation_center, const UnitVector3& visual_axis);

  const EyeModel& model() const { return model_; }
  // Albedos, iris texture, eyelids: what the renderer needs beyond geometry.
  const EyeAppearance& appearance() const { return appearance_; }
  void set_appearance(const EyeAppearance& appearance) { appearance_ = appearance; }
  const EyeMotion& motion() const { return motion_; }
  void set_motion(const EyeMotion& motion) { motion_ = motion; }
  // The eye `t_s` seconds after mid-exposure: its optical axis's yaw and
  // pitch moved by the motion's rates times t_s, the eye turned by the
  // shortest rotation from its axis to that one about the centre of
  // rotation; appearance and motion kept. t_s = 0 or a still eye: this eye.
  Eye at_time(double t_s) const;
  const Pose& world_from_eye() const { return world_from_eye_; }
  const Pose& eye_from_world() const { return eye_from_world_; }

  Point3 cornea_center() const;
  Point3 rotation_center() const;
  Point3 corneal_apex() const;
  UnitVector3 optical_axis() const;
  UnitVector3 visual_axis() const;
  Point3 pupil_center() const;
  // Border point at `angle_rad` around the pupil, measured in the iris plane
  // from eye +x toward eye +y.
  Point3 pupil_border_point(double angle_rad) const;
  // Whether a point of the anterior cornea lies on the cap (inside the limbus).
  bool on_cap(const Point3& world_point) const;
  // Whether the open segment between two points crosses the anterior
  // corneal cap (what stands out of the sclera's sphere in front).
  bool cap_crosses(const Point3& from, const Point3& to) const;

 private:
  EyeModel model_;
  Pose world_from_eye_;
  Pose eye_from_world_;
  EyeAppearance appearance_;
  EyeMotion motion_;
};

// The eye-frame axes for an optical axis o: x = normalize(e_x - (e_x.o) o),
// y = o cross x (falls back to e_y when o is within 1e-6 of +-e_x).
Rotation world_from_eye_rotation(const UnitVector3& optical_axis);

}  // namespace purkinje
