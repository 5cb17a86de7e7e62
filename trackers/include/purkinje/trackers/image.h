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
  // Values lie in [0, 2^bits - 1], the top one being saturation; larger
  // ones count as saturated too. Data kept in a word's high bits (as in a
  // 12-bit PNG) must be shifted down first.
  int bits = 8;
};

// Contiguous rows of 8-bit or 16-bit pixels. Throws std::invalid_argument
// when the pixels are fewer than width x height.
GreyView grey_view(std::span<const std::uint8_t> pixels, int width, int height);
GreyView grey_view(std::span<const std::uint16_t> pixels, int width, int height, int bits = 16);

}  // namespace purkinje::trackers
