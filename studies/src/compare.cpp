// The compare study's displacement field: see compare.h.

#include "purkinje/studies/compare.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "purkinje/models/check.h"
#include "purkinje/models/csv.h"
#include "purkinje/models/scene_file.h"

#include <nlohmann/json.hpp>

namespace purkinje::studies {
namespace {

constexpr double kDegree = std::numbers::pi / 180;

void check_versions(const Scene& world, const Scene& assumed, const CompareSettings& s) {
  const auto fail = [](const std::string& rule) { throw std::invalid_argument("compare: " + rule); };
  if (world.eyes.size() != 1 || assumed.eyes.size() != 1) {
    fail("the world has " + std::to_string(world.eyes.size()) + " eyes and the assumed version " +
         std::to_string(assumed.eyes.size()) + ": each must have one");
  }
  if (world.cameras.size() != assumed.cameras.size() || world.illuminators.size() != assumed.illuminators.size()) {
    fail("the versions must have the same cameras and lights (world: " + std::to_string(world.cameras.size()) +
         " cameras, " + std::to_string(world.illuminators.size()) + " lights; assumed: " +
         std::to_string(assumed.cameras.size()) + " cameras, " + std::to_string(assumed.illuminators.size()) +
         " lights)");
  }
  if (s.camera < 0 || static_cast<std::size_t>(s.camera) >= world.cameras.size()) {
    fail("camera = " + std::to_string(s.camera) + ": the scenes have " + std::to_string(world.cameras.size()) +
         " cameras");
  }
  if (s.grid < 1 || s.grid > 64) fail("grid = " + std::to_string(s.grid) + ": must be from 1 to 64");
  if (!(s.cap_deg > 0 && s.cap_deg <= 60)) fail("cap_deg = " + check::format_number(s.cap_deg) + ": must be in (0, 60]");
  if (s.pupil_border_points < 6 || s.pupil_border_points > 100000) {
    fail("pupil_border_points = " + std::to_string(s.pupil_border_points) + ": must be from 6 to 100000");
  }
}

// The version's scene with its eye turned as `aim` says.
template <class Aim>
Scene turned(const Scene& version, Aim aim) {
  Scene scene = version;
  const Eye& eye = version.eyes.front();
  Eye now = aim(eye);
  now.set_appearance(eye.appearance());
  now.set_motion(eye.motion());
  scene.eyes = {now};
  return scene;
}

bool has_pixel(PathStatus s) { return s == PathStatus::ok || s == PathStatus::outside_image; }

std::vector<FeaturePair> features(const Scene& world, const Scene& assumed, const CompareSettings& s) {
  TruthOptions options;
  options.pupil_border_points = s.pupil_border_points;
  const SceneTruth w = compute_truth(world, options), a = compute_truth(assumed, options);
  const EyeInCameraTruth& wv = w.views[static_cast<std::size_t>(s.camera)];
  const EyeInCameraTruth& av = a.views[static_cast<std::size_t>(s.camera)];
  std::vector<FeaturePair> out;
  for (std::size_t i = 0; i < wv.glints.size(); ++i) {
    FeaturePair f;
    f.feature = "glint." + world.illuminators[i].name;
    f.world_status = wv.glints[i].status;
    f.assumed_status = av.glints[i].status;
    if (has_pixel(f.world_status)) f.world = wv.glints[i].pixel;
    if (has_pixel(f.assumed_status)) f.assumed = av.glints[i].pixel;
    out.push_back(f);
  }
  FeaturePair center;
  center.feature = "pupil_center";
  center.world_status = wv.pupil.refracted_center_status;
  center.assumed_status = av.pupil.refracted_center_status;
  if (has_pixel(center.world_status)) center.world = wv.pupil.refracted_center;
  if (has_pixel(center.assumed_status)) center.assumed = av.pupil.refracted_center;
  out.push_back(center);
  FeaturePair ellipse;
  ellipse.feature = "pupil_ellipse";
  ellipse.world_status = wv.pupil.ellipse_valid ? PathStatus::ok : PathStatus::no_solution;
  ellipse.assumed_status = av.pupil.ellipse_valid ? PathStatus::ok : PathStatus::no_solution;
  if (wv.pupil.ellipse_valid) {
    ellipse.world_ellipse = wv.pupil.ellipse;
    ellipse.world = wv.pupil.ellipse.center;
  }
  if (av.pupil.ellipse_valid) {
    ellipse.assumed_ellipse = av.pupil.ellipse;
    ellipse.assumed = av.pupil.ellipse.center;
  }
  out.push_back(ellipse);
  return out;
}

}  // namespace

std::optional<Pixel> FeaturePair::displacement() const {
  if (!world || !assumed) return std::nullopt;
  return Pixel{assumed->u - world->u, assumed->v - world->v};
}

DisplacementField displacement_field(const Scene& world, const Scene& assumed, const CompareSettings& settings) {
  check_versions(world, assumed, settings);
  DisplacementField field;
  field.on_screen = world.screen.has_value();
  const Eye& world_eye = world.eyes.front();
  if (field.on_screen) {
    const Screen& screen = *world.screen;
    const Screen& assumed_screen = assumed.screen.value_or(screen);
    for (const ScreenPoint& t : screen.grid(settings.grid, settings.grid)) {
      FieldPoint p{t.x_mm, t.y_mm, {}};
      const Scene w = turned(world, [&](const Eye& e) {
        return Eye::fixating(e.model(), e.rotation_center(), screen.at(t));
      });
      const Scene a = turned(assumed, [&](const Eye& e) {
        return Eye::fixating(e.model(), e.rotation_center(), assumed_screen.at(t));
      });
      p.features = features(w, a, settings);
      field.points.push_back(std::move(p));
    }
    return field;
  }
  // Gaze turns about the world eye's own visual axis: toward eye +x (yaw)
  // and eye +y (pitch, up), the same world directions for both versions.
  const UnitVector3 v0 = world_eye.visual_axis();
  const UnitVector3 x = UnitVector3::normalize(world_eye.world_from_eye().rotation().column(0).vector() -
                                               v0.vector() * dot(world_eye.world_from_eye().rotation().column(0), v0));
  const Vector3 y = cross(v0, x);
  const int n = settings.grid;
  for (int row = 0; row < n; ++row) {
    for (int col = 0; col < n; ++col) {
      const double yaw = n == 1 ? 0 : settings.cap_deg * (2.0 * col / (n - 1) - 1);
      const double pitch = n == 1 ? 0 : settings.cap_deg * (1 - 2.0 * row / (n - 1));
      const UnitVector3 d =
          UnitVector3::normalize(v0.vector() + x.vector() * std::tan(yaw * kDegree) + y * std::tan(pitch * kDegree));
      FieldPoint p{yaw, pitch, {}};
      const Scene w = turned(world, [&](const Eye& e) { return Eye::with_visual_axis(e.model(), e.rotation_center(), d); });
      const Scene a =
          turned(assumed, [&](const Eye& e) { return Eye::with_visual_axis(e.model(), e.rotation_center(), d); });
      p.features = features(w, a, settings);
      field.points.push_back(std::move(p));
    }
  }
  return field;
}

std::string displacement_csv(const DisplacementField& field) {
  std::ostringstream out;
  const auto number = [](const std::optional<double>& v) { return v ? check::format_number(*v) : std::string(); };
  out << (field.on_screen ? "target_x_mm,target_y_mm" : "gaze_yaw_deg,gaze_pitch_deg")
      << ",feature,world_status,assumed_status,world_u_px,world_v_px,assumed_u_px,assumed_v_px,du_px,dv_px,"
         "displacement_px,world_semi_axis_1_px,world_semi_axis_2_px,world_angle_deg,assumed_semi_axis_1_px,"
         "assumed_semi_axis_2_px,assumed_angle_deg\n";
  for (const FieldPoint& p : field.points) {
    for (const FeaturePair& f : p.features) {
      const auto d = f.displacement();
      const auto axes = [&](const std::optional<Ellipse>& e) {
        if (!e) return std::string(",,");
        return check::format_number(e->semi_axis_1_px) + "," + check::format_number(e->semi_axis_2_px) + "," +
               check::format_number(e->angle_rad / kDegree);
      };
      out << check::format_number(p.x) << ',' << check::format_number(p.y) << ',' << csv_cell(f.feature) << ','
          << to_string(f.world_status) << ',' << to_string(f.assumed_status) << ','
          << number(f.world ? std::optional(f.world->u) : std::nullopt) << ','
          << number(f.world ? std::optional(f.world->v) : std::nullopt) << ','
          << number(f.assumed ? std::optional(f.assumed->u) : std::nullopt) << ','
          << number(f.assumed ? std::optional(f.assumed->v) : std::nullopt) << ','
          << number(d ? std::optional(d->u) : std::nullopt) << ',' << number(d ? std::optional(d->v) : std::nullopt)
          << ',' << number(d ? std::optional(std::hypot(d->u, d->v)) : std::nullopt) << ','
          << axes(f.world_ellipse) << ',' << axes(f.assumed_ellipse) << '\n';
    }
  }
  return out.str();
}

}  // namespace purkinje::studies

namespace purkinje::studies {
namespace {

// Mean, RMS and largest of some values, with where the largest is.
struct Spread {
  std::size_t n = 0;
  double sum = 0, sum2 = 0, max = 0;
  std::size_t max_at = 0;
  void add(double v, std::size_t at) {
    if (n == 0 || v > max) max = v, max_at = at;
    ++n, sum += v, sum2 += v * v;
  }
  void write(Results& r, const std::string& prefix, const std::string& unit) const {
    if (n == 0) return;
    r.add(prefix + "mean", sum / static_cast<double>(n), unit);
    r.add(prefix + "rms", std::sqrt(sum2 / static_cast<double>(n)), unit);
    r.add(prefix + "max", max, unit);
  }
};

void summarize_field(const DisplacementField& field, std::vector<SimulationRun>& out) {
  if (field.points.empty()) return;
  const std::string unit = field.on_screen ? "mm" : "deg";
  for (std::size_t f = 0; f < field.points.front().features.size(); ++f) {
    SimulationRun run{"displacement", field.points.front().features[f].feature, {}, std::nullopt};
    Results& r = run.results;
    Spread length;
    double du = 0, dv = 0;
    int only_world = 0, only_assumed = 0;
    Spread axis_1, axis_2;
    for (std::size_t p = 0; p < field.points.size(); ++p) {
      const FeaturePair& pair = field.points[p].features[f];
      if (const auto d = pair.displacement()) {
        length.add(std::hypot(d->u, d->v), p);
        du += d->u, dv += d->v;
      } else {
        only_world += pair.world && !pair.assumed ? 1 : 0;
        only_assumed += pair.assumed && !pair.world ? 1 : 0;
      }
      if (pair.world_ellipse && pair.assumed_ellipse) {
        axis_1.add(std::abs(pair.assumed_ellipse->semi_axis_1_px - pair.world_ellipse->semi_axis_1_px), p);
        axis_2.add(std::abs(pair.assumed_ellipse->semi_axis_2_px - pair.world_ellipse->semi_axis_2_px), p);
      }
    }
    r.add("targets", static_cast<double>(field.points.size()));
    r.add("targets_in_both", static_cast<double>(length.n));
    r.add("targets_in_world_only", static_cast<double>(only_world));
    r.add("targets_in_assumed_only", static_cast<double>(only_assumed));
    if (length.n > 0) {
      length.write(r, "displacement_", "px");
      r.add("displacement_mean_u", du / static_cast<double>(length.n), "px");
      r.add("displacement_mean_v", dv / static_cast<double>(length.n), "px");
    }
    if (length.n > 0 && length.max > 0) {
      const FieldPoint& at = field.points[length.max_at];
      r.add("displacement_max_at", {at.x, at.y}, unit);
    }
    axis_1.write(r, "semi_axis_1_change_", "px");
    axis_2.write(r, "semi_axis_2_change_", "px");
    out.push_back(std::move(run));
  }
}

// The runs' results under `prefix`: what each calibration reported.
void add_calibration_runs(const std::string& prefix, const CalibrationStudy& study, std::vector<SimulationRun>& out) {
  for (SimulationRun run : study.runs) {
    run.case_name = prefix + ": " + run.case_name;
    out.push_back(std::move(run));
  }
}

// Per head position and method: both versions' gaze errors and the change.
void summarize_gaze(const CompareStudy& study, std::vector<SimulationRun>& out) {
  for (const GazePanel& panel : study.baseline->panels) {
    for (const char* method : {"model-based", "polynomial"}) {
      SimulationRun run{"gaze: " + panel.title, method, {}, std::nullopt};
      Spread baseline, assumed, change;
      int missing = 0;
      for (std::size_t i = 0; i < study.gaze.size(); ++i) {
        const GazeChange& g = study.gaze[i];
        if (g.position != panel.title || g.method != method) continue;
        if (g.baseline_error_deg) baseline.add(*g.baseline_error_deg, i);
        if (g.assumed_error_deg) assumed.add(*g.assumed_error_deg, i);
        if (g.change_deg) {
          change.add(*g.change_deg, i);
        } else {
          ++missing;
        }
      }
      Results& r = run.results;
      r.add("targets_with_both_estimates", static_cast<double>(change.n));
      r.add("targets_without", static_cast<double>(missing));
      baseline.write(r, "error_believing_world_", "deg");
      assumed.write(r, "error_believing_assumed_", "deg");
      change.write(r, "change_", "deg");
      if (change.n > 0 && change.max > 0) {
        const ScreenPoint& at = study.gaze[change.max_at].target;
        r.add("change_max_at", {at.x_mm, at.y_mm}, "mm");
      }
      // The tracker's own account, believing the assumed version: its
      // cornea errors and how often the truth lies within 3 reported s.d.
      for (const SimulationRun& a : study.assumed->runs) {
        if (a.case_name != panel.title || a.algorithm != method) continue;
        for (const char* key : {"gaze_within_3sd_screen_x", "gaze_within_3sd_screen_y", "cornea_lateral_error_mean",
                                "cornea_depth_error_mean", "cornea_depth_error_rms", "cornea_within_3sd_depth",
                                "cornea_within_3sd_lateral_both_axes"}) {
          if (const Results::Entry* e = a.results.find(key)) {
            r.add(std::string("believing_assumed_") + key, std::get<double>(e->value), e->unit);
          }
        }
      }
      out.push_back(std::move(run));
    }
  }
}

void summarize_images(const renderer::RenderResult& world, const renderer::RenderResult& assumed,
                      std::vector<SimulationRun>& out) {
  SimulationRun run{"images", "difference (assumed - world)", {}, std::nullopt};
  Results& r = run.results;
  const auto& we = world.electrons.values;
  const auto& ae = assumed.electrons.values;
  double largest = 0, sum2 = 0;
  std::size_t changed = 0;
  for (std::size_t i = 0; i < we.size(); ++i) {
    const double d = static_cast<double>(ae[i]) - static_cast<double>(we[i]);
    largest = std::max(largest, std::abs(d));
    sum2 += d * d;
    changed += d != 0 ? 1 : 0;
  }
  std::size_t sensor_changed = 0;
  int sensor_largest = 0;
  for (std::size_t i = 0; i < world.sensor.values.size(); ++i) {
    const int d = static_cast<int>(assumed.sensor.values[i]) - static_cast<int>(world.sensor.values[i]);
    sensor_largest = std::max(sensor_largest, std::abs(d));
    sensor_changed += d != 0 ? 1 : 0;
  }
  const double n = static_cast<double>(we.size());
  r.add("pixels", n);
  r.add("electrons_changed_pixels", 100.0 * static_cast<double>(changed) / n, "%");
  r.add("electrons_difference_max", largest, "e-");
  r.add("electrons_difference_rms", std::sqrt(sum2 / n), "e-");
  r.add("sensor_changed_pixels", 100.0 * static_cast<double>(sensor_changed) / n, "%");
  r.add("sensor_difference_max", static_cast<double>(sensor_largest), "DN");
  out.push_back(std::move(run));
}

}  // namespace

namespace {

// The eye with another anatomy, its centre of rotation, optical axis and
// appearance kept.
Eye with_anatomy(const Eye& eye, const EyeModel& model) {
  Eye changed = Eye::with_rotation_center(model, eye.rotation_center(), eye.optical_axis());
  changed.set_appearance(eye.appearance());
  changed.set_motion(eye.motion());
  return changed;
}

}  // namespace

Scene with_one_surface_cornea(const Scene& scene, const Conicoid& anterior) {
  const std::string given = "the assumed cornea (R, Q) = (" + check::format_number(anterior.radius_mm) + ", " +
                            check::format_number(anterior.asphericity) + ")";
  if (!(anterior.radius_mm > 0 && anterior.radius_mm < 100) || !(anterior.asphericity > -1 && anterior.asphericity < 10)) {
    throw std::invalid_argument(given + ": must have the apex radius R in (0, 100) mm and the asphericity Q in (-1, 10)");
  }
  Scene out = scene;
  for (Eye& eye : out.eyes) {
    EyeModel model = eye.model();
    model.anterior_cornea = anterior;
    model.posterior_cornea.reset();
    model.aqueous_index = 1.3375;
    if (const auto problem = anatomy_problem(model)) {
      throw std::invalid_argument(given + ": the eye's anatomy refuses it: " + problem->key + " = " + problem->value +
                                  ": " + problem->rule);
    }
    eye = with_anatomy(eye, model);
  }
  return out;
}

Scene with_eye_model(const Scene& scene, const std::string& model) {
  if (scene.eyes.size() != 1) {
    throw std::invalid_argument("compare: an eye model replaces the eye of a scene with one eye (it has " +
                                std::to_string(scene.eyes.size()) + ")");
  }
  static const std::vector<std::string> kAnatomy = {"model",          "cornea", "posterior_cornea",
                                                    "aqueous_index",  "iris",   "pupil",
                                                    "rotation_center_depth_mm", "sclera_radius_mm", "kappa_deg"};
  const auto& presets = eye_model_preset_names();
  const bool preset = std::find(presets.begin(), presets.end(), model) != presets.end();
  nlohmann::ordered_json anatomy;
  if (preset) {
    anatomy = {{"model", model}};
  } else {
    std::ifstream in(model, std::ios::binary);
    if (!in) {
      std::string names;
      for (const std::string& p : presets) names += (names.empty() ? "" : ", ") + p;
      throw SceneError(model + ": cannot open the eye-model file (nor is it a preset: " + names + ")");
    }
    std::ostringstream text;
    text << in.rdbuf();
    try {
      anatomy = nlohmann::ordered_json::parse(text.str(), nullptr, true, /*ignore_comments=*/true);
    } catch (const nlohmann::json::parse_error& error) {
      throw SceneError(model + ": not JSON: " + error.what());
    }
    if (!anatomy.is_object()) throw SceneError(model + ": must be a JSON object of an eye's anatomy keys");
    for (const auto& [key, value] : anatomy.items()) {
      if (std::find(kAnatomy.begin(), kAnatomy.end(), key) == kAnatomy.end()) {
        std::string keys;
        for (const std::string& k : kAnatomy) keys += (keys.empty() ? "" : ", ") + k;
        throw SceneError(model + ": key \"" + key + "\": an eye-model file holds only anatomy (" + keys + ")");
      }
    }
  }
  // The scene as a file, its eye's anatomy replaced, read back by the
  // scene reader: the file's keys get the reader's rules and messages.
  nlohmann::ordered_json file = nlohmann::ordered_json::parse(scene_to_json(scene));
  nlohmann::ordered_json& eye = file["eyes"][0];
  const double pupil_radius = scene.eyes.front().model().pupil_radius_mm;
  for (const std::string& key : kAnatomy) eye.erase(key);
  for (const auto& [key, value] : anatomy.items()) eye[key] = value;
  if (!anatomy.contains("pupil")) eye["pupil"] = {{"radius_mm", pupil_radius}};
  const Point3 center = scene.eyes.front().rotation_center();
  eye["position"] = {{"rotation_center_mm", {center.x, center.y, center.z}}};
  return parse_scene(file.dump(), preset ? "eye model \"" + model + "\"" : model);
}

CalibrationSettings CompareStudySettings::default_calibration() {
  CalibrationSettings s;
  s.grid = 9;
  s.exact_features = true;
  s.noise_frames = 0;
  return s;
}

std::vector<std::array<double, 3>> default_head_moves(const Scene& world) {
  if (world.eyes.empty() || world.cameras.empty()) return {};
  const Camera& camera = world.cameras.front();
  const double distance = (world.eyes.front().rotation_center() - camera.center()).norm();
  // Two significant digits: moves people can name (50 and 100 mm, not 50.47).
  const double decade = std::pow(10.0, std::floor(std::log10(distance / 12)) - 1);
  const double step = std::round(distance / 12 / decade) * decade;
  const auto move = [&](const Vector3& along_camera) {
    const Vector3 v = camera.world_from_camera() * along_camera;
    const auto tidy = [](double x) { return std::abs(x) < 1e-9 ? 0.0 : x; };  // no -0 or 1e-17 in names
    return std::array<double, 3>{tidy(v.x), tidy(v.y), tidy(v.z)};
  };
  return {move(Vector3{step, 0, 0}), move(Vector3{0, 0, 2 * step})};
}

namespace {

// Why the study cannot calibrate on the world (empty: it can): what
// calibration needs of a rig, beyond the eye models' rules.
std::string cannot_calibrate(const Scene& world) {
  if (!world.screen) return "the world has no screen for the eye to fixate";
  if (world.illuminators.size() < 2) {
    return "the world has " + std::to_string(world.illuminators.size()) +
           " light(s): the cornea's centre needs the glints of two or more";
  }
  return "";
}

}  // namespace

std::size_t compare_steps(const Scene& world, const CompareStudySettings& settings) {
  std::size_t steps = settings.images ? 2 : 0;
  if (settings.calibrate && cannot_calibrate(world).empty()) steps += 2 * calibration_frames(settings.calibration);
  return steps;
}

CompareStudy run_compare(const Scene& world, const Scene& assumed, const CompareStudySettings& settings,
                         const std::function<void()>& step) {
  CompareStudy study;
  study.field = displacement_field(world, assumed, settings.field);
  summarize_field(study.field, study.summary);

  if (!settings.calibrate) {
    study.calibration_skipped = "not asked for";
  } else {
    CalibrationSettings believing_world = settings.calibration;
    believing_world.tracker_rig.reset();
    believing_world.propagate_uncertainty = false;  // not reported: the baseline's errors are what count
    CalibrationSettings believing_assumed = settings.calibration;
    believing_assumed.tracker_rig = assumed;
    // A tracker believes a screen: the world's, where the assumed version has none.
    if (!assumed.screen) believing_assumed.tracker_rig->screen = world.screen;
    study.calibration_skipped = cannot_calibrate(world);
    if (study.calibration_skipped.empty()) {
      // The eye models' rules: each version's, named.
      check_calibration_rig(world, "the world", believing_world);
      check_calibration_rig(world, "the assumed version", believing_assumed);
      study.baseline = run_calibration(world, believing_world, step);
      study.assumed = run_calibration(world, believing_assumed, step);
      const Screen& screen = *world.screen;
      for (std::size_t p = 0; p < study.baseline->panels.size(); ++p) {
        const GazePanel& b = study.baseline->panels[p];
        const GazePanel& a = study.assumed->panels[p];
        for (std::size_t m = 0; m < 2; ++m) {
          for (std::size_t i = 0; i < b.targets.size(); ++i) {
            GazeChange g{b.title, m == 0 ? "model-based" : "polynomial", b.targets[i], b.estimates[m][i],
                         a.estimates[m][i], std::nullopt, std::nullopt, std::nullopt};
            const Point3& eye = b.cornea_centers[i];
            const auto angle = [&](const ScreenPoint& from, const ScreenPoint& to) {
              return angle_between(screen.at(from) - eye, screen.at(to) - eye) / kDegree;
            };
            if (g.baseline) g.baseline_error_deg = angle(*g.baseline, g.target);
            if (g.assumed) g.assumed_error_deg = angle(*g.assumed, g.target);
            if (g.baseline && g.assumed) g.change_deg = angle(*g.baseline, *g.assumed);
            study.gaze.push_back(g);
          }
        }
      }
      summarize_gaze(study, study.summary);
    }
  }
  if (!study.calibration_skipped.empty()) {
    SimulationRun skipped{"gaze", "both methods", {}, std::nullopt};
    skipped.results.add("calibration", "skipped: " + study.calibration_skipped);
    study.summary.push_back(std::move(skipped));
  }

  if (settings.images) {
    const Intrinsics& w = world.cameras[static_cast<std::size_t>(settings.field.camera)].intrinsics();
    const Intrinsics& a = assumed.cameras[static_cast<std::size_t>(settings.field.camera)].intrinsics();
    if (w.width != a.width || w.height != a.height) {
      throw std::invalid_argument("compare: images of " + std::to_string(w.width) + " x " + std::to_string(w.height) +
                                  " px (the world) and " + std::to_string(a.width) + " x " +
                                  std::to_string(a.height) +
                                  " px (the assumed version) have no difference image; compare without images");
    }
    study.world_image = renderer::render(world, settings.field.camera, settings.render);
    if (step) step();
    study.assumed_image = renderer::render(assumed, settings.field.camera, settings.render);
    if (step) step();
    summarize_images(*study.world_image, *study.assumed_image, study.summary);
  }
  if (study.baseline) {
    add_calibration_runs("believing the world", *study.baseline, study.summary);
    add_calibration_runs("believing the assumed", *study.assumed, study.summary);
  }
  return study;
}

std::string gaze_change_csv(const std::vector<GazeChange>& gaze) {
  std::ostringstream out;
  const auto number = [](const std::optional<double>& v) { return v ? check::format_number(*v) : std::string(); };
  out << "position,method,target_x_mm,target_y_mm,believing_world_x_mm,believing_world_y_mm,"
         "believing_assumed_x_mm,believing_assumed_y_mm,error_believing_world_deg,error_believing_assumed_deg,"
         "change_deg\n";
  for (const GazeChange& g : gaze) {
    const auto point = [&](const std::optional<ScreenPoint>& p) {
      return p ? check::format_number(p->x_mm) + "," + check::format_number(p->y_mm) : std::string(",");
    };
    out << csv_cell(g.position) << ',' << g.method << ',' << check::format_number(g.target.x_mm) << ','
        << check::format_number(g.target.y_mm) << ',' << point(g.baseline) << ',' << point(g.assumed) << ','
        << number(g.baseline_error_deg) << ',' << number(g.assumed_error_deg) << ',' << number(g.change_deg)
        << '\n';
  }
  return out.str();
}

}  // namespace purkinje::studies

namespace purkinje::studies {

const std::vector<SweepParameter>& sweep_parameters() {
  static const std::vector<SweepParameter> parameters = {
      {"cornea_radius", "mm", "the anterior cornea's apex radius"},
      {"cornea_asphericity", "", "the anterior cornea's asphericity Q"},
      {"aqueous_index", "", "the aqueous humour's refractive index"},
      {"iris_depth", "mm", "the iris' (and pupil's) depth behind the corneal apex"},
      {"pupil_decentration_x", "mm", "the pupil's centre in the iris plane, eye x"},
      {"pupil_decentration_y", "mm", "the pupil's centre in the iris plane, eye y (up)"},
      {"kappa_horizontal", "deg", "the visual axis from the optical axis, toward eye x"},
      {"kappa_vertical", "deg", "the visual axis from the optical axis, up"},
      {"led_offset_x", "mm", "the first light moved along world x"},
      {"led_offset_y", "mm", "the first light moved along world y"},
      {"led_offset_z", "mm", "the first light moved along world z"},
  };
  return parameters;
}

Scene with_parameter(const Scene& world, const std::string& parameter, double value) {
  const auto fail = [&](const std::string& rule) {
    throw std::invalid_argument("sweep: " + parameter + " = " + check::format_number(value) + ": " + rule);
  };
  const auto& known = sweep_parameters();
  if (std::none_of(known.begin(), known.end(), [&](const SweepParameter& p) { return p.name == parameter; })) {
    std::string names;
    for (const SweepParameter& p : known) names += (names.empty() ? "" : ", ") + p.name;
    throw std::invalid_argument("sweep: unknown parameter \"" + parameter + "\" (known: " + names + ")");
  }
  if (!std::isfinite(value)) fail("must be a finite number");
  Scene out = world;
  if (parameter.starts_with("led_offset_")) {
    if (out.illuminators.empty()) fail("the scene has no light to move");
    Point3& at = out.illuminators.front().position;
    (parameter == "led_offset_x" ? at.x : parameter == "led_offset_y" ? at.y : at.z) += value;
    return out;
  }
  if (world.eyes.size() != 1) fail("the scene must have one eye");
  const Eye& eye = world.eyes.front();
  EyeModel m = eye.model();
  constexpr double kDeg = std::numbers::pi / 180;
  double* field = parameter == "cornea_radius"          ? &m.anterior_cornea.radius_mm
                  : parameter == "cornea_asphericity"   ? &m.anterior_cornea.asphericity
                  : parameter == "aqueous_index"        ? &m.aqueous_index
                  : parameter == "iris_depth"           ? &m.iris_depth_mm
                  : parameter == "pupil_decentration_x" ? &m.pupil_decentration_x_mm
                  : parameter == "pupil_decentration_y" ? &m.pupil_decentration_y_mm
                  : parameter == "kappa_horizontal"     ? &m.kappa_horizontal_rad
                  : parameter == "kappa_vertical"       ? &m.kappa_vertical_rad
                                                        : nullptr;
  if (!field) throw std::logic_error("sweep: " + parameter + " is in sweep_parameters but not in with_parameter");
  if (parameter == "aqueous_index" && !(value > 1)) fail("must be more than 1");
  const bool kappa = parameter.starts_with("kappa_");
  if (kappa && !(std::abs(value) <= 45)) fail("must be within 45 deg");
  const double set = kappa ? value * kDeg : value;
  // The world's own value: the world's eye itself, bit for bit (its pose
  // rebuilt would differ in the last bits).
  if (*field == set) return out;
  *field = set;
  if (const auto problem = anatomy_problem(m)) {
    fail("the eye's anatomy refuses it: " + problem->key + " = " + problem->value + ": " + problem->rule);
  }
  out.eyes = {with_anatomy(eye, m)};
  return out;
}

void check_sweep(const Scene& world, const SweepSettings& s) {
  const auto fail = [&](const std::string& rule) { throw std::invalid_argument("sweep: " + rule); };
  if (s.steps < 2 || s.steps > 1000) fail("steps = " + std::to_string(s.steps) + ": must be from 2 to 1000");
  if (!std::isfinite(s.from) || !std::isfinite(s.to) || s.from == s.to) {
    fail("from " + check::format_number(s.from) + " to " + check::format_number(s.to) +
         ": must be two different finite numbers");
  }
  if (s.noise_frames < 0 || s.noise_frames > 10000) {
    fail("noise_frames = " + std::to_string(s.noise_frames) + ": must be from 0 to 10000");
  }
  for (const double v : {s.from, s.to}) with_parameter(world, s.parameter, v);
}

namespace {

double sweep_value(const SweepSettings& s, int k) {
  // Weighted ends over the count: -0.5 to 0 in ten steps gives -0.35, not
  // -0.35000000000000003.
  return (s.from * (s.steps - 1 - k) + s.to * k) / (s.steps - 1);
}

}  // namespace

std::size_t sweep_steps(const Scene& world, const CompareStudySettings& settings, const SweepSettings& sweep) {
  CompareStudySettings each = settings;
  each.images = false;
  const bool measured = sweep.noise_frames > 0 && world.screen.has_value();
  return (measured ? static_cast<std::size_t>(sweep.noise_frames) + compare_steps(world, each) : 0) +
         static_cast<std::size_t>(sweep.steps) * compare_steps(world, each);
}

Sweep run_sweep(const Scene& world, const CompareStudySettings& settings, const SweepSettings& sweep,
                const std::function<void()>& step) {
  check_sweep(world, sweep);
  Sweep out;
  out.parameter = sweep.parameter;
  for (const SweepParameter& p : sweep_parameters()) {
    if (p.name == sweep.parameter) out.unit = p.unit;
  }
  // Every value's version first: a value refused refuses the sweep before any work.
  std::vector<Scene> versions;
  for (int k = 0; k < sweep.steps; ++k) {
    out.values.push_back(sweep_value(sweep, k));
    versions.push_back(with_parameter(world, sweep.parameter, out.values.back()));
  }
  CompareStudySettings each = settings;
  each.images = false;
  if (sweep.noise_frames > 0 && world.screen) {
    out.noise = measure_detector_noise(world, sweep.noise_frames, sweep.seed, step);
    if (!each.calibration.glint_noise_px && out.noise->glint_px > 0) each.calibration.glint_noise_px = out.noise->glint_px;
    if (!each.calibration.pupil_noise_px && out.noise->pupil_px > 0) each.calibration.pupil_noise_px = out.noise->pupil_px;
    // What that noise alone costs gaze, as the tracker reports it: the
    // world believed as it is.
    const CompareStudy floor = run_compare(world, world, each, step);
    if (floor.assumed) {
      for (const SimulationRun& run : floor.assumed->runs) {
        if (run.case_name == "home" && run.algorithm == "model-based") {
          out.gaze_noise_deg = run.results.number("gaze_sd_median");
        }
      }
    }
  }
  for (const Scene& version : versions) out.summaries.push_back(run_compare(world, version, each, step).summary);
  return out;
}

std::string sweep_csv(const Sweep& sweep) {
  std::ostringstream out;
  out << "value,subject,quantity,mean,rms,max,unit\n";
  const auto cell = [](const Results& r, const std::string& key) {
    const auto v = r.number(key);
    return v ? check::format_number(*v) : std::string();
  };
  for (std::size_t k = 0; k < sweep.values.size(); ++k) {
    const std::string value = check::format_number(sweep.values[k]);
    for (const SimulationRun& run : sweep.summaries[k]) {
      const Results& r = run.results;
      if (run.case_name == "displacement") {
        out << value << ',' << csv_cell(run.algorithm) << ",displacement," << cell(r, "displacement_mean") << ','
            << cell(r, "displacement_rms") << ',' << cell(r, "displacement_max") << ",px\n";
      } else if (run.case_name.starts_with("gaze: ")) {
        const std::string subject = csv_cell(run.algorithm + ", " + run.case_name.substr(6));
        out << value << ',' << subject << ",gaze_change," << cell(r, "change_mean") << ',' << cell(r, "change_rms")
            << ',' << cell(r, "change_max") << ",deg\n";
        if (r.number("believing_assumed_cornea_depth_error_mean")) {
          out << value << ',' << subject << ",cornea_depth_error,"
              << cell(r, "believing_assumed_cornea_depth_error_mean") << ','
              << cell(r, "believing_assumed_cornea_depth_error_rms") << ",,mm\n";
        }
        if (r.number("believing_assumed_cornea_within_3sd_depth")) {
          out << value << ',' << subject << ",cornea_within_3sd_depth,"
              << cell(r, "believing_assumed_cornea_within_3sd_depth") << ",,,%\n";
        }
      }
    }
  }
  return out.str();
}

std::string sweep_json(const Sweep& sweep) {
  nlohmann::ordered_json j;
  j["parameter"] = sweep.parameter;
  j["unit"] = sweep.unit;
  for (const SweepParameter& p : sweep_parameters()) {
    if (p.name == sweep.parameter) j["meaning"] = p.meaning;
  }
  j["values"] = sweep.values;
  nlohmann::ordered_json floor = nlohmann::ordered_json::object();
  if (sweep.noise) {
    floor["frames"] = sweep.noise->frames;
    floor["glint_px"] = sweep.noise->glint_errors > 0 ? nlohmann::ordered_json(sweep.noise->glint_px) : nullptr;
    floor["pupil_px"] = sweep.noise->pupil_errors > 0 ? nlohmann::ordered_json(sweep.noise->pupil_px) : nullptr;
    floor["glint_errors"] = sweep.noise->glint_errors;
    floor["pupil_errors"] = sweep.noise->pupil_errors;
  }
  floor["gaze_deg"] = sweep.gaze_noise_deg ? nlohmann::ordered_json(*sweep.gaze_noise_deg) : nullptr;
  j["noise_floor"] = floor;
  return j.dump(2) + "\n";
}

}  // namespace purkinje::studies
