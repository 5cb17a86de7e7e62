#pragma once
// Tests that run under each of Embree's instruction sets in one process:
// the renderer reads kEmbreeConfigVariable whenever it creates a device.

#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include "purkinje/renderer/ray_tracer.h"

namespace purkinje::testing {

// Sets the renderer's Embree configuration for its lifetime and restores
// what the environment held before (CTest runs the suites again with it
// set: see tests/CMakeLists.txt).
class ScopedEmbreeConfig {
 public:
  explicit ScopedEmbreeConfig(const std::string& config) {
    if (const char* old = std::getenv(renderer::kEmbreeConfigVariable)) old_ = old;
    ::setenv(renderer::kEmbreeConfigVariable, config.c_str(), 1);
  }
  ~ScopedEmbreeConfig() {
    if (old_) ::setenv(renderer::kEmbreeConfigVariable, old_->c_str(), 1);
    else ::unsetenv(renderer::kEmbreeConfigVariable);
  }
  ScopedEmbreeConfig(const ScopedEmbreeConfig&) = delete;
  ScopedEmbreeConfig& operator=(const ScopedEmbreeConfig&) = delete;

 private:
  std::optional<std::string> old_;
};

// Embree's instruction sets that this CPU runs, lowest first.
inline std::vector<std::string> runnable_isas() {
  std::vector<std::string> isas;
  for (const char* isa : {"sse2", "sse4.2", "avx", "avx2", "avx512"}) {
    isas.push_back(isa);
    if (isa == renderer::cpu_isa()) break;
  }
  return isas;
}

}  // namespace purkinje::testing
