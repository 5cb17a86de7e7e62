// Pixel filters (RenderOptions::pixel_filter): the sample offsets' moments
// against the filters' own, integrated here by Simpson's rule from the
// formulas written out again; and what a filter may and may not change in
// an image.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "pixel_filter.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/renderer/render.h"

namespace purkinje::renderer {
namespace {

// Second moment of a filter along one axis, integral x^2 f / integral f
// over [-w/2, w/2].
template <class F>
double second_moment(F f, double w) {
  constexpr int n = 20000;  // even
  const double h = w / n;
  double m0 = 0, m2 = 0;
  for (int i = 0; i <= n; ++i) {
    const double x = -w / 2 + i * h;
    const double c = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
    m0 += c * f(x);
    m2 += c * x * x * f(x);
  }
  return m2 / m0;
}

// The same moment of the sampler's offsets, over u evenly in [0, 1).
double sampled_second_moment(const PixelFilterSampler& s) {
  constexpr int n = 200000;
  double m2 = 0;
  for (int i = 0; i < n; ++i) {
    const double x = s.offset((i + 0.5) / n);
    m2 += x * x;
  }
  return m2 / n;
}

TEST(PixelFilter, TheBoxSpreadsSamplesEvenlyOverItsWidth) {
  const PixelFilterSampler box(PixelFilter{});
  for (const double u : {0.0, 0.1, 0.5, 0.73, 0.999}) EXPECT_EQ(box.offset(u), u - 0.5);
  const PixelFilterSampler wide(PixelFilter{PixelFilterKind::box, 2.0});
  EXPECT_EQ(wide.offset(0.25), -0.5);
  EXPECT_NEAR(sampled_second_moment(wide), 4.0 / 12, 1e-9);  // w^2 / 12
}

TEST(PixelFilter, GaussianAndBlackmanHarrisSamplesHaveTheirFiltersMoments) {
  const double w = 3.0;
  const double sigma = w / 6;
  const double gauss = second_moment([&](double x) { return std::exp(-x * x / (2 * sigma * sigma)); }, w);
  // A Gaussian cut at 3 sigma keeps about 97.3% of its variance.
  EXPECT_NEAR(gauss / (sigma * sigma), 0.9733, 1e-3);
  const PixelFilterSampler g(PixelFilter{PixelFilterKind::gaussian, 0});
  EXPECT_NEAR(sampled_second_moment(g), gauss, 1e-4 * gauss);

  const double pi = std::numbers::pi;
  const auto blackman_harris = [&](double x) {  // Harris 1978, over [0, w] shifted to [-w/2, w/2]
    const double n = x + w / 2;
    return 0.35875 - 0.48829 * std::cos(2 * pi * n / w) + 0.14128 * std::cos(4 * pi * n / w) -
           0.01168 * std::cos(6 * pi * n / w);
  };
  const double bh = second_moment(blackman_harris, w);
  const PixelFilterSampler b(PixelFilter{PixelFilterKind::blackman_harris, 0});
  EXPECT_NEAR(sampled_second_moment(b), bh, 1e-4 * bh);
  // Narrower than the box of the same width: most weight near the centre.
  EXPECT_LT(bh, w * w / 12 / 3);

  // Symmetric about the centre, increasing, within the support.
  for (const PixelFilterSampler* s : {&g, &b}) {
    double last = -w;
    for (int i = 0; i < 1000; ++i) {
      const double u = (i + 0.5) / 1000;
      EXPECT_NEAR(s->offset(u), -s->offset(1 - u), 1e-9);
      EXPECT_GT(s->offset(u), last);
      last = s->offset(u);
      EXPECT_LE(std::abs(last), w / 2);
    }
  }
}

TEST(PixelFilter, NamesAndWidthsAreTheOptionsAndBadWidthsAreRefused) {
  for (const PixelFilterKind k : {PixelFilterKind::box, PixelFilterKind::gaussian, PixelFilterKind::blackman_harris}) {
    EXPECT_EQ(pixel_filter_kind(to_string(k)), k);
  }
  EXPECT_FALSE(pixel_filter_kind("mitchell"));
  EXPECT_EQ(pixel_filter_width_px({PixelFilterKind::box, 0}), 1.0);
  EXPECT_EQ(pixel_filter_width_px({PixelFilterKind::gaussian, 0}), 3.0);
  EXPECT_EQ(pixel_filter_width_px({PixelFilterKind::blackman_harris, 2.5}), 2.5);

  const Scene scene = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/remote.json");
  RenderOptions options;
  options.region = PixelRegion{0, 0, 8, 8};
  for (const double bad : {0.1, -1.0, 17.0, std::nan("")}) {
    options.pixel_filter = {PixelFilterKind::gaussian, bad};
    try {
      render(scene, 0, options);
      ADD_FAILURE() << bad << " was taken";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("pixel_filter width_px"), std::string::npos) << e.what();
    }
  }
}

// A pixel's rays are its own whatever the filter, so a region is exactly
// that part of the whole image; and where the radiance is flat (skin far
// from the eye, lit from 600 mm) a filter changes it by no more than its
// spread of positions does the radiance.
TEST(PixelFilter, ARegionIsThatPartOfTheWholeImageAndFlatSkinStaysPut) {
  const Scene scene = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/remote.json");
  RenderOptions options;
  options.noise = false;
  options.samples_per_pixel = 4;
  options.pixel_filter = {PixelFilterKind::blackman_harris, 0};
  const PixelRegion region{300, 200, 340, 240};
  options.region = region;
  const RenderResult part = render(scene, 0, options);
  options.region = PixelRegion{280, 180, 360, 260};
  const RenderResult larger = render(scene, 0, options);
  for (int y = region.y0; y < region.y1; ++y) {
    for (int x = region.x0; x < region.x1; ++x) {
      ASSERT_EQ(part.radiance.at(x, y), larger.radiance.at(x, y)) << x << ", " << y;
    }
  }
  options.region = PixelRegion{20, 20, 40, 36};
  const RenderResult filtered = render(scene, 0, options);
  options.pixel_filter = {};
  const RenderResult box = render(scene, 0, options);
  for (int y = 20; y < 36; ++y) {
    for (int x = 20; x < 40; ++x) {
      EXPECT_NEAR(filtered.radiance.at(x, y), box.radiance.at(x, y), 1e-3 * box.radiance.at(x, y));
    }
  }
}

}  // namespace
}  // namespace purkinje::renderer
