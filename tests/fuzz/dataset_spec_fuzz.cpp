// Fuzz target: the dataset spec reader (parse_dataset_spec) and the draws
// of a spec it accepts. It documents one exception, DatasetSpecError;
// anything else escaping, a crash or a sanitizer report is a finding. On
// success the spec must hold what dataset_spec.h promises: a count in
// [1, 2^40], a camera at least, every parameter's distribution well formed
// (fixed, choice and grid with values, weights one per choice, uniform and
// normal intervals not reversed, a normal's sd > 0). Then images 0, 1 and
// count - 1 are drawn (three at most: the fuzzer needs speed): each value
// finite, of its parameter's type (integers exact, booleans 0 or 1),
// within its distribution (an interval's ends, one of the values listed,
// never a choice of weight 0) and within the parameter's range in
// docs/dataset-format.md, the same when drawn again, the render seed below
// 2^53. Each draw's scene (scene_for_image) may be refused with
// DatasetSpecError only (a draw no eye can have), and a scene it returns
// must have cameras the renderer takes (point_spread: a focus distance
// beyond the focal length, as the scene reader demands).
//
// The spec's scene is resolved against a folder this target makes once in
// the temporary directory, so that a relative name never reaches a file of
// the tree or of the user. It holds scene.json, a tiny remote-like scene
// (a 64 x 48 camera, two LEDs, an eye with lids, a screen, a mesh card
// from square.obj) for gaze, screen, lid, illuminator and mesh parameters,
// and a FIFO, fifo.json, which a spec may name: refused, not blocking.


#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>

#include "fuzz_target.h"
#include "purkinje/models/camera_optics.h"
#include "purkinje/models/dataset_spec.h"

namespace {

// The corpus names it as "scene.json" (tests/fuzz/corpus/dataset_spec/).
constexpr const char* kSceneJson = R"({
  "format": 1,
  "name": "tiny_remote",
  "cameras": [ { "name": "cam0", "resolution_px": [64, 48], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                 "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600], "up": [0, -1, 0] } ],
  "illuminators": [ { "name": "led_left", "position_mm": [-100, 0, 0], "radiant_intensity_w_sr": 0.3 },
                    { "name": "led_right", "position_mm": [100, 0, 0], "radiant_intensity_w_sr": 0.3 } ],
  "eyes": [ { "model": "navarro", "pupil": { "radius_mm": 2.0 },
              "position": { "cornea_center_mm": [0, 0, 600] },
              "orientation": { "gaze_target_mm": [0, -150, 0] },
              "eyelids": {} } ],
  "meshes": [ { "name": "card", "file": "square.obj", "albedo": 0.3,
                "position_mm": [200, 200, 300], "scale": 10 } ],
  "screen": { "center_mm": [0, -182, 0], "size_mm": [518, 324] }
}
)";

// A unit square in the z = 0 plane, two triangles.
constexpr const char* kSquareObj =
    "v 0 0 0\n"
    "v 1 0 0\n"
    "v 1 1 0\n"
    "v 0 1 0\n"
    "f 1 2 3 4\n";

const std::filesystem::path& spec_folder() {
  static const FuzzFolder folder("dataset-spec", {{"scene.json", kSceneJson}, {"square.obj", kSquareObj}}, "fifo.json");
  return folder.path();
}

constexpr std::uint64_t kMaxCount = std::uint64_t{1} << 40;
constexpr std::uint64_t kSeedLimit = std::uint64_t{1} << 53;

void check_distribution(const purkinje::VariedParameter& p) {
  using K = purkinje::Distribution::Kind;
  const purkinje::Distribution& d = p.distribution;
  PURKINJE_FUZZ_CHECK(!p.name.empty());
  for (double v : d.values) PURKINJE_FUZZ_CHECK(std::isfinite(v));
  switch (d.kind) {
    case K::fixed:
    case K::grid:
      PURKINJE_FUZZ_CHECK(!d.values.empty());
      PURKINJE_FUZZ_CHECK(d.weights.empty());
      break;
    case K::choice: {
      PURKINJE_FUZZ_CHECK(!d.values.empty());
      PURKINJE_FUZZ_CHECK(d.weights.empty() || d.weights.size() == d.values.size());
      double total = 0;
      for (double w : d.weights) {
        PURKINJE_FUZZ_CHECK(std::isfinite(w) && w >= 0);
        total += w;
      }
      PURKINJE_FUZZ_CHECK(d.weights.empty() || total > 0);
      break;
    }
    case K::uniform:
    case K::cap:
      PURKINJE_FUZZ_CHECK(std::isfinite(d.low) && std::isfinite(d.high) && d.low <= d.high);
      break;
    case K::normal:
      PURKINJE_FUZZ_CHECK(std::isfinite(d.mean) && std::isfinite(d.sd) && d.sd > 0);
      PURKINJE_FUZZ_CHECK(std::isfinite(d.low) && std::isfinite(d.high) && d.low < d.high);
      break;
  }
}

// The range docs/dataset-format.md gives a parameter ("Parameters"): a
// drawn value outside it reaches the scene, the labels and the table.
struct DocumentedRange {
  const char* name;
  double low, high;
  bool low_open;
};
constexpr DocumentedRange kDocumentedRanges[] = {
    {"gaze_turn_deg", 0, 90, false},          {"gaze_direction_deg", -360, 360, false},
    {"pupil_radius_mm", 0, 10, true},         {"eye_offset_x_mm", -1000, 1000, false},
    {"eye_offset_y_mm", -1000, 1000, false},  {"eye_offset_z_mm", -1000, 1000, false},
    {"head_yaw_deg", -90, 90, false},         {"head_pitch_deg", -90, 90, false},
    {"head_roll_deg", -90, 90, false},        {"lid_opening", 0, 1, false},
    {"iris_seed", 0, 9007199254740991.0, false},
    {"iris_texture_contrast", 0, 1, false},   {"iris_albedo", 0, 1, false},
    {"sclera_albedo", 0, 1, false},           {"skin_albedo", 0, 1, false},
    {"fundus_reflectance", 0, 1, false},      {"cornea_radius_mm", 0, 100, true},
    {"sclera_roughness_deg", 0, 10, false},   {"meniscus_radius_mm", 0, 1, false},   {"skin_texture_contrast", 0, 1, false},
    {"upper_meniscus_radius_mm", 0, 1, false},
    {"sclera_vessel_contrast", 0, 1, false},
    {"cornea_asphericity", -1, 10, false},    {"kappa_horizontal_deg", -45, 45, false},
    {"kappa_vertical_deg", -45, 45, false},   {"rotation_center_depth_mm", 0, 100, true},
    {"led_power_scale", 0, 1e6, false},       {"exposure_s", 0, 10, true},
    {"gain", 0, 1e6, true},                   {"read_noise_e", 0, 1e6, false},
    {"focus_distance_mm", 0, 1e6, true},
};

bool within_documented_range(const purkinje::VariedParameter& p, const purkinje::Scene& scene, double v) {
  const std::string& name = p.name;
  if (name == "bits") return v == 8 || v == 10 || v == 12 || v == 16;
  if (name == "screen_x_mm" || name == "screen_y_mm") {
    return scene.screen && v >= 0 && v <= (name == "screen_x_mm" ? scene.screen->width_mm : scene.screen->height_mm);
  }
  if (name.rfind("illuminator.", 0) == 0 && name.size() > 12 &&
      name.compare(name.size() - 12, 12, ".power_scale") == 0) {
    return v >= 0 && v <= 1e6;
  }
  for (const DocumentedRange& r : kDocumentedRanges) {
    if (name == r.name) return (r.low_open ? v > r.low : v >= r.low) && v <= r.high;
  }
  return true;  // booleans: checked by type
}

bool of_its_type(const purkinje::VariedParameter& p, double v) {
  switch (p.type) {
    case purkinje::ParameterType::integer: return v == std::floor(v);
    case purkinje::ParameterType::boolean: return v == 0 || v == 1;
    case purkinje::ParameterType::real: return true;
  }
  return false;
}

bool within_distribution(const purkinje::Distribution& d, double v) {
  using K = purkinje::Distribution::Kind;
  switch (d.kind) {
    case K::fixed: return v == d.values.front();
    case K::grid: return std::find(d.values.begin(), d.values.end(), v) != d.values.end();
    case K::choice:
      // One of the values, and never one that only a weight of 0 gives.
      for (std::size_t i = 0; i < d.values.size(); ++i) {
        if (d.values[i] == v && (d.weights.empty() || d.weights[i] > 0)) return true;
      }
      return false;
    case K::uniform:
    case K::normal:
    case K::cap: return v >= d.low && v <= d.high;
  }
  return false;
}

// A drawn value as its parameter and distribution allow it; a broken
// promise names the parameter and the value first.
void check_drawn(const purkinje::VariedParameter& p, const purkinje::Scene& scene, std::uint64_t image, double v) {
  const bool finite = std::isfinite(v);
  const bool typed = of_its_type(p, v);
  const bool in_range = within_documented_range(p, scene, v);
  const bool in_distribution = within_distribution(p.distribution, v);
  if (!(finite && typed && in_range && in_distribution)) {
    std::fprintf(stderr, "image %llu: %s drawn as %.17g\n", static_cast<unsigned long long>(image), p.name.c_str(), v);
  }
  PURKINJE_FUZZ_CHECK(finite);
  PURKINJE_FUZZ_CHECK(typed);
  PURKINJE_FUZZ_CHECK(in_range);
  PURKINJE_FUZZ_CHECK(in_distribution);
}

}  // namespace

PURKINJE_FUZZ_TARGET(dataset_spec) {
  purkinje::DatasetSpec spec;
  try {
    spec = purkinje::parse_dataset_spec(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json",
                                        spec_folder());
  } catch (const purkinje::DatasetSpecError&) {
    return 0;
  }
  PURKINJE_FUZZ_CHECK(!spec.name.empty());
  PURKINJE_FUZZ_CHECK(spec.count >= 1 && spec.count <= kMaxCount);
  PURKINJE_FUZZ_CHECK(spec.seed < kSeedLimit);
  PURKINJE_FUZZ_CHECK(!spec.scene.cameras.empty() && !spec.scene.eyes.empty());
  PURKINJE_FUZZ_CHECK(spec.outputs.image || spec.outputs.segmentation || spec.outputs.exr);
  PURKINJE_FUZZ_CHECK(spec.samples_per_pixel >= 1 && spec.edge_samples_per_pixel >= 0);
  for (const purkinje::VariedParameter& p : spec.parameters) check_distribution(p);

  // Three images at most: 0, 1 and the last (fewer when they coincide).
  const std::uint64_t indices[3] = {0, 1, spec.count - 1};
  const std::size_t images = spec.count == 1 ? 1 : spec.count == 2 ? 2 : 3;
  for (std::size_t i = 0; i < images; ++i) {
    const std::uint64_t k = indices[i];
    const purkinje::ImageDraw draw = purkinje::draw_image(spec, k);
    PURKINJE_FUZZ_CHECK(draw.index == k);
    PURKINJE_FUZZ_CHECK(draw.seed < kSeedLimit);
    PURKINJE_FUZZ_CHECK(draw.values.size() == spec.parameters.size());
    for (std::size_t j = 0; j < draw.values.size(); ++j) check_drawn(spec.parameters[j], spec.scene, k, draw.values[j]);
    if (i == 0) {
      // A function of (seed, index, name) alone: the same draws again.
      const purkinje::ImageDraw again = purkinje::draw_image(spec, k);
      PURKINJE_FUZZ_CHECK(again.seed == draw.seed && again.values == draw.values);
    }
    purkinje::Scene scene;
    try {
      scene = purkinje::scene_for_image(spec, draw);
    } catch (const purkinje::DatasetSpecError&) {
      continue;  // a draw no eye can have: documented
    }
    PURKINJE_FUZZ_CHECK(!scene.eyes.empty() && !scene.cameras.empty());
    PURKINJE_FUZZ_CHECK(scene.eyes.front().rotation_center().is_finite());
    PURKINJE_FUZZ_CHECK(scene.eyes.front().cornea_center().is_finite());
    PURKINJE_FUZZ_CHECK(scene.eyes.front().pupil_center().is_finite());
    for (const purkinje::Illuminator& light : scene.illuminators) {
      PURKINJE_FUZZ_CHECK(light.radiant_intensity_w_sr >= 0 && std::isfinite(light.radiant_intensity_w_sr));
    }
    // The scene reader refuses a camera the renderer cannot image with
    // (a focus distance inside the focal length); an image's scene must
    // not bring one back, or generate fails mid-set after its check.
    for (const purkinje::Camera& camera : scene.cameras) {
      try {
        (void)purkinje::point_spread(camera, 600);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "point_spread of camera %s: %s\n", camera.name().c_str(), e.what());
        PURKINJE_FUZZ_CHECK(!"an image's scene has a camera the renderer refuses");
      }
    }
  }
  return 0;
}
