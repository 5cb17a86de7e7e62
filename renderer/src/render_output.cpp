// Writing a rendered image as files: PNG, EXR and labels, all-or-nothing.

#include <cmath>
#include <nlohmann/json.hpp>

#include "purkinje/models/labels.h"
#include "purkinje/renderer/image_io.h"
#include "purkinje/renderer/render.h"

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
  return out;
}

}  // namespace

std::string render_labels_json(const Scene& scene, const RenderResult& result,
                               const RenderOptions& options, const RenderFiles& files) {
  json labels = json::parse(truth_to_json(scene, result.truth));
  const Camera& camera = scene.cameras[result.camera];
  json render = json::object();
  render["camera"] = result.camera;
  render["camera_name"] = camera.name();
  render["files"] = {{"image", files.image.filename().string()},
                     {"exr", files.exr.filename().string()},
                     {"labels", files.labels.filename().string()}};
  render["mode"] = to_string(options.mode);
  render["samples_per_pixel"] = options.samples_per_pixel;
  render["seed"] = options.seed;
  render["iris_cache_resolution"] = options.iris_cache_resolution;
  render["sensor"] = sensor_json(camera.sensor(), options.noise);
  json glints = json::array();
  for (const GlintImage& g : result.glints) {
    json out = json::object();
    out["eye"] = g.eye;
    out["illuminator"] = g.illuminator;
    out["status"] = to_string(g.status);
    out["fresnel_reflectance"] = number(g.radiometry.fresnel);
    out["power_w"] = number(g.radiometry.power_w);
    out["electrons"] = number(g.electrons);
    out["saturates"] = g.electrons > 0 && g.electrons >= camera.sensor().full_well_e;
    glints.push_back(out);
  }
  render["glints"] = glints;
  labels["render"] = render;
  return labels.dump(2) + "\n";
}

RenderFiles write_render(const std::filesystem::path& dir, const std::string& stem, const Scene& scene,
                         const RenderResult& result, const RenderOptions& options) {
  RenderFiles files{dir / (stem + ".png"), dir / (stem + ".exr"), dir / (stem + ".json")};
  std::vector<NamedPlane> planes;
  planes.push_back({"Y", result.radiance});
  planes.push_back({"electrons", result.electrons});
  for (const NamedPlane& p : result.aovs) planes.push_back(p);
  const std::string labels = render_labels_json(scene, result, options, files);

  FileSet set;
  set.add(files.image, [&](const std::filesystem::path& t) { write_png(t, result.sensor); });
  set.add(files.exr, [&](const std::filesystem::path& t) { write_exr(t, planes); });
  set.add(files.labels, [&](const std::filesystem::path& t) {
    // write_file_atomically renames its own temporary onto `t`; FileSet
    // then renames `t` into place with the others.
    write_file_atomically(t, labels);
  });
  set.commit();
  return files;
}

}  // namespace purkinje::renderer
