#include "purkinje/studies/track.h"

#include <chrono>
#include <filesystem>
#include <iterator>
#include <sstream>
#include <stdexcept>

#include "purkinje/models/spelling.h"
#include "purkinje/studies/tracker.h"

namespace purkinje::studies {

namespace fs = std::filesystem;

TrackedSet track_images(const std::vector<LabelledImage>& images, const Scene* rig, const std::string& rig_file,
                        const trackers::ScoringSettings& settings, const std::function<void()>& step) {
  TrackedSet out;
  trackers::Scorer scorer(settings);
  const Tracker default_tracker;
  std::map<int, Tracker> by_camera;
  for (const LabelledImage& image : images) {
    const trackers::GreyImage pixels = read_pixels(image);
    const Tracker* tracker = &default_tracker;
    if (rig && !image.labels.views.empty()) {
      const int camera = image.labels.views.front().camera;
      if (camera >= static_cast<int>(rig->cameras.size()) || rig->eyes.empty() ||
          image.labels.views.front().glints.size() != rig->illuminators.size()) {
        throw std::runtime_error(image.labels.image.string() + ": its labels' camera " + std::to_string(camera) +
                                 " and lights do not match " + rig_file);
      }
      tracker = &by_camera.try_emplace(camera, rig->cameras[camera], rig->illuminators, rig->eyes.front())
                     .first->second;
    }
    const auto start = std::chrono::steady_clock::now();
    trackers::Detections found = tracker->track(pixels.view());
    out.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    scorer.add(image.name, image.labels.views, found);
    out.detections[image.name] = std::move(found);
    if (step) step();
  }
  out.score = scorer.score();
  return out;
}

namespace {

// The labelled image a detections file's name means: the image's file
// name itself, a path ending in it (trackers write where they read), or
// its name without the extension; empty when none or several match.
std::string resolve_image(const std::string& name, const std::map<std::string, std::string>& by_name,
                          const std::multimap<std::string, std::string>& by_stem, bool& ambiguous) {
  ambiguous = false;
  if (by_name.count(name)) return name;
  const fs::path path(name);
  if (by_name.count(path.filename().string())) return path.filename().string();
  const auto [first, last] = by_stem.equal_range(path.filename().string());
  if (first != last && std::next(first) == last) return first->second;
  ambiguous = first != last;
  return {};
}

}  // namespace

ScoredSet score_detections(const std::vector<LabelledImage>& images, const trackers::DetectionsFile& file,
                           const std::string& file_name, trackers::ScoringSettings settings, double min_confidence) {
  ScoredSet out;
  std::map<std::string, std::string> by_name;
  std::multimap<std::string, std::string> by_stem;
  for (const LabelledImage& image : images) {
    by_name[image.name] = image.name;
    by_stem.emplace(fs::path(image.name).stem().string(), image.name);
  }
  std::map<std::string, std::string> named_as;  // labelled image -> the file's name for it
  int skipped_images = 0, below_confidence = 0;
  std::string first_skipped;
  for (const auto& [name, found] : file.images) {
    bool ambiguous = false;
    const std::string image = resolve_image(name, by_name, by_stem, ambiguous);
    if (image.empty()) {
      if (skipped_images++ == 0) {
        first_skipped = name + " (line " + std::to_string(file.line_of.at(name)) + ")" +
                        (ambiguous ? ": its name without extension is several images'" : "");
      }
      continue;
    }
    if (const auto [it, fresh] = named_as.emplace(image, name); !fresh) {
      throw std::runtime_error(file_name + ": lines " + std::to_string(file.line_of.at(it->second)) + " (" +
                               it->second + ") and " + std::to_string(file.line_of.at(name)) + " (" + name +
                               ") both name the labelled image " + image);
    }
    trackers::Detections& d = out.detections[image];
    d.glints.insert(d.glints.end(), found.glints.begin(), found.glints.end());
    for (const trackers::PupilFound& p : found.pupils) {
      if (p.confidence && *p.confidence < min_confidence) {
        ++below_confidence;
        continue;
      }
      d.pupils.push_back(p);
    }
  }
  if (!file.ignored_columns.empty()) {
    std::string line = "columns not read:";
    for (const std::string& c : file.ignored_columns) {
      line += " " + c;
      // A misspelt optional column would silently read as absent.
      if (const auto meant = closest_match(c, {"image", "feature", "u_px", "v_px", "illuminator", "semi_axis_1_px",
                                               "semi_axis_2_px", "angle_deg", "confidence"})) {
        line += " (did you mean " + *meant + "?)";
      }
    }
    out.notes.push_back(line);
  }
  if (file.failure_rows > 0) {
    out.notes.push_back(std::to_string(file.failure_rows) + " rows say nothing was found (failed frames)");
  }
  if (below_confidence > 0) {
    std::ostringstream threshold;  // as the command line printed it
    threshold << min_confidence;
    out.notes.push_back(std::to_string(below_confidence) + " pupils below --min-confidence " + threshold.str() +
                        " left out");
  }
  if (skipped_images > 0) {
    out.notes.push_back(std::to_string(skipped_images) +
                        " images of the detections file are not among the labelled ones and were left out, the "
                        "first " +
                        first_skipped);
  }
  if (!file.has_glints) out.notes.push_back("no glint rows: glints not scored");
  if (!file.has_pupils) out.notes.push_back("no pupil rows: pupils not scored");

  settings.score_glints = file.has_glints;
  settings.score_pupils = file.has_pupils;
  trackers::Scorer scorer(settings);
  const trackers::Detections none;
  for (const LabelledImage& image : images) {
    const auto found = out.detections.find(image.name);
    scorer.add(image.name, image.labels.views, found == out.detections.end() ? none : found->second);
  }
  out.score = scorer.score();
  return out;
}

}  // namespace purkinje::studies
