// The blob glint detector on synthetic images whose glint centres are known
// in closed form (a Gaussian spot integrated over each pixel). The
// renderer's images are in rendered_glints_test.cpp.

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "cv_view.h"
#include "purkinje/trackers/glints.h"

namespace purkinje::trackers {
namespace {

struct Spot {
  double u, v;         // centre
  double energy_dn;    // summed over the pixels
  double sigma_px;
};

// The spots' brightness on pixel (x, y), 8-bit DN, unclipped: each a
// Gaussian integrated over the pixel (pixel centres at integers).
double spots_dn(int x, int y, const std::vector<Spot>& spots) {
  const auto mass = [](double lo, double hi, double centre, double sigma) {
    return 0.5 * (std::erf((hi - centre) / (sigma * std::sqrt(2.0))) - std::erf((lo - centre) / (sigma * std::sqrt(2.0))));
  };
  double sum = 0;
  for (const Spot& s : spots) {
    sum += s.energy_dn * mass(x - 0.5, x + 0.5, s.u, s.sigma_px) * mass(y - 0.5, y + 0.5, s.v, s.sigma_px);
  }
  return sum;
}

// Background `level + slope * u`, plus spots integrated over each pixel
// (pixel centres at integers), rounded and clipped as a sensor's ADC does,
// plus Gaussian noise of `noise_dn`.
cv::Mat synthetic(int width, int height, const std::vector<Spot>& spots, double level, double slope,
                  double noise_dn = 0, int depth = CV_8U, unsigned seed = 1, double step_u = 1e9,
                  double step_dn = 0) {
  const double top = depth == CV_8U ? 255 : 65535;
  const double scale = top / 255;  // spots and background are given in 8-bit numbers
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, noise_dn);
  cv::Mat image(height, width, depth);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      double value = level + slope * x + (x >= step_u ? step_dn : 0) + spots_dn(x, y, spots);  // a step: the pupil's edge
      if (noise_dn > 0) value += noise(rng);
      const double dn = std::clamp(std::round(value * scale), 0.0, top);
      if (depth == CV_8U) {
        image.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(dn);
      } else {
        image.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(dn);
      }
    }
  }
  return image;
}

// The centroid of a pixel-integrated Gaussian of sigma >= 0.7 px lies within
// 1e-4 px of its centre (the sampling's periodic bias is of order
// exp(-2 pi^2 sigma^2) / pi); rounding to whole DN and the centroid's disc,
// which leaves the farthest tails out, add about a hundredth (measured:
// 0.011 px at worst).
TEST(BlobGlintDetector, FindsSubPixelCentresOfSpotsOnASlopedBackground) {
  const BlobGlintDetector detector;
  double worst = 0;
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) {
      const Spot spot{30 + 0.2 * i, 20 + 0.2 * j + 0.1, 600, 0.7};
      const std::vector<Glint> glints = detector.detect(view(synthetic(64, 48, {spot}, 40, 0.5)));
      ASSERT_EQ(glints.size(), 1u) << i << ", " << j;
      worst = std::max(worst, std::hypot(glints[0].centre.u - spot.u, glints[0].centre.v - spot.v));
      EXPECT_FALSE(glints[0].saturated);
      EXPECT_NEAR(glints[0].energy_dn, 600, 30);
    }
  }
  EXPECT_LT(worst, 0.02);
  RecordProperty("worst_px", std::to_string(worst));
}

TEST(BlobGlintDetector, ASaturatedSpotKeepsItsCentre) {
  const BlobGlintDetector detector;
  // Peak 6000 / (2 pi 1.2^2) = 660 DN: clipped at 255 over a disc of pixels.
  const Spot spot{31.37, 22.81, 6000, 1.2};
  const std::vector<Glint> glints = detector.detect(view(synthetic(64, 48, {spot}, 60, 0)));
  ASSERT_EQ(glints.size(), 1u);
  EXPECT_TRUE(glints[0].saturated);
  EXPECT_NEAR(glints[0].centre.u, spot.u, 0.03);
  EXPECT_NEAR(glints[0].centre.v, spot.v, 0.03);
}

// A glint on the pupil's edge: dark on one side, the iris 90 DN brighter on
// the other. Clipped at full scale, the plateau reaches farther on the
// bright side; the centre comes from a fit of the spot to the unclipped
// pixels above the background, not from the plateau's centroid.
TEST(BlobGlintDetector, ASaturatedSpotOnAnEdgeKeepsItsCentre) {
  const BlobGlintDetector detector;
  double worst = 0;
  for (const double du : {-0.6, -0.3, 0.0, 0.3, 0.6}) {
    const Spot spot{31.2 + du, 22.4, 3000, 0.8};
    const std::vector<Glint> glints = detector.detect(view(synthetic(64, 48, {spot}, 15, 0, 0, CV_8U, 1, 31.5, 90)));
    ASSERT_EQ(glints.size(), 1u) << du;
    EXPECT_TRUE(glints[0].saturated);
    worst = std::max(worst, std::hypot(glints[0].centre.u - spot.u, glints[0].centre.v - spot.v));
  }
  EXPECT_LT(worst, 0.05);
  RecordProperty("worst_on_edge_px", std::to_string(worst));
}

// A glint on the pupil's edge whose bright side is textured, as an iris
// is: each pixel there draws its own level, 30 +- 8 DN. The background
// under the spot is unseen; a background from the texture's darkest
// pixels (the top-hat's opening) reads the iris side's flank high and
// pulls the centre toward it by about 0.3 px. The spot's pixel-integrated
// Gaussian is the renderer's (sigma 0.5 px, saturated over two to four
// pixels). The centre must stay within 0.1 px, and within 4 of its
// reported standard deviations.
TEST(BlobGlintDetector, ASaturatedSpotOnATexturedEdgeIsWithinItsReportedDeviation) {
  const BlobGlintDetector detector;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> texture(-8, 8);
  double worst = 0, worst_normalized = 0;
  int count = 0;
  for (const double du : {-0.4, -0.2, 0.0, 0.2, 0.4}) {
    for (const double dv : {-0.3, 0.0, 0.3}) {
      const Spot spot{32 + du, 24 + dv, 1500, 0.5};
      cv::Mat image = synthetic(64, 48, {spot}, 0, 0, 0, CV_8U, 1, 32.5, 0);
      for (int y = 0; y < image.rows; ++y) {
        for (int x = 33; x < image.cols; ++x) {  // the iris: right of the edge at u = 32.5
          image.at<std::uint8_t>(y, x) = cv::saturate_cast<std::uint8_t>(image.at<std::uint8_t>(y, x) + 30 + texture(rng));
        }
      }
      const std::vector<Glint> glints = detector.detect(view(image));
      ASSERT_EQ(glints.size(), 1u) << du << ", " << dv;
      ASSERT_TRUE(glints[0].saturated);
      const Glint& g = glints[0];
      ASSERT_GT(g.centre_sd_u_px, 0);
      ASSERT_GT(g.centre_sd_v_px, 0);
      worst = std::max(worst, std::hypot(g.centre.u - spot.u, g.centre.v - spot.v));
      worst_normalized = std::max({worst_normalized, std::abs(g.centre.u - spot.u) / g.centre_sd_u_px,
                                   std::abs(g.centre.v - spot.v) / g.centre_sd_v_px});
      ++count;
    }
  }
  EXPECT_EQ(count, 15);
  EXPECT_LT(worst, 0.1);
  EXPECT_LT(worst_normalized, 4);
  RecordProperty("worst_px", std::to_string(worst));
  RecordProperty("worst_in_sd", std::to_string(worst_normalized));
}

// Under pixel noise alone, the reported standard deviation of a saturated
// spot's centre is its scatter over many draws. The noise is additive (not
// shot noise): the detector is told of a sensor with 2 DN of read noise
// and a million electrons per DN, whose shot noise is negligible.
TEST(BlobGlintDetector, ASaturatedSpotsReportedDeviationIsItsScatterUnderNoise) {
  BlobGlintSettings settings;
  settings.full_scale_e = 255e6;
  settings.read_noise_e = 2e6;
  const BlobGlintDetector detector(settings);
  const Spot spot{40.3, 29.6, 1200, 0.6};
  const int draws = 300;
  double sum_u = 0, sum_v = 0, sum_uu = 0, sum_vv = 0, reported_u = 0, reported_v = 0;
  for (int seed = 1; seed <= draws; ++seed) {
    const std::vector<Glint> glints =
        detector.detect(view(synthetic(80, 60, {spot}, 60, 0, 2.0, CV_8U, static_cast<unsigned>(seed))));
    ASSERT_EQ(glints.size(), 1u) << seed;
    ASSERT_TRUE(glints[0].saturated) << seed;
    const double du = glints[0].centre.u - spot.u, dv = glints[0].centre.v - spot.v;
    sum_u += du, sum_v += dv, sum_uu += du * du, sum_vv += dv * dv;
    reported_u += glints[0].centre_sd_u_px * glints[0].centre_sd_u_px;
    reported_v += glints[0].centre_sd_v_px * glints[0].centre_sd_v_px;
  }
  const double sd_u = std::sqrt(sum_uu / draws - (sum_u / draws) * (sum_u / draws));
  const double sd_v = std::sqrt(sum_vv / draws - (sum_v / draws) * (sum_v / draws));
  const double said_u = std::sqrt(reported_u / draws), said_v = std::sqrt(reported_v / draws);
  // 300 draws measure a standard deviation to about 4% (1 / sqrt(2 x 300)).
  EXPECT_NEAR(said_u / sd_u, 1, 0.25) << sd_u << " measured, " << said_u << " reported";
  EXPECT_NEAR(said_v / sd_v, 1, 0.25) << sd_v << " measured, " << said_v << " reported";
  EXPECT_LT(std::abs(sum_u / draws), 3 * sd_u / std::sqrt(draws) + 0.005);  // no bias beyond the rounding's
  EXPECT_LT(std::abs(sum_v / draws), 3 * sd_v / std::sqrt(draws) + 0.005);
  RecordProperty("scatter_px", std::to_string(sd_u) + ", " + std::to_string(sd_v));
  RecordProperty("reported_px", std::to_string(said_u) + ", " + std::to_string(said_v));
}

// Under a sensor's own noise (shot noise, whose variance grows with the
// pixel's value, and read noise), told to the detector, the reported
// standard deviation is the scatter over many draws: the bundled sensors'
// 10000 e- full well on 8 bits (39 electrons per DN) and 4 e- read noise,
// drawn as the renderer draws them (Poisson electrons, Gaussian read
// noise, rounded and clipped).
TEST(BlobGlintDetector, ASaturatedSpotsReportedDeviationIsItsScatterUnderShotNoise) {
  const BlobGlintSettings settings;  // the defaults are that sensor
  const double electrons_per_dn = settings.full_scale_e / 255;
  const BlobGlintDetector detector(settings);
  const Spot spot{40.3, 29.6, 1200, 0.6};
  std::mt19937 rng(7);
  std::normal_distribution<double> read(0, settings.read_noise_e);
  const int draws = 300;
  std::vector<double> du, dv;
  double reported_u = 0, reported_v = 0;
  for (int draw = 0; draw < draws; ++draw) {
    cv::Mat image(60, 80, CV_8U);
    for (int y = 0; y < image.rows; ++y) {
      for (int x = 0; x < image.cols; ++x) {
        // Electrons beyond the full well are lost: a clipped pixel stays clipped.
        std::poisson_distribution<int> shot((30 + spots_dn(x, y, {spot})) * electrons_per_dn);
        const double dn = std::round((shot(rng) + read(rng)) / electrons_per_dn);
        image.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(std::clamp(dn, 0.0, 255.0));
      }
    }
    const std::vector<Glint> glints = detector.detect(view(image));
    ASSERT_EQ(glints.size(), 1u) << draw;
    ASSERT_TRUE(glints[0].saturated) << draw;
    du.push_back(glints[0].centre.u - spot.u);
    dv.push_back(glints[0].centre.v - spot.v);
    reported_u += glints[0].centre_sd_u_px * glints[0].centre_sd_u_px;
    reported_v += glints[0].centre_sd_v_px * glints[0].centre_sd_v_px;
  }
  const auto sample_sd = [](const std::vector<double>& x) {
    double sum = 0, squares = 0;
    for (const double e : x) sum += e, squares += e * e;
    const double n = static_cast<double>(x.size());
    return std::sqrt((squares - sum * sum / n) / (n - 1));
  };
  const double said_u = std::sqrt(reported_u / draws), said_v = std::sqrt(reported_v / draws);
  // 300 draws measure a standard deviation to about 4%. Averaging the
  // near background's fit's variance in, as before, said 2.4 to 2.6 times
  // the scatter here.
  EXPECT_NEAR(said_u / sample_sd(du), 1, 0.25) << sample_sd(du) << " measured, " << said_u << " reported";
  EXPECT_NEAR(said_v / sample_sd(dv), 1, 0.25) << sample_sd(dv) << " measured, " << said_v << " reported";
  RecordProperty("scatter_px", std::to_string(sample_sd(du)) + ", " + std::to_string(sample_sd(dv)));
  RecordProperty("reported_px", std::to_string(said_u) + ", " + std::to_string(said_v));
}

// A told width (the camera's point spread) serves as well as the frame's
// own estimate, and an unsaturated glint's centroid reports no deviation.
TEST(BlobGlintDetector, AToldSpotWidthKeepsTheCentreAndAnUnsaturatedGlintReportsNoDeviation) {
  BlobGlintSettings told;
  told.spot_sigma_px = 0.6;
  const Spot bright{30.27, 21.64, 1500, 0.6}, faint{50.4, 30.2, 400, 0.8};
  for (const BlobGlintSettings& settings : {BlobGlintSettings{}, told}) {
    const std::vector<Glint> glints =
        BlobGlintDetector(settings).detect(view(synthetic(72, 48, {bright, faint}, 40, 0, 1.0, CV_8U, 3)));
    ASSERT_EQ(glints.size(), 2u);
    EXPECT_TRUE(glints[0].saturated);
    EXPECT_NEAR(glints[0].centre.u, bright.u, 0.03);
    EXPECT_NEAR(glints[0].centre.v, bright.v, 0.03);
    EXPECT_FALSE(glints[1].saturated);
    EXPECT_EQ(glints[1].centre_sd_u_px, 0);
    EXPECT_EQ(glints[1].centre_sd_v_px, 0);
  }
}

TEST(BlobGlintDetector, SixteenBitImagesGiveTheSameCentres) {
  const BlobGlintDetector detector;
  const Spot spot{17.33, 25.71, 500, 0.8};
  const std::vector<Glint> eight = detector.detect(view(synthetic(40, 40, {spot}, 50, 0, 0, CV_8U)));
  const std::vector<Glint> sixteen = detector.detect(view(synthetic(40, 40, {spot}, 50, 0, 0, CV_16U)));
  ASSERT_EQ(eight.size(), 1u);
  ASSERT_EQ(sixteen.size(), 1u);
  // Both near the true centre and near each other.
  EXPECT_NEAR(sixteen[0].centre.u, spot.u, 0.02);
  EXPECT_NEAR(sixteen[0].centre.v, spot.v, 0.02);
  EXPECT_NEAR(eight[0].centre.u, sixteen[0].centre.u, 0.02);
  EXPECT_NEAR(eight[0].centre.v, sixteen[0].centre.v, 0.02);
}

TEST(BlobGlintDetector, NoiseAloneGivesNoGlintsAndNoisySpotsStayClose) {
  const BlobGlintDetector detector;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    EXPECT_TRUE(detector.detect(view(synthetic(80, 60, {}, 120, 0.3, 3.0, CV_8U, seed))).empty()) << seed;
  }
  double worst = 0;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const Spot spot{40.3, 29.6, 800, 0.8};
    const std::vector<Glint> glints = detector.detect(view(synthetic(80, 60, {spot}, 120, 0.3, 3.0, CV_8U, seed)));
    ASSERT_EQ(glints.size(), 1u) << seed;
    worst = std::max(worst, std::hypot(glints[0].centre.u - spot.u, glints[0].centre.v - spot.v));
  }
  // Noise of 3 DN on about 20 weighed pixels against 800 DN of signal.
  EXPECT_LT(worst, 0.1);
  RecordProperty("worst_noisy_px", std::to_string(worst));
}

TEST(BlobGlintDetector, SeparatesNearbyGlintsAndOrdersThemByEnergy) {
  const BlobGlintDetector detector;
  const std::vector<Spot> spots{{20.2, 20.4, 400, 0.7}, {25.6, 20.1, 900, 0.7}, {22.9, 25.3, 600, 0.7}};
  const std::vector<Glint> glints = detector.detect(view(synthetic(48, 48, spots, 30, 0)));
  ASSERT_EQ(glints.size(), 3u);
  EXPECT_NEAR(glints[0].centre.u, 25.6, 0.05);  // the brightest first
  EXPECT_NEAR(glints[1].centre.u, 22.9, 0.05);
  EXPECT_NEAR(glints[2].centre.u, 20.2, 0.05);
}

// A bright disc 31 px across: the square opening cannot reach into its
// rim, so the top-hat leaves slivers there, bright but inside the disc's
// brightness; they do not stand out from all around them.
TEST(BlobGlintDetector, ABrightRegionLargerThanAnyGlintIsNotOne) {
  const BlobGlintDetector detector;
  cv::Mat image(60, 60, CV_8U, cv::Scalar(40));
  for (int y = 0; y < 60; ++y) {
    for (int x = 0; x < 60; ++x) {
      if (std::hypot(x - 30, y - 30) <= 15) image.at<std::uint8_t>(y, x) = 250;
    }
  }
  EXPECT_TRUE(detector.detect(view(image)).empty());
}

TEST(BlobGlintDetector, GlintsAtTheImagesEdgeAreFoundWithoutReadingOutside) {
  const BlobGlintDetector detector;
  const Spot corner{0.4, 0.3, 600, 0.7};
  const std::vector<Glint> glints = detector.detect(view(synthetic(32, 32, {corner}, 40, 0)));
  ASSERT_EQ(glints.size(), 1u);
  // Half the spot lies outside the image: the centroid of what remains
  // moves inward, but stays on the corner pixel.
  EXPECT_LT(std::hypot(glints[0].centre.u, glints[0].centre.v), 1.0);
}

// A hot pixel is one bright pixel: no optics put a point's light there
// alone. Its neighbours hold nothing, so it is dropped; a narrow spot
// (sigma 0.3 px, centred on a pixel: its four neighbours hold 0.21 of
// the peak; the rule's bar is 0.1) is kept, with hot pixels beside it.
TEST(BlobGlintDetector, AHotPixelIsNoGlintButANarrowSpotIs) {
  cv::Mat image = synthetic(48, 48, {{30, 24, 250, 0.3}}, 40, 0);
  image.at<std::uint8_t>(12, 10) = 250;  // a hot pixel, saturated
  image.at<std::uint8_t>(36, 14) = 140;  // and a dimmer one
  const std::vector<Glint> glints = BlobGlintDetector().detect(view(image));
  ASSERT_EQ(glints.size(), 1u);
  EXPECT_NEAR(glints[0].centre.u, 30, 0.05);
  EXPECT_NEAR(glints[0].centre.v, 24, 0.05);
  // Without the rule, the hot pixels are glints too.
  BlobGlintSettings all;
  all.min_neighbour_share = 0;
  EXPECT_EQ(BlobGlintDetector(all).detect(view(image)).size(), 3u);
}

// An unsaturated spot on the iris side of the pupil's edge (a 90 DN step
// between it and its pupil-side neighbour): the edge is no reason to
// drop it, since a neighbour below the background counts as none. And a
// hot pixel joined to a glint's blob does not drop the glint.
TEST(BlobGlintDetector, TheLonePixelRuleKeepsSpotsOnTheEdgeAndBesideHotPixels) {
  for (const double sigma : {0.5, 0.7}) {
    const Spot spot{32, 24, 150, sigma};
    const std::vector<Glint> glints =
        BlobGlintDetector().detect(view(synthetic(64, 48, {spot}, 15, 0, 0, CV_8U, 1, 31.5, 90)));
    ASSERT_EQ(glints.size(), 1u) << sigma;
    EXPECT_NEAR(glints[0].centre.u, 32, 0.3) << sigma;
  }
  cv::Mat image = synthetic(48, 48, {{24, 24, 600, 0.5}}, 40, 0);
  image.at<std::uint8_t>(22, 26) = 255;  // diagonal to the spot's corner, saturated
  const std::vector<Glint> glints = BlobGlintDetector().detect(view(image));
  ASSERT_EQ(glints.size(), 1u);
  EXPECT_NEAR(glints[0].centre.v, 24, 0.5);
}

TEST(BlobGlintDetector, RejectsImagesItCannotReadNamingTheRule) {
  const BlobGlintDetector detector;
  const std::vector<std::uint8_t> pixels(100, 0);
  EXPECT_THROW(detector.detect(GreyView{}), std::invalid_argument);
  const auto message = [&](const GreyView& v) {
    try {
      detector.detect(v);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message({pixels.data(), 10, 10, 10, 3, 8}).find("bytes_per_pixel = 3"), std::string::npos);
  EXPECT_NE(message({pixels.data(), 10, 10, 10, 1, 12}).find("bits = 12"), std::string::npos);
  EXPECT_NE(message({pixels.data(), 10, 10, 5, 1, 8}).find("row_bytes = 5"), std::string::npos);
  EXPECT_NE(message({pixels.data(), 0, 10, 10, 1, 8}).find("empty"), std::string::npos);
  const std::vector<std::uint16_t> wide(100, 0);
  EXPECT_NE(message({wide.data(), 4, 10, 9, 2, 16}).find("aligned"), std::string::npos);  // odd row bytes
  EXPECT_THROW(grey_view(std::span<const std::uint8_t>(pixels), 20, 10), std::invalid_argument);  // too few pixels
}

TEST(BlobGlintDetector, RejectsSettingsOutOfRangeNamingThem) {
  BlobGlintSettings s;
  s.threshold = 0;
  try {
    BlobGlintDetector{s};
    FAIL() << "threshold 0 was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("threshold"), std::string::npos) << e.what();
  }
  s = {};
  s.min_area_px = 10;
  s.max_area_px = 5;
  EXPECT_THROW(BlobGlintDetector{s}, std::invalid_argument);
  s = {};
  s.background_radius_px = 0;
  EXPECT_THROW(BlobGlintDetector{s}, std::invalid_argument);
  for (const double share : {-0.1, 4.5, std::nan("")}) {
    s = {};
    s.min_neighbour_share = share;
    EXPECT_THROW(BlobGlintDetector{s}, std::invalid_argument) << share;
  }
  // The settings' error, or why there is none to check.
  const auto refusal = [](const BlobGlintSettings& settings) {
    try {
      BlobGlintDetector{settings};
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  for (const double sigma : {-1.0, 0.05, 11.0, std::nan("")}) {
    s = {};
    s.spot_sigma_px = sigma;
    EXPECT_NE(refusal(s).find("spot_sigma_px"), std::string::npos) << sigma << ": " << refusal(s);
  }
  for (const double electrons : {0.0, -1.0, HUGE_VAL, std::nan("")}) {
    s = {};
    s.full_scale_e = electrons;
    EXPECT_NE(refusal(s).find("full_scale_e"), std::string::npos) << electrons << ": " << refusal(s);
  }
  for (const double electrons : {-1.0, HUGE_VAL, std::nan("")}) {
    s = {};
    s.read_noise_e = electrons;
    EXPECT_NE(refusal(s).find("read_noise_e"), std::string::npos) << electrons << ": " << refusal(s);
  }
  s = {};
  s.read_noise_e = 0;  // a noiseless read is allowed: the rounding remains
  EXPECT_EQ(refusal(s), "(accepted)");
}

}  // namespace
}  // namespace purkinje::trackers
