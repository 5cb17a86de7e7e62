// Writing a rendered image as files: PNG, EXR and labels, all-or-nothing.

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <nlohmann/json.hpp>

#include "purkinje/models/input_file.h"
#include "purkinje/models/labels.h"
#include "purkinje/models/output_file.h"
#include "materials.h"
#include "purkinje/renderer/image_io.h"
#include "purkinje/renderer/render.h"
#include "purkinje/renderer/sensor_model.h"

namespace purkinje::renderer {
namespace {

using json = nlohmann::ordered_json;

json number(double v) {
  if (!std::isfinite(v)) return nullptr;
  return v == 0 ? 0.0 : v;
}

json sensor_json(const Sensor& s, bool noise) {
  json out = json::object();
  out["pixel_pitch_mm"] = number(s.pixel_pitch_mm);
  out["f_number"] = number(s.f_number);
  out["exposure_s"] = number(s.exposure_s);
  out["quantum_efficiency"] = number(s.quantum_efficiency);
  out["full_well_e"] = number(s.full_well_e);
  out["read_noise_e"] = number(s.read_noise_e);
  out["gain"] = number(s.gain);
  out["bits"] = s.bits;
  out["psf_sigma_px"] = number(s.psf_sigma_px);
  out["focus_distance_mm"] = s.focus_distance_mm ? number(*s.focus_distance_mm) : json(nullptr);
  out["noise"] = s.noise && noise;
  // The realism keys only when set (as in scene files).
  if (s.corner_illumination != 1) out["corner_illumination"] = number(s.corner_illumination);
  if (s.hot_pixel_fraction > 0) {
    out["hot_pixel_fraction"] = number(s.hot_pixel_fraction);
    out["hot_pixel_e_per_s"] = number(s.hot_pixel_e_per_s);
    out["hot_pixel_seed"] = s.hot_pixel_seed;
  }
  if (s.jpeg_quality) out["jpeg_quality"] = *s.jpeg_quality;
  return out;
}

// Whether the brightest noise-free pixel within 3 px of the glint reaches
// the level where the sensor clips: the full well, or the ADC's top at
// gains above 1.
bool saturates(const RenderResult& result, const GlintImage& g, const Camera& camera) {
  const Sensor& s = camera.sensor();
  const double clip = s.full_well_e / std::max(1.0, s.gain);
  for (const EyeInCameraTruth& view : result.truth.views) {
    if (view.camera != result.camera || view.eye != g.eye) continue;
    const Pixel p = view.glints[g.illuminator].pixel;
    const ImagePlane& e = result.electrons;
    double peak = 0;
    for (int y = static_cast<int>(std::floor(p.v)) - 3; y <= static_cast<int>(std::ceil(p.v)) + 3; ++y) {
      for (int x = static_cast<int>(std::floor(p.u)) - 3; x <= static_cast<int>(std::ceil(p.u)) + 3; ++x) {
        if (x >= 0 && y >= 0 && x < e.width && y < e.height) peak = std::max(peak, double(e.at(x, y)));
      }
    }
    return peak >= clip;
  }
  return false;
}

// What decides an image's pixels besides the scene: every option that
// changes a byte of the files.
json settings_document(const Camera& camera, const RenderOptions& options) {
  json settings = json::object();
  settings["mode"] = to_string(options.mode);
  settings["samples_per_pixel"] = options.samples_per_pixel;
  // What adaptive sampling gave the pixels it refined (no more than the rest: off).
  settings["edge_samples_per_pixel"] = edge_samples_per_pixel(options);
  settings["pixel_filter"] = {{"kind", to_string(options.pixel_filter.kind)},
                              {"width_px", pixel_filter_width_px(options.pixel_filter)}};
  settings["seed"] = options.seed;
  settings["iris_cache_resolution"] = options.iris_cache_resolution;
  if (options.mode == RenderMode::reference) settings["photons_per_light"] = options.reference_photons_per_light;
  settings["glint_masks"] = options.per_light_glint_masks;
  settings["sensor"] = sensor_json(camera.sensor(), options.noise);
  return settings;
}

// The labels without the image files' checks (added once they are written).
json labels_document(const Scene& scene, const RenderResult& result, const RenderOptions& options,
                     const RenderFiles& files) {
  json labels = json::parse(truth_to_json(scene, result.truth));
  const Camera& camera = scene.cameras[result.camera];
  json render = json::object();
  render["camera"] = result.camera;
  render["camera_name"] = camera.name();
  json names = json::object();
  if (!files.image.empty()) names["image"] = files.image.filename().string();
  if (!files.exr.empty()) names["exr"] = files.exr.filename().string();
  if (!files.segmentation.empty()) names["segmentation"] = files.segmentation.filename().string();
  names["labels"] = files.labels.filename().string();
  render["files"] = names;
  const json settings = settings_document(camera, options);  // named: items() does not keep a temporary alive
  for (const auto& [key, value] : settings.items()) render[key] = value;
  json glints = json::array();
  for (const GlintImage& g : result.glints) {
    json out = json::object();
    out["eye"] = g.eye;
    out["illuminator"] = g.illuminator;
    out["status"] = to_string(g.status);
    out["fresnel_reflectance"] = number(g.radiometry.fresnel);
    out["power_w"] = number(g.radiometry.power_w);
    out["electrons"] = number(g.electrons);
    out["saturates"] = g.status == PathStatus::ok && saturates(result, g, camera);
    glints.push_back(out);
  }
  render["glints"] = glints;
  // Only when some eye has a tear film or the scene spectacle lenses: each
  // view's distractors in order.
  if (scene_has_distractors(scene)) {
    json distractors = json::array();
    for (const GlintImage& d : result.distractors) {
      const double* c = d.radiometry.roughness_cov_px2;
      distractors.push_back({{"eye", d.eye},
                             {"illuminator", d.illuminator},
                             {"status", to_string(d.status)},
                             {"fresnel_reflectance", number(d.radiometry.fresnel)},
                             {"power_w", number(d.radiometry.power_w)},
                             {"electrons", number(d.electrons)},
                             {"spread_cov_px2", {number(c[0]), number(c[1]), number(c[2])}}});
    }
    render["distractors"] = distractors;
  }
  // Where a glint detector may see a glint that is none (only when the
  // sensor has hot pixels).
  if (camera.sensor().hot_pixel_fraction > 0) {
    json hot = json::array();
    for (const HotPixel& p : hot_pixels(camera.sensor(), camera.intrinsics().width, camera.intrinsics().height)) {
      hot.push_back({{"x_px", p.x}, {"y_px", p.y}, {"dark_e", number(p.dark_e)}});
    }
    render["hot_pixels"] = hot;
  }
  labels["render"] = render;
  return labels;
}

void add_check(json& files, const std::string& kind, const std::filesystem::path& file) {
  const FileCheck check = file_check_of_file(file);
  files[kind + "_bytes"] = check.bytes;
  files[kind + "_crc32"] = crc32_text(check.crc32);
}

}  // namespace

std::string render_settings_json(const Scene& scene, int camera, const RenderOptions& options) {
  return settings_document(scene.cameras.at(static_cast<std::size_t>(camera)), options).dump();
}

std::vector<std::string> exr_plane_names(const Scene& scene, const RenderOptions& options) {
  std::vector<std::string> names = {"Y", "electrons", "depth", "N.x", "N.y", "N.z", "id", "skin", "sclera", "iris", "pupil"};
  if (scene_has_lashes(scene)) names.push_back("lash");
  if (scene_has_brows(scene)) names.push_back("brow");
  names.insert(names.end(), {"cornea", "glint"});
  if (options.per_light_glint_masks) {
    for (const Illuminator& light : scene.illuminators) names.push_back("glint." + light.name);
  }
  if (scene_has_distractors(scene)) names.push_back("distractor");
  return names;
}

RenderFiles add_render(FileSet& set, const std::filesystem::path& dir, const std::string& stem,
                       const Scene& scene, const RenderResult& result, const RenderOptions& options,
                       const ImageFileChoice& choice) {
  RenderFiles files;
  if (choice.image) files.image = dir / (stem + ".png");
  if (choice.exr) files.exr = dir / (stem + ".exr");
  if (choice.segmentation) files.segmentation = dir / (stem + "_classes.png");
  files.labels = dir / (stem + ".json");
  auto labels = std::make_shared<json>(labels_document(scene, result, options, files));
  if (!choice.labels_extra.empty()) {
    const json extra = json::parse(choice.labels_extra);  // named: items() does not keep a temporary alive
    for (const auto& [key, value] : extra.items()) (*labels)[key] = value;
  }
  if (choice.image) {
    auto sensor = std::make_shared<SensorImage>(result.sensor);
    set.add(files.image, [sensor](const std::filesystem::path& t) { write_png(t, *sensor); });
  }
  if (choice.exr) {
    auto planes = std::make_shared<std::vector<NamedPlane>>();
    planes->push_back({"Y", result.radiance});
    planes->push_back({"electrons", result.electrons});
    for (const NamedPlane& p : result.aovs) planes->push_back(p);
    if (!choice.exr_planes.empty()) {
      std::vector<NamedPlane> chosen;
      for (const std::string& name : choice.exr_planes) {
        const auto it = std::find_if(planes->begin(), planes->end(), [&](const NamedPlane& p) { return p.name == name; });
        if (it == planes->end()) throw std::invalid_argument("EXR plane \"" + name + "\": the render has no such plane");
        chosen.push_back(std::move(*it));
      }
      *planes = std::move(chosen);
    }
    set.add(files.exr, [planes, settings = choice.exr_settings](const std::filesystem::path& t) {
      write_exr(t, *planes, settings);
    });
  }
  if (choice.segmentation) {
    const auto id = std::find_if(result.aovs.begin(), result.aovs.end(), [](const NamedPlane& p) { return p.name == "id"; });
    if (id == result.aovs.end()) throw std::logic_error("add_render: the render has no id plane");
    auto classes = std::make_shared<ImagePlane>(id->plane);
    set.add(files.segmentation, [classes](const std::filesystem::path& t) { write_class_png(t, *classes); });
  }
  // Labels last, with the size and CRC-32 of the image files as written:
  // renamed into place after them, they tell a complete unit from one a
  // kill left half replaced (docs/labels.md).
  set.add(files.labels, [labels, files, &set, indent = choice.indent_labels](const std::filesystem::path& t) {
    json& names = (*labels)["render"]["files"];
    if (!files.image.empty()) add_check(names, "image", set.temporary_of(files.image));
    if (!files.exr.empty()) add_check(names, "exr", set.temporary_of(files.exr));
    if (!files.segmentation.empty()) add_check(names, "segmentation", set.temporary_of(files.segmentation));
    // `t` is FileSet's own temporary, flushed and renamed into place by it.
    std::ofstream out(t, std::ios::binary | std::ios::trunc);
    out << labels->dump(indent ? 2 : -1) << "\n";
    out.close();
    if (!out) throw std::runtime_error(t.string() + ": cannot write the labels");
  });
  return files;
}

RenderFiles write_render(const std::filesystem::path& dir, const std::string& stem, const Scene& scene,
                         const RenderResult& result, const RenderOptions& options) {
  FileSet set;
  const RenderFiles files = add_render(set, dir, stem, scene, result, options);
  set.commit();
  return files;
}

}  // namespace purkinje::renderer
