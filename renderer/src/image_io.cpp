// The project's one OpenImageIO adapter.
//
// Images are encoded by OIIO into memory and written to disk here with
// plain POSIX calls, because OIIO 2.4's file writers do not report failed
// writes reliably. Measured with a 4 kB file-size limit: an EXR cut short
// at its final flush returns true from open, write_image and close with
// no error at all; the PNG writer returns true as well and leaves the
// failure only in geterror(). Writing the bytes with models' write_bytes
// also lets the error name the file and errno's reason exactly.

#include "purkinje/renderer/image_io.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/half.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

#include "purkinje/models/output_file.h"

namespace purkinje::renderer {
namespace {

// Debian's OpenImageIO is built without NDEBUG, so it prints "OIIO DEBUG"
// lines by default, one of them on every EXR write below (for the date we
// withhold on purpose). A user who sets OPENIMAGEIO_DEBUG keeps them.
void quiet_openimageio() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (std::getenv("OPENIMAGEIO_DEBUG") == nullptr) OIIO::attribute("debug", 0);
  });
}

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& reason) {
  std::string message = file.string();
  message += ": ";
  message += reason;
  throw OutputError(message);
}

// Encodes one image with the named OIIO writer ("png", "openexr") into
// memory. The path only labels OIIO's messages; the format is named
// explicitly because temporaries carry no image extension.
std::vector<unsigned char> encode(const char* format, const std::filesystem::path& file,
                                  const OIIO::ImageSpec& spec, OIIO::TypeDesc pixel_type,
                                  const void* pixels) {
  quiet_openimageio();
  std::vector<unsigned char> bytes;
  // The raw size bounds what the codecs write, less a header: one
  // allocation, where growing the vector copied it a dozen times.
  bytes.reserve(spec.image_bytes() + 65536);
  OIIO::Filesystem::IOVecOutput memory(bytes);
  auto output = OIIO::ImageOutput::create(format, &memory);
  if (!output)
    fail(file, std::string("cannot create a ") + format + " writer: " + OIIO::geterror());
  // A writer may report an error while returning true (see above).
  const bool written = output->open(file.string(), spec) &&
                       output->write_image(pixel_type, pixels) && output->close() &&
                       !output->has_error();
  if (!written) fail(file, std::string("cannot encode ") + format + ": " + output->geterror());
  return bytes;
}

std::unique_ptr<OIIO::ImageInput> open_input(const char* format,
                                             const std::filesystem::path& file) {
  quiet_openimageio();
  auto input = OIIO::ImageInput::create(format);
  if (!input) fail(file, std::string("cannot create a ") + format + " reader: " + OIIO::geterror());
  OIIO::ImageSpec spec;
  if (!input->open(file.string(), spec)) fail(file, "cannot read: " + input->geterror());
  return input;
}

std::string pixel_name(std::size_t index, int width) {
  std::string name = "(";
  name += std::to_string(index % static_cast<std::size_t>(width));
  name += ", ";
  name += std::to_string(index / static_cast<std::size_t>(width));
  name += ')';
  return name;
}

void validate(const SensorImage& image) {
  auto reject = [](const std::string& rule) { throw std::invalid_argument("write_png: " + rule); };
  if (image.bits != 8 && image.bits != 10 && image.bits != 12 && image.bits != 16)
    reject("bits = " + std::to_string(image.bits) + ": must be 8, 10, 12 or 16");
  if (image.width <= 0 || image.height <= 0)
    reject("size " + std::to_string(image.width) + " x " + std::to_string(image.height) +
           ": must be positive");
  const std::size_t pixels = static_cast<std::size_t>(image.width) * image.height;
  if (image.values.size() != pixels)
    reject(std::to_string(image.values.size()) + " values for " + std::to_string(image.width) +
           " x " + std::to_string(image.height) + " pixels");
  const unsigned maximum = (1u << image.bits) - 1u;
  for (std::size_t i = 0; i < pixels; ++i) {
    if (image.values[i] > maximum)
      reject("value " + std::to_string(image.values[i]) + " at pixel " +
             pixel_name(i, image.width) + " exceeds the " + std::to_string(image.bits) +
             "-bit maximum " + std::to_string(maximum));
  }
}

void validate(const std::vector<NamedPlane>& planes) {
  auto reject = [](const std::string& rule) { throw std::invalid_argument("write_exr: " + rule); };
  if (planes.empty()) reject("no planes to write");
  const int width = planes.front().plane.width;
  const int height = planes.front().plane.height;
  if (width <= 0 || height <= 0)
    reject("size " + std::to_string(width) + " x " + std::to_string(height) + ": must be positive");
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  std::set<std::string> names;
  for (const NamedPlane& p : planes) {
    const std::string quoted = "plane \"" + p.name + "\"";
    if (p.name.empty()) reject("a plane has an empty name");
    // OIIO would silently rename a duplicate to "channelN".
    if (!names.insert(p.name).second) reject(quoted + " appears twice");
    if (p.plane.width != width || p.plane.height != height)
      reject(quoted + " is " + std::to_string(p.plane.width) + " x " +
             std::to_string(p.plane.height) + ", the first plane \"" + planes.front().name +
             "\" is " + std::to_string(width) + " x " + std::to_string(height));
    if (p.plane.values.size() != pixels)
      reject(quoted + " has " + std::to_string(p.plane.values.size()) + " values for " +
             std::to_string(pixels) + " pixels");
    // Infinity is a legitimate value (depth of the background), NaN never.
    // Looked for in a loop the compiler vectorizes; found, named.
    bool has_nan = false;
    for (const float v : p.plane.values) has_nan |= v != v;
    if (has_nan) {
      const auto at = std::find_if(p.plane.values.begin(), p.plane.values.end(), [](float v) { return v != v; });
      reject(quoted + " is NaN at pixel " + pixel_name(static_cast<std::size_t>(at - p.plane.values.begin()), width));
    }
  }
}

}  // namespace

void write_png(const std::filesystem::path& file, const SensorImage& image) {
  validate(image);
  const std::size_t pixels = image.values.size();
  OIIO::ImageSpec spec(image.width, image.height, 1,
                       image.bits == 8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16);
  spec.channelnames = {"Y"};
  // zlib level 1: measured on a 1280 x 1024 12-bit eye-like image, 7x
  // faster than OIIO's default 6 (66 against 490 ms) for a file 6% larger.
  spec.attribute("png:compressionLevel", 1);
  std::vector<unsigned char> bytes;
  if (image.bits == 8) {
    std::vector<unsigned char> narrow(image.values.begin(), image.values.end());
    bytes = encode("png", file, spec, OIIO::TypeDesc::UINT8, narrow.data());
  } else {
    std::vector<unsigned short> wide(pixels);
    const int shift = 16 - image.bits;
    for (std::size_t i = 0; i < pixels; ++i)
      wide[i] = static_cast<unsigned short>(image.values[i] << shift);
    bytes = encode("png", file, spec, OIIO::TypeDesc::UINT16, wide.data());
  }
  write_bytes(file, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

void write_exr(const std::filesystem::path& file, const std::vector<NamedPlane>& planes, const ExrSettings& settings) {
  validate(planes);
  const int width = planes.front().plane.width;
  const int height = planes.front().plane.height;
  const std::size_t channels = planes.size();
  const std::size_t pixels = static_cast<std::size_t>(width) * height;

  OIIO::ImageSpec spec(width, height, static_cast<int>(channels),
                       settings.half ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT);
  spec.channelnames.clear();
  for (const NamedPlane& p : planes) spec.channelnames.push_back(p.name);
  // The default channel naming marks a fourth channel as alpha; none is.
  spec.alpha_channel = -1;
  spec.z_channel = -1;
  spec.attribute("compression", settings.compression);
  // OIIO stamps the current time as capDate unless a DateTime is given;
  // a null string counts as given and writes nothing, keeping the bytes
  // a function of the pixels alone.
  const char* no_date = nullptr;
  spec.attribute("DateTime", OIIO::TypeString, &no_date);

  std::vector<unsigned char> bytes;
  if (settings.half) {
    // Converted here: OIIO's own float-to-half conversion cost 40 ms for a
    // remote image's 13 planes, more than the fastest codecs' encoding.
    // Kept for the thread's next image: fresh memory costs a page fault
    // per 4 KB, a tenth of a fast codec's time.
    thread_local std::vector<half> interleaved;
    interleaved.resize(pixels * channels);
    std::vector<const float*> sources;
    for (const NamedPlane& p : planes) sources.push_back(p.plane.values.data());
    // Pixel by pixel: the output is written in order (plane by plane, it
    // was written with a stride of `channels`, a tenth of the encoding).
    half* out = interleaved.data();
    for (std::size_t i = 0; i < pixels; ++i) {
      for (std::size_t c = 0; c < channels; ++c) *out++ = half(sources[c][i]);
    }
    bytes = encode("openexr", file, spec, OIIO::TypeDesc::HALF, interleaved.data());
  } else {
    std::vector<float> interleaved(pixels * channels);
    for (std::size_t c = 0; c < channels; ++c) {
      const std::vector<float>& values = planes[c].plane.values;
      for (std::size_t i = 0; i < pixels; ++i) interleaved[i * channels + c] = values[i];
    }
    bytes = encode("openexr", file, spec, OIIO::TypeDesc::FLOAT, interleaved.data());
  }
  write_bytes(file, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

SensorImage read_png(const std::filesystem::path& file) {
  auto input = open_input("png", file);
  const OIIO::ImageSpec& spec = input->spec();
  if (spec.nchannels != 1)
    fail(file,
         "expected a single-channel PNG, found " + std::to_string(spec.nchannels) + " channels");
  // OIIO names only unusual depths (1, 2, 4 bits) in oiio:BitsPerSample.
  const int stored_bits =
      spec.get_int_attribute("oiio:BitsPerSample", static_cast<int>(spec.format.size()) * 8);
  if (stored_bits != 8 && stored_bits != 16)
    fail(file, "expected 8 or 16 bits per sample, found " + std::to_string(stored_bits));

  SensorImage image;
  image.width = spec.width;
  image.height = spec.height;
  image.bits = stored_bits;
  const std::size_t pixels = static_cast<std::size_t>(spec.width) * spec.height;
  image.values.resize(pixels);
  bool read = false;
  // Read in the stored type: OIIO would rescale 8-bit data read as 16-bit.
  if (stored_bits == 8) {
    std::vector<unsigned char> narrow(pixels);
    read = input->read_image(0, 0, 0, 1, OIIO::TypeDesc::UINT8, narrow.data());
    image.values.assign(narrow.begin(), narrow.end());
  } else {
    read = input->read_image(0, 0, 0, 1, OIIO::TypeDesc::UINT16, image.values.data());
  }
  if (!read) fail(file, "cannot read: " + input->geterror());
  return image;
}

std::vector<NamedPlane> read_exr(const std::filesystem::path& file) {
  auto input = open_input("openexr", file);
  const OIIO::ImageSpec& spec = input->spec();
  if (spec.deep) fail(file, "deep EXR images are not supported");
  const std::size_t channels = static_cast<std::size_t>(spec.nchannels);
  const std::size_t pixels = static_cast<std::size_t>(spec.width) * spec.height;
  std::vector<float> interleaved(pixels * channels);
  if (!input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, interleaved.data()))
    fail(file, "cannot read: " + input->geterror());

  std::vector<NamedPlane> planes(channels);
  for (std::size_t c = 0; c < channels; ++c) {
    planes[c].name = spec.channel_name(static_cast<int>(c));
    planes[c].plane = ImagePlane(spec.width, spec.height);
    for (std::size_t i = 0; i < pixels; ++i)
      planes[c].plane.values[i] = interleaved[i * channels + c];
  }
  return planes;
}

}  // namespace purkinje::renderer
