#pragma once
// Grey image files as the trackers read them, and overlays drawn on them
// for people to look at (`purkinje track` and `purkinje score`).

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "purkinje/models/screen.h"
#include "purkinje/models/truth.h"
#include "purkinje/trackers/image.h"
#include "purkinje/trackers/scoring.h"

namespace purkinje::trackers {

// A grey image with its pixels owned.
struct GreyImage {
  std::vector<std::uint16_t> pixels;  // row by row
  int width = 0, height = 0;
  int bits = 8;
  GreyView view() const { return grey_view(pixels, width, height, bits); }
};

// An 8- or 16-bit grey (or colour, taken to grey) image file: PNG, TIFF,
// PGM and whatever else OpenCV reads. `bits` are the sensor's significant
// bits: a 16-bit file keeps them in its words' high bits (as `purkinje
// render` writes PNGs of more than 8 bits), so its values are shifted down
// by 16 - bits; an 8-bit file needs bits = 8. Throws std::runtime_error
// naming the file and the rule.
GreyImage read_grey_image(const std::filesystem::path& file, int bits);

// The part of the image around what is labelled and found, enlarged to
// about 640 px across, with the labels in green and the detections in red:
// glints as crosses with their light's number, pupils as their ellipse
// and a cross at the centre. Written as PNG, all or nothing
// (std::runtime_error naming the file when it cannot be).
void write_overlay(const std::filesystem::path& file, const GreyImage& image,
                   const std::vector<EyeInCameraTruth>& views, const Detections& found);

}  // namespace purkinje::trackers
