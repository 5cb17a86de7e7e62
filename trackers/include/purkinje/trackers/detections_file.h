#pragma once
// Detections as CSV, the format another tracker's output is scored from
// (`purkinje score --detections FILE.csv`) and `purkinje track` writes its
// own in (docs/trackers.md, "Detections files"):
//
//   image,feature,u_px,v_px,illuminator,semi_axis_1_px,semi_axis_2_px,angle_deg,confidence
//   eye_0001.png,glint,316.62,239.55,0,,,,
//   eye_0001.png,pupil,317.66,234.93,,10.05,9.84,-21.9,0.97
//
// A header row names the columns, in any order; image, feature (glint or
// pupil), u_px and v_px are required, the others may be left out or left
// empty. illuminator is a glint's light (from 0); the ellipse (all three
// of its columns, angle of semi-axis 1 from +u toward +v) and confidence
// (in [0, 1]) are a pupil's. Pixel centres sit at integer coordinates.

#include <filesystem>
#include <map>
#include <string>

#include "purkinje/trackers/scoring.h"

namespace purkinje::trackers {

// By image (as the file names it). Throws std::runtime_error naming the
// file, the line, the column, its text and the rule for a malformed file.
// Regular files of at most kMaxDetectionsFileBytes only (input_file.h).
std::map<std::string, Detections> read_detections_csv(const std::filesystem::path& file);
// The same from the file's text; `file` names it in messages.
std::map<std::string, Detections> parse_detections_csv(const std::string& text, const std::filesystem::path& file);

// The same format, all nine columns, images in the map's order.
std::string detections_csv(const std::map<std::string, Detections>& detections);

}  // namespace purkinje::trackers
