#include "blobs.h"

#include <algorithm>
#include <cstdint>

namespace purkinje::trackers {

std::vector<Blob> label_blobs(const cv::Mat& mask, cv::Mat& labels, std::vector<cv::Point>& seeds,
                              std::vector<cv::Point>& stack) {
  cv::findNonZero(mask, seeds);
  std::vector<Blob> blobs(1);  // blob 0: the background
  for (const cv::Point& seed : seeds) {
    if (labels.at<int>(seed) != 0) continue;
    const int label = static_cast<int>(blobs.size());
    Blob blob;
    int u0 = seed.x, u1 = seed.x, v0 = seed.y, v1 = seed.y;
    labels.at<int>(seed) = label;
    stack.assign(1, seed);
    while (!stack.empty()) {
      const cv::Point p = stack.back();
      stack.pop_back();
      ++blob.area;
      u0 = std::min(u0, p.x), u1 = std::max(u1, p.x), v0 = std::min(v0, p.y), v1 = std::max(v1, p.y);
      for (int dv = -1; dv <= 1; ++dv) {
        for (int du = -1; du <= 1; ++du) {
          const cv::Point q(p.x + du, p.y + dv);
          if (q.x < 0 || q.y < 0 || q.x >= mask.cols || q.y >= mask.rows) continue;
          if (!mask.at<std::uint8_t>(q) || labels.at<int>(q) != 0) continue;
          labels.at<int>(q) = label;
          stack.push_back(q);
        }
      }
    }
    blob.box = cv::Rect(u0, v0, u1 - u0 + 1, v1 - v0 + 1);
    blobs.push_back(blob);
  }
  return blobs;
}


}  // namespace purkinje::trackers
