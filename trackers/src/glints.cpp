#include "purkinje/trackers/glints.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace purkinje::trackers {

namespace {

// The largest value of an image's type: where a sensor saturates.
double full_scale(const cv::Mat& image) { return image.depth() == CV_8U ? 255.0 : 65535.0; }

void check_image(const cv::Mat& image) {
  if (image.empty()) throw std::invalid_argument("BlobGlintDetector: the image is empty");
  if (image.channels() != 1 || (image.depth() != CV_8U && image.depth() != CV_16U)) {
    throw std::invalid_argument("BlobGlintDetector: image type " + cv::typeToString(image.type()) +
                                ": must be single-channel 8- or 16-bit (CV_8UC1 or CV_16UC1)");
  }
}

// A spot's brightness over pixel (u, v): a Gaussian of total `energy`
// and width `sigma` about `c`, integrated over the pixel.
double spot_over_pixel(double u, double v, const Pixel& c, double energy, double sigma) {
  const double k = 1 / (sigma * std::numbers::sqrt2);
  const auto along = [k](double x, double centre) {
    return 0.5 * (std::erf((x + 0.5 - centre) * k) - std::erf((x - 0.5 - centre) * k));
  };
  return energy * along(u, c.u) * along(v, c.v);
}

// What a saturated glint's pixels say: its brightness above the
// background where unclipped, and where clipped only that it is at least
// this much.
struct SpotPixel {
  int u, v;
  double value;
  bool at_least;
};

// Fits the spot (centre, energy, width) to the pixels by Levenberg-Marquardt,
// from a start found by the centroid; a clipped pixel counts only where the
// spot falls short of its bound. False when the fit does not settle.
bool fit_spot(const std::vector<SpotPixel>& pixels, Pixel& centre, double& energy) {
  double p[4] = {centre.u, centre.v, energy, 0.8};
  const auto residuals = [&](const double* q, std::vector<double>& out) {
    out.resize(pixels.size());
    for (std::size_t i = 0; i < pixels.size(); ++i) {
      const double model = spot_over_pixel(pixels[i].u, pixels[i].v, {q[0], q[1]}, q[2], q[3]);
      const double r = model - pixels[i].value;
      out[i] = pixels[i].at_least ? std::min(r, 0.0) : r;
    }
  };
  std::vector<double> r, r_plus, r_minus;
  residuals(p, r);
  const auto cost = [](const std::vector<double>& x) {
    double c = 0;
    for (const double e : x) c += e * e;
    return c;
  };
  double lambda = 1e-3;
  for (int iteration = 0; iteration < 50; ++iteration) {
    // Jacobian by central differences (4 parameters, a few dozen pixels).
    double jtj[4][4] = {}, jtr[4] = {};
    std::vector<std::array<double, 4>> j(pixels.size());
    for (int a = 0; a < 4; ++a) {
      const double h = a == 2 ? 1e-4 * std::max(1.0, std::abs(p[2])) : 1e-5;
      double q[4] = {p[0], p[1], p[2], p[3]};
      q[a] = p[a] + h;
      residuals(q, r_plus);
      q[a] = p[a] - h;
      residuals(q, r_minus);
      for (std::size_t i = 0; i < pixels.size(); ++i) j[i][a] = (r_plus[i] - r_minus[i]) / (2 * h);
    }
    for (std::size_t i = 0; i < pixels.size(); ++i) {
      for (int a = 0; a < 4; ++a) {
        jtr[a] += j[i][a] * r[i];
        for (int b = 0; b < 4; ++b) jtj[a][b] += j[i][a] * j[i][b];
      }
    }
    cv::Matx44d m;
    cv::Vec4d g;
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) m(a, b) = jtj[a][b] + (a == b ? lambda * (jtj[a][a] + 1e-12) : 0.0);
      g[a] = -jtr[a];
    }
    cv::Vec4d step;
    if (!cv::solve(m, g, step, cv::DECOMP_CHOLESKY)) return false;
    const double q[4] = {p[0] + step[0], p[1] + step[1], p[2] + step[2], std::clamp(p[3] + step[3], 0.3, 5.0)};
    std::vector<double> r_new;
    residuals(q, r_new);
    if (cost(r_new) < cost(r)) {
      std::copy(q, q + 4, p);
      r = std::move(r_new);
      lambda = std::max(lambda / 4, 1e-9);
      if (std::hypot(step[0], step[1]) < 1e-6) break;
    } else {
      lambda *= 8;
      if (lambda > 1e9) break;
    }
  }
  if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && p[2] > 0)) return false;
  // A fit that wandered off the blob is no better than the centroid.
  if (std::hypot(p[0] - centre.u, p[1] - centre.v) > 1.5) return false;
  centre = {p[0], p[1]};
  energy = p[2];
  return true;
}

}  // namespace

BlobGlintDetector::BlobGlintDetector(const BlobGlintSettings& s) : settings_(s) {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("BlobGlintSettings: " + what); };
  if (s.background_radius_px < 1 || s.background_radius_px > 100) {
    fail("background_radius_px = " + std::to_string(s.background_radius_px) + ": must be in [1, 100]");
  }
  if (!(s.threshold > 0 && s.threshold < 1)) fail("threshold = " + std::to_string(s.threshold) + ": must be in (0, 1)");
  if (!(s.relative_threshold >= 0 && s.relative_threshold < 1)) {
    fail("relative_threshold = " + std::to_string(s.relative_threshold) + ": must be in [0, 1)");
  }
  if (s.min_area_px < 1 || s.max_area_px < s.min_area_px) {
    fail("min_area_px = " + std::to_string(s.min_area_px) + ", max_area_px = " + std::to_string(s.max_area_px) +
         ": must satisfy 1 <= min_area_px <= max_area_px");
  }
  if (s.centroid_margin_px < 0 || s.centroid_margin_px > 20) {
    fail("centroid_margin_px = " + std::to_string(s.centroid_margin_px) + ": must be in [0, 20]");
  }
}

std::vector<Glint> BlobGlintDetector::detect(const cv::Mat& image) const {
  check_image(image);
  cv::Mat grey;
  image.convertTo(grey, CV_32F);
  const double top = full_scale(image);
  const int r = settings_.background_radius_px;
  const cv::Mat disc = cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * r + 1, 2 * r + 1});
  cv::Mat above;  // brightness above the local background
  cv::morphologyEx(grey, above, cv::MORPH_TOPHAT, disc, {-1, -1}, 1, cv::BORDER_REPLICATE);

  double brightest = 0;
  cv::minMaxLoc(above, nullptr, &brightest);
  const double threshold = std::max(settings_.threshold * top, settings_.relative_threshold * brightest);
  cv::Mat blobs = above > threshold;
  cv::Mat labels, stats, centroids;
  const int count = cv::connectedComponentsWithStats(blobs, labels, stats, centroids, 8, CV_32S);

  std::vector<Glint> glints;
  const int m = settings_.centroid_margin_px;
  for (int label = 1; label < count; ++label) {
    const int area = stats.at<int>(label, cv::CC_STAT_AREA);
    if (area < settings_.min_area_px || area > settings_.max_area_px) continue;
    const cv::Rect box(stats.at<int>(label, cv::CC_STAT_LEFT), stats.at<int>(label, cv::CC_STAT_TOP),
                       stats.at<int>(label, cv::CC_STAT_WIDTH), stats.at<int>(label, cv::CC_STAT_HEIGHT));
    // The blob and a ring of `m` pixels around it (the point-spread
    // function's tails), and farther out, to the background disc's radius,
    // the surroundings; all within the image.
    const int reach = std::max(r, m + 1);
    const cv::Rect window =
        (box + cv::Size(2 * reach, 2 * reach) - cv::Point(reach, reach)) & cv::Rect(0, 0, image.cols, image.rows);
    const cv::Mat blob = labels(window) == label;
    cv::Mat weighed, surroundings;
    cv::dilate(blob, weighed, cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * m + 1, 2 * m + 1}));
    cv::dilate(blob, surroundings, disc);
    surroundings &= ~weighed & ~blobs(window);  // other glints nearby are not the background
    // A glint stands out from all around it: a small bright part of a
    // larger bright region (the corner of a bright patch, which the
    // opening's disc cannot reach into) does not.
    double around_max = 0;
    cv::minMaxLoc(grey(window), nullptr, &around_max, nullptr, nullptr, surroundings);
    double blob_max = 0;
    cv::minMaxLoc(grey(window), nullptr, &blob_max, nullptr, nullptr, blob);
    if (blob_max - around_max < 0.5 * threshold) continue;
    // The top-hat's own level around the glint (noise leaves it above
    // zero) is taken off the weights, so that the ring's noise does not
    // pull the centroid toward the ring's middle.
    const double pedestal = cv::countNonZero(surroundings) > 0 ? cv::mean(above(window), surroundings)[0] : 0.0;
    // The centroid over a disc about the centre found so far, twice: a
    // disc, unlike the blob's own outline, cuts a symmetric spot's tails
    // evenly, and other blobs are left out.
    const double radius = std::sqrt(area / std::numbers::pi) + m + 0.5;
    Pixel centre{stats.at<int>(label, cv::CC_STAT_LEFT) + 0.5 * (box.width - 1),
                 stats.at<int>(label, cv::CC_STAT_TOP) + 0.5 * (box.height - 1)};
    double sum = 0, peak = 0;
    bool saturated = false;
    for (int pass = 0; pass < 3; ++pass) {
      double sum_u = 0, sum_v = 0;
      sum = 0;
      for (int y = 0; y < window.height; ++y) {
        for (int x = 0; x < window.width; ++x) {
          const int u = window.x + x, v = window.y + y;
          if (std::hypot(u - centre.u, v - centre.v) > radius) continue;
          const int other = labels.at<int>(v, u);
          if (other != 0 && other != label) continue;
          const double w = std::max(0.0, above.at<float>(v, u) - pedestal);
          sum += w;
          sum_u += w * u;
          sum_v += w * v;
          peak = std::max(peak, w);
          saturated = saturated || grey.at<float>(v, u) >= top;
        }
      }
      if (!(sum > 0)) break;
      centre = {sum_u / sum, sum_v / sum};
    }
    if (!(sum > 0)) continue;
    // A clipped plateau is symmetric only on an even background; on an
    // edge (the pupil's) its brighter side reaches farther. The spot's
    // unclipped flanks above the background tell its centre there.
    double energy = sum;
    if (saturated) {
      std::vector<SpotPixel> pixels;
      for (int y = 0; y < window.height; ++y) {
        for (int x = 0; x < window.width; ++x) {
          const int u = window.x + x, v = window.y + y;
          if (std::hypot(u - centre.u, v - centre.v) > radius + 1) continue;
          const int other = labels.at<int>(v, u);
          if (other != 0 && other != label) continue;
          pixels.push_back({u, v, above.at<float>(v, u) - pedestal, grey.at<float>(v, u) >= top});
        }
      }
      fit_spot(pixels, centre, energy);
    }
    Glint g;
    g.centre = centre;
    g.energy_dn = energy;
    g.peak_dn = peak;
    g.area_px = area;
    g.saturated = saturated;
    glints.push_back(g);
  }
  std::sort(glints.begin(), glints.end(), [](const Glint& a, const Glint& b) { return a.energy_dn > b.energy_dn; });
  return glints;
}

}  // namespace purkinje::trackers
