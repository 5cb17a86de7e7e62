#include "purkinje/trackers/glints.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstdint>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include "purkinje/models/camera_optics.h"
#include "purkinje/models/check.h"
#include "purkinje/models/optimizer.h"
#include "purkinje/models/specular.h"
#include "blobs.h"
#include "grey_mat.h"

namespace purkinje::trackers {

namespace {

// What a saturated glint's pixels say: its brightness above the
// background where unclipped, and where clipped only that it is at least
// this much.
struct SpotPixel {
  int u, v;
  double value;
  bool at_least;
  double weight;  // 1 / the value's standard deviation
  // How the pixel's background moves with the edge's parameters (see
  // PupilEdge), less the move of the seen pixels' median that corrects it.
  std::array<double, 6> by_edge{};
};

// (J^T J)^-1 for a row-major Jacobian of `n` columns: a least-squares
// fit's covariance in units of its residuals. nullopt when J^T J is singular.
std::optional<cv::Mat> inverse_normal(const std::vector<double>& jacobian, int n) {
  cv::Mat normal = cv::Mat::zeros(n, n, CV_64F);
  for (std::size_t row = 0; row < jacobian.size(); row += n) {
    for (int a = 0; a < n; ++a) {
      for (int b = 0; b < n; ++b) normal.at<double>(a, b) += jacobian[row + a] * jacobian[row + b];
    }
  }
  cv::Mat inverse;
  if (!(cv::invert(normal, inverse, cv::DECOMP_EIG) > 0)) return std::nullopt;
  return inverse;
}

// The pupil's edge across a spot's surroundings: brightness
// low + (high - low) Phi(f / blur), f the signed distance from a line
// (normal at `angle`, `offset` px from the spot's start) bent by
// `curvature` (1 / px), and the covariance of the six parameters (low,
// high, angle, offset, curvature, log blur) from the seen pixels' scatter
// about it.
struct PupilEdge {
  std::array<double, 6> x{};
  std::array<double, 36> covariance{};
  // The brightness at (du, dv) from the spot's start, and its derivatives
  // by the parameters.
  double at(double du, double dv, double* by = nullptr) const { return model(x.data(), du, dv, by); }
  static double model(const double* q, double du, double dv, double* by) {
    const double c = std::cos(q[2]), s = std::sin(q[2]), blur = std::exp(q[5]);
    const double along = c * du + s * dv, across = -s * du + c * dv;
    const double f = along - q[3] + 0.5 * q[4] * across * across;
    const double phi = 0.5 * std::erfc(-f / (blur * std::numbers::sqrt2));
    if (by) {
      const double density = (q[1] - q[0]) * std::exp(-0.5 * f * f / (blur * blur)) /
                             (blur * std::sqrt(2 * std::numbers::pi));
      by[0] = 1 - phi;
      by[1] = phi;
      by[2] = density * (across - q[4] * across * along);
      by[3] = -density;
      by[4] = density * 0.5 * across * across;
      by[5] = -density * f;
    }
    return q[0] + (q[1] - q[0]) * phi;
  }
};

// The pupil's edge through a spot's seen surroundings (offsets from the
// spot's start, and brightness), when one is there: a step that explains
// most of their spread, well above the scatter left about it, that
// passes within `reach` px of the spot. A coarse search over directions
// and offsets, then a least-squares fit (the optimizer facade).
std::optional<PupilEdge> find_pupil_edge(const std::vector<std::array<double, 3>>& seen, double reach) {
  const int count = static_cast<int>(seen.size());
  if (count < 12) return std::nullopt;
  double mean = 0;
  for (const auto& p : seen) mean += p[2];
  mean /= count;
  double spread = 0;
  for (const auto& p : seen) spread += (p[2] - mean) * (p[2] - mean);
  // The coarse search: a sharp step, whose levels are the two sides'
  // means (no erf: this runs for every saturated spot, most with no edge).
  PupilEdge best;
  double best_cost = spread;
  std::vector<double> along(count);
  for (int k = 0; k < 8; ++k) {
    const double angle = k * std::numbers::pi / 8, c = std::cos(angle), s = std::sin(angle);
    for (int i = 0; i < count; ++i) along[i] = c * seen[i][0] + s * seen[i][1];
    for (double offset = -reach; offset <= reach; offset += 0.5) {
      double n0 = 0, n1 = 0, s0 = 0, s1 = 0, q0 = 0, q1 = 0;
      for (int i = 0; i < count; ++i) {
        const double y = seen[i][2];
        if (along[i] < offset) {
          n0 += 1, s0 += y, q0 += y * y;
        } else {
          n1 += 1, s1 += y, q1 += y * y;
        }
      }
      if (n0 < 3 || n1 < 3) continue;
      const double cost = q0 - s0 * s0 / n0 + q1 - s1 * s1 / n1;
      if (!(cost < best_cost)) continue;
      best_cost = cost;
      // The normal points to the brighter side.
      const bool flip = s1 / n1 < s0 / n0;
      best.x = {flip ? s1 / n1 : s0 / n0, flip ? s0 / n0 : s1 / n1, flip ? angle + std::numbers::pi : angle,
                flip ? -offset : offset, 0, std::log(0.7)};
    }
  }
  // A step that explains most of the spread and stands out from the
  // scatter left about it (twice here; four times once refined, below);
  // else no edge, and no refinement to pay for.
  if (!(best_cost < 0.5 * spread) || !(best.x[1] - best.x[0] > 2 * std::sqrt(best_cost / (count - 2)))) {
    return std::nullopt;
  }
  const optimizer::ResidualFunction residuals = [&](const double* q, double* r, double* jacobian) {
    if (!(std::abs(q[4]) < 0.5 && std::abs(q[5]) < 2)) return false;  // a bend of 2 px radius at most; blur 0.1 to 7 px
    for (int i = 0; i < count; ++i) {
      r[i] = PupilEdge::model(q, seen[i][0], seen[i][1], jacobian ? jacobian + 6 * i : nullptr) - seen[i][2];
    }
    return true;
  };
  // A thousandth of a pixel in the edge's place is far below its own
  // uncertainty: looser tolerances than the facade's save a third of the time.
  optimizer::Options options;
  options.max_iterations = 20;
  options.function_tolerance = 1e-8;
  options.parameter_tolerance = 1e-6;
  optimizer::solve(count, std::span<double>(best.x.data(), 6), residuals, options);
  std::vector<double> r(count), jacobian(6 * count);
  if (!residuals(best.x.data(), r.data(), jacobian.data())) return std::nullopt;
  double cost = 0;
  for (const double e : r) cost += e * e;
  const double scatter = std::sqrt(cost / (count - 6));
  // Where the step is too weak to tell from the scatter, or runs clear of
  // the spot, the seen pixels' median serves.
  if (!(best.x[1] - best.x[0] > 4 * scatter) || !(std::abs(best.x[3]) < reach)) return std::nullopt;
  const std::optional<cv::Mat> covariance = inverse_normal(jacobian, 6);
  if (!covariance) return std::nullopt;
  for (int a = 0; a < 36; ++a) best.covariance[a] = covariance->at<double>(a / 6, a % 6) * scatter * scatter;
  return best;
}

// The share of a Gaussian (centre c, width sigma) along one axis that falls
// on each pixel from `first` on, and its derivatives by c and by sigma.
struct PixelShares {
  std::vector<double> share, by_centre, by_width;
  void compute(int first, int count, double c, double sigma) {
    share.resize(count);
    by_centre.resize(count);
    by_width.resize(count);
    const double k = 1 / (sigma * std::numbers::sqrt2);
    const double g = 1 / (sigma * std::sqrt(2 * std::numbers::pi)), h = 1 / (sigma * std::sqrt(std::numbers::pi));
    for (int i = 0; i < count; ++i) {
      const double a = (first + i + 0.5 - c) * k, b = (first + i - 0.5 - c) * k;
      const double ea = std::exp(-a * a), eb = std::exp(-b * b);
      share[i] = 0.5 * (std::erf(a) - std::erf(b));
      by_centre[i] = -g * (ea - eb);
      by_width[i] = -h * (a * ea - b * eb);
    }
  }
};

// A spot fitted: its centre, energy and width (the Gaussian's standard
// deviation, px), and the variances of the centre's u and v.
struct SpotFit {
  Pixel centre;
  double energy = 0, sigma = 0, var_u = 0, var_v = 0;
};

// Fits the spot (centre, energy and, unless `sigma` > 0 holds it, width: a
// Gaussian integrated over each pixel) to the pixels by weighted least
// squares (the optimizer facade), from `start`; a clipped pixel counts only
// where the spot falls short of its bound. The model is separable, so each
// axis's erf and exp are taken once per column and row. nullopt when the
// fit fails or wanders off the blob.
std::optional<SpotFit> fit_spot(const std::vector<SpotPixel>& pixels, const Pixel& start, double start_energy,
                                double sigma, const PupilEdge* edge = nullptr) {
  if (pixels.empty()) return std::nullopt;
  int u0 = pixels.front().u, u1 = u0, v0 = pixels.front().v, v1 = v0;
  for (const SpotPixel& p : pixels) {
    u0 = std::min(u0, p.u), u1 = std::max(u1, p.u), v0 = std::min(v0, p.v), v1 = std::max(v1, p.v);
  }
  const bool free_width = !(sigma > 0);
  const int n = free_width ? 4 : 3;
  // Parameters: centre u and v, energy, and the log of the width (so that it stays positive).
  std::array<double, 4> x{start.u, start.v, start_energy, std::log(free_width ? 0.8 : sigma)};
  PixelShares along_u, along_v;
  const optimizer::ResidualFunction residuals = [&](const double* q, double* r, double* jacobian) {
    if (free_width && !(std::abs(q[3]) < 3)) return false;  // a width between 0.05 and 20 px
    const double width = free_width ? std::exp(q[3]) : sigma;
    along_u.compute(u0, u1 - u0 + 1, q[0], width);
    along_v.compute(v0, v1 - v0 + 1, q[1], width);
    for (std::size_t i = 0; i < pixels.size(); ++i) {
      const int iu = pixels[i].u - u0, iv = pixels[i].v - v0;
      const double pu = along_u.share[iu], pv = along_v.share[iv];
      const double d = q[2] * pu * pv - pixels[i].value;
      const double w = !pixels[i].at_least || d < 0 ? pixels[i].weight : 0.0;
      r[i] = w * d;
      if (!jacobian) continue;
      double* row = jacobian + n * i;
      row[0] = w * q[2] * along_u.by_centre[iu] * pv;
      row[1] = w * q[2] * pu * along_v.by_centre[iv];
      row[2] = w * pu * pv;
      if (free_width) row[3] = w * q[2] * width * (along_u.by_width[iu] * pv + pu * along_v.by_width[iv]);
    }
    return true;
  };
  const optimizer::Summary summary =
      optimizer::solve(static_cast<int>(pixels.size()), std::span<double>(x.data(), n), residuals);
  if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !(x[2] > 0)) return std::nullopt;
  // A fit that wandered off the blob is no better than the centroid.
  if (summary.final_cost > summary.initial_cost || std::hypot(x[0] - start.u, x[1] - start.v) > 1.5) {
    return std::nullopt;
  }
  // The centre's covariance, (J^T J)^-1 of the weighted residuals of the
  // unclipped pixels. A clipped pixel only bounds the spot: where the
  // bound holds the fit at the solution, counting it as a measurement
  // would claim a precision no pixel gave (on the headset, glints 5 to 8
  // reported s.d. off; 3.7 at most without).
  std::vector<double> r(pixels.size()), jacobian(pixels.size() * n);
  if (!residuals(x.data(), r.data(), jacobian.data())) return std::nullopt;
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    if (pixels[i].at_least) std::fill_n(jacobian.begin() + n * i, n, 0.0);
  }
  const std::optional<cv::Mat> inverse = inverse_normal(jacobian, n);
  if (!inverse) return std::nullopt;
  const cv::Mat& covariance = *inverse;
  // A normal matrix near singular (few pixels weigh) gives no deviation to trust.
  double var_u = covariance.at<double>(0, 0), var_v = covariance.at<double>(1, 1);
  if (edge) {
    // The edge's own uncertainty moves every pixel's background together.
    std::array<double, 6> along_u{}, along_v{};
    for (std::size_t i = 0; i < pixels.size(); ++i) {  // a clipped pixel's row is zero: it moves nothing
      double hu = 0, hv = 0;  // the centre's move per unit of the pixel's value
      for (int a = 0; a < n; ++a) {
        hu += covariance.at<double>(0, a) * jacobian[n * i + a];
        hv += covariance.at<double>(1, a) * jacobian[n * i + a];
      }
      for (int a = 0; a < 6; ++a) {
        along_u[a] += hu * pixels[i].weight * pixels[i].by_edge[a];
        along_v[a] += hv * pixels[i].weight * pixels[i].by_edge[a];
      }
    }
    for (int a = 0; a < 6; ++a) {
      for (int b = 0; b < 6; ++b) {
        var_u += along_u[a] * edge->covariance[6 * a + b] * along_u[b];
        var_v += along_v[a] * edge->covariance[6 * a + b] * along_v[b];
      }
    }
  }
  if (!(var_u > 0 && var_v > 0 && std::isfinite(var_u) && std::isfinite(var_v))) return std::nullopt;
  SpotFit fit;
  fit.centre = {x[0], x[1]};
  fit.energy = x[2];
  fit.sigma = free_width ? std::exp(x[3]) : sigma;
  fit.var_u = var_u;
  fit.var_v = var_v;
  return fit;
}

// A saturated glint's spot, for fitting once the frame's width is known:
// its pixels with the background from just outside its core ([0]) and
// from beyond its flank ([1]), and where the fit starts.
struct SaturatedSpot {
  std::size_t glint;  // index into the frame's glints
  Pixel start;
  double start_energy;
  std::array<std::vector<SpotPixel>, 2> pixels;
  std::optional<PupilEdge> edge;  // across the far background, where one crosses
};

// Images of a frame's size, kept per thread from frame to frame: fresh
// ones cost a page fault per 4 KB, as much as the detection itself.
// `labels` is all zeros between frames.
struct Scratch {
  cv::Mat grey, above_int, above, blobs, labels;
  std::vector<cv::Point> seeds, stack;
  std::vector<float> around;
};
Scratch& scratch_for(const cv::Size& size) {
  thread_local Scratch scratch;
  if (scratch.labels.size() != size) scratch.labels = cv::Mat::zeros(size, CV_32S);
  return scratch;
}


// One frame's images and levels, shared by the steps of a detection.
struct Frame {
  Scratch& scratch;  // grey, above (the top-hat), blobs and labels filled
  int cols, rows;
  double top;        // where the sensor saturates, DN
  int r;             // the background's radius, px
  int m;             // the centroid's margin, px
  double threshold;  // above the background, DN
  double dn_per_electron, read_variance;
  // A pixel's noise variance (DN^2) at a value of v DN: shot, read and rounding.
  double noise_variance(double v) const { return std::max(0.0, v) * dn_per_electron + read_variance; }
};

// A blob in its window: the blob and a ring of `m` pixels around it (the
// point-spread function's tails), and farther out, to the background
// disc's radius, the surroundings; all within the image.
struct BlobWindow {
  int label;
  cv::Rect window;
  cv::Mat blob, surroundings;
};

BlobWindow blob_window(const Frame& f, int label, const cv::Rect& box, const cv::Mat& disc) {
  const int reach = std::max(f.r, f.m + 1);
  BlobWindow w{label, (box + cv::Size(2 * reach, 2 * reach) - cv::Point(reach, reach)) & cv::Rect(0, 0, f.cols, f.rows),
               {}, {}};
  w.blob = f.scratch.labels(w.window) == label;
  cv::Mat weighed;
  cv::dilate(w.blob, weighed, cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * f.m + 1, 2 * f.m + 1}));
  cv::dilate(w.blob, w.surroundings, disc);
  w.surroundings &= ~weighed & ~f.scratch.blobs(w.window);  // other glints nearby are not the background
  return w;
}

// The part of the window joined to the blob's peak above the level halfway
// between the peak and the middle of its surroundings.
struct Peak {
  cv::Mat joined;  // connected parts above that level
  int part;        // the peak's
};

// Whether a blob holds a peak that shares its brightness with its four
// neighbours as optics would (settings' min_neighbour_share): a local
// maximum whose neighbours hold that share of its height, both above the
// median of the ring of pixels two away (the top-hat's own background
// lies below the noise, whose positive part would count). A neighbour
// below that level counts as none: on the pupil's edge the dark side's
// neighbour must not cancel the bright side's. Every local maximum of the
// blob is tried, so that a hot pixel joined to a glint's blob does not
// drop the glint. Neighbours beyond the image are left out, the others
// scaled.
bool spread_by_optics(const Frame& f, int label, const Blob& blob, double min_share) {
  if (min_share <= 0) return true;
  const cv::Mat& grey = f.scratch.grey;
  const auto inside = [&](cv::Point q) { return q.x >= 0 && q.y >= 0 && q.x < f.cols && q.y < f.rows; };
  const std::array<cv::Point, 4> steps = {cv::Point{1, 0}, cv::Point{-1, 0}, cv::Point{0, 1}, cv::Point{0, -1}};
  for (int y = blob.box.y; y < blob.box.y + blob.box.height; ++y) {
    for (int x = blob.box.x; x < blob.box.x + blob.box.width; ++x) {
      const cv::Point at{x, y};
      if (f.scratch.labels.at<int>(at) != label) continue;
      const float value = grey.at<float>(at);
      bool maximum = true;
      for (const cv::Point d : steps) maximum = maximum && (!inside(at + d) || grey.at<float>(at + d) <= value);
      if (!maximum) continue;
      std::array<float, 16> ring{};
      std::size_t n = 0;
      for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) {
          const cv::Point q = at + cv::Point{dx, dy};
          if (std::max(std::abs(dx), std::abs(dy)) == 2 && inside(q)) ring[n++] = grey.at<float>(q);
        }
      }
      if (n == 0) return true;  // an image too small to tell
      std::nth_element(ring.begin(), ring.begin() + n / 2, ring.begin() + n);
      const double height = value - ring[n / 2];
      if (!(height > 0)) continue;
      double neighbours = 0;
      int counted = 0;
      for (const cv::Point d : steps) {
        if (!inside(at + d)) continue;
        neighbours += std::max(0.0, static_cast<double>(grey.at<float>(at + d)) - ring[n / 2]);
        ++counted;
      }
      if (counted == 0 || neighbours * 4 / counted >= min_share * height) return true;
    }
  }
  return false;
}

// A glint stands out from all around it: a small bright part of a larger
// bright region (the rim of a bright patch, which the opening's square
// cannot reach into, or a lit lid margin) does not. What stands out is
// what is joined to the peak above the level halfway between the peak and
// the middle of its surroundings: it must stay within the blob's margin.
// (Brighter things nearby but apart, such as a saturated sclera beside a
// glint on the iris, do not matter.) nullopt for a blob that does not.
std::optional<Peak> standing_peak(const Frame& f, const BlobWindow& w) {
  const cv::Mat grey = f.scratch.grey(w.window);
  double blob_max = 0;
  cv::Point brightest_at;
  cv::minMaxLoc(grey, nullptr, &blob_max, nullptr, &brightest_at, w.blob);
  std::vector<float>& around = f.scratch.around;
  around.clear();
  for (int y = 0; y < w.window.height; ++y) {
    for (int x = 0; x < w.window.width; ++x) {
      if (w.surroundings.at<std::uint8_t>(y, x)) around.push_back(grey.at<float>(y, x));
    }
  }
  if (around.empty()) return std::nullopt;
  std::nth_element(around.begin(), around.begin() + around.size() / 2, around.end());
  const double around_level = around[around.size() / 2];
  // Above its surroundings' middle by the threshold, too: the iris's
  // texture beside the dark pupil rises above the opening's background,
  // but hardly above the iris around it.
  if (blob_max - around_level < f.threshold) return std::nullopt;
  Peak peak;
  cv::connectedComponents(grey > 0.5 * (blob_max + around_level), peak.joined, 8, CV_32S);
  peak.part = peak.joined.at<int>(brightest_at);
  for (int y = 0; y < w.window.height; ++y) {
    for (int x = 0; x < w.window.width; ++x) {
      if (w.surroundings.at<std::uint8_t>(y, x) && peak.joined.at<int>(y, x) == peak.part) return std::nullopt;
    }
  }
  return peak;
}

// The blob's glint by its centroid over a disc about the centre found so
// far, taken three times: a disc, unlike the blob's own outline, cuts a
// symmetric spot's tails evenly, and other blobs are left out. nullopt
// when nothing is left above the pedestal.
std::optional<Glint> centroid_glint(const Frame& f, const BlobWindow& w, const Blob& found) {
  const cv::Mat& above = f.scratch.above;
  const cv::Mat& labels = f.scratch.labels;
  const cv::Rect& window = w.window;
  const cv::Rect box = found.box;
  // The top-hat's own level around the glint (noise leaves it above
  // zero) is taken off the weights, so that the ring's noise does not
  // pull the centroid toward the ring's middle.
  const double pedestal = cv::countNonZero(w.surroundings) > 0 ? cv::mean(above(window), w.surroundings)[0] : 0.0;
  const double radius = std::sqrt(found.area / std::numbers::pi) + f.m + 0.5;
  Pixel centre{box.x + 0.5 * (box.width - 1), box.y + 0.5 * (box.height - 1)};
  // The window's pixels within `within` of the centre that belong to no
  // other blob: what the centroid weighs.
  const auto weighs = [&](int u, int v, double within) {
    const int other = labels.at<int>(v, u);
    return std::hypot(u - centre.u, v - centre.v) <= within && (other == 0 || other == w.label);
  };
  double sum = 0, peak = 0;
  bool saturated = false;
  for (int pass = 0; pass < 3; ++pass) {
    double sum_u = 0, sum_v = 0;
    sum = 0, peak = 0, saturated = false;
    for (int y = 0; y < window.height; ++y) {
      for (int x = 0; x < window.width; ++x) {
        const int u = window.x + x, v = window.y + y;
        if (!weighs(u, v, radius)) continue;
        const double weight = std::max(0.0, above.at<float>(v, u) - pedestal);
        sum += weight;
        sum_u += weight * u;
        sum_v += weight * v;
        peak = std::max(peak, weight);
        saturated = saturated || f.scratch.grey.at<float>(v, u) >= f.top;
      }
    }
    if (!(sum > 0)) break;
    centre = {sum_u / sum, sum_v / sum};
  }
  if (!(sum > 0)) return std::nullopt;
  Glint g;
  g.centre = centre;
  g.energy_dn = sum;
  g.peak_dn = peak;
  g.area_px = found.area;
  g.saturated = saturated;
  return g;
}

// A saturated spot's pixels around its core, for a flank: the core
// `unseen` (and the second time its flank too), the pixels `fitted` a
// pixel beyond, each with its brightness above the background under it.
// The background is the median of the nearest five or more pixels seen
// (the smallest square about it that holds them, or as many as the window
// has), and their scatter (1.4826 x the median absolute deviation), which
// beyond their own noise is the texture the background may hold. Beyond
// the flank, where the pupil's edge crosses, the background is the edge's
// brightness plus the median of the seen pixels' departures from it.
std::vector<SpotPixel> flank_pixels(const Frame& f, const BlobWindow& w, const cv::Mat& ours, const cv::Mat& seen,
                                    const cv::Mat& fitted, const Pixel& start, const PupilEdge* edge) {
  const cv::Rect& window = w.window;
  const cv::Mat local = f.scratch.grey(window);
  const double su = start.u - window.x, sv = start.v - window.y;
  // Without an edge the departures are the pixels themselves.
  cv::Mat departure = local;
  // Per window pixel, where there is an edge: its brightness there, and its derivatives.
  std::vector<double> edge_at;
  std::vector<std::array<double, 6>> edge_by;
  if (edge) {
    departure = local.clone();
    edge_at.resize(window.area());
    edge_by.resize(window.area());
    for (int y = 0; y < window.height; ++y) {
      for (int x = 0; x < window.width; ++x) {
        const int i = y * window.width + x;
        edge_at[i] = edge->at(x - su, y - sv, edge_by[i].data());
        departure.at<float>(y, x) -= static_cast<float>(edge_at[i]);
      }
    }
  }
  std::vector<float>& around = f.scratch.around;
  std::vector<SpotPixel> pixels;
  for (int y = 0; y < window.height; ++y) {
    for (int x = 0; x < window.width; ++x) {
      if (!fitted.at<std::uint8_t>(y, x) || !ours.at<std::uint8_t>(y, x)) continue;
      around.clear();
      std::array<double, 6> moved{};
      for (int k = 1; k <= 2 * f.r && around.size() < 5; ++k) {
        around.clear();
        moved = {};
        for (int yy = std::max(0, y - k); yy <= std::min(window.height - 1, y + k); ++yy) {
          for (int xx = std::max(0, x - k); xx <= std::min(window.width - 1, x + k); ++xx) {
            if (!seen.at<std::uint8_t>(yy, xx)) continue;
            around.push_back(departure.at<float>(yy, xx));
            if (edge) {
              for (int a = 0; a < 6; ++a) moved[a] += edge_by[yy * window.width + xx][a];
            }
          }
        }
      }
      if (around.empty()) continue;
      const auto middle = around.begin() + around.size() / 2;
      std::nth_element(around.begin(), middle, around.end());
      std::array<double, 6> by_edge{};
      double background = *middle;
      if (edge) {
        const double below = edge_at[y * window.width + x];
        by_edge = edge_by[y * window.width + x];
        background += below;
        for (int a = 0; a < 6; ++a) by_edge[a] -= moved[a] / static_cast<double>(around.size());
        for (float& a : around) a += static_cast<float>(below);  // the scatter about the background
      }
      for (float& a : around) a = std::abs(a - static_cast<float>(background));
      std::nth_element(around.begin(), middle, around.end());
      const double scatter = 1.4826 * *middle;
      const double value = local.at<float>(y, x);
      const double texture = std::max(0.0, scatter * scatter - f.noise_variance(background));
      pixels.push_back({window.x + x, window.y + y, value - background, value >= f.top,
                        1 / std::sqrt(f.noise_variance(value) + texture), by_edge});
    }
  }
  return pixels;
}

// A clipped plateau is symmetric only on an even background; on an edge
// (the pupil's) its brighter side reaches farther. The spot's unclipped
// flanks above the background tell its centre there: gathered here,
// fitted once the frame's width is known.
SaturatedSpot saturated_spot(const Frame& f, const BlobWindow& w, const Peak& peak, std::size_t glint,
                             double energy) {
  const cv::Rect& window = w.window;
  const cv::Mat core = peak.joined == peak.part;  // above the level halfway to the peak
  SaturatedSpot spot{glint, {}, energy, {}, std::nullopt};
  const cv::Moments moments = cv::moments(core, true);
  spot.start = {window.x + moments.m10 / moments.m00, window.y + moments.m01 / moments.m00};
  const cv::Mat own = f.scratch.labels(window), local = f.scratch.grey(window);
  const cv::Mat ours = (own == 0) | (own == w.label);
  for (int flank = 0; flank < 2; ++flank) {
    // Where the background is unseen: the core, and the second time its
    // flank too. The fit takes a pixel more, whose background is mostly
    // itself: it holds the spot's tails near zero.
    cv::Mat unseen, fitted;
    cv::dilate(core, unseen, cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * flank + 1, 2 * flank + 1}));
    cv::dilate(core, fitted, cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * flank + 3, 2 * flank + 3}));
    const cv::Mat seen = ~unseen & ours;
    if (flank == 1) {
      const double su = spot.start.u - window.x, sv = spot.start.v - window.y;
      std::vector<std::array<double, 3>> seen_pixels;
      for (int y = 0; y < window.height; ++y) {
        for (int x = 0; x < window.width; ++x) {
          if (seen.at<std::uint8_t>(y, x)) seen_pixels.push_back({x - su, y - sv, local.at<float>(y, x)});
        }
      }
      spot.edge = find_pupil_edge(seen_pixels, f.r - 1.0);
    }
    const PupilEdge* edge = flank == 1 && spot.edge ? &*spot.edge : nullptr;
    spot.pixels[flank] = flank_pixels(f, w, ours, seen, fitted, spot.start, edge);
  }
  return spot;
}

// The saturated glints' centres from their flanks, with a shared width:
// the camera's point spread, as told (`spot_sigma_px` > 0) or as the median
// of their own fits (one spot's flanks hardly tell width from centre).
void fit_saturated(std::vector<Glint>& glints, const std::vector<SaturatedSpot>& spots, double spot_sigma_px) {
  double sigma = spot_sigma_px;
  if (!(sigma > 0) && !spots.empty()) {
    std::vector<double> widths;
    for (const SaturatedSpot& spot : spots) {
      if (const auto fit = fit_spot(spot.pixels[1], spot.start, spot.start_energy, 0)) widths.push_back(fit->sigma);
    }
    if (!widths.empty()) {
      std::sort(widths.begin(), widths.end());
      const std::size_t half = widths.size() / 2;
      sigma = widths.size() % 2 ? widths[half] : 0.5 * (widths[half - 1] + widths[half]);
    }
  }
  for (const SaturatedSpot& spot : spots) {
    // Without a width (no spot could be fitted), each spot fits its own.
    const auto near = fit_spot(spot.pixels[0], spot.start, spot.start_energy, sigma);
    const auto far =
        fit_spot(spot.pixels[1], spot.start, spot.start_energy, sigma, spot.edge ? &*spot.edge : nullptr);
    Glint& g = glints[spot.glint];
    if (near && far) {
      // The unseen background lies between the two estimates: the mean of
      // the fits, with half their difference as a further error.
      const double du = 0.5 * (near->centre.u - far->centre.u), dv = 0.5 * (near->centre.v - far->centre.v);
      g.centre = {0.5 * (near->centre.u + far->centre.u), 0.5 * (near->centre.v + far->centre.v)};
      g.energy_dn = 0.5 * (near->energy + far->energy);
      // The far fit's own variance: the near one's counts the spot's own
      // flank, seen beside the core, as the background's scatter, and said
      // 2.2 to 2.6 times the scatter under noise alone (tests).
      g.centre_sd_u_px = std::sqrt(far->var_u + du * du);
      g.centre_sd_v_px = std::sqrt(far->var_v + dv * dv);
    } else if (near || far) {
      // One background alone does not bracket the unseen one: no deviation.
      const SpotFit& fit = near ? *near : *far;
      g.centre = fit.centre;
      g.energy_dn = fit.energy;
    }
  }
}

}  // namespace

BlobGlintDetector::BlobGlintDetector(const BlobGlintSettings& s) : settings_(s) {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("BlobGlintSettings: " + what); };
  if (s.background_radius_px < 1 || s.background_radius_px > 100) {
    fail("background_radius_px = " + std::to_string(s.background_radius_px) + ": must be in [1, 100]");
  }
  if (!(s.threshold > 0 && s.threshold < 1)) {
    fail("threshold = " + check::format_number(s.threshold) + ": must be in (0, 1)");
  }
  if (!(s.relative_threshold >= 0 && s.relative_threshold < 1)) {
    fail("relative_threshold = " + check::format_number(s.relative_threshold) + ": must be in [0, 1)");
  }
  if (!(s.min_neighbour_share >= 0 && s.min_neighbour_share <= 4)) {
    fail("min_neighbour_share = " + check::format_number(s.min_neighbour_share) + ": must be in [0, 4]");
  }
  if (s.min_area_px < 1 || s.max_area_px < s.min_area_px) {
    fail("min_area_px = " + std::to_string(s.min_area_px) + ", max_area_px = " + std::to_string(s.max_area_px) +
         ": must satisfy 1 <= min_area_px <= max_area_px");
  }
  if (s.centroid_margin_px < 0 || s.centroid_margin_px > 20) {
    fail("centroid_margin_px = " + std::to_string(s.centroid_margin_px) + ": must be in [0, 20]");
  }
  if (!(s.spot_sigma_px == 0 || (s.spot_sigma_px >= 0.1 && s.spot_sigma_px <= 10))) {
    fail("spot_sigma_px = " + check::format_number(s.spot_sigma_px) + ": must be 0 or in [0.1, 10]");
  }
  if (!(s.full_scale_e > 0 && std::isfinite(s.full_scale_e))) {
    fail("full_scale_e = " + check::format_number(s.full_scale_e) + ": must be positive and finite");
  }
  if (!(s.read_noise_e >= 0 && std::isfinite(s.read_noise_e))) {
    fail("read_noise_e = " + check::format_number(s.read_noise_e) + ": must be non-negative and finite");
  }
}

std::vector<Glint> BlobGlintDetector::detect(const GreyView& view) const {
  const cv::Mat image = mat_of(view, "BlobGlintDetector");  // read only
  Scratch& scratch = scratch_for(image.size());
  image.convertTo(scratch.grey, CV_32F);
  const double top = std::ldexp(1.0, view.bits) - 1;  // where the sensor saturates
  const int r = settings_.background_radius_px;
  // A square, not a disc: separable, so the opening costs a twentieth
  // (0.12 against 2.3 ms for 640 x 480), and taken in the image's own
  // integers, where OpenCV's morphology is vectorized.
  const cv::Mat square = cv::getStructuringElement(cv::MORPH_RECT, {2 * r + 1, 2 * r + 1});
  // Brightness above the local background.
  cv::morphologyEx(image, scratch.above_int, cv::MORPH_TOPHAT, square, {-1, -1}, 1, cv::BORDER_REPLICATE);
  scratch.above_int.convertTo(scratch.above, CV_32F);
  const cv::Mat disc = cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * r + 1, 2 * r + 1});

  double brightest = 0;
  cv::minMaxLoc(scratch.above, nullptr, &brightest);
  const double threshold = std::max(settings_.threshold * top, settings_.relative_threshold * brightest);
  cv::compare(scratch.above, threshold, scratch.blobs, cv::CMP_GT);
  // Zeros again for the next frame, however this one ends (the seeds are
  // this frame's from here on).
  scratch.seeds.clear();
  const ClearLabels clear_labels(scratch.labels, scratch.seeds);
  const std::vector<Blob> found = label_blobs(scratch.blobs, scratch.labels, scratch.seeds, scratch.stack);

  const double dn_per_electron = top / settings_.full_scale_e;
  const Frame frame{scratch,   image.cols, image.rows,     top, r, settings_.centroid_margin_px,
                    threshold, dn_per_electron, std::pow(settings_.read_noise_e * dn_per_electron, 2) + 1.0 / 12};
  std::vector<Glint> glints;
  std::vector<SaturatedSpot> spots;
  for (int label = 1; label < static_cast<int>(found.size()); ++label) {
    if (found[label].area < settings_.min_area_px || found[label].area > settings_.max_area_px) continue;
    if (!spread_by_optics(frame, label, found[label], settings_.min_neighbour_share)) continue;
    const BlobWindow window = blob_window(frame, label, found[label].box, disc);
    const std::optional<Peak> peak = standing_peak(frame, window);
    if (!peak) continue;
    const std::optional<Glint> glint = centroid_glint(frame, window, found[label]);
    if (!glint) continue;
    if (glint->saturated) spots.push_back(saturated_spot(frame, window, *peak, glints.size(), glint->energy_dn));
    glints.push_back(*glint);
  }
  fit_saturated(glints, spots, settings_.spot_sigma_px);
  std::sort(glints.begin(), glints.end(), [](const Glint& a, const Glint& b) { return a.energy_dn > b.energy_dn; });
  return glints;
}

namespace {

// A similarity transform of the image plane: z -> q z + t, complex.
struct Similarity {
  std::complex<double> q{1, 0}, t{0, 0};
  std::complex<double> operator()(std::complex<double> z) const { return q * z + t; }
};

std::complex<double> complex_of(const Pixel& p) { return {p.u, p.v}; }

}  // namespace

void identify_glints(std::vector<Glint>& glints, const std::vector<std::optional<Pixel>>& expected,
                     const GlintMatchSettings& s) {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("GlintMatchSettings: " + what); };
  if (!(s.max_scale >= 1)) fail("max_scale = " + check::format_number(s.max_scale) + ": must be >= 1");
  if (!(s.max_rotation_rad >= 0 && s.max_rotation_rad <= std::numbers::pi)) {
    fail("max_rotation_rad = " + check::format_number(s.max_rotation_rad) + ": must be in [0, pi]");
  }
  if (!(s.gate_fraction > 0 && s.gate_fraction < 0.5)) {
    fail("gate_fraction = " + check::format_number(s.gate_fraction) + ": must be in (0, 0.5)");
  }
  for (Glint& g : glints) g.illuminator = -1;
  std::vector<int> lights;
  std::vector<std::complex<double>> places;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    if (!expected[i]) continue;
    lights.push_back(static_cast<int>(i));
    places.push_back(complex_of(*expected[i]));
  }
  // The brightest detections only: a pattern has as many glints as lights.
  const std::size_t candidates = std::min(glints.size(), 2 * places.size() + 4);
  if (places.size() < 2 || candidates < 2) return;
  double spacing = INFINITY;  // the smallest distance between two expected glints
  for (std::size_t i = 0; i < places.size(); ++i) {
    for (std::size_t j = i + 1; j < places.size(); ++j) spacing = std::min(spacing, std::abs(places[i] - places[j]));
  }
  if (!(spacing > 0)) return;  // two lights at one place: their glints cannot be told apart
  std::vector<std::complex<double>> found(candidates);
  for (std::size_t k = 0; k < candidates; ++k) found[k] = complex_of(glints[k].centre);

  // Nearest detection to each transformed expected glint within the gate:
  // how many, and their squared distances' sum.
  const auto score = [&](const Similarity& m, double gate, double& residual) {
    int count = 0;
    residual = 0;
    for (const std::complex<double>& place : places) {
      const std::complex<double> p = m(place);
      double nearest = gate;
      for (const std::complex<double>& f : found) nearest = std::min(nearest, std::abs(f - p));
      if (nearest < gate) {
        ++count;
        residual += nearest * nearest;
      }
    }
    return count;
  };
  Similarity best;
  int best_count = 0;
  double best_cost = INFINITY;
  for (std::size_t a = 0; a < candidates; ++a) {
    for (std::size_t b = 0; b < candidates; ++b) {
      if (a == b) continue;
      for (std::size_t i = 0; i < places.size(); ++i) {
        for (std::size_t j = 0; j < places.size(); ++j) {
          if (i == j) continue;
          Similarity m;
          m.q = (found[b] - found[a]) / (places[j] - places[i]);
          const double scale = std::abs(m.q);
          if (!(scale >= 1 / s.max_scale && scale <= s.max_scale) || std::abs(std::arg(m.q)) > s.max_rotation_rad) {
            continue;
          }
          m.t = found[a] - m.q * places[i];
          const double gate = s.gate_fraction * spacing * scale;
          double residual = 0;
          const int count = score(m, gate, residual);
          // Among equal counts: glints near their places, then the least
          // change of scale and turn (each measured against its bound).
          const double cost = residual / (gate * gate * count) + std::abs(std::log(scale)) / std::log(s.max_scale + 1e-12) +
                              std::abs(std::arg(m.q)) / (s.max_rotation_rad + 1e-12);
          if (count > best_count || (count == best_count && cost < best_cost)) {
            best = m;
            best_count = count;
            best_cost = cost;
          }
        }
      }
    }
  }
  if (best_count < 2) return;
  // Each expected glint takes the nearest free detection within the gate,
  // nearest pairs first.
  const double gate = s.gate_fraction * spacing * std::abs(best.q);
  struct Pair {
    double distance;
    std::size_t place, glint;
  };
  std::vector<Pair> pairs;
  for (std::size_t i = 0; i < places.size(); ++i) {
    const std::complex<double> p = best(places[i]);
    for (std::size_t k = 0; k < candidates; ++k) {
      const double d = std::abs(found[k] - p);
      if (d < gate) pairs.push_back({d, i, k});
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& x, const Pair& y) { return x.distance < y.distance; });
  std::vector<bool> place_used(places.size(), false);
  for (const Pair& pair : pairs) {
    if (place_used[pair.place] || glints[pair.glint].illuminator >= 0) continue;
    place_used[pair.place] = true;
    glints[pair.glint].illuminator = lights[pair.place];
  }
}

std::vector<std::optional<Pixel>> nominal_glint_layout(const Camera& camera, const std::vector<Illuminator>& lights,
                                                       const Eye& nominal_eye) {
  std::vector<std::optional<Pixel>> layout;
  for (const Illuminator& light : lights) {
    const Reflection r = solve_reflection(nominal_eye, light.position, camera.center());
    std::optional<Pixel> place;
    if (r.status == PathStatus::ok) {
      const Projection p = camera.project(r.point);
      if (p.status != ProjectionStatus::behind_camera) place = p.pixel;
    }
    layout.push_back(place);
  }
  return layout;
}

BlobGlintSettings glint_settings_for(const Camera& camera, const std::vector<Illuminator>& lights,
                                     const Point3& nominal_cornea) {
  BlobGlintSettings settings;
  const double depth = (camera.camera_from_world() * nominal_cornea).z;
  const bool points =
      std::all_of(lights.begin(), lights.end(), [](const Illuminator& l) { return l.emitter_diameter_mm == 0; });
  if (depth > camera.focal_length_mm() && points) {
    const PointSpread spread = point_spread(camera, depth);
    // The detector refuses a told width outside [0.1, 10] px; left at 0 it estimates its own.
    if (spread.defocus_radius_px == 0 && spread.sigma_px >= 0.1 && spread.sigma_px <= 10) {
      settings.spot_sigma_px = spread.sigma_px;
    }
  }
  const Sensor& sensor = camera.sensor();
  if (sensor.gain > 0) settings.full_scale_e = sensor.full_well_e / sensor.gain;
  settings.read_noise_e = sensor.read_noise_e;
  return settings;
}

}  // namespace purkinje::trackers
