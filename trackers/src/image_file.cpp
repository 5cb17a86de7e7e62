#include "purkinje/trackers/image_file.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <string>

#include "purkinje/models/input_file.h"
#include "purkinje/models/labels.h"
#include "purkinje/models/output_file.h"

namespace purkinje::trackers {

GreyImage read_grey_image(const std::filesystem::path& file, int bits) {
  const auto fail = [&](const std::string& rule) { throw std::runtime_error(file.string() + ": " + rule); };
  if (bits < 1 || bits > 16) fail("bits = " + std::to_string(bits) + ": must be in [1, 16]");
  std::string bytes;
  try {
    bytes = read_input_file(file, kMaxImageFileBytes, "an image file");
  } catch (const InputFileError& e) {
    fail("cannot be read: " + e.reason());
  }
  cv::Mat m;
  try {
    const cv::Mat encoded(1, static_cast<int>(bytes.size()), CV_8U, bytes.data());
    m = cv::imdecode(encoded, cv::IMREAD_ANYDEPTH | cv::IMREAD_GRAYSCALE);
  } catch (const cv::Exception& e) {
    fail(std::string("cannot be read as an image: ") + e.what());
  }
  if (m.empty()) fail("cannot be read as an image (not a format OpenCV reads)");
  if (m.depth() != CV_8U && m.depth() != CV_16U) fail("must hold 8- or 16-bit integers");
  if (m.depth() == CV_8U && bits > 8) {
    fail("an 8-bit image for a sensor of " + std::to_string(bits) + " bits: expected a 16-bit file");
  }
  GreyImage image;
  image.width = m.cols;
  image.height = m.rows;
  image.bits = bits;
  image.pixels.resize(static_cast<std::size_t>(m.cols) * m.rows);
  const int shift = m.depth() == CV_16U ? 16 - bits : 0;
  for (int y = 0; y < m.rows; ++y) {
    for (int x = 0; x < m.cols; ++x) {
      const int value = m.depth() == CV_8U ? m.at<std::uint8_t>(y, x) : m.at<std::uint16_t>(y, x) >> shift;
      image.pixels[static_cast<std::size_t>(y) * m.cols + x] = static_cast<std::uint16_t>(value);
    }
  }
  return image;
}

namespace {

const cv::Scalar kLabel(0, 200, 0), kDetection(0, 0, 255);  // BGR

// The part of the image drawn, and how much it is enlarged.
struct Frame {
  cv::Rect crop;
  int scale = 1;
  cv::Point2f at(const Pixel& p) const {
    // Pixel centres at integers; an enlarged pixel's centre sits at k p + (k - 1) / 2.
    return {static_cast<float>(scale * (p.u - crop.x) + 0.5 * (scale - 1)),
            static_cast<float>(scale * (p.v - crop.y) + 0.5 * (scale - 1))};
  }
};

// Around everything labelled or found, with a margin, enlarged to about
// 640 px across: a remote camera's eye is a few dozen pixels wide.
Frame frame_of(const GreyImage& image, const std::vector<EyeInCameraTruth>& views, const Detections& found) {
  double u0 = INFINITY, v0 = INFINITY, u1 = -INFINITY, v1 = -INFINITY;
  const auto take = [&](const Pixel& p, double r) {
    if (!std::isfinite(p.u) || !std::isfinite(p.v)) return;
    u0 = std::min(u0, p.u - r), u1 = std::max(u1, p.u + r), v0 = std::min(v0, p.v - r), v1 = std::max(v1, p.v + r);
  };
  for (const EyeInCameraTruth& view : views) {
    for (const GlintTruth& g : view.glints) {
      if (g.status == PathStatus::ok) take(g.pixel, 0);
    }
    if (view.pupil.ellipse_valid) take(view.pupil.ellipse.center, view.pupil.ellipse.semi_axis_1_px);
  }
  for (const Glint& g : found.glints) take(g.centre, 0);
  for (const PupilFound& p : found.pupils) take(p.centre, p.ellipse ? p.ellipse->semi_axis_1_px : 0);
  const cv::Rect whole(0, 0, image.width, image.height);
  if (!(u1 >= u0 && v1 >= v0)) return {whole, 1};
  const double margin = std::max(24.0, 0.6 * std::max(u1 - u0, v1 - v0));
  const auto clamp = [](double x, int lo, int hi) { return std::clamp(static_cast<int>(std::floor(x)), lo, hi); };
  const int x0 = clamp(u0 - margin, 0, image.width - 1), y0 = clamp(v0 - margin, 0, image.height - 1);
  const int x1 = clamp(u1 + margin, x0, image.width - 1), y1 = clamp(v1 + margin, y0, image.height - 1);
  const cv::Rect crop(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
  return {crop, std::clamp(640 / std::max(crop.width, crop.height), 1, 8)};
}

void cross(cv::Mat& m, const Frame& f, const Pixel& p, const cv::Scalar& colour, bool diagonal) {
  const cv::Point2f c = f.at(p);
  const float s = 6;
  if (diagonal) {
    cv::line(m, c + cv::Point2f(-s, -s), c + cv::Point2f(s, s), colour, 1, cv::LINE_AA);
    cv::line(m, c + cv::Point2f(-s, s), c + cv::Point2f(s, -s), colour, 1, cv::LINE_AA);
  } else {
    cv::line(m, c + cv::Point2f(-s, 0), c + cv::Point2f(s, 0), colour, 1, cv::LINE_AA);
    cv::line(m, c + cv::Point2f(0, -s), c + cv::Point2f(0, s), colour, 1, cv::LINE_AA);
  }
}

void ellipse(cv::Mat& m, const Frame& f, const Ellipse& e, const cv::Scalar& colour) {
  if (!(e.semi_axis_1_px > 0 && e.semi_axis_2_px > 0)) return;
  const cv::Size2f axes(static_cast<float>(2 * f.scale * e.semi_axis_1_px),
                        static_cast<float>(2 * f.scale * e.semi_axis_2_px));
  cv::ellipse(m, cv::RotatedRect(f.at(e.center), axes, static_cast<float>(e.angle_rad * 180 / std::numbers::pi)),
              colour, 1, cv::LINE_AA);
}

void number(cv::Mat& m, const Frame& f, const Pixel& p, int n, const cv::Point2f& offset, const cv::Scalar& colour) {
  cv::putText(m, std::to_string(n), f.at(p) + offset, cv::FONT_HERSHEY_PLAIN, 1.0, colour, 1, cv::LINE_AA);
}

}  // namespace

void write_overlay(const std::filesystem::path& file, const GreyImage& image,
                   const std::vector<EyeInCameraTruth>& views, const Detections& found) {
  const Frame f = frame_of(image, views, found);
  cv::Mat grey(f.crop.height, f.crop.width, CV_8U);
  const int shift = std::max(0, image.bits - 8);
  for (int y = 0; y < f.crop.height; ++y) {
    for (int x = 0; x < f.crop.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y + f.crop.y) * image.width + x + f.crop.x;
      grey.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(std::min(255, image.pixels[i] >> shift));
    }
  }
  cv::Mat big, colour;
  cv::resize(grey, big, {}, f.scale, f.scale, cv::INTER_NEAREST);
  cv::cvtColor(big, colour, cv::COLOR_GRAY2BGR);
  for (const EyeInCameraTruth& view : views) {
    for (const GlintTruth& g : view.glints) {
      if (g.status != PathStatus::ok) continue;
      cross(colour, f, g.pixel, kLabel, false);
      number(colour, f, g.pixel, g.illuminator, {6, -6}, kLabel);
    }
    if (view.pupil.ellipse_valid) {
      ellipse(colour, f, view.pupil.ellipse, kLabel);
      cross(colour, f, view.pupil.ellipse.center, kLabel, false);
    }
  }
  for (const Glint& g : found.glints) {
    cross(colour, f, g.centre, kDetection, true);
    if (g.illuminator >= 0) number(colour, f, g.centre, g.illuminator, {6, 16}, kDetection);
  }
  for (const PupilFound& p : found.pupils) {
    if (p.ellipse) ellipse(colour, f, *p.ellipse, kDetection);
    cross(colour, f, p.centre, kDetection, true);
  }
  cv::putText(colour, "green: labels, red: detections", {6, colour.rows - 8}, cv::FONT_HERSHEY_PLAIN, 1.0,
              cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  std::vector<unsigned char> png;
  if (!cv::imencode(".png", colour, png)) throw std::runtime_error(file.string() + ": the overlay cannot be encoded");
  write_file_atomically(file, std::string(png.begin(), png.end()));
}

}  // namespace purkinje::trackers
