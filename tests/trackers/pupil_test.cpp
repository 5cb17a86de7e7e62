// The starburst pupil detector on synthetic eyes whose pupil outline is
// known exactly: a dark ellipse drawn with its pixels' coverage (8 x 8
// samples each), in a textured iris, blurred by a symmetric point spread,
// which moves the centre of neither the ellipse nor its edges' half-level
// crossings. The renderer's images are in rendered_pupil_test.cpp.

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "cv_view.h"
#include "purkinje/trackers/glints.h"
#include "purkinje/trackers/pupil.h"

namespace purkinje::trackers {
namespace {

constexpr double kPi = std::numbers::pi;

struct Spot {
  double u, v, peak_dn;  // a Gaussian of sigma 1 px
};

struct SyntheticEye {
  Ellipse pupil{{100.3, 90.6}, 15, 15, 0};
  double pupil_dn = 12, iris_dn = 90, skin_dn = 160;
  double iris_radius_px = 40;  // about the pupil's centre
  double spokes_dn = 8;        // the iris's radial texture
  double blur_px = 0.8;
  double noise_dn = 0;
  std::optional<double> lid_v;       // skin above this row (an upper lid)
  std::optional<Ellipse> shadow;     // a dark region as dark as the pupil (a corner's shadow)
  std::vector<Spot> glints;
  int width = 200, height = 180;
};

bool inside(const Ellipse& e, double u, double v) {
  const double c = std::cos(e.angle_rad), s = std::sin(e.angle_rad);
  const double x = c * (u - e.center.u) + s * (v - e.center.v), y = -s * (u - e.center.u) + c * (v - e.center.v);
  return (x * x) / (e.semi_axis_1_px * e.semi_axis_1_px) + (y * y) / (e.semi_axis_2_px * e.semi_axis_2_px) <= 1;
}

double radiance(const SyntheticEye& eye, double u, double v) {
  if (eye.lid_v && v < *eye.lid_v) return eye.skin_dn;
  if (inside(eye.pupil, u, v)) return eye.pupil_dn;
  if (eye.shadow && inside(*eye.shadow, u, v)) return eye.pupil_dn;
  const double du = u - eye.pupil.center.u, dv = v - eye.pupil.center.v;
  if (std::hypot(du, dv) < eye.iris_radius_px) return eye.iris_dn + eye.spokes_dn * std::cos(24 * std::atan2(dv, du));
  return eye.skin_dn;
}

// In 8-bit numbers; `scale` takes them to the image's (4 for 10 bits in 16).
cv::Mat draw(const SyntheticEye& eye, int depth = CV_8U, double scale = 1, unsigned seed = 1) {
  cv::Mat linear(eye.height, eye.width, CV_64F);
  constexpr int kSub = 8;
  for (int y = 0; y < eye.height; ++y) {
    for (int x = 0; x < eye.width; ++x) {
      double sum = 0;
      for (int j = 0; j < kSub; ++j) {
        for (int i = 0; i < kSub; ++i) sum += radiance(eye, x - 0.5 + (i + 0.5) / kSub, y - 0.5 + (j + 0.5) / kSub);
      }
      linear.at<double>(y, x) = sum / (kSub * kSub);
    }
  }
  if (eye.blur_px > 0) cv::GaussianBlur(linear, linear, {0, 0}, eye.blur_px, eye.blur_px, cv::BORDER_REPLICATE);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, eye.noise_dn);
  const double top = depth == CV_8U ? 255 : 65535;
  cv::Mat image(eye.height, eye.width, depth);
  for (int y = 0; y < eye.height; ++y) {
    for (int x = 0; x < eye.width; ++x) {
      double value = linear.at<double>(y, x);
      for (const Spot& g : eye.glints) value += g.peak_dn * std::exp(-0.5 * (std::pow(x - g.u, 2) + std::pow(y - g.v, 2)));
      if (eye.noise_dn > 0) value += noise(rng);
      const double dn = std::clamp(std::round(value * scale), 0.0, std::min(top, 255 * scale));
      if (depth == CV_8U) {
        image.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(dn);
      } else {
        image.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(dn);
      }
    }
  }
  return image;
}

double centre_error(const PupilDetection& d, const Ellipse& truth) {
  return std::hypot(d.ellipse.center.u - truth.center.u, d.ellipse.center.v - truth.center.v);
}

// Orientations of an axis are equal modulo pi.
double angle_error(double a, double b) { return std::abs(std::remainder(a - b, kPi)); }

// Blur moves each edge's half-level crossing inward by about sigma^2 / 2R
// (0.02 px here) and leaves the centre; sampling and the fit add a few
// thousandths (measured: 0.006 px at worst).
TEST(StarburstPupilDetector, FindsAnEllipticPupilToAHundredthOfAPixel) {
  const StarburstPupilDetector detector;
  double worst = 0;
  for (const double ratio : {1.0, 0.75, 0.5}) {
    for (const double angle : {0.0, 0.5, -1.2}) {
      for (int k = 0; k < 3; ++k) {
        SyntheticEye eye;
        eye.pupil = {{100.0 + 0.37 * k, 90.0 + 0.21 * k}, 16, 16 * ratio, angle};
        const std::optional<PupilDetection> found = detector.detect(view(draw(eye)), {});
        ASSERT_TRUE(found) << ratio << ", " << angle << ", " << k;
        worst = std::max(worst, centre_error(*found, eye.pupil));
        EXPECT_NEAR(found->ellipse.semi_axis_1_px, 16, 0.1);
        EXPECT_NEAR(found->ellipse.semi_axis_2_px, 16 * ratio, 0.1);
        if (ratio < 1) {
          EXPECT_LT(angle_error(found->ellipse.angle_rad, angle), 0.02);
        }
        EXPECT_GT(found->confidence, 0.95);
      }
    }
  }
  EXPECT_LT(worst, 0.02);
  ::testing::Test::RecordProperty("worst_px", std::to_string(worst));
}

TEST(StarburstPupilDetector, FindsSmallAndLargePupils) {
  const StarburstPupilDetector detector;
  for (const double radius : {3.5, 6.0, 60.0}) {
    SyntheticEye eye;
    eye.pupil = {{110.4, 109.7}, radius, radius, 0};
    eye.iris_radius_px = std::max(20.0, 1.4 * radius);
    eye.width = eye.height = 220;
    const std::optional<PupilDetection> found = detector.detect(view(draw(eye)), {});
    ASSERT_TRUE(found) << radius;
    EXPECT_LT(centre_error(*found, eye.pupil), 0.05) << radius;
    EXPECT_NEAR(found->ellipse.semi_axis_1_px, radius, 0.15) << radius;
    EXPECT_NEAR(found->ellipse.semi_axis_2_px, radius, 0.15) << radius;
  }
}

// Under 3 DN of noise (the edge is 78 DN high) the edge points scatter by
// about 0.1 px along their rays; their fit's centre by a few hundredths.
TEST(StarburstPupilDetector, ToleratesSensorNoise) {
  const StarburstPupilDetector detector;
  double worst = 0;
  for (unsigned seed = 1; seed <= 10; ++seed) {
    SyntheticEye eye;
    eye.pupil = {{100.2, 90.7}, 14, 10, 0.3};
    eye.noise_dn = 3;
    const std::optional<PupilDetection> found = detector.detect(view(draw(eye, CV_8U, 1, seed)), {});
    ASSERT_TRUE(found) << seed;
    worst = std::max(worst, centre_error(*found, eye.pupil));
  }
  EXPECT_LT(worst, 0.1);
  ::testing::Test::RecordProperty("worst_px", std::to_string(worst));
}

// Saturated glints on the pupil's edge: told by the glint detector, their
// surroundings are left out; untold, RANSAC leaves their edges out.
TEST(StarburstPupilDetector, GlintsOnThePupilsEdgeDoNotMoveIt) {
  SyntheticEye eye;
  eye.pupil = {{100.3, 90.6}, 15, 13, 0.2};
  for (int k = 0; k < 4; ++k) {
    const double t = kPi / 4 + k * kPi / 2;
    eye.glints.push_back({eye.pupil.center.u + 15 * std::cos(t), eye.pupil.center.v + 13 * std::sin(t), 400});
  }
  eye.glints.push_back({eye.pupil.center.u + 3, eye.pupil.center.v - 2, 400});  // and one inside
  const cv::Mat image = draw(eye);
  const std::vector<Glint> glints = BlobGlintDetector().detect(view(image));
  ASSERT_EQ(glints.size(), 5u);
  const StarburstPupilDetector detector;
  const std::optional<PupilDetection> told = detector.detect(view(image), glints);
  ASSERT_TRUE(told);
  EXPECT_LT(centre_error(*told, eye.pupil), 0.05);
  EXPECT_NEAR(told->ellipse.semi_axis_1_px, 15, 0.15);
  const std::optional<PupilDetection> untold = detector.detect(view(image), {});
  ASSERT_TRUE(untold);
  EXPECT_LT(centre_error(*untold, eye.pupil), 0.1);
}

// A lid over the pupil's top third: its edge is a rise to far brighter
// than the iris, and left out; the confidence tells how much of the
// outline is seen. Where the lid meets the pupil, the level beyond an edge
// point takes in some skin, which moves the point outward a little
// (measured: the centre 0.10 px toward the lid).
TEST(StarburstPupilDetector, AnEyelidOverThePupilLeavesItsCentreAndLowersTheConfidence) {
  SyntheticEye eye;
  eye.pupil = {{100.3, 90.6}, 16, 14, 0};
  eye.lid_v = eye.pupil.center.v - 6;  // hides 36% of the outline (by angle seen from the centre)
  const std::optional<PupilDetection> found = StarburstPupilDetector().detect(view(draw(eye)), {});
  ASSERT_TRUE(found);
  EXPECT_LT(centre_error(*found, eye.pupil), 0.15);
  EXPECT_NEAR(found->ellipse.semi_axis_1_px, 16, 0.2);
  EXPECT_GT(found->confidence, 0.5);
  EXPECT_LT(found->confidence, 0.75);
  // Half covered: the lid's edge runs through the centre.
  eye.lid_v = eye.pupil.center.v;
  const std::optional<PupilDetection> half = StarburstPupilDetector().detect(view(draw(eye)), {});
  ASSERT_TRUE(half);
  EXPECT_LT(centre_error(*half, eye.pupil), 0.15);
  EXPECT_NEAR(half->confidence, 0.5, 0.07);
}

// A shadow as dark as the pupil in the eye's corner, narrow but whole,
// beside a wide pupil a lid covers a third of: the shadow's outline is the
// better supported (confidence 1 against 0.62), the pupil is the wider
// (score 0.62 x 4 against 1 x 2.14).
TEST(StarburstPupilDetector, ANarrowShadowAsDarkAsThePupilIsNotThePupil) {
  SyntheticEye eye;
  eye.pupil = {{80.3, 100.6}, 16, 16, 0};
  eye.lid_v = eye.pupil.center.v - 6;
  eye.shadow = Ellipse{{160, 130}, 18, 4.6, 1.2};
  const StarburstPupilDetector detector;
  const std::optional<PupilDetection> found = detector.detect(view(draw(eye)), {});
  ASSERT_TRUE(found);
  EXPECT_LT(centre_error(*found, eye.pupil), 0.15);
  EXPECT_LT(found->confidence, 0.75);
  // Alone, the shadow is found, and wholly outlined: it is a candidate.
  eye.pupil.center = {-100, -100};
  const std::optional<PupilDetection> shadow = detector.detect(view(draw(eye)), {});
  ASSERT_TRUE(shadow);
  EXPECT_LT(centre_error(*shadow, *eye.shadow), 0.15);
  EXPECT_GT(shadow->confidence, 0.95);
}

// Something darker than the pupil that touches the image's border (a
// headset lens's black rim, a vignetted corner) hides no pupil.
TEST(StarburstPupilDetector, ADarkerRimAtTheBorderDoesNotHideThePupil) {
  SyntheticEye eye;
  eye.pupil = {{100.3, 90.6}, 12, 11, 0.4};
  eye.pupil_dn = 20;
  cv::Mat image = draw(eye);
  image.rowRange(image.rows - 4, image.rows).setTo(0);
  image.colRange(0, 6).setTo(2);
  const std::optional<PupilDetection> found = StarburstPupilDetector().detect(view(image), {});
  ASSERT_TRUE(found);
  EXPECT_LT(centre_error(*found, eye.pupil), 0.05);
}

TEST(StarburstPupilDetector, FindsNothingWithoutAPupil) {
  const StarburstPupilDetector detector;
  SyntheticEye no_pupil;
  no_pupil.pupil = {{-100, -100}, 5, 5, 0};  // off the image
  no_pupil.noise_dn = 2;
  EXPECT_FALSE(detector.detect(view(draw(no_pupil)), {}));
  const cv::Mat black = cv::Mat::zeros(120, 160, CV_8U), grey(120, 160, CV_8U, cv::Scalar(128));
  EXPECT_FALSE(detector.detect(view(black), {}));
  EXPECT_FALSE(detector.detect(view(grey), {}));
  const cv::Mat tiny(2, 2, CV_8U, cv::Scalar(0));
  EXPECT_FALSE(detector.detect(view(tiny), {}));
  // A pupil cut by the image's border is no pupil to fit.
  SyntheticEye cut;
  cut.pupil = {{4, 90}, 15, 15, 0};
  const std::optional<PupilDetection> edge = detector.detect(view(draw(cut)), {});
  if (edge) {
    EXPECT_LT(edge->confidence, 0.75);
  }
}

// 10-bit data in 16-bit words: the same pupil as the 8-bit image's.
TEST(StarburstPupilDetector, ReadsSixteenBitImages) {
  SyntheticEye eye;
  eye.pupil = {{100.3, 90.6}, 12, 10, 0.7};
  const std::optional<PupilDetection> ten_bits =
      StarburstPupilDetector().detect(view(draw(eye, CV_16U, 4), 10), {});
  ASSERT_TRUE(ten_bits);
  EXPECT_LT(centre_error(*ten_bits, eye.pupil), 0.02);
}

TEST(StarburstPupilDetector, RejectsBadSettingsNamingTheField) {
  const auto rejects = [](const StarburstPupilSettings& s, const std::string& field) {
    try {
      StarburstPupilDetector detector(s);
      ADD_FAILURE() << field << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  StarburstPupilSettings s;
  s.min_radius_px = 0.5;
  rejects(s, "min_radius_px");
  s = {};
  s.max_radius_px = 2;
  rejects(s, "max_radius_px");
  s = {};
  s.candidates = 0;
  rejects(s, "candidates");
  s = {};
  s.rays = 16;  // the confidence counts 32 sectors
  rejects(s, "rays");
  s = {};
  s.ransac_iterations = 0;
  rejects(s, "ransac_iterations");
  s = {};
  s.inlier_px = std::nan("");
  rejects(s, "inlier_px");
  s = {};
  s.min_axis_ratio = 0;
  rejects(s, "min_axis_ratio");
  s = {};
  s.min_contrast = 1;
  rejects(s, "min_contrast");
  s = {};
  s.min_confidence = 1.5;
  rejects(s, "min_confidence");
  s = {};
  s.glint_margin_px = -1;
  rejects(s, "glint_margin_px");
}

TEST(StarburstPupilDetector, RejectsImagesItCannotRead) {
  const std::vector<std::uint8_t> pixels(30, 0);
  GreyView bad{pixels.data(), 5, 6, 5, 3, 8};
  try {
    StarburstPupilDetector().detect(bad, {});
    ADD_FAILURE() << "3 bytes per pixel accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("StarburstPupilDetector"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("bytes_per_pixel"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace purkinje::trackers
