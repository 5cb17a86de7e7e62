#include "purkinje/studies/generate.h"

#include <OpenImageIO/hash.h>

#include <algorithm>
#include <charconv>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "purkinje/models/check.h"
#include "purkinje/models/csv.h"
#include "purkinje/models/input_file.h"
#include "purkinje/models/output_file.h"
#include "purkinje/models/version.h"
#include "purkinje/renderer/ray_tracer.h"
#include "purkinje/studies/render_set.h"

namespace purkinje::studies {
namespace {

namespace fs = std::filesystem;
namespace r = renderer;
using json = nlohmann::ordered_json;

constexpr int kManifestFormat = 1;

// The image files a set may write, in the labels' and the table's order.
constexpr const char* kFileKinds[] = {"image", "segmentation", "exr", "labels"};

// At least 6 digits, whatever the set's count: image k's names (and its
// labels, which name its files) are the same in a trial and the set.
std::string padded(std::uint64_t k) {
  std::string index = std::to_string(k);
  if (index.size() < 6) index.insert(0, 6 - index.size(), '0');
  return index;
}

std::string image_stem(const GeneratePlan& plan, std::uint64_t k, int camera) {
  return portable_file_name(plan.spec.name + "_" + padded(k) + "_" + plan.spec.scene.cameras[camera].name());
}

std::string number_text(const nlohmann::json& v) {
  if (v.is_null()) return "";
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number_integer() || v.is_number_unsigned()) return v.dump();
  if (v.is_number()) return check::format_number(v.get<double>());
  return csv_cell(v.get<std::string>());
}

// A drawn value as the labels and the table write it.
json value_json(const VariedParameter& p, double v) {
  if (p.type == ParameterType::boolean) return v != 0;
  if (p.type == ParameterType::integer) return static_cast<std::int64_t>(v);
  return v;
}

std::string sha1_of_file(const fs::path& file) {
  OIIO::SHA1 sha1;
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    const std::string why = unreadable_input(file, std::uintmax_t{1} << 50, "a table");
    throw std::runtime_error(file.string() + ": cannot read: " + (why.empty() ? "cannot open it" : why));
  }
  std::vector<char> buffer(1 << 16);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    sha1.append(buffer.data(), static_cast<std::size_t>(in.gcount()));
  }
  return sha1.digest();
}

// The spec, its scene and its meshes as read: what decides the set's bytes
// besides the program (whose version is recorded beside it).
std::string spec_sha1(const DatasetSpec& spec) {
  OIIO::SHA1 sha1;
  sha1.append(spec.text);
  sha1.append(std::string_view("\0", 1));
  sha1.append(spec.scene_text);
  for (const Mesh& m : spec.scene.meshes) {
    sha1.append(m.name);
    sha1.append(m.vertices.data(), m.vertices.size() * sizeof(Point3));
    sha1.append(m.triangles.data(), m.triangles.size() * sizeof(Triangle));
    sha1.append(&m.albedo, sizeof m.albedo);
  }
  return sha1.digest();
}

// ---------------------------------------------------------------- the table

// One row per image and camera: its index, draws, files and the truth a
// tracker is scored on, each column's unit in its name (docs/datasets.md).
class Table {
 public:
  explicit Table(const GeneratePlan& plan) : plan_(plan) {}

  std::string header() const {
    std::vector<std::string> columns = {"index", "camera", "seed"};
    for (const VariedParameter& p : plan_.spec.parameters) columns.push_back(p.name);
    for (const char* kind : kFileKinds) {
      if (!written(kind)) continue;
      columns.push_back(kind);
      columns.push_back(std::string(kind) + "_bytes");
      columns.push_back(std::string(kind) + "_crc32");
    }
    for (const Illuminator& l : plan_.spec.scene.illuminators) {
      for (const char* c : {".status", ".u_px", ".v_px"}) columns.push_back("glint." + l.name + c);
    }
    for (const char* c : {"pupil.status", "pupil.u_px", "pupil.v_px", "pupil.ellipse.u_px", "pupil.ellipse.v_px",
                          "pupil.ellipse.semi_axis_1_px", "pupil.ellipse.semi_axis_2_px", "pupil.ellipse.angle_deg",
                          "pupil.visible_ellipse.u_px", "pupil.visible_ellipse.v_px",
                          "pupil.visible_ellipse.semi_axis_1_px", "pupil.visible_ellipse.semi_axis_2_px",
                          "pupil.visible_ellipse.angle_deg"}) {
      columns.push_back(c);
    }
    for (const char* point : {"cornea_center", "rotation_center", "pupil_center"}) {
      for (const char* axis : {"_x_mm", "_y_mm", "_z_mm"}) columns.push_back(std::string("eye.") + point + axis);
    }
    for (const char* axis : {"optical_axis", "visual_axis"}) {
      for (const char* c : {"_x", "_y", "_z"}) columns.push_back(std::string("eye.") + axis + c);
    }
    columns.push_back("eye.cornea_radius_mm");
    columns.push_back("eye.pupil_radius_mm");
    std::string line;
    for (const std::string& c : columns) {
      if (!line.empty()) line += ',';
      line += csv_cell(c);
    }
    return line + "\n";
  }

  // The row of image k's camera from its labels file (parsed) and the
  // labels file's own check.
  std::string row(const nlohmann::json& labels, const FileCheck& labels_check) const {
    const nlohmann::json& dataset = labels.at("dataset");
    const nlohmann::json& render = labels.at("render");
    std::vector<std::string> cells = {number_text(dataset.at("index")), csv_cell(render.at("camera_name")),
                                      number_text(dataset.at("seed"))};
    for (const VariedParameter& p : plan_.spec.parameters) cells.push_back(number_text(dataset.at("parameters").at(p.name)));
    const nlohmann::json& files = render.at("files");
    for (const char* kind : kFileKinds) {
      if (!written(kind)) continue;
      cells.push_back(csv_cell(files.at(kind)));
      if (std::string(kind) == "labels") {
        cells.push_back(std::to_string(labels_check.bytes));
        cells.push_back(crc32_text(labels_check.crc32));
      } else {
        cells.push_back(number_text(files.at(std::string(kind) + "_bytes")));
        cells.push_back(csv_cell(files.at(std::string(kind) + "_crc32")));
      }
    }
    const nlohmann::json* view = nullptr;
    for (const nlohmann::json& v : labels.at("views")) {
      if (v.at("camera_name") == render.at("camera_name") && v.at("eye") == 0) view = &v;
    }
    if (view == nullptr) throw std::runtime_error("no view of the first eye");
    for (const Illuminator& l : plan_.spec.scene.illuminators) {
      const nlohmann::json* glint = nullptr;
      for (const nlohmann::json& g : view->at("glints")) {
        if (g.at("illuminator_name") == l.name) glint = &g;
      }
      if (glint == nullptr) {
        cells.insert(cells.end(), {"off", "", ""});
      } else {
        cells.push_back(csv_cell(glint->at("status")));
        cells.push_back(number_text(glint->value("u_px", nlohmann::json())));
        cells.push_back(number_text(glint->value("v_px", nlohmann::json())));
      }
    }
    const nlohmann::json& pupil = view->at("pupil");
    const nlohmann::json& centre = pupil.at("refracted_center");
    cells.push_back(csv_cell(centre.at("status")));
    cells.push_back(number_text(centre.value("u_px", nlohmann::json())));
    cells.push_back(number_text(centre.value("v_px", nlohmann::json())));
    for (const char* key : {"ellipse", "visible_ellipse"}) {
      const nlohmann::json e = pupil.value(key, nlohmann::json());
      for (const char* field : {"center_u_px", "center_v_px", "semi_axis_1_px", "semi_axis_2_px", "angle_deg"}) {
        cells.push_back(e.is_object() ? number_text(e.at(field)) : "");
      }
    }
    const nlohmann::json& eye = labels.at("eyes").at(0);
    for (const char* point : {"cornea_center_mm", "rotation_center_mm", "pupil_center_mm"}) {
      for (int i = 0; i < 3; ++i) cells.push_back(number_text(eye.at(point).at(i)));
    }
    for (const char* axis : {"optical_axis", "visual_axis"}) {
      for (int i = 0; i < 3; ++i) cells.push_back(number_text(eye.at(axis).at(i)));
    }
    cells.push_back(number_text(eye.at("cornea_radius_mm")));
    cells.push_back(number_text(eye.at("pupil_radius_mm")));
    std::string line;
    for (std::size_t i = 0; i < cells.size(); ++i) line += (i ? "," : "") + cells[i];
    return line + "\n";
  }

 private:
  bool written(const std::string& kind) const {
    if (kind == "image") return plan_.files.image;
    if (kind == "segmentation") return plan_.files.segmentation;
    if (kind == "exr") return plan_.files.exr;
    return true;
  }

  const GeneratePlan& plan_;
};

// ---------------------------------------------------------------- images

// The labels' "dataset" section of image k: what makes its bytes.
json dataset_section(const GeneratePlan& plan, const ImageDraw& draw) {
  json parameters = json::object();
  for (std::size_t i = 0; i < plan.spec.parameters.size(); ++i) {
    parameters[plan.spec.parameters[i].name] = value_json(plan.spec.parameters[i], draw.values[i]);
  }
  json section = json::object();
  section["name"] = plan.spec.name;
  section["index"] = draw.index;  // not the set's count: image k is the same in a trial of 100 and the set
  section["seed"] = draw.seed;
  section["spec_sha1"] = plan.spec_sha1;
  section["purkinje_version"] = version();
  section["parameters"] = parameters;
  return section;
}

// The labels of image k's camera when they, and the files they check, are
// what this run would write; nullopt otherwise (rendered again).
std::optional<nlohmann::json> complete_labels(const GeneratePlan& plan, const fs::path& labels_file,
                                             const json& dataset) {
  try {
    nlohmann::json labels =
        nlohmann::json::parse(read_input_file(labels_file, kMaxLabelsFileBytes, "a labels file"));
    if (labels.at("dataset").dump() != nlohmann::json::parse(dataset.dump()).dump()) {
      // Another set under this one's names: not this run's to replace.
      if (labels.at("dataset").at("spec_sha1") != plan.spec_sha1 ||
          labels.at("dataset").at("name") != plan.spec.name) {
        throw ResumeRefused(labels_file.string() + ": an image of another data set (spec_sha1 " +
                            labels.at("dataset").at("spec_sha1").get<std::string>() + ", this spec's " +
                            plan.spec_sha1 + "): --resume continues only the same spec in the same folder");
      }
      return std::nullopt;
    }
    const nlohmann::json& files = labels.at("render").at("files");
    for (const char* kind : {"image", "segmentation", "exr"}) {
      if (!files.contains(kind)) continue;
      const FileCheck check = file_check_of_file(labels_file.parent_path() / files.at(kind).get<std::string>());
      if (files.at(std::string(kind) + "_bytes").get<std::uintmax_t>() != check.bytes ||
          files.at(std::string(kind) + "_crc32").get<std::string>() != crc32_text(check.crc32)) {
        return std::nullopt;
      }
    }
    return labels;
  } catch (const ResumeRefused&) {
    throw;
  } catch (const std::exception&) {
    return std::nullopt;  // missing, cut short, or another run's
  }
}

// What a manifest says of its table: the same for a shard, the whole set
// and the merge of its shards but for `shard`.
struct Manifest {
  std::string name, version, spec_sha1;
  std::uint64_t count = 0, cameras = 0;
  std::optional<Shard> shard;
  std::uint64_t rows = 0, files = 0, bytes = 0;
  std::string table_file, table_sha1;

  std::string text() const {
    json m = json::object();
    m["manifest_format"] = kManifestFormat;
    m["name"] = name;
    m["purkinje_version"] = version;
    m["spec_sha1"] = spec_sha1;
    m["count"] = count;
    m["cameras"] = cameras;
    if (shard) m["shard"] = {{"index", shard->index}, {"count", shard->count}};
    m["rows"] = rows;
    m["files"] = files;
    m["bytes"] = bytes;
    m["table"] = {{"file", table_file}, {"sha1", table_sha1}};
    return m.dump(2) + "\n";
  }

  static Manifest read(const fs::path& file) {
    try {
      const nlohmann::json m = nlohmann::json::parse(read_input_file(file, kMaxLabelsFileBytes, "a manifest"));
      if (m.at("manifest_format") != kManifestFormat) throw std::runtime_error("manifest_format is not 1");
      Manifest out;
      out.name = m.at("name");
      out.version = m.at("purkinje_version");
      out.spec_sha1 = m.at("spec_sha1");
      out.count = m.at("count");
      out.cameras = m.at("cameras");
      if (m.contains("shard")) out.shard = Shard{m.at("shard").at("index"), m.at("shard").at("count")};
      out.rows = m.at("rows");
      out.files = m.at("files");
      out.bytes = m.at("bytes");
      out.table_file = m.at("table").at("file");
      out.table_sha1 = m.at("table").at("sha1");
      return out;
    } catch (const std::exception& error) {
      throw std::runtime_error(file.string() + ": not a data set's manifest: " + error.what());
    }
  }
};

}  // namespace

std::string table_file_name(const Shard& shard) {
  if (shard.count == 1) return "table.csv";
  return "table.shard-" + std::to_string(shard.index) + "-of-" + std::to_string(shard.count) + ".csv";
}

std::string manifest_file_name(const Shard& shard) {
  if (shard.count == 1) return "manifest.json";
  return "manifest.shard-" + std::to_string(shard.index) + "-of-" + std::to_string(shard.count) + ".json";
}

GeneratePlan plan_generate(const GenerateRequest& request) {
  GeneratePlan plan;
  plan.request = request;
  plan.spec = load_dataset_spec(request.spec_file);
  plan.count = request.count.value_or(plan.spec.count);
  if (plan.count < 1 || plan.count > (std::uint64_t{1} << 40)) {
    throw std::invalid_argument("--count " + std::to_string(plan.count) + ": must be in [1, 2^40]");
  }
  const Shard& shard = request.shard;
  if (shard.count < 1 || shard.index >= shard.count) {
    throw std::invalid_argument("--shard " + std::to_string(shard.index) + "/" + std::to_string(shard.count) +
                                ": must be i/N with 0 <= i < N");
  }
  for (std::uint64_t k = shard.index; k < plan.count; k += shard.count) plan.images.push_back(k);
  for (int i = 0; i < static_cast<int>(plan.spec.scene.cameras.size()); ++i) {
    if (plan.spec.camera.empty() || plan.spec.scene.cameras[i].name() == plan.spec.camera) plan.cameras.push_back(i);
  }
  r::embree_device();  // a bad PURKINJE_EMBREE_CONFIG is named now, not after the first render

  plan.options.samples_per_pixel = plan.spec.samples_per_pixel;
  plan.options.edge_samples_per_pixel = plan.spec.edge_samples_per_pixel;
  plan.options.threads = request.threads;
  const DatasetOutputs& outputs = plan.spec.outputs;
  plan.files.image = outputs.image;
  plan.files.segmentation = outputs.segmentation;
  plan.files.exr = outputs.exr;
  plan.files.exr_planes = outputs.exr_planes;
  plan.files.exr_settings = {outputs.exr_half, outputs.exr_compression};
  plan.files.indent_labels = false;
  for (const std::string& plane : outputs.exr_planes) {
    if (plane.rfind("glint.", 0) == 0) plan.options.per_light_glint_masks = true;
  }
  const std::vector<std::string> planes = r::exr_plane_names(plan.spec.scene, plan.options);
  for (const std::string& plane : outputs.exr_planes) {
    if (std::find(planes.begin(), planes.end(), plane) == planes.end()) {
      std::string valid;
      for (const std::string& p : planes) valid += (valid.empty() ? "" : ", ") + p;
      throw DatasetSpecError(request.spec_file.string() + ": outputs.exr.planes = \"" + plane +
                             "\": the render has no such plane (valid: " + valid + ")");
    }
  }
  // A light's glint plane cannot be written for an image without that
  // light.
  for (const std::string& plane : outputs.exr_planes) {
    if (plane.rfind("glint.", 0) != 0) continue;
    for (const VariedParameter& p : plan.spec.parameters) {
      if (p.name == "illuminator." + plane.substr(6) + ".on") {
        throw DatasetSpecError(request.spec_file.string() + ": outputs.exr.planes = \"" + plane +
                               "\": its illuminator is switched off in some images (parameters.illuminators." +
                               plane.substr(6) + ".on): leave the plane out, or keep the light on");
      }
    }
  }
  // Every image's draws make an eye before anything is written: a set
  // must not stop on image 90,000 for a pupil beyond its iris. The meshes
  // play no part in that, and copying them for each image would cost more
  // than the check.
  DatasetSpec without_meshes = plan.spec;
  without_meshes.scene.meshes.clear();
  for (std::uint64_t k : plan.images) scene_for_image(without_meshes, draw_image(plan.spec, k));
  plan.spec_sha1 = spec_sha1(plan.spec);
  plan.table_file = table_file_name(shard);
  plan.manifest_file = manifest_file_name(shard);
  // One image's files, every camera's, differ by name ("cam0" and
  // "cam0_classes" would share cam0_classes.png).
  std::vector<std::string> first;
  for (int camera : plan.cameras) {
    const std::string stem = image_stem(plan, 0, camera);
    for (const char* suffix : {".png", "_classes.png", ".exr", ".json"}) first.push_back(stem + suffix);
  }
  std::sort(first.begin(), first.end());
  if (const auto same = std::adjacent_find(first.begin(), first.end()); same != first.end()) {
    throw DatasetSpecError(request.spec_file.string() + ": two cameras would both write " + *same +
                           ": give them names that differ in letters, digits, '-', '_' or '.'");
  }
  return plan;
}

std::vector<std::string> generate_outputs(const GeneratePlan& plan) {
  std::vector<std::string> out = {plan.table_file, plan.manifest_file};
  for (std::uint64_t k : plan.images) {
    for (int camera : plan.cameras) {
      const std::string stem = image_stem(plan, k, camera);
      if (plan.files.image) out.push_back(stem + ".png");
      if (plan.files.segmentation) out.push_back(stem + "_classes.png");
      if (plan.files.exr) out.push_back(stem + ".exr");
      out.push_back(stem + ".json");
    }
  }
  return out;
}

GenerateOutcome generate(const GeneratePlan& plan, const GenerateHooks& hooks) {
  const fs::path& dir = plan.request.output_dir;
  create_output_folder(dir);
  if (plan.request.resume) {
    // Only this shard's: another shard may be writing beside it, from a
    // machine where its process id means nothing.
    const std::vector<std::string> names = generate_outputs(plan);
    const std::set<std::string> own(names.begin(), names.end());
    remove_stale_temporaries(dir, [&](const std::string& target) { return own.count(target) > 0; });
  }
  GenerateOutcome outcome;
  // Reused from image to image: fresh images' memory costs a page fault
  // per 4 KB (render.h).
  std::vector<r::RenderResult> results(plan.cameras.size());
  r::RenderOptions options = plan.options;
  for (std::uint64_t k : plan.images) {
    const ImageDraw draw = draw_image(plan.spec, k);
    const json dataset = dataset_section(plan, draw);
    bool complete = plan.request.resume;
    for (int camera : plan.cameras) {
      complete = complete && complete_labels(plan, dir / (image_stem(plan, k, camera) + ".json"), dataset).has_value();
    }
    if (complete) {
      ++outcome.resumed;
    } else {
      const Scene scene = scene_for_image(plan.spec, draw);
      options.seed = draw.seed;
      r::ImageFileChoice files = plan.files;
      json extra = json::object();
      extra["dataset"] = dataset;
      files.labels_extra = extra.dump();
      // Every camera rendered before anything is written: one image's
      // files are all or nothing.
      FileSet set;
      for (std::size_t c = 0; c < plan.cameras.size(); ++c) {
        try {
          r::render(scene, plan.cameras[c], options, results[c]);
        } catch (const OutputError&) {
          throw;
        } catch (const std::exception& error) {
          throw std::invalid_argument(plan.request.spec_file.string() + ": image " + std::to_string(k) + ": " +
                                      error.what());
        }
        r::add_render(set, dir, image_stem(plan, k, plan.cameras[c]), scene, results[c], options, files);
      }
      set.commit();
      ++outcome.rendered;
    }
    stop_point("unit_written");
    if (hooks.image_done) hooks.image_done();
  }

  // The table from the labels as written (a resumed image's row is the
  // one its first run would have written), then the manifest that checks it.
  const Table table(plan);
  auto table_sha1 = std::make_shared<std::string>();
  auto totals = std::make_shared<std::pair<std::uint64_t, std::uint64_t>>(0, 0);  // files, bytes
  auto rows = std::make_shared<std::uint64_t>(0);
  FileSet set;
  const fs::path table_path = dir / plan.table_file;
  set.add(table_path, [&, table_sha1, totals, rows](const fs::path& t) {
    std::ofstream out(t, std::ios::binary | std::ios::trunc);
    OIIO::SHA1 sha1;
    const auto put = [&](const std::string& text) {
      out << text;
      sha1.append(text);
    };
    put(table.header());
    for (std::uint64_t k : plan.images) {
      for (int camera : plan.cameras) {
        const fs::path labels_file = dir / (image_stem(plan, k, camera) + ".json");
        const std::string text = read_input_file(labels_file, kMaxLabelsFileBytes, "a labels file");
        const FileCheck check = file_check_of(text);
        const nlohmann::json labels = nlohmann::json::parse(text);
        put(table.row(labels, check));
        ++*rows;
        const nlohmann::json& files = labels.at("render").at("files");
        for (const char* kind : {"image", "segmentation", "exr"}) {
          if (!files.contains(kind)) continue;
          ++totals->first;
          totals->second += files.at(std::string(kind) + "_bytes").get<std::uint64_t>();
        }
        ++totals->first;
        totals->second += check.bytes;
      }
    }
    out.close();
    if (!out) throw OutputError(t.string() + ": cannot write the table");
    *table_sha1 = sha1.digest();
  });
  const fs::path manifest_path = dir / plan.manifest_file;
  set.add(manifest_path, [&, table_sha1, totals, rows](const fs::path& t) {
    Manifest manifest;
    manifest.name = plan.spec.name;
    manifest.version = version();
    manifest.spec_sha1 = plan.spec_sha1;
    manifest.count = plan.count;
    manifest.cameras = plan.cameras.size();
    if (plan.request.shard.count > 1) manifest.shard = plan.request.shard;
    manifest.rows = *rows;
    manifest.files = totals->first;
    manifest.bytes = totals->second;
    manifest.table_file = plan.table_file;
    manifest.table_sha1 = *table_sha1;
    write_bytes(t, manifest.text());
  });
  set.commit();
  outcome.table = table_path;
  outcome.manifest = manifest_path;
  return outcome;
}

namespace {

// The shard whose manifest `file` is (manifest_file_name's
// manifest.shard-I-of-N.json, leading zeros allowed); nothing for any other
// name. I and N beyond 2^64 - 1 are refused, naming the file.
std::optional<Shard> shard_of_manifest(const fs::path& file) {
  constexpr std::string_view prefix = "manifest.shard-", middle = "-of-", suffix = ".json";
  const std::string name = file.filename().string();
  std::string_view rest = name;
  if (!rest.starts_with(prefix) || !rest.ends_with(suffix) || rest.size() < prefix.size() + suffix.size()) {
    return std::nullopt;
  }
  rest = rest.substr(prefix.size(), rest.size() - prefix.size() - suffix.size());
  const std::size_t of = rest.find(middle);
  if (of == std::string_view::npos) return std::nullopt;
  const std::string_view i = rest.substr(0, of), n = rest.substr(of + middle.size());
  const auto digits = [](std::string_view text) {
    return !text.empty() && std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
  };
  if (!digits(i) || !digits(n)) return std::nullopt;
  Shard shard;
  for (const auto& [text, value] : {std::pair{i, &shard.index}, std::pair{n, &shard.count}}) {
    if (std::from_chars(text.data(), text.data() + text.size(), *value).ec != std::errc{}) {
      throw std::runtime_error(file.string() + ": a shard number beyond " +
                               std::to_string(std::numeric_limits<std::uint64_t>::max()));
    }
  }
  return shard;
}

}  // namespace

MergeOutcome merge_shards(const fs::path& dir) {
  std::map<std::uint64_t, std::map<std::uint64_t, fs::path>> splits;  // N -> i -> file
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (const std::optional<Shard> shard = shard_of_manifest(e.path())) splits[shard->count][shard->index] = e.path();
  }
  if (ec) throw std::runtime_error(dir.string() + ": cannot list: " + ec.message());
  if (splits.empty()) {
    throw std::runtime_error(dir.string() + ": no shard manifests (manifest.shard-I-of-N.json): generate --shard I/N writes them");
  }
  if (splits.size() > 1) {
    throw std::runtime_error(dir.string() + ": shards of " + std::to_string(splits.begin()->first) + " and of " +
                             std::to_string(std::next(splits.begin())->first) +
                             " shards side by side: merge one split (move the other away)");
  }
  const std::uint64_t n = splits.begin()->first;
  const std::map<std::uint64_t, fs::path>& files = splits.begin()->second;
  std::vector<Manifest> shards;
  for (std::uint64_t i = 0; i < n; ++i) {
    const auto it = files.find(i);
    if (it == files.end()) {
      throw std::runtime_error((dir / manifest_file_name({i, n})).string() + ": missing: shard " + std::to_string(i) +
                               " of " + std::to_string(n) + " has not finished; run generate --shard " +
                               std::to_string(i) + "/" + std::to_string(n) + " (with --resume if it started)");
    }
    Manifest m = Manifest::read(it->second);
    const Manifest& first = shards.empty() ? m : shards.front();
    const auto differ = [&](const std::string& what, const std::string& a, const std::string& b) {
      throw std::runtime_error(it->second.string() + ": " + what + " " + a + "; " + manifest_file_name({0, n}) +
                               " says " + b + ": shards of different sets cannot be merged");
    };
    if (!m.shard || m.shard->index != i || m.shard->count != n) {
      throw std::runtime_error(it->second.string() + ": its shard is not " + std::to_string(i) + " of " +
                               std::to_string(n) + " as its name says");
    }
    if (m.name != first.name) differ("name", m.name, first.name);
    if (m.spec_sha1 != first.spec_sha1) differ("spec_sha1", m.spec_sha1, first.spec_sha1);
    if (m.version != first.version) differ("purkinje_version", m.version, first.version);
    if (m.count != first.count) differ("count", std::to_string(m.count), std::to_string(first.count));
    if (m.cameras != first.cameras) differ("cameras", std::to_string(m.cameras), std::to_string(first.cameras));
    // Shard i holds the images i, i + n, ...: so many rows, no other.
    const std::uint64_t images = m.count > i ? (m.count - 1 - i) / n + 1 : 0;
    if (m.rows != images * m.cameras) {
      throw std::runtime_error(it->second.string() + ": " + std::to_string(m.rows) + " rows; shard " +
                               std::to_string(i) + " of " + std::to_string(n) + " of " + std::to_string(m.count) +
                               " images has " + std::to_string(images * m.cameras));
    }
    const std::string found = sha1_of_file(dir / m.table_file);
    if (found != m.table_sha1) {
      throw std::runtime_error((dir / m.table_file).string() + ": SHA-1 " + found + "; its manifest says " +
                               m.table_sha1 + ": the table changed after its shard finished; run generate --shard " +
                               std::to_string(i) + "/" + std::to_string(n) + " --resume again");
    }
    shards.push_back(m);
  }

  Manifest merged = shards.front();
  merged.shard.reset();
  merged.rows = merged.files = merged.bytes = 0;
  for (const Manifest& m : shards) {
    merged.rows += m.rows;
    merged.files += m.files;
    merged.bytes += m.bytes;
  }
  merged.table_file = table_file_name({0, 1});
  if (merged.rows != merged.count * merged.cameras) {
    throw std::runtime_error(dir.string() + ": the shards' tables hold " + std::to_string(merged.rows) +
                             " rows; a set of " + std::to_string(merged.count) + " images of " +
                             std::to_string(merged.cameras) + " cameras has " +
                             std::to_string(merged.count * merged.cameras));
  }
  auto sha1_text = std::make_shared<std::string>();
  FileSet set;
  const fs::path table_path = dir / merged.table_file;
  set.add(table_path, [&, sha1_text](const fs::path& t) {
    // Image k's rows are in shard k mod N, in order: taken in turn.
    std::vector<std::ifstream> in;
    std::string header;
    for (const Manifest& m : shards) {
      in.emplace_back(dir / m.table_file, std::ios::binary);
      std::string line;
      std::getline(in.back(), line);
      if (in.size() == 1) header = line;
      if (line != header) {
        throw std::runtime_error((dir / m.table_file).string() + ": its header is not " + shards.front().table_file +
                                 "'s");
      }
    }
    std::ofstream out(t, std::ios::binary | std::ios::trunc);
    OIIO::SHA1 sha1;
    const auto put = [&](const std::string& line) {
      out << line << '\n';
      sha1.append(line);
      sha1.append(std::string_view("\n", 1));
    };
    put(header);
    std::string line;
    for (std::uint64_t k = 0; k < merged.count; ++k) {
      std::ifstream& shard = in[k % n];
      for (std::uint64_t c = 0; c < merged.cameras; ++c) {
        if (!std::getline(shard, line)) {
          throw std::runtime_error((dir / shards[k % n].table_file).string() + ": ends before image " +
                                   std::to_string(k));
        }
        put(line);
      }
    }
    for (std::size_t s = 0; s < in.size(); ++s) {
      if (std::getline(in[s], line)) {
        throw std::runtime_error((dir / shards[s].table_file).string() + ": rows beyond its manifest's");
      }
    }
    out.close();
    if (!out) throw OutputError(t.string() + ": cannot write the table");
    *sha1_text = sha1.digest();
  });
  const fs::path manifest_path = dir / manifest_file_name({0, 1});
  set.add(manifest_path, [&, sha1_text](const fs::path& t) {
    merged.table_sha1 = *sha1_text;
    write_bytes(t, merged.text());
  });
  set.commit();
  return {n, merged.rows, table_path, manifest_path};
}

}  // namespace purkinje::studies
