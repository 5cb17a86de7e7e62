#pragma once
// A float image with named planes: the renderer's in-memory currency
// (linear radiance, electrons, AOVs). Row-major, (0, 0) the top-left pixel.

#include <cstddef>
#include <string>
#include <vector>

namespace purkinje::renderer {

struct ImagePlane {
  int width = 0, height = 0;
  std::vector<float> values;  // width * height, row-major

  ImagePlane() = default;
  ImagePlane(int w, int h, float fill = 0.0f)
      : width(w), height(h), values(static_cast<std::size_t>(w) * h, fill) {}
  float& at(int x, int y) { return values[static_cast<std::size_t>(y) * width + x]; }
  float at(int x, int y) const { return values[static_cast<std::size_t>(y) * width + x]; }
};

// One named channel of an EXR file, e.g. "R", "depth", "N.x", "id", "glint.led0".
struct NamedPlane {
  std::string name;
  ImagePlane plane;
};

// Digital numbers from the sensor's ADC, 0 .. 2^bits - 1.
struct SensorImage {
  int width = 0, height = 0;
  int bits = 8;
  std::vector<unsigned short> values;  // row-major
};

}  // namespace purkinje::renderer
