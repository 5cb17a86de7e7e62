#pragma once
// All of the renderer's randomness, internal to renderer/: counter-based,
// every number a pure function of (seed, stream, index), so an image does
// not depend on threads or on the order pixels are done in. One mixer
// (splitmix64's finalizer) serves every stream: camera jitter, the caches'
// gather directions, the reference's paths and photons, the sensor's noise
// (a per-pixel sequence), and the iris texture's lattice. Also the
// low-discrepancy points the samples sit at.

#include <array>
#include <cmath>
#include <cstdint>

#include "purkinje/models/counter_random.h"
#include "purkinje/renderer/sensor_model.h"  // uniform01, the public face of these streams

namespace purkinje::renderer {

// The streams, one per purpose. The fast and the reference integrators
// never share a render, so their streams reuse 3 and 4; the sensor's
// noise is keyed apart, above the 2^63 that uniform01's callers keep below.
enum Stream : std::uint64_t {
  kJitterStream = 1,      // camera rays' sub-pixel positions (fast and reference)
  kCacheNodeStream = 3,   // fast: the diffuse cache's gather at its nodes
  kCacheMissStream = 4,   // fast: the gather where no node serves a point
  kPathStream = 3,        // reference: a camera path's decisions
  kPhotonStream = 4,      // reference: the photons through the cornea
  kIrisIndirectStream = 5,  // fast: the iris's indirect light at its ring nodes
  kMirrorGatherStream = 6,  // fast: the gather at a surface seen in the cornea's mirror
  kSensorNoiseStream = 0x8000000000000001ull,
  // A sensor's hot pixels, keyed by its hot_pixel_seed (not the render's).
  kHotPixelStream = 0x8000000000000002ull,
};

// Tables of Marsaglia and Tsang's ziggurat for the standard normal (2000,
// "The ziggurat method for generating random variables"): 128 layers of
// equal area v under exp(-x^2 / 2), the base one with the tail beyond r.
struct Ziggurat {
  static constexpr double r = 3.442619855899;        // right edge of the base layer
  static constexpr double v = 9.91256303526217e-3;   // area of each layer
  static constexpr double scale = 2147483648.0;      // 2^31: draws are signed 32-bit
  std::array<double, 128> k{};  // accept |draw| < k[i] at once (layer i's rectangle core)
  std::array<double, 128> w{};  // x = draw * w[i]
  std::array<double, 128> f{};  // exp(-x_i^2 / 2)
  Ziggurat() {
    double x = r, outer = r;
    const double q = v / std::exp(-0.5 * r * r);
    k[0] = (r / q) * scale;
    k[1] = 0;
    w[0] = q / scale;
    w[127] = r / scale;
    f[0] = 1;
    f[127] = std::exp(-0.5 * r * r);
    for (int i = 126; i >= 1; --i) {
      x = std::sqrt(-2 * std::log(v / x + std::exp(-0.5 * x * x)));
      k[i + 1] = (x / outer) * scale;
      outer = x;
      f[i] = std::exp(-0.5 * x * x);
      w[i] = x / scale;
    }
  }
};

// Built at load time (sampler.cpp): no guard on the hot path.
extern const Ziggurat kZiggurat;

// A pixel's private sequence: splitmix64 started from the pixel's key.
class PixelRandom {
 public:
  explicit PixelRandom(std::uint64_t key) : state_(key) {}
  std::uint64_t bits() {
    state_ += 0x9E3779B97F4A7C15ull;
    return mix64(state_);
  }
  double uniform() { return to_unit(bits()); }
  // Ziggurat: ~99% of draws cost one table look-up and a multiply. The
  // layer comes from the low bits and the signed position from the high
  // ones, so the two are independent (Doornik, 2005).
  double normal() {
    const Ziggurat& z = kZiggurat;
    const std::uint64_t b = bits();
    const int layer = static_cast<int>(b & 127);
    const double draw = static_cast<double>(static_cast<std::int32_t>(static_cast<std::uint32_t>(b >> 32)));
    if (std::abs(draw) < z.k[layer]) [[likely]] {
      return draw * z.w[layer];
    }
    return normal_outside_core(layer, draw);
  }

 private:
  // The rare rest of the ziggurat, kept out of line (sampler.cpp) so the
  // common path inlines.
  [[gnu::noinline]] double normal_outside_core(int layer, double draw);

  std::uint64_t state_;
};

// The random numbers of one camera path of the reference integrator:
// dimension d of path p is uniform01(seed, kPathStream, p * 2^10 + d).
class PathSampler {
 public:
  static constexpr int kDimensionBits = 10;
  static constexpr std::uint64_t kDimensions = std::uint64_t{1} << kDimensionBits;
  PathSampler(std::uint64_t seed, std::uint64_t path) : seed_(seed), base_(path << kDimensionBits) {}
  // Past the last dimension the path reuses numbers; the reference's
  // bounce limit keeps paths far below that.
  double next() {
    const std::uint64_t d = dimension_++ & (kDimensions - 1);
    return uniform01(seed_, kPathStream, base_ + d);
  }

 private:
  std::uint64_t seed_, base_, dimension_ = 0;
};

// Additive recurrence (the R2 sequence): well-spread points of the unit
// square for any count, shifted by (shift_u, shift_v).
inline std::array<double, 2> r2_point(int sample, double shift_u, double shift_v) {
  constexpr double a1 = 0.7548776662466927, a2 = 0.5698402909980532;
  const double u = shift_u + a1 * sample, v = shift_v + a2 * sample;
  return {u - std::floor(u), v - std::floor(v)};
}

}  // namespace purkinje::renderer
