// Segmentation images as indexed PNG through libpng: OpenImageIO writes no
// palette PNG, and an 8-bit grey image of the classes 0..6 shows black in
// every viewer. The project's one libpng adapter.

#include <png.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "purkinje/models/output_file.h"
#include "purkinje/renderer/image_io.h"

namespace purkinje::renderer {
namespace {

constexpr int kClassCount = 7;
// background, skin, sclera, iris, pupil, lash, brow: distinct at a glance.
constexpr std::array<png_color, kClassCount> kPalette = {{
    {0, 0, 0},
    {222, 170, 135},
    {240, 240, 240},
    {60, 110, 200},
    {200, 30, 60},
    {250, 200, 0},
    {120, 70, 30},
}};

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& reason) {
  throw OutputError(file.string() + ": " + reason);
}

// libpng reports errors by longjmp; these turn them into the message the
// caller throws once setjmp returns.
void on_error(png_structp png, png_const_charp message) {
  *static_cast<std::string*>(png_get_error_ptr(png)) = message;
  png_longjmp(png, 1);
}
void on_warning(png_structp, png_const_charp) {}

void append(png_structp png, png_bytep data, png_size_t length) {
  auto* bytes = static_cast<std::vector<unsigned char>*>(png_get_io_ptr(png));
  bytes->insert(bytes->end(), data, data + length);
}
void no_flush(png_structp) {}

}  // namespace

void write_class_png(const std::filesystem::path& file, const ImagePlane& classes) {
  if (classes.width <= 0 || classes.height <= 0 ||
      classes.values.size() != static_cast<std::size_t>(classes.width) * classes.height) {
    throw std::invalid_argument("write_class_png: " + std::to_string(classes.width) + " x " +
                                std::to_string(classes.height) + " pixels with " +
                                std::to_string(classes.values.size()) + " values");
  }
  std::vector<unsigned char> pixels(classes.values.size());
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const float v = classes.values[i];
    if (!(v >= 0 && v < kClassCount && v == std::floor(v))) {
      throw std::invalid_argument("write_class_png: value " + std::to_string(v) + " at pixel " + std::to_string(i) +
                                  " is not a class (0 to " + std::to_string(kClassCount - 1) + ")");
    }
    pixels[i] = static_cast<unsigned char>(v);
  }
  // Everything with a destructor lives before setjmp: libpng's longjmp
  // skips the frames between.
  std::string error;
  std::vector<unsigned char> bytes;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, on_error, on_warning);
  if (png == nullptr) fail(file, "cannot create a PNG writer");
  png_infop info = png_create_info_struct(png);
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    fail(file, "cannot encode the class PNG: " + error);
  }
  png_set_write_fn(png, &bytes, append, no_flush);
  // Level 1: classes are long runs, which the fastest level already packs.
  png_set_compression_level(png, 1);
  png_set_IHDR(png, info, static_cast<png_uint_32>(classes.width), static_cast<png_uint_32>(classes.height), 8,
               PNG_COLOR_TYPE_PALETTE, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_PLTE(png, info, kPalette.data(), kClassCount);
  png_write_info(png, info);
  for (int y = 0; y < classes.height; ++y) {
    png_write_row(png, pixels.data() + static_cast<std::size_t>(y) * classes.width);
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  write_bytes(file, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

ImagePlane read_class_png(const std::filesystem::path& file) {
  std::FILE* in = std::fopen(file.c_str(), "rb");
  if (in == nullptr) fail(file, "cannot open");
  std::string error;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &error, on_error, on_warning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  // Everything with a destructor lives before setjmp: libpng's longjmp
  // skips the frames between.
  ImagePlane out;
  std::vector<unsigned char> row;
  if (png == nullptr || info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    std::fclose(in);
    fail(file, "cannot read the class PNG: " + error);
  }
  png_init_io(png, in);
  png_read_info(png, info);
  if (png_get_color_type(png, info) != PNG_COLOR_TYPE_PALETTE || png_get_bit_depth(png, info) != 8) {
    error = "not an 8-bit indexed PNG";
    png_longjmp(png, 1);
  }
  const int width = static_cast<int>(png_get_image_width(png, info));
  const int height = static_cast<int>(png_get_image_height(png, info));
  row.resize(static_cast<std::size_t>(width));
  out = ImagePlane(width, height);
  for (int y = 0; y < height; ++y) {
    png_read_row(png, row.data(), nullptr);
    for (int x = 0; x < width; ++x) out.at(x, y) = row[static_cast<std::size_t>(x)];
  }
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  std::fclose(in);
  return out;
}

}  // namespace purkinje::renderer
