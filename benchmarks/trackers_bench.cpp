// Detectors' speed per frame on one core (the trackers issue's bar: at
// least 300 frames/s for 640 x 480, glints and pupil together), on a noisy
// render of each bundled scene.

#include <benchmark/benchmark.h>

#include <opencv2/core.hpp>

#include <map>
#include <string>

#include "purkinje/models/scene_file.h"
#include "purkinje/renderer/render.h"
#include "purkinje/trackers/glints.h"

namespace purkinje::trackers {
namespace {

const cv::Mat& frame(const std::string& name) {
  static std::map<std::string, cv::Mat> frames;
  auto it = frames.find(name);
  if (it == frames.end()) {
    const Scene scene = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/" + name + ".json");
    renderer::RenderOptions options;
    options.seed = 1;
    const renderer::SensorImage s = renderer::render(scene, 0, options).sensor;
    cv::Mat image(s.height, s.width, CV_8U);
    for (std::size_t i = 0; i < s.values.size(); ++i) image.data[i] = static_cast<std::uint8_t>(s.values[i]);
    it = frames.emplace(name, image).first;
  }
  return it->second;
}

void glints(benchmark::State& state, const std::string& name) {
  cv::setNumThreads(1);  // per core
  const cv::Mat& image = frame(name);
  const BlobGlintDetector detector;
  for (auto _ : state) benchmark::DoNotOptimize(detector.detect(image));
  state.counters["frames_per_s"] = benchmark::Counter(static_cast<double>(state.iterations()),
                                                      benchmark::Counter::kIsRate);
}

void BM_GlintDetectorRemote(benchmark::State& s) { glints(s, "remote"); }
void BM_GlintDetectorHeadset(benchmark::State& s) { glints(s, "headset"); }
BENCHMARK(BM_GlintDetectorRemote)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GlintDetectorHeadset)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace purkinje::trackers
