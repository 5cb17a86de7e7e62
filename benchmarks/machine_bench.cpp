// The machine beside every figure: the CPU's model and vector extensions,
// the instruction set Embree's kernels use (PURKINJE_EMBREE_CONFIG can
// lower it) and OpenCV's dispatch (OPENCV_CPU_DISABLE can cap it), printed
// in the benchmark's context header and its JSON output. A figure without
// them cannot be compared with a user's machine (docs/benchmarks.md).

#include <benchmark/benchmark.h>

#include <fstream>
#include <opencv2/core/utility.hpp>
#include <sstream>
#include <string>

#include "purkinje/renderer/ray_tracer.h"

namespace purkinje {
namespace {

// /proc/cpuinfo's first "model name" and the vector extensions among its flags.
std::pair<std::string, std::string> cpu_model_and_extensions() {
  std::ifstream in("/proc/cpuinfo");
  std::string line, model = "unknown", extensions;
  bool flags_seen = false;
  while (std::getline(in, line)) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::string key = line.substr(0, line.find_last_not_of(" \t", colon - 1) + 1);
    const std::string value = colon + 2 <= line.size() ? line.substr(colon + 2) : "";
    if (key == "model name" && model == "unknown") model = value;
    if (key == "flags" && !flags_seen) {
      flags_seen = true;
      std::istringstream flags(value);
      for (std::string f; flags >> f;) {
        if (f.starts_with("sse4") || f.starts_with("avx") || f == "fma") extensions += (extensions.empty() ? "" : " ") + f;
      }
    }
  }
  return {model, extensions};
}

const bool kContextAdded = [] {
  const auto [model, extensions] = cpu_model_and_extensions();
  benchmark::AddCustomContext("cpu_model", model);
  benchmark::AddCustomContext("cpu_vector_extensions", extensions);
  std::string embree;
  try {
    embree = renderer::embree_device().isa;
  } catch (const std::exception& e) {
    embree = e.what();
  }
  benchmark::AddCustomContext("embree_isa", embree);
  benchmark::AddCustomContext("opencv_cpu_features", cv::getCPUFeaturesLine());
  return true;
}();

}  // namespace
}  // namespace purkinje
