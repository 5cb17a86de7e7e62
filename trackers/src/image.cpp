#include "purkinje/trackers/image.h"

#include <cstdint>
#include <stdexcept>
#include <string>

#include "grey_mat.h"

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

cv::Mat mat_of(const GreyView& image, const std::string& who) {
  const auto fail = [&](const std::string& what) { throw std::invalid_argument(who + ": image " + what); };
  if (image.data == nullptr || image.width <= 0 || image.height <= 0) {
    fail("is empty (" + std::to_string(image.width) + " x " + std::to_string(image.height) + ")");
  }
  if (image.bytes_per_pixel != 1 && image.bytes_per_pixel != 2) {
    fail("bytes_per_pixel = " + std::to_string(image.bytes_per_pixel) + ": must be 1 or 2 (8- or 16-bit grey)");
  }
  if (image.bits < 1 || image.bits > 8 * image.bytes_per_pixel) {
    fail("bits = " + std::to_string(image.bits) + ": must be in [1, " + std::to_string(8 * image.bytes_per_pixel) +
         "] for " + std::to_string(image.bytes_per_pixel) + " byte(s) per pixel");
  }
  if (image.row_bytes % image.bytes_per_pixel != 0 ||
      reinterpret_cast<std::uintptr_t>(image.data) % image.bytes_per_pixel != 0) {
    fail("row_bytes = " + std::to_string(image.row_bytes) + " or its data's address is not a multiple of " +
         std::to_string(image.bytes_per_pixel) + " bytes: 16-bit pixels must be aligned");
  }
  if (image.row_bytes < static_cast<std::size_t>(image.width) * image.bytes_per_pixel) {
    fail("row_bytes = " + std::to_string(image.row_bytes) + ": must be at least width * bytes_per_pixel = " +
         std::to_string(image.width * image.bytes_per_pixel));
  }
  return cv::Mat(image.height, image.width, image.bytes_per_pixel == 1 ? CV_8U : CV_16U,
                 const_cast<void*>(image.data), image.row_bytes);
}

}  // namespace purkinje::trackers
