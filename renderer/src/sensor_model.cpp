#include "purkinje/renderer/sensor_model.h"

#include "purkinje/models/check.h"
#include "sampler.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <cstdint>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace purkinje::renderer {
namespace {

using check::fail;
using check::require_non_negative;
using check::require_positive;

constexpr double kPlanck = 6.62607015e-34;    // J s (exact, SI 2019)
constexpr double kLightSpeed = 299792458.0;   // m / s (exact)

void require_plane(const char* what, const ImagePlane& plane) {
  if (plane.width < 0 || plane.height < 0 ||
      plane.values.size() != static_cast<std::size_t>(plane.width) * plane.height) {
    std::ostringstream s;
    s << what << ": " << plane.width << " x " << plane.height << " image holds "
      << plane.values.size() << " values: must hold width * height";
    throw std::invalid_argument(s.str());
  }
}

// Photons per joule at a wavelength.
double photons_per_joule(double wavelength_nm) {
  require_positive("wavelength_nm", wavelength_nm);
  return wavelength_nm * 1e-9 / (kPlanck * kLightSpeed);
}

// 1 / k, so that the Poisson inversion multiplies instead of divides.
constexpr std::array<double, 64> kInverse = [] {
  std::array<double, 64> t{};
  for (std::size_t i = 1; i < t.size(); ++i) t[i] = 1.0 / static_cast<double>(i);
  return t;
}();

// log(k!) for k < 32.
const std::array<double, 32> kLogFactorial = [] {
  std::array<double, 32> t{};
  for (std::size_t i = 1; i < t.size(); ++i) t[i] = t[i - 1] + std::log(static_cast<double>(i));
  return t;
}();

// log(k!) without std::lgamma, which writes the global signgam (a data race
// under TBB).
double log_factorial(double k) {
  if (k < static_cast<double>(kLogFactorial.size())) return kLogFactorial[static_cast<std::size_t>(k)];
  // Stirling's series for log Gamma(x), x = k + 1 >= 33: next term ~2e-17.
  const double x = k + 1, ix = 1 / x, ix2 = ix * ix;
  return (x - 0.5) * std::log(x) - x + 0.5 * std::log(2 * std::numbers::pi) +
         ix * (1.0 / 12 - ix2 * (1.0 / 360 - ix2 * (1.0 / 1260 - ix2 / 1680)));
}

// Below this mean, inversion (about mean + 1 steps); from here on PTRS,
// which is exact for means >= 10.
constexpr double kPoissonInversionLimit = 10;
// Above this mean the normal approximation's skewness error (< 1e-5) is far
// below anything a 16-bit ADC resolves, and PTRS' log-density difference
// would lose precision.
constexpr double kPoissonNormalLimit = 1e10;

// floor for |x| < 2^62, without the libm call or branches that std::floor
// costs on baseline x86-64 (no SSE4.1 roundsd).
double floor_of(double x) {
  const double truncated = static_cast<double>(static_cast<std::int64_t>(x));
  return truncated - (truncated > x ? 1.0 : 0.0);
}

double poisson(double mean, PixelRandom& rng) {
  if (mean <= 0) return 0;
  if (mean < kPoissonInversionLimit) {
    const double u = rng.uniform();
    double p = std::exp(-mean), cdf = p;
    std::size_t k = 0;
    // The cap only guards against a cdf that rounds below u; at mean < 10
    // the probability beyond 63 is below 1e-30.
    while (u > cdf && k + 1 < kInverse.size()) {
      ++k;
      p *= mean * kInverse[k];
      cdf += p;
    }
    return static_cast<double>(k);
  }
  if (mean >= kPoissonNormalLimit) return std::max(0.0, std::round(mean + std::sqrt(mean) * rng.normal()));
  // Hormann (1993), "The transformed rejection method for generating Poisson
  // random variables" (PTRS).
  const double slam = std::sqrt(mean);
  const double b = 0.931 + 2.53 * slam;
  const double a = -0.059 + 0.02483 * b;
  const double vr = 0.9277 - 3.6224 / (b - 2);
  // For the draws the squeeze leaves (60% at a mean of 12, 25% at 500).
  double log_mean = 0, inv_alpha = 0;
  for (;;) {
    const double u = rng.uniform() - 0.5;
    const double v = rng.uniform();
    const double us = 0.5 - std::abs(u);
    // us can reach 0 (u = -0.5) and send this to -inf; negative k are
    // rejected and huge ones fail the final test, so clamping changes no
    // outcome but keeps the conversion defined.
    const double k = floor_of(std::clamp((2 * a / us + b) * u + mean + 0.43, -1.0, 0x1p62));
    if (us >= 0.07 && v <= vr) [[likely]] {
      return k;
    }
    if (k < 0 || (us < 0.013 && v > us)) continue;
    if (log_mean == 0) {
      log_mean = std::log(mean);
      inv_alpha = 1.1239 + 1.1328 / (b - 3.4);
    }
    if (std::log(v * inv_alpha / (a / (us * us) + b)) <= -mean + k * log_mean - log_factorial(k)) {
      return k;
    }
  }
}

// ---------------------------------------------------------------------------
// Blur kernels.

// Half-width of the Gaussian kernel: ~4 sigma, plus one tap so that small
// sigmas keep their (relatively heavy) second neighbours.
int gaussian_radius(double sigma) { return static_cast<int>(std::ceil(4 * sigma)) + 1; }

// The discrete Gaussian T(n, t) = exp(-t) I_n(t) (Lindeberg): the discrete
// analogue of the Gaussian, whose variance is exactly t for every t. (A
// sampled Gaussian's variance is 14% low at sigma 0.5.) Miller's backward
// recurrence I_{n-1} = I_{n+1} + (2n / t) I_n gives the ratios (stable
// downwards); the kernel is truncated to |n| <= radius and normalized.
std::vector<double> truncated_discrete_gaussian(double t, int radius) {
  std::vector<double> taps(radius + 1, 0.0);
  taps[0] = 1;
  // Below this the kernel differs from a delta by < 1e-12 (and the
  // recurrence's growth factor 2n / t would overflow).
  if (t < 1e-12) return taps;
  const int start = 2 * radius + 32;  // I_start / I_radius is negligible
  double above = 0, here = 1e-280;  // I_{n+1}, I_n, up to a common factor
  for (int n = start; n >= 1; --n) {
    if (n <= radius) taps[n] = here;
    const double below = above + (2.0 * n / t) * here;
    above = here;
    here = below;
    if (here > 1e250) {
      for (double& w : taps) w *= 1e-250;
      above *= 1e-250;
      here *= 1e-250;
    }
  }
  taps[0] = here;
  // Normalized over the kept taps, so that flat regions stay flat.
  double kept = taps[0];
  for (int n = 1; n <= radius; ++n) kept += 2 * taps[n];
  for (double& w : taps) w /= kept;
  return taps;
}

// The truncated discrete Gaussian whose variance is sigma^2: truncation
// at ~4 sigma drops up to 0.1% of the variance, so t is raised to match.
std::vector<double> discrete_gaussian(double sigma, int radius) {
  const double target = sigma * sigma;
  double t = target;
  std::vector<double> taps;
  for (int iteration = 0; iteration < 8; ++iteration) {
    taps = truncated_discrete_gaussian(t, radius);
    double variance = 0;
    for (int n = 1; n <= radius; ++n) variance += 2.0 * n * n * taps[n];
    if (std::abs(variance - target) <= 1e-12 * target) break;
    t += target - variance;  // d variance / d t is ~1
  }
  return taps;
}

// Integral of sqrt(r^2 - x^2), from 0 to x.
double half_chord_integral(double r, double x) {
  x = std::clamp(x, -r, r);
  return 0.5 * (x * std::sqrt(std::max(0.0, r * r - x * x)) + r * r * std::asin(x / r));
}

// Exact area of the disc x^2 + y^2 <= r^2 inside [x0, x1] x [y0, y1]. Between
// the breakpoints the overlap's upper and lower edges are each either the
// circle or the rectangle, so each piece integrates in closed form.
double disc_area_in_rectangle(double r, double x0, double x1, double y0, double y1) {
  // Unused cuts repeat x1: empty pieces.
  std::array<double, 8> cuts = {x0, x1, -r, r, x1, x1, x1, x1};
  int n = 4;
  for (double y : {y0, y1}) {
    if (std::abs(y) < r) {
      const double x = std::sqrt(r * r - y * y);
      cuts[n++] = -x;
      cuts[n++] = x;
    }
  }
  std::sort(cuts.begin(), cuts.end());
  double area = 0;
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
    const double a = std::max(cuts[i], x0), b = std::min(cuts[i + 1], x1);
    if (!(b > a)) continue;
    const double m = 0.5 * (a + b);
    if (std::abs(m) >= r) continue;
    const double hm = std::sqrt(r * r - m * m);
    const bool upper_is_circle = hm < y1, lower_is_circle = -hm > y0;
    if ((upper_is_circle ? hm : y1) <= (lower_is_circle ? -hm : y0)) continue;
    const double chord = half_chord_integral(r, b) - half_chord_integral(r, a);
    area += upper_is_circle ? chord : y1 * (b - a);
    area -= lower_is_circle ? -chord : y0 * (b - a);
  }
  return area;
}

// A disc kernel: for each kernel row dy in [-radius, radius], the weights of
// taps dx in [-radius, radius].
struct DiscKernel {
  int radius = 0;
  std::vector<double> weights;  // (2 radius + 1)^2, row-major
  double at(int dx, int dy) const {
    return weights[static_cast<std::size_t>(dy + radius) * (2 * radius + 1) + dx + radius];
  }
};

DiscKernel pixel_weighted_disc(double disc_radius) {
  DiscKernel k;
  k.radius = static_cast<int>(std::ceil(disc_radius + 0.5));
  const int side = 2 * k.radius + 1;
  k.weights.assign(static_cast<std::size_t>(side) * side, 0.0);
  // One quadrant, mirrored: the kernel is exactly symmetric.
  double total = 0;
  for (int dy = 0; dy <= k.radius; ++dy) {
    for (int dx = 0; dx <= k.radius; ++dx) {
      const double area = disc_area_in_rectangle(disc_radius, dx - 0.5, dx + 0.5, dy - 0.5, dy + 0.5);
      for (int sy : {-1, 1}) {
        for (int sx : {-1, 1}) {
          if ((sy < 0 && dy == 0) || (sx < 0 && dx == 0)) continue;
          k.weights[static_cast<std::size_t>(sy * dy + k.radius) * side + sx * dx + k.radius] = area;
          total += area;
        }
      }
    }
  }
  for (double& w : k.weights) w /= total;
  return k;
}

double variance_along_x(const DiscKernel& k) {
  double v = 0;
  for (int dy = -k.radius; dy <= k.radius; ++dy) {
    for (int dx = -k.radius; dx <= k.radius; ++dx) v += dx * dx * k.at(dx, dy);
  }
  return v;
}

// The pixel-weighted disc of the blur circle's own radius r has variance
// r^2 / 4 + ~1/12 per axis: the pixel footprint's 1/12 px^2 is counted a
// second time, since the input image is already an average over each pixel.
// The disc is therefore shrunk slightly (r^2 - 1/3 for large r) until the
// kernel's variance is exactly r^2 / 4, as for add_point_image.
DiscKernel defocus_kernel(double blur_radius) {
  const double target = blur_radius * blur_radius / 4;
  // A disc of radius <= 0.5 stays inside the centre pixel: variance 0.
  double lo = 0.5, hi = blur_radius + 1;
  while (variance_along_x(pixel_weighted_disc(hi)) < target) hi *= 2;
  for (int i = 0; i < 60 && hi - lo > 1e-10 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (variance_along_x(pixel_weighted_disc(mid)) < target ? lo : hi) = mid;
  }
  return pixel_weighted_disc(0.5 * (lo + hi));
}

// Rows are independent: every output value is computed by the same
// operations in the same order whatever the partition, so results do not
// depend on the thread count.
template <class Body>
void for_rows(int height, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<int>(0, height, 8), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y != rows.end(); ++y) body(y);
  });
}

// A w x h plane of zeros in `plane`, reusing its memory.
void reset(ImagePlane& plane, int w, int h) {
  plane.width = w;
  plane.height = h;
  plane.values.assign(static_cast<std::size_t>(w) * h, 0.0f);
}

// Into `out`, through `vertical` (both resized, their memory reused).
void gaussian_blur(const ImagePlane& in, double sigma, ImagePlane& vertical, ImagePlane& out) {
  const int radius = gaussian_radius(sigma);
  const std::vector<double> taps64 = discrete_gaussian(sigma, radius);
  std::vector<float> taps(2 * radius + 1);
  for (int k = -radius; k <= radius; ++k) taps[k + radius] = static_cast<float>(taps64[std::abs(k)]);
  const int w = in.width, h = in.height;

  reset(vertical, w, h);
  for_rows(h, [&](int y) {
    float* out = &vertical.values[static_cast<std::size_t>(y) * w];
    for (int k = -radius; k <= radius; ++k) {
      const float wk = taps[k + radius];
      const float* src = &in.values[static_cast<std::size_t>(std::clamp(y + k, 0, h - 1)) * w];
      for (int x = 0; x < w; ++x) out[x] += wk * src[x];
    }
  });

  reset(out, w, h);
  tbb::parallel_for(tbb::blocked_range<int>(0, h, 8), [&](const tbb::blocked_range<int>& rows) {
    std::vector<float> padded(static_cast<std::size_t>(w) + 2 * radius);
    for (int y = rows.begin(); y != rows.end(); ++y) {
      const float* src = &vertical.values[static_cast<std::size_t>(y) * w];
      std::fill(padded.begin(), padded.begin() + radius, src[0]);
      std::copy(src, src + w, padded.begin() + radius);
      std::fill(padded.begin() + radius + w, padded.end(), src[w - 1]);
      float* dst = &out.values[static_cast<std::size_t>(y) * w];
      for (int k = 0; k <= 2 * radius; ++k) {
        const float wk = taps[k];
        const float* p = padded.data() + k;
        for (int x = 0; x < w; ++x) dst[x] += wk * p[x];
      }
    }
  });
}

// Into `out` (resized, its memory reused).
void disc_blur(const ImagePlane& in, double blur_radius, ImagePlane& out) {
  const DiscKernel kernel = defocus_kernel(blur_radius);
  const int r = kernel.radius, w = in.width, h = in.height;
  // Edge-clamped copy, so the inner loops need no bounds checks.
  const int pw = w + 2 * r;
  std::vector<float> padded(static_cast<std::size_t>(pw) * (h + 2 * r));
  for (int py = 0; py < h + 2 * r; ++py) {
    const float* src = &in.values[static_cast<std::size_t>(std::clamp(py - r, 0, h - 1)) * w];
    float* row = &padded[static_cast<std::size_t>(py) * pw];
    std::fill(row, row + r, src[0]);
    std::copy(src, src + w, row + r);
    std::fill(row + r + w, row + pw, src[w - 1]);
  }
  reset(out, w, h);
  for_rows(h, [&](int y) {
    float* dst = &out.values[static_cast<std::size_t>(y) * w];
    for (int dy = -r; dy <= r; ++dy) {
      const float* row = &padded[static_cast<std::size_t>(y + dy + r) * pw];
      for (int dx = -r; dx <= r; ++dx) {
        const float wk = static_cast<float>(kernel.at(dx, dy));
        if (wk == 0) continue;
        const float* p = row + dx + r;
        for (int x = 0; x < w; ++x) dst[x] += wk * p[x];
      }
    }
  });
}

// ---------------------------------------------------------------------------
// Point images.

// Gauss-Legendre nodes and weights on [-1, 1], 8 points.
constexpr std::array<double, 4> kGaussNodes = {0.1834346424956498, 0.5255324099163290,
                                               0.7966664774136267, 0.9602898564975363};
constexpr std::array<double, 4> kGaussWeights = {0.3626837833783620, 0.3137066458778873,
                                                 0.2223810344533745, 0.1012285362903763};

// Standard normal CDF.
double normal_cdf(double z) { return 0.5 * std::erfc(-z * std::numbers::sqrt2 / 2); }

// Fraction of N(mean, sigma^2) in each pixel [i - 0.5, i + 0.5] of
// [first, first + weights.size()); sigma 0 puts everything in the nearest pixel.
void axis_weights(double mean, double sigma, int first, std::vector<double>& weights) {
  if (sigma == 0) {
    const double nearest = std::floor(mean + 0.5);
    for (std::size_t i = 0; i < weights.size(); ++i) weights[i] = (first + static_cast<double>(i) == nearest);
    return;
  }
  double lower = normal_cdf((first - 0.5 - mean) / sigma);
  for (std::size_t i = 0; i < weights.size(); ++i) {
    const double upper = normal_cdf((first + static_cast<double>(i) + 0.5 - mean) / sigma);
    weights[i] = upper - lower;
    lower = upper;
  }
}

// Pixel integrals of a correlated 2-D Gaussian over a window, written as
// weights[o * inner_count + i] for outer pixel o and inner pixel i. The
// density factors into the outer marginal N(outer_mean, outer_var) and the
// inner conditional N(inner_mean + slope (y - outer_mean), conditional_var):
// the inner integral is exact (erf), the outer one Gauss-Legendre on
// sub-intervals no wider than the integrand's narrowest feature.
// A conditional spread below this (px) is treated as a line: it moves mass
// across pixel borders by less than 1e-3 px.
constexpr double kLineSigma = 1e-3;

void correlated_weights(double inner_mean, double outer_mean, double inner_var, double outer_var,
                        double cov, int inner_first, int inner_count, int outer_first,
                        int outer_count, std::vector<double>& weights) {
  const double outer_sigma = std::sqrt(outer_var);
  const double slope = cov / outer_var;
  const double conditional_var = std::max(0.0, inner_var - cov * cov / outer_var);
  const double conditional_sigma = std::sqrt(conditional_var);
  weights.assign(static_cast<std::size_t>(inner_count) * outer_count, 0.0);

  if (conditional_sigma < kLineSigma) {
    // The source lies on the line x = inner_mean + slope (y - outer_mean)
    // (within kLineSigma): a pixel receives the marginal mass of the
    // y-interval where the line crosses it.
    for (int o = 0; o < outer_count; ++o) {
      const double y0 = outer_first + o - 0.5, y1 = y0 + 1;
      for (int i = 0; i < inner_count; ++i) {
        const double x0 = inner_first + i - 0.5, x1 = x0 + 1;
        double ya = outer_mean + (x0 - inner_mean) / slope, yb = outer_mean + (x1 - inner_mean) / slope;
        if (ya > yb) std::swap(ya, yb);
        const double lo = std::max(ya, y0), hi = std::min(yb, y1);
        if (hi > lo) {
          weights[static_cast<std::size_t>(o) * inner_count + i] =
              normal_cdf((hi - outer_mean) / outer_sigma) - normal_cdf((lo - outer_mean) / outer_sigma);
        }
      }
    }
    return;
  }

  // Narrowest feature in the outer direction: the marginal's width, or how
  // far y moves the conditional mean by one conditional sigma (|slope| <= 1
  // as the outer axis has the larger variance, so this is >= kLineSigma).
  const double feature = std::min(outer_sigma, conditional_sigma / std::abs(slope));
  const int pieces = std::clamp(static_cast<int>(std::ceil(1.0 / feature)), 1, 4096);
  const double half = 0.5 / pieces;
  std::vector<double> cdf(inner_count + 1);
  const double density_scale = 1 / (outer_sigma * std::sqrt(2 * std::numbers::pi));
  for (int o = 0; o < outer_count; ++o) {
    double* row = &weights[static_cast<std::size_t>(o) * inner_count];
    for (int p = 0; p < pieces; ++p) {
      const double centre = outer_first + o - 0.5 + (2 * p + 1) * half;
      for (int g = 0; g < 8; ++g) {
        const double y = centre + (g < 4 ? -1 : 1) * kGaussNodes[g % 4] * half;
        const double dy = y - outer_mean;
        const double weight =
            kGaussWeights[g % 4] * half * density_scale * std::exp(-0.5 * dy * dy / outer_var);
        const double mean = inner_mean + slope * dy;
        for (int i = 0; i <= inner_count; ++i) cdf[i] = normal_cdf((inner_first + i - 0.5 - mean) / conditional_sigma);
        for (int i = 0; i < inner_count; ++i) row[i] += weight * (cdf[i + 1] - cdf[i]);
      }
    }
  }
}

// Pixel range [first, last] within +-5 sigma of mean, clipped to [0, size).
// Returns false if empty.
bool window(double mean, double sigma, int size, int& first, int& last) {
  const double lo = std::floor(mean - 5 * sigma + 0.5), hi = std::floor(mean + 5 * sigma + 0.5);
  if (hi < 0 || lo > size - 1) return false;
  first = static_cast<int>(std::max(lo, 0.0));
  last = static_cast<int>(std::min(hi, size - 1.0));
  return true;
}

}  // namespace

double electrons_per_unit_radiance(const Sensor& sensor, double wavelength_nm) {
  require_positive("sensor.pixel_pitch_mm", sensor.pixel_pitch_mm);
  require_positive("sensor.f_number", sensor.f_number);
  require_non_negative("sensor.exposure_s", sensor.exposure_s);
  require_non_negative("sensor.quantum_efficiency", sensor.quantum_efficiency);
  const double pixel_area_m2 = (sensor.pixel_pitch_mm * 1e-3) * (sensor.pixel_pitch_mm * 1e-3);
  // Irradiance on the sensor from radiance L through an f/N lens:
  // E = L pi / (4 N^2) on axis (camera equation, distant object).
  const double solid_angle_factor = std::numbers::pi / 4 / (sensor.f_number * sensor.f_number);
  return solid_angle_factor * pixel_area_m2 * sensor.exposure_s * sensor.quantum_efficiency *
         photons_per_joule(wavelength_nm);
}

double electrons_per_watt(const Sensor& sensor, double wavelength_nm) {
  require_non_negative("sensor.exposure_s", sensor.exposure_s);
  require_non_negative("sensor.quantum_efficiency", sensor.quantum_efficiency);
  return sensor.exposure_s * sensor.quantum_efficiency * photons_per_joule(wavelength_nm);
}

ImagePlane blur(const ImagePlane& plane, const PointSpread& psf) {
  ImagePlane out, scratch;
  blur(plane, psf, out, scratch);
  return out;
}

void blur(const ImagePlane& plane, const PointSpread& psf, ImagePlane& out, ImagePlane& scratch) {
  require_plane("blur", plane);
  require_non_negative("psf.sigma_px", psf.sigma_px);
  require_non_negative("psf.defocus_radius_px", psf.defocus_radius_px);
  if (&out == &plane || &scratch == &plane || &out == &scratch) {
    throw std::invalid_argument("blur: the input, the output and the scratch plane must be three planes");
  }
  if (plane.values.empty() || (!(psf.sigma_px > 0) && !(psf.defocus_radius_px > 0))) {
    out.width = plane.width;
    out.height = plane.height;
    out.values.assign(plane.values.begin(), plane.values.end());
    return;
  }
  if (psf.sigma_px > 0) {
    gaussian_blur(plane, psf.sigma_px, scratch, out);
    if (psf.defocus_radius_px > 0) {
      std::swap(out, scratch);  // the Gaussian's result is now the disc's input
      disc_blur(scratch, psf.defocus_radius_px, out);
    }
  } else {
    disc_blur(plane, psf.defocus_radius_px, out);
  }
}

void add_point_image(ImagePlane& electrons, double u, double v, double total_electrons,
                     const PointSpread& psf, const double source_cov_px2[3]) {
  require_plane("add_point_image", electrons);
  if (!std::isfinite(u)) fail("add_point_image: u", u, "must be finite");
  if (!std::isfinite(v)) fail("add_point_image: v", v, "must be finite");
  require_non_negative("add_point_image: total_electrons", total_electrons);
  require_non_negative("psf.sigma_px", psf.sigma_px);
  require_non_negative("psf.defocus_radius_px", psf.defocus_radius_px);
  require_non_negative("source_cov_px2[0] (u-u)", source_cov_px2[0]);
  require_non_negative("source_cov_px2[2] (v-v)", source_cov_px2[2]);
  if (!std::isfinite(source_cov_px2[1])) fail("source_cov_px2[1] (u-v)", source_cov_px2[1], "must be finite");
  double cov = source_cov_px2[1];
  const double bound = std::sqrt(source_cov_px2[0] * source_cov_px2[2]);
  if (std::abs(cov) > bound * (1 + 1e-9) + 1e-12) {
    fail("source_cov_px2[1] (u-v)", cov,
         "must not exceed sqrt(u-u * v-v) = " + check::format_number(bound) + " in magnitude (positive semi-definite)");
  }
  cov = std::clamp(cov, -bound, bound);
  if (total_electrons == 0 || electrons.values.empty()) return;

  // The defocus disc enters as a Gaussian of the disc's covariance
  // (r^2 / 4 per axis): the same second moments, but a soft edge.
  const double isotropic = psf.sigma_px * psf.sigma_px + psf.defocus_radius_px * psf.defocus_radius_px / 4;
  const double var_u = isotropic + source_cov_px2[0], var_v = isotropic + source_cov_px2[2];
  int x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  if (!window(u, std::sqrt(var_u), electrons.width, x0, x1) ||
      !window(v, std::sqrt(var_v), electrons.height, y0, y1)) {
    return;
  }
  const int nx = x1 - x0 + 1, ny = y1 - y0 + 1;

  if (cov == 0) {
    std::vector<double> wx(nx), wy(ny);
    axis_weights(u, std::sqrt(var_u), x0, wx);
    axis_weights(v, std::sqrt(var_v), y0, wy);
    for (int j = 0; j < ny; ++j) {
      if (wy[j] == 0) continue;
      for (int i = 0; i < nx; ++i) {
        electrons.at(x0 + i, y0 + j) += static_cast<float>(total_electrons * wy[j] * wx[i]);
      }
    }
    return;
  }

  // Integrate along the axis whose features are wider (fewer sub-intervals).
  // (Both of the integrand's outer-axis widths, sqrt(var) and
  // sqrt(det var) / |cov|, grow with that axis' variance.)
  const bool outer_is_v = var_v >= var_u;
  std::vector<double> weights;
  if (outer_is_v) {
    correlated_weights(u, v, var_u, var_v, cov, x0, nx, y0, ny, weights);
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        electrons.at(x0 + i, y0 + j) +=
            static_cast<float>(total_electrons * weights[static_cast<std::size_t>(j) * nx + i]);
      }
    }
  } else {
    correlated_weights(v, u, var_v, var_u, cov, y0, ny, x0, nx, weights);
    for (int i = 0; i < nx; ++i) {
      for (int j = 0; j < ny; ++j) {
        electrons.at(x0 + i, y0 + j) +=
            static_cast<float>(total_electrons * weights[static_cast<std::size_t>(i) * ny + j]);
      }
    }
  }
}

double lens_illumination(const Camera& camera, double u, double v) {
  const double corner = camera.sensor().corner_illumination;
  if (corner == 1) return 1;
  if (!(corner > 0 && corner <= 1)) fail("sensor.corner_illumination", corner, "must be > 0 and <= 1");
  const Intrinsics& k = camera.intrinsics();
  // The farthest corner of the image's pixel edges from the principal point.
  const double far_u = std::max(k.cx + 0.5, k.width - 0.5 - k.cx), far_v = std::max(k.cy + 0.5, k.height - 0.5 - k.cy);
  const double rho2 = ((u - k.cx) * (u - k.cx) + (v - k.cy) * (v - k.cy)) / (far_u * far_u + far_v * far_v);
  return std::max(0.0, 1 - (1 - corner) * rho2);
}

std::vector<HotPixel> hot_pixels(const Sensor& sensor, int width, int height) {
  if (!(sensor.hot_pixel_fraction >= 0 && sensor.hot_pixel_fraction <= 0.01)) {
    fail("sensor.hot_pixel_fraction", sensor.hot_pixel_fraction, "must be between 0 and 0.01");
  }
  require_non_negative("sensor.hot_pixel_e_per_s", sensor.hot_pixel_e_per_s);
  require_non_negative("sensor.exposure_s", sensor.exposure_s);
  std::vector<HotPixel> hot;
  if (sensor.hot_pixel_fraction == 0) return hot;
  const double mean_e = sensor.hot_pixel_e_per_s * sensor.exposure_s;
  const std::uint64_t pixels = static_cast<std::uint64_t>(std::max(width, 0)) * std::max(height, 0);
  for (std::uint64_t i = 0; i < pixels; ++i) {
    if (uniform01(sensor.hot_pixel_seed, kHotPixelStream, 2 * i) >= sensor.hot_pixel_fraction) continue;
    hot.push_back({static_cast<int>(i % width), static_cast<int>(i / width),
                   mean_e * (0.5 + uniform01(sensor.hot_pixel_seed, kHotPixelStream, 2 * i + 1))});
  }
  return hot;
}

SensorImage expose(const ImagePlane& electrons, const Sensor& sensor, std::uint64_t seed) {
  require_plane("expose", electrons);
  if (sensor.bits != 8 && sensor.bits != 10 && sensor.bits != 12 && sensor.bits != 16) {
    throw std::invalid_argument("sensor.bits = " + std::to_string(sensor.bits) + ": must be 8, 10, 12 or 16");
  }
  require_positive("sensor.full_well_e", sensor.full_well_e);
  require_non_negative("sensor.gain", sensor.gain);
  require_non_negative("sensor.read_noise_e", sensor.read_noise_e);

  SensorImage image;
  image.width = electrons.width;
  image.height = electrons.height;
  image.bits = sensor.bits;
  image.values.assign(electrons.values.size(), 0);
  const std::int64_t max_dn = (std::int64_t{1} << sensor.bits) - 1;
  const double max_dn_real = static_cast<double>(max_dn);
  const double dn_per_electron = sensor.gain * max_dn_real / sensor.full_well_e;
  const double full_well = sensor.full_well_e, read_noise = sensor.read_noise_e;

  // Dark charge: zero but for the hot pixels.
  std::vector<double> dark;
  const std::vector<HotPixel> hot = hot_pixels(sensor, electrons.width, electrons.height);
  if (!hot.empty()) {
    dark.assign(electrons.values.size(), 0.0);
    for (const HotPixel& p : hot) dark[static_cast<std::size_t>(p.y) * electrons.width + p.x] = p.dark_e;
  }

  const bool noise = sensor.noise;
  const std::uint64_t noise_key = stream_key(seed, kSensorNoiseStream);
  for_rows(electrons.height, [&](int y) {
    const std::size_t row = static_cast<std::size_t>(y) * electrons.width;
    const float* in = electrons.values.data() + row;
    unsigned short* out = image.values.data() + row;
    for (int x = 0; x < electrons.width; ++x) {
      double mean = in[x];
      if (!dark.empty()) mean = (mean > 0 ? mean : 0.0) + dark[row + x];
      // NaN and negative light count as none; light that overflowed to
      // +inf saturates like any other far too bright pixel.
      double e = mean > 0 ? std::min(mean, std::numeric_limits<double>::max()) : 0.0;
      // So far above the full well that no draw could come back below it.
      const bool saturated = e > full_well && e - 40 * std::sqrt(e) - 40 * read_noise > full_well;
      if (noise && !saturated) {
        PixelRandom rng(counter_key(noise_key, row + x));
        if (e > 0) e = poisson(e, rng);
        if (read_noise > 0) e += read_noise * rng.normal();
      }
      // Clipping and rounding free of branches: in dark pixels read noise
      // makes the sign of e a coin flip. Truncation rounds half up for
      // e >= 0 and gives <= 0 below; the bounds keep any gain or read noise
      // within int64.
      const double scaled = std::min(e, full_well) * dn_per_electron + 0.5;
      const auto dn = static_cast<std::int64_t>(std::min(std::max(scaled, -1.0), max_dn_real));
      out[x] = static_cast<unsigned short>(std::clamp<std::int64_t>(dn, 0, max_dn));
    }
  });
  return image;
}


}  // namespace purkinje::renderer
