#pragma once
// Image files through OpenImageIO. Written into a FileSet
// (models/output_file.h), they go to temporaries beside their targets and
// are renamed into place only when all of them were written, so a failure
// (unwritable folder, full disk) leaves no partial image or label file.

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "purkinje/models/output_file.h"
#include "purkinje/renderer/image.h"

namespace purkinje::renderer {

using purkinje::OutputError;

// PNG of the sensor image: 8-bit for bits = 8, otherwise 16-bit with the
// values shifted to the most significant bits (so a 12-bit image looks
// right in any viewer; value >> (16 - bits) recovers the DN).
void write_png(const std::filesystem::path& file, const SensorImage& image);
// How an EXR stores its planes: 32-bit or half floats, and the codec
// (OpenEXR's names: "none", "rle", "zips", "zip", "piz", "pxr24", "b44",
// "b44a", "dwaa", "dwab"; the lossy ones change the values).
struct ExrSettings {
  bool half = false;
  std::string compression = "zip";
};

// OpenEXR, one channel per plane (32-bit float, zip unless `settings` say
// otherwise). OpenEXR stores the
// channels sorted by name, so readers see them in that (or their own)
// order, not the given one. Planes must share one size and have distinct,
// non-empty names; NaN is rejected (infinity is kept). Both writers throw
// std::invalid_argument for bad input and OutputError when writing fails,
// and put no date or software name in the file: equal inputs give equal
// bytes.
void write_exr(const std::filesystem::path& file, const std::vector<NamedPlane>& planes,
               const ExrSettings& settings = {});
// An indexed (palette) 8-bit PNG of the pixel classes (the "id" AOV: 0
// background, 1 skin, 2 sclera, 3 iris, 4 pupil): each pixel's byte is its
// class, which numpy and PIL read as is; viewers show the palette's
// colours. Throws std::invalid_argument for a value that is not a class,
// OutputError when writing fails; no date in the file.
void write_class_png(const std::filesystem::path& file, const ImagePlane& classes);
// Reads a class PNG back: the class indices (for tests and tools).
ImagePlane read_class_png(const std::filesystem::path& file);

// Reads a PNG written by write_png back (for tests and tools); DN values
// as written, before any bit shift is undone. Throws OutputError on failure.
SensorImage read_png(const std::filesystem::path& file);
// Reads every channel of an EXR file. Throws OutputError on failure.
std::vector<NamedPlane> read_exr(const std::filesystem::path& file);

using purkinje::FileSet;

}  // namespace purkinje::renderer
