#pragma once
// Ground-truth labels as files: JSON (the complete record) and CSV (one row
// per image feature, for pandas). Every field, its unit and frame are
// documented in docs/labels.md. No NaN is ever written: a value that does
// not exist for a feature's status is null in JSON and empty in CSV.

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "purkinje/models/input_file.h"
#include "purkinje/models/scene.h"
#include "purkinje/models/truth.h"

namespace purkinje {

inline constexpr int kLabelsFormatVersion = 1;

// The scene (cameras, illuminators, eyes) and its truth as pretty-printed
// JSON, ending in a newline. `truth` must have been computed from `scene`.
std::string truth_to_json(const Scene& scene, const SceneTruth& truth);

// One row per glint, pupil-border point, pupil centre (refracted and
// straight), pupil ellipse, cornea centre and rotation centre, per
// (camera, eye); a header row first.
std::string truth_to_csv(const Scene& scene, const SceneTruth& truth);

// One rendered image's labels file, as `purkinje render` writes it beside
// the image (docs/labels.md), read back for scoring detectors.
struct ImageLabels {
  std::filesystem::path image;  // the image file, in the labels file's folder
  // What the image file must be (size, CRC-32) for these labels to be its
  // own; absent in labels written before the check was.
  std::optional<FileCheck> image_check;
  int width_px = 0, height_px = 0;
  int bits = 8;  // the sensor's significant bits (a PNG of more than 8 keeps them in its words' high bits)
  // The views of this image's camera. Only the image-plane fields are
  // read: each glint's and distractor's illuminator, status and pixel (and
  // a distractor's kind); the pupil's ellipse,
  // each border point's status and the refracted centre's status and
  // pixel; the 3D paths are left empty.
  std::vector<EyeInCameraTruth> views;
};

// Throws std::runtime_error naming the file, the key, its value and the
// rule when the file cannot be read or is not a labels file of this format.
// Regular files of at most kMaxLabelsFileBytes only (input_file.h).
ImageLabels read_image_labels(const std::filesystem::path& file);
// The same from the file's text; `file` names it in messages and is the
// folder the image is looked for in.
ImageLabels parse_image_labels(std::string_view text, const std::filesystem::path& file);

}  // namespace purkinje
