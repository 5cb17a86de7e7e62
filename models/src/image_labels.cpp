// Reading one rendered image's labels back (for scoring): the image-plane
// fields only, each checked, every error naming the file, key and value.

#include <charconv>
#include <cmath>
#include <optional>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

#include "purkinje/models/input_file.h"
#include "purkinje/models/labels.h"

namespace purkinje {
namespace {

using json = nlohmann::json;

// Whether `v` holds arrays or objects nested more than `levels` deep; looks
// no deeper than that, so it recurses at most `levels` times.
bool nested_deeper_than(const json& v, int levels) {
  if (!v.is_structured()) return false;
  if (levels == 0) return true;
  for (const json& element : v) {
    if (nested_deeper_than(element, levels - 1)) return true;
  }
  return false;
}

class Reader {
 public:
  explicit Reader(std::filesystem::path file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const std::string& key, const json* value, const std::string& rule) const {
    std::string text = file_.string() + ": " + key;
    if (value) {
      // dump() recurses once per level: a value nested 100000 deep (found
      // by fuzzing) overflowed the stack. No value read here nests more
      // than 4 deep, so a deeper one is shown by its outer brackets only.
      std::string shown = !nested_deeper_than(*value, 4) ? value->dump() : value->is_array() ? "[...]" : "{...}";
      if (shown.size() > 60) shown = shown.substr(0, 57) + "...";
      text += " = " + shown;
    }
    throw std::runtime_error(text + ": " + rule);
  }

  static std::string join(const std::string& path, const char* key) { return path.empty() ? key : path + "." + key; }

  const json& member(const json& object, const std::string& path, const char* key) const {
    const auto it = object.find(key);
    if (it == object.end()) {
      fail(join(path, key), nullptr, "missing (a labels file of `purkinje render`, docs/labels.md)");
    }
    return *it;
  }
  const json& array(const json& object, const std::string& path, const char* key) const {
    const json& v = member(object, path, key);
    if (!v.is_array()) fail(join(path, key), &v, "must be an array");
    return v;
  }
  const json& object(const json& parent, const std::string& path, const char* key) const {
    const json& v = member(parent, path, key);
    if (!v.is_object()) fail(join(path, key), &v, "must be an object");
    return v;
  }
  double number(const json& object, const std::string& path, const char* key) const {
    const json& v = member(object, path, key);
    if (!v.is_number() || !std::isfinite(v.get<double>())) fail(join(path, key), &v, "must be a finite number");
    return v.get<double>();
  }
  int integer(const json& object, const std::string& path, const char* key, int lo, int hi) const {
    const json& v = member(object, path, key);
    if (!v.is_number_integer() || v.get<long long>() < lo || v.get<long long>() > hi) {
      fail(join(path, key), &v, "must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    }
    return static_cast<int>(v.get<long long>());
  }
  // A file's size and CRC-32 as "<kind>_bytes" and "<kind>_crc32" (eight
  // hexadecimal digits), or nothing when neither is there (labels written
  // before they were).
  std::optional<FileCheck> file_check(const json& files, const std::string& path, const std::string& kind) const {
    const std::string bytes_key = kind + "_bytes", crc_key = kind + "_crc32";
    if (!files.contains(bytes_key) && !files.contains(crc_key)) return std::nullopt;
    const json& bytes = member(files, path, bytes_key.c_str());
    const json& crc = member(files, path, crc_key.c_str());
    if (!bytes.is_number_unsigned()) fail(join(path, bytes_key.c_str()), &bytes, "must be a byte count");
    const std::string text = crc.is_string() ? crc.get<std::string>() : "";
    FileCheck check;
    check.bytes = bytes.get<std::uintmax_t>();
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), check.crc32, 16);
    if (text.size() != 8 || error != std::errc() || end != text.data() + text.size()) {
      fail(join(path, crc_key.c_str()), &crc, "must be a CRC-32 as eight hexadecimal digits");
    }
    return check;
  }
  PathStatus status(const json& object, const std::string& path) const {
    const json& v = member(object, path, "status");
    if (v.is_string()) {
      for (int s = 0; s <= static_cast<int>(PathStatus::invalid_input); ++s) {
        if (v.get<std::string>() == to_string(static_cast<PathStatus>(s))) return static_cast<PathStatus>(s);
      }
    }
    fail(path + ".status", &v, "must be a path status (docs/labels.md)");
  }
  // A pixel's u_px and v_px: numbers, or both null (no pixel).
  Pixel pixel(const json& object, const std::string& path) const {
    if (member(object, path, "u_px").is_null() && member(object, path, "v_px").is_null()) return {};
    return {number(object, path, "u_px"), number(object, path, "v_px")};
  }

 private:
  std::filesystem::path file_;
};

}  // namespace

ImageLabels read_image_labels(const std::filesystem::path& file) {
  return parse_image_labels(read_input_file(file, kMaxLabelsFileBytes, "a labels file"), file);
}

ImageLabels parse_image_labels(std::string_view text, const std::filesystem::path& file) {
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {
    // A syntax error, or a number beyond double's range (1e400).
    std::string what = e.what();
    if (const auto bracket = what.find("] "); bracket != std::string::npos) what = what.substr(bracket + 2);
    throw std::runtime_error(file.string() + ": not JSON: " + what);
  }
  const Reader r(file);
  if (!root.is_object()) r.fail("(top level)", nullptr, "must be an object");
  const int format = r.integer(root, "", "labels_format", 0, 1000000);
  if (format != kLabelsFormatVersion) {
    r.fail("labels_format", &root["labels_format"], "must be " + std::to_string(kLabelsFormatVersion));
  }
  const json& render = r.object(root, "", "render");
  ImageLabels labels;
  const json& files = r.object(render, "render", "files");
  const json& image = r.member(files, "render.files", "image");
  // A name in the labels file's folder, as `purkinje render` writes it
  // (labels.h). A folder part ("../x.png", "/tmp/x.png", "a/x.png", found by
  // fuzzing) would read an image elsewhere, and two labels files naming
  // "a/x.png" and "b/x.png" would score under the same name, x.png.
  const auto plain_file_name = [](const std::string& name) {
    return !name.empty() && name != "." && name != ".." && name.find('/') == std::string::npos &&
           name.find('\0') == std::string::npos;  // the system would cut the name at a NUL
  };
  if (!image.is_string() || !plain_file_name(image.get<std::string>())) {
    r.fail("render.files.image", &image, "must be a file name in the labels file's folder, without a folder part");
  }
  labels.image = file.parent_path() / image.get<std::string>();
  labels.image_check = r.file_check(files, "render.files", "image");
  labels.bits = r.integer(r.object(render, "render", "sensor"), "render.sensor", "bits", 1, 16);
  const int camera = r.integer(render, "render", "camera", 0, 1000000);
  const json& cameras = r.array(root, "", "cameras");
  if (camera >= static_cast<int>(cameras.size())) r.fail("render.camera", &render["camera"], "names no camera");
  const std::string camera_path = "cameras[" + std::to_string(camera) + "]";
  labels.width_px = r.integer(cameras[camera], camera_path, "width_px", 1, 1 << 20);
  labels.height_px = r.integer(cameras[camera], camera_path, "height_px", 1, 1 << 20);
  const int lights = static_cast<int>(r.array(root, "", "illuminators").size());

  const json& views = r.array(root, "", "views");
  for (std::size_t i = 0; i < views.size(); ++i) {
    const std::string path = "views[" + std::to_string(i) + "]";
    const json& v = views[i];
    if (!v.is_object()) r.fail(path, &v, "must be an object");
    EyeInCameraTruth view;
    view.camera = r.integer(v, path, "camera", 0, 1000000);
    if (view.camera != camera) continue;  // another camera's
    view.eye = r.integer(v, path, "eye", 0, 1000000);
    const json& glints = r.array(v, path, "glints");
    for (std::size_t g = 0; g < glints.size(); ++g) {
      const std::string glint_path = path + ".glints[" + std::to_string(g) + "]";
      GlintTruth truth;
      truth.illuminator = r.integer(glints[g], glint_path, "illuminator", 0, lights - 1);
      truth.status = r.status(glints[g], glint_path);
      truth.pixel = r.pixel(glints[g], glint_path);
      view.glints.push_back(truth);
    }
    // Absent for an eye without a tear film in a scene without spectacle lenses.
    if (v.contains("distractors")) {
      const json& distractors = r.array(v, path, "distractors");
      for (std::size_t d = 0; d < distractors.size(); ++d) {
        const std::string distractor_path = path + ".distractors[" + std::to_string(d) + "]";
        DistractorTruth truth;
        const json& kind = r.member(distractors[d], distractor_path, "kind");
        bool known = false;
        for (const DistractorKind k : {DistractorKind::sclera, DistractorKind::tear_meniscus,
                                       DistractorKind::upper_tear_meniscus, DistractorKind::spectacle_lens_front,
                                       DistractorKind::spectacle_lens_back}) {
          if (kind == to_string(k)) {
            truth.kind = k;
            known = true;
          }
        }
        if (!known) {
          r.fail(distractor_path + ".kind", &kind,
                 "must be \"sclera\", \"tear_meniscus\", \"upper_tear_meniscus\", \"spectacle_lens_front\" or "
                 "\"spectacle_lens_back\"");
        }
        truth.illuminator = r.integer(distractors[d], distractor_path, "illuminator", 0, lights - 1);
        truth.status = r.status(distractors[d], distractor_path);
        truth.pixel = r.pixel(distractors[d], distractor_path);
        view.distractors.push_back(truth);
      }
    }
    const std::string pupil_path = path + ".pupil";
    const json& pupil = r.object(v, path, "pupil");
    const json& border = r.array(pupil, pupil_path, "border");
    for (std::size_t b = 0; b < border.size(); ++b) {
      const std::string point_path = pupil_path + ".border[" + std::to_string(b) + "]";
      PupilBorderPointTruth point;
      point.angle_rad = r.number(border[b], point_path, "angle_deg") * std::numbers::pi / 180;
      point.status = r.status(border[b], point_path);
      point.pixel = r.pixel(border[b], point_path);
      view.pupil.border.push_back(point);
    }
    const json& ellipse = r.member(pupil, pupil_path, "ellipse");
    if (!ellipse.is_null()) {
      const std::string e = pupil_path + ".ellipse";
      if (!ellipse.is_object()) r.fail(e, &ellipse, "must be an object or null");
      view.pupil.ellipse_valid = true;
      view.pupil.ellipse.center = {r.number(ellipse, e, "center_u_px"), r.number(ellipse, e, "center_v_px")};
      view.pupil.ellipse.semi_axis_1_px = r.number(ellipse, e, "semi_axis_1_px");
      view.pupil.ellipse.semi_axis_2_px = r.number(ellipse, e, "semi_axis_2_px");
      view.pupil.ellipse.angle_rad = r.number(ellipse, e, "angle_deg") * std::numbers::pi / 180;
      if (!(view.pupil.ellipse.semi_axis_1_px > 0 && view.pupil.ellipse.semi_axis_2_px > 0)) {
        r.fail(e + ".semi_axis_1_px", &ellipse["semi_axis_1_px"], "semi-axes must be positive");
      }
    }
    const json& centre = r.object(pupil, pupil_path, "refracted_center");
    view.pupil.refracted_center_status = r.status(centre, pupil_path + ".refracted_center");
    view.pupil.refracted_center = r.pixel(centre, pupil_path + ".refracted_center");
    labels.views.push_back(std::move(view));
  }
  return labels;
}

}  // namespace purkinje
