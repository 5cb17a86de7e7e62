#pragma once
// A grey camera image as the trackers read it: plain memory, so that real
// cameras' frames, the renderer's sensor images, OpenCV matrices and
// numpy arrays all pass without a copy, and OpenCV stays inside trackers/.

#include <cstddef>
#include <cstdint>
#include <span>

namespace purkinje::trackers {

// Not owned. Pixel (x, y) starts at data + y * row_bytes + x * bytes_per_pixel.
struct GreyView {
  const void* data = nullptr;
  int width = 0, height = 0;
  std::size_t row_bytes = 0;
  int bytes_per_pixel = 1;  // 1, or 2 (native byte order)
  int bits = 8;             // values lie in [0, 2^bits - 1]; the top one is saturation
};

// Contiguous rows of 8-bit or 16-bit pixels.
inline GreyView grey_view(std::span<const std::uint8_t> pixels, int width, int height) {
  return {pixels.data(), width, height, static_cast<std::size_t>(width), 1, 8};
}
inline GreyView grey_view(std::span<const std::uint16_t> pixels, int width, int height, int bits = 16) {
  return {pixels.data(), width, height, static_cast<std::size_t>(width) * 2, 2, bits};
}

}  // namespace purkinje::trackers
