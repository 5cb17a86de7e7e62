#include "purkinje/studies/image_set.h"

#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>

#include "purkinje/models/input_file.h"

namespace purkinje::studies {

namespace fs = std::filesystem;

std::vector<fs::path> labels_files(const std::vector<std::string>& inputs,
                                  const std::function<void(const std::string&)>& note) {
  std::vector<fs::path> files;
  for (const std::string& input : inputs) {
    const fs::path path(input);
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
      std::vector<fs::path> in_folder;
      std::set<fs::path> image_stems;
      for (const fs::directory_entry& e : fs::directory_iterator(path)) {
        if (!e.is_regular_file()) continue;
        const fs::path extension = e.path().extension();
        if (extension == ".json") in_folder.push_back(e.path());
        if (extension == ".png" || extension == ".tif" || extension == ".tiff" || extension == ".pgm") {
          image_stems.insert(e.path().stem());
        }
      }
      std::vector<std::string> left_out;
      std::erase_if(in_folder, [&](const fs::path& f) {
        const bool labels = image_stems.count(f.stem()) > 0;
        if (!labels) left_out.push_back(f.filename().string());
        return !labels;
      });
      if (in_folder.empty()) {
        throw std::runtime_error(input + ": a folder without labels files (.json beside an image of the same name)");
      }
      if (!left_out.empty()) {
        std::sort(left_out.begin(), left_out.end());
        if (note) note(input + ": " + std::to_string(left_out.size()) + " .json files without an image beside them left out (" +
             left_out.front() + (left_out.size() > 1 ? ", ..." : "") + ")");
      }
      std::sort(in_folder.begin(), in_folder.end());
      files.insert(files.end(), in_folder.begin(), in_folder.end());
    } else if (path.extension() == ".json") {
      files.push_back(path);
    } else {
      files.push_back(fs::path(path).replace_extension(".json"));
    }
  }
  return files;
}

std::vector<LabelledImage> read_labelled_images(const std::vector<fs::path>& files, const std::function<void()>& step) {
  std::vector<LabelledImage> images;
  std::map<std::string, fs::path> seen;
  for (const fs::path& file : files) {
    LabelledImage image{"", read_image_labels(file)};
    image.name = image.labels.image.filename().string();
    if (image.labels.image_check) {
      std::error_code ec;
      const std::uintmax_t bytes = fs::file_size(image.labels.image, ec);
      if (!ec && bytes != image.labels.image_check->bytes) {
        throw std::runtime_error(image.labels.image.string() + ": does not match its labels (" + std::to_string(bytes) +
                                 " bytes; the labels say " + std::to_string(image.labels.image_check->bytes) +
                                 "): a unit a run left half replaced; render it again (render --resume)");
      }
    }
    const auto [it, fresh] = seen.emplace(image.name, file);
    if (!fresh) {
      throw std::runtime_error(file.string() + ": labels an image named " + image.name + ", as " +
                               it->second.string() + " does: image names must differ");
    }
    images.push_back(std::move(image));
    if (step) step();
  }
  return images;
}

trackers::GreyImage read_pixels(const LabelledImage& image) {
  // An image that differs from its labels' record is another run's (a run
  // killed between renaming an image and its labels).
  if (image.labels.image_check) {
    const FileCheck found = file_check_of(read_input_file(image.labels.image, kMaxImageFileBytes, "an image file"));
    if (found != *image.labels.image_check) {
      throw std::runtime_error(image.labels.image.string() + ": does not match its labels (" +
                               std::to_string(found.bytes) + " bytes, CRC-32 " + crc32_text(found.crc32) +
                               "; the labels say " + std::to_string(image.labels.image_check->bytes) + " bytes, " +
                               crc32_text(image.labels.image_check->crc32) +
                               "): a unit a run left half replaced; render it again (render --resume)");
    }
  }
  trackers::GreyImage pixels = trackers::read_grey_image(image.labels.image, image.labels.bits);
  if (pixels.width != image.labels.width_px || pixels.height != image.labels.height_px) {
    throw std::runtime_error(image.labels.image.string() + ": " + std::to_string(pixels.width) + " x " +
                             std::to_string(pixels.height) + " pixels; its labels say " +
                             std::to_string(image.labels.width_px) + " x " + std::to_string(image.labels.height_px));
  }
  return pixels;
}

}  // namespace purkinje::studies
