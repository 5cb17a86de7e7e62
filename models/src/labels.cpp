// Label files. The layout of both formats is documented field by field in
// docs/labels.md; keep the two in step.

#include "purkinje/models/labels.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <stdexcept>

#include "purkinje/models/csv.h"

namespace purkinje {
namespace {

// Keys in the order written, which is the order docs/labels.md lists them.
using json = nlohmann::ordered_json;

constexpr double kDegreesPerRadian = 180.0 / std::numbers::pi;

// ------------------------------------------------------ values or null
// Every number goes through these, so a NaN or infinity cannot reach a
// file even if a status check upstream is wrong.

json number(double v) {
  if (!std::isfinite(v)) return nullptr;
  return v == 0 ? 0.0 : v;  // no "-0.0" in files
}
json degrees(double radians) { return number(radians * kDegreesPerRadian); }
// A face's lashes or brows: their numbers and seed.
template <class Hairs, std::size_t N>
json hairs_json(const Hairs& hairs, const std::array<HairKey<Hairs>, N>& keys) {
  json o = json::object();
  for (const HairKey<Hairs>& key : keys) o[std::string(key.name)] = number(hairs.*key.member);
  o["seed"] = hairs.seed;
  return o;
}
json triple(double x, double y, double z) {
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) return nullptr;
  return json::array({number(x), number(y), number(z)});
}
json point(const Point3& p) { return triple(p.x, p.y, p.z); }
json vector(const Vector3& v) { return triple(v.x, v.y, v.z); }

// Pixel validity by status. truth.cpp fills the pixel of an off_cornea path
// too, unless the point is behind the camera, which only the camera knows;
// an occluded point was ok before something hid it, so its pixel is where
// it would be seen.
bool pixel_valid(PathStatus status, const Camera& camera, const Point3& surface_point) {
  switch (status) {
    case PathStatus::ok:
    case PathStatus::outside_image:
    case PathStatus::occluded: return true;
    case PathStatus::off_cornea:
      return camera.project(surface_point).status != ProjectionStatus::behind_camera;
    default: return false;
  }
}
// The 3D path exists: the solver found it, on the cap or beyond the limbus.
bool path_valid(PathStatus solver_status) {
  return solver_status == PathStatus::ok || solver_status == PathStatus::off_cornea;
}

void pixel_fields(json& out, bool valid, const Pixel& p) {
  out["u_px"] = valid ? number(p.u) : json(nullptr);
  out["v_px"] = valid ? number(p.v) : json(nullptr);
}

json projection_json(const Projection& p) {
  json out = json::object();
  out["status"] = to_string(p.status);
  pixel_fields(out, p.status != ProjectionStatus::behind_camera, p.pixel);
  return out;
}

json rotation_rows(const Rotation& r) {
  json rows = json::array();
  for (int i = 0; i < 3; ++i) rows.push_back(json::array({number(r(i, 0)), number(r(i, 1)), number(r(i, 2))}));
  return rows;
}

json pose_json(const Pose& pose) {
  json out = json::object();
  out["rotation"] = rotation_rows(pose.rotation());
  out["rotation_vector_deg"] = vector(pose.rotation().rotation_vector() * kDegreesPerRadian);
  out["translation_mm"] = vector(pose.translation());
  return out;
}

json camera_json(const Camera& c, int index) {
  const Intrinsics& k = c.intrinsics();
  const Distortion& d = c.distortion();
  json out = json::object();
  out["index"] = index;
  out["name"] = c.name();
  out["width_px"] = k.width;
  out["height_px"] = k.height;
  out["fx_px"] = number(k.fx);
  out["fy_px"] = number(k.fy);
  out["cx_px"] = number(k.cx);
  out["cy_px"] = number(k.cy);
  out["distortion"] = {{"k1", number(d.k1)}, {"k2", number(d.k2)}, {"p1", number(d.p1)},
                       {"p2", number(d.p2)}, {"k3", number(d.k3)}};
  out["center_mm"] = point(c.center());
  out["world_from_camera"] = pose_json(c.world_from_camera());
  out["camera_from_world"] = pose_json(c.camera_from_world());
  return out;
}

json illuminator_json(const Illuminator& l, int index) {
  json out = json::object();
  out["index"] = index;
  out["name"] = l.name;
  out["position_mm"] = point(l.position);
  out["radiant_intensity_w_sr"] = number(l.radiant_intensity_w_sr);
  out["wavelength_nm"] = number(l.wavelength_nm);
  out["emitter_diameter_mm"] = number(l.emitter_diameter_mm);
  return out;
}

json eye_json(const Eye& eye, const EyeTruth& t, int index) {
  const EyeModel& m = eye.model();
  json out = json::object();
  out["index"] = index;
  out["model"] = m.name;
  out["cornea_center_mm"] = point(t.cornea_center);
  out["cornea_radius_mm"] = number(t.cornea_radius_mm);
  out["cornea_asphericity"] = number(m.anterior_cornea.asphericity);
  out["corneal_apex_mm"] = point(eye.corneal_apex());
  out["limbus_radius_mm"] = number(m.limbus_radius_mm);
  out["rotation_center_mm"] = point(t.rotation_center);
  out["pupil_center_mm"] = point(t.pupil_center);
  out["pupil_radius_mm"] = number(t.pupil_radius_mm);
  out["optical_axis"] = vector(t.optical_axis);
  out["visual_axis"] = vector(t.visual_axis);
  // Only for an eye that turns during the exposure: its pose above is the
  // one at mid-exposure.
  if (!eye.motion().still()) {
    out["motion"] = {{"yaw_deg_s", number(eye.motion().yaw_deg_s)}, {"pitch_deg_s", number(eye.motion().pitch_deg_s)}};
  }
  out["kappa_deg"] = {{"horizontal", degrees(m.kappa_horizontal_rad)},
                      {"vertical", degrees(m.kappa_vertical_rad)}};
  out["posterior_cornea"] = m.posterior_cornea.has_value();
  out["aqueous_index"] = number(m.aqueous_index);
  out["rotation_center_depth_mm"] = number(m.rotation_center_depth_mm);
  // How the eye looks: what a data set varies besides its geometry.
  const EyeAppearance& a = eye.appearance();
  json look = json::object();
  look["iris_albedo"] = number(a.iris_albedo);
  look["iris_texture_contrast"] = number(a.iris_texture_contrast);
  look["iris_seed"] = a.iris_seed;
  look["sclera_albedo"] = number(a.sclera_albedo);
  look["skin_albedo"] = number(a.skin_albedo);
  look["fundus_reflectance"] = number(a.fundus_reflectance);
  look["head_forward"] = vector(a.head_forward);
  look["head_up"] = vector(a.head_up);
  look["lid_opening"] = a.eyelids ? number(a.eyelids->opening) : json(nullptr);
  json face(nullptr);
  if (a.face) {
    face = {{"side", to_string(a.face->side)}};
    for (const FaceKey& key : kFaceKeys) face[std::string(key.name)] = number(a.face.value().*key.member);
    face["lashes"] = a.face->lashes ? hairs_json(*a.face->lashes, kLashKeys) : json(nullptr);
    face["brows"] = a.face->brows ? hairs_json(*a.face->brows, kBrowKeys) : json(nullptr);
  }
  look["face"] = face;
  // The textures and the tear film only when on (as in scene files).
  if (a.iris_furrow_contrast != 0) look["iris_furrow_contrast"] = number(a.iris_furrow_contrast);
  if (a.iris_freckles != 0) look["iris_freckles"] = a.iris_freckles;
  if (a.skin_texture_contrast != 0) look["skin_texture_contrast"] = number(a.skin_texture_contrast);
  if (a.sclera_vessel_contrast != 0) look["sclera_vessel_contrast"] = number(a.sclera_vessel_contrast);
  if (a.tear_film) {
    look["tear_film"] = {{"sclera_roughness_deg", number(a.tear_film->sclera_roughness_deg)},
                         {"meniscus_radius_mm", number(a.tear_film->meniscus_radius_mm)},
                         {"upper_meniscus_radius_mm", number(a.tear_film->upper_meniscus_radius_mm)}};
  }
  out["appearance"] = look;
  return out;
}

json glint_json(const GlintTruth& g, const Scene& scene, const Camera& camera) {
  const Reflection& r = g.reflection;
  const bool has_path = path_valid(r.status);
  json out = json::object();
  out["illuminator"] = g.illuminator;
  out["illuminator_name"] = scene.illuminators.at(g.illuminator).name;
  out["status"] = to_string(g.status);
  if (g.status == PathStatus::occluded) out["occluded_by"] = to_string(g.occluder);
  pixel_fields(out, has_path && pixel_valid(g.status, camera, r.point), g.pixel);
  const json null;
  out["point_mm"] = has_path ? point(r.point) : null;
  out["normal"] = has_path ? vector(r.normal) : null;
  out["incident"] = has_path ? vector(r.incident) : null;
  out["reflected"] = has_path ? vector(r.reflected) : null;
  out["incidence_deg"] = has_path ? degrees(r.incidence_rad) : null;
  out["on_cap"] = has_path ? json(r.on_cap) : null;
  return out;
}

json distractor_json(const DistractorTruth& d, const Scene& scene, const Camera& camera) {
  const Reflection& r = d.reflection;
  json out = json::object();
  out["kind"] = to_string(d.kind);
  out["illuminator"] = d.illuminator;
  out["illuminator_name"] = scene.illuminators.at(d.illuminator).name;
  if (d.spectacle_lens >= 0) {
    out["spectacle_lens"] = d.spectacle_lens;
    out["spectacle_lens_name"] = scene.spectacle_lenses.at(d.spectacle_lens).name;
  }
  out["status"] = to_string(d.status);
  if (d.status == PathStatus::occluded) out["occluded_by"] = to_string(d.occluder);
  pixel_fields(out, pixel_valid(d.status, camera, r.point), d.pixel);
  out["point_mm"] = point(r.point);
  out["normal"] = vector(r.normal);
  out["incident"] = vector(r.incident);
  out["reflected"] = vector(r.reflected);
  out["incidence_deg"] = degrees(r.incidence_rad);
  return out;
}

void refraction_fields(json& out, const Refraction& r) {
  const bool has_path = path_valid(r.status);
  const json null;
  out["cornea_point_mm"] = has_path ? point(r.anterior_point) : null;
  out["posterior_point_mm"] = has_path && r.posterior_point ? point(*r.posterior_point) : null;
  out["cornea_normal"] = has_path ? vector(r.anterior_normal) : null;
  out["inner_direction"] = has_path ? vector(r.inner_direction) : null;
  out["outer_direction"] = has_path ? vector(r.outer_direction) : null;
  out["on_cap"] = has_path ? json(r.on_cap) : null;
}

json ellipse_json(bool valid, const Ellipse& e) {
  if (!valid) return nullptr;
  json out = json::object();
  out["center_u_px"] = number(e.center.u);
  out["center_v_px"] = number(e.center.v);
  out["semi_axis_1_px"] = number(e.semi_axis_1_px);
  out["semi_axis_2_px"] = number(e.semi_axis_2_px);
  out["angle_deg"] = degrees(e.angle_rad);
  return out;
}

json pupil_json(const PupilTruth& p, const Camera& camera) {
  json out = json::object();
  json border = json::array();
  for (std::size_t i = 0; i < p.border.size(); ++i) {
    const PupilBorderPointTruth& b = p.border[i];
    json point_out = json::object();
    point_out["index"] = i;
    point_out["angle_deg"] = degrees(b.angle_rad);
    point_out["status"] = to_string(b.status);
    if (b.status == PathStatus::occluded) point_out["occluded_by"] = to_string(b.occluder);
    pixel_fields(point_out,
                 path_valid(b.refraction.status) &&
                     pixel_valid(b.status, camera, b.refraction.anterior_point),
                 b.pixel);
    point_out["border_point_mm"] = point(b.border_point);
    refraction_fields(point_out, b.refraction);
    border.push_back(point_out);
  }
  out["border"] = border;
  out["ellipse"] = ellipse_json(p.ellipse_valid, p.ellipse);
  out["visible_ellipse"] = ellipse_json(p.visible_ellipse_valid, p.visible_ellipse);
  json centre = json::object();
  centre["status"] = to_string(p.refracted_center_status);
  if (p.refracted_center_status == PathStatus::occluded) centre["occluded_by"] = to_string(p.refracted_center_occluder);
  pixel_fields(centre,
               path_valid(p.refracted_center_path.status) &&
                   pixel_valid(p.refracted_center_status, camera,
                               p.refracted_center_path.anterior_point),
               p.refracted_center);
  refraction_fields(centre, p.refracted_center_path);
  out["refracted_center"] = centre;
  out["unrefracted_center"] = projection_json(p.unrefracted_center);
  return out;
}

json view_json(const EyeInCameraTruth& v, const Scene& scene) {
  const Camera& camera = scene.cameras.at(v.camera);
  json out = json::object();
  out["camera"] = v.camera;
  out["camera_name"] = camera.name();
  out["eye"] = v.eye;
  out["cornea_center"] = projection_json(v.cornea_center);
  out["rotation_center"] = projection_json(v.rotation_center);
  json glints = json::array();
  for (const GlintTruth& g : v.glints) glints.push_back(glint_json(g, scene, camera));
  out["glints"] = glints;
  // Only for an eye with a tear film, whose sclera mirrors the lights, or
  // in a scene with spectacle lenses, which mirror them.
  if (scene.eyes.at(v.eye).appearance().tear_film || !scene.spectacle_lenses.empty()) {
    json distractors = json::array();
    for (const DistractorTruth& d : v.distractors) distractors.push_back(distractor_json(d, scene, camera));
    out["distractors"] = distractors;
  }
  out["pupil"] = pupil_json(v.pupil, camera);
  return out;
}

// Pretty JSON that keeps short arrays of numbers ([x, y, z], matrix rows)
// on one line; nlohmann's dump(2) would spend a line on every number.
void write_pretty(const json& j, std::string& out, int indent) {
  const std::string pad(static_cast<std::size_t>(indent) + 2, ' ');
  const std::string close_pad(static_cast<std::size_t>(indent), ' ');
  if (j.is_object() && !j.empty()) {
    out += "{\n";
    bool first = true;
    for (const auto& [key, value] : j.items()) {
      if (!first) out += ",\n";
      first = false;
      out += pad + json(key).dump() + ": ";
      write_pretty(value, out, indent + 2);
    }
    out += "\n" + close_pad + "}";
  } else if (j.is_array() && !j.empty()) {
    const bool flat = std::all_of(j.begin(), j.end(), [](const json& e) { return e.is_primitive(); });
    if (flat) {
      out += "[";
      for (std::size_t i = 0; i < j.size(); ++i) out += (i ? ", " : "") + j[i].dump();
      out += "]";
      return;
    }
    out += "[\n";
    for (std::size_t i = 0; i < j.size(); ++i) {
      if (i) out += ",\n";
      out += pad;
      write_pretty(j[i], out, indent + 2);
    }
    out += "\n" + close_pad + "]";
  } else {
    out += j.dump();
  }
}

// ---------------------------------------------------------------- CSV

const char* const kCsvColumns[] = {
    "camera", "camera_name", "eye",   "feature", "index",         "name",           "status",
    "u_px",   "v_px",        "x_mm",  "y_mm",    "z_mm",          "on_cap",         "incidence_deg",
    "angle_deg", "semi_axis_1_px", "semi_axis_2_px", "kind"};
constexpr std::size_t kCsvColumnCount = sizeof kCsvColumns / sizeof kCsvColumns[0];

std::string csv_number(double v) {
  if (!std::isfinite(v)) return "";
  if (v == 0) v = 0.0;  // no "-0" in files
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, result.ptr);
}


struct CsvRow {
  std::string cells[kCsvColumnCount];
  void set(const char* column, std::string value) {
    for (std::size_t i = 0; i < kCsvColumnCount; ++i) {
      if (std::strcmp(kCsvColumns[i], column) == 0) {
        cells[i] = std::move(value);
        return;
      }
    }
    throw std::logic_error(std::string("no CSV column ") + column);
  }
  void set_pixel(bool valid, const Pixel& p) {
    if (!valid) return;
    set("u_px", csv_number(p.u));
    set("v_px", csv_number(p.v));
  }
  void set_point(const Point3& p) {
    if (!p.is_finite()) return;
    set("x_mm", csv_number(p.x));
    set("y_mm", csv_number(p.y));
    set("z_mm", csv_number(p.z));
  }
  void append_to(std::string& out) const {
    for (std::size_t i = 0; i < kCsvColumnCount; ++i) out += (i ? "," : "") + cells[i];
    out += "\n";
  }
};

}  // namespace

std::string truth_to_json(const Scene& scene, const SceneTruth& truth) {
  if (truth.eyes.size() != scene.eyes.size()) {
    throw std::invalid_argument("truth_to_json: the truth has " + std::to_string(truth.eyes.size()) +
                                " eyes, the scene " + std::to_string(scene.eyes.size()));
  }
  json root = json::object();
  root["labels_format"] = kLabelsFormatVersion;
  root["scene"] = scene.name;
  root["units"] = {{"length", "mm"},
                   {"angle", "deg"},
                   {"image", "px, OpenCV convention: (0, 0) is the centre of the top-left pixel, "
                             "u right, v down"},
                   {"frame", "world, unless a field says otherwise"}};
  json cameras = json::array();
  for (std::size_t i = 0; i < scene.cameras.size(); ++i) {
    cameras.push_back(camera_json(scene.cameras[i], static_cast<int>(i)));
  }
  root["cameras"] = cameras;
  json lights = json::array();
  for (std::size_t i = 0; i < scene.illuminators.size(); ++i) {
    lights.push_back(illuminator_json(scene.illuminators[i], static_cast<int>(i)));
  }
  root["illuminators"] = lights;
  json eyes = json::array();
  for (std::size_t i = 0; i < scene.eyes.size(); ++i) {
    eyes.push_back(eye_json(scene.eyes[i], truth.eyes[i], static_cast<int>(i)));
  }
  root["eyes"] = eyes;
  json views = json::array();
  for (const EyeInCameraTruth& v : truth.views) views.push_back(view_json(v, scene));
  root["views"] = views;

  std::string out;
  write_pretty(root, out, 0);
  return out + "\n";
}

std::string truth_to_csv(const Scene& scene, const SceneTruth& truth) {
  std::string out;
  for (std::size_t i = 0; i < kCsvColumnCount; ++i) {
    if (i) out += ',';
    out += kCsvColumns[i];
  }
  out += "\n";

  for (const EyeInCameraTruth& v : truth.views) {
    const Camera& camera = scene.cameras.at(v.camera);
    const EyeTruth& eye = truth.eyes.at(v.eye);
    auto row = [&](const char* feature) {
      CsvRow r;
      r.set("camera", std::to_string(v.camera));
      r.set("camera_name", csv_cell(camera.name()));
      r.set("eye", std::to_string(v.eye));
      r.set("feature", feature);
      return r;
    };

    for (const GlintTruth& g : v.glints) {
      CsvRow r = row("glint");
      r.set("index", std::to_string(g.illuminator));
      r.set("name", csv_cell(scene.illuminators.at(g.illuminator).name));
      r.set("status", to_string(g.status));
      const Reflection& path = g.reflection;
      if (path_valid(path.status)) {
        r.set_pixel(pixel_valid(g.status, camera, path.point), g.pixel);
        r.set_point(path.point);
        r.set("on_cap", path.on_cap ? "1" : "0");
        r.set("incidence_deg", csv_number(path.incidence_rad * kDegreesPerRadian));
      }
      r.append_to(out);
    }

    for (const DistractorTruth& d : v.distractors) {
      CsvRow r = row("distractor");
      r.set("index", std::to_string(d.illuminator));
      r.set("name", csv_cell(scene.illuminators.at(d.illuminator).name));
      r.set("status", to_string(d.status));
      r.set_pixel(pixel_valid(d.status, camera, d.reflection.point), d.pixel);
      r.set_point(d.reflection.point);
      r.set("on_cap", "0");
      r.set("incidence_deg", csv_number(d.reflection.incidence_rad * kDegreesPerRadian));
      r.set("kind", to_string(d.kind));
      r.append_to(out);
    }

    const PupilTruth& pupil = v.pupil;
    for (std::size_t i = 0; i < pupil.border.size(); ++i) {
      const PupilBorderPointTruth& b = pupil.border[i];
      CsvRow r = row("pupil_border");
      r.set("index", std::to_string(i));
      r.set("status", to_string(b.status));
      r.set("angle_deg", csv_number(b.angle_rad * kDegreesPerRadian));
      r.set_point(b.border_point);
      if (path_valid(b.refraction.status)) {
        r.set_pixel(pixel_valid(b.status, camera, b.refraction.anterior_point), b.pixel);
        r.set("on_cap", b.refraction.on_cap ? "1" : "0");
      }
      r.append_to(out);
    }

    {
      CsvRow r = row("pupil_ellipse");
      r.set("status", pupil.ellipse_valid ? "ok" : "no_fit");
      if (pupil.ellipse_valid) {
        r.set_pixel(true, pupil.ellipse.center);
        r.set("angle_deg", csv_number(pupil.ellipse.angle_rad * kDegreesPerRadian));
        r.set("semi_axis_1_px", csv_number(pupil.ellipse.semi_axis_1_px));
        r.set("semi_axis_2_px", csv_number(pupil.ellipse.semi_axis_2_px));
      }
      r.append_to(out);
    }
    {
      CsvRow r = row("pupil_center_refracted");
      r.set("status", to_string(pupil.refracted_center_status));
      const Refraction& path = pupil.refracted_center_path;
      if (path_valid(path.status)) {
        r.set_pixel(pixel_valid(pupil.refracted_center_status, camera, path.anterior_point),
                    pupil.refracted_center);
        r.set("on_cap", path.on_cap ? "1" : "0");
      }
      r.set_point(eye.pupil_center);
      r.append_to(out);
    }
    auto projected = [&](const char* feature, const Projection& p, const Point3& where) {
      CsvRow r = row(feature);
      r.set("status", to_string(p.status));
      r.set_pixel(p.status != ProjectionStatus::behind_camera, p.pixel);
      r.set_point(where);
      r.append_to(out);
    };
    projected("pupil_center_unrefracted", pupil.unrefracted_center, eye.pupil_center);
    projected("cornea_center", v.cornea_center, eye.cornea_center);
    projected("rotation_center", v.rotation_center, eye.rotation_center);
  }
  return out;
}

}  // namespace purkinje
