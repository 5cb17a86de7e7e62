#include "sampler.h"

namespace purkinje::renderer {

const Ziggurat kZiggurat;

double uniform01(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) {
  return to_unit(counter_key(stream_key(seed, stream), index));
}

// The rare rest of the ziggurat.
double PixelRandom::normal_outside_core(int layer, double draw) {
  const Ziggurat& z = kZiggurat;
  for (;;) {
    const double x = draw * z.w[layer];
    if (layer == 0) {  // the tail beyond r, by Marsaglia's exponential method
      double tail = 0, y = 0;
      do {
        tail = -std::log(1 - uniform()) / Ziggurat::r;
        y = -std::log(1 - uniform());
      } while (y + y < tail * tail);
      return draw > 0 ? Ziggurat::r + tail : -Ziggurat::r - tail;
    }
    // The wedge between the layer's core and the curve.
    if (z.f[layer] + uniform() * (z.f[layer - 1] - z.f[layer]) < std::exp(-0.5 * x * x)) return x;
    const std::uint64_t b = bits();
    layer = static_cast<int>(b & 127);
    draw = static_cast<double>(static_cast<std::int32_t>(static_cast<std::uint32_t>(b >> 32)));
    if (std::abs(draw) < z.k[layer]) return draw * z.w[layer];
  }
}

}  // namespace purkinje::renderer
