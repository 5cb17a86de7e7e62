// `purkinje track` and `purkinje score`: detectors run over a labelled image
// set, or another tracker's detections read, and scored against the labels.
// Documented in docs/cli.md.

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.h"
#include "output_checks.h"
#include "progress.h"
#include "purkinje/models/input_file.h"
#include "purkinje/models/labels.h"
#include "purkinje/models/output_file.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/models/spelling.h"
#include "purkinje/studies/tracker.h"
#include "purkinje/trackers/detections_file.h"
#include "purkinje/trackers/image_file.h"
#include "purkinje/trackers/scoring.h"

namespace purkinje::tools {
namespace {

namespace fs = std::filesystem;

struct LabelledImage {
  std::string name;  // the image's file name: how detections files name it
  ImageLabels labels;
};

// The labels files the inputs name: a labels file itself, an image beside
// its labels (same name, .json), or a folder (its .json files that have
// an image of the same name beside them, in order: a score.json or any
// other JSON file in the folder is no image's labels).
std::vector<fs::path> labels_files(const std::vector<std::string>& inputs) {
  std::vector<fs::path> files;
  for (const std::string& input : inputs) {
    const fs::path path(input);
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
      std::vector<fs::path> in_folder;
      std::set<fs::path> image_stems;
      for (const fs::directory_entry& e : fs::directory_iterator(path)) {
        if (!e.is_regular_file()) continue;
        const fs::path extension = e.path().extension();
        if (extension == ".json") in_folder.push_back(e.path());
        if (extension == ".png" || extension == ".tif" || extension == ".tiff" || extension == ".pgm") {
          image_stems.insert(e.path().stem());
        }
      }
      std::vector<std::string> left_out;
      std::erase_if(in_folder, [&](const fs::path& f) {
        const bool labels = image_stems.count(f.stem()) > 0;
        if (!labels) left_out.push_back(f.filename().string());
        return !labels;
      });
      if (in_folder.empty()) {
        throw std::runtime_error(input + ": a folder without labels files (.json beside an image of the same name)");
      }
      if (!left_out.empty()) {
        std::sort(left_out.begin(), left_out.end());
        std::cerr << input << ": " << left_out.size() << " .json files without an image beside them left out ("
                  << left_out.front() << (left_out.size() > 1 ? ", ..." : "") << ")\n";
      }
      std::sort(in_folder.begin(), in_folder.end());
      files.insert(files.end(), in_folder.begin(), in_folder.end());
    } else if (path.extension() == ".json") {
      files.push_back(path);
    } else {
      files.push_back(fs::path(path).replace_extension(".json"));
    }
  }
  return files;
}

std::vector<LabelledImage> read_labels(const std::vector<std::string>& inputs, bool quiet) {
  std::vector<LabelledImage> images;
  std::map<std::string, fs::path> seen;
  const std::vector<fs::path> files = labels_files(inputs);
  Progress progress("reading labels", files.size(), quiet);
  for (const fs::path& file : files) {
    LabelledImage image{"", read_image_labels(file)};
    image.name = image.labels.image.filename().string();
    // The image's size against its labels' record, for every command: a
    // unit a killed run left half replaced is refused even where the
    // pixels are not read (score). track checks the CRC-32 too.
    if (image.labels.image_check) {
      std::error_code ec;
      const std::uintmax_t bytes = fs::file_size(image.labels.image, ec);
      if (!ec && bytes != image.labels.image_check->bytes) {
        throw std::runtime_error(image.labels.image.string() + ": does not match its labels (" + std::to_string(bytes) +
                                 " bytes; the labels say " + std::to_string(image.labels.image_check->bytes) +
                                 "): a unit a run left half replaced; render it again (render --resume)");
      }
    }
    const auto [it, fresh] = seen.emplace(image.name, file);
    if (!fresh) {
      throw std::runtime_error(file.string() + ": labels an image named " + image.name + ", as " +
                               it->second.string() + " does: image names must differ");
    }
    images.push_back(std::move(image));
    progress.step();
  }
  return images;
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

trackers::GreyImage read_image(const LabelledImage& image) {
  // Labels record their image's size and CRC-32: an image that differs is
  // another run's (a run killed between renaming an image and its labels).
  if (image.labels.image_check) {
    const FileCheck found =
        file_check_of(read_input_file(image.labels.image, kMaxImageFileBytes, "an image file"));
    if (found != *image.labels.image_check) {
      throw std::runtime_error(image.labels.image.string() + ": does not match its labels (" +
                               std::to_string(found.bytes) + " bytes, CRC-32 " + crc32_text(found.crc32) +
                               "; the labels say " + std::to_string(image.labels.image_check->bytes) + " bytes, " +
                               crc32_text(image.labels.image_check->crc32) +
                               "): a unit a run left half replaced; render it again (render --resume)");
    }
  }
  trackers::GreyImage pixels = trackers::read_grey_image(image.labels.image, image.labels.bits);
  if (pixels.width != image.labels.width_px || pixels.height != image.labels.height_px) {
    throw std::runtime_error(image.labels.image.string() + ": " + std::to_string(pixels.width) + " x " +
                             std::to_string(pixels.height) + " pixels; its labels say " +
                             std::to_string(image.labels.width_px) + " x " + std::to_string(image.labels.height_px));
  }
  return pixels;
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
      const auto it = std::find_if(images.begin(), images.end(), [&](const LabelledImage& i) { return i.name == name; });
      overlays.push_back({&*it, read_image(*it)});
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
            << (with_detections ? ", detections.csv" : "") << " and " << overlays.size() << " overlays (the worst images)\n";
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
  trackers::Scorer scorer(settings);
  std::map<std::string, trackers::Detections> detections;
  // Without a rig, the detectors' defaults; with one, a tracker per camera
  // that knows its optics and which light makes which glint.
  const studies::Tracker default_tracker;
  std::map<int, studies::Tracker> trackers_by_camera;
  double seconds = 0;
  try {
    Progress progress("track", images.size(), request.quiet);
    for (const LabelledImage& image : images) {
      const trackers::GreyImage pixels = read_image(image);
      const studies::Tracker* tracker = &default_tracker;
      if (rig && !image.labels.views.empty()) {
        const int camera = image.labels.views.front().camera;
        if (camera >= static_cast<int>(rig->cameras.size()) || rig->eyes.empty() ||
            image.labels.views.front().glints.size() != rig->illuminators.size()) {
          throw std::runtime_error(image.labels.image.string() + ": its labels' camera " + std::to_string(camera) +
                                   " and lights do not match " + request.scene_file);
        }
        tracker = &trackers_by_camera.try_emplace(camera, rig->cameras[camera], rig->illuminators, rig->eyes.front())
                       .first->second;
      }
      const auto start = std::chrono::steady_clock::now();
      trackers::Detections found = tracker->track(pixels.view());
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      scorer.add(image.name, image.labels.views, found);
      detections[image.name] = std::move(found);
      progress.step();
    }
  } catch (const std::exception& error) {
    std::cerr << "purkinje track: error: " << error.what() << "\n";
    return kBadInput;
  }
  std::cout << "tracked " << images.size() << " images: glints and pupil in " << std::fixed << std::setprecision(2)
            << (images.empty() ? 0.0 : 1e3 * seconds / images.size()) << " ms per image on average"
            << (rig ? "" : "; no --scene: glints not identified") << "\n"
            << std::defaultfloat;
  return write_outputs("track", request, scorer.score(), detections, images, true);
}

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
  std::map<std::string, std::string> by_name;
  std::multimap<std::string, std::string> by_stem;
  for (const LabelledImage& image : images) {
    by_name[image.name] = image.name;
    by_stem.emplace(fs::path(image.name).stem().string(), image.name);
  }
  // Rows of images outside the inputs are left out, not fatal: a tracker
  // run over a whole folder is scored on the part that is labelled.
  std::map<std::string, trackers::Detections> detections;
  std::map<std::string, std::string> named_as;  // labelled image -> the file's name for it
  int skipped_images = 0, below_confidence = 0;
  std::string first_skipped;
  for (auto& [name, found] : file.images) {
    bool ambiguous = false;
    const std::string image = resolve_image(name, by_name, by_stem, ambiguous);
    if (image.empty()) {
      if (skipped_images++ == 0) {
        first_skipped = name + " (line " + std::to_string(file.line_of.at(name)) + ")" +
                        (ambiguous ? ": its name without extension is several images'" : "");
      }
      continue;
    }
    // Two names for one image (cam0/f1.png and cam1/f1.png) would merge
    // two images' detections.
    if (const auto [it, fresh] = named_as.emplace(image, name); !fresh) {
      std::cerr << "purkinje score: error: " << request.detections_file << ": lines "
                << file.line_of.at(it->second) << " (" << it->second << ") and " << file.line_of.at(name) << " ("
                << name << ") both name the labelled image " << image << "\n";
      return kBadInput;
    }
    trackers::Detections& d = detections[image];
    d.glints.insert(d.glints.end(), found.glints.begin(), found.glints.end());
    for (const trackers::PupilFound& p : found.pupils) {
      if (p.confidence && *p.confidence < request.min_confidence) {
        ++below_confidence;
        continue;
      }
      d.pupils.push_back(p);
    }
  }
  std::ostringstream notes;
  if (!file.ignored_columns.empty()) {
    notes << "columns not read:";
    for (const std::string& c : file.ignored_columns) {
      notes << " " << c;
      // A misspelt optional column would silently read as absent.
      if (const auto meant = closest_match(c, {"image", "feature", "u_px", "v_px", "illuminator", "semi_axis_1_px",
                                               "semi_axis_2_px", "angle_deg", "confidence"})) {
        notes << " (did you mean " << *meant << "?)";
      }
    }
    notes << "\n";
  }
  if (file.failure_rows > 0) notes << file.failure_rows << " rows say nothing was found (failed frames)\n";
  if (below_confidence > 0) {
    notes << below_confidence << " pupils below --min-confidence " << request.min_confidence << " left out\n";
  }
  if (skipped_images > 0) {
    notes << skipped_images << " images of the detections file are not among the labelled ones and were left out, "
          << "the first " << first_skipped << "\n";
  }
  if (!file.has_glints) notes << "no glint rows: glints not scored\n";
  if (!file.has_pupils) notes << "no pupil rows: pupils not scored\n";
  std::cerr << notes.str();

  trackers::ScoringSettings settings;
  settings.match_radius_px = request.match_radius_px;
  settings.min_pupil_overlap = request.min_pupil_overlap;
  settings.score_glints = file.has_glints;
  settings.score_pupils = file.has_pupils;
  trackers::Scorer scorer(settings);
  const trackers::Detections none;
  for (const LabelledImage& image : images) {
    const auto found = detections.find(image.name);
    scorer.add(image.name, image.labels.views, found == detections.end() ? none : found->second);
  }
  return write_outputs("score", request, scorer.score(), detections, images, false);
}

}  // namespace purkinje::tools
