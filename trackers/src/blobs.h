#pragma once
// Labelling the 8-connected blobs of a sparse mask, shared by the glint and
// pupil detectors (internal to trackers/).

#include <opencv2/core.hpp>

#include <vector>

namespace purkinje::trackers {

// A blob's pixel count and bounding box.
struct Blob {
  int area = 0;
  cv::Rect box;
};

// The 8-connected blobs of a sparse mask, numbered from 1 in `labels`
// (CV_32S, the mask's size): from its non-zero pixels only, since
// cv::connectedComponentsWithStats scans the whole image at some length
// (1.1 ms for 640 x 480, a third of a frame's budget). `labels` must be
// zero where `mask` is set; `seeds` are left holding the mask's pixels
// (to clear `labels` by afterwards); `stack` is working space. Entry 0 of
// the result is the background.
std::vector<Blob> label_blobs(const cv::Mat& mask, cv::Mat& labels, std::vector<cv::Point>& seeds,
                              std::vector<cv::Point>& stack);

// Sets `labels` back to zero at `seeds` when it goes out of scope, however
// the scope is left.
class ClearLabels {
 public:
  ClearLabels(cv::Mat& labels, const std::vector<cv::Point>& seeds) : labels_(labels), seeds_(seeds) {}
  ~ClearLabels() {
    for (const cv::Point& p : seeds_) labels_.at<int>(p) = 0;
  }
  ClearLabels(const ClearLabels&) = delete;
  ClearLabels& operator=(const ClearLabels&) = delete;

 private:
  cv::Mat& labels_;
  const std::vector<cv::Point>& seeds_;
};

}  // namespace purkinje::trackers
