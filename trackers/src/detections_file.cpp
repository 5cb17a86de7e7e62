#include "purkinje/trackers/detections_file.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "purkinje/models/csv.h"
#include "purkinje/models/input_file.h"

namespace purkinje::trackers {

namespace {

// The cells of one CSV line (RFC 4180 quoting; no line breaks in cells).
// False when a quote is not closed.
// Spaces and tabs outside quotes are no part of a cell ("a.png, glint, 3",
// as CSV written by hand or by printf has them); inside quotes they are.
bool split_cells(const std::string& line, std::vector<std::string>& cells) {
  cells.assign(1, "");
  bool quoted = false, was_quoted = false;
  std::string pending;  // unquoted blanks, kept only if more of the cell follows
  const auto add = [&](char c) {
    cells.back() += pending;
    pending.clear();
    cells.back() += c;
  };
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        add('"'), ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        add(c);
      }
    } else if (c == '"') {
      quoted = was_quoted = true;
      pending.clear();
    } else if (c == ',') {
      cells.emplace_back();
      pending.clear();
      was_quoted = false;
    } else if (c == ' ' || c == '\t') {
      if (!cells.back().empty() || was_quoted) pending += c;
    } else {
      add(c);
    }
  }
  return !quoted;
}

// Whether a cell reads as the number -1 ("-1", "-1.0", "-1e0").
bool is_minus_one(const std::string& text) {
  double x = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), x);
  return !text.empty() && error == std::errc() && end == text.data() + text.size() && x == -1;
}

// A cell that says "no value" as trackers write it: empty, or nan.
bool says_nothing(const std::string& text) {
  return text.empty() || text == "nan" || text == "NaN" || text == "NAN" || text == "-nan";
}

enum Column { image, feature, u_px, v_px, illuminator, semi_axis_1_px, semi_axis_2_px, angle_deg, confidence, kColumns };
constexpr const char* kNames[kColumns] = {"image", "feature", "u_px", "v_px", "illuminator",
                                          "semi_axis_1_px", "semi_axis_2_px", "angle_deg", "confidence"};

class Row {
 public:
  Row(const std::filesystem::path& file, int line, const std::vector<std::string>& cells, const int* where)
      : file_(file), line_(line), cells_(cells), where_(where) {}

  [[noreturn]] void fail(Column c, const std::string& rule) const {
    throw std::runtime_error(file_.string() + ":" + std::to_string(line_) + ": column " + kNames[c] + " = \"" +
                             text(c) + "\": " + rule);
  }
  std::string text(Column c) const { return where_[c] >= 0 ? cells_[where_[c]] : std::string(); }
  bool empty(Column c) const { return text(c).empty(); }
  double number(Column c) const {
    const std::string t = text(c);
    double x = 0;
    const auto [end, error] = std::from_chars(t.data(), t.data() + t.size(), x);
    if (t.empty() || error != std::errc() || end != t.data() + t.size() || !std::isfinite(x)) {
      fail(c, "must be a finite number");
    }
    return x;
  }
  std::optional<double> optional_number(Column c) const {
    if (empty(c)) return std::nullopt;
    return number(c);
  }

 private:
  const std::filesystem::path& file_;
  int line_;
  const std::vector<std::string>& cells_;
  const int* where_;
};

}  // namespace

std::map<std::string, Detections> read_detections_csv(const std::filesystem::path& file) {
  return read_detections_file(file).images;
}

std::map<std::string, Detections> parse_detections_csv(const std::string& text, const std::filesystem::path& file) {
  return parse_detections_file(text, file).images;
}

DetectionsFile read_detections_file(const std::filesystem::path& file) {
  return parse_detections_file(read_input_file(file, kMaxDetectionsFileBytes, "a detections file"), file);
}

DetectionsFile parse_detections_file(std::string text, const std::filesystem::path& file) {
  // A UTF-8 byte-order mark, as spreadsheet programs write it, is no part
  // of the first column's name.
  if (text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);
  std::istringstream in(text);
  const auto fail = [&](int line, const std::string& what) {
    throw std::runtime_error(file.string() + ":" + std::to_string(line) + ": " + what);
  };
  DetectionsFile out;
  std::vector<std::string> cells;
  int where[kColumns];
  std::fill(where, where + kColumns, -1);
  std::size_t header_cells = 0;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;  // blank
    if (!split_cells(line, cells)) fail(number, "a quoted cell is not closed");
    if (header_cells == 0) {
      for (std::size_t i = 0; i < cells.size(); ++i) {
        const auto name = std::find_if(std::begin(kNames), std::end(kNames), [&](const char* n) { return cells[i] == n; });
        if (name == std::end(kNames)) {
          // Trackers write more than we read (timestamps, their own ids).
          out.ignored_columns.push_back(cells[i]);
          continue;
        }
        int& slot = where[name - std::begin(kNames)];
        if (slot >= 0) fail(number, "header: column \"" + cells[i] + "\" twice");
        slot = static_cast<int>(i);
      }
      for (const Column c : {image, feature, u_px, v_px}) {
        if (where[c] < 0) {
          fail(number, std::string("header: the column ") + kNames[c] +
                           " is missing (required: image, feature, u_px, v_px; optional: illuminator, "
                           "semi_axis_1_px, semi_axis_2_px, angle_deg, confidence)");
        }
      }
      header_cells = cells.size();
      continue;
    }
    if (cells.size() != header_cells) {
      fail(number, std::to_string(cells.size()) + " cells: the header has " + std::to_string(header_cells));
    }
    const Row row(file, number, cells, where);
    if (row.empty(image)) row.fail(image, "must name an image");
    const std::string name = row.text(image);
    out.line_of.emplace(name, number);
    Detections& d = out.images[name];
    const bool glint_row = row.text(feature) == "glint";
    if (!glint_row && row.text(feature) != "pupil") row.fail(feature, "must be glint or pupil");
    (glint_row ? out.has_glints : out.has_pupils) = true;
    // A failed frame, as trackers write it: no centre (empty or nan), or
    // (-1, -1). The image was read and nothing of this feature was found.
    const std::string u = row.text(u_px), v = row.text(v_px);
    if ((says_nothing(u) && says_nothing(v)) || (is_minus_one(u) && is_minus_one(v))) {
      ++out.failure_rows;
      continue;
    }
    if (says_nothing(u) != says_nothing(v)) row.fail(says_nothing(u) ? u_px : v_px, "must be a finite number like the other coordinate (both empty, both nan or both -1: nothing found)");
    const Pixel centre{row.number(u_px), row.number(v_px)};
    const std::optional<double> light = row.optional_number(illuminator);
    const std::optional<double> a = row.optional_number(semi_axis_1_px), b = row.optional_number(semi_axis_2_px),
                                angle = row.optional_number(angle_deg);
    // Confidence -1 is "none" in several toolkits. (Assigned, not chosen by
    // a conditional expression: g++ 12 warned falsely that the latter's
    // value may be used uninitialized.)
    std::optional<double> conf;
    if (!is_minus_one(row.text(confidence))) conf = row.optional_number(confidence);
    if (glint_row) {
      for (const Column c : {semi_axis_1_px, semi_axis_2_px, angle_deg}) {
        if (!row.empty(c)) row.fail(c, "is a pupil's column: leave it empty for a glint");
      }
      if (!row.empty(confidence) && !is_minus_one(row.text(confidence))) {
        row.fail(confidence, "is a pupil's column: leave it empty for a glint");
      }
      Glint g;
      g.centre = centre;
      if (light) {
        if (!(*light >= 0 && *light < 1e6 && *light == std::floor(*light))) {
          row.fail(illuminator, "must be a light's index, an integer from 0");
        }
        g.illuminator = static_cast<int>(*light);
      }
      d.glints.push_back(g);
    } else {
      if (light) row.fail(illuminator, "is a glint's column: leave it empty for a pupil");
      PupilFound p;
      p.centre = centre;
      if (a || b || angle) {
        if (!a || !(*a > 0)) row.fail(semi_axis_1_px, "must be a positive number (with the other two ellipse columns)");
        if (!b || !(*b > 0)) row.fail(semi_axis_2_px, "must be a positive number (with the other two ellipse columns)");
        if (!angle) row.fail(angle_deg, "must be a number (with the other two ellipse columns)");
        if (!(std::abs(*angle) <= 360)) row.fail(angle_deg, "must be in [-360, 360] degrees");
        p.ellipse = Ellipse{centre, *a, *b, *angle * std::numbers::pi / 180};
      }
      if (conf) {
        if (!(*conf >= 0 && *conf <= 1)) row.fail(confidence, "must be in [0, 1], or -1 for none");
        p.confidence = *conf;
      }
      d.pupils.push_back(p);
    }
  }
  if (header_cells == 0) throw std::runtime_error(file.string() + ": empty: a header row is needed");
  return out;
}

namespace {

// The shortest text that reads back as the same number: scoring the file
// gives the same figures as scoring the detections.
std::string exact(double x) {
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, x).ptr;
  return std::string(buffer, end);
}

}  // namespace

std::string detections_csv(const std::map<std::string, Detections>& detections) {
  std::ostringstream out;
  out << "image,feature,u_px,v_px,illuminator,semi_axis_1_px,semi_axis_2_px,angle_deg,confidence\n";
  for (const auto& [image_name, d] : detections) {
    for (const Glint& g : d.glints) {
      out << csv_cell(image_name) << ",glint," << exact(g.centre.u) << ',' << exact(g.centre.v) << ',';
      if (g.illuminator >= 0) out << g.illuminator;
      out << ",,,,\n";
    }
    for (const PupilFound& p : d.pupils) {
      out << csv_cell(image_name) << ",pupil," << exact(p.centre.u) << ',' << exact(p.centre.v) << ",,";
      if (p.ellipse) {
        out << exact(p.ellipse->semi_axis_1_px) << ',' << exact(p.ellipse->semi_axis_2_px) << ','
            << exact(p.ellipse->angle_rad * 180 / std::numbers::pi);
      } else {
        out << ",,";
      }
      out << ',';
      if (p.confidence) out << exact(*p.confidence);
      out << '\n';
    }
  }
  return out.str();
}

}  // namespace purkinje::trackers
