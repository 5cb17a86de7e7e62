#pragma once
// The detectors read plain memory; the tests draw with OpenCV.

#include <opencv2/core.hpp>

#include "purkinje/trackers/image.h"

namespace purkinje::trackers {

inline GreyView view(const cv::Mat& image, int bits = 0) {
  return {image.data, image.cols, image.rows, image.step[0], static_cast<int>(image.elemSize()),
          bits > 0 ? bits : image.depth() == CV_8U ? 8 : 16};
}

}  // namespace purkinje::trackers
