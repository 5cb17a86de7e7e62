#include "purkinje/renderer/sensor_model.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace purkinje::renderer {
namespace {

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no exception)";
}

// Pixel-weighted moments of a plane: total, centroid, central second moments.
struct Moments {
  double total = 0, u = 0, v = 0, uu = 0, uv = 0, vv = 0;
};

Moments moments_of(const ImagePlane& p) {
  Moments m;
  for (int y = 0; y < p.height; ++y) {
    for (int x = 0; x < p.width; ++x) {
      const double w = p.at(x, y);
      m.total += w;
      m.u += w * x;
      m.v += w * y;
    }
  }
  m.u /= m.total;
  m.v /= m.total;
  for (int y = 0; y < p.height; ++y) {
    for (int x = 0; x < p.width; ++x) {
      const double w = p.at(x, y) / m.total, du = x - m.u, dv = y - m.v;
      m.uu += w * du * du;
      m.uv += w * du * dv;
      m.vv += w * dv * dv;
    }
  }
  return m;
}

ImagePlane delta(int size) {
  ImagePlane p(size, size);
  p.at(size / 2, size / 2) = 1;
  return p;
}

const double kNoSourceSpread[3] = {0, 0, 0};

// A sensor whose digital numbers are the electrons themselves (16 bits,
// full well 65535 e, gain 1): DN = round(e).
Sensor counting_sensor(double read_noise_e) {
  Sensor s;
  s.bits = 16;
  s.full_well_e = 65535;
  s.gain = 1;
  s.read_noise_e = read_noise_e;
  s.noise = true;
  return s;
}

// ---------------------------------------------------------------------------
// Radiometry.

TEST(SensorRadiometry, ElectronsPerUnitRadianceFollowTheCameraEquation) {
  Sensor s;
  s.pixel_pitch_mm = 0.01;  // 1e-10 m^2
  s.f_number = 2;
  s.exposure_s = 0.01;
  s.quantum_efficiency = 0.5;
  // (pi / 4) / 2^2 = 0.19634954; lambda / (h c) at 1000 nm = 1e-6 /
  // 1.98644586e-25 J m = 5.0341166e18 photons/J;
  // 0.19634954 * 1e-10 * 0.01 * 0.5 * 5.0341166e18 = 494223.2 electrons.
  EXPECT_NEAR(electrons_per_unit_radiance(s, 1000), 494223.2, 0.1);
  // Linear in the pixel area, inverse square in the f-number.
  s.f_number = 4;
  EXPECT_NEAR(electrons_per_unit_radiance(s, 1000), 494223.2 / 4, 0.1);
}

TEST(SensorRadiometry, ElectronsPerWattCountPhotonsTimesEfficiency) {
  Sensor s;
  s.exposure_s = 0.01;
  s.quantum_efficiency = 0.5;
  // 1 W for 0.01 s at 1000 nm: 0.01 J * 5.0341166e18 photons/J * 0.5.
  EXPECT_NEAR(electrons_per_watt(s, 1000) / 2.5170583e16, 1.0, 1e-7);
  // Photon energy scales as 1 / lambda.
  EXPECT_NEAR(electrons_per_watt(s, 500) / 2.5170583e16, 0.5, 1e-7);
}

TEST(SensorRadiometry, RejectsMeaninglessSensors) {
  Sensor s;
  EXPECT_NE(message_of([&] { electrons_per_unit_radiance(s, 0); }).find("wavelength_nm = 0"),
            std::string::npos);
  s.pixel_pitch_mm = -0.005;
  EXPECT_NE(message_of([&] { electrons_per_unit_radiance(s, 850); }).find("sensor.pixel_pitch_mm = -0.005"),
            std::string::npos);
  s = Sensor{};
  s.exposure_s = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(message_of([&] { electrons_per_watt(s, 850); }).find("sensor.exposure_s"), std::string::npos);
}

// ---------------------------------------------------------------------------
// Blur.

TEST(Blur, WithoutSpreadReturnsTheInputUnchanged) {
  ImagePlane p(7, 5);
  for (std::size_t i = 0; i < p.values.size(); ++i) p.values[i] = static_cast<float>(i * i) - 3.5f;
  const ImagePlane out = blur(p, {0.0, 0.0});
  EXPECT_EQ(out.width, 7);
  EXPECT_EQ(out.height, 5);
  EXPECT_EQ(out.values, p.values);
}

// Into planes that held another image (another size, other values): what
// they held must not show.
TEST(Blur, IntoReusedPlanesGivesWhatFreshPlanesGive) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<float> value(0, 100);
  ImagePlane p(37, 23);
  for (float& v : p.values) v = value(rng);
  for (const PointSpread psf : {PointSpread{0, 0}, PointSpread{0.8, 0}, PointSpread{0, 2.5}, PointSpread{0.7, 3.3}}) {
    ImagePlane out(50, 61, 9.0f), scratch(3, 2, -4.0f);
    blur(p, psf, out, scratch);
    const ImagePlane fresh = blur(p, psf);
    EXPECT_EQ(out.width, 37);
    EXPECT_EQ(out.height, 23);
    EXPECT_EQ(out.values, fresh.values) << psf.sigma_px << " " << psf.defocus_radius_px;
  }
  ImagePlane out;
  EXPECT_THROW(blur(p, {0.5, 0}, out, out), std::invalid_argument);
  EXPECT_THROW(blur(p, {0.5, 0}, p, out), std::invalid_argument);
}

TEST(Blur, FlatImageStaysFlatUpToTheBorders) {
  for (const PointSpread psf : {PointSpread{0.5, 0}, PointSpread{2.2, 0}, PointSpread{0.7, 3.3}}) {
    const ImagePlane out = blur(ImagePlane(40, 30, 7.25f), psf);
    for (float value : out.values) ASSERT_NEAR(value, 7.25, 1e-5) << psf.sigma_px << " " << psf.defocus_radius_px;
  }
}

TEST(Blur, ConservesTheSumOfAnInteriorImage) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<float> value(0, 100);
  ImagePlane p(80, 70);
  for (int y = 20; y < 50; ++y) {
    for (int x = 20; x < 60; ++x) p.at(x, y) = value(rng);
  }
  double before = 0;
  for (float v : p.values) before += v;
  for (const PointSpread psf : {PointSpread{0.5, 0}, PointSpread{1.3, 0}, PointSpread{1.0, 4.5}}) {
    double after = 0;
    for (float v : blur(p, psf).values) after += v;
    EXPECT_NEAR(after / before, 1.0, 1e-5);
  }
}

TEST(Blur, VarianceOfABlurredDeltaIsSigmaSquared) {
  for (double sigma : {0.3, 0.5, 1.3, 3.0}) {
    const Moments m = moments_of(blur(delta(64), {sigma, 0}));
    EXPECT_NEAR(m.total, 1.0, 1e-5);
    EXPECT_NEAR(m.u, 32, 1e-5);
    // A sampled Gaussian would give 0.215 at sigma 0.5.
    EXPECT_NEAR(m.uu / (sigma * sigma), 1.0, 1e-3) << sigma;
    EXPECT_NEAR(m.vv / (sigma * sigma), 1.0, 1e-3) << sigma;
    EXPECT_NEAR(m.uv, 0.0, 1e-6);
  }
}

TEST(Blur, DefocusDiscAddsAQuarterOfItsRadiusSquared) {
  struct Case {
    double sigma, radius;
  };
  for (const Case c : {Case{0.5, 3.0}, Case{0.0, 1.2}, Case{0.0, 0.4}, Case{0.8, 8.0}}) {
    const Moments m = moments_of(blur(delta(64), {c.sigma, c.radius}));
    const double expected = c.sigma * c.sigma + c.radius * c.radius / 4;
    EXPECT_NEAR(m.total, 1.0, 1e-5);
    EXPECT_NEAR(m.uu / expected, 1.0, 1e-3) << c.sigma << " " << c.radius;
    EXPECT_NEAR(m.vv / expected, 1.0, 1e-3) << c.sigma << " " << c.radius;
    EXPECT_NEAR(m.uv, 0.0, 1e-6);
  }
}

TEST(Blur, DefocusDiscHasAFlatTopAndASharpEdge) {
  const double r = 6;
  const ImagePlane out = blur(delta(41), {0.0, r});
  const float top = out.at(20, 20);
  // A uniform disc of area ~pi r^2 (shrunk by 1/3 px^2 for the pixel footprint).
  EXPECT_NEAR(top, 1 / (std::numbers::pi * (r * r - 1.0 / 3)), 1e-4);
  for (int y = 0; y < 41; ++y) {
    for (int x = 0; x < 41; ++x) {
      const double d = std::hypot(x - 20, y - 20);
      if (d <= r - 1) {
        EXPECT_NEAR(out.at(x, y), top, 1e-6) << x << "," << y;
      }
      if (d >= r + 1) {
        EXPECT_EQ(out.at(x, y), 0.0f) << x << "," << y;
      }
    }
  }
}

TEST(Blur, EdgesAreClampedNotDarkened) {
  // Bright left half: with clamp-to-edge the border columns keep their
  // value; zero padding would halve column 0.
  ImagePlane p(60, 20);
  for (int y = 0; y < 20; ++y) {
    for (int x = 0; x < 30; ++x) p.at(x, y) = 10;
  }
  for (const PointSpread psf : {PointSpread{1.5, 0}, PointSpread{0.5, 4}}) {
    const ImagePlane out = blur(p, psf);
    for (int y = 0; y < 20; ++y) {
      EXPECT_NEAR(out.at(0, y), 10, 1e-4);
      EXPECT_NEAR(out.at(59, y), 0, 1e-6);
      // The step's midpoint stays between columns 29 and 30.
      EXPECT_NEAR(out.at(29, y) + out.at(30, y), 10, 1e-4);
    }
  }
}

TEST(Blur, RejectsNegativeOrNonFiniteSpread) {
  const ImagePlane p(4, 4);
  EXPECT_NE(message_of([&] { blur(p, {-0.5, 0}); }).find("psf.sigma_px = -0.5"), std::string::npos);
  EXPECT_NE(message_of([&] { blur(p, {0.5, std::nan("")}); }).find("psf.defocus_radius_px"), std::string::npos);
}

// ---------------------------------------------------------------------------
// Point images.

TEST(PointImage, DepositsAllElectronsOfAnInteriorSpot) {
  const double diagonal[3] = {0, 0, 0}, tilted[3] = {2.0, 0.8, 1.0};
  for (const double* cov : {diagonal, tilted}) {
    ImagePlane p(64, 64);
    add_point_image(p, 30.3, 29.8, 12345.0, {0.5, 0}, cov);
    EXPECT_NEAR(moments_of(p).total / 12345.0, 1.0, 1e-5);
  }
}

TEST(PointImage, CentroidIsThePointWithinFiveThousandthsOfAPixel) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> offset(-0.5, 0.5);
  const double tilted[3] = {0.3, 0.2, 0.4};
  double worst_round = 0, worst_tilted = 0;
  for (int i = 0; i < 100; ++i) {
    const double u = 15 + offset(rng), v = 16 + offset(rng);
    ImagePlane p(32, 32);
    add_point_image(p, u, v, 1000.0, {0.5, 0}, kNoSourceSpread);
    Moments m = moments_of(p);
    worst_round = std::max({worst_round, std::abs(m.u - u), std::abs(m.v - v)});
    // The correlated case goes through numerical integration.
    ImagePlane q(32, 32);
    add_point_image(q, u, v, 1000.0, {0.5, 0}, tilted);
    m = moments_of(q);
    worst_tilted = std::max({worst_tilted, std::abs(m.u - u), std::abs(m.v - v)});
  }
  EXPECT_LT(worst_round, 0.005);
  EXPECT_LT(worst_tilted, 0.005);
  // The sampling bias is real but small: about 0.0023 px at sigma 0.5.
  EXPECT_GT(worst_round, 0.001);
}

TEST(PointImage, SecondMomentsAreTheCovariancePlusThePixel) {
  // Pixel integration adds a uniform [-0.5, 0.5] per axis: 1/12 px^2 on
  // the diagonal, nothing off it.
  struct Case {
    double cov[3];
    PointSpread psf;
  };
  const Case cases[] = {{{2.0, 0.8, 1.0}, {0.5, 0}},    // wider in u
                        {{0.5, -0.6, 3.0}, {0.5, 0}},   // wider in v, negative correlation
                        {{1.5, 0.0, 0.2}, {0.5, 0}},    // axis-aligned
                        {{0.0, 0.0, 0.0}, {0.5, 2.0}}};  // defocus: + r^2 / 4
  for (const Case& c : cases) {
    ImagePlane p(64, 64);
    add_point_image(p, 31.37, 32.81, 500.0, c.psf, c.cov);
    const Moments m = moments_of(p);
    const double iso = c.psf.sigma_px * c.psf.sigma_px + c.psf.defocus_radius_px * c.psf.defocus_radius_px / 4;
    EXPECT_NEAR(m.total / 500.0, 1.0, 1e-5);
    EXPECT_NEAR(m.u, 31.37, 1e-3);
    EXPECT_NEAR(m.v, 32.81, 1e-3);
    EXPECT_NEAR(m.uu / (iso + c.cov[0] + 1.0 / 12), 1.0, 0.005) << c.cov[0];
    EXPECT_NEAR(m.vv / (iso + c.cov[2] + 1.0 / 12), 1.0, 0.005) << c.cov[2];
    EXPECT_NEAR(m.uv, c.cov[1], 0.005) << c.cov[1];
  }
}

TEST(PointImage, LineSourceWithoutBlurStaysOnItsDiagonal) {
  // Rank-one covariance along u = v, no point spread: every draw falls on
  // the line v - 20.3 = u - 10.3, i.e. in pixels (i, i + 10) only.
  const double line[3] = {1.0, 1.0, 1.0};
  ImagePlane p(40, 40);
  add_point_image(p, 10.3, 20.3, 100.0, {0.0, 0.0}, line);
  double off_diagonal = 0;
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 40; ++x) {
      if (y != x + 10) off_diagonal += p.at(x, y);
    }
  }
  EXPECT_LT(off_diagonal, 1e-3);
  const Moments m = moments_of(p);
  EXPECT_NEAR(m.total, 100.0, 1e-3);
  EXPECT_NEAR(m.u, 10.3, 1e-4);
  EXPECT_NEAR(m.v, 20.3, 1e-4);
  // Rounding a unit normal to integers: variance 1 + 1/12 (Sheppard).
  EXPECT_NEAR(m.uu, 1 + 1.0 / 12, 1e-3);
  EXPECT_NEAR(m.vv, 1 + 1.0 / 12, 1e-3);
  EXPECT_NEAR(m.uv, 1 + 1.0 / 12, 1e-3);
}

TEST(PointImage, ZeroSpreadPutsEverythingIntoTheNearestPixel) {
  ImagePlane p(32, 32);
  add_point_image(p, 10.3, 20.7, 250.0, {0.0, 0.0}, kNoSourceSpread);
  EXPECT_FLOAT_EQ(p.at(10, 21), 250.0f);
  EXPECT_NEAR(moments_of(p).total, 250.0, 1e-9);
}

TEST(PointImage, LightBeyondTheImageIsLost) {
  // Centred on column 0 with sigma 1: the image holds u >= -0.5, a
  // fraction Phi(0.5) = 0.6914625.
  ImagePlane p(32, 32);
  add_point_image(p, 0.0, 16.0, 1000.0, {1.0, 0}, kNoSourceSpread);
  EXPECT_NEAR(moments_of(p).total / 1000.0, 0.6914625, 2e-6);
  // Entirely outside: nothing changes.
  ImagePlane q(32, 32);
  add_point_image(q, -40.0, 16.0, 1000.0, {1.0, 0}, kNoSourceSpread);
  add_point_image(q, 16.0, 1e9, 1000.0, {1.0, 0}, kNoSourceSpread);
  for (float v : q.values) ASSERT_EQ(v, 0.0f);
}

TEST(PointImage, AddsToWhatIsAlreadyThere) {
  ImagePlane p(16, 16, 3.0f);
  add_point_image(p, 8.0, 8.0, 160.0, {0.0, 0.0}, kNoSourceSpread);
  EXPECT_FLOAT_EQ(p.at(8, 8), 163.0f);
  EXPECT_FLOAT_EQ(p.at(7, 8), 3.0f);
}

TEST(PointImage, RejectsBadInputs) {
  ImagePlane p(16, 16);
  const PointSpread psf{0.5, 0};
  EXPECT_NE(message_of([&] { add_point_image(p, std::nan(""), 8, 10, psf, kNoSourceSpread); }).find("u = nan"),
            std::string::npos);
  EXPECT_NE(message_of([&] { add_point_image(p, 8, 8, -10, psf, kNoSourceSpread); }).find("total_electrons = -10"),
            std::string::npos);
  const double not_psd[3] = {1.0, 2.0, 1.0};
  EXPECT_NE(message_of([&] { add_point_image(p, 8, 8, 10, psf, not_psd); }).find("semi-definite"),
            std::string::npos);
  const double negative[3] = {-1.0, 0.0, 1.0};
  EXPECT_NE(message_of([&] { add_point_image(p, 8, 8, 10, psf, negative); }).find("source_cov_px2[0]"),
            std::string::npos);
  for (float v : p.values) ASSERT_EQ(v, 0.0f);
}

// ---------------------------------------------------------------------------
// Exposure.

TEST(Expose, NoiselessDigitalNumbersByHand) {
  Sensor s;
  s.noise = false;
  s.full_well_e = 10000;
  s.gain = 1;
  s.bits = 8;
  ImagePlane e(4, 1);
  e.values = {0.0f, 1234.0f, 10000.0f, 20.0f};
  SensorImage dn = expose(e, s, 1);
  EXPECT_EQ(dn.bits, 8);
  EXPECT_EQ(dn.width, 4);
  EXPECT_EQ(dn.height, 1);
  // 1234 * 255 / 10000 = 31.467; 20 * 255 / 10000 = 0.51.
  EXPECT_EQ(dn.values, (std::vector<unsigned short>{0, 31, 255, 1}));

  s.bits = 10;  // 3000 * 1023 / 10000 = 306.9
  e.values = {3000.0f, 0.0f, 0.0f, 0.0f};
  EXPECT_EQ(expose(e, s, 1).values[0], 307);
  s.bits = 12;  // 2500 * 4095 / 10000 = 1023.75
  e.values[0] = 2500;
  EXPECT_EQ(expose(e, s, 1).values[0], 1024);
  s.bits = 16;
  s.full_well_e = 20000;  // 12345 * 65535 / 20000 = 40451.479
  e.values[0] = 12345;
  EXPECT_EQ(expose(e, s, 1).values[0], 40451);
}

TEST(Expose, ClipsAtFullWellAndAtTheAdcMaximum) {
  Sensor s;
  s.noise = false;
  s.full_well_e = 10000;
  s.bits = 8;
  ImagePlane e(3, 1);
  e.values = {20000.0f, 3100.0f, 6000.0f};
  // 3100 * 255 / 10000 = 79.05; 6000 * 255 / 10000 = 153.
  s.gain = 1;
  EXPECT_EQ(expose(e, s, 1).values, (std::vector<unsigned short>{255, 79, 153}));
  // Gain 2: 3100 e -> 158.1 DN; 6000 e -> 306 DN, beyond the ADC.
  s.gain = 2;
  EXPECT_EQ(expose(e, s, 1).values, (std::vector<unsigned short>{255, 158, 255}));
  // Gain 0.6: the full well only reaches 0.6 * 255 = 153; 3100 e -> 47.43,
  // 6000 e -> 91.8.
  s.gain = 0.6;
  EXPECT_EQ(expose(e, s, 1).values, (std::vector<unsigned short>{153, 47, 92}));
  s.bits = 16;
  s.gain = 1;
  EXPECT_EQ(expose(e, s, 1).values[0], 65535);
}

TEST(Expose, NaNOrNegativeElectronsCountAsZeroAndInfinitySaturates) {
  ImagePlane e(4, 1);
  e.values = {std::numeric_limits<float>::quiet_NaN(), -5.0f,
              -std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity()};
  Sensor s;
  s.noise = false;
  EXPECT_EQ(expose(e, s, 3).values, (std::vector<unsigned short>{0, 0, 0, 255}));
  // With noise only the read noise remains: a few electrons, a DN or so.
  s.noise = true;
  s.read_noise_e = 4;
  const SensorImage noisy = expose(e, s, 3);
  for (int i = 0; i < 3; ++i) EXPECT_LE(noisy.values[i], 1);
  EXPECT_EQ(noisy.values[3], 255);
}

TEST(Expose, RejectsUnsupportedBitDepthsNamingThem) {
  ImagePlane e(2, 2);
  Sensor s;
  for (int bits : {0, 9, 14, 32}) {
    s.bits = bits;
    EXPECT_NE(message_of([&] { expose(e, s, 1); }).find("sensor.bits = " + std::to_string(bits)),
              std::string::npos);
  }
  s.bits = 8;
  s.full_well_e = 0;
  EXPECT_NE(message_of([&] { expose(e, s, 1); }).find("sensor.full_well_e = 0"), std::string::npos);
}

struct SampleStats {
  double mean = 0, variance = 0;
  std::map<int, int> histogram;
};

SampleStats expose_constant(double electrons, const Sensor& s, std::uint64_t seed, int size = 512) {
  const SensorImage dn = expose(ImagePlane(size, size, static_cast<float>(electrons)), s, seed);
  SampleStats st;
  for (unsigned short v : dn.values) {
    st.mean += v;
    ++st.histogram[v];
  }
  st.mean /= dn.values.size();
  for (unsigned short v : dn.values) st.variance += (v - st.mean) * (v - st.mean);
  st.variance /= dn.values.size() - 1;
  return st;
}

TEST(Expose, NoiseHasPoissonPlusReadNoiseMeanAndVariance) {
  struct Case {
    double electrons, read_noise;
  };
  constexpr double n = 512.0 * 512.0;
  for (const Case c : {Case{5, 0}, Case{50, 4}, Case{5000, 10}, Case{9.5, 0}, Case{10, 0}, Case{12, 0}}) {
    const SampleStats st = expose_constant(c.electrons, counting_sensor(c.read_noise), 42);
    // DN = round(e): rounding a continuous value adds 1/12.
    const double variance = c.electrons + c.read_noise * c.read_noise + (c.read_noise > 0 ? 1.0 / 12 : 0);
    // Five standard errors; the variance's standard error is var sqrt(2 / n)
    // (plus the Poisson excess kurtosis, negligible here).
    EXPECT_NEAR(st.mean, c.electrons, 5 * std::sqrt(variance / n)) << c.electrons;
    EXPECT_NEAR(st.variance, variance, 5 * variance * std::sqrt(2 / n + 1 / (c.electrons * n))) << c.electrons;
  }
}

TEST(Expose, ShotNoiseHistogramIsPoisson) {
  // Chi-square against the Poisson pmf, on both sides of the switch from
  // inversion to transformed rejection (10 electrons).
  for (double mean : {0.3, 5.0, 9.9, 10.0, 14.0, 50.0, 800.0}) {
    const SampleStats st = expose_constant(mean, counting_sensor(0), 9, 400);
    const double n = 400.0 * 400.0;
    std::vector<double> expected, observed;
    double pending_expected = 0, pending_observed = 0;
    const int top = static_cast<int>(mean + 12 * std::sqrt(mean) + 20);
    for (int k = 0; k <= top; ++k) {
      pending_expected += n * std::exp(-mean + k * std::log(mean) - std::lgamma(k + 1.0));
      pending_observed += st.histogram.count(k) ? st.histogram.at(k) : 0;
      if (pending_expected >= 20 || k == top) {
        expected.push_back(pending_expected);
        observed.push_back(pending_observed);
        pending_expected = pending_observed = 0;
      }
    }
    double chi2 = 0;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      chi2 += (observed[i] - expected[i]) * (observed[i] - expected[i]) / expected[i];
    }
    const double dof = static_cast<double>(expected.size()) - 1;
    // Mean dof, standard deviation sqrt(2 dof): 6 sigma.
    EXPECT_LT(chi2, dof + 6 * std::sqrt(2 * dof)) << "mean " << mean << ", " << expected.size() << " bins";
    // And not suspiciously good either (a generator replaying the pmf).
    EXPECT_GT(chi2, dof - 6 * std::sqrt(2 * dof)) << "mean " << mean;
  }
}

TEST(Expose, ReadNoiseIsGaussian) {
  // 20000 e with 3000 e of read noise: the Poisson part adds 0.2% to the
  // variance and nothing visible to the shape, so the sample is N(20000,
  // 3000^2 + 20000) (+1/12 from rounding), far from 0 and the full well.
  const SampleStats st = expose_constant(20000, counting_sensor(3000), 21, 1024);
  const double n = 1024.0 * 1024.0, variance = 3000.0 * 3000.0 + 20000 + 1.0 / 12, sd = std::sqrt(variance);
  EXPECT_NEAR(st.mean, 20000, 5 * sd / std::sqrt(n));
  EXPECT_NEAR(st.variance / variance, 1.0, 5 * std::sqrt(2 / n));
  // Fourth moment 3 sigma^4: standard error sqrt(96 / n) sigma^4.
  double fourth = 0;
  for (const auto& [dn, count] : st.histogram) fourth += count * std::pow((dn - st.mean) / sd, 4);
  EXPECT_NEAR(fourth / n, 3.0, 5 * std::sqrt(96 / n));
  // Chi-square over 100 bins of sd / 10 within +-5 sd, the outer ones open.
  const auto cdf = [&](double dn) { return 0.5 * std::erfc(-(dn - 20000) / sd / std::numbers::sqrt2); };
  std::vector<double> observed(100, 0.0);
  for (const auto& [dn, count] : st.histogram) {
    observed[std::clamp(static_cast<int>(std::floor((dn - 20000) / (sd / 10) + 50)), 0, 99)] += count;
  }
  double chi2 = 0;
  for (int i = 0; i < 100; ++i) {
    // Bin i holds DN values whose (dn - mean) / (sd / 10) + 50 floors to i;
    // DN are integers, so its edges in e are those of the rounding.
    const double lo_edge = 20000 + (i - 50) * sd / 10, hi_edge = lo_edge + sd / 10;
    const double lower = i == 0 ? 0.0 : cdf(std::ceil(lo_edge) - 0.5);
    const double upper = i == 99 ? 1.0 : cdf(std::ceil(hi_edge) - 0.5);
    const double expected = n * (upper - lower);
    chi2 += (observed[i] - expected) * (observed[i] - expected) / expected;
  }
  EXPECT_LT(chi2, 99 + 6 * std::sqrt(2 * 99.0));
  // Beyond 3.44 sigma draws come from the ziggurat's separate tail sampler:
  // P(|z| > 4) = 6.334e-5.
  double beyond_four_sigma = 0;
  for (const auto& [dn, count] : st.histogram) beyond_four_sigma += std::abs(dn - 20000) > 4 * sd ? count : 0;
  EXPECT_NEAR(beyond_four_sigma, n * 6.334e-5, 5 * std::sqrt(n * 6.334e-5));
}

TEST(Expose, SameSeedSameImageOtherSeedOtherImage) {
  ImagePlane e(64, 48);
  for (std::size_t i = 0; i < e.values.size(); ++i) e.values[i] = static_cast<float>(i % 3000);
  Sensor s;
  s.bits = 16;  // 6.5 DN per electron: every draw shows
  const SensorImage a = expose(e, s, 1234), b = expose(e, s, 1234), c = expose(e, s, 1235);
  EXPECT_EQ(a.values, b.values);
  int differing = 0;
  for (std::size_t i = 0; i < a.values.size(); ++i) differing += a.values[i] != c.values[i];
  EXPECT_GT(differing, static_cast<int>(a.values.size()) / 2);
  // A pixel's draws depend only on (seed, pixel): the same pixel in a
  // smaller image gets the same value.
  ImagePlane head(64, 10);
  std::copy(e.values.begin(), e.values.begin() + head.values.size(), head.values.begin());
  const SensorImage h = expose(head, s, 1234);
  EXPECT_TRUE(std::equal(h.values.begin(), h.values.end(), a.values.begin()));
}

TEST(Expose, ResultsDoNotDependOnTheThreadCount) {
  ImagePlane e(97, 61);
  for (std::size_t i = 0; i < e.values.size(); ++i) e.values[i] = static_cast<float>((i * 37) % 5000) * 0.9f;
  Sensor s;
  s.bits = 16;
  const SensorImage parallel = expose(e, s, 77);
  const ImagePlane blurred = blur(e, {0.8, 2.5});
  const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  EXPECT_EQ(expose(e, s, 77).values, parallel.values);
  EXPECT_EQ(blur(e, {0.8, 2.5}).values, blurred.values);
}

TEST(Expose, FarBeyondFullWellSaturatesEvenWithNoise) {
  Sensor s;
  s.full_well_e = 10000;
  ImagePlane e(8, 8, 1e12f);
  for (unsigned short dn : expose(e, s, 5).values) EXPECT_EQ(dn, 255);
}

// ---------------------------------------------------------------------------
// Counter-based random numbers.

TEST(Uniform01, IsAPureFunctionInTheUnitInterval) {
  EXPECT_EQ(uniform01(1, 2, 3), uniform01(1, 2, 3));
  EXPECT_NE(uniform01(1, 2, 3), uniform01(1, 2, 4));
  EXPECT_NE(uniform01(1, 2, 3), uniform01(1, 3, 3));
  EXPECT_NE(uniform01(1, 2, 3), uniform01(2, 2, 3));
  // Moments of U(0, 1), and no correlation between neighbouring indices
  // (the renderer draws u and v of a jitter from 2 i and 2 i + 1).
  constexpr int n = 200000;
  double sum = 0, sum2 = 0, lag = 0, previous = uniform01(9, 1, 0);
  for (int i = 0; i < n; ++i) {
    const double x = uniform01(9, 1, static_cast<std::uint64_t>(i));
    ASSERT_GE(x, 0.0);
    ASSERT_LT(x, 1.0);
    sum += x;
    sum2 += x * x;
    lag += (x - 0.5) * (previous - 0.5);
    previous = x;
  }
  EXPECT_NEAR(sum / n, 0.5, 5 * std::sqrt(1.0 / 12 / n));
  EXPECT_NEAR(sum2 / n - (sum / n) * (sum / n), 1.0 / 12, 0.002);
  EXPECT_NEAR(lag / n / (1.0 / 12), 0.0, 5 / std::sqrt(n));
}

}  // namespace
}  // namespace purkinje::renderer
