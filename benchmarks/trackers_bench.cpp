// Detectors' speed per frame on one core (the trackers issue's bar: at
// least 300 frames/s for 640 x 480, glints and pupil together), on a noisy
// render of each bundled scene.

#include <benchmark/benchmark.h>

#include <opencv2/core.hpp>

#include <map>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "purkinje/models/scene_file.h"
#include "purkinje/renderer/render.h"
#include "purkinje/models/truth.h"
#include "purkinje/trackers/cornea.h"
#include "purkinje/trackers/gaze.h"
#include "purkinje/trackers/glints.h"
#include "purkinje/trackers/pupil.h"
#include "purkinje/trackers/scoring.h"

namespace purkinje::trackers {
namespace {

const renderer::SensorImage& frame(const std::string& name) {
  static std::map<std::string, renderer::SensorImage> frames;
  auto it = frames.find(name);
  if (it == frames.end()) {
    const Scene scene = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/" + name + ".json");
    renderer::RenderOptions options;
    options.seed = 1;
    it = frames.emplace(name, renderer::render(scene, 0, options).sensor).first;
  }
  return it->second;
}

// The scene's frame as the detectors read it, with OpenCV on one thread:
// per core, frames, not their rows, go in parallel.
GreyView one_core_view(const std::string& name) {
  cv::setNumThreads(1);
  const renderer::SensorImage& s = frame(name);
  return grey_view(std::span<const std::uint16_t>(s.values), s.width, s.height, s.bits);
}

void count_frames(benchmark::State& state) {
  state.counters["frames_per_s"] = benchmark::Counter(static_cast<double>(state.iterations()),
                                                      benchmark::Counter::kIsRate);
}

void glints(benchmark::State& state, const std::string& name) {
  const GreyView image = one_core_view(name);
  const BlobGlintDetector detector;
  for (auto _ : state) benchmark::DoNotOptimize(detector.detect(image));
  count_frames(state);
}

// The pupil alone, told the frame's glints.
void pupil(benchmark::State& state, const std::string& name) {
  const GreyView image = one_core_view(name);
  const std::vector<Glint> found = BlobGlintDetector().detect(image);
  const StarburstPupilDetector detector;
  for (auto _ : state) benchmark::DoNotOptimize(detector.detect(image, found));
  count_frames(state);
}

// A whole frame: glints, then the pupil with the glints masked (the bar).
void frame_tracked(benchmark::State& state, const std::string& name) {
  const GreyView image = one_core_view(name);
  const BlobGlintDetector glint_detector;
  const StarburstPupilDetector pupil_detector;
  for (auto _ : state) benchmark::DoNotOptimize(pupil_detector.detect(image, glint_detector.detect(image)));
  count_frames(state);
}

void BM_GlintDetectorRemote(benchmark::State& s) { glints(s, "remote"); }
void BM_GlintDetectorHeadset(benchmark::State& s) { glints(s, "headset"); }
BENCHMARK(BM_GlintDetectorRemote)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GlintDetectorHeadset)->Unit(benchmark::kMillisecond);
void BM_PupilDetectorRemote(benchmark::State& s) { pupil(s, "remote"); }
void BM_PupilDetectorHeadset(benchmark::State& s) { pupil(s, "headset"); }
BENCHMARK(BM_PupilDetectorRemote)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PupilDetectorHeadset)->Unit(benchmark::kMillisecond);
void BM_TrackersRemote(benchmark::State& s) { frame_tracked(s, "remote"); }
void BM_TrackersHeadset(benchmark::State& s) { frame_tracked(s, "headset"); }
BENCHMARK(BM_TrackersRemote)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TrackersHeadset)->Unit(benchmark::kMillisecond);

// The cornea's centre from one frame's glints (the calibration issue's
// bar: at most 20 us), exact or with 0.1 px of Gaussian noise (64 draws,
// taken in turn), from a start 3.9 mm off.
void cornea_center(benchmark::State& state, const std::string& name, double noise_px) {
  const Scene scene = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/" + name + ".json");
  const Scene spherical = name == "remote" ? [&] {
    Scene s = scene;
    Eye eye = Eye::with_cornea_center(keratometric_eye(), scene.eyes[0].cornea_center(), scene.eyes[0].optical_axis());
    s.eyes = {eye};
    return s;
  }() : scene;
  const std::vector<Glint> exact = exact_detections(compute_truth(spherical).views).glints;
  std::mt19937 random(7);
  std::normal_distribution<double> noise(0, noise_px);
  std::vector<std::vector<Glint>> draws(noise_px > 0 ? 64 : 1, exact);
  for (std::vector<Glint>& glints : draws) {
    for (Glint& g : glints) g.centre = {g.centre.u + noise(random), g.centre.v + noise(random)};
  }
  const Point3 start = scene.eyes[0].cornea_center() + Vector3{2, -1.5, 3};
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        estimate_cornea_center(scene.cameras[0], scene.illuminators, draws[i++ % draws.size()], start));
  }
}
void BM_CorneaCenterHeadset(benchmark::State& s) { cornea_center(s, "headset", 0); }
void BM_CorneaCenterHeadsetNoisy(benchmark::State& s) { cornea_center(s, "headset", 0.1); }
void BM_CorneaCenterRemoteNoisy(benchmark::State& s) { cornea_center(s, "remote", 0.1); }
BENCHMARK(BM_CorneaCenterHeadset)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CorneaCenterHeadsetNoisy)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CorneaCenterRemoteNoisy)->Unit(benchmark::kMicrosecond);

// The remote's own aspheric cornea (Navarro's, Q = -0.26) with its
// optical axis given, as gaze's alternation calls it: 0.1 px noise.
void BM_CorneaCenterRemoteConicoidNoisy(benchmark::State& state) {
  const Scene scene = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/remote.json");
  const std::vector<Glint> exact = exact_detections(compute_truth(scene).views).glints;
  std::mt19937 random(7);
  std::normal_distribution<double> noise(0, 0.1);
  std::vector<std::vector<Glint>> draws(64, exact);
  for (std::vector<Glint>& glints : draws) {
    for (Glint& g : glints) g.centre = {g.centre.u + noise(random), g.centre.v + noise(random)};
  }
  CorneaFitSettings conicoid;
  conicoid.cornea_radius_mm = 7.72;
  conicoid.cornea_asphericity = -0.26;
  const Point3 start = scene.eyes[0].cornea_center() + Vector3{2, -1.5, 3};
  const UnitVector3 axis = scene.eyes[0].optical_axis();
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(estimate_cornea_center(scene.cameras[0], scene.illuminators, draws[i++ % draws.size()],
                                                    start, conicoid, axis));
  }
}
BENCHMARK(BM_CorneaCenterRemoteConicoidNoisy)->Unit(benchmark::kMicrosecond);

// A 9-point gaze calibration (the calibration issue's bar: at most 10
// ms): the bundled remote rig and screen, a one-surface spherical eye with
// kappa fixating a 3 x 3 grid, exact features (the pupil's outline, 36
// points) with 0.1 px of noise on the glints and 0.05 px on the pupil; the
// model-based method (cornea over the nine frames, kappa, the centre of
// rotation) and the polynomial.
struct NineFrames {
  Scene rig = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/remote.json");
  std::vector<GazeFeatures> frames;
  std::vector<Point3> targets;
  std::vector<ScreenPoint> on_screen = rig.screen->grid(3, 3);
};

NineFrames nine_frames(const Conicoid& cornea = {7.8, 0}) {
  NineFrames n;
  EyeModel eye = keratometric_eye();
  eye.anterior_cornea = cornea;
  eye.kappa_horizontal_rad = 0.087;
  eye.kappa_vertical_rad = 0.026;
  std::mt19937 random(3);
  std::normal_distribution<double> glint(0, 0.1), pupil(0, 0.05);
  for (const ScreenPoint& t : n.on_screen) {
    Scene s = n.rig;
    s.eyes = {Eye::fixating(eye, n.rig.eyes[0].rotation_center(), n.rig.screen->at(t))};
    GazeFeatures f = *exact_gaze_features(compute_truth(s).views.front());
    for (Glint& g : f.glints) g.centre = {g.centre.u + glint(random), g.centre.v + glint(random)};
    // The pupil moves as a whole: its centre and its outline.
    const double du = pupil(random), dv = pupil(random);
    f.pupil_center = {f.pupil_center.u + du, f.pupil_center.v + dv};
    for (Pixel& p : f.pupil_outline) p = {p.u + du, p.v + dv};
    n.frames.push_back(f);
    n.targets.push_back(n.rig.screen->at(t));
  }
  return n;
}

void BM_GazeCalibrationModelBased(benchmark::State& state) {
  const NineFrames n = nine_frames();
  const GazeEyeModel nominal;
  for (auto _ : state) {
    benchmark::DoNotOptimize(calibrate_model_gaze(n.rig.cameras[0], n.rig.illuminators, n.frames, n.targets, nominal,
                                                  n.rig.eyes[0].rotation_center()));
  }
}
BENCHMARK(BM_GazeCalibrationModelBased)->Unit(benchmark::kMillisecond);

// The same with a conicoid cornea (Q = -0.26) in eye and model: each
// frame's cornea and pupil axis alternate until they settle.
void BM_GazeCalibrationModelBasedConicoid(benchmark::State& state) {
  const NineFrames n = nine_frames({7.72, -0.26});
  GazeEyeModel model;
  model.cornea_radius_mm = 7.72;
  model.cornea_asphericity = -0.26;
  model.pupil_depth_mm = 7.72 - 3.6;
  for (auto _ : state) {
    benchmark::DoNotOptimize(calibrate_model_gaze(n.rig.cameras[0], n.rig.illuminators, n.frames, n.targets, model,
                                                  n.rig.eyes[0].rotation_center()));
  }
}
BENCHMARK(BM_GazeCalibrationModelBasedConicoid)->Unit(benchmark::kMillisecond);

void BM_GazeCalibrationPolynomial(benchmark::State& state) {
  const NineFrames n = nine_frames();
  for (auto _ : state) benchmark::DoNotOptimize(PolynomialGaze::calibrate(n.frames, n.on_screen));
}
BENCHMARK(BM_GazeCalibrationPolynomial)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace purkinje::trackers
