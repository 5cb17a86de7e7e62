#include "purkinje/studies/render_set.h"

#include <algorithm>
#include <cstdlib>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "purkinje/models/input_file.h"
#include "purkinje/models/labels.h"
#include "purkinje/models/output_file.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/models/truth.h"
#include "purkinje/renderer/ray_tracer.h"

namespace purkinje::studies {
namespace {

namespace fs = std::filesystem;
namespace r = renderer;

std::string file_stem(const std::string& prefix, const std::string& camera) {
  return portable_file_name((prefix.empty() ? "scene" : prefix) + "_" + camera);
}

// Variation k's stem among `count`: "<scene>_v<k>", k with at least 4 digits.
std::string variation_stem(const Scene& scene, std::size_t k, std::size_t count) {
  const std::size_t digits = std::max<std::size_t>(4, std::to_string(count - 1).size());
  std::string index = std::to_string(k);
  index.insert(0, digits - index.size(), '0');
  return (scene.name.empty() ? std::string("scene") : scene.name) + "_v" + index;
}

// Renders `cameras` of `scene` and writes their files under `stem_prefix`
// as one all-or-nothing set: every camera is rendered before anything is
// written, so a failure leaves no file at all.
void render_unit(const RenderPlan& plan, const Scene& scene, const std::string& stem_prefix,
                 r::RenderOptions options, const RenderSetHooks& hooks, bool show_progress) {
  const std::string& scene_file = plan.request.scene_file;
  std::vector<std::string> stems;
  for (int camera : plan.cameras) {
    const std::string stem = file_stem(stem_prefix, scene.cameras[camera].name());
    if (std::find(stems.begin(), stems.end(), stem) != stems.end()) {
      throw std::invalid_argument(scene_file + ": cameras '" + scene.cameras[camera].name() +
                                  "' and another camera would both write " + stem +
                                  ".*: give them names that differ in letters, digits, '-', '_' or '.'");
    }
    stems.push_back(stem);
  }
  std::vector<r::RenderResult> results;
  for (int camera : plan.cameras) {
    const std::string& name = scene.cameras[camera].name();
    if (show_progress && hooks.camera_progress) {
      options.progress = [&](double fraction) { hooks.camera_progress(name, fraction); };
    }
    try {
      results.push_back(r::render(scene, camera, options));
    } catch (const std::exception& error) {
      if (show_progress && hooks.camera_done) hooks.camera_done();
      throw std::invalid_argument(scene_file + ": " + error.what());
    }
    if (show_progress && hooks.camera_done) hooks.camera_done();
  }

  create_output_folder(plan.request.output_dir);
  FileSet files;
  std::vector<r::RenderFiles> written;
  for (std::size_t i = 0; i < results.size(); ++i) {
    written.push_back(r::add_render(files, plan.request.output_dir, stems[i], scene, results[i], options));
  }
  files.commit();
  if (hooks.wrote) {
    for (const r::RenderFiles& f : written) hooks.wrote(f);
  }
}


// Whether every camera's files of a variation are in place and are what
// this run would write: labels whose scene part (cameras, lights, eyes:
// the variation's pose and pupil) and render settings (every option that
// changes a byte) equal this run's, and whose recorded size and CRC-32 of
// the PNG and EXR match the files beside them.
bool unit_complete(const fs::path& dir, const std::string& stem_prefix, const Scene& scene,
                   const std::vector<int>& cameras, const r::RenderOptions& options) {
  using json = nlohmann::json;
  try {
    const json truth = json::parse(truth_to_json(scene, compute_truth(scene)));
    for (int camera : cameras) {
      const std::string stem = file_stem(stem_prefix, scene.cameras[camera].name());
      const json labels = json::parse(read_input_file(dir / (stem + ".json"), kMaxLabelsFileBytes, "a labels file"));
      for (const char* key : {"labels_format", "scene", "units", "cameras", "illuminators", "eyes"}) {
        if (labels.at(key) != truth.at(key)) return false;
      }
      const json& render = labels.at("render");
      // Named: items() does not keep a temporary alive.
      const json settings = json::parse(r::render_settings_json(scene, camera, options));
      for (const auto& [key, value] : settings.items()) {
        if (render.at(key) != value) return false;
      }
      const json& files = render.at("files");
      for (const auto& [kind, extension] : {std::pair{"image", ".png"}, std::pair{"exr", ".exr"}}) {
        const std::string name = files.at(kind).get<std::string>();
        if (name != stem + extension) return false;
        const FileCheck check = file_check_of_file(dir / name);
        if (files.at(std::string(kind) + "_bytes").get<std::uintmax_t>() != check.bytes ||
            files.at(std::string(kind) + "_crc32").get<std::string>() != crc32_text(check.crc32)) {
          return false;
        }
      }
    }
  } catch (const std::exception&) {
    return false;  // missing, cut short, or not this run's: rendered again
  }
  return true;
}

// A set's index: one line per variation, written as units finish.
class VariationIndex {
 public:
  explicit VariationIndex(const RenderPlan& plan) : plan_(plan), file_(plan.request.output_dir / "variations.csv") {}

  const fs::path& file() const { return file_; }
  std::string stem(std::size_t k) const { return variation_stem(plan_.scene, k, plan_.variations.size()); }

  std::string line(std::size_t k) const {
    const EyeVariation& v = plan_.variations[k];
    std::ostringstream line;
    line << std::setprecision(10) << k << ',' << stem(k) << ',' << plan_.request.options.seed + k << ','
         << v.gaze_turn_rad * 180 / std::numbers::pi << ',' << v.turn_direction_rad * 180 / std::numbers::pi << ','
         << v.pupil_radius_mm << '\n';
    return line.str();
  }

  // --resume: the whole lines a killed run wrote, each checked against
  // this run's; then the index starts again from them (a line a kill cut
  // short would otherwise run into the next one appended).
  void start() {
    std::error_code ec;  // unreachable folders are the write's to report
    if (plan_.request.resume && fs::exists(file_, ec)) read_killed_run();
    std::string start = kHeader;
    for (const auto& [k, line] : indexed_) start += line;
    write_file_atomically(file_, start);
  }

  void add(std::size_t k) {
    if (!indexed_.count(k)) append_to_file(file_, line(k));
  }

  void finish() const {
    std::string list = kHeader;
    for (std::size_t k = 0; k < plan_.variations.size(); ++k) list += line(k);
    write_file_atomically(file_, list);
  }

 private:
  static constexpr const char* kHeader = "index,stem,seed,gaze_turn_deg,turn_direction_deg,pupil_radius_mm\n";

  void read_killed_run() {
    std::string text;
    try {
      text = read_input_file(file_, std::uintmax_t{1} << 32, "an index");
    } catch (const std::exception& error) {
      throw OutputError(error.what());
    }
    const std::string header = kHeader;
    if (text.rfind(header, 0) != 0) {
      throw ResumeRefused(file_.string() + ": not the index of a --variations set: --resume continues only such a set");
    }
    // Whole lines only: a kill may have cut the last one short.
    for (std::size_t at = header.size(), end; (end = text.find('\n', at)) != std::string::npos; at = end + 1) {
      const std::string line = text.substr(at, end + 1 - at);
      indexed_[std::strtoull(line.c_str(), nullptr, 10)] = line;
    }
    for (const auto& [k, line] : indexed_) {
      const std::string again = " --resume needs the options of the run it continues";
      if (k >= plan_.variations.size()) {
        throw ResumeRefused(file_.string() + " lists variation " + std::to_string(k) + "; this run has " +
                            std::to_string(plan_.variations.size()) + ":" + again);
      }
      if (line != this->line(k)) {
        throw ResumeRefused(file_.string() + ": variation " + std::to_string(k) + " was made with other options (" +
                            line.substr(0, line.size() - 1) + "):" + again);
      }
    }
  }

  const RenderPlan& plan_;
  fs::path file_;
  std::map<std::size_t, std::string> indexed_;
};

// Each variation's files are written as soon as it is rendered (a set of
// hundreds would not fit in memory), each all or nothing, the labels last
// with their images' checks; the index grows a line per finished
// variation, and is written whole at the end.
RenderSetOutcome render_variations(const RenderPlan& plan, const RenderSetHooks& hooks) {
  const RenderSetRequest& request = plan.request;
  VariationIndex index(plan);
  create_output_folder(request.output_dir);
  index.start();
  if (request.resume) remove_stale_temporaries(request.output_dir);
  RenderSetOutcome outcome;
  outcome.index_file = index.file();
  r::RenderOptions options = request.options;
  for (std::size_t k = 0; k < plan.variations.size(); ++k) {
    options.seed = request.options.seed + k;  // the noise differs from image to image
    const Scene varied = with_eye_variation(plan.scene, plan.variations[k]);
    if (request.resume && unit_complete(request.output_dir, index.stem(k), varied, plan.cameras, options)) {
      ++outcome.resumed;
    } else {
      render_unit(plan, varied, index.stem(k), options, hooks, false);
    }
    stop_point("unit_written");
    if (hooks.unit_done) hooks.unit_done();
    index.add(k);
  }
  index.finish();
  return outcome;
}

}  // namespace

RenderPlan plan_render_set(const RenderSetRequest& request) {
  RenderPlan plan{request, load_scene(request.scene_file), {}, {}};
  for (int i = 0; i < static_cast<int>(plan.scene.cameras.size()); ++i) {
    if (request.camera.empty() || plan.scene.cameras[i].name() == request.camera) plan.cameras.push_back(i);
  }
  if (plan.cameras.empty()) {
    throw std::invalid_argument(request.scene_file + ": no camera named '" + request.camera + "'");
  }
  r::embree_device();  // a bad PURKINJE_EMBREE_CONFIG is named now, not after the first render
  if (request.variations > 0) {
    if (plan.scene.eyes.empty()) throw std::invalid_argument(request.scene_file + ": --variations needs an eye");
    plan.variations = random_eye_variations(request.variation_seed, request.variations, request.variation_range);
  }
  return plan;
}

std::vector<std::string> render_set_outputs(const RenderPlan& plan) {
  std::vector<std::string> outputs;
  const auto add_unit = [&](const std::string& stem_prefix) {
    for (int camera : plan.cameras) {
      for (const char* extension : {".png", ".exr", ".json"}) {
        outputs.push_back(file_stem(stem_prefix, plan.scene.cameras[camera].name()) + extension);
      }
    }
  };
  if (plan.variations.empty()) {
    add_unit(plan.scene.name);
  } else {
    outputs.push_back("variations.csv");
    for (std::size_t k = 0; k < plan.variations.size(); ++k) {
      add_unit(variation_stem(plan.scene, k, plan.variations.size()));
    }
  }
  return outputs;
}

RenderSetOutcome render_set(const RenderPlan& plan, const RenderSetHooks& hooks) {
  if (!plan.variations.empty()) return render_variations(plan, hooks);
  render_unit(plan, plan.scene, plan.scene.name, plan.request.options, hooks, true);
  return {};
}

}  // namespace purkinje::studies
