// `purkinje track` and `purkinje score`: detectors run over a labelled image
// set, or another tracker's detections read, and scored against the labels.
// Documented in docs/cli.md.

#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli.h"
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

struct ScoreOutput {
  std::vector<std::string> inputs;  // labels files, images beside their labels, or folders of them
  std::string output_dir;
  int overlays = 10;               // the worst this many images, drawn
  double match_radius_px = 5;
  double min_pupil_overlap = 0.5;  // a pupil's ellipse, when given, must overlap the label's this much
  bool quiet = false;  // no progress on stderr
};

struct TrackRequest : ScoreOutput {
  std::string scene_file;  // the tracker's rig and nominal eye, for glint identity (empty: none)
};

struct ScoreRequest : ScoreOutput {
  std::string detections_file;
  double min_confidence = 0;  // pupils reported less confident are left out
};

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
int write_outputs(const ScoreOutput& request, const trackers::Score& score,
                  const std::map<std::string, trackers::Detections>& detections,
                  const std::vector<LabelledImage>& images, bool with_detections) {
  struct Overlay {
    const LabelledImage* image;
    trackers::GreyImage pixels;
  };
  std::vector<Overlay> overlays;
  for (const std::string& name : trackers::worst_images(score, request.overlays)) {
    const auto it = std::find_if(images.begin(), images.end(), [&](const LabelledImage& i) { return i.name == name; });
    overlays.push_back({&*it, studies::read_pixels(*it)});
  }
  const fs::path dir(request.output_dir);
  const std::string table = trackers::score_table(score);
  writing([&] {
    create_output_folder(dir);
    create_output_folder(dir / "overlays");
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
  });
  std::cout << table << "\nwrote " << (dir / "score.txt").string() << ", score.csv, score.json"
            << (with_detections ? ", detections.csv" : "") << " and " << overlays.size()
            << " overlays (the worst images)\n";
  return kOk;
}

trackers::ScoringSettings scoring_settings(const ScoreOutput& request) {
  trackers::ScoringSettings settings;
  settings.match_radius_px = request.match_radius_px;
  settings.min_pupil_overlap = request.min_pupil_overlap;
  return settings;
}

int run_track(const TrackRequest& request) {
  refuse(check_outputs(request, {"detections.csv"}, {request.scene_file}));
  const std::vector<LabelledImage> images = read_labels(request.inputs, request.quiet);
  std::optional<Scene> rig;
  if (!request.scene_file.empty()) rig = load_scene(request.scene_file);
  studies::TrackedSet tracked;
  {
    Progress progress("track", images.size(), request.quiet);  // its last line cleared before the summary
    tracked = studies::track_images(images, rig ? &*rig : nullptr, request.scene_file, scoring_settings(request),
                                    [&] { progress.step(); });
  }
  std::cout << "tracked " << images.size() << " images: glints and pupil in " << std::fixed << std::setprecision(2)
            << (images.empty() ? 0.0 : 1e3 * tracked.seconds / images.size()) << " ms per image on average"
            << (rig ? "" : "; no --scene: glints not identified") << "\n"
            << std::defaultfloat;
  return write_outputs(request, tracked.score, tracked.detections, images, true);
}

int run_score(const ScoreRequest& request) {
  refuse(check_outputs(request, {}, {request.detections_file}));
  const std::vector<LabelledImage> images = read_labels(request.inputs, request.quiet);
  const trackers::DetectionsFile file = trackers::read_detections_file(request.detections_file);
  const studies::ScoredSet scored =
      studies::score_detections(images, file, request.detections_file, scoring_settings(request), request.min_confidence);
  for (const std::string& note : scored.notes) std::cerr << note << "\n";
  return write_outputs(request, scored.score, scored.detections, images, false);
}

// The inputs and outputs `track` and `score` share.
void add_score_output_options(CLI::App& command, ScoreOutput& request) {
  command.add_option("INPUTS", request.inputs, "Labels files, images or folders")->required();
  command.add_option("-o,--output", request.output_dir, "Output folder (created if missing)")->required();
  command.add_option("--overlays", request.overlays, "Draw this many of the worst images")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  command.add_flag("--quiet", request.quiet, "No progress on standard error");
  command.add_option("--min-pupil-overlap", request.min_pupil_overlap,
                     "A pupil given with its ellipse is found only if that ellipse overlaps the label's\n"
                     "by this much (intersection over union; 0: centres only)")
      ->check(kFinite)
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  command.add_option("--match-radius", request.match_radius_px,
                     "A detection within this many pixels of a label is paired with it")
      ->check(kFinite)
      ->check(CLI::Range(0.001, 1000.0))
      ->capture_default_str();
}

}  // namespace

Command add_track_command(CLI::App& app) {
  auto request = std::make_shared<TrackRequest>();
  CLI::App* track =
      app.add_subcommand("track", "Run purkinje's glint and pupil detectors over labelled images and score them");
  track->footer(std::string("INPUTS are labels files (.json, as purkinje render writes them), images beside\n"
                            "their labels, or folders of them. Writes DIR/score.txt, score.csv, score.json,\n"
                            "detections.csv and overlays/ (docs/cli.md, docs/trackers.md).\n\n") +
                kExitCodes);
  add_score_output_options(*track, *request);
  track->add_option("--scene", request->scene_file,
                    "Scene file of the tracker's rig and nominal eye: glints are identified\n"
                    "from where its lights put them (default: glints not identified)");
  return {track, [request] { return run_command("track", [&] { return run_track(*request); }); }};
}

Command add_score_command(CLI::App& app) {
  auto request = std::make_shared<ScoreRequest>();
  CLI::App* score =
      app.add_subcommand("score", "Score another tracker's detections (CSV) against the labels of the images");
  score->footer(std::string("The detections file's columns: image, feature (glint or pupil), u_px, v_px,\n"
                            "and optionally illuminator, semi_axis_1_px, semi_axis_2_px, angle_deg,\n"
                            "confidence (docs/trackers.md); other columns are ignored. Pixel centres sit at\n"
                            "integer coordinates: (0, 0) is the centre of the top-left pixel, as in OpenCV\n"
                            "and in the labels; a tracker whose (0, 0) is the pixel's corner subtracts 0.5.\n"
                            "image: the image's file name, a path ending in it, or its name without the\n"
                            "extension. A frame where nothing was found: u_px and v_px both empty, both nan\n"
                            "or both -1; confidence -1: none. Writes DIR/score.txt, score.csv, score.json\n"
                            "and overlays/.\n\n") +
                kExitCodes);
  score->add_option("--detections", request->detections_file, "Detections file (CSV)")->required();
  score->add_option("--min-confidence", request->min_confidence,
                    "Leave out pupils the tracker reports with a confidence below this")
      ->check(kFinite)
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  add_score_output_options(*score, *request);
  return {score, [request] { return run_command("score", [&] { return run_score(*request); }); }};
}

}  // namespace purkinje::tools
