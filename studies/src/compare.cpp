// The compare study's displacement field: see compare.h.

#include "purkinje/studies/compare.h"

#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "purkinje/models/check.h"
#include "purkinje/models/csv.h"

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
