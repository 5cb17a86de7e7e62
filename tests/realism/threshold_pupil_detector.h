#pragma once
// An ordinary dark-pupil detector (threshold, morphology, contours, ellipse
// fit), the kind a tracker engineer writes in an afternoon with OpenCV. The
// realism test runs it on rendered sensor images: if the images look like
// real near-infrared eye images, it finds the pupil where the labels say.
//
// It lives with the test, not in trackers/, on purpose: trackers/ will get
// the real detectors (behind the pupil-detector interface, scored against
// labels), and trackers/ must never depend on renderer/. This one is a
// yardstick for the renderer's images, deliberately plain, and it reads
// nothing but 8-bit pixels.

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>
#include <random>
#include <vector>

namespace purkinje::realism {

// Tuned once on the bundled scenes' 8-bit images and left alone.
struct ThresholdPupilDetectorSettings {
  int dark_offset_dn = 4;         // the pupil: at most this far above the darkest (median-filtered) pixel
  int glint_fill_px = 7;          // closing that fills glints inside and on the pupil's edge
  int lid_reach_px = 7;           // contour points this close to a large bright region are the lid's edge
  int ransac_iterations = 2000;
  double inlier_px = 1.0;
  double min_axis_ratio = 0.25;   // a pupil seen at up to about 75 deg
  double min_dark_inside = 0.9;   // of the ellipse's interior not under a lid
};

namespace detail {

// Distance to an ellipse along the ray from its centre: near the curve,
// where inliers are, it is close to the true distance. The ellipse's frame
// is set up once, since RANSAC measures every contour point against it.
class EllipseDistance {
 public:
  explicit EllipseDistance(const cv::RotatedRect& e)
      : c_(e.center), cos_(std::cos(e.angle * std::numbers::pi / 180)),
        sin_(std::sin(e.angle * std::numbers::pi / 180)), a_(e.size.width / 2), b_(e.size.height / 2) {}
  double operator()(const cv::Point2f& p) const {
    const double dx = p.x - c_.x, dy = p.y - c_.y;
    const double x = cos_ * dx + sin_ * dy, y = -sin_ * dx + cos_ * dy;
    const double r = std::hypot(x / a_, y / b_);
    return r > 0 ? std::abs(1 - 1 / r) * std::hypot(x, y) : std::min(a_, b_);
  }

 private:
  cv::Point2f c_;
  double cos_, sin_, a_, b_;
};

// A pupil is dark inside, except where a lid covers it: of the interior
// samples not on bright lid or skin, the fraction that is dark.
inline double dark_inside(const cv::RotatedRect& e, const cv::Mat& dark, const cv::Mat& lids) {
  const double t = e.angle * std::numbers::pi / 180;
  int seen = 0, dark_count = 0;
  for (int k = 0; k < 16; ++k) {
    for (double s : {0.3, 0.7}) {
      const double x = s * e.size.width / 2 * std::cos(k * std::numbers::pi / 8);
      const double y = s * e.size.height / 2 * std::sin(k * std::numbers::pi / 8);
      const int u = static_cast<int>(std::lround(e.center.x + std::cos(t) * x - std::sin(t) * y));
      const int v = static_cast<int>(std::lround(e.center.y + std::sin(t) * x + std::cos(t) * y));
      const bool inside_image = u >= 0 && v >= 0 && u < dark.cols && v < dark.rows;
      if (inside_image && lids.at<std::uint8_t>(v, u) && !dark.at<std::uint8_t>(v, u)) continue;
      ++seen;
      if (inside_image && dark.at<std::uint8_t>(v, u)) ++dark_count;
    }
  }
  return seen > 0 ? static_cast<double>(dark_count) / seen : 0.0;
}

inline bool plausible_pupil(const cv::RotatedRect& e, double max_axis, double min_axis_ratio) {
  const double lo = std::min(e.size.width, e.size.height), hi = std::max(e.size.width, e.size.height);
  return std::isfinite(e.center.x) && std::isfinite(e.center.y) && lo > 2 && hi < max_axis &&
         lo > min_axis_ratio * hi;
}

}  // namespace detail

struct PupilEllipse {
  cv::RotatedRect ellipse;  // centre in OpenCV pixel coordinates (pixel centres at integers)
  std::size_t support = 0;  // contour points on it
};

// Finds the dark pupil in an 8-bit single-channel image of an eye region.
inline std::optional<PupilEllipse> detect_pupil(const cv::Mat& image,
                                                const ThresholdPupilDetectorSettings& s = {}) {
  CV_Assert(image.type() == CV_8UC1);
  const auto disc = [](int size) { return cv::getStructuringElement(cv::MORPH_ELLIPSE, {size, size}); };
  cv::Mat smooth;
  cv::medianBlur(image, smooth, 3);  // sensor noise; unlike a Gaussian, it does not smear glints into a small pupil
  double darkest = 0;
  cv::minMaxLoc(smooth, &darkest);
  cv::Mat dark;
  cv::threshold(smooth, dark, darkest + s.dark_offset_dn, 255, cv::THRESH_BINARY_INV);
  cv::morphologyEx(dark, dark, cv::MORPH_CLOSE, disc(s.glint_fill_px));
  cv::morphologyEx(dark, dark, cv::MORPH_OPEN, disc(3));

  // Otsu splits the eye region into dark (pupil, iris, shadows) and bright
  // (skin, lids, sclera, glints); opening drops the glints, which closing
  // has already dealt with, and leaves the large bright regions: the lids.
  // Where the dark region meets them its edge is the lid's, not the pupil's.
  cv::Mat lids;
  cv::threshold(smooth, lids, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
  cv::morphologyEx(lids, lids, cv::MORPH_OPEN, disc(s.glint_fill_px));
  cv::dilate(lids, lids, disc(s.lid_reach_px));

  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(dark, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  std::optional<PupilEllipse> best;
  for (const std::vector<cv::Point>& contour : contours) {
    if (cv::contourArea(contour) < 20) continue;
    std::vector<cv::Point2f> edge;
    for (const cv::Point& p : contour) {
      if (!lids.at<std::uint8_t>(p)) edge.emplace_back(p);
    }
    if (edge.size() < 6) continue;
    // RANSAC: a lid or its shadow cuts the pupil's outline with a foreign
    // edge, which a least-squares fit to the whole contour would follow.
    std::mt19937 rng(1);
    std::vector<cv::Point2f> inliers;
    for (int i = 0; i < s.ransac_iterations; ++i) {
      std::vector<cv::Point2f> sample;
      for (int k = 0; k < 5; ++k) sample.push_back(edge[rng() % edge.size()]);
      const cv::RotatedRect e = cv::fitEllipseDirect(sample);
      if (!detail::plausible_pupil(e, std::max(image.cols, image.rows), s.min_axis_ratio) ||
          detail::dark_inside(e, dark, lids) < s.min_dark_inside) {
        continue;
      }
      const detail::EllipseDistance distance(e);
      std::vector<cv::Point2f> on_it;
      for (const cv::Point2f& p : edge) {
        if (distance(p) < s.inlier_px) on_it.push_back(p);
      }
      if (on_it.size() > inliers.size()) inliers = std::move(on_it);
    }
    if (inliers.size() < 6 || (best && inliers.size() <= best->support)) continue;
    const cv::RotatedRect e = cv::fitEllipse(inliers);
    if (detail::plausible_pupil(e, std::max(image.cols, image.rows), s.min_axis_ratio)) {
      best = PupilEllipse{e, inliers.size()};
    }
  }
  return best;
}

}  // namespace purkinje::realism
