// Ground truth for a whole bundled scene: every glint, 36 refracted
// pupil-border points with their ellipse, the refracted pupil centre.

#include <benchmark/benchmark.h>

#include <string>

#include "purkinje/models/scene_file.h"
#include "purkinje/models/truth.h"

namespace purkinje {
namespace {

void scene_truth(benchmark::State& state, const char* name) {
  const Scene scene = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/" + name);
  for (auto _ : state) {
    SceneTruth t = compute_truth(scene);
    benchmark::DoNotOptimize(t);
  }
}

void BM_TruthRemoteScene(benchmark::State& s) { scene_truth(s, "remote.json"); }
void BM_TruthHeadsetScene(benchmark::State& s) { scene_truth(s, "headset.json"); }
BENCHMARK(BM_TruthRemoteScene)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_TruthHeadsetScene)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace purkinje
