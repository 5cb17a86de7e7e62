// Dataset specs: reading (json_reader.h, the scene reader's rules and
// messages), counter-based draws and the scene each image's draws make.
// Every key is documented in docs/dataset-format.md.

#include "purkinje/models/dataset_spec.h"

#include <cmath>
#include <initializer_list>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <unordered_map>

#include "json_reader.h"
#include "purkinje/models/counter_random.h"
#include "purkinje/models/input_file.h"
#include "purkinje/models/scene_file.h"

namespace purkinje {
namespace {

using namespace json_reader;

constexpr double kDegree = std::numbers::pi / 180.0;
// Integers above 2^53 are not exact in many JSON readers (scene_file.cpp).
constexpr double kMaxExactInteger = 9007199254740991.0;
constexpr std::uint64_t kMaxCount = std::uint64_t{1} << 40;

// What a parameter may take: [low, high] (low excluded when low_open), or
// one of `allowed` when it is not empty.
struct ParameterRule {
  ParameterRule(std::string name, ParameterType type, double low = 0, double high = 0, bool low_open = false,
                std::vector<double> allowed = {})
      : name(std::move(name)), type(type), low(low), high(high), low_open(low_open), allowed(std::move(allowed)) {}

  std::string name;
  ParameterType type;
  double low, high;
  bool low_open;
  std::vector<double> allowed;

  std::string range_text() const {
    if (type == ParameterType::boolean) return "true or false";
    if (!allowed.empty()) {
      std::string text = "one of ";
      for (std::size_t i = 0; i < allowed.size(); ++i) text += (i ? ", " : "") + format_number(allowed[i]);
      return text;
    }
    return std::string(low_open ? "(" : "[") + format_number(low) + ", " + format_number(high) + "]";
  }
  bool admits(double v) const {
    if (type == ParameterType::boolean) return v == 0 || v == 1;
    if (!allowed.empty()) return std::find(allowed.begin(), allowed.end(), v) != allowed.end();
    return (low_open ? v > low : v >= low) && v <= high;
  }
};

std::vector<ParameterRule> concatenated(std::initializer_list<std::vector<ParameterRule>> parts) {
  std::vector<ParameterRule> all;
  for (const std::vector<ParameterRule>& part : parts) all.insert(all.end(), part.begin(), part.end());
  return all;
}

// The parameters every scene has, in the table's column order.
const std::vector<ParameterRule>& scene_rules() {
  using T = ParameterType;
  // The face's keys but those the other eye's face shares (its midline):
  // a data set varies the first eye.
  const auto face_rules = [] {
    std::vector<ParameterRule> face;
    for (const FaceKey& key : kFaceKeys) {
      if (!key.shared) face.push_back({std::string(key.name), T::real, key.low, key.high});
    }
    return face;
  };
  // A face's lashes ("lash_...") or brows ("brows_...": "brow_" begins a face key).
  const auto hair_rules = [](const std::string& prefix, const auto& keys) {
    std::vector<ParameterRule> hairs;
    for (const auto& key : keys) hairs.push_back({prefix + std::string(key.name), T::real, key.low, key.high});
    hairs.push_back({prefix + "seed", T::integer, 0, kMaxExactInteger});
    return hairs;
  };
  static const std::vector<ParameterRule> rules = concatenated({std::vector<ParameterRule>{
      {"gaze_turn_deg", T::real, 0, 90},
      {"gaze_direction_deg", T::real, -360, 360},
      {"screen_x_mm", T::real, 0, 1e6},  // and within the screen (checked with the scene)
      {"screen_y_mm", T::real, 0, 1e6},
      {"pupil_radius_mm", T::real, 0, 10, true},
      {"eye_offset_x_mm", T::real, -1000, 1000},
      {"eye_offset_y_mm", T::real, -1000, 1000},
      {"eye_offset_z_mm", T::real, -1000, 1000},
      {"head_yaw_deg", T::real, -90, 90},
      {"head_pitch_deg", T::real, -90, 90},
      {"head_roll_deg", T::real, -90, 90},
      {"gaze_speed_deg_s", T::real, 0, 1000},
      {"gaze_speed_direction_deg", T::real, -360, 360},
      {"lid_opening", T::real, 0, 1},
      {"blink", T::boolean}},
      face_rules(), hair_rules("lash_", kLashKeys), hair_rules("brows_", kBrowKeys), std::vector<ParameterRule>{
      {"iris_seed", T::integer, 0, kMaxExactInteger},
      {"iris_furrow_contrast", T::real, 0, 1},
      {"iris_freckles", T::integer, 0, 20},
      {"iris_texture_contrast", T::real, 0, 1},
      {"iris_albedo", T::real, 0, 1},
      {"sclera_albedo", T::real, 0, 1},
      {"skin_albedo", T::real, 0, 1},
      {"fundus_reflectance", T::real, 0, 1},
      {"sclera_roughness_deg", T::real, 0, 10},
      {"meniscus_radius_mm", T::real, 0, 1},
      {"upper_meniscus_radius_mm", T::real, 0, 1},
      {"skin_texture_contrast", T::real, 0, 1},
      {"sclera_vessel_contrast", T::real, 0, 1},
      {"cornea_radius_mm", T::real, 0, 100, true},
      {"cornea_asphericity", T::real, -1, 10},
      {"posterior_cornea", T::boolean},
      {"kappa_horizontal_deg", T::real, -45, 45},
      {"kappa_vertical_deg", T::real, -45, 45},
      {"rotation_center_depth_mm", T::real, 0, 100, true},
      {"led_power_scale", T::real, 0, 1e6},
      {"exposure_s", T::real, 0, 10, true},
      {"gain", T::real, 0, 1e6, true},
      {"read_noise_e", T::real, 0, 1e6},
      {"noise", T::boolean},
      {"focus_distance_mm", T::real, 0, 1e6, true},
      {"bits", T::integer, 0, 0, false, {8, 10, 12, 16}},
      {"corner_illumination", T::real, 0, 1, true},
      {"hot_pixel_fraction", T::real, 0, 0.01},
      {"jpeg_quality", T::integer, 1, 100}}});
  return rules;
}

const char* const kExrCodecs[] = {"none", "rle", "zips", "zip", "piz", "pxr24", "b44", "b44a", "dwaa", "dwab"};

// A parameter's value as written: true/false for booleans, an integer for
// integers, a finite number for reals; then its rule.
double read_value(const Value& v, const ParameterRule& rule) {
  double x = 0;
  if (rule.type == ParameterType::boolean) {
    x = v.as_bool() ? 1 : 0;
  } else {
    x = v.as_double();
    if (rule.type == ParameterType::integer && x != std::floor(x)) v.fail("must be an integer (" + rule.name + ")");
  }
  if (!rule.admits(x)) v.fail("must be " + std::string(rule.allowed.empty() ? "in " : "") + rule.range_text() + " (" + rule.name + ")");
  return x;
}

std::vector<double> read_values(const Value& v, const ParameterRule& rule) {
  std::vector<double> out;
  for (const Value& e : v.elements()) out.push_back(read_value(e, rule));
  if (out.empty()) v.fail("must list at least one value");
  return out;
}

// [low, high] of a uniform or a truncation, each end within the rule.
std::pair<double, double> read_interval(const Value& v, const ParameterRule& rule) {
  const std::vector<Value> ends = v.elements();
  if (ends.size() != 2) v.fail("must be [low, high]");
  const double low = read_value(ends[0], rule), high = read_value(ends[1], rule);
  if (!(low <= high)) v.fail("the low end must not exceed the high one");
  return {low, high};
}

Distribution read_distribution(const Value& v, const ParameterRule& rule) {
  Distribution d;
  if (!v.raw().is_object()) {
    d.values = {read_value(v, rule)};
    return d;
  }
  Object o(v);
  const bool boolean = rule.type == ParameterType::boolean;
  const bool discrete = boolean || !rule.allowed.empty();
  int kinds = 0;
  for (const char* kind : {"fixed", "uniform", "normal", "choice", "grid"}) kinds += v.raw().contains(kind) ? 1 : 0;
  if (kinds != 1) o.where().fail(format_value(v.raw()), "give exactly one of fixed, uniform, normal, choice, grid");
  if (v.raw().contains("weights") && !v.raw().contains("choice")) {
    o.where().child("weights").fail("", "weights go with choice only");
  }
  if (auto f = o.optional("fixed")) {
    d.values = {read_value(*f, rule)};
  } else if (auto u = o.optional("uniform")) {
    if (discrete) u->fail("draw " + rule.name + " with choice: it takes " + rule.range_text());
    d.kind = Distribution::Kind::uniform;
    std::tie(d.low, d.high) = read_interval(*u, rule);
  } else if (auto n = o.optional("normal")) {
    if (discrete || rule.type == ParameterType::integer) {
      n->fail("a normal draws real numbers; " + rule.name + " takes " +
              (discrete ? rule.range_text() : std::string("integers")));
    }
    d.kind = Distribution::Kind::normal;
    Object normal(*n);
    d.mean = read_value(normal.required("mean"), rule);
    d.sd = normal.required("sd").positive();
    d.low = normal.has("min") ? read_value(*normal.optional("min"), rule) : rule.low;
    d.high = normal.has("max") ? read_value(*normal.optional("max"), rule) : rule.high;
    if (!(d.low < d.high)) normal.where().fail("", "min must be below max");
    if (rule.low_open && d.low <= rule.low) {
      normal.where().child("min").fail("", "required: " + rule.name + " must stay above " + format_number(rule.low));
    }
    normal.finish();
  } else if (auto c = o.optional("choice")) {
    d.kind = Distribution::Kind::choice;
    d.values = read_values(*c, rule);
    if (auto w = o.optional("weights")) {
      for (const Value& e : w->elements()) d.weights.push_back(e.non_negative());
      if (d.weights.size() != d.values.size()) {
        w->fail("must give one weight per choice (" + std::to_string(d.values.size()) + ")");
      }
      double total = 0;
      for (double x : d.weights) total += x;
      if (!(total > 0)) w->fail("must not all be 0");
      // An infinite sum would draw the last choice whatever its weight.
      if (!std::isfinite(total)) w->fail("must have a finite sum");
    }
  } else if (auto g = o.optional("grid")) {
    d.kind = Distribution::Kind::grid;
    if (g->raw().is_array()) {
      d.values = read_values(*g, rule);
    } else {
      if (discrete) g->fail("list the values of " + rule.name + ": it takes " + rule.range_text());
      Object range(*g);
      const double from = read_value(range.required("from"), rule), to = read_value(range.required("to"), rule);
      const int steps = range.required("steps").as_int();
      if (steps < 1 || steps > 1000000) range.where().child("steps").fail(std::to_string(steps), "must be in [1, 1000000]");
      for (int i = 0; i < steps; ++i) {
        // lerp: exact at both ends and monotone (from + (to - from) * i / n
        // overshot `to` in the last bit, past a parameter's range).
        double x = steps == 1 ? from : std::lerp(from, to, static_cast<double>(i) / (steps - 1));
        x = std::clamp(x, std::min(from, to), std::max(from, to));
        if (rule.type == ParameterType::integer) x = std::round(x);
        d.values.push_back(x);
      }
      range.finish();
    }
  }
  o.finish();
  return d;
}

// ---------------------------------------------------------------- reading

struct Reader {
  const std::string& source;
  std::filesystem::path folder;
  std::string text;

  DatasetSpec read() {
    const json root_json = parse_json(text, source);
    Object root(Value(root_json, Location{&source, ""}));
    const Value format = root.required("dataset_format", "the dataset format version, " +
                                                             std::to_string(kDatasetFormatVersion));
    if (format.as_int() != kDatasetFormatVersion) {
      format.fail("unsupported dataset format version (this program reads " +
                  std::to_string(kDatasetFormatVersion) + ")");
    }
    DatasetSpec spec;
    spec.text = text;
    spec.name = root.get_or<std::string>("name", std::filesystem::path(source).stem().string());
    if (spec.name.empty()) root.required("name").fail("must not be empty");
    const Value scene = root.required("scene", "the base scene file, relative to this file");
    spec.scene_file = folder / scene.as_string();
    try {
      spec.scene_text = read_input_file(spec.scene_file, kMaxSceneFileBytes, "a scene file");
      spec.scene = parse_scene(spec.scene_text, spec.scene_file.string(), spec.scene_file.parent_path());
    } catch (const InputFileError& error) {
      scene.fail(spec.scene_file.string() + ": cannot read: " + error.reason());
    } catch (const SceneError& error) {
      scene.fail(error.what());
    }
    spec.source = source;
    // Names go into file names and one-line CSV records: a line break in
    // one would split a record.
    const auto check_name = [&](const std::string& kind, const std::string& name) {
      if (name.find_first_of("\r\n") != std::string::npos) {
        scene.fail(kind + " \"" + name + "\" holds a line break: rename it for a data set's table");
      }
    };
    for (const Camera& c : spec.scene.cameras) check_name("camera", c.name());
    for (const Illuminator& l : spec.scene.illuminators) check_name("illuminator", l.name);
    for (const Mesh& m : spec.scene.meshes) check_name("mesh", m.name);
    for (const SpectacleLens& l : spec.scene.spectacle_lenses) check_name("spectacle lens", l.name);
    const Value count = root.required("count", "how many images");
    spec.count = count.as_exact_count();
    if (spec.count < 1 || spec.count > kMaxCount) count.fail("must be in [1, 2^40]");
    if (auto seed = root.optional("seed")) spec.seed = seed->as_exact_count();
    if (auto camera = root.optional("camera")) {
      spec.camera = camera->as_string();
      bool found = false;
      std::vector<std::string> names;
      for (const Camera& c : spec.scene.cameras) {
        found = found || c.name() == spec.camera;
        names.push_back(c.name());
      }
      if (!found) camera->fail("the scene has no such camera (it has " + join(names) + ")");
    }
    if (auto render = root.optional_object("render")) {
      if (auto s = render->optional("samples_per_pixel")) {
        spec.samples_per_pixel = s->as_int();
        if (spec.samples_per_pixel < 1 || spec.samples_per_pixel > (1 << 20)) s->fail("must be in [1, 1048576]");
      }
      if (auto s = render->optional("edge_samples_per_pixel")) {
        spec.edge_samples_per_pixel = s->as_int();
        if (spec.edge_samples_per_pixel < 0 || spec.edge_samples_per_pixel > (1 << 20)) {
          s->fail("must be in [0, 1048576]");
        }
      }
      render->finish();
    }
    if (auto outputs = root.optional_object("outputs")) read_outputs(*outputs, spec.outputs);
    read_parameters(root, spec);
    root.finish();
    return spec;
  }

  void read_outputs(Object& o, DatasetOutputs& out) {
    out.image = o.get_or<bool>("image", out.image);
    out.segmentation = o.get_or<bool>("segmentation", out.segmentation);
    if (auto exr = o.optional("exr")) {
      if (exr->raw().is_boolean()) {
        out.exr = exr->as_bool();
      } else {
        Object e(*exr);
        out.exr = true;
        if (auto planes = e.optional("planes")) {
          for (const Value& p : planes->elements()) {
            const std::string name = p.as_string();
            if (name.empty()) p.fail("must not be empty");
            if (std::find(out.exr_planes.begin(), out.exr_planes.end(), name) != out.exr_planes.end()) {
              p.fail("is listed twice");
            }
            out.exr_planes.push_back(name);
          }
          if (out.exr_planes.empty()) planes->fail("must list at least one plane (or leave planes out: all)");
        }
        out.exr_half = e.get_or<bool>("half", out.exr_half);
        if (auto codec = e.optional("compression")) {
          out.exr_compression = codec->as_string();
          if (std::find(std::begin(kExrCodecs), std::end(kExrCodecs), out.exr_compression) == std::end(kExrCodecs)) {
            std::vector<std::string> names(std::begin(kExrCodecs), std::end(kExrCodecs));
            codec->fail("unknown OpenEXR compression (valid: " + join(names) + ")");
          }
        }
        e.finish();
      }
    }
    o.finish();
    if (!out.image && !out.segmentation && !out.exr) {
      o.where().fail("", "writes no image: turn on image, segmentation or exr");
    }
  }

  void add(DatasetSpec& spec, const ParameterRule& rule, Distribution d) {
    spec.parameters.push_back({rule.name, rule.type, std::move(d)});
  }

  void read_parameters(Object& root, DatasetSpec& spec) {
    const Scene& scene = spec.scene;
    std::map<std::string, Distribution> drawn;
    std::map<std::string, Location> where;
    // Gaze in a cone or on the screen, as a shorthand.
    if (auto gaze = root.optional_object("gaze")) {
      if (gaze->one_of("cone_deg", "screen")) {
        const Value cone = gaze->required("cone_deg");
        const double max = cone.within(0, 90);
        Distribution turn;
        turn.kind = Distribution::Kind::cap;
        turn.high = max;
        Distribution direction;
        direction.kind = Distribution::Kind::uniform;
        direction.high = 360;
        drawn["gaze_turn_deg"] = turn;
        drawn["gaze_direction_deg"] = direction;
        where.emplace("gaze_turn_deg", cone.where());
        where.emplace("gaze_direction_deg", cone.where());
      } else {
        const Value screen_value = gaze->required("screen");
        if (!scene.screen) screen_value.fail("the scene has no screen (scene-format.md: screen)");
        Distribution x, y;
        if (screen_value.raw().is_string()) {
          if (screen_value.as_string() != "uniform") screen_value.fail("must be \"uniform\" or {\"grid\": [columns, rows]}");
          x.kind = y.kind = Distribution::Kind::uniform;
          x.high = scene.screen->width_mm;
          y.high = scene.screen->height_mm;
        } else {
          Object s(screen_value);
          const Value grid = s.required("grid", "[columns, rows] of targets");
          const std::vector<Value> size = grid.elements();
          if (size.size() != 2) grid.fail("must be [columns, rows]");
          const int columns = size[0].as_int(), rows = size[1].as_int();
          if (columns < 1 || rows < 1 || columns > 1000 || rows > 1000) grid.fail("columns and rows must be in [1, 1000]");
          s.finish();
          x.kind = y.kind = Distribution::Kind::grid;
          for (int c = 0; c < columns; ++c) x.values.push_back(scene.screen->width_mm * (c + 0.5) / columns);
          for (int r = 0; r < rows; ++r) y.values.push_back(scene.screen->height_mm * (r + 0.5) / rows);
        }
        drawn["screen_x_mm"] = x;
        drawn["screen_y_mm"] = y;
        where.emplace("screen_x_mm", screen_value.where());
        where.emplace("screen_y_mm", screen_value.where());
      }
      gaze->finish();
    }
    std::vector<ParameterRule> scene_specific;
    if (auto parameters = root.optional_object("parameters")) {
      for (const ParameterRule& rule : scene_rules()) {
        auto v = parameters->optional(rule.name);
        if (!v) continue;
        if (drawn.count(rule.name)) v->fail("given by gaze too: give it once");
        drawn[rule.name] = read_distribution(*v, rule);
        where.emplace(rule.name, v->where());
      }
      if (auto lights = parameters->optional_object("illuminators")) {
        for (const Illuminator& l : scene.illuminators) {
          auto o = lights->optional_object(l.name);
          if (!o) continue;
          for (const auto& [key, rule] : {std::pair{"on", ParameterRule{"", ParameterType::boolean}},
                                          std::pair{"power_scale", ParameterRule{"", ParameterType::real, 0, 1e6}}}) {
            ParameterRule named = rule;
            named.name = "illuminator." + l.name + "." + key;
            if (auto v = o->optional(key)) {
              drawn[named.name] = read_distribution(*v, named);
              where.emplace(named.name, v->where());
              scene_specific.push_back(named);
            }
          }
          o->finish();
        }
        lights->finish();
      }
      if (auto meshes = parameters->optional_object("meshes")) {
        for (const Mesh& m : scene.meshes) {
          auto o = meshes->optional_object(m.name);
          if (!o) continue;
          ParameterRule on{"mesh." + m.name + ".on", ParameterType::boolean};
          if (auto v = o->optional("on")) {
            drawn[on.name] = read_distribution(*v, on);
            where.emplace(on.name, v->where());
            scene_specific.push_back(on);
          }
          o->finish();
        }
        meshes->finish();
      }
      if (auto lenses = parameters->optional_object("spectacle_lenses")) {
        for (const SpectacleLens& lens : scene.spectacle_lenses) {
          auto o = lenses->optional_object(lens.name);
          if (!o) continue;
          ParameterRule on{"spectacle_lens." + lens.name + ".on", ParameterType::boolean};
          if (auto v = o->optional("on")) {
            drawn[on.name] = read_distribution(*v, on);
            where.emplace(on.name, v->where());
            scene_specific.push_back(on);
          }
          o->finish();
        }
        lenses->finish();
      }
      parameters->finish();
    }
    // Rules between parameters and the scene.
    const auto given = [&](const char* name) { return drawn.count(name) > 0; };
    if ((given("screen_x_mm") || given("screen_y_mm")) && (given("gaze_turn_deg") || given("gaze_direction_deg"))) {
      where.at(given("screen_x_mm") ? "screen_x_mm" : "screen_y_mm")
          .fail("", "gaze is given by a turn and by a screen target: give one");
    }
    if (given("gaze_speed_direction_deg") && !given("gaze_speed_deg_s")) {
      where.at("gaze_speed_direction_deg").fail("", "a direction without gaze_speed_deg_s: give the speed too");
    }
    for (const char* axis : {"screen_x_mm", "screen_y_mm"}) {
      if (!given(axis)) continue;
      if (!scene.screen) where.at(axis).fail("", "the scene has no screen (scene-format.md: screen)");
      const double size = std::string(axis) == "screen_x_mm" ? scene.screen->width_mm : scene.screen->height_mm;
      const Distribution& d = drawn.at(axis);
      const double low = d.values.empty() ? d.low : *std::min_element(d.values.begin(), d.values.end());
      const double high = d.values.empty() ? d.high : *std::max_element(d.values.begin(), d.values.end());
      if (low < 0 || high > size) {
        where.at(axis).fail("", "reaches " + format_number(low < 0 ? low : high) + ": must stay on the screen, [0, " +
                                    format_number(size) + "] mm from its top-left corner");
      }
    }
    const bool lids = scene.eyes.front().appearance().eyelids.has_value();
    for (const char* name : {"lid_opening", "blink", "skin_albedo", "skin_texture_contrast"}) {
      if (given(name) && !lids) where.at(name).fail("", "the scene's first eye has no eyelids (scene-format.md: eyelids)");
    }
    for (const char* name : {"sclera_roughness_deg", "meniscus_radius_mm", "upper_meniscus_radius_mm"}) {
      if (given(name) && !scene.eyes.front().appearance().tear_film) {
        where.at(name).fail("", "the scene's first eye has no tear film (scene-format.md: tear film)");
      }
    }
    const bool face = scene.eyes.front().appearance().face.has_value();
    for (const FaceKey& key : kFaceKeys) {
      const std::string name(key.name);
      if (given(name.c_str()) && !face) where.at(name).fail("", "the scene's first eye has no face (scene-format.md: face)");
    }
    const bool lashes = face && scene.eyes.front().appearance().face->lashes.has_value();
    const bool brows = face && scene.eyes.front().appearance().face->brows.has_value();
    for (const ParameterRule& rule : scene_rules()) {
      if (rule.name.starts_with("lash_") && given(rule.name.c_str()) && !lashes) {
        where.at(rule.name).fail("", "the scene's first eye has no lashes (scene-format.md: lashes)");
      }
      if (rule.name.starts_with("brows_") && given(rule.name.c_str()) && !brows) {
        where.at(rule.name).fail("", "the scene's first eye has no brows (scene-format.md: brows)");
      }
    }
    // JPEG holds 8 bits: no set may draw a JPEG quality and a deeper image
    // for one camera (the scene file's rule).
    const auto may_be_deep = [&](const Camera& camera) {
      if (!given("bits")) return camera.sensor().bits != 8;
      const Distribution& d = drawn.at("bits");
      const std::vector<double> bits = d.values.empty() ? std::vector<double>{d.low, d.high} : d.values;
      return std::any_of(bits.begin(), bits.end(), [](double b) { return b != 8; });
    };
    for (const Camera& camera : scene.cameras) {
      if (!spec.camera.empty() && camera.name() != spec.camera) continue;
      if ((given("jpeg_quality") || camera.sensor().jpeg_quality) && may_be_deep(camera)) {
        where.at(given("jpeg_quality") ? "jpeg_quality" : "bits")
            .fail("", "camera '" + camera.name() + "' would get a JPEG of more than 8 bits: JPEG holds 8 bits");
      }
    }
    // A focus no nearer than the lens: the scene file's rule, for every
    // camera the set renders.
    if (given("focus_distance_mm")) {
      const Distribution& d = drawn.at("focus_distance_mm");
      const double nearest = d.values.empty() ? d.low : *std::min_element(d.values.begin(), d.values.end());
      for (const Camera& camera : scene.cameras) {
        if (!spec.camera.empty() && camera.name() != spec.camera) continue;
        const double focal_length = camera.focal_length_mm();
        if (!(nearest > focal_length)) {
          where.at("focus_distance_mm")
              .fail("", "reaches " + format_number(nearest) + " mm: must stay beyond camera '" + camera.name() +
                            "''s focal length, " + format_number(focal_length) + " mm");
        }
      }
    }
    for (const ParameterRule& rule : scene_rules()) {
      if (given(rule.name.c_str())) add(spec, rule, drawn.at(rule.name));
    }
    for (const ParameterRule& rule : scene_specific) add(spec, rule, drawn.at(rule.name));
  }
};

// ---------------------------------------------------------------- drawing

// 64-bit FNV-1a: a parameter's stream from its name, so adding a parameter
// to a spec leaves the others' draws as they were.
std::uint64_t name_stream(const std::string& name) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : name) h = (h ^ c) * 0x100000001b3ull;
  return h;
}

double standard_normal_cdf(double x) { return 0.5 * std::erfc(-x / std::numbers::sqrt2); }

// A normal truncated to [low, high] at u in [0, 1): the inverse CDF over
// the interval, worked in the tail nearer zero for precision.
double truncated_normal(const Distribution& d, double u) {
  double a = (d.low - d.mean) / d.sd, b = (d.high - d.mean) / d.sd;
  // Truncated to a sliver of a standard deviation the normal is uniform to
  // first order, and the CDF's two ends round together.
  if (b - a < 1e-7) return d.low + u * (d.high - d.low);
  // Beyond 37 sd both ends of the CDF underflow; there the normal's tail is
  // an exponential of rate a (Mills' ratio, to 1/a^2 < 0.1%).
  if (a > 37 || b < -37) {
    const bool lower = b < -37;
    const double near = lower ? -b : a, far = lower ? -a : b;
    const double z = near - std::log1p(-u * -std::expm1(-near * (far - near))) / near;
    return std::clamp(d.mean + d.sd * (lower ? -z : z), d.low, d.high);
  }
  const bool upper = a > 0;
  if (upper) {
    std::tie(a, b) = std::pair{-b, -a};
    u = 1 - u;
  }
  const double pa = standard_normal_cdf(a), pb = standard_normal_cdf(b);
  double p = pa + u * (pb - pa);
  p = std::clamp(p, std::nextafter(0.0, 1.0), std::nextafter(1.0, 0.0));
  double z = inverse_normal_cdf(p);
  if (upper) z = -z;
  return std::clamp(d.mean + d.sd * z, d.low, d.high);
}

double draw(const Distribution& d, ParameterType type, double u, std::size_t grid_position) {
  using K = Distribution::Kind;
  switch (d.kind) {
    case K::fixed: return d.values.front();
    case K::grid: return d.values[grid_position];
    case K::uniform:
      if (type == ParameterType::integer) {
        return std::min(d.high, d.low + std::floor(u * (d.high - d.low + 1)));
      }
      return d.low + u * (d.high - d.low);
    case K::normal: return truncated_normal(d, u);
    case K::cap: {
      const double c_low = std::cos(d.low * kDegree), c_high = std::cos(d.high * kDegree);
      return std::acos(std::clamp(c_low - u * (c_low - c_high), -1.0, 1.0)) / kDegree;
    }
    case K::choice: {
      if (d.weights.empty()) {
        return d.values[std::min(d.values.size() - 1, static_cast<std::size_t>(u * static_cast<double>(d.values.size())))];
      }
      double total = 0;
      for (double w : d.weights) total += w;
      double cumulative = 0;
      for (std::size_t i = 0; i < d.values.size(); ++i) {
        cumulative += d.weights[i];
        if (u * total < cumulative) return d.values[i];
      }
      return d.values.back();
    }
  }
  return d.values.front();
}

// ---------------------------------------------------------------- the scene

Rotation head_rotation(const EyeAppearance& a, double yaw_deg, double pitch_deg, double roll_deg) {
  const UnitVector3 forward = a.head_forward, up = a.head_up;
  const UnitVector3 side = UnitVector3::normalize(cross(up, forward));
  // Yaw about up, then pitch about the turned side axis, then roll about
  // the turned forward axis (intrinsic): each angle in the head's terms.
  const Rotation yaw = Rotation::from_axis_angle(up, yaw_deg * kDegree);
  const Rotation pitch = Rotation::from_axis_angle(yaw * side, -pitch_deg * kDegree);
  const Rotation roll = Rotation::from_axis_angle(pitch * (yaw * forward), roll_deg * kDegree);
  return roll * pitch * yaw;
}

}  // namespace

double inverse_normal_cdf(double p) {
  if (!(p > 0 && p < 1)) {
    if (p == 0) return -std::numeric_limits<double>::infinity();
    if (p == 1) return std::numeric_limits<double>::infinity();
    return std::numeric_limits<double>::quiet_NaN();
  }
  if (p > 0.5) return -inverse_normal_cdf(1 - p);  // 1 - p is exact here
  // Abramowitz and Stegun 26.2.23 (error below 4.5e-4) to start, then
  // Newton's method on the CDF, kept within a bracket.
  const double t = std::sqrt(-2 * std::log(p));
  double x = -(t - (2.515517 + 0.802853 * t + 0.010328 * t * t) / (1 + 1.432788 * t + 0.189269 * t * t + 0.001308 * t * t * t));
  double low = -40, high = 0;
  for (int i = 0; i < 100; ++i) {
    const double f = standard_normal_cdf(x) - p;
    if (f > 0) high = x;
    else low = x;
    const double density = std::exp(-0.5 * x * x) / std::sqrt(2 * std::numbers::pi);
    double next = x - f / density;
    if (!(next > low && next < high)) next = 0.5 * (low + high);
    if (std::abs(next - x) <= 1e-15 * std::max(1.0, std::abs(x))) return next;
    x = next;
  }
  return x;
}

DatasetSpec parse_dataset_spec(const std::string& text, const std::string& source_name,
                               const std::filesystem::path& folder) {
  try {
    return Reader{source_name, folder, text}.read();
  } catch (const JsonFileError& error) {
    throw DatasetSpecError(error.what());
  }
}

DatasetSpec load_dataset_spec(const std::filesystem::path& file) {
  std::string text;
  try {
    text = read_input_file(file, kMaxSceneFileBytes, "a dataset spec");
  } catch (const InputFileError& e) {
    throw DatasetSpecError(file.string() + ": cannot read: " + e.reason());
  }
  return parse_dataset_spec(text, file.string(), file.parent_path());
}

std::vector<std::string> dataset_parameter_names() {
  std::vector<std::string> names;
  for (const ParameterRule& r : scene_rules()) names.push_back(r.name);
  for (const char* n : {"illuminator.NAME.on", "illuminator.NAME.power_scale", "mesh.NAME.on", "spectacle_lens.NAME.on"}) {
    names.emplace_back(n);
  }
  return names;
}

ImageDraw draw_image(const DatasetSpec& spec, std::uint64_t index) {
  ImageDraw out;
  out.index = index;
  // Below 2^53: exact in the labels and the table whatever reads them.
  out.seed = counter_key(stream_key(spec.seed, name_stream("render.seed")), index) >> 11;
  // The grid parameters form a product, the last in column order varying
  // fastest; image k takes the product's entry k modulo its size.
  std::vector<std::size_t> positions(spec.parameters.size(), 0);
  std::uint64_t rest = index;
  std::uint64_t product = 1;
  for (const VariedParameter& p : spec.parameters) {
    if (p.distribution.kind != Distribution::Kind::grid) continue;
    // Capped beyond any index (< 2^40): a product that wrapped past 2^64
    // to 0 divided by zero below.
    const std::uint64_t size = p.distribution.values.size();
    product = product > (kMaxCount + 1) / size ? kMaxCount + 1 : product * size;
  }
  rest = index % product;
  for (std::size_t i = spec.parameters.size(); i-- > 0;) {
    const Distribution& d = spec.parameters[i].distribution;
    if (d.kind != Distribution::Kind::grid) continue;
    positions[i] = static_cast<std::size_t>(rest % d.values.size());
    rest /= d.values.size();
  }
  for (std::size_t i = 0; i < spec.parameters.size(); ++i) {
    const VariedParameter& p = spec.parameters[i];
    const double u = to_unit(counter_key(stream_key(spec.seed, name_stream(p.name)), index));
    out.values.push_back(draw(p.distribution, p.type, u, positions[i]));
  }
  return out;
}

Scene scene_for_image(const DatasetSpec& spec, const ImageDraw& image) {
  std::unordered_map<std::string, double> drawn;
  for (std::size_t i = 0; i < spec.parameters.size(); ++i) drawn[spec.parameters[i].name] = image.values.at(i);
  const auto value = [&](const std::string& name) -> std::optional<double> {
    const auto it = drawn.find(name);
    if (it == drawn.end()) return std::nullopt;
    return it->second;
  };
  const auto fail = [&](const std::string& what) {
    std::string values;
    for (std::size_t i = 0; i < spec.parameters.size(); ++i) {
      values += (i ? ", " : "") + spec.parameters[i].name + " = " + format_number(image.values[i]);
    }
    throw DatasetSpecError((spec.source.empty() ? spec.name : spec.source) + ": image " + std::to_string(image.index) +
                           ": " + what + " (drawn: " + values + ")");
  };

  Scene scene = spec.scene;
  const Eye& base = spec.scene.eyes.front();
  EyeModel model = base.model();
  bool eye_changed = false;
  const auto set = [&](const char* name, double& field, double scale = 1) {
    if (auto v = value(name)) {
      field = *v * scale;
      eye_changed = true;
    }
  };
  set("pupil_radius_mm", model.pupil_radius_mm);
  set("cornea_radius_mm", model.anterior_cornea.radius_mm);
  set("cornea_asphericity", model.anterior_cornea.asphericity);
  set("kappa_horizontal_deg", model.kappa_horizontal_rad, kDegree);
  set("kappa_vertical_deg", model.kappa_vertical_rad, kDegree);
  set("rotation_center_depth_mm", model.rotation_center_depth_mm);
  if (auto posterior = value("posterior_cornea")) {
    eye_changed = true;
    // On: Le Grand's posterior surface and indices where the model has
    // none; off: one surface with the keratometric index (eye_presets.cpp).
    if (*posterior != 0 && !model.posterior_cornea) {
      model.posterior_cornea = le_grand_eye().posterior_cornea;
      model.aqueous_index = le_grand_eye().aqueous_index;
    } else if (*posterior == 0 && model.posterior_cornea) {
      model.posterior_cornea.reset();
      model.aqueous_index = keratometric_eye().aqueous_index;
    }
  }
  if (const std::optional<AnatomyProblem> problem = anatomy_problem(model)) {
    fail(problem->key + " = " + problem->value + ": " + problem->rule);
  }

  EyeAppearance look = base.appearance();
  if (auto v = value("iris_seed")) look.iris_seed = static_cast<std::uint64_t>(*v);
  if (auto v = value("iris_texture_contrast")) look.iris_texture_contrast = *v;
  if (auto v = value("iris_albedo")) look.iris_albedo = *v;
  if (auto v = value("iris_furrow_contrast")) look.iris_furrow_contrast = *v;
  if (auto v = value("iris_freckles")) look.iris_freckles = static_cast<int>(*v);
  if (auto v = value("sclera_albedo")) look.sclera_albedo = *v;
  if (auto v = value("skin_albedo")) look.skin_albedo = *v;
  if (auto v = value("fundus_reflectance")) look.fundus_reflectance = *v;
  if (auto v = value("skin_texture_contrast")) look.skin_texture_contrast = *v;
  if (auto v = value("sclera_vessel_contrast")) look.sclera_vessel_contrast = *v;
  if (look.tear_film) {
    if (auto v = value("sclera_roughness_deg")) look.tear_film->sclera_roughness_deg = *v;
    if (auto v = value("meniscus_radius_mm")) look.tear_film->meniscus_radius_mm = *v;
    if (auto v = value("upper_meniscus_radius_mm")) look.tear_film->upper_meniscus_radius_mm = *v;
  }
  if (look.eyelids) {
    if (auto v = value("lid_opening")) look.eyelids->opening = *v;
    if (value("blink").value_or(0) != 0) look.eyelids->opening = 0;
  }
  if (look.face) {
    for (const FaceKey& key : kFaceKeys) {
      if (auto v = value(std::string(key.name))) look.face.value().*key.member = *v;
    }
    const auto draw_hairs = [&](const std::string& prefix, auto& hairs, const auto& keys) {
      for (const auto& key : keys) {
        if (auto v = value(prefix + std::string(key.name))) hairs.*key.member = *v;
      }
      if (auto v = value(prefix + "seed")) hairs.seed = static_cast<std::uint64_t>(*v);
    };
    if (look.face->lashes) draw_hairs("lash_", *look.face->lashes, kLashKeys);
    if (look.face->brows) draw_hairs("brows_", *look.face->brows, kBrowKeys);
  }
  const double yaw = value("head_yaw_deg").value_or(0), pitch = value("head_pitch_deg").value_or(0),
               roll = value("head_roll_deg").value_or(0);
  if (yaw != 0 || pitch != 0 || roll != 0) {
    const Rotation turn = head_rotation(look, yaw, pitch, roll);
    look.head_forward = turn * look.head_forward;
    look.head_up = turn * look.head_up;
  }
  const Vector3 offset{value("eye_offset_x_mm").value_or(0), value("eye_offset_y_mm").value_or(0),
                       value("eye_offset_z_mm").value_or(0)};
  const auto screen_x = value("screen_x_mm"), screen_y = value("screen_y_mm");
  const auto turn = value("gaze_turn_deg"), direction = value("gaze_direction_deg");
  eye_changed = eye_changed || offset.norm() > 0 || screen_x || screen_y || turn || direction;
  if (eye_changed) {
    const Point3 rotation_center = base.rotation_center() + offset;
    try {
      if (screen_x || screen_y) {
        const Screen& screen = *spec.scene.screen;
        const Point3 target = screen.at({screen_x.value_or(screen.width_mm / 2), screen_y.value_or(screen.height_mm / 2)});
        scene.eyes.front() = Eye::fixating(model, rotation_center, target);
      } else {
        // As with_eye_variation turns it: about the scene's gaze, the
        // direction measured from the head's up (before the head turns).
        const UnitVector3 gaze = base.visual_axis();
        const UnitVector3 head_up = base.appearance().head_up;
        const UnitVector3 up = UnitVector3::normalize(head_up.vector() - gaze.vector() * dot(head_up, gaze));
        const UnitVector3 side = UnitVector3::normalize(cross(up, gaze));
        const double t = turn.value_or(0) * kDegree, a = direction.value_or(0) * kDegree;
        const UnitVector3 toward = UnitVector3::normalize(up * std::cos(a) + side * std::sin(a));
        const Vector3 turned = gaze.vector() * std::cos(t) + toward.vector() * std::sin(t);
        scene.eyes.front() = Eye::with_visual_axis(model, rotation_center, UnitVector3::normalize(turned));
      }
    } catch (const std::invalid_argument& error) {
      fail(error.what());
    }
  }
  scene.eyes.front().set_appearance(look);
  // The motion during the exposure: the scene's, or the drawn angular
  // speed along the drawn direction (0 deg: yaw, toward +x; 90 deg: pitch,
  // up). A yaw rate turns the axis by its rate times cos(pitch).
  EyeMotion motion = base.motion();
  if (const auto speed = value("gaze_speed_deg_s")) {
    const double a = value("gaze_speed_direction_deg").value_or(0) * kDegree;
    const double cos_pitch = std::sqrt(std::max(0.0, 1 - std::pow(scene.eyes.front().optical_axis().y(), 2)));
    motion = {*speed * std::cos(a) / std::max(cos_pitch, 0.1), *speed * std::sin(a)};
  }
  scene.eyes.front().set_motion(motion);
  // A moved eye must not swallow a camera or a light: the scene reader's
  // rule, here by the sphere around the centre of rotation that holds the
  // sclera and the corneal apex.
  {
    const Eye& eye = scene.eyes.front();
    const double radius = std::max(eye.model().sclera_radius_mm, distance(eye.rotation_center(), eye.corneal_apex()));
    const auto outside = [&](const Point3& p, const std::string& what) {
      if (!(distance(p, eye.rotation_center()) > radius)) {
        fail(what + " lies within " + format_number(radius) + " mm of the eye's centre of rotation: inside the eye");
      }
    };
    for (const Camera& c : scene.cameras) outside(c.center(), "camera '" + c.name() + "'");
    for (const Illuminator& l : spec.scene.illuminators) outside(l.position, "illuminator '" + l.name + "'");
  }

  // Illuminators: scaled, and those off left out of the scene (their
  // glints do not exist; the table marks them off).
  scene.illuminators.clear();
  const double power = value("led_power_scale").value_or(1);
  for (Illuminator light : spec.scene.illuminators) {
    if (value("illuminator." + light.name + ".on").value_or(1) == 0) continue;
    light.radiant_intensity_w_sr *= power * value("illuminator." + light.name + ".power_scale").value_or(1);
    scene.illuminators.push_back(light);
  }
  scene.meshes.clear();
  for (const Mesh& mesh : spec.scene.meshes) {
    if (value("mesh." + mesh.name + ".on").value_or(1) != 0) scene.meshes.push_back(mesh);
  }
  scene.spectacle_lenses.clear();
  for (const SpectacleLens& lens : spec.scene.spectacle_lenses) {
    if (value("spectacle_lens." + lens.name + ".on").value_or(1) != 0) scene.spectacle_lenses.push_back(lens);
  }
  for (Camera& camera : scene.cameras) {
    Sensor s = camera.sensor();
    if (auto v = value("exposure_s")) s.exposure_s = *v;
    if (auto v = value("gain")) s.gain = *v;
    if (auto v = value("read_noise_e")) s.read_noise_e = *v;
    if (auto v = value("noise")) s.noise = *v != 0;
    if (auto v = value("focus_distance_mm")) s.focus_distance_mm = *v;
    if (auto v = value("bits")) s.bits = static_cast<int>(*v);
    if (auto v = value("corner_illumination")) s.corner_illumination = *v;
    if (auto v = value("hot_pixel_fraction")) s.hot_pixel_fraction = *v;
    if (auto v = value("jpeg_quality")) s.jpeg_quality = static_cast<int>(*v);
    camera = Camera(camera.name(), camera.intrinsics(), camera.distortion(), camera.world_from_camera(), s);
  }
  return scene;
}

}  // namespace purkinje
