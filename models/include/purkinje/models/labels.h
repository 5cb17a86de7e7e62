#pragma once
// Ground-truth labels as files: JSON (the complete record) and CSV (one row
// per image feature, for pandas). Every field, its unit and frame are
// documented in docs/labels.md. No NaN is ever written: a value that does
// not exist for a feature's status is null in JSON and empty in CSV.

#include <filesystem>
#include <string>

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

// Writes `contents` to a temporary file in the same directory, flushes it
// to disk and renames it over `file`, so readers see the old file or the
// whole new one, never a part. Throws std::runtime_error naming the path
// and the system's reason; no temporary file is left behind.
void write_file_atomically(const std::filesystem::path& file, const std::string& contents);

}  // namespace purkinje
