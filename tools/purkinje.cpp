// The purkinje command line: argument parsing and exit codes only; the
// work is done by the libraries. Documented in docs/cli.md.

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <mutex>
#include <optional>
#include <new>
#include <numbers>
#include <cmath>
#include <sstream>
#include <string>

#include "commands.h"
#include "output_checks.h"
#include "progress.h"
#include "purkinje/models/eye_variation.h"
#include "purkinje/models/input_file.h"
#include "purkinje/models/labels.h"
#include "purkinje/models/output_file.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/models/spelling.h"
#include "purkinje/models/truth.h"
#include "purkinje/renderer/image_io.h"
#include "purkinje/renderer/ray_tracer.h"
#include "purkinje/renderer/render.h"

namespace {

// The project's version, as in the top-level CMakeLists.txt.
#ifndef PURKINJE_VERSION
#define PURKINJE_VERSION "0.1.0"
#endif

using purkinje::tools::kBadInput;
using purkinje::tools::kOk;
using purkinje::tools::kOutputError;
using purkinje::tools::kUsageError;

constexpr const char* kExitCodes =
    "Exit codes:\n"
    "  0  success\n"
    "  1  bad input: a scene, labels, image or detections file is missing, malformed or invalid\n"
    "     (message on stderr)\n"
    "  2  usage error: unknown option, missing or invalid argument\n"
    "  3  output error: the output could not be written (no partial file is left)";

// CLI11's Range lets NaN through (every comparison with it is false), and
// its unsigned conversion reads "-1" as 2^64 - 1: numbers are checked as
// text first.
const CLI::Validator kFinite(
    [](const std::string& text) -> std::string {
      double value = 0;
      const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
      if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) {
        return "must be a finite number, not \"" + text + "\"";
      }
      return {};
    },
    "FINITE");
const CLI::Validator kSeed(
    [](const std::string& text) -> std::string {
      std::uint64_t value = 0;
      const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
      if (text.empty() || error != std::errc() || end != text.data() + text.size()) {
        return "must be an integer from 0 to 18446744073709551615 (2^64 - 1), not \"" + text + "\"";
      }
      return {};
    },
    "SEED");

struct TruthRequest {
  std::string scene_file;
  std::string output_file;  // empty: standard output
  std::string format;       // empty: from the output file's extension, else json
  int pupil_points = purkinje::TruthOptions{}.pupil_border_points;
};

int run_truth(const TruthRequest& request) {
  if (!request.output_file.empty()) {
    if (const auto refusal = purkinje::tools::check_output_file(request.output_file, {request.scene_file})) {
      std::cerr << "purkinje truth: error: " << refusal->message << "\n";
      return refusal->exit_code;
    }
  }
  std::string labels;
  try {
    const purkinje::Scene scene = purkinje::load_scene(request.scene_file);
    purkinje::TruthOptions options;
    options.pupil_border_points = request.pupil_points;
    const purkinje::SceneTruth truth = purkinje::compute_truth(scene, options);
    std::string format = request.format;
    if (format.empty()) {
      const bool csv_file = request.output_file.size() >= 4 &&
                            request.output_file.compare(request.output_file.size() - 4, 4, ".csv") == 0;
      format = csv_file ? "csv" : "json";
    }
    labels = format == "csv" ? purkinje::truth_to_csv(scene, truth)
                             : purkinje::truth_to_json(scene, truth);
  } catch (const std::exception& error) {
    std::cerr << "purkinje truth: error: " << error.what() << "\n";
    return kBadInput;
  }

  if (request.output_file.empty()) {
    std::cout << labels << std::flush;
    if (!std::cout) {
      std::cerr << "purkinje truth: error: cannot write to standard output\n";
      return kOutputError;
    }
    return kOk;
  }
  try {
    purkinje::write_file_atomically(request.output_file, labels);
  } catch (const std::exception& error) {
    std::cerr << "purkinje truth: error: " << error.what() << "\n";
    return kOutputError;
  }
  return kOk;
}

struct RenderRequest {
  std::string scene_file;
  std::string output_dir;
  std::string camera;  // empty: every camera
  std::string mode = "fast";
  int samples = purkinje::renderer::RenderOptions{}.samples_per_pixel;
  int edge_samples = purkinje::renderer::RenderOptions{}.edge_samples_per_pixel;
  std::int64_t photons = purkinje::renderer::RenderOptions{}.reference_photons_per_light;
  std::uint64_t seed = 0;
  bool no_noise = false;
  bool glint_masks = false;
  int threads = 0;
  int variations = 0;  // 0: the scene as it is
  std::uint64_t variation_seed = 1;
  bool resume = false;  // continue a killed --variations run in the same folder
  bool quiet = false;   // no progress on stderr
  double max_gaze_deg = 30;
  double min_pupil_mm = 1, max_pupil_mm = 4;
};

// File names keep to a portable set of characters.
std::string file_stem(const std::string& scene, const std::string& camera) {
  std::string stem = scene.empty() ? "scene" : scene;
  stem += "_" + camera;
  for (char& c : stem) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '-' || c == '_' || c == '.';
    if (!ok) c = '_';
  }
  return stem;
}

// Renders `cameras` of `scene` and writes their files under `stem_prefix`
// as one all-or-nothing set; returns an exit code, the error on stderr.
int render_and_write(const RenderRequest& request, const purkinje::Scene& scene, const std::vector<int>& cameras,
                     const std::string& stem_prefix, purkinje::renderer::RenderOptions options,
                     const std::string& progress_label, bool show_progress) {
  namespace r = purkinje::renderer;
  // Every camera is rendered before anything is written, so a failure
  // leaves no file at all: all images go out in one all-or-nothing set.
  std::vector<std::string> stems;
  for (int camera : cameras) {
    const std::string stem = file_stem(stem_prefix, scene.cameras[camera].name());
    if (std::find(stems.begin(), stems.end(), stem) != stems.end()) {
      std::cerr << "purkinje render: error: " << request.scene_file << ": cameras '"
                << scene.cameras[camera].name() << "' and another camera would both write " << stem
                << ".*: give them names that differ in letters, digits, '-', '_' or '.'\n";
      return kBadInput;
    }
    stems.push_back(stem);
  }
  const bool terminal = show_progress && isatty(STDERR_FILENO) != 0;
  std::vector<r::RenderResult> results;
  for (int camera : cameras) {
    const std::string name = progress_label + scene.cameras[camera].name();
    std::mutex progress_mutex;
    int shown = -1;
    if (terminal) {
      options.progress = [&](double fraction) {
        const std::lock_guard<std::mutex> lock(progress_mutex);
        const int percent = static_cast<int>(fraction * 100);
        if (percent <= shown) return;  // workers may report out of order
        shown = percent;
        std::fprintf(stderr, "\rrendering %s: %3d%%", name.c_str(), percent);
      };
    }
    try {
      results.push_back(r::render(scene, camera, options));
    } catch (const std::exception& error) {
      if (terminal) std::fprintf(stderr, "\n");
      std::cerr << "purkinje render: error: " << request.scene_file << ": " << error.what() << "\n";
      return kBadInput;
    }
    if (terminal) std::fprintf(stderr, "\r\033[K");
  }

  std::error_code ec;
  std::filesystem::create_directories(request.output_dir, ec);
  if (ec) {
    std::cerr << "purkinje render: error: " << request.output_dir << ": cannot create the output folder: "
              << ec.message() << "\n";
    return kOutputError;
  }
  try {
    r::FileSet files;
    std::vector<r::RenderFiles> written;
    for (std::size_t i = 0; i < results.size(); ++i) {
      written.push_back(r::add_render(files, request.output_dir, stems[i], scene, results[i], options));
    }
    files.commit();
    for (const r::RenderFiles& f : written) {
      std::cout << "wrote " << f.image.string() << ", " << f.exr.filename().string() << ", "
                << f.labels.filename().string() << "\n";
    }
  } catch (const std::exception& error) {
    std::cerr << "purkinje render: error: " << error.what() << "\n";
    return kOutputError;
  }
  return kOk;
}

// Variation k's stem among `count`: "<scene>_v<k>", k with at least 4 digits.
std::string variation_stem(const purkinje::Scene& scene, std::size_t k, std::size_t count) {
  const std::size_t digits = std::max<std::size_t>(4, std::to_string(count - 1).size());
  std::string index = std::to_string(k);
  index.insert(0, digits - index.size(), '0');
  return (scene.name.empty() ? std::string("scene") : scene.name) + "_v" + index;
}

// A hidden temporary a killed run left: its process is gone.
void remove_stale_temporaries(const std::filesystem::path& dir) {
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const std::optional<long> pid = purkinje::temporary_owner(e.path().filename().string());
    if (pid && *pid > 0 && ::kill(static_cast<pid_t>(*pid), 0) != 0 && errno == ESRCH) {
      std::filesystem::remove(e.path(), ec);
    }
  }
}

// Whether every camera's files of a variation are in place and are what
// this run would write: labels whose scene part (cameras, lights, eyes:
// the variation's pose and pupil) and render settings (every option that
// changes a byte) equal this run's, and whose recorded size and CRC-32 of
// the PNG and EXR match the files beside them.
bool unit_complete(const std::filesystem::path& dir, const std::string& stem_prefix, const purkinje::Scene& scene,
                   const std::vector<int>& cameras, const purkinje::renderer::RenderOptions& options) {
  using json = nlohmann::json;
  try {
    const json truth = json::parse(purkinje::truth_to_json(scene, purkinje::compute_truth(scene)));
    for (int camera : cameras) {
      const std::string stem = file_stem(stem_prefix, scene.cameras[camera].name());
      const json labels = json::parse(purkinje::read_input_file(dir / (stem + ".json"), purkinje::kMaxLabelsFileBytes,
                                                                "a labels file"));
      for (const char* key : {"labels_format", "scene", "units", "cameras", "illuminators", "eyes"}) {
        if (labels.at(key) != truth.at(key)) return false;
      }
      const json& render = labels.at("render");
      // Named: items() does not keep a temporary alive.
      const json settings = json::parse(purkinje::renderer::render_settings_json(scene, camera, options));
      for (const auto& [key, value] : settings.items()) {
        if (render.at(key) != value) return false;
      }
      const json& files = render.at("files");
      for (const auto& [kind, extension] : {std::pair{"image", ".png"}, std::pair{"exr", ".exr"}}) {
        const std::string name = files.at(kind).get<std::string>();
        if (name != stem + extension) return false;
        const purkinje::FileCheck check = purkinje::file_check_of_file(dir / name);
        if (files.at(std::string(kind) + "_bytes").get<std::uintmax_t>() != check.bytes ||
            files.at(std::string(kind) + "_crc32").get<std::string>() != purkinje::crc32_text(check.crc32)) {
          return false;
        }
      }
    }
  } catch (const std::exception&) {
    return false;  // missing, cut short, or not this run's: rendered again
  }
  return true;
}

// Appends a line to the index and flushes it to the disk.
void append_line(const std::filesystem::path& file, const std::string& line) {
  const auto fail = [&](int error) {
    throw std::runtime_error(file.string() + ": cannot append: " + std::strerror(error));
  };
  const int fd = ::open(file.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (fd < 0) fail(errno);
  std::size_t done = 0;
  while (done < line.size()) {
    const ssize_t written = ::write(fd, line.data() + done, line.size() - done);
    if (written < 0 && errno == EINTR) continue;
    if (written < 0) {
      const int error = errno;
      ::close(fd);
      fail(error);
    }
    done += static_cast<std::size_t>(written);
  }
  if (::fsync(fd) != 0) {
    const int error = errno;
    ::close(fd);
    fail(error);
  }
  ::close(fd);
}

int run_render(const RenderRequest& request) {
  namespace r = purkinje::renderer;
  purkinje::Scene scene;
  std::vector<int> cameras;
  std::vector<purkinje::EyeVariation> variations;
  r::RenderOptions options;
  try {
    scene = purkinje::load_scene(request.scene_file);
    for (int i = 0; i < static_cast<int>(scene.cameras.size()); ++i) {
      if (request.camera.empty() || scene.cameras[i].name() == request.camera) cameras.push_back(i);
    }
    if (cameras.empty()) {
      throw std::invalid_argument(request.scene_file + ": no camera named '" + request.camera + "'");
    }
    r::embree_device();  // a bad PURKINJE_EMBREE_CONFIG is named now, not after the first render
    if (request.variations > 0) {
      if (scene.eyes.empty()) throw std::invalid_argument(request.scene_file + ": --variations needs an eye");
      constexpr double kDegree = std::numbers::pi / 180;
      variations = purkinje::random_eye_variations(
          request.variation_seed, request.variations,
          {request.max_gaze_deg * kDegree, request.min_pupil_mm, request.max_pupil_mm});
    }
  } catch (const std::exception& error) {
    std::cerr << "purkinje render: error: " << error.what() << "\n";
    return kBadInput;
  }
  // The files a render writes; for a set, the index and, should the scene
  // file itself lie in the folder, any name of the set's pattern.
  std::vector<std::string> outputs;
  if (variations.empty()) {
    for (int camera : cameras) {
      for (const char* extension : {".png", ".exr", ".json"}) {
        outputs.push_back(file_stem(scene.name, scene.cameras[camera].name()) + extension);
      }
    }
  } else {
    // Every unit's names, checked now: a folder or FIFO in the way would
    // otherwise stop the run after hours.
    outputs.push_back("variations.csv");
    for (std::size_t k = 0; k < variations.size(); ++k) {
      for (int camera : cameras) {
        for (const char* extension : {".png", ".exr", ".json"}) {
          outputs.push_back(file_stem(variation_stem(scene, k, variations.size()), scene.cameras[camera].name()) +
                            extension);
        }
      }
    }
  }
  if (const auto refusal = purkinje::tools::check_output_folder(request.output_dir, {}, outputs, {request.scene_file})) {
    std::cerr << "purkinje render: error: " << refusal->message << "\n";
    return refusal->exit_code;
  }
  options.mode = request.mode == "reference" ? r::RenderMode::reference : r::RenderMode::fast;
  options.reference_photons_per_light = request.photons;
  options.samples_per_pixel = request.samples;
  options.edge_samples_per_pixel = request.edge_samples;
  options.seed = request.seed;
  options.noise = !request.no_noise;
  options.per_light_glint_masks = request.glint_masks;
  options.threads = request.threads;
  if (variations.empty()) return render_and_write(request, scene, cameras, scene.name, options, "", !request.quiet);

  // Each variation's files are written as soon as it is rendered (a set
  // of hundreds would not fit in memory), each all or nothing, the labels
  // last with their images' checks; the index grows a line per finished
  // variation, and is written whole at the end.
  const std::filesystem::path dir(request.output_dir);
  const std::filesystem::path index_file = dir / "variations.csv";
  const std::string header = "index,stem,seed,gaze_turn_deg,turn_direction_deg,pupil_radius_mm\n";
  const auto stem_of = [&](std::size_t k) { return variation_stem(scene, k, variations.size()); };
  const auto line_of = [&](std::size_t k) {
    const purkinje::EyeVariation& v = variations[k];
    std::ostringstream line;
    line << std::setprecision(10) << k << ',' << stem_of(k) << ',' << request.seed + k << ','
         << v.gaze_turn_rad * 180 / std::numbers::pi << ',' << v.turn_direction_rad * 180 / std::numbers::pi << ','
         << v.pupil_radius_mm << '\n';
    return line.str();
  };
  std::map<std::size_t, std::string> indexed;  // --resume: the lines the killed run wrote
  try {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw std::runtime_error(dir.string() + ": cannot create the output folder: " + ec.message());
    if (request.resume && std::filesystem::exists(index_file)) {
      const std::string text = purkinje::read_input_file(index_file, std::uintmax_t{1} << 32, "an index");
      if (text.rfind(header, 0) != 0) {
        std::cerr << "purkinje render: error: " << index_file.string()
                  << ": not the index of a --variations set: --resume continues only such a set\n";
        return kUsageError;
      }
      // Whole lines only: a kill may have cut the last one short.
      for (std::size_t at = header.size(), end; (end = text.find('\n', at)) != std::string::npos; at = end + 1) {
        const std::string line = text.substr(at, end + 1 - at);
        indexed[std::strtoull(line.c_str(), nullptr, 10)] = line;
      }
    }
  } catch (const std::exception& error) {
    std::cerr << "purkinje render: error: " << error.what() << "\n";
    return kOutputError;
  }
  for (const auto& [k, line] : indexed) {
    if (k >= variations.size()) {
      std::cerr << "purkinje render: error: " << index_file.string() << " lists variation " << k << "; this run has "
                << variations.size() << ": --resume needs the options of the run it continues\n";
      return kUsageError;
    }
    if (line != line_of(k)) {
      std::cerr << "purkinje render: error: " << index_file.string() << ": variation " << k
                << " was made with other options (" << line.substr(0, line.size() - 1)
                << "): --resume needs the options of the run it continues\n";
      return kUsageError;
    }
  }
  // The index starts whole: the header and the whole lines kept (a line a
  // kill cut short would otherwise run into the next one appended).
  try {
    std::string start = header;
    for (const auto& [k, line] : indexed) start += line;
    purkinje::write_file_atomically(index_file, start);
  } catch (const std::exception& error) {
    std::cerr << "purkinje render: error: " << error.what() << "\n";
    return kOutputError;
  }
  if (request.resume) remove_stale_temporaries(dir);
  std::size_t resumed = 0;
  purkinje::tools::Progress progress("render", variations.size(), request.quiet);
  for (std::size_t k = 0; k < variations.size(); ++k) {
    options.seed = request.seed + k;  // the noise differs from image to image
    const purkinje::Scene varied = purkinje::with_eye_variation(scene, variations[k]);
    if (request.resume && unit_complete(dir, stem_of(k), varied, cameras, options)) {
      ++resumed;
    } else {
      const int code = render_and_write(request, varied, cameras, stem_of(k), options, "", false);
      if (code != kOk) return code;
    }
    purkinje::stop_point("unit_written");
    progress.step();
    if (!indexed.count(k)) {
      try {
        append_line(index_file, line_of(k));
      } catch (const std::exception& error) {
        std::cerr << "purkinje render: error: " << error.what() << "\n";
        return kOutputError;
      }
    }
  }
  std::string list = header;
  for (std::size_t k = 0; k < variations.size(); ++k) list += line_of(k);
  try {
    purkinje::write_file_atomically(index_file, list);
  } catch (const std::exception& error) {
    std::cerr << "purkinje render: error: " << error.what() << "\n";
    return kOutputError;
  }
  if (request.resume) std::cout << "resumed: " << resumed << " of " << variations.size() << " variations were complete\n";
  std::cout << "wrote " << index_file.string() << "\n";
  return kOk;
}

// The inputs and outputs `track` and `score` share.
void add_score_output_options(CLI::App& command, purkinje::tools::ScoreOutput& request) {
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

// The version, and the instruction set Embree's kernels will use: what a
// benchmark figure or a bug report needs beside it.
std::string version_text() {
  std::string embree;
  try {
    const purkinje::renderer::EmbreeDevice device = purkinje::renderer::embree_device();
    embree = "isa " + device.isa + " (the CPU's best: " + purkinje::renderer::cpu_isa() + ")";
  } catch (const std::exception& error) {
    embree = error.what();
  }
  return std::string("purkinje ") + PURKINJE_VERSION + "\nembree: " + embree;
}

int run(int argc, char** argv) {
  CLI::App app{"purkinje: physically based simulator of eye-tracker cameras"};
  app.set_version_flag("--version", version_text());
  app.footer(kExitCodes);
  app.require_subcommand(1);

  TruthRequest truth_request;
  CLI::App* truth = app.add_subcommand(
      "truth", "Compute the exact ground truth of a scene: glints, refracted pupil, axes");
  truth->footer(std::string("Writes JSON (default) or CSV; the fields are documented in "
                            "docs/labels.md.\n\n") +
                kExitCodes);
  truth->add_option("SCENE", truth_request.scene_file, "Scene file (JSON, see docs/scene-format.md)")
      ->required();
  truth->add_option("-o,--output", truth_request.output_file,
                    "Output file, replaced atomically (default: standard output)");
  truth->add_option("--format", truth_request.format,
                    "Output format (default: csv if the output file ends in .csv, else json)")
      ->check(CLI::IsMember({"json", "csv"}));
  truth->add_option("--pupil-points", truth_request.pupil_points,
                    "Number of pupil-border points per view")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();

  RenderRequest render_request;
  CLI::App* render = app.add_subcommand(
      "render", "Render near-infrared camera images of a scene, with AOVs and labels");
  render->footer(std::string("For each camera, writes DIR/<scene>_<camera>.png (sensor image),\n"
                             ".exr (radiance, linear electrons, AOVs) and .json (labels; see\n"
                             "docs/labels.md and docs/rendering.md).\n\n") +
                 kExitCodes);
  render->add_option("SCENE", render_request.scene_file, "Scene file (JSON, see docs/scene-format.md)")
      ->required();
  render->add_option("-o,--output", render_request.output_dir, "Output folder (created if missing)")
      ->required();
  render->add_option("--camera", render_request.camera, "Render only the camera of this name");
  render->add_option("--mode", render_request.mode,
                     "fast, or reference: brute force, to validate fast (many times slower;\n"
                     "use --samples 256 or more)")
      ->check(CLI::IsMember({"fast", "reference"}))
      ->capture_default_str();
  render->add_option("--samples", render_request.samples, "Camera rays per pixel (one: through its centre)")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  render->add_option("--edge-samples", render_request.edge_samples,
                     "Camera rays per pixel on outlines, texture and shadow edges\n"
                     "(adaptive sampling; 0 or at most --samples: off)")
      ->check(CLI::Range(0, 1 << 20))
      ->capture_default_str();
  render->add_option("--photons", render_request.photons,
                     "Reference mode: photons per light and eye for the light through the cornea")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{1} << 30))
      ->capture_default_str();
  render->add_option("--seed", render_request.seed, "Seed of jitter and sensor noise")
      ->check(kSeed)
      ->capture_default_str();
  render->add_flag("--no-noise", render_request.no_noise, "Leave out shot and read noise");
  render->add_flag("--glint-masks", render_request.glint_masks, "Add one glint mask per illuminator to the EXR");
  render->add_option("--threads", render_request.threads, "Worker threads (0: all); output does not depend on it")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  render->add_option("--variations", render_request.variations,
                     "Render this many variations of the scene: its first eye turned about its\n"
                     "centre of rotation and its pupil resized, at random (0: the scene as it is)")
      ->check(CLI::Range(0, 10000000))
      ->capture_default_str();
  render->add_flag("--quiet", render_request.quiet, "No progress on standard error");
  render->add_flag("--resume", render_request.resume,
                   "Continue a killed --variations run in the same folder with the same options:\n"
                   "complete variations are kept, the rest rendered again (the same bytes as one run)");
  render->add_option("--variation-seed", render_request.variation_seed, "Seed of the variations' draws")
      ->check(kSeed)
      ->capture_default_str();
  render->add_option("--max-gaze-deg", render_request.max_gaze_deg,
                     "Variations: gaze uniform over the cap within this angle of the scene's")
      ->check(kFinite)
      ->check(CLI::Range(0.0, 90.0))
      ->capture_default_str();
  render->add_option("--min-pupil-mm", render_request.min_pupil_mm, "Variations: smallest pupil radius")
      ->check(kFinite)
      ->check(CLI::Range(0.1, 10.0))
      ->capture_default_str();
  render->add_option("--max-pupil-mm", render_request.max_pupil_mm, "Variations: largest pupil radius")
      ->check(kFinite)
      ->check(CLI::Range(0.1, 10.0))
      ->capture_default_str();

  purkinje::tools::TrackRequest track_request;
  CLI::App* track = app.add_subcommand(
      "track", "Run purkinje's glint and pupil detectors over labelled images and score them");
  track->footer(std::string("INPUTS are labels files (.json, as purkinje render writes them), images beside\n"
                            "their labels, or folders of them. Writes DIR/score.txt, score.csv, score.json,\n"
                            "detections.csv and overlays/ (docs/cli.md, docs/trackers.md).\n\n") +
                kExitCodes);
  add_score_output_options(*track, track_request);
  track->add_option("--scene", track_request.scene_file,
                    "Scene file of the tracker's rig and nominal eye: glints are identified\n"
                    "from where its lights put them (default: glints not identified)");

  purkinje::tools::ScoreRequest score_request;
  CLI::App* score = app.add_subcommand(
      "score", "Score another tracker's detections (CSV) against the labels of the images");
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
  score->add_option("--detections", score_request.detections_file, "Detections file (CSV)")->required();
  score->add_option("--min-confidence", score_request.min_confidence,
                    "Leave out pupils the tracker reports with a confidence below this")
      ->check(kFinite)
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  add_score_output_options(*score, score_request);

  purkinje::tools::CalibrateRequest calibrate_request;
  std::vector<std::string> head_moves;
  std::string tracker_cornea;
  CLI::App* calibrate = app.add_subcommand(
      "calibrate", "Render the eye fixating targets on the scene's screen, detect, calibrate gaze, score");
  calibrate->footer(std::string("The scene needs a \"screen\" (docs/scene-format.md). Its eye fixates a\n"
                                "calibration grid, then a test grid at its own place and at each head move;\n"
                                "each frame is rendered and read by purkinje's detectors. The model-based method\n"
                                "and the second-order polynomial are calibrated and scored against the truth.\n"
                                "Writes DIR/calibration.txt, calibration.json, frames.csv and gaze_error.png\n"
                                "(docs/calibration.md).\n\n") +
                    kExitCodes);
  calibrate->add_option("SCENE", calibrate_request.scene_file, "Scene file with a screen")->required();
  calibrate->add_option("-o,--output", calibrate_request.output_dir, "Output folder (created if missing)")
      ->required();
  calibrate->add_option("--grid", calibrate_request.grid, "Test targets: N x N over the screen")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  calibrate->add_option("--calibration-grid", calibrate_request.calibration_grid,
                        "Calibration targets: N x N over the screen")
      ->check(CLI::Range(3, 16))
      ->capture_default_str();
  calibrate->add_option("--head-move", head_moves,
                        "A test position beside the scene's, as the eye's move \"x,y,z\" in mm (repeatable),\n"
                        "e.g. --head-move 100,0,0 --head-move 0,0,100");
  calibrate->add_option("--tracker-cornea", tracker_cornea,
                        "The tracker's cornea as \"R,Q\": apex radius (mm) and asphericity, e.g. 7.8,0 for\n"
                        "the classic sphere (default: the scene eye's own, the correct model)");
  calibrate->add_flag("--fit-radius", calibrate_request.fit_radius,
                      "Fit the cornea's radius from all calibration frames' glints");
  calibrate->add_flag("--fit-pupil-depth", calibrate_request.fit_pupil_depth,
                      "Fit the pupil's depth behind the cornea's centre with kappa");
  calibrate->add_option("--glint-noise", calibrate_request.glint_noise_px,
                        "The glint detector's noise (s.d., px) the uncertainties assume\n"
                        "(default: measured against the noise frames' labels)")
      ->check(kFinite)
      ->check(CLI::Range(1e-6, 10.0));
  calibrate->add_option("--pupil-noise", calibrate_request.pupil_noise_px,
                        "The pupil detector's noise (s.d., px) the uncertainties assume\n"
                        "(default: measured against the noise frames' labels)")
      ->check(kFinite)
      ->check(CLI::Range(1e-6, 10.0));
  calibrate->add_option("--noise-frames", calibrate_request.noise_frames,
                        "Frames at random targets that only measure the detectors' noise (0: the calibration frames)")
      ->check(CLI::Range(0, 10000))
      ->capture_default_str();
  calibrate->add_flag("--quiet", calibrate_request.quiet, "No progress on standard error");
  calibrate->add_option("--seed", calibrate_request.seed, "Render seed of the first frame")
      ->check(kSeed)
      ->capture_default_str();

  // A mistyped subcommand would only get CLI11's "A subcommand is required".
  std::vector<std::string> subcommand_names;
  for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    subcommand_names.push_back(sub->get_name());
  }
  if (argc > 1 && argv[1][0] != '-' &&
      std::find(subcommand_names.begin(), subcommand_names.end(), argv[1]) == subcommand_names.end()) {
    std::cerr << "purkinje: unknown subcommand '" << argv[1] << "'";
    if (const auto meant = purkinje::closest_match(argv[1], subcommand_names)) {
      std::cerr << "; did you mean '" << *meant << "'?";
    }
    std::cerr << " (subcommands:";
    for (const std::string& name : subcommand_names) std::cerr << ' ' << name;
    std::cerr << ")\n";
    return kUsageError;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    // A mistyped option: name the one meant, beside CLI11's own message.
    for (const CLI::App* sub : app.get_subcommands()) {
      std::vector<std::string> long_names;
      for (const CLI::Option* option : sub->get_options()) {
        for (const std::string& name : option->get_lnames()) long_names.push_back("--" + name);
      }
      for (const std::string& extra : sub->remaining()) {
        if (!extra.starts_with("--")) continue;
        const std::string typed = extra.substr(0, extra.find('='));
        if (const auto meant = purkinje::closest_match(typed, long_names)) {
          std::cerr << "purkinje " << sub->get_name() << ": unknown option " << typed << "; did you mean " << *meant
                    << "?\n";
        }
      }
    }
    // --help and --version arrive here too, with exit code 0.
    return app.exit(error) == 0 ? kOk : kUsageError;
  }
  if (*truth) return run_truth(truth_request);
  if (*render) {
    if (render_request.resume && render_request.variations == 0) {
      std::cerr << "purkinje render: --resume continues a --variations run: give --variations N\n";
      return kUsageError;
    }
    if (render_request.min_pupil_mm > render_request.max_pupil_mm) {
      std::cerr << "purkinje render: --min-pupil-mm " << render_request.min_pupil_mm << " is above --max-pupil-mm "
                << render_request.max_pupil_mm << "\n";
      return kUsageError;
    }
    return run_render(render_request);
  }
  if (*track) return purkinje::tools::run_track(track_request);
  if (*score) return purkinje::tools::run_score(score_request);
  if (*calibrate) {
    for (const std::string& move : head_moves) {
      std::array<double, 3> m{};
      char comma1 = 0, comma2 = 0;
      std::istringstream in(move);
      if (!(in >> m[0] >> comma1 >> m[1] >> comma2 >> m[2]) || comma1 != ',' || comma2 != ',' || !in.eof() ||
          !std::isfinite(m[0]) || !std::isfinite(m[1]) || !std::isfinite(m[2])) {
        std::cerr << "purkinje calibrate: --head-move \"" << move << "\": must be three numbers \"x,y,z\" in mm\n";
        return kUsageError;
      }
      calibrate_request.head_moves.push_back(m);
    }
    if (!tracker_cornea.empty()) {
      std::array<double, 2> c{};
      char comma = 0;
      std::istringstream in(tracker_cornea);
      if (!(in >> c[0] >> comma >> c[1]) || comma != ',' || !in.eof() || !(c[0] > 0 && c[0] < 100) ||
          !(c[1] > -1 && c[1] < 10)) {
        std::cerr << "purkinje calibrate: --tracker-cornea \"" << tracker_cornea
                  << "\": must be \"R,Q\" with the apex radius R in (0, 100) mm and the asphericity Q in (-1, 10)\n";
        return kUsageError;
      }
      calibrate_request.tracker_cornea = c;
    }
    return purkinje::tools::run_calibrate(calibrate_request);
  }
  return kUsageError;  // unreachable: a subcommand is required
}

}  // namespace

// No exception leaves main: the commands catch what their inputs and
// outputs throw; what is left (memory exhausted, a bug) still gets a line
// and an exit code instead of std::terminate's abort.
int main(int argc, char** argv) {
  purkinje::remove_temporaries_on_signals();
  try {
    return run(argc, argv);
  } catch (const std::bad_alloc&) {
    std::cerr << "purkinje: error: out of memory\n";
  } catch (const std::exception& error) {
    std::cerr << "purkinje: internal error: " << error.what() << "\n";
  } catch (...) {
    std::cerr << "purkinje: internal error: an unknown exception\n";
  }
  return kBadInput;
}
