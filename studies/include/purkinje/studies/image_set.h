#pragma once
// A labelled image set as commands and bindings read it: the labels files
// their inputs name, each image's labels, and its pixels checked against
// what the labels record of them.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "purkinje/models/labels.h"
#include "purkinje/trackers/image_file.h"

namespace purkinje::studies {

struct LabelledImage {
  std::string name;  // the image's file name: how detections files name it
  ImageLabels labels;
};

// The labels files the inputs name: a labels file itself, an image beside
// its labels (same name, .json), or a folder (its .json files that have an
// image of the same name beside them, in order: a score.json or any other
// JSON file in the folder is no image's labels). `note` is told a line,
// as each folder is read, for its JSON files left out so. Throws
// std::runtime_error for a folder without labels files.
std::vector<std::filesystem::path> labels_files(const std::vector<std::string>& inputs,
                                                const std::function<void(const std::string&)>& note);

// Each labels file read, in order, `step` called after each. Throws
// std::runtime_error naming the file for labels that cannot be read, an
// image whose size is not the labels' record (a unit a killed run left
// half replaced: score reads no pixels but is refused it too), or two
// labels files naming images alike.
std::vector<LabelledImage> read_labelled_images(const std::vector<std::filesystem::path>& files,
                                                const std::function<void()>& step = {});

// The image's pixels. Throws std::runtime_error naming the image when its
// bytes are not those its labels record (size and CRC-32) or its pixels
// not the labels' width and height.
trackers::GreyImage read_pixels(const LabelledImage& image);

}  // namespace purkinje::studies
