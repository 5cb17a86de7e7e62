// MJPEG-like compression of sensor images through libjpeg, the project's
// one use of it. Not through OpenImageIO: render() calls this, and the
// Python package's core module must not load OpenImageIO's hundreds of
// libraries (python/src/bindings.h).

// jpeglib.h needs size_t and FILE declared before it.
#include <cstddef>
#include <cstdio>

#include <jpeglib.h>

#include <csetjmp>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "purkinje/renderer/sensor_model.h"

namespace purkinje::renderer {
namespace {

// libjpeg's default error handler exits the process; this one jumps back
// to the setjmp with the message kept.
struct ErrorManager {
  jpeg_error_mgr base;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void on_error(j_common_ptr info) {
  auto* errors = reinterpret_cast<ErrorManager*>(info->err);
  (*info->err->format_message)(info, errors->message);
  std::longjmp(errors->jump, 1);
}

void on_message(j_common_ptr, int) {}  // no warnings on stderr

// libjpeg's state and error handler for one image, owned by the caller:
// the setjmp frames below hold only a pointer to it, which the jump
// leaves as it was. Both structs report to `errors` (jpeg_create_*
// keep the handler set here).
struct Codec {
  jpeg_compress_struct compress{};
  jpeg_decompress_struct decompress{};
  ErrorManager errors{};

  Codec() {
    compress.err = decompress.err = jpeg_std_error(&errors.base);
    errors.base.error_exit = on_error;
    errors.base.emit_message = on_message;
  }
  Codec(const Codec&) = delete;
  Codec& operator=(const Codec&) = delete;
};

// Encodes an 8-bit grey image into `buffer` (of `*size` bytes, large
// enough for any JPEG of the image: libjpeg then never allocates one of
// its own); `*size` becomes the JPEG's. Returns false with `message` set
// on failure.
bool encode(Codec* codec, const unsigned char* pixels, int width, int height, int quality, unsigned char* buffer,
            unsigned long* size, char* message) {
  jpeg_compress_struct* info = &codec->compress;
  if (setjmp(codec->errors.jump)) {
    std::snprintf(message, JMSG_LENGTH_MAX, "%s", codec->errors.message);
    jpeg_destroy_compress(info);
    return false;
  }
  jpeg_create_compress(info);
  unsigned char* out = buffer;
  jpeg_mem_dest(info, &out, size);
  info->image_width = static_cast<JDIMENSION>(width);
  info->image_height = static_cast<JDIMENSION>(height);
  info->input_components = 1;
  info->in_color_space = JCS_GRAYSCALE;
  jpeg_set_defaults(info);
  jpeg_set_quality(info, quality, TRUE);
  jpeg_start_compress(info, TRUE);
  while (info->next_scanline < info->image_height) {
    JSAMPROW row = const_cast<unsigned char*>(pixels) + static_cast<std::size_t>(info->next_scanline) * width;
    jpeg_write_scanlines(info, &row, 1);
  }
  jpeg_finish_compress(info);
  jpeg_destroy_compress(info);
  if (out != buffer) {  // cannot happen with the caller's bound; never leak
    std::free(out);
    std::snprintf(message, JMSG_LENGTH_MAX, "the JPEG outgrew its buffer");
    return false;
  }
  return true;
}

bool decode(Codec* codec, const unsigned char* bytes, unsigned long size, int width, int height, unsigned char* pixels,
            char* message) {
  jpeg_decompress_struct* info = &codec->decompress;
  if (setjmp(codec->errors.jump)) {
    std::snprintf(message, JMSG_LENGTH_MAX, "%s", codec->errors.message);
    jpeg_destroy_decompress(info);
    return false;
  }
  jpeg_create_decompress(info);
  jpeg_mem_src(info, bytes, size);
  jpeg_read_header(info, TRUE);
  info->out_color_space = JCS_GRAYSCALE;
  jpeg_start_decompress(info);
  if (info->output_width != static_cast<JDIMENSION>(width) || info->output_height != static_cast<JDIMENSION>(height) ||
      info->output_components != 1) {
    std::snprintf(message, JMSG_LENGTH_MAX, "decoded %u x %u x %d, not %d x %d x 1", info->output_width,
                  info->output_height, info->output_components, width, height);
    jpeg_destroy_decompress(info);
    return false;
  }
  while (info->output_scanline < info->output_height) {
    JSAMPROW row = pixels + static_cast<std::size_t>(info->output_scanline) * width;
    jpeg_read_scanlines(info, &row, 1);
  }
  jpeg_finish_decompress(info);
  jpeg_destroy_decompress(info);
  return true;
}

}  // namespace

void compress_jpeg(SensorImage& image, int quality) {
  if (image.bits != 8) {
    throw std::invalid_argument("compress_jpeg: bits = " + std::to_string(image.bits) + ": JPEG holds 8 bits");
  }
  if (quality < 1 || quality > 100) {
    throw std::invalid_argument("compress_jpeg: quality = " + std::to_string(quality) + ": must be 1 to 100");
  }
  if (image.width <= 0 || image.height <= 0 ||
      image.values.size() != static_cast<std::size_t>(image.width) * image.height) {
    throw std::invalid_argument("compress_jpeg: " + std::to_string(image.values.size()) + " values for " +
                                std::to_string(image.width) + " x " + std::to_string(image.height) + " pixels");
  }
  std::vector<unsigned char> pixels(image.values.size());
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    if (image.values[i] > 255) {
      throw std::invalid_argument("compress_jpeg: value " + std::to_string(image.values[i]) + " exceeds 8 bits");
    }
    pixels[i] = static_cast<unsigned char>(image.values[i]);
  }
  // A baseline JPEG codes each 8 x 8 block in at most 64 x (16 + 11) bits,
  // 3.4 bytes a pixel; 4 a pixel and the headers' room bound any image.
  std::vector<unsigned char> bytes(4 * pixels.size() + 65536);
  unsigned long size = static_cast<unsigned long>(bytes.size());
  Codec codec;
  char message[JMSG_LENGTH_MAX] = {};
  const bool decoded = encode(&codec, pixels.data(), image.width, image.height, quality, bytes.data(), &size, message) &&
                       decode(&codec, bytes.data(), size, image.width, image.height, pixels.data(), message);
  if (!decoded) throw std::runtime_error(std::string("compress_jpeg: libjpeg: ") + message);
  for (std::size_t i = 0; i < pixels.size(); ++i) image.values[i] = pixels[i];
}

}  // namespace purkinje::renderer
