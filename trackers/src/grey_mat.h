#pragma once
// The trackers' own bridge from image views to OpenCV (kept out of the
// public headers: OpenCV is private to trackers/).

#include <opencv2/core.hpp>

#include <string>

#include "purkinje/trackers/image.h"

namespace purkinje::trackers {

// The image as an OpenCV matrix (CV_8U or CV_16U) over the same memory,
// after checking it. Throws std::invalid_argument naming `who`, the field,
// its value and the rule.
cv::Mat mat_of(const GreyView& image, const std::string& who);

}  // namespace purkinje::trackers
