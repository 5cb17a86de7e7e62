#include "pixel_filter.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace purkinje::renderer {
namespace {

constexpr double kPi = std::numbers::pi;
// Nodes of the inverse distribution's bracket; Newton steps on the exact
// distribution (halving where they would leave it) then make an offset
// exact to rounding.
constexpr int kTable = 1024;
constexpr int kMaxSteps = 60;
constexpr double kTolerancePx = 1e-13;
// Harris's (1978) four-term Blackman-Harris window, centred on 0:
// sum_k a_k cos(2 pi k x / w), |x| <= w / 2 (the signs of the
// non-centred form's odd terms turn over).
constexpr double kBlackmanHarris[4] = {0.35875, 0.48829, 0.14128, 0.01168};

}  // namespace

double PixelFilterSampler::density(double x) const {
  const double w = width_px_;
  if (kind_ == PixelFilterKind::gaussian) {
    const double sigma = w / 6;
    return std::exp(-0.5 * (x / sigma) * (x / sigma)) /
           (sigma * std::sqrt(2 * kPi) * std::erf(w / (2 * sigma * std::numbers::sqrt2)));
  }
  if (kind_ == PixelFilterKind::blackman_harris) {
    double f = 0;
    for (int k = 0; k < 4; ++k) f += kBlackmanHarris[k] * std::cos(2 * kPi * k * x / w);
    return f / (kBlackmanHarris[0] * w);  // the cosines integrate to 0 over the support
  }
  return 1 / w;
}

double PixelFilterSampler::cdf(double x) const {
  const double w = width_px_;
  if (kind_ == PixelFilterKind::gaussian) {
    const double s = w / 6 * std::numbers::sqrt2;
    return 0.5 * (1 + std::erf(x / s) / std::erf(w / (2 * s)));
  }
  if (kind_ == PixelFilterKind::blackman_harris) {
    double f = kBlackmanHarris[0] * (x + w / 2);
    for (int k = 1; k < 4; ++k) f += kBlackmanHarris[k] * w / (2 * kPi * k) * std::sin(2 * kPi * k * x / w);
    return f / (kBlackmanHarris[0] * w);
  }
  return x / w + 0.5;
}

PixelFilterSampler::PixelFilterSampler(const PixelFilter& filter)
    : kind_(filter.kind), width_px_(pixel_filter_width_px(filter)) {
  if (kind_ == PixelFilterKind::box) return;
  // First guesses: the distribution at fine steps, inverted at evenly
  // spaced probabilities.
  constexpr int kSteps = 16 * kTable;
  inverse_cdf_.resize(kTable + 1);
  const double h = width_px_ / kSteps;
  int j = 0;
  for (int i = 0; i <= kTable; ++i) {
    const double target = static_cast<double>(i) / kTable;
    while (j < kSteps && cdf(-0.5 * width_px_ + h * (j + 1)) < target) ++j;
    inverse_cdf_[i] = -0.5 * width_px_ + h * j;
  }
}

double PixelFilterSampler::offset(double u) const {
  if (kind_ == PixelFilterKind::box) return (u - 0.5) * width_px_;
  const double half = 0.5 * width_px_;
  u = std::clamp(u, 0.0, 1.0);
  const double f = u * kTable;
  const int i = std::min(static_cast<int>(f), kTable - 1);
  // The table brackets the root (a node lies at most one fine step left of
  // its probability's root); Newton's steps stay in the bracket, else halve it.
  double lo = inverse_cdf_[i], hi = std::min(inverse_cdf_[i + 1] + width_px_ / (16 * kTable), half);
  double x = lo + (f - i) * (hi - lo);
  for (int step = 0; step < kMaxSteps && hi - lo > kTolerancePx; ++step) {
    const double c = cdf(x) - u;
    if (c == 0) break;
    (c < 0 ? lo : hi) = x;
    const double d = density(x);
    const double next = d > 0 ? x - c / d : lo;  // no slope: halve
    const double was = x;
    x = next > lo && next < hi ? next : 0.5 * (lo + hi);
    if (std::abs(x - was) < kTolerancePx) break;
  }
  return std::clamp(x, -half, half);
}

}  // namespace purkinje::renderer
