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
#include <vector>

#include "purkinje/trackers/scoring.h"

namespace purkinje::trackers {

// A detections file as read. Trackers write files differently, and the
// reader takes what they write (docs/trackers.md, "Detections files"):
// a UTF-8 byte-order mark, spaces around cells, columns it does not know
// (ignored and listed), failure rows (no centre: u_px and v_px both empty,
// both nan, or both -1: the image was read and nothing of that feature
// found), and confidence -1 ("none").
struct DetectionsFile {
  std::map<std::string, Detections> images;  // by the name the file gives, failure rows' images included
  std::map<std::string, int> line_of;        // each image's first line
  std::vector<std::string> ignored_columns;  // header columns not read
  int failure_rows = 0;
  bool has_glints = false, has_pupils = false;  // rows (failure rows too) of each feature
};
DetectionsFile read_detections_file(const std::filesystem::path& file);
DetectionsFile parse_detections_file(std::string text, const std::filesystem::path& file);

// By image (as the file names it). Throws std::runtime_error naming the
// file, the line, the column, its text and the rule for a malformed file.
// Regular files of at most kMaxDetectionsFileBytes only (input_file.h).
std::map<std::string, Detections> read_detections_csv(const std::filesystem::path& file);
// The same from the file's text; `file` names it in messages.
std::map<std::string, Detections> parse_detections_csv(const std::string& text, const std::filesystem::path& file);

// The same format, all nine columns, images in the map's order.
std::string detections_csv(const std::map<std::string, Detections>& detections);

}  // namespace purkinje::trackers
