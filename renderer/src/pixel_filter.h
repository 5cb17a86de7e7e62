#pragma once
// Sample positions about a pixel's centre drawn from its pixel filter
// (RenderOptions::pixel_filter): filter importance sampling, one axis at a
// time (the filters are separable).

#include <vector>

#include "purkinje/renderer/render.h"

namespace purkinje::renderer {

class PixelFilterSampler {
 public:
  explicit PixelFilterSampler(const PixelFilter& filter);
  // The offset (px) from the pixel's centre, along one axis, of the sample
  // at u in [0, 1): the filter's inverse cumulative distribution. The box
  // gives (u - 1/2) w exactly.
  double offset(double u) const;

 private:
  // The filter's cumulative distribution and density along an axis.
  double cdf(double x) const;
  double density(double x) const;

  PixelFilterKind kind_ = PixelFilterKind::box;
  double width_px_ = 1;
  std::vector<double> inverse_cdf_;  // a first guess: offsets at u = i / (size - 1)
};

}  // namespace purkinje::renderer
