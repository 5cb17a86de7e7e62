// `purkinje track` and `purkinje score`: detectors run over a labelled image
// set, or another tracker's detections read, and scored against the labels.
// Documented in docs/cli.md.

#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.h"
#include "output_checks.h"
#include "progress.h"
#include "purkinje/models/output_file.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/studies/image_set.h"
#include "purkinje/studies/track.h"
#include "purkinje/trackers/detections_file.h"
#include "purkinje/trackers/image_file.h"
#include "purkinje/trackers/scoring.h"

namespace purkinje::tools {
namespace {

namespace fs = std::filesystem;

using studies::LabelledImage;

// The labelled images the inputs name, with a progress line; notes on
// files left out go to stderr.
std::vector<LabelledImage> read_labels(const std::vector<std::string>& inputs, bool quiet) {
  const std::vector<fs::path> files =
      studies::labels_files(inputs, [](const std::string& note) { std::cerr << note << "\n"; });
  Progress progress("reading labels", files.size(), quiet);
  return studies::read_labelled_images(files, [&] { progress.step(); });
}

// The output folder may not be an input folder (or the folder of a labels
// file or image given), nor hold the command's inputs under the names of
// its outputs.
std::optional<Refusal> check_outputs(const ScoreOutput& request, std::vector<std::string> files,
                                     const std::vector<fs::path>& inputs) {
  std::vector<fs::path> input_folders;
  for (const std::string& input : request.inputs) {
    const fs::path path(input);
    std::error_code ec;
    input_folders.push_back(fs::is_directory(path, ec) ? path : path.parent_path().empty() ? "." : path.parent_path());
  }
  for (const char* name : {"score.txt", "score.csv", "score.json"}) files.emplace_back(name);
  std::vector<fs::path> given;
  for (const fs::path& input : inputs) {
    if (!input.empty()) given.push_back(input);
  }
  return check_output_folder(request.output_dir, input_folders, files, given);
}

// Writes the score's files, the detections (when given) and the worst
// images' overlays into the output folder, each file all or nothing, and
// prints the table. The overlays' images are read before anything is
// written, so that a missing image writes nothing.
int write_outputs(const char* command, const ScoreOutput& request, const trackers::Score& score,
                  const std::map<std::string, trackers::Detections>& detections,
                  const std::vector<LabelledImage>& images, bool with_detections) {
  struct Overlay {
    const LabelledImage* image;
    trackers::GreyImage pixels;
  };
  std::vector<Overlay> overlays;
  try {
    for (const std::string& name : trackers::worst_images(score, request.overlays)) {
      const auto it =
          std::find_if(images.begin(), images.end(), [&](const LabelledImage& i) { return i.name == name; });
      overlays.push_back({&*it, studies::read_pixels(*it)});
    }
  } catch (const std::exception& error) {
    std::cerr << "purkinje " << command << ": error: " << error.what() << "\n";
    return kBadInput;
  }
  const fs::path dir(request.output_dir);
  const std::string table = trackers::score_table(score);
  try {
    std::error_code ec;
    fs::create_directories(dir / "overlays", ec);
    if (ec) throw std::runtime_error(dir.string() + ": cannot create the output folder: " + ec.message());
    write_file_atomically(dir / "score.txt", table);
    write_file_atomically(dir / "score.csv", trackers::score_csv(score));
    write_file_atomically(dir / "score.json", trackers::score_json(score));
    if (with_detections) write_file_atomically(dir / "detections.csv", trackers::detections_csv(detections));
    const trackers::Detections none;
    for (const Overlay& o : overlays) {
      const auto found = detections.find(o.image->name);
      trackers::write_overlay(dir / "overlays" / fs::path(o.image->name).replace_extension(".png"), o.pixels,
                              o.image->labels.views, found == detections.end() ? none : found->second);
    }
  } catch (const std::exception& error) {
    std::cerr << "purkinje " << command << ": error: " << error.what() << "\n";
    return kOutputError;
  }
  std::cout << table << "\nwrote " << (dir / "score.txt").string() << ", score.csv, score.json"
            << (with_detections ? ", detections.csv" : "") << " and " << overlays.size()
            << " overlays (the worst images)\n";
  return kOk;
}

}  // namespace

int run_track(const TrackRequest& request) {
  if (const auto refusal = check_outputs(request, {"detections.csv"}, {request.scene_file})) {
    std::cerr << "purkinje track: error: " << refusal->message << "\n";
    return refusal->exit_code;
  }
  std::vector<LabelledImage> images;
  std::optional<Scene> rig;
  try {
    images = read_labels(request.inputs, request.quiet);
    if (!request.scene_file.empty()) rig = load_scene(request.scene_file);
  } catch (const std::exception& error) {
    std::cerr << "purkinje track: error: " << error.what() << "\n";
    return kBadInput;
  }
  trackers::ScoringSettings settings;
  settings.match_radius_px = request.match_radius_px;
  settings.min_pupil_overlap = request.min_pupil_overlap;
  studies::TrackedSet tracked;
  try {
    Progress progress("track", images.size(), request.quiet);
    tracked = studies::track_images(images, rig ? &*rig : nullptr, request.scene_file, settings,
                                    [&] { progress.step(); });
  } catch (const std::exception& error) {
    std::cerr << "purkinje track: error: " << error.what() << "\n";
    return kBadInput;
  }
  std::cout << "tracked " << images.size() << " images: glints and pupil in " << std::fixed << std::setprecision(2)
            << (images.empty() ? 0.0 : 1e3 * tracked.seconds / images.size()) << " ms per image on average"
            << (rig ? "" : "; no --scene: glints not identified") << "\n"
            << std::defaultfloat;
  return write_outputs("track", request, tracked.score, tracked.detections, images, true);
}

int run_score(const ScoreRequest& request) {
  if (const auto refusal = check_outputs(request, {}, {request.detections_file})) {
    std::cerr << "purkinje score: error: " << refusal->message << "\n";
    return refusal->exit_code;
  }
  std::vector<LabelledImage> images;
  trackers::DetectionsFile file;
  try {
    images = read_labels(request.inputs, request.quiet);
    file = trackers::read_detections_file(request.detections_file);
  } catch (const std::exception& error) {
    std::cerr << "purkinje score: error: " << error.what() << "\n";
    return kBadInput;
  }
  trackers::ScoringSettings settings;
  settings.match_radius_px = request.match_radius_px;
  settings.min_pupil_overlap = request.min_pupil_overlap;
  studies::ScoredSet scored;
  try {
    scored = studies::score_detections(images, file, request.detections_file, settings, request.min_confidence);
  } catch (const std::exception& error) {
    std::cerr << "purkinje score: error: " << error.what() << "\n";
    return kBadInput;
  }
  for (const std::string& note : scored.notes) std::cerr << note << "\n";
  return write_outputs("score", request, scored.score, scored.detections, images, false);
}

}  // namespace purkinje::tools
