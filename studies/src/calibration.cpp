// The calibration study (`purkinje calibrate`): see calibration.h.

#include "purkinje/studies/calibration.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "purkinje/models/labels.h"
#include "purkinje/renderer/render.h"
#include "purkinje/studies/tracker.h"
#include "purkinje/trackers/cornea.h"
#include "purkinje/trackers/image.h"

namespace purkinje::studies {
namespace {

constexpr double kDegree = std::numbers::pi / 180;

// One rendered frame: the eye fixating a target from a head position.
struct Frame {
  int position = 0;  // 0: the scene's eye position; then the head moves in order
  ScreenPoint target;
  Point3 cornea_center;                 // truth
  std::optional<trackers::GazeFeatures> found;  // from the image; nullopt: a glint or the pupil missed
  int glints_told = 0;
  // The detections' errors against the labels, per axis (px): each told
  // glint's on the cornea, and the pupil ellipse's centre; and the errors
  // over their reported standard deviations, of the glints that report one.
  std::vector<double> glint_errors_px, pupil_errors_px, glint_errors_sd;
  std::vector<double> glint_errors_without_sd_px;  // of the glints that report none
};

std::string format(double value, int digits = 4) {
  std::ostringstream out;
  out.precision(digits);
  out << value;
  return out.str();
}

// The features exactly where the scene puts them: each light's glint that
// reaches the camera, and the pupil's whole imaged outline.
void exact_features(const Scene& scene, Frame& f) {
  const SceneTruth truth = compute_truth(scene);
  const EyeInCameraTruth& view = truth.views.front();
  std::vector<trackers::Glint> glints;
  for (const GlintTruth& label : view.glints) {
    if (label.status != PathStatus::ok) continue;
    trackers::Glint g;
    g.centre = label.pixel;
    g.illuminator = label.illuminator;
    glints.push_back(g);
  }
  f.glints_told = static_cast<int>(glints.size());
  if (view.pupil.ellipse_valid && f.glints_told >= 2) {
    f.found = trackers::GazeFeatures{glints, view.pupil.ellipse.center, trackers::ellipse_outline(view.pupil.ellipse)};
  }
}

// The eye fixating `target` from rotation centre `center`: rendered and
// read by the detectors, or its exact features.
Frame frame_at(const Scene& rig, const Point3& center, int position, const ScreenPoint& target,
               const Tracker& tracker, std::uint64_t seed, bool exact) {
  Frame f;
  f.position = position;
  f.target = target;
  Scene scene = rig;
  const Eye& nominal = rig.eyes.front();
  // A fixation: the eye holds still on the target, whatever motion the
  // rig's eye had.
  Eye eye = Eye::fixating(nominal.model(), center, rig.screen->at(target));
  eye.set_appearance(nominal.appearance());
  scene.eyes = {eye};
  f.cornea_center = eye.cornea_center();
  if (exact) {
    exact_features(scene, f);
    return f;
  }
  renderer::RenderOptions options;
  options.seed = seed;
  const renderer::RenderResult result = renderer::render(scene, 0, options);
  const trackers::GreyView image =
      trackers::grey_view(std::span<const std::uint16_t>(result.sensor.values), result.sensor.width,
                          result.sensor.height, result.sensor.bits);
  const trackers::Detections found = tracker.track(image);
  const std::vector<trackers::Glint>& glints = found.glints;
  const trackers::PupilFound* pupil = found.pupils.empty() ? nullptr : &found.pupils.front();
  const EyeInCameraTruth& view = result.truth.views.front();
  for (const trackers::Glint& g : glints) {
    if (g.illuminator < 0) continue;
    ++f.glints_told;
    const GlintTruth& label = view.glints[g.illuminator];
    if (label.status == PathStatus::ok && std::hypot(g.centre.u - label.pixel.u, g.centre.v - label.pixel.v) <= 5) {
      f.glint_errors_px.push_back(g.centre.u - label.pixel.u);
      f.glint_errors_px.push_back(g.centre.v - label.pixel.v);
      if (g.centre_sd_u_px > 0 && g.centre_sd_v_px > 0) {
        f.glint_errors_sd.push_back((g.centre.u - label.pixel.u) / g.centre_sd_u_px);
        f.glint_errors_sd.push_back((g.centre.v - label.pixel.v) / g.centre_sd_v_px);
      } else {
        f.glint_errors_without_sd_px.push_back(g.centre.u - label.pixel.u);
        f.glint_errors_without_sd_px.push_back(g.centre.v - label.pixel.v);
      }
    }
  }
  if (pupil && view.pupil.ellipse_valid) {
    const Pixel& label = view.pupil.ellipse.center;
    if (std::hypot(pupil->centre.u - label.u, pupil->centre.v - label.v) <= 5) {
      f.pupil_errors_px = {pupil->centre.u - label.u, pupil->centre.v - label.v};
    }
  }
  if (pupil && f.glints_told >= 2) {
    f.found = trackers::GazeFeatures{glints, pupil->centre, trackers::ellipse_outline(*pupil->ellipse)};
  }
  return f;
}

// The RMS of a frame's detection errors per axis; empty when there are none.
std::string rms(const std::vector<double>& errors) {
  if (errors.empty()) return "";
  double sum = 0;
  for (const double e : errors) sum += e * e;
  return format(std::sqrt(sum / static_cast<double>(errors.size())), 6);
}

// Summaries of one method at one head position.
struct Tally {
  std::vector<double> errors_deg;
  int missing = 0;
  int within_3sd_x = 0, within_3sd_y = 0, with_sd = 0;
  std::vector<double> sd_deg;  // each estimate's reported s.d. on the screen (RMS of both axes) as an angle at the eye
};

void add_errors(Results& r, const std::string& prefix, const Tally& t) {
  std::vector<double> e = t.errors_deg;
  std::sort(e.begin(), e.end());
  r.add(prefix + "frames", static_cast<double>(e.size()));
  r.add(prefix + "frames_without_estimate", static_cast<double>(t.missing));
  if (e.empty()) return;
  double sum = 0;
  for (const double x : e) sum += x;
  r.add(prefix + "error_mean", sum / e.size(), "deg");
  r.add(prefix + "error_median", e[e.size() / 2], "deg");
  r.add(prefix + "error_p95", e[std::min(e.size() - 1, static_cast<std::size_t>(0.95 * e.size()))], "deg");
  r.add(prefix + "error_max", e.back(), "deg");
  if (t.with_sd > 0) {
    r.add(prefix + "within_3sd_screen_x", 100.0 * t.within_3sd_x / t.with_sd, "%");
    r.add(prefix + "within_3sd_screen_y", 100.0 * t.within_3sd_y / t.with_sd, "%");
    std::vector<double> sd = t.sd_deg;
    std::nth_element(sd.begin(), sd.begin() + static_cast<std::ptrdiff_t>(sd.size() / 2), sd.end());
    r.add(prefix + "sd_median", sd[sd.size() / 2], "deg");
  }
}

// The eye model the tracker assumes: the scene eye's anterior cornea (or
// the one asked for) with one refracting surface, whose index is the
// eye's own behind a one-surface cornea and otherwise the keratometric
// 1.3375, which gives the anterior radius the whole cornea's power.
trackers::GazeEyeModel tracker_eye(const Scene& rig, const CalibrationSettings& settings) {
  const EyeModel& scene_eye = rig.eyes.front().model();
  trackers::GazeEyeModel nominal;
  nominal.cornea_radius_mm =
      settings.tracker_cornea ? (*settings.tracker_cornea)[0] : scene_eye.anterior_cornea.radius_mm;
  nominal.cornea_asphericity =
      settings.tracker_cornea ? (*settings.tracker_cornea)[1] : scene_eye.anterior_cornea.asphericity;
  nominal.refractive_index = scene_eye.posterior_cornea ? 1.3375 : scene_eye.aqueous_index;
  nominal.pupil_depth_mm = scene_eye.anterior_cornea.radius_mm - scene_eye.iris_depth_mm;
  return nominal;
}

// Frames rendered only to measure the detectors' noise: the eye at `home`
// fixating targets uniform over the screen drawn from `target_seed`, the
// renders seeded from `render_seed` on.
std::vector<Frame> noise_frames_of(const Scene& rig, const Point3& home, const Tracker& tracker, int count,
                                   std::uint64_t target_seed, std::uint64_t render_seed,
                                   const std::function<void()>& step) {
  const Screen& screen = *rig.screen;
  std::mt19937_64 random(target_seed);
  std::uniform_real_distribution<double> along(0, 1);
  std::vector<Frame> frames;
  for (int i = 0; i < count; ++i) {
    const ScreenPoint t{along(random) * screen.width_mm, along(random) * screen.height_mm};
    frames.push_back(frame_at(rig, home, 0, t, tracker, render_seed++, false));
    if (step) step();
  }
  return frames;
}

// Every frame the study renders, read by the tracker.
struct RenderedFrames {
  std::vector<Frame> calibration, tests, noise;
  double spot_sigma_px = 0;  // what the tracker told its glint detector (0: estimated per frame)
};

RenderedFrames render_frames(const Scene& rig, const Scene& believed,
                             const std::vector<std::pair<std::string, Point3>>& positions,
                             const CalibrationSettings& settings, const std::function<void()>& step) {
  const Screen& screen = *rig.screen;
  const Point3 home = positions.front().second;
  RenderedFrames frames;
  std::uint64_t seed = settings.seed;
  // The tracker knows its rig, as it believes it: the camera's optics (the
  // spot's width, the sensor's noise) and where the lights put glints on
  // the nominal eye.
  const Tracker tracker(believed.cameras.front(), believed.illuminators, believed.eyes.front());
  frames.spot_sigma_px = tracker.glint_settings().spot_sigma_px;
  for (const ScreenPoint& t : screen.grid(settings.calibration_grid, settings.calibration_grid)) {
    frames.calibration.push_back(frame_at(rig, home, 0, t, tracker, seed++, settings.exact_features));
    if (step) step();
  }
  for (std::size_t p = 0; p < positions.size(); ++p) {
    for (const ScreenPoint& t : screen.grid(settings.grid, settings.grid)) {
      frames.tests.push_back(frame_at(rig, positions[p].second, static_cast<int>(p), t, tracker, seed++, settings.exact_features));
      if (step) step();
    }
  }
  const int noise_frames = settings.exact_features ? 0 : settings.noise_frames;
  frames.noise = noise_frames_of(rig, home, tracker, noise_frames, settings.seed, seed, step);
  return frames;
}

// The RMS of the frames' `errors`, clipped as the cornea fit rejects
// glints (beyond 6 s.d., repeated until it settles) so that a merged glint
// does not inflate it; `fallback` without errors; at least 1e-3 px.
double clipped_rms(const std::vector<Frame>& frames, std::vector<double> Frame::*errors, double fallback) {
  const double clip = trackers::CorneaFitSettings{}.reject_beyond_sd;
  std::vector<double> all;
  for (const Frame& f : frames) all.insert(all.end(), (f.*errors).begin(), (f.*errors).end());
  double sd = INFINITY;
  for (int round = 0; round < 20; ++round) {
    double sum = 0;
    std::size_t count = 0;
    for (const double e : all) {
      if (std::abs(e) <= clip * sd) sum += e * e, ++count;
    }
    const double next = count > 0 ? std::sqrt(sum / count) : fallback;
    if (next == sd) break;
    sd = next;
  }
  return std::max(1e-3, sd);
}

struct MeasuredNoise {
  trackers::FeatureNoise noise;
  bool own_glint_sd = false;  // saturated glints keep their own s.d., scaled
  std::string measured_from;  // for people
};

MeasuredNoise measure_noise(const RenderedFrames& frames, const CalibrationSettings& settings) {
  // The detectors' noise: as given, or measured against the noise frames'
  // labels, or the calibration frames' without noise frames (a simulator
  // knows them; a tracker on real images would take its detectors'
  // specification). The RMS error, clipped as the
  // cornea fit rejects glints (beyond 6 s.d., repeated until it settles),
  // so that a merged glint does not inflate it.
  const std::vector<Frame>& measured_on = frames.noise.empty() ? frames.calibration : frames.noise;
  const auto measured = [&](std::vector<double> Frame::*errors, const std::optional<double>& given,
                            double fallback) {
    if (given) return *given;
    return clipped_rms(measured_on, errors, fallback);
  };
  MeasuredNoise out;
  trackers::FeatureNoise& noise = out.noise;
  noise = {measured(&Frame::glint_errors_px, settings.glint_noise_px, trackers::FeatureNoise{}.glint_px),
           measured(&Frame::pupil_errors_px, settings.pupil_noise_px, trackers::FeatureNoise{}.pupil_px)};
  // Glints that report their own standard deviation (saturated ones) keep
  // it, scaled by the RMS of their errors over it, measured the same way;
  // a given --glint-noise serves every glint.
  out.own_glint_sd = !settings.glint_noise_px &&
                     std::any_of(measured_on.begin(), measured_on.end(),
                                 [](const Frame& f) { return !f.glint_errors_sd.empty(); });
  if (out.own_glint_sd) {
    noise.glint_sd_scale = measured(&Frame::glint_errors_sd, std::nullopt, 1.0);
    // glint_px then serves only the glints without their own, where there are any.
    if (std::any_of(measured_on.begin(), measured_on.end(),
                    [](const Frame& f) { return !f.glint_errors_without_sd_px.empty(); })) {
      noise.glint_px = measured(&Frame::glint_errors_without_sd_px, std::nullopt, noise.glint_px);
    }
  }
  out.measured_from = settings.exact_features ? std::string("assumed: exact features (FeatureNoise's default)")
                      : frames.noise.empty()  ? std::string("measured on the calibration frames")
                                              : "measured on " + std::to_string(frames.noise.size()) + " noise frames";
  return out;
}

// The model-based calibration's results, every partial one.
SimulationRun model_calibration_run(const Scene& rig, const CalibrationSettings& settings,
                                    const trackers::GazeEyeModel& nominal, const trackers::ModelGazeCalibration& model,
                                    std::size_t frames_used, const RenderedFrames& frames,
                                    const MeasuredNoise& measured) {
  const EyeModel& scene_eye = rig.eyes.front().model();
  const Point3 home = rig.eyes.front().rotation_center();
  const std::string& measured_from = measured.measured_from;
  const trackers::FeatureNoise& noise = measured.noise;
  const bool own_glint_sd = measured.own_glint_sd;
  SimulationRun run{"calibration", "model-based", {}, std::nullopt};
  Results& r = run.results;
  r.add("frames_used", static_cast<double>(frames_used));
  r.add(settings.exact_features ? "frames_computed" : "frames_rendered", static_cast<double>(frames.calibration.size()));
  r.add("features", settings.exact_features ? std::string("exact: from the labels")
                                            : std::string("detected in the rendered frames"));
  r.add("kappa_horizontal", model.model.kappa_horizontal_rad / kDegree, "deg");
  r.add("kappa_vertical", model.model.kappa_vertical_rad / kDegree, "deg");
  r.add("kappa_true_horizontal", rig.eyes.front().model().kappa_horizontal_rad / kDegree, "deg");
  r.add("kappa_true_vertical", rig.eyes.front().model().kappa_vertical_rad / kDegree, "deg");
  if (model.covariance.size() >= 4) {
    r.add("kappa_horizontal_sd", std::sqrt(model.covariance[0]) / kDegree, "deg");
    const int n = settings.fit_pupil_depth ? 3 : 2;
    r.add("kappa_vertical_sd", std::sqrt(model.covariance[n + 1]) / kDegree, "deg");
    if (settings.fit_pupil_depth) r.add("pupil_depth_sd", std::sqrt(model.covariance[8]), "mm");
  }
  r.add("pupil_depth", model.model.pupil_depth_mm, "mm");
  r.add("pupil_depth_true", scene_eye.anterior_cornea.radius_mm - scene_eye.iris_depth_mm, "mm");
  r.add("cornea_radius", model.model.cornea_radius_mm, "mm");
  if (settings.fit_radius) r.add("cornea_radius_sd", model.cornea_radius_sd_mm, "mm");
  r.add("cornea_radius_true", scene_eye.anterior_cornea.radius_mm, "mm");
  r.add("cornea_asphericity", nominal.cornea_asphericity);
  r.add("cornea_asphericity_true", scene_eye.anterior_cornea.asphericity);
  r.add("tracker_cornea_from", settings.tracker_cornea  ? std::string("given")
                               : settings.tracker_rig ? std::string("the tracker rig's eye")
                                                      : std::string("the scene's eye"));
  r.add("refractive_index", nominal.refractive_index);
  r.add("rms_error_at_targets", model.rms_error_rad / kDegree, "deg");
  if (model.rotation_center) {
    r.add("rotation_center", {model.rotation_center->x, model.rotation_center->y, model.rotation_center->z}, "mm");
    r.add("rotation_center_sd",
          {model.rotation_center_sd_mm[0], model.rotation_center_sd_mm[1], model.rotation_center_sd_mm[2]}, "mm");
    r.add("rotation_center_error", distance(*model.rotation_center, home), "mm");
    r.add("rotation_distance", model.rotation_distance_mm, "mm");
  } else {
    r.add("rotation_center", std::string("not determined: the optical axes are too alike"));
  }
  r.add("glint_noise", noise.glint_px, "px");
  r.add("glint_noise_from", settings.glint_noise_px ? std::string("given") : measured_from);
  if (settings.exact_features) {
    r.add("glint_spot_sigma", std::string("none: exact features"));
  } else if (frames.spot_sigma_px > 0) {
    r.add("glint_spot_sigma", frames.spot_sigma_px, "px");
  } else {
    r.add("glint_spot_sigma", std::string("estimated per frame (defocus or sized lights)"));
  }
  r.add("glint_sd_scale", noise.glint_sd_scale);
  r.add("glint_sd_from", own_glint_sd ? "the detector's, scaled as " + measured_from
                                      : std::string("none: every glint has glint_noise"));
  r.add("pupil_noise", noise.pupil_px, "px");
  r.add("pupil_noise_from", settings.pupil_noise_px ? std::string("given") : measured_from);
  std::string warnings;
  for (const std::string& w : model.warnings) warnings += (warnings.empty() ? "" : "; ") + w;
  r.add("warnings", warnings.empty() ? std::string("none") : warnings);
  return run;
}

// The test frames at head position `p` (`name`) by both methods, scored
// against the truth: a row each in `csv`, each method's results and the
// gaze map's panel into `out`.
void score_position(const Scene& rig, const Scene& believed, const std::vector<Frame>& tests, std::size_t p,
                    const std::string& name, const trackers::ModelGazeCalibration& model,
                    const trackers::PolynomialGaze& polynomial, const trackers::FeatureNoise& noise,
                    const CalibrationSettings& settings, std::ostream& csv, CalibrationStudy& out) {
  // The tracker estimates with what it believes; the errors are the
  // world's: its screen, where the eye really is.
  const Camera& camera = believed.cameras.front();
  const Screen& believed_screen = *believed.screen;
  const Screen& screen = *rig.screen;
  const Point3 nominal_cornea = believed.eyes.front().cornea_center();
  Tally model_tally, polynomial_tally;
  std::vector<double> lateral, depth;
  int depth_within = 0, lateral_within = 0, cornea_with_sd = 0;
  GazePanel panel{name, {}, {}, {}};
  for (const Frame& f : tests) {
    if (f.position != static_cast<int>(p)) continue;
    panel.targets.push_back(f.target);
    panel.cornea_centers.push_back(f.cornea_center);
    const auto error_deg = [&](const ScreenPoint& p) {
      return angle_between(screen.at(p) - f.cornea_center, screen.at(f.target) - f.cornea_center) / kDegree;
    };
    csv << '"' << name << "\"," << f.target.x_mm << ',' << f.target.y_mm << ',' << f.glints_told << ','
        << (f.found ? 1 : 0) << ',' << rms(f.glint_errors_px) << ',' << rms(f.pupil_errors_px);
    std::optional<ScreenPoint> by_model, by_polynomial;
    if (f.found) {
      const trackers::ModelGaze g =
          trackers::estimate_model_gaze(camera, believed.illuminators, *f.found, model.model, believed_screen,
                                        nominal_cornea, noise, settings.propagate_uncertainty);
      // The cornea's error along the camera's line of sight (depth) and
      // across it, on two fixed axes: the camera's x and y made
      // perpendicular to the line of sight. Each is checked against its
      // own s.d., as the screen's x and y are.
      const Vector3 sight = (f.cornea_center - camera.center()) / (f.cornea_center - camera.center()).norm();
      const Vector3 camera_x = camera.world_from_camera() * Vector3{1, 0, 0};
      const Vector3 off_sight = camera_x - dot(camera_x, sight) * sight;
      const Vector3 across_x = off_sight / off_sight.norm();
      const Vector3 across_y = cross(sight, across_x);
      const Vector3 e = g.cornea_center - f.cornea_center;
      const auto variance_along = [&](const Vector3& d) {
        double v = 0;
        for (int a = 0; a < 3; ++a) {
          for (int b = 0; b < 3; ++b) v += d[a] * g.cornea_covariance_mm2[3 * a + b] * d[b];
        }
        return v;
      };
      const double along = dot(e, sight);
      const double across = (e - along * sight).norm();
      const double depth_var = variance_along(sight);
      if (g.cornea_determined) {
        csv << ',' << across << ',' << along << ',' << std::sqrt(depth_var) << ',' << dot(e, across_x) << ','
            << dot(e, across_y) << ',' << std::sqrt(variance_along(across_x)) << ','
            << std::sqrt(variance_along(across_y));
      } else {
        csv << ",,,,,,,";
      }
      if (g.cornea_determined) {
        lateral.push_back(across);
        depth.push_back(along);
      }
      // Shares within 3 s.d. only of propagated uncertainties: the glint
      // fit's alone, about a fixed axis, is no estimate's.
      if (g.cornea_determined && settings.propagate_uncertainty) {
        ++cornea_with_sd;
        depth_within += std::abs(along) <= 3 * std::sqrt(depth_var) ? 1 : 0;
        lateral_within += std::abs(dot(e, across_x)) <= 3 * std::sqrt(variance_along(across_x)) &&
                                  std::abs(dot(e, across_y)) <= 3 * std::sqrt(variance_along(across_y))
                              ? 1
                              : 0;
      }
      if (g.valid && g.on_screen) {
        by_model = g.on_screen;
        model_tally.errors_deg.push_back(error_deg(*by_model));
        csv << ',' << by_model->x_mm << ',' << by_model->y_mm;
        if (g.on_screen_covariance_mm2) {
          const double sx = std::sqrt((*g.on_screen_covariance_mm2)[0]);
          const double sy = std::sqrt((*g.on_screen_covariance_mm2)[3]);
          ++model_tally.with_sd;
          model_tally.sd_deg.push_back(
              std::atan(std::sqrt((sx * sx + sy * sy) / 2) / distance(screen.at(f.target), f.cornea_center)) / kDegree);
          model_tally.within_3sd_x += std::abs(by_model->x_mm - f.target.x_mm) <= 3 * sx ? 1 : 0;
          model_tally.within_3sd_y += std::abs(by_model->y_mm - f.target.y_mm) <= 3 * sy ? 1 : 0;
          csv << ',' << sx << ',' << sy;
        } else {
          csv << ",,";
        }
        csv << ',' << model_tally.errors_deg.back();
      } else {
        ++model_tally.missing;
        csv << ",,,,,";
      }
      by_polynomial = polynomial.estimate(*f.found);
    } else {
      ++model_tally.missing;
      csv << ",,,,,,,,,,,,";
    }
    if (by_polynomial) {
      polynomial_tally.errors_deg.push_back(error_deg(*by_polynomial));
      csv << ',' << by_polynomial->x_mm << ',' << by_polynomial->y_mm << ',' << polynomial_tally.errors_deg.back();
    } else {
      ++polynomial_tally.missing;
      csv << ",,,";
    }
    csv << '\n';
    panel.estimates[0].push_back(by_model);
    panel.estimates[1].push_back(by_polynomial);
  }
  SimulationRun m{name, "model-based", {}, std::nullopt};
  add_errors(m.results, "gaze_", model_tally);
  if (!depth.empty()) {
    double sum_lateral = 0, sum_depth = 0, sum_depth2 = 0;
    for (std::size_t i = 0; i < depth.size(); ++i) {
      sum_lateral += lateral[i];
      sum_depth += depth[i];
      sum_depth2 += depth[i] * depth[i];
    }
    const double n = static_cast<double>(depth.size());
    m.results.add("cornea_lateral_error_mean", sum_lateral / n, "mm");
    m.results.add("cornea_depth_error_mean", sum_depth / n, "mm");
    m.results.add("cornea_depth_error_rms", std::sqrt(sum_depth2 / n), "mm");
    if (cornea_with_sd > 0) {
      m.results.add("cornea_within_3sd_depth", 100.0 * depth_within / cornea_with_sd, "%");
      m.results.add("cornea_within_3sd_lateral_both_axes", 100.0 * lateral_within / cornea_with_sd, "%");
    }
  }
  out.runs.push_back(std::move(m));
  SimulationRun by_polynomial_run{name, "polynomial", {}, std::nullopt};
  add_errors(by_polynomial_run.results, "gaze_", polynomial_tally);
  out.runs.push_back(std::move(by_polynomial_run));
  out.panels.push_back(std::move(panel));
}

}  // namespace

void check_calibration_rig(const Scene& rig, const std::string& rig_file, const CalibrationSettings& settings) {
  // The settings' ranges (the command line's options check them too, as text).
  const auto within = [](const char* name, double value, double low, double high) {
    if (!(value >= low && value <= high)) {
      throw std::invalid_argument(std::string("calibration: ") + name + " = " + format(value) + ": must be from " +
                                  format(low) + " to " + format(high));
    }
  };
  within("grid", settings.grid, 1, 64);
  within("calibration_grid", settings.calibration_grid, 3, 16);
  within("noise_frames", settings.noise_frames, 0, 10000);
  if (settings.glint_noise_px) within("glint_noise_px", *settings.glint_noise_px, 1e-6, 10);
  if (settings.pupil_noise_px) within("pupil_noise_px", *settings.pupil_noise_px, 1e-6, 10);
  for (const auto& move : settings.head_moves) {
    for (const double v : move) within("head_moves", v, -1e6, 1e6);
  }
  if (const auto& c = settings.tracker_cornea) {
    if (!((*c)[0] > 0 && (*c)[0] < 100) || !((*c)[1] > -1 && (*c)[1] < 10)) {
      throw std::invalid_argument("calibration: tracker_cornea = (" + format((*c)[0]) + ", " + format((*c)[1]) +
                                  "): must be (R, Q) with the apex radius R in (0, 100) mm and the asphericity Q "
                                  "in (-1, 10)");
    }
  }
  if (!rig.screen) {
    throw std::runtime_error(rig_file + ": no \"screen\" block: calibration needs the screen the eye "
                             "looks at (docs/scene-format.md)");
  }
  if (rig.illuminators.size() < 2) {
    throw std::runtime_error(rig_file + ": " + std::to_string(rig.illuminators.size()) +
                             " illuminator(s): the cornea's centre needs the glints of two or more");
  }
  if (rig.eyes.size() != 1) {
    throw std::runtime_error(rig_file + ": " + std::to_string(rig.eyes.size()) +
                             " eyes: calibration follows one eye");
  }
  if (const auto& believed = settings.tracker_rig) {
    if (believed->cameras.size() != rig.cameras.size() || believed->illuminators.size() != rig.illuminators.size() ||
        believed->eyes.size() != 1 || !believed->screen) {
      throw std::invalid_argument("calibration: the tracker rig must have the rig's cameras and lights in number, one "
                                  "eye and a screen (it has " + std::to_string(believed->cameras.size()) +
                                  " cameras, " + std::to_string(believed->illuminators.size()) + " lights, " +
                                  std::to_string(believed->eyes.size()) + " eyes" +
                                  (believed->screen ? "" : ", no screen") + ")");
    }
  }
  const Scene& tracker_scene = settings.tracker_rig ? *settings.tracker_rig : rig;
  const double q = tracker_scene.eyes.front().model().anterior_cornea.asphericity;
  if (!settings.tracker_cornea && !(q > -1 && q < 10)) {
    throw std::runtime_error(rig_file + ": the eye's anterior_cornea asphericity " + format(q) +
                             ": the tracker's cornea must be an ellipsoid, Q in (-1, 10); give another "
                             "with --tracker-cornea R,Q");
  }
}

DetectorNoise measure_detector_noise(const Scene& rig, int frames, std::uint64_t seed,
                                     const std::function<void()>& step) {
  if (!rig.screen || rig.eyes.size() != 1) {
    throw std::invalid_argument("measure_detector_noise: the rig needs a screen and one eye");
  }
  if (frames < 1 || frames > 10000) {
    throw std::invalid_argument("measure_detector_noise: frames = " + std::to_string(frames) +
                                ": must be from 1 to 10000");
  }
  const Tracker tracker(rig.cameras.front(), rig.illuminators, rig.eyes.front());
  const std::vector<Frame> rendered =
      noise_frames_of(rig, rig.eyes.front().rotation_center(), tracker, frames, seed, seed, step);
  DetectorNoise noise;
  noise.frames = frames;
  for (const Frame& f : rendered) {
    noise.glint_errors += static_cast<int>(f.glint_errors_px.size() / 2);
    noise.pupil_errors += static_cast<int>(f.pupil_errors_px.size() / 2);
  }
  if (noise.glint_errors > 0) noise.glint_px = clipped_rms(rendered, &Frame::glint_errors_px, 0);
  if (noise.pupil_errors > 0) noise.pupil_px = clipped_rms(rendered, &Frame::pupil_errors_px, 0);
  return noise;
}

std::size_t calibration_frames(const CalibrationSettings& settings) {
  return static_cast<std::size_t>(settings.calibration_grid * settings.calibration_grid +
                                  (1 + settings.head_moves.size()) * settings.grid * settings.grid +
                                  (settings.exact_features ? 0 : settings.noise_frames));
}

CalibrationStudy run_calibration(const Scene& rig, const CalibrationSettings& settings,
                                 const std::function<void()>& step) {
  const Scene& believed = settings.tracker_rig ? *settings.tracker_rig : rig;
  const Camera& camera = believed.cameras.front();
  const Screen& believed_screen = *believed.screen;
  const Point3 home = rig.eyes.front().rotation_center();
  // Where the tracker expects the cornea (its nominal eye): every fit's
  // start, never the frame's truth.
  const Point3 nominal_cornea = believed.eyes.front().cornea_center();
  const trackers::GazeEyeModel nominal = tracker_eye(believed, settings);
  std::vector<std::pair<std::string, Point3>> positions{{"home", home}};
  for (const std::array<double, 3>& m : settings.head_moves) {
    positions.push_back({"moved " + format(m[0]) + "," + format(m[1]) + "," + format(m[2]) + " mm",
                         home + Vector3{m[0], m[1], m[2]}});
  }
  const RenderedFrames frames = render_frames(rig, believed, positions, settings, step);
  const std::vector<Frame>& calibration = frames.calibration;

  // Calibration on the frames whose features were all found.
  std::vector<trackers::GazeFeatures> features;
  std::vector<Point3> targets;
  std::vector<ScreenPoint> screen_targets;
  for (const Frame& f : calibration) {
    if (!f.found) continue;
    features.push_back(*f.found);
    targets.push_back(believed_screen.at(f.target));  // where the tracker believes the target is
    screen_targets.push_back(f.target);
  }
  if (features.size() < 6) {
    throw std::runtime_error(std::string(settings.exact_features ? "the camera sees glints of two lights and the pupil"
                                                                 : "the detectors found glints and pupil") +
                             " in " + std::to_string(features.size()) + " of " +
                             std::to_string(calibration.size()) + " calibration frames: at least 6 are needed");
  }
  const MeasuredNoise measured = measure_noise(frames, settings);
  const trackers::FeatureNoise& noise = measured.noise;
  trackers::ModelGazeCalibrationSettings model_settings;
  model_settings.fit_cornea_radius = settings.fit_radius;
  model_settings.fit_pupil_depth = settings.fit_pupil_depth;
  model_settings.noise = noise;
  model_settings.propagate_noise = settings.propagate_uncertainty;
  const trackers::ModelGazeCalibration model = trackers::calibrate_model_gaze(
      camera, believed.illuminators, features, targets, nominal, nominal_cornea, model_settings);
  const trackers::PolynomialGaze polynomial = trackers::PolynomialGaze::calibrate(features, screen_targets);
  if (!model.converged || model.covariance.empty()) {
    std::string message = "the model-based calibration failed:";
    for (const std::string& w : model.warnings) message += "\n  " + w;
    throw std::runtime_error(message);
  }

  CalibrationStudy out;
  out.runs.push_back(model_calibration_run(rig, settings, nominal, model, features.size(), frames, measured));
  {
    SimulationRun run{"calibration", "polynomial", {}, std::nullopt};
    run.results.add("frames_used", static_cast<double>(features.size()));
    run.results.add("rms_residual_at_targets", polynomial.rms_residual_mm(), "mm");
    out.runs.push_back(std::move(run));
  }

  // Every test frame by both methods, scored against the truth.
  std::ostringstream csv;  // frames.csv
  csv << "position,target_x_mm,target_y_mm,glints_told,pupil_found,glint_error_rms_px,pupil_error_rms_px,"
         "cornea_lateral_error_mm,cornea_depth_error_mm,"
         "cornea_depth_sd_mm,cornea_across_x_error_mm,cornea_across_y_error_mm,cornea_across_x_sd_mm,"
         "cornea_across_y_sd_mm,model_x_mm,model_y_mm,model_sd_x_mm,model_sd_y_mm,model_error_deg,polynomial_x_mm,"
         "polynomial_y_mm,polynomial_error_deg\n";
  try {
    for (std::size_t p = 0; p < positions.size(); ++p) {
      score_position(rig, believed, frames.tests, p, positions[p].first, model, polynomial, noise, settings, csv,
                     out);
    }
  } catch (const std::exception& error) {
    throw std::runtime_error(std::string("while scoring: ") + error.what());
  }
  out.frames_csv = csv.str();
  return out;
}

}  // namespace purkinje::studies
