#include "purkinje/trackers/gaze.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "purkinje/models/eye.h"
#include "purkinje/models/optimizer.h"
#include "purkinje/trackers/cornea.h"
#include "purkinje/trackers/scoring.h"

namespace purkinje::trackers {

namespace {

// The nearer point where a ray meets a sphere, as the distance along the
// ray (> 0); nullopt when it passes by or the sphere is behind.
std::optional<double> enter_sphere(const Point3& origin, const Vector3& direction, const Point3& center,
                                   double radius) {
  const Vector3 from = origin - center;
  const double b = dot(direction, from);
  const double discriminant = b * b - (from.squared_norm() - radius * radius);
  if (!(discriminant >= 0)) return std::nullopt;
  const double s = -b - std::sqrt(discriminant);
  if (!(s > 0)) return std::nullopt;
  return s;
}

// Two unit vectors across a direction, for angular residuals about it.
std::pair<Vector3, Vector3> across(const UnitVector3& d) {
  const Vector3 axis = std::abs(d.x()) < 0.9 ? Vector3{1, 0, 0} : Vector3{0, 1, 0};
  const Vector3 u = cross(d, axis) / cross(d, axis).norm();
  return {u, cross(d, u)};
}

}  // namespace

std::vector<Pixel> ellipse_outline(const Ellipse& e, int points) {
  std::vector<Pixel> out;
  const double c = std::cos(e.angle_rad), s = std::sin(e.angle_rad);
  for (int i = 0; i < points; ++i) {
    const double t = 2 * std::numbers::pi * i / points;
    const double a = e.semi_axis_1_px * std::cos(t), b = e.semi_axis_2_px * std::sin(t);
    out.push_back({e.center.u + a * c - b * s, e.center.v + a * s + b * c});
  }
  return out;
}

std::optional<GazeFeatures> exact_gaze_features(const EyeInCameraTruth& view, PupilFeature pupil) {
  const Detections exact = exact_detections({view});
  GazeFeatures f;
  f.glints = exact.glints;
  if (pupil == PupilFeature::ellipse_center) {
    if (exact.pupils.empty()) return std::nullopt;
    f.pupil_center = exact.pupils.front().centre;
    return f;
  }
  if (view.pupil.refracted_center_status != PathStatus::ok) return std::nullopt;
  f.pupil_center = view.pupil.refracted_center;
  if (pupil == PupilFeature::outline) {
    for (const PupilBorderPointTruth& b : view.pupil.border) {
      if (b.status == PathStatus::ok) f.pupil_outline.push_back(b.pixel);
    }
    if (f.pupil_outline.size() < 5) return std::nullopt;
  }
  return f;
}

UnitVector3 visual_axis_for(const UnitVector3& optical_axis, double h, double v) {
  const Vector3 in_eye{std::sin(h) * std::cos(v), std::sin(v), std::cos(h) * std::cos(v)};
  return UnitVector3::normalize(world_from_eye_rotation(optical_axis) * in_eye);
}

namespace {

// A pixel's camera ray refracted into the model's cornea (Snell's law in
// vector form): where it enters, relative to the cornea's centre, and its
// unit direction inside. A conicoid cornea's apex points along `axis`.
// nullopt when the ray misses the cornea.
struct RefractedRay {
  Vector3 entry;
  Vector3 inside;
};

std::optional<RefractedRay> refract_into_cornea(const Point3& o, const UnitVector3& ray, const Point3& cornea_center,
                                                const UnitVector3& axis, const GazeEyeModel& model) {
  const double radius = model.cornea_radius_mm, q = model.cornea_asphericity;
  Vector3 entry, normal;
  if (q == 0) {
    const std::optional<double> to_cornea = enter_sphere(o, ray, cornea_center, radius);
    if (!to_cornea) return std::nullopt;
    entry = (o + *to_cornea * ray) - cornea_center;
    normal = entry / radius;
  } else {
    // The conicoid of cornea_glint.h, F(s) = |s|^2 - z^2 + (1 + Q)(R - z)^2
    // - 2 R (R - z) with z = a.s, along s = s0 + t d: a quadratic in t.
    const Vector3 s0 = o - cornea_center;
    const double z0 = dot(axis, s0), dz = dot(axis, ray.vector());
    const double a = 1 + q * dz * dz;
    const double half_b = dot(s0, ray.vector()) - q * (radius - z0) * dz;
    const double c = s0.squared_norm() - z0 * z0 + (1 + q) * (radius - z0) * (radius - z0) - 2 * radius * (radius - z0);
    const double discriminant = half_b * half_b - a * c;
    if (!(discriminant >= 0) || !(a > 0)) return std::nullopt;
    const double t = (-half_b - std::sqrt(discriminant)) / a;
    if (!(t > 0)) return std::nullopt;
    entry = s0 + t * ray.vector();
    const double z = dot(axis, entry);
    // In front of the equator only: behind it the ray would enter the head.
    if (!(z > radius - radius / (1 + q))) return std::nullopt;
    const Vector3 g = entry - q * (radius - z) * axis.vector();
    normal = g / g.norm();
  }
  const double eta = 1 / model.refractive_index;
  const double cos_in = -dot(normal, ray);
  const double sin2_out = eta * eta * (1 - cos_in * cos_in);
  return RefractedRay{entry, eta * ray + (eta * cos_in - std::sqrt(1 - sin2_out)) * normal};
}

std::optional<RefractedRay> refract_into_cornea(const Camera& camera, const Point3& cornea_center,
                                                const UnitVector3& axis, const Pixel& pixel,
                                                const GazeEyeModel& model) {
  return refract_into_cornea(camera.center(), camera.back_project(pixel), cornea_center, axis, model);
}

// The optical axis from the imaged pupil centre with a given cornea axis
// (for a conicoid's refraction).
std::optional<OpticalAxis> axis_from_center(const Camera& camera, const Point3& cornea_center,
                                            const UnitVector3& cornea_axis, const Pixel& pupil_center,
                                            const GazeEyeModel& model) {
  const std::optional<RefractedRay> ray = refract_into_cornea(camera, cornea_center, cornea_axis, pupil_center, model);
  if (!ray) return std::nullopt;
  const Point3 entry = cornea_center + ray->entry;
  const std::optional<double> to_pupil = enter_sphere(entry, ray->inside, cornea_center, model.pupil_depth_mm);
  if (!to_pupil) return std::nullopt;
  const Point3 pupil = entry + *to_pupil * ray->inside;
  const std::optional<UnitVector3> axis = UnitVector3::try_normalize(pupil - cornea_center);
  if (!axis) return std::nullopt;
  return OpticalAxis{pupil, *axis};
}

// A conicoid's refraction depends on the axis being sought: a fixed point,
// which settles within a few steps since the refraction hardly turns with
// the axis.
constexpr int kAxisIterations = 50;

}  // namespace

std::optional<OpticalAxis> optical_axis_from_pupil(const Camera& camera, const Point3& cornea_center,
                                                   const Pixel& pupil_center, const GazeEyeModel& model) {
  // The eye faces the camera, near enough for a start.
  std::optional<UnitVector3> axis = UnitVector3::try_normalize(camera.center() - cornea_center);
  if (!axis) return std::nullopt;
  double change = INFINITY;
  for (int i = 0; i < kAxisIterations; ++i) {
    const std::optional<OpticalAxis> next = axis_from_center(camera, cornea_center, *axis, pupil_center, model);
    if (!next || model.cornea_asphericity == 0) return next;
    const double step = angle_between(next->direction, *axis);
    axis = next->direction;
    // Done at 1e-12 rad, or once the steps stop shrinking (rounding).
    if (step < 1e-12 || (step >= change && step < 1e-10)) return next;
    change = step;
  }
  return std::nullopt;
}

std::optional<OpticalAxis> optical_axis_from_pupil_outline(const Camera& camera, const Point3& cornea_center,
                                                           const std::vector<Pixel>& outline,
                                                           const GazeEyeModel& model,
                                                           const std::optional<UnitVector3>& start) {
  // Entry points relative to the cornea's centre: the fixed point's
  // changes near convergence are far below a world coordinate's rounding.
  std::vector<RefractedRay> rays;
  std::optional<UnitVector3> axis = start;
  if (!axis) axis = UnitVector3::try_normalize(camera.center() - cornea_center);
  if (!axis) return std::nullopt;
  // For a sphere the rays do not depend on the axis: traced once. The
  // camera's rays never do: back-projected once.
  const Point3 o = camera.center();
  std::vector<UnitVector3> sight;
  sight.reserve(outline.size());
  for (const Pixel& p : outline) sight.push_back(camera.back_project(p));
  const auto trace = [&] {
    rays.clear();
    for (const UnitVector3& d : sight) {
      const std::optional<RefractedRay> ray = refract_into_cornea(o, d, cornea_center, *axis, model);
      if (ray) rays.push_back(*ray);
    }
    return rays.size() >= 5;
  };
  if (!trace()) return std::nullopt;
  if (!start) {
    Vector3 middle;
    for (const RefractedRay& r : rays) middle += r.entry;
    axis = UnitVector3::try_normalize(middle);
    if (!axis) return std::nullopt;
  }
  const double depth = model.pupil_depth_mm;
  double change = INFINITY;
  // The last plain step, while has_last_move (not a std::optional: g++ 12
  // warned falsely that its value may be used uninitialized).
  Vector3 last_move;
  bool has_last_move = false;
  std::optional<UnitVector3> before_jump;  // the plain step's axis, while an Aitken step is tried
  bool jumps = true;
  for (int iteration = 0; iteration < 200; ++iteration) {
    if (model.cornea_asphericity != 0 && iteration > 0 && !trace()) {
      // A jump that left the cornea: back to the plain step, no more jumps.
      if (!before_jump) return std::nullopt;
      axis = before_jump;
      jumps = false;
      if (!trace()) return std::nullopt;
    }
    before_jump.reset();
    // The least-squares circle by its normal equations: 3 x 3, whatever
    // the outline's length (the points lie about the axis, so they are
    // well conditioned).
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    // The rays meet the plane across the axis at the pupil's depth; a
    // circle fitted there (Kasa: linear in the centre and radius) gives
    // the centre whatever the points' spacing.
    const Vector3 on_axis = depth * axis->vector();
    const Vector3 reference = std::abs(axis->x()) < 0.9 ? Vector3{1, 0, 0} : Vector3{0, 1, 0};
    const Vector3 e1 = cross(*axis, reference) / cross(*axis, reference).norm();
    const Vector3 e2 = cross(*axis, e1);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const double along = dot(rays[i].inside, *axis);
      if (!(std::abs(along) > 1e-9)) return std::nullopt;
      const double s = (depth - dot(rays[i].entry, *axis)) / along;
      const Vector3 x = rays[i].entry + s * rays[i].inside - on_axis;
      const double u = dot(x, e1), v = dot(x, e2);
      const Eigen::Vector3d row(2 * u, 2 * v, 1);
      ata.noalias() += row * row.transpose();
      atb += row * (u * u + v * v);
    }
    const Eigen::Vector3d fit = ata.ldlt().solve(atb);
    if (!fit.allFinite()) return std::nullopt;
    const std::optional<UnitVector3> next = UnitVector3::try_normalize(on_axis + fit[0] * e1 + fit[1] * e2);
    if (!next) return std::nullopt;
    const double step = angle_between(*next, *axis);
    const Vector3 move = next->vector() - axis->vector();
    axis = next;
    // Done at 1e-12 rad, or once the steps stop shrinking (rounding).
    if (step < 1e-12 || (step >= change && step < 1e-10)) {
      return OpticalAxis{cornea_center + depth * axis->vector(), *axis};
    }
    // A conicoid's fixed point converges linearly, each step a near
    // constant multiple r of the last along one line (r about -0.05: the
    // axis overshoots and swings back): the rest of the way, r / (1 - r)
    // of this step, taken at once (Aitken), then two plain steps to measure
    // r again. The test above still decides when it has converged.
    if (has_last_move && jumps) {
      const double r = dot(move, last_move) / last_move.squared_norm();
      if (std::abs(r) < 0.5 && std::abs(dot(move, last_move)) > 0.9 * move.norm() * last_move.norm()) {
        if (const auto jumped = UnitVector3::try_normalize(axis->vector() + move * (r / (1 - r)))) {
          before_jump = axis;
          axis = jumped;
        }
        has_last_move = false;
        change = INFINITY;
        continue;
      }
    }
    if (model.cornea_asphericity != 0) {
      last_move = move;
      has_last_move = true;
    }
    change = step;
  }
  return std::nullopt;
}

namespace {

// The optical axis from the outline when the features have one, else from
// the imaged centre.
std::optional<OpticalAxis> pupil_axis(const Camera& camera, const Point3& cornea_center, const GazeFeatures& f,
                                      const GazeEyeModel& model) {
  const std::optional<OpticalAxis> from_center = optical_axis_from_pupil(camera, cornea_center, f.pupil_center, model);
  if (f.pupil_outline.size() < 5) return from_center;
  return optical_axis_from_pupil_outline(camera, cornea_center, f.pupil_outline, model,
                                         from_center ? std::optional<UnitVector3>(from_center->direction) : std::nullopt);
}

// The cornea's centres from the frames' glints, and each frame's optical
// axis from its pupil. A conicoid's glints depend on the axis and the
// axis on the centre: they alternate, from a sphere of the apex radius,
// until the centres settle. `glints` are the frames' told glints.
struct CorneaAndAxes {
  CorneaFit cornea;
  std::vector<std::optional<OpticalAxis>> axes;  // per frame; nullopt where the pupil's ray misses the model
  bool settled = true;
};

CorneaAndAxes cornea_and_axes(const Camera& camera, const std::vector<Illuminator>& lights,
                              const std::vector<GlintObservation>& glints, const std::vector<GazeFeatures>& frames,
                              const GazeEyeModel& model, const CorneaFitSettings& settings,
                              std::vector<Point3> starts) {
  CorneaAndAxes out;
  CorneaFitSettings sphere = settings;
  sphere.cornea_asphericity = 0;
  // The pupils refracted at the cornea as fitted, radius too.
  const auto axes_at = [&](const CorneaFit& fit) {
    GazeEyeModel fitted = model;
    fitted.cornea_radius_mm = fit.cornea_radius_mm;
    out.axes.clear();
    for (std::size_t f = 0; f < frames.size(); ++f) {
      out.axes.push_back(pupil_axis(camera, fit.centers[f], frames[f], fitted));
    }
  };
  out.cornea = fit_cornea({camera}, lights, glints, starts, sphere);
  if (!out.cornea.converged || !out.cornea.has_covariance()) return out;
  axes_at(out.cornea);
  if (model.cornea_asphericity == 0) return out;
  CorneaFitSettings conicoid = settings;
  conicoid.cornea_asphericity = model.cornea_asphericity;
  out.settled = false;
  for (int pass = 0; pass < kAxisIterations && !out.settled; ++pass) {
    std::vector<UnitVector3> directions;
    for (const std::optional<OpticalAxis>& a : out.axes) {
      if (!a) return out;
      directions.push_back(a->direction);
    }
    starts = out.cornea.centers;
    out.cornea = fit_cornea({camera}, lights, glints, starts, conicoid, directions);
    if (!out.cornea.converged || !out.cornea.has_covariance()) return out;
    axes_at(out.cornea);
    // Settled at 1e-9 of the distance (0.6 nm at 600 mm): far below any
    // noise, and above the fit's own stopping tolerance (1e-10 of all
    // centres' coordinates together).
    double moved = 0, scale = 1;
    for (std::size_t f = 0; f < starts.size(); ++f) {
      moved = std::max(moved, distance(starts[f], out.cornea.centers[f]));
      scale = std::max(scale, distance(camera.center(), out.cornea.centers[f]));
    }
    out.settled = moved < 1e-9 * scale;
  }
  return out;
}

void check(const FeatureNoise& noise, const std::string& owner) {
  const auto fail = [&](const char* key, double value, const char* rule) {
    std::ostringstream text;  // not to_string, which prints a tiny value as 0.000000
    text << owner << "." << key << " = " << value << ": " << rule;
    throw std::invalid_argument(text.str());
  };
  if (!(noise.glint_px > 0 && std::isfinite(noise.glint_px))) fail("glint_px", noise.glint_px, "must be finite and > 0");
  if (!(noise.pupil_px > 0 && std::isfinite(noise.pupil_px))) fail("pupil_px", noise.pupil_px, "must be finite and > 0");
  if (!(noise.glint_sd_scale >= 0 && std::isfinite(noise.glint_sd_scale))) {
    fail("glint_sd_scale", noise.glint_sd_scale, "must be finite and >= 0 (0: the glints' own deviations are not used)");
  }
}

// A glint's standard deviation along u (axis 0) or v, as the cornea fit
// takes it: its observation's own, or glint_px.
double glint_sd(const Glint& g, int axis, const FeatureNoise& noise) {
  const GlintObservation o = observation_of(g, 0, 0, noise.glint_sd_scale);
  const double own = axis == 0 ? o.sd_u_px : o.sd_v_px;
  return own > 0 ? own : noise.glint_px;
}

// The estimate without its uncertainty.
ModelGaze model_gaze(const Camera& camera, const std::vector<Illuminator>& lights, const GazeFeatures& features,
                     const GazeEyeModel& model, const Screen& screen, const Point3& start, const FeatureNoise& noise,
                     double reject_beyond_sd, std::vector<int>* rejected = nullptr) {
  ModelGaze out;
  CorneaFitSettings settings;
  settings.cornea_radius_mm = model.cornea_radius_mm;
  settings.pixel_noise_px = noise.glint_px;
  settings.reject_beyond_sd = reject_beyond_sd;
  std::vector<GlintObservation> glints;
  add_observations(glints, features.glints, 0, 0, noise.glint_sd_scale);
  const CorneaAndAxes fitted = cornea_and_axes(camera, lights, glints, {features}, model, settings, {start});
  const CorneaFit& cornea = fitted.cornea;
  out.warnings = cornea.warnings;
  out.cornea_center = cornea.centers.front();
  if (rejected != nullptr) *rejected = cornea.rejected;
  if (!cornea.converged || !cornea.has_covariance()) {
    out.warnings.push_back("no gaze: the cornea's centre is not determined by the glints");
    return out;
  }
  // A sphere's centre stands without the pupil; a conicoid's only once
  // it has settled with the pupil's axis.
  if (fitted.settled) {
    out.cornea_determined = true;
    out.cornea_covariance_mm2 = cornea.center_covariance(0);
  }
  const std::optional<OpticalAxis>& axis = fitted.axes.front();
  if (!axis) {
    out.warnings.push_back("no gaze: the pupil's ray misses the model's cornea or pupil");
    return out;
  }
  if (!fitted.settled) {
    out.warnings.push_back("no gaze: the conicoid cornea's centre and the pupil's axis did not settle together");
    return out;
  }
  out.pupil_center = axis->pupil_center;
  out.optical_axis = axis->direction;
  out.visual_axis = visual_axis_for(axis->direction, model.kappa_horizontal_rad, model.kappa_vertical_rad);
  out.on_screen = screen.hit(out.cornea_center, out.visual_axis);
  out.valid = true;
  return out;
}

}  // namespace

ModelGaze estimate_model_gaze(const Camera& camera, const std::vector<Illuminator>& lights,
                              const GazeFeatures& features, const GazeEyeModel& model, const Screen& screen,
                              const Point3& start, const std::optional<FeatureNoise>& given_noise, bool propagate) {
  const FeatureNoise noise = given_noise.value_or(FeatureNoise{});
  check(noise, "estimate_model_gaze: noise");
  std::vector<int> rejected;
  ModelGaze out =
      model_gaze(camera, lights, features, model, screen, start, noise, CorneaFitSettings{}.reject_beyond_sd, &rejected);
  if (!given_noise || !propagate || !out.valid) return out;
  // Each feature coordinate moved both ways by a small step; the cornea's
  // centre's and the screen point's changes give the Jacobians, and their
  // covariances follow. A conicoid's centre moves with the pupil too,
  // through the axis its glints are fitted about, which the glint fit's
  // own covariance holds fixed. The glints the estimate rejected stay
  // out, and no more are rejected: a glint near the bound must not flip
  // between the two sides.
  GazeFeatures kept = features;
  int told = 0;
  for (Glint& g : kept.glints) {
    if (g.illuminator < 0) continue;
    if (std::find(rejected.begin(), rejected.end(), told++) != rejected.end()) g.illuminator = -1;
  }
  constexpr double step_px = 1e-3;
  Eigen::Matrix3d cornea_covariance = Eigen::Matrix3d::Zero();
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();
  // A moved feature that takes the gaze off the screen costs the screen
  // point's covariance only: the cornea's columns stand.
  bool screen_ok = out.on_screen.has_value();
  const auto add = [&](GazeFeatures moved_plus, GazeFeatures moved_minus, double sd_px) {
    const ModelGaze plus = model_gaze(camera, lights, moved_plus, model, screen, out.cornea_center, noise, 0);
    const ModelGaze minus = model_gaze(camera, lights, moved_minus, model, screen, out.cornea_center, noise, 0);
    if (!plus.valid || !minus.valid) return false;
    const Vector3 moved = (plus.cornea_center - minus.cornea_center) / (2 * step_px);
    const Eigen::Vector3d centre_column(moved.x, moved.y, moved.z);
    cornea_covariance += sd_px * sd_px * centre_column * centre_column.transpose();
    if (!screen_ok) return true;
    if (!plus.on_screen || !minus.on_screen) {
      screen_ok = false;
      return true;
    }
    const Eigen::Vector2d column((plus.on_screen->x_mm - minus.on_screen->x_mm) / (2 * step_px),
                                 (plus.on_screen->y_mm - minus.on_screen->y_mm) / (2 * step_px));
    covariance += sd_px * sd_px * column * column.transpose();
    return true;
  };
  bool ok = true;
  for (std::size_t i = 0; i < kept.glints.size() && ok; ++i) {
    if (kept.glints[i].illuminator < 0) continue;
    for (int axis = 0; axis < 2 && ok; ++axis) {
      GazeFeatures plus = kept, minus = kept;
      (axis == 0 ? plus.glints[i].centre.u : plus.glints[i].centre.v) += step_px;
      (axis == 0 ? minus.glints[i].centre.u : minus.glints[i].centre.v) -= step_px;
      ok = add(plus, minus, glint_sd(kept.glints[i], axis, noise));
    }
  }
  // The pupil moved as a whole: its centre and its outline together.
  for (int axis = 0; axis < 2 && ok; ++axis) {
    GazeFeatures plus = kept, minus = kept;
    const auto shift = [&](GazeFeatures& f, double by) {
      (axis == 0 ? f.pupil_center.u : f.pupil_center.v) += by;
      for (Pixel& p : f.pupil_outline) (axis == 0 ? p.u : p.v) += by;
    };
    shift(plus, step_px);
    shift(minus, -step_px);
    ok = add(plus, minus, noise.pupil_px);
  }
  if (!ok) {
    out.warnings.push_back(
        "no propagated uncertainty: the estimate fails for features a thousandth of a pixel away (the cornea's "
        "covariance is the glint fit's, about a fixed axis)");
    return out;
  }
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) out.cornea_covariance_mm2[3 * a + b] = cornea_covariance(a, b);
  }
  if (out.on_screen && !screen_ok) {
    out.warnings.push_back("no screen uncertainty: the gaze leaves the screen for features a thousandth of a pixel away");
  }
  if (screen_ok) {
    out.on_screen_covariance_mm2 = std::array<double, 4>{covariance(0, 0), covariance(0, 1), covariance(1, 0),
                                                         covariance(1, 1)};
  }
  return out;
}

namespace {

// The centre of rotation, where the optical axes through the cornea's
// centres meet in the least-squares sense, and its standard deviations;
// left unset when an axis is missing or the axes do not determine it.
void fit_rotation_center(ModelGazeCalibration& out, const Camera& camera, const std::vector<Point3>& centers,
                         const std::vector<GazeFeatures>& frames) {
  const int rows = 3 * static_cast<int>(frames.size());
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(rows, 4);
  Eigen::VectorXd c(rows);
  bool axes = true;
  for (std::size_t f = 0; f < frames.size() && axes; ++f) {
    const std::optional<OpticalAxis> axis = pupil_axis(camera, centers[f], frames[f], out.model);
    axes = axis.has_value();
    if (!axes) break;
    for (int k = 0; k < 3; ++k) {
      const int row = 3 * static_cast<int>(f) + k;
      a(row, k) = 1;
      a(row, 3) = axis->direction.vector()[k];
      c[row] = centers[f][k];
    }
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd singular = svd.singularValues();
  if (axes && rows > 4 && singular[3] > 1e-6 * singular[0]) {
    const Eigen::VectorXd x = svd.solve(c);
    const double rss = (a * x - c).squaredNorm();
    // (A^T A)^-1 = V S^-2 V^T: no diagonal can come out negative.
    const Eigen::MatrixXd covariance = rss / (rows - 4) * svd.matrixV() *
                                       singular.cwiseAbs2().cwiseInverse().asDiagonal() * svd.matrixV().transpose();
    out.rotation_center = Point3{x[0], x[1], x[2]};
    out.rotation_distance_mm = x[3];
    for (int k = 0; k < 3; ++k) out.rotation_center_sd_mm[k] = std::sqrt(covariance(k, k));
  }
}

// One calibration with the cornea's axes from `initial`'s pupil depth.
ModelGazeCalibration calibrate_pass(const Camera& camera, const std::vector<Illuminator>& lights,
                                    const std::vector<GazeFeatures>& frames, const std::vector<Point3>& targets,
                                    const GazeEyeModel& initial, const std::vector<Point3>& starts,
                                    const ModelGazeCalibrationSettings& settings) {
  const int n = settings.fit_pupil_depth ? 3 : 2;
  if (frames.size() != targets.size()) {
    throw std::invalid_argument("calibrate_model_gaze: " + std::to_string(frames.size()) + " frames but " +
                                std::to_string(targets.size()) + " targets: must be as many");
  }
  if (2 * static_cast<int>(frames.size()) < n + 1) {
    throw std::invalid_argument("calibrate_model_gaze: " + std::to_string(frames.size()) +
                                " targets: too few for the unknowns");
  }
  ModelGazeCalibration out;
  out.model = initial;

  // The cornea first, from the glints (a conicoid's with the pupils' axes,
  // which the pupil's depth moves): its centres do not depend on kappa.
  std::vector<GlintObservation> glints;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    add_observations(glints, frames[f].glints, static_cast<int>(f), 0, settings.noise.glint_sd_scale);
  }
  CorneaFitSettings cornea_settings;
  cornea_settings.cornea_radius_mm = initial.cornea_radius_mm;
  cornea_settings.fit_radius = settings.fit_cornea_radius;
  cornea_settings.pixel_noise_px = settings.noise.glint_px;
  const CorneaAndAxes fitted = cornea_and_axes(camera, lights, glints, frames, initial, cornea_settings, starts);
  const CorneaFit& cornea = fitted.cornea;
  out.warnings = cornea.warnings;
  out.cornea_centers = cornea.centers;
  if (!cornea.converged || !cornea.has_covariance()) {
    out.warnings.push_back("not calibrated: the glints do not determine the cornea");
    return out;
  }
  if (!fitted.settled) {
    const bool missed = std::any_of(fitted.axes.begin(), fitted.axes.end(),
                                    [](const std::optional<OpticalAxis>& a) { return !a; });
    out.warnings.push_back(missed ? "not calibrated: a pupil's ray misses the model's cornea or pupil"
                                  : "not calibrated: the conicoid cornea's centres and the pupils' axes did not "
                                    "settle together");
    return out;
  }
  out.model.cornea_radius_mm = cornea.cornea_radius_mm;
  out.cornea_radius_sd_mm = cornea.radius_sd_mm();

  const int m = 2 * static_cast<int>(frames.size());
  std::vector<std::pair<Vector3, Vector3>> bases;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const std::optional<UnitVector3> want = UnitVector3::try_normalize(targets[f] - cornea.centers[f]);
    if (!want) throw std::invalid_argument("calibrate_model_gaze: target " + std::to_string(f) + " is at the eye");
    bases.push_back(across(*want));
  }
  // Residuals: the visual axis across the direction to each target, about
  // the angle between them in radians.
  const auto predict = [&](const double* x, double* r) {
    GazeEyeModel model = out.model;
    model.kappa_horizontal_rad = x[0];
    model.kappa_vertical_rad = x[1];
    if (settings.fit_pupil_depth) model.pupil_depth_mm = x[2];
    if (!(model.pupil_depth_mm > 0 && model.pupil_depth_mm < model.cornea_radius_mm)) return false;
    for (std::size_t f = 0; f < frames.size(); ++f) {
      const std::optional<OpticalAxis> axis = pupil_axis(camera, cornea.centers[f], frames[f], model);
      if (!axis) return false;
      const UnitVector3 v = visual_axis_for(axis->direction, x[0], x[1]);
      r[2 * f] = dot(v, bases[f].first);
      r[2 * f + 1] = dot(v, bases[f].second);
    }
    return true;
  };
  std::vector<double> plus(m), minus(m);
  const optimizer::ResidualFunction residuals = [&](const double* x, double* r, double* jacobian) {
    if (!predict(x, r)) return false;
    if (jacobian == nullptr) return true;
    for (int k = 0; k < n; ++k) {
      // Central differences: the chain is smooth, and 1e-7 keeps the
      // truncation (h^2) and rounding (eps / h) errors near 1e-10.
      const double h = k < 2 ? 1e-7 : 1e-6;
      std::vector<double> xp(x, x + n), xm(x, x + n);
      xp[k] += h, xm[k] -= h;
      if (!predict(xp.data(), plus.data()) || !predict(xm.data(), minus.data())) return false;
      for (int i = 0; i < m; ++i) jacobian[i * n + k] = (plus[i] - minus[i]) / (2 * h);
    }
    return true;
  };
  std::vector<double> x{initial.kappa_horizontal_rad, initial.kappa_vertical_rad};
  if (settings.fit_pupil_depth) x.push_back(initial.pupil_depth_mm);
  optimizer::Options options;
  options.parameter_tolerance = 1e-12;
  options.function_tolerance = 1e-14;
  const optimizer::Summary summary = optimizer::solve(m, x, residuals, options);
  out.converged = summary.converged;
  out.model.kappa_horizontal_rad = x[0];
  out.model.kappa_vertical_rad = x[1];
  if (settings.fit_pupil_depth) out.model.pupil_depth_mm = x[2];

  std::vector<double> r(m), jacobian(static_cast<std::size_t>(m) * n);
  if (!residuals(x.data(), r.data(), jacobian.data())) {
    out.converged = false;
    out.warnings.push_back("not calibrated: a pupil's ray misses the model at the estimate (" + summary.message + ")");
    return out;
  }
  double sum = 0;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    // The residuals are the sine of the angle to the target, split in two.
    const double angle = std::asin(std::min(1.0, std::hypot(r[2 * f], r[2 * f + 1])));
    sum += angle * angle;
  }
  out.rms_error_rad = std::sqrt(sum / frames.size());
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> j(jacobian.data(), m, n);
  const Eigen::MatrixXd normal = j.transpose() * j;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(normal);
  const double lo = eigen.eigenvalues()(0), hi = eigen.eigenvalues()(n - 1);
  if (!(lo > 0 && hi / lo < 1e12)) {
    out.warnings.push_back("the targets do not determine kappa and the pupil's depth apart: spread them over the screen");
  } else if (m > n) {
    double rss = 0;
    for (const double e : r) rss += e * e;
    // From the eigenvalues (all > 0 here), so that no diagonal comes out
    // negative by rounding.
    const Eigen::MatrixXd covariance = rss / (m - n) * eigen.eigenvectors() *
                                       eigen.eigenvalues().cwiseInverse().asDiagonal() *
                                       eigen.eigenvectors().transpose();
    out.covariance.assign(covariance.data(), covariance.data() + n * n);
  }
  if (!out.converged) out.warnings.push_back("the calibration stopped before converging: " + summary.message);

  fit_rotation_center(out, camera, cornea.centers, frames);
  return out;
}

// A conicoid's centres depend on the axes, and so on the pupil's depth:
// with the depth fitted, passes repeat from the last depth until it
// settles. A sphere's take one pass.
ModelGazeCalibration calibrate_once(const Camera& camera, const std::vector<Illuminator>& lights,
                                    const std::vector<GazeFeatures>& frames, const std::vector<Point3>& targets,
                                    const GazeEyeModel& initial, const Point3& start,
                                    const ModelGazeCalibrationSettings& settings) {
  ModelGazeCalibration out =
      calibrate_pass(camera, lights, frames, targets, initial, std::vector<Point3>(frames.size(), start), settings);
  if (initial.cornea_asphericity == 0 || !settings.fit_pupil_depth) return out;
  GazeEyeModel from = initial;
  for (int pass = 0; pass < kAxisIterations; ++pass) {
    if (!out.converged || std::abs(out.model.pupil_depth_mm - from.pupil_depth_mm) < 1e-10) return out;
    from.pupil_depth_mm = out.model.pupil_depth_mm;
    from.kappa_horizontal_rad = out.model.kappa_horizontal_rad;
    from.kappa_vertical_rad = out.model.kappa_vertical_rad;
    out = calibrate_pass(camera, lights, frames, targets, from, out.cornea_centers, settings);
  }
  out.converged = false;
  out.warnings.push_back("the calibration stopped before converging: the pupil's depth and the conicoid "
                         "cornea's centres did not settle together");
  return out;
}

// The calibration's estimates as one vector: kappa (and the depth), then
// the centre of rotation when placed.
std::vector<double> estimates(const ModelGazeCalibration& c, bool depth) {
  std::vector<double> x{c.model.kappa_horizontal_rad, c.model.kappa_vertical_rad};
  if (depth) x.push_back(c.model.pupil_depth_mm);
  if (c.rotation_center) x.insert(x.end(), {c.rotation_center->x, c.rotation_center->y, c.rotation_center->z});
  return x;
}

}  // namespace

ModelGazeCalibration calibrate_model_gaze(const Camera& camera, const std::vector<Illuminator>& lights,
                                          const std::vector<GazeFeatures>& frames,
                                          const std::vector<Point3>& targets, const GazeEyeModel& initial,
                                          const Point3& start, const ModelGazeCalibrationSettings& settings) {
  check(settings.noise, "calibrate_model_gaze: settings.noise");
  ModelGazeCalibration out = calibrate_once(camera, lights, frames, targets, initial, start, settings);
  if (!settings.propagate_noise || !out.converged || out.covariance.empty()) return out;
  // Each feature coordinate moved both ways by a small step, the whole
  // calibration run again from the estimate: the Jacobian of the
  // estimates by the features, and their covariance J diag(sd^2) J^T.
  const FeatureNoise& noise = settings.noise;
  const bool depth = settings.fit_pupil_depth;
  const std::vector<double> center = estimates(out, depth);
  const Eigen::Index k = static_cast<Eigen::Index>(center.size());
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(k, k);
  constexpr double step_px = 1e-3;
  ModelGazeCalibrationSettings once = settings;
  once.propagate_noise = false;
  const GazeEyeModel from = out.model;
  const auto add = [&](const std::vector<GazeFeatures>& plus, const std::vector<GazeFeatures>& minus, double sd) {
    const ModelGazeCalibration p = calibrate_once(camera, lights, plus, targets, from, start, once);
    const ModelGazeCalibration m = calibrate_once(camera, lights, minus, targets, from, start, once);
    const std::vector<double> xp = estimates(p, depth), xm = estimates(m, depth);
    if (!p.converged || !m.converged || static_cast<Eigen::Index>(xp.size()) != k ||
        static_cast<Eigen::Index>(xm.size()) != k) {
      return false;
    }
    Eigen::VectorXd column(k);
    for (Eigen::Index i = 0; i < k; ++i) column[i] = (xp[i] - xm[i]) / (2 * step_px);
    covariance += sd * sd * column * column.transpose();
    return true;
  };
  bool ok = true;
  for (std::size_t f = 0; f < frames.size() && ok; ++f) {
    for (std::size_t g = 0; g < frames[f].glints.size() && ok; ++g) {
      if (frames[f].glints[g].illuminator < 0) continue;
      for (int axis = 0; axis < 2 && ok; ++axis) {
        std::vector<GazeFeatures> plus = frames, minus = frames;
        (axis == 0 ? plus[f].glints[g].centre.u : plus[f].glints[g].centre.v) += step_px;
        (axis == 0 ? minus[f].glints[g].centre.u : minus[f].glints[g].centre.v) -= step_px;
        ok = add(plus, minus, glint_sd(frames[f].glints[g], axis, noise));
      }
    }
    // The pupil moved as a whole: its centre and its outline together.
    for (int axis = 0; axis < 2 && ok; ++axis) {
      std::vector<GazeFeatures> plus = frames, minus = frames;
      const auto shift = [&](GazeFeatures& moved, double by) {
        (axis == 0 ? moved.pupil_center.u : moved.pupil_center.v) += by;
        for (Pixel& p : moved.pupil_outline) (axis == 0 ? p.u : p.v) += by;
      };
      shift(plus[f], step_px);
      shift(minus[f], -step_px);
      ok = add(plus, minus, noise.pupil_px);
    }
  }
  if (!ok) {
    out.warnings.push_back("uncertainty from the residuals' scatter: the calibration fails for features a "
                           "thousandth of a pixel away");
    return out;
  }
  const Eigen::Index n = depth ? 3 : 2;
  for (Eigen::Index a = 0; a < n; ++a) {
    for (Eigen::Index b = 0; b < n; ++b) out.covariance[a * n + b] = covariance(a, b);
  }
  if (out.rotation_center) {
    for (int i = 0; i < 3; ++i) out.rotation_center_sd_mm[i] = std::sqrt(covariance(n + i, n + i));
  }
  return out;
}

std::optional<Pixel> pupil_glint_vector(const GazeFeatures& features) {
  double u = 0, v = 0;
  int count = 0;
  for (const Glint& g : features.glints) {
    if (g.illuminator < 0) continue;
    u += g.centre.u, v += g.centre.v;
    ++count;
  }
  if (count == 0) return std::nullopt;
  return Pixel{features.pupil_center.u - u / count, features.pupil_center.v - v / count};
}

PolynomialGaze PolynomialGaze::calibrate(const std::vector<GazeFeatures>& frames,
                                         const std::vector<ScreenPoint>& targets) {
  if (frames.size() != targets.size()) {
    throw std::invalid_argument("PolynomialGaze::calibrate: " + std::to_string(frames.size()) + " frames but " +
                                std::to_string(targets.size()) + " targets: must be as many");
  }
  if (frames.size() < 6) {
    throw std::invalid_argument("PolynomialGaze::calibrate: " + std::to_string(frames.size()) +
                                " frames: a second-order polynomial needs at least 6");
  }
  std::vector<Pixel> vectors;
  double scale = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const std::optional<Pixel> d = pupil_glint_vector(frames[i]);
    if (!d) {
      throw std::invalid_argument("PolynomialGaze::calibrate: frame " + std::to_string(i) +
                                  " has no glint with its light told");
    }
    vectors.push_back(*d);
    scale = std::max({scale, std::abs(d->u), std::abs(d->v)});
  }
  PolynomialGaze out;
  out.scale_px_ = scale > 0 ? scale : 1;  // the basis on [-1, 1], for a well-conditioned fit
  const int count = static_cast<int>(frames.size());
  Eigen::MatrixXd a(count, 6);
  Eigen::VectorXd bx(count), by(count);
  for (int i = 0; i < count; ++i) {
    const double x = vectors[i].u / out.scale_px_, y = vectors[i].v / out.scale_px_;
    a.row(i) << 1, x, y, x * y, x * x, y * y;
    bx[i] = targets[i].x_mm;
    by[i] = targets[i].y_mm;
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
  if (qr.rank() < 6) {
    throw std::invalid_argument(
        "PolynomialGaze::calibrate: the pupil-glint vectors are degenerate for a second-order polynomial "
        "(rank " + std::to_string(qr.rank()) + " of 6): spread the targets over the screen");
  }
  const Eigen::VectorXd cx = qr.solve(bx), cy = qr.solve(by);
  for (int k = 0; k < 6; ++k) out.x_[k] = cx[k], out.y_[k] = cy[k];
  const Eigen::VectorXd ex = a * cx - bx, ey = a * cy - by;
  out.rms_residual_mm_ = std::sqrt((ex.squaredNorm() + ey.squaredNorm()) / count);
  return out;
}

std::optional<ScreenPoint> PolynomialGaze::estimate(const GazeFeatures& features) const {
  const std::optional<Pixel> d = pupil_glint_vector(features);
  if (!d) return std::nullopt;
  const double x = d->u / scale_px_, y = d->v / scale_px_;
  const double basis[6] = {1, x, y, x * y, x * x, y * y};
  ScreenPoint p;
  for (int k = 0; k < 6; ++k) {
    p.x_mm += x_[k] * basis[k];
    p.y_mm += y_[k] * basis[k];
  }
  return p;
}

}  // namespace purkinje::trackers
