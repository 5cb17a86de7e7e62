#include "purkinje/trackers/image.h"

#include <stdexcept>
#include <string>

namespace purkinje::trackers {

namespace {

void check_pixel_count(std::size_t pixels, int width, int height) {
  if (width < 0 || height < 0 || pixels < static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    throw std::invalid_argument("grey_view: " + std::to_string(pixels) + " pixels for a " + std::to_string(width) +
                                " x " + std::to_string(height) + " image: must be at least width x height");
  }
}

}  // namespace

GreyView grey_view(std::span<const std::uint8_t> pixels, int width, int height) {
  check_pixel_count(pixels.size(), width, height);
  return {pixels.data(), width, height, static_cast<std::size_t>(width), 1, 8};
}

GreyView grey_view(std::span<const std::uint16_t> pixels, int width, int height, int bits) {
  check_pixel_count(pixels.size(), width, height);
  return {pixels.data(), width, height, static_cast<std::size_t>(width) * 2, 2, bits};
}

}  // namespace purkinje::trackers
