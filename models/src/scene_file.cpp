// Scene files: JSON with comments, read through a small typed reader that
// knows the path of every value, marks every key it reads and rejects the
// keys nobody read. Every key and rule is documented in docs/scene-format.md.

#include "purkinje/models/scene_file.h"

#include "json_reader.h"
#include "purkinje/models/input_file.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <climits>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <set>
#include <sstream>
#include <string_view>
#include <type_traits>
#include <vector>

#include "purkinje/models/obj_file.h"

namespace purkinje {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;
constexpr int kMaxResolutionPx = 65536;
// A triangle whose sides meet at a sine below this has no area to shade,
// and its orientation is noise: the OBJ reader's rule (obj_file.cpp).
constexpr double kDegenerateSine = 1e-12;

using namespace json_reader;

// A direction as given when it is a unit vector to rounding (a dumped
// scene's: normalizing again could move its last bits), else normalized.
UnitVector3 unit_as_given(const Vector3& v) {
  if (std::abs(v.squared_norm() - 1.0) <= 8 * std::numeric_limits<double>::epsilon()) {
    return UnitVector3::from_normalized_unchecked(v);
  }
  return UnitVector3::normalize(v);
}

// A rotation given as its matrix, rows of three: exact, as a dump needs.
Rotation read_rotation_matrix(const Value& m) {
  const std::string rule = "must be a 3 x 3 rotation matrix, rows [[r00, r01, r02], [r10, r11, r12], [r20, r21, r22]]";
  if (!m.raw().is_array() || m.raw().size() != 3) m.fail(rule);
  std::array<std::vector<double>, 3> rows;
  for (int i = 0; i < 3; ++i) {
    const Value row = m.elements()[i];
    if (!row.raw().is_array() || row.raw().size() != 3) m.fail(rule);
    rows[i] = row.as_numbers(3);
  }
  const Vector3 x{rows[0][0], rows[1][0], rows[2][0]}, y{rows[0][1], rows[1][1], rows[2][1]},
      z{rows[0][2], rows[1][2], rows[2][2]};
  try {
    return Rotation::from_columns(UnitVector3::from(x), UnitVector3::from(y), UnitVector3::from(z));
  } catch (const std::invalid_argument&) {
    m.fail("must be a rotation: orthonormal columns, right-handed (determinant +1), within 1e-9");
  }
}

// ---------------------------------------------------------------- cameras

// The sensor block; `sensor` arrives with the pixel pitch already set when
// the camera was given by focal length (`focal_length_mm` set), which the
// block may then not repeat.
Sensor read_sensor(Object& s, Sensor sensor, std::optional<double> focal_length_mm,
                   const Intrinsics& intrinsics) {
  const bool pitch_from_camera = focal_length_mm.has_value();
  if (auto pitch = s.optional("pixel_pitch_mm")) {
    if (pitch_from_camera) {
      pitch->fail("allowed only with intrinsics_px (with focal_length_mm, the camera's own "
                  "pixel_pitch_mm gives it)");
    }
    sensor.pixel_pitch_mm = pitch->positive();
  }
  sensor.f_number = s.positive_or("f_number", sensor.f_number);
  sensor.exposure_s = s.positive_or("exposure_s", sensor.exposure_s);
  if (auto qe = s.optional("quantum_efficiency")) {
    sensor.quantum_efficiency = qe->as_double();
    if (!(sensor.quantum_efficiency > 0 && sensor.quantum_efficiency <= 1)) {
      qe->fail("must be > 0 and <= 1");
    }
  }
  sensor.full_well_e = s.positive_or("full_well_e", sensor.full_well_e);
  sensor.read_noise_e = s.non_negative_or("read_noise_e", sensor.read_noise_e);
  sensor.gain = s.positive_or("gain", sensor.gain);
  if (auto bits = s.optional("bits")) {
    sensor.bits = bits->as_int();
    if (sensor.bits != 8 && sensor.bits != 10 && sensor.bits != 12 && sensor.bits != 16) {
      bits->fail("must be one of 8, 10, 12, 16");
    }
  }
  // Wider than 20 px is no longer a lens but a fog, and the blur kernels
  // would grow to the size of the image.
  sensor.psf_sigma_px = s.within_or("psf_sigma_px", 0, 20, sensor.psf_sigma_px);
  if (auto focus = s.optional("focus_distance_mm")) {
    // A thin lens images nothing nearer than its focal length: the blur
    // circle would have no finite size.
    // The message quotes the focal length as written; the test also holds
    // for the renderer's fx * pitch, which may round a hair above it.
    const double renderer_focal_mm = intrinsics.fx * sensor.pixel_pitch_mm;
    const double focal_mm = focal_length_mm.value_or(renderer_focal_mm);
    const double distance_mm = focus->as_double();
    if (!(distance_mm > focal_mm && distance_mm > renderer_focal_mm)) {
      focus->fail("must be > the focal length (" + format_number(focal_mm) + " mm)");
    }
    sensor.focus_distance_mm = distance_mm;
  }
  sensor.noise = s.get_or<bool>("noise", sensor.noise);
  // A corner at 0 would be black, and a lens brighter at its corners than
  // at its centre is no vignetting.
  if (auto corner = s.optional("corner_illumination")) {
    sensor.corner_illumination = corner->as_double();
    if (!(sensor.corner_illumination > 0 && sensor.corner_illumination <= 1)) corner->fail("must be > 0 and <= 1");
  }
  // Beyond 1% a sensor is scrap, not a camera with hot pixels.
  sensor.hot_pixel_fraction = s.within_or("hot_pixel_fraction", 0, 0.01, sensor.hot_pixel_fraction);
  sensor.hot_pixel_e_per_s = s.non_negative_or("hot_pixel_e_per_s", sensor.hot_pixel_e_per_s);
  if (auto seed = s.optional("hot_pixel_seed")) sensor.hot_pixel_seed = seed->as_exact_count();
  if (auto quality = s.optional("jpeg_quality")) {
    const int q = quality->as_int();
    if (q < 1 || q > 100) quality->fail("must be an integer from 1 to 100");
    if (sensor.bits != 8) quality->fail("needs 8-bit images (bits = " + std::to_string(sensor.bits) + "): JPEG holds 8 bits");
    sensor.jpeg_quality = q;
  }
  s.finish();
  return sensor;
}

// A face's lashes or brows: its numbers within their bounds and a seed.
template <class Hairs, std::size_t N>
Hairs read_hairs(const Value& value, const std::array<HairKey<Hairs>, N>& keys) {
  Object o(value);
  Hairs hairs;
  for (const HairKey<Hairs>& key : keys) {
    hairs.*key.member = o.within_or(std::string(key.name), key.low, key.high, hairs.*key.member);
  }
  if (auto seed = o.optional("seed")) hairs.seed = seed->as_exact_count();
  o.finish();
  return hairs;
}

Camera read_camera(Object& c, std::size_t index) {
  const std::string name = c.get_or<std::string>("name", "cam" + std::to_string(index));
  if (name.empty()) c.required("name").fail("must not be empty");

  const Value resolution = c.required("resolution_px", "[width, height]");
  if (!resolution.raw().is_array() || resolution.raw().size() != 2) {
    resolution.fail("must be an array of 2 integers [width, height]");
  }
  int size[2];
  for (int i = 0; i < 2; ++i) {
    const Value e = resolution.elements()[i];
    size[i] = e.as_int();
    if (size[i] < 1) e.fail("must be >= 1");
    if (size[i] > kMaxResolutionPx) e.fail("must be <= " + std::to_string(kMaxResolutionPx));
  }
  const int width = size[0], height = size[1];

  Intrinsics intrinsics;
  Sensor sensor;
  std::optional<double> focal_length_mm;
  if (c.one_of("focal_length_mm", "intrinsics_px")) {
    const double focal = c.required("focal_length_mm").positive();
    focal_length_mm = focal;
    const double pitch = c.required("pixel_pitch_mm", "needed with focal_length_mm").positive();
    intrinsics = Intrinsics::from_focal_length(focal, pitch, width, height);
    sensor.pixel_pitch_mm = pitch;
  } else {
    if (c.has("pixel_pitch_mm")) {
      c.required("pixel_pitch_mm")
          .fail("not used with intrinsics_px (give focal_length_mm, or sensor.pixel_pitch_mm)");
    }
    Object k = c.object("intrinsics_px");
    intrinsics.width = width;
    intrinsics.height = height;
    intrinsics.fx = k.required("fx").positive();
    intrinsics.fy = k.required("fy").positive();
    intrinsics.cx = k.get_or<double>("cx", (width - 1) / 2.0);
    intrinsics.cy = k.get_or<double>("cy", (height - 1) / 2.0);
    k.finish();
  }

  Distortion distortion;
  if (auto d = c.optional_object("distortion")) {
    distortion.k1 = d->get_or<double>("k1", 0.0);
    distortion.k2 = d->get_or<double>("k2", 0.0);
    distortion.p1 = d->get_or<double>("p1", 0.0);
    distortion.p2 = d->get_or<double>("p2", 0.0);
    distortion.k3 = d->get_or<double>("k3", 0.0);
    d->finish();
  }

  if (auto s = c.optional_object("sensor")) {
    sensor = read_sensor(*s, sensor, focal_length_mm, intrinsics);
  }

  const Point3 position = c.get<Point3>("position_mm");
  Pose world_from_camera;
  const std::size_t orientation = c.one_of({"look_at_mm", "rotation_vector_deg", "rotation_matrix"});
  if (orientation != 0 && c.has("up")) c.required("up").fail("only used with look_at_mm");
  if (orientation == 0) {
    const Value look_at = c.required("look_at_mm");
    const Point3 target = look_at.as_point3();
    const Vector3 forward = target - position;
    if (!(forward.norm() > 0)) look_at.fail("must differ from position_mm");
    Vector3 up{0, -1, 0};
    if (auto u = c.optional("up")) {
      up = u->as_vector3();
      if (!(up.norm() > 0)) u->fail("must not be the zero vector");
      if (cross(forward / forward.norm(), up / up.norm()).norm() < 1e-6) {
        u->fail("must not be parallel to the viewing direction (look_at_mm - position_mm)");
      }
    } else if (cross(forward / forward.norm(), up).norm() < 1e-6) {
      look_at.fail("looks straight along the default up [0, -1, 0]: give \"up\"");
    }
    world_from_camera = camera_looking_at(position, target, up);
  } else if (orientation == 1) {
    const Vector3 degrees = c.get<Vector3>("rotation_vector_deg");
    world_from_camera = Pose(Rotation::from_rotation_vector(degrees * kDegree), position.from_origin());
  } else {
    world_from_camera = Pose(read_rotation_matrix(c.required("rotation_matrix")), position.from_origin());
  }
  c.finish();
  return Camera(name, intrinsics, distortion, world_from_camera, sensor);
}

// ----------------------------------------------------------- illuminators

Illuminator read_illuminator(Object& l, std::size_t index) {
  Illuminator out;
  out.name = l.get_or<std::string>("name", "led" + std::to_string(index));
  if (out.name.empty()) l.required("name").fail("must not be empty");
  out.position = l.get<Point3>("position_mm");
  out.radiant_intensity_w_sr = l.non_negative_or("radiant_intensity_w_sr", out.radiant_intensity_w_sr);
  out.wavelength_nm = l.positive_or("wavelength_nm", out.wavelength_nm);
  out.emitter_diameter_mm = l.non_negative_or("emitter_diameter_mm", out.emitter_diameter_mm);
  l.finish();
  return out;
}

// ----------------------------------------------------------------- screen

// What the eye looks at: centre and size, rows along `right` and columns
// along `down` (by default world +x and +y, a screen facing an eye that
// looks along -z, as the bundled scenes have it).
Screen read_screen(Object& s) {
  const bool centered = s.one_of("center_mm", "top_left_mm");
  const Point3 anchor = s.get<Point3>(centered ? "center_mm" : "top_left_mm");
  const Value size = s.required("size_mm", "the width and height in mm, [w, h]");
  const std::vector<double> wh = size.as_numbers(2);
  if (!(wh[0] > 0 && wh[1] > 0)) size.fail("width and height must be > 0");
  const auto right_value = s.optional("right");
  const auto down_value = s.optional("down");
  const Vector3 right = right_value ? right_value->direction() : Vector3{1, 0, 0};
  const Vector3 down = down_value ? down_value->direction() : Vector3{0, 1, 0};
  s.finish();
  const UnitVector3 r = unit_as_given(right), d = unit_as_given(down);
  if (!(std::abs(dot(r, d)) < 1e-6)) {
    (down_value ? *down_value : right_value ? *right_value : size).fail("right and down must be perpendicular");
  }
  if (centered) return Screen::centered(anchor, wh[0], wh[1], r, d);
  return Screen{anchor, r, d, wh[0], wh[1]};
}

// ------------------------------------------------------- spectacle lenses

// Vogel's rule for a lens's base curve (its front surface's power, D):
// power / 2 + 6 for plus lenses, power / 4 + 6 for minus lenses.
double vogel_base_curve_d(double power_d) { return power_d > 0 ? power_d / 2 + 6 : power_d / 4 + 6; }

// The centre thickness that leaves a plus lens's edge 1 mm thick at the
// outline's farthest point (at least 2 mm, a minus lens's usual centre).
double default_center_thickness_mm(double power_d, double front_radius_mm, double n, double reach_mm) {
  SpectacleLens lens;
  lens.center_thickness_mm = 2;
  if (!(power_d > 0)) return lens.center_thickness_mm;
  lens.front_radius_mm = front_radius_mm;
  lens.refractive_index = n;
  for (int i = 0; i < 30; ++i) {
    lens.back_radius_mm = back_radius_for_power_mm(power_d, front_radius_mm, lens.center_thickness_mm, n);
    const double edge = lens_thickness_mm(lens, reach_mm, 0);
    lens.center_thickness_mm = std::max(2.0, lens.center_thickness_mm + 1.0 - edge);
  }
  return lens.center_thickness_mm;
}

// A glasses lens, placed as a mesh is: position_mm its front vertex (the
// optical centre), rotation_vector_deg or rotation_matrix turning the lens
// frame (+z out of the front, away from the eye; +x along the outline's
// first semi-axis) into the world; shaped by a prescription (power_d, with
// base_curve_d and center_thickness_mm defaulted) or by its radii (as a
// dump writes it).
SpectacleLens read_spectacle_lens(Object& o, std::size_t index) {
  SpectacleLens lens;
  lens.name = o.get_or<std::string>("name", "lens" + std::to_string(index));
  if (lens.name.empty()) o.required("name").fail("must not be empty");
  const Point3 position = o.get<Point3>("position_mm");
  const std::size_t orientation = o.one_of({"rotation_vector_deg", "rotation_matrix"});
  const Rotation rotation =
      orientation == 0 ? Rotation::from_rotation_vector(o.get<Vector3>("rotation_vector_deg") * kDegree)
                       : read_rotation_matrix(o.required("rotation_matrix"));
  lens.world_from_lens = Pose(rotation, position.from_origin());
  lens.refractive_index = o.within_or("refractive_index", 1.0, 3.0, lens.refractive_index);
  if (!(lens.refractive_index > 1)) o.required("refractive_index").fail("must be above 1");
  if (auto axes = o.optional("outline_semi_axes_mm")) {
    const std::vector<Value> a = axes->elements();
    if (a.size() != 2) axes->fail("must hold 2 semi-axes in mm, [along lens x, along lens y]");
    for (int i = 0; i < 2; ++i) lens.outline_semi_axes_mm[i] = a[i].within(1e-3, 60);
  }
  const double reach = std::max(lens.outline_semi_axes_mm[0], lens.outline_semi_axes_mm[1]);
  if (o.one_of("power_d", "front_radius_mm")) {
    if (o.has("back_radius_mm")) o.required("back_radius_mm").fail("only used with front_radius_mm");
    const Value power = o.required("power_d");
    const double power_d = power.within(-20, 20);
    const double base_d = o.within_or("base_curve_d", 0.5, 20.0, std::max(0.5, vogel_base_curve_d(power_d)));
    lens.front_radius_mm = 1000 * (lens.refractive_index - 1) / base_d;
    try {
      lens.center_thickness_mm = o.within_or(
          "center_thickness_mm", 0.1, 30.0,
          default_center_thickness_mm(power_d, lens.front_radius_mm, lens.refractive_index, reach));
      lens.back_radius_mm =
          back_radius_for_power_mm(power_d, lens.front_radius_mm, lens.center_thickness_mm, lens.refractive_index);
    } catch (const std::invalid_argument& e) {
      power.fail(e.what());
    }
  } else {
    if (o.has("base_curve_d")) o.required("base_curve_d").fail("only used with power_d");
    lens.front_radius_mm = o.get<double>("front_radius_mm");
    lens.back_radius_mm = o.get<double>("back_radius_mm");
    lens.center_thickness_mm = o.get<double>("center_thickness_mm");
  }
  o.finish();
  try {
    check_spectacle_lens(lens);
  } catch (const std::invalid_argument& e) {
    o.where().fail("", e.what());
  }
  return lens;
}

// ----------------------------------------------------------------- meshes

// Vertices and triangles given in the scene itself (a dump, or a mesh
// built in code): indices from 0, each below the vertex count.
ObjMesh read_inline_mesh(Object& m) {
  ObjMesh mesh;
  const Value vertices = m.required("vertices_mm");
  for (const Value& v : vertices.elements()) mesh.vertices.push_back(v.as_point3());
  if (mesh.vertices.empty()) vertices.fail("must hold at least 3 vertices");
  const Value triangles = m.required("triangles", "[[i, j, k], ...], vertex indices from 0");
  for (const Value& t : triangles.elements()) {
    if (!t.raw().is_array() || t.raw().size() != 3) t.fail("must be an array of 3 vertex indices");
    Triangle triangle{};
    for (int k = 0; k < 3; ++k) {
      const Value index = t.elements()[k];
      const int i = index.as_int();
      if (i < 0 || static_cast<std::size_t>(i) >= mesh.vertices.size()) {
        index.fail("must be a vertex index from 0 to " + std::to_string(mesh.vertices.size() - 1));
      }
      triangle[k] = static_cast<std::uint32_t>(i);
    }
    mesh.triangles.push_back(triangle);
  }
  if (mesh.triangles.empty()) triangles.fail("must hold at least one triangle");
  return mesh;
}

// A mesh placed in the world: world = position + R (scale * v), R the
// rotation vector's, its vertices from an OBJ file or given inline. The
// file is read last, so that a misspelt key is reported before a large
// file is read.
Mesh read_mesh(Object& m, std::size_t index, const std::filesystem::path& folder) {
  Mesh mesh;
  mesh.name = m.get_or<std::string>("name", "mesh" + std::to_string(index));
  if (mesh.name.empty()) m.required("name").fail("must not be empty");
  const bool from_file = m.one_of("file", "vertices_mm");
  // No default: nothing is typical of an arbitrary object.
  mesh.albedo = m.required("albedo", "its Lambertian albedo, 0 to 1").within(0, 1);
  const Point3 position = m.get_or<Point3>("position_mm", Point3::origin());
  const Vector3 degrees = m.get_or<Vector3>("rotation_vector_deg", Vector3{});
  const double scale = m.positive_or("scale", 1.0);
  const Value source = m.required(from_file ? "file" : "vertices_mm");
  ObjMesh obj;
  if (from_file) {
    const std::filesystem::path file_name = source.as_string();
    if (file_name.empty()) source.fail("must not be empty");
    if (m.has("triangles")) m.required("triangles").fail("only used with vertices_mm");
    m.finish();
    const std::filesystem::path path = file_name.is_absolute() ? file_name : folder / file_name;
    std::error_code ignored;
    if (!std::filesystem::exists(path, ignored)) {
      source.fail(path == file_name ? "no such file" : "no such file (looked for " + path.string() + ")");
    }
    try {
      obj = load_obj(path);
    } catch (const ObjError& error) {
      source.fail(error.what());
    }
  } else {
    obj = read_inline_mesh(m);
    m.finish();
  }

  // Identity placement keeps the vertices' bits (a dump's are world points).
  const bool placed = !(position == Point3::origin() && degrees == Vector3{} && scale == 1.0);
  const Rotation rotation = Rotation::from_rotation_vector(degrees * kDegree);
  mesh.vertices.reserve(obj.vertices.size());
  for (std::size_t i = 0; i < obj.vertices.size(); ++i) {
    const Point3 p = placed ? position + rotation * (obj.vertices[i].from_origin() * scale) : obj.vertices[i];
    if (!p.is_finite() || std::abs(p.x) > kMaxCoordinateMm || std::abs(p.y) > kMaxCoordinateMm ||
        std::abs(p.z) > kMaxCoordinateMm) {
      source.fail("vertex " + std::to_string(i + (from_file ? 1 : 0)) + " lands at " + format_point(p) +
                  " mm, beyond +-" + format_number(kMaxCoordinateMm) + " mm (1 km): check scale and position_mm");
    }
    mesh.vertices.push_back(p);
  }
  // Placing rounds: a tiny scale (1e-300, found by fuzzing), or a small
  // mesh far from the origin, can merge a triangle's vertices, and the
  // renderer takes each triangle's plane. Triangles left without area are
  // left out, as the OBJ reader leaves out the file's own.
  for (const Triangle& t : obj.triangles) {
    const Vector3 a = mesh.vertices[t[1]] - mesh.vertices[t[0]];
    const Vector3 b = mesh.vertices[t[2]] - mesh.vertices[t[0]];
    if (cross(a, b).norm() > kDegenerateSine * a.norm() * b.norm()) mesh.triangles.push_back(t);
  }
  if (mesh.triangles.empty()) {
    source.fail("all " + std::to_string(obj.triangles.size()) + " triangles have zero area once placed (scale " +
                format_number(scale) + ", position_mm " + format_point(position) +
                "): check scale and position_mm");
  }
  return mesh;
}

// ------------------------------------------------------------------- eyes

// Anatomy that no single key can get wrong (the keys interact): the eye
// model's own rules (anatomy_problem in eye.h), reported at their keys.
void check_eye_model(const EyeModel& m, const Location& eye) {
  if (const std::optional<AnatomyProblem> problem = anatomy_problem(m)) {
    eye.child(problem->key).fail(problem->value, problem->rule);
  }
}

EyeModel read_eye_model(Object& e) {
  const std::string preset = e.get_or<std::string>("model", "keratometric");
  auto found = eye_model_preset(preset);
  if (!found) {
    e.required("model").fail("unknown eye model (valid: " + join(eye_model_preset_names()) + ")");
  }
  EyeModel m = *found;

  if (auto c = e.optional_object("cornea")) {
    m.anterior_cornea.radius_mm = c->positive_or("radius_mm", m.anterior_cornea.radius_mm);
    if (auto q = c->optional("asphericity")) m.anterior_cornea.asphericity = q->asphericity();
    m.limbus_radius_mm = c->positive_or("limbus_radius_mm", m.limbus_radius_mm);
    c->finish();
  }
  if (auto p = e.optional("posterior_cornea")) {
    if (p->raw().is_string()) {
      if (p->as_string() != "none") p->fail("must be an object or \"none\"");
      m.posterior_cornea.reset();
    } else {
      if (!p->raw().is_object()) p->fail("must be an object or \"none\"");
      Object o(*p);
      PosteriorCornea back = m.posterior_cornea.value_or(PosteriorCornea{});
      back.surface.radius_mm = o.positive_or("radius_mm", back.surface.radius_mm);
      if (auto q = o.optional("asphericity")) back.surface.asphericity = q->asphericity();
      back.thickness_mm = o.positive_or("thickness_mm", back.thickness_mm);
      if (auto n = o.optional("index")) back.cornea_index = n->refractive_index();
      o.finish();
      m.posterior_cornea = back;
    }
  }
  if (auto n = e.optional("aqueous_index")) m.aqueous_index = n->refractive_index();
  if (auto iris = e.optional_object("iris")) {
    m.iris_depth_mm = iris->positive_or("depth_mm", m.iris_depth_mm);
    m.iris_radius_mm = iris->positive_or("radius_mm", m.iris_radius_mm);
    iris->finish();
  }
  if (auto pupil = e.optional_object("pupil")) {
    m.pupil_radius_mm = pupil->positive_or("radius_mm", m.pupil_radius_mm);
    if (auto d = pupil->optional("decentration_mm")) {
      const auto xy = d->as_numbers(2);
      m.pupil_decentration_x_mm = xy[0];
      m.pupil_decentration_y_mm = xy[1];
    }
    pupil->finish();
  }
  m.rotation_center_depth_mm = e.positive_or("rotation_center_depth_mm", m.rotation_center_depth_mm);
  m.sclera_radius_mm = e.positive_or("sclera_radius_mm", m.sclera_radius_mm);
  if (auto kappa = e.optional_object("kappa_deg")) {
    if (auto h = kappa->optional("horizontal")) m.kappa_horizontal_rad = h->within(-45, 45) * kDegree;
    if (auto v = kappa->optional("vertical")) m.kappa_vertical_rad = v->within(-45, 45) * kDegree;
    kappa->finish();
  }
  check_eye_model(m, e.where());
  return m;
}

// Lid heights along the head's up direction: the opening must close
// between the margins. The key blamed is one the user wrote, where possible.
void check_lid_heights(Object& o, const Eyelids& lids) {
  const Location& where = o.where();
  if (!(lids.lower_margin_mm < lids.closing_line_mm)) {
    if (o.has("lower_margin_mm")) {
      where.child("lower_margin_mm")
          .fail_number(lids.lower_margin_mm,
                       "must be < closing_line_mm (" + format_number(lids.closing_line_mm) + ")");
    }
    where.child("closing_line_mm")
        .fail_number(lids.closing_line_mm,
                     "must be > lower_margin_mm (" + format_number(lids.lower_margin_mm) + ")");
  }
  if (!(lids.closing_line_mm < lids.upper_margin_mm)) {
    if (o.has("upper_margin_mm")) {
      where.child("upper_margin_mm")
          .fail_number(lids.upper_margin_mm,
                       "must be > closing_line_mm (" + format_number(lids.closing_line_mm) + ")");
    }
    where.child("closing_line_mm")
        .fail_number(lids.closing_line_mm,
                     "must be < upper_margin_mm (" + format_number(lids.upper_margin_mm) + ")");
  }
}

// Albedos, iris texture, head frame and eyelids; the preset has none of
// these, so the defaults are EyeAppearance's.
EyeAppearance read_appearance(Object& e) {
  EyeAppearance a;
  if (auto o = e.optional_object("appearance")) {
    a.iris_albedo = o->within_or("iris_albedo", 0, 1, a.iris_albedo);
    a.iris_texture_contrast = o->within_or("iris_texture_contrast", 0, 1, a.iris_texture_contrast);
    if (auto seed = o->optional("iris_seed")) a.iris_seed = seed->as_exact_count();
    a.iris_furrow_contrast = o->within_or("iris_furrow_contrast", 0, 1, a.iris_furrow_contrast);
    if (auto freckles = o->optional("iris_freckles")) {
      a.iris_freckles = freckles->as_int();
      if (a.iris_freckles < 0 || a.iris_freckles > 20) freckles->fail("must be between 0 and 20");
    }
    a.sclera_albedo = o->within_or("sclera_albedo", 0, 1, a.sclera_albedo);
    a.skin_albedo = o->within_or("skin_albedo", 0, 1, a.skin_albedo);
    a.fundus_reflectance = o->within_or("fundus_reflectance", 0, 1, a.fundus_reflectance);
    a.skin_texture_contrast = o->within_or("skin_texture_contrast", 0, 1, a.skin_texture_contrast);
    a.sclera_vessel_contrast = o->within_or("sclera_vessel_contrast", 0, 1, a.sclera_vessel_contrast);
    if (auto film = o->optional_object("tear_film")) {
      TearFilm t;
      // Beyond 10 deg a highlight spreads over a third of the sclera's
      // radius and its spread's first-order form no longer holds.
      t.sclera_roughness_deg = film->within_or("sclera_roughness_deg", 0, 10, t.sclera_roughness_deg);
      // Past 1 mm tears run over the lid (epiphora), no meniscus.
      t.meniscus_radius_mm = film->within_or("meniscus_radius_mm", 0, 1, t.meniscus_radius_mm);
      t.upper_meniscus_radius_mm = film->within_or("upper_meniscus_radius_mm", 0, 1, t.upper_meniscus_radius_mm);
      film->finish();
      a.tear_film = t;
    }
    o->finish();
  }

  if (auto lids_value = e.optional("eyelids")) {
    Object o(*lids_value);
    Eyelids lids;
    lids.opening = o.within_or("opening", 0, 1, lids.opening);
    lids.upper_margin_mm = o.get_or<double>("upper_margin_mm", lids.upper_margin_mm);
    lids.lower_margin_mm = o.get_or<double>("lower_margin_mm", lids.lower_margin_mm);
    lids.closing_line_mm = o.get_or<double>("closing_line_mm", lids.closing_line_mm);
    lids.half_width_mm = o.positive_or("half_width_mm", lids.half_width_mm);
    // Lid-gaze coupling: 0 holds a margin to the head, 1 turns it with the
    // eye; 2 is beyond any lid and bounds typing slips (20 for 0.2).
    lids.upper_gain_upgaze = o.within_or("upper_gain_upgaze", 0, 2, lids.upper_gain_upgaze);
    lids.upper_gain_downgaze = o.within_or("upper_gain_downgaze", 0, 2, lids.upper_gain_downgaze);
    lids.lower_gain_upgaze = o.within_or("lower_gain_upgaze", 0, 2, lids.lower_gain_upgaze);
    lids.lower_gain_downgaze = o.within_or("lower_gain_downgaze", 0, 2, lids.lower_gain_downgaze);
    check_lid_heights(o, lids);
    o.finish();
    a.eyelids = lids;
  }

  if (auto face_value = e.optional("face")) {
    if (!a.eyelids) face_value->fail("only used with eyelids (add \"eyelids\": {})");
    Object o(*face_value);
    Face face;
    if (auto side = o.optional("side")) {
      const std::string name = side->as_string();
      if (name != to_string(EyeSide::right) && name != to_string(EyeSide::left)) {
        side->fail("must be \"right\" or \"left\" (which eye of the face)");
      }
      face.side = name == to_string(EyeSide::right) ? EyeSide::right : EyeSide::left;
    }
    for (const FaceKey& key : kFaceKeys) {
      face.*key.member = o.within_or(std::string(key.name), key.low, key.high, face.*key.member);
    }
    if (auto lashes = o.optional("lashes")) face.lashes = read_hairs(*lashes, kLashKeys);
    if (auto brows = o.optional("brows")) face.brows = read_hairs(*brows, kBrowKeys);
    o.finish();
    a.face = face;
  }

  if (auto head_value = e.optional("head")) {
    // The head frame places nothing but the lids and skin.
    if (!a.eyelids) head_value->fail("only used with eyelids (add \"eyelids\": {})");
    Object head(*head_value);
    Vector3 forward = a.head_forward;
    Vector3 up = a.head_up;
    const auto forward_value = head.optional("forward");
    if (forward_value) forward = forward_value->direction();
    const auto up_value = head.optional("up");
    if (up_value) up = up_value->direction();
    const UnitVector3 f = unit_as_given(forward);
    if (cross(f, up / up.norm()).norm() < 1e-6) {
      if (up_value) up_value->fail("must not be parallel to head.forward");
      // The defaults are perpendicular: only a given forward meets the default up.
      forward_value.value().fail("is parallel to the default head.up [0, -1, 0]: give \"up\"");
    }
    head.finish();
    // As a camera's up: only the part across the forward direction counts,
    // so the renderer gets an orthonormal pair.
    a.head_forward = f;
    const double along = dot(up, f);
    a.head_up = std::abs(along) <= 8 * std::numeric_limits<double>::epsilon() ? unit_as_given(up)
                                                                               : UnitVector3::normalize(up - along * f);
  }
  return a;
}

Eye read_eye(Object& e) {
  EyeModel model = read_eye_model(e);

  Object position = e.object("position");
  const bool at_cornea_center = position.one_of("cornea_center_mm", "rotation_center_mm");
  const Value anchor = position.required(at_cornea_center ? "cornea_center_mm" : "rotation_center_mm");
  const Point3 anchor_point = anchor.as_point3();
  position.finish();

  Object orientation = e.object("orientation");
  std::optional<Eye> eye;
  if (auto target_value = orientation.optional("gaze_target_mm")) {
    for (const char* key : {"yaw_deg", "pitch_deg", "optical_axis"}) {
      if (orientation.has(key)) {
        orientation.required(key).fail("cannot be combined with gaze_target_mm");
      }
    }
    const Point3 target = target_value->as_point3();
    // Nobody fixates closer than a few centimetres, and a nearer target
    // could even lie inside the eye whatever way it turns.
    const double nearest = 2.0 * model.rotation_center_depth_mm;
    if (!(distance(target, anchor_point) > nearest)) {
      target_value->fail("is " + format_number(distance(target, anchor_point)) +
                         " mm from " + anchor.where().path +
                         ": must be more than 2 x rotation_center_depth_mm = " +
                         format_number(nearest) + " mm away");
    }
    try {
      eye = at_cornea_center ? Eye::fixating_from_cornea_center(model, anchor_point, target)
                             : Eye::fixating(model, anchor_point, target);
    } catch (const std::invalid_argument& error) {
      target_value->fail(error.what());
    }
  } else if (auto axis_value = orientation.optional("optical_axis")) {
    for (const char* key : {"yaw_deg", "pitch_deg"}) {
      if (orientation.has(key)) orientation.required(key).fail("cannot be combined with optical_axis");
    }
    const UnitVector3 axis = unit_as_given(axis_value->direction());
    eye = at_cornea_center ? Eye::with_cornea_center(model, anchor_point, axis)
                           : Eye::with_rotation_center(model, anchor_point, axis);
  } else {
    const double yaw = orientation.has("yaw_deg") ? orientation.required("yaw_deg").within(-180, 180) : 0.0;
    const double pitch =
        orientation.has("pitch_deg") ? orientation.required("pitch_deg").within(-89, 89) : 0.0;
    const UnitVector3 axis = optical_axis_from_yaw_pitch(yaw * kDegree, pitch * kDegree);
    eye = at_cornea_center ? Eye::with_cornea_center(model, anchor_point, axis)
                           : Eye::with_rotation_center(model, anchor_point, axis);
  }
  orientation.finish();
  // A saccade peaks at 500 to 900 deg/s; beyond 1000 no eye turns.
  if (auto motion = e.optional_object("motion")) {
    EyeMotion m;
    m.yaw_deg_s = motion->within_or("yaw_deg_s", -1000, 1000, 0);
    m.pitch_deg_s = motion->within_or("pitch_deg_s", -1000, 1000, 0);
    motion->finish();
    eye->set_motion(m);
  }
  eye->set_appearance(read_appearance(e));
  e.finish();
  return *eye;
}

// Why `p` lies inside `eye`, or nullopt. The eye is the sclera sphere
// united with the corneal cap; the whole sphere of the cornea's apical
// curvature is included too, to stay clear of surfaces near the limbus.
std::optional<std::string> inside_eye(const Eye& eye, const Point3& p) {
  const EyeModel& m = eye.model();
  if (distance(p, eye.rotation_center()) < m.sclera_radius_mm) return "inside the sclera sphere";
  if (distance(p, eye.cornea_center()) < m.anterior_cornea.radius_mm) return "inside the cornea";
  const Point3 q = eye.eye_from_world() * p;
  const double depth = m.anterior_cornea.radius_mm - q.z;
  const double r2 = q.x * q.x + q.y * q.y;
  const Conicoid& s = m.anterior_cornea;
  if (depth >= 0 && depth <= m.limbus_depth_mm() &&
      r2 + (1.0 + s.asphericity) * depth * depth - 2.0 * s.radius_mm * depth < 0) {
    return "inside the cornea";
  }
  return std::nullopt;
}

void check_outside_eyes(const Scene& scene, const Point3& p, const Location& where) {
  for (std::size_t i = 0; i < scene.eyes.size(); ++i) {
    if (auto why = inside_eye(scene.eyes[i], p)) {
      where.fail(format_point(p), "lies " + *why + " of eyes[" + std::to_string(i) + "]");
    }
  }
}

}  // namespace

namespace {

Scene read_scene(const std::string& text, const std::string& source_name, const std::filesystem::path& folder) {
  const json root_json = parse_json(text, source_name);
  Object root(Value(root_json, Location{&source_name, ""}));

  // The version first: a newer file is best rejected before its keys are.
  const Value format = root.required("format", "the scene format version, " +
                                                   std::to_string(kSceneFormatVersion));
  if (format.as_int() != kSceneFormatVersion) {
    format.fail("unsupported format version (this program reads " +
                std::to_string(kSceneFormatVersion) + ")");
  }

  Scene scene;
  scene.name = root.get_or<std::string>("name", std::filesystem::path(source_name).stem().string());

  std::set<std::string> names;
  auto check_unique = [&names](const std::string& name, Object& o) {
    if (!names.insert(name).second) {
      const auto v = o.optional("name");
      (v ? v->where() : o.where())
          .fail("\"" + name + "\"", "duplicate name (camera and illuminator names must be unique)");
    }
  };

  // Eyes first: cameras and lights are then checked against them.
  for (const Value& v : read_list(root, "eyes", true)) {
    Object e(v);
    scene.eyes.push_back(located(e.where(), [&] { return read_eye(e); }));
  }
  std::vector<Value> camera_values = read_list(root, "cameras", true);
  for (std::size_t i = 0; i < camera_values.size(); ++i) {
    Object c(camera_values[i]);
    scene.cameras.push_back(located(c.where(), [&] { return read_camera(c, i); }));
    check_unique(scene.cameras.back().name(), c);
    check_outside_eyes(scene, scene.cameras.back().center(), c.where().child("position_mm"));
  }
  std::vector<Value> light_values = read_list(root, "illuminators", false);
  for (std::size_t i = 0; i < light_values.size(); ++i) {
    Object l(light_values[i]);
    scene.illuminators.push_back(read_illuminator(l, i));
    check_unique(scene.illuminators.back().name, l);
    check_outside_eyes(scene, scene.illuminators.back().position, l.where().child("position_mm"));
  }
  if (auto screen = root.optional_object("screen")) scene.screen = read_screen(*screen);
  std::set<std::string> lens_names;
  std::vector<Value> lens_values = read_list(root, "spectacle_lenses", false);
  for (std::size_t i = 0; i < lens_values.size(); ++i) {
    Object o(lens_values[i]);
    scene.spectacle_lenses.push_back(read_spectacle_lens(o, i));
    if (!lens_names.insert(scene.spectacle_lenses.back().name).second) {
      const auto v = o.optional("name");
      (v ? v->where() : o.where())
          .fail("\"" + scene.spectacle_lenses.back().name + "\"", "duplicate name (lens names must be unique)");
    }
    try {
      check_spectacle_lens_placement(scene, static_cast<int>(i));
    } catch (const std::invalid_argument& e) {
      o.where().child("position_mm").fail("", e.what());
    }
  }
  // Meshes last: their files are read only once the rest of the scene is
  // known to be good.
  std::set<std::string> mesh_names;
  std::vector<Value> mesh_values = read_list(root, "meshes", false);
  for (std::size_t i = 0; i < mesh_values.size(); ++i) {
    Object m(mesh_values[i]);
    scene.meshes.push_back(read_mesh(m, i, folder));
    if (!mesh_names.insert(scene.meshes.back().name).second) {
      const auto v = m.optional("name");
      (v ? v->where() : m.where())
          .fail("\"" + scene.meshes.back().name + "\"", "duplicate name (mesh names must be unique)");
    }
  }
  root.finish();
  return scene;
}

}  // namespace

namespace {

using ordered_json = nlohmann::ordered_json;

ordered_json triple(double x, double y, double z) { return ordered_json::array({x, y, z}); }
ordered_json point(const Point3& p) { return triple(p.x, p.y, p.z); }
ordered_json direction(const UnitVector3& v) { return triple(v.x(), v.y(), v.z()); }

ordered_json sensor_json(const Sensor& s) {
  ordered_json o;
  o["pixel_pitch_mm"] = s.pixel_pitch_mm;
  o["f_number"] = s.f_number;
  o["exposure_s"] = s.exposure_s;
  o["quantum_efficiency"] = s.quantum_efficiency;
  o["full_well_e"] = s.full_well_e;
  o["read_noise_e"] = s.read_noise_e;
  o["gain"] = s.gain;
  o["bits"] = s.bits;
  o["psf_sigma_px"] = s.psf_sigma_px;
  if (s.focus_distance_mm) o["focus_distance_mm"] = *s.focus_distance_mm;
  o["noise"] = s.noise;
  // The realism keys only when set: scenes without them write as before.
  if (s.corner_illumination != 1) o["corner_illumination"] = s.corner_illumination;
  if (s.hot_pixel_fraction > 0) {
    o["hot_pixel_fraction"] = s.hot_pixel_fraction;
    o["hot_pixel_e_per_s"] = s.hot_pixel_e_per_s;
    o["hot_pixel_seed"] = s.hot_pixel_seed;
  }
  if (s.jpeg_quality) o["jpeg_quality"] = *s.jpeg_quality;
  return o;
}

template <class Hairs, std::size_t N>
ordered_json hairs_json(const Hairs& hairs, const std::array<HairKey<Hairs>, N>& keys) {
  ordered_json o;
  for (const HairKey<Hairs>& key : keys) o[std::string(key.name)] = hairs.*key.member;
  o["seed"] = hairs.seed;
  return o;
}

ordered_json camera_json(const Camera& c) {
  const Intrinsics& k = c.intrinsics();
  const Distortion& d = c.distortion();
  const Rotation& r = c.world_from_camera().rotation();
  ordered_json o;
  o["name"] = c.name();
  o["resolution_px"] = {k.width, k.height};
  o["intrinsics_px"] = {{"fx", k.fx}, {"fy", k.fy}, {"cx", k.cx}, {"cy", k.cy}};
  o["distortion"] = {{"k1", d.k1}, {"k2", d.k2}, {"p1", d.p1}, {"p2", d.p2}, {"k3", d.k3}};
  o["position_mm"] = point(c.center());
  o["rotation_matrix"] = ordered_json::array();
  for (int row = 0; row < 3; ++row) o["rotation_matrix"].push_back(triple(r(row, 0), r(row, 1), r(row, 2)));
  o["sensor"] = sensor_json(c.sensor());
  return o;
}

ordered_json eye_json(const Eye& eye, std::size_t index) {
  const EyeModel& m = eye.model();
  const std::string where = "eyes[" + std::to_string(index) + "]";
  if (!eye_model_preset(m.name)) {
    throw std::invalid_argument(where + ": model \"" + m.name +
                                "\" is no preset, and a scene file starts every eye from one (" +
                                join(eye_model_preset_names()) + ")");
  }
  // The format orients an eye by its optical axis alone (eye.h's frame).
  const Rotation& r = eye.world_from_eye().rotation();
  const Rotation expected = world_from_eye_rotation(eye.optical_axis());
  for (int i = 0; i < 9; ++i) {
    if (std::abs(r(i / 3, i % 3) - expected(i / 3, i % 3)) > 1e-12) {
      throw std::invalid_argument(where + ": turned about its optical axis, which a scene file cannot express");
    }
  }
  ordered_json o;
  o["model"] = m.name;
  o["cornea"] = {{"radius_mm", m.anterior_cornea.radius_mm},
                 {"asphericity", m.anterior_cornea.asphericity},
                 {"limbus_radius_mm", m.limbus_radius_mm}};
  if (m.posterior_cornea) {
    const PosteriorCornea& p = *m.posterior_cornea;
    o["posterior_cornea"] = {{"radius_mm", p.surface.radius_mm},
                             {"asphericity", p.surface.asphericity},
                             {"thickness_mm", p.thickness_mm},
                             {"index", p.cornea_index}};
  } else {
    o["posterior_cornea"] = "none";
  }
  o["aqueous_index"] = m.aqueous_index;
  o["iris"] = {{"depth_mm", m.iris_depth_mm}, {"radius_mm", m.iris_radius_mm}};
  o["pupil"] = {{"radius_mm", m.pupil_radius_mm},
                {"decentration_mm", {m.pupil_decentration_x_mm, m.pupil_decentration_y_mm}}};
  o["rotation_center_depth_mm"] = m.rotation_center_depth_mm;
  o["sclera_radius_mm"] = m.sclera_radius_mm;
  // Radians read from degrees (d * pi/180) come back exactly from the
  // quotient; radians set in code may lie between two such products and
  // come back within an ulp.
  o["kappa_deg"] = {{"horizontal", m.kappa_horizontal_rad / kDegree}, {"vertical", m.kappa_vertical_rad / kDegree}};
  o["position"] = {{"cornea_center_mm", point(eye.cornea_center())}};
  o["orientation"] = {{"optical_axis", direction(eye.optical_axis())}};
  if (!eye.motion().still()) o["motion"] = {{"yaw_deg_s", eye.motion().yaw_deg_s}, {"pitch_deg_s", eye.motion().pitch_deg_s}};
  const EyeAppearance& a = eye.appearance();
  o["appearance"] = {{"iris_albedo", a.iris_albedo},
                     {"iris_texture_contrast", a.iris_texture_contrast},
                     {"iris_seed", a.iris_seed},
                     {"sclera_albedo", a.sclera_albedo},
                     {"skin_albedo", a.skin_albedo},
                     {"fundus_reflectance", a.fundus_reflectance}};
  // The textures only when on (every older scene's dump keeps its bytes).
  if (a.iris_furrow_contrast != 0) o["appearance"]["iris_furrow_contrast"] = a.iris_furrow_contrast;
  if (a.iris_freckles != 0) o["appearance"]["iris_freckles"] = a.iris_freckles;
  if (a.skin_texture_contrast != 0) o["appearance"]["skin_texture_contrast"] = a.skin_texture_contrast;
  if (a.sclera_vessel_contrast != 0) o["appearance"]["sclera_vessel_contrast"] = a.sclera_vessel_contrast;
  if (a.tear_film) {
    o["appearance"]["tear_film"] = {{"sclera_roughness_deg", a.tear_film->sclera_roughness_deg},
                                    {"meniscus_radius_mm", a.tear_film->meniscus_radius_mm},
                                    {"upper_meniscus_radius_mm", a.tear_film->upper_meniscus_radius_mm}};
  }
  // Without lids the head frame places nothing, and the format has none.
  if (a.eyelids) {
    const Eyelids& l = *a.eyelids;
    o["eyelids"] = {{"opening", l.opening},
                    {"upper_margin_mm", l.upper_margin_mm},
                    {"lower_margin_mm", l.lower_margin_mm},
                    {"closing_line_mm", l.closing_line_mm},
                    {"half_width_mm", l.half_width_mm},
                    {"upper_gain_upgaze", l.upper_gain_upgaze},
                    {"upper_gain_downgaze", l.upper_gain_downgaze},
                    {"lower_gain_upgaze", l.lower_gain_upgaze},
                    {"lower_gain_downgaze", l.lower_gain_downgaze}};
    if (a.face) {
      const Face& f = *a.face;
      ordered_json face = {{"side", to_string(f.side)}};
      for (const FaceKey& key : kFaceKeys) face[std::string(key.name)] = f.*key.member;
      if (f.lashes) face["lashes"] = hairs_json(*f.lashes, kLashKeys);
      if (f.brows) face["brows"] = hairs_json(*f.brows, kBrowKeys);
      o["face"] = face;
    }
    o["head"] = {{"forward", direction(a.head_forward)}, {"up", direction(a.head_up)}};
  }
  return o;
}

ordered_json mesh_json(const Mesh& mesh) {
  ordered_json o;
  o["name"] = mesh.name;
  o["albedo"] = mesh.albedo;
  ordered_json& vertices = o["vertices_mm"] = ordered_json::array();
  for (const Point3& p : mesh.vertices) vertices.push_back(point(p));
  ordered_json& triangles = o["triangles"] = ordered_json::array();
  for (const Triangle& t : mesh.triangles) triangles.push_back({t[0], t[1], t[2]});
  return o;
}

}  // namespace

std::string scene_to_json(const Scene& scene) {
  ordered_json root;
  root["format"] = kSceneFormatVersion;
  root["name"] = scene.name;
  root["cameras"] = ordered_json::array();
  for (const Camera& c : scene.cameras) root["cameras"].push_back(camera_json(c));
  root["illuminators"] = ordered_json::array();
  for (const Illuminator& l : scene.illuminators) {
    root["illuminators"].push_back({{"name", l.name},
                                    {"position_mm", point(l.position)},
                                    {"radiant_intensity_w_sr", l.radiant_intensity_w_sr},
                                    {"wavelength_nm", l.wavelength_nm},
                                    {"emitter_diameter_mm", l.emitter_diameter_mm}});
  }
  root["eyes"] = ordered_json::array();
  for (std::size_t i = 0; i < scene.eyes.size(); ++i) root["eyes"].push_back(eye_json(scene.eyes[i], i));
  root["meshes"] = ordered_json::array();
  for (const Mesh& m : scene.meshes) root["meshes"].push_back(mesh_json(m));
  if (!scene.spectacle_lenses.empty()) {
    root["spectacle_lenses"] = ordered_json::array();
    for (const SpectacleLens& lens : scene.spectacle_lenses) {
      const Rotation& r = lens.world_from_lens.rotation();
      ordered_json o;
      o["name"] = lens.name;
      o["position_mm"] = point(Point3::origin() + lens.world_from_lens.translation());
      o["rotation_matrix"] = ordered_json::array();
      for (int row = 0; row < 3; ++row) o["rotation_matrix"].push_back(triple(r(row, 0), r(row, 1), r(row, 2)));
      o["front_radius_mm"] = lens.front_radius_mm;
      o["back_radius_mm"] = lens.back_radius_mm;
      o["center_thickness_mm"] = lens.center_thickness_mm;
      o["refractive_index"] = lens.refractive_index;
      o["outline_semi_axes_mm"] = {lens.outline_semi_axes_mm[0], lens.outline_semi_axes_mm[1]};
      root["spectacle_lenses"].push_back(o);
    }
  }
  if (scene.screen) {
    const Screen& s = *scene.screen;
    root["screen"] = {{"top_left_mm", point(s.top_left)},
                      {"size_mm", {s.width_mm, s.height_mm}},
                      {"right", direction(s.right)},
                      {"down", direction(s.down)}};
  }
  return root.dump(2) + "\n";
}

Scene parse_scene(const std::string& text, const std::string& source_name, const std::filesystem::path& folder) {
  try {
    return read_scene(text, source_name, folder);
  } catch (const JsonFileError& error) {
    throw SceneError(error.what());
  }
}

Scene load_scene(const std::filesystem::path& file) {
  std::string text;
  try {
    text = read_input_file(file, kMaxSceneFileBytes, "a scene file");
  } catch (const InputFileError& e) {
    throw SceneError(file.string() + ": cannot read: " + e.reason());
  }
  return parse_scene(text, file.string(), file.parent_path());
}

}  // namespace purkinje
