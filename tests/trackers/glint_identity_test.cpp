// Which light made which glint: patterns of expected glints moved, scaled
// and turned, with glints missing and spurious ones added.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "purkinje/trackers/glints.h"

namespace purkinje::trackers {
namespace {

// A ring of `n` lights' glints about (100, 100), radius 20 px.
std::vector<std::optional<Pixel>> ring(int n) {
  std::vector<std::optional<Pixel>> places;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * std::numbers::pi * i / n;
    places.push_back(Pixel{100 + 20 * std::cos(a), 100 + 20 * std::sin(a)});
  }
  return places;
}

// The glints of `places` scaled by `scale`, turned by `angle` about the
// origin and moved by (du, dv), each jittered by up to `jitter_px`.
std::vector<Glint> seen(const std::vector<std::optional<Pixel>>& places, double scale, double angle, double du,
                        double dv, double jitter_px, std::mt19937& rng) {
  std::uniform_real_distribution<double> jitter(-jitter_px, jitter_px);
  std::vector<Glint> glints;
  for (std::size_t i = 0; i < places.size(); ++i) {
    const Pixel& p = *places[i];
    Glint g;
    g.centre = {scale * (std::cos(angle) * p.u - std::sin(angle) * p.v) + du + jitter(rng),
                scale * (std::sin(angle) * p.u + std::cos(angle) * p.v) + dv + jitter(rng)};
    g.illuminator = static_cast<int>(i);  // the truth, until identify_glints overwrites it
    glints.push_back(g);
  }
  return glints;
}

TEST(IdentifyGlints, ARingMovedScaledAndTurnedWithMissingAndSpuriousGlints) {
  std::mt19937 rng(7);
  for (const double angle : {-0.3, -0.1, 0.0, 0.15, 0.3}) {
    for (const double scale : {0.6, 1.0, 1.4}) {
      const std::vector<std::optional<Pixel>> expected = ring(8);
      // Turned about the ring's own centre, then moved.
      std::vector<Glint> glints =
          seen(expected, scale, angle, 37 + 100 * (1 - scale * std::cos(angle)) + 100 * scale * std::sin(angle),
               -21 + 100 * (1 - scale * std::cos(angle)) - 100 * scale * std::sin(angle), 0.3, rng);
      glints.erase(glints.begin() + 5);  // two glints hidden (by a lid, say)
      glints.erase(glints.begin() + 2);
      // Spurious ones: in the ring's middle, and far off.
      for (const Pixel p : {Pixel{137, 79}, Pixel{10, 10}, Pixel{180, 40}}) {
        Glint g;
        g.centre = p;
        glints.push_back(g);
      }
      std::shuffle(glints.begin(), glints.end(), rng);  // detectors order by brightness, not by light
      std::vector<int> truth;
      for (const Glint& g : glints) truth.push_back(g.illuminator);
      identify_glints(glints, expected);
      for (std::size_t k = 0; k < glints.size(); ++k) {
        EXPECT_EQ(glints[k].illuminator, truth[k]) << "angle " << angle << " scale " << scale << " glint " << k;
      }
    }
  }
}

// Two lights beside a camera, their two glints and a spurious one. With
// two lights every pair of detections fits the layout exactly; the pair
// nearest the layout's own spacing and orientation is the glints.
void expect_two_lights_told_from(const Pixel& spurious) {
  const std::vector<std::optional<Pixel>> expected{Pixel{316.6, 239.5}, Pixel{322.4, 239.6}};
  std::vector<Glint> glints(3);
  glints[0].centre = spurious;        // the brightest
  glints[1].centre = {343.5, 230.2};  // light 1
  glints[2].centre = {337.2, 230.0};  // light 0
  identify_glints(glints, expected);
  EXPECT_EQ(glints[0].illuminator, -1);
  EXPECT_EQ(glints[1].illuminator, 1);
  EXPECT_EQ(glints[2].illuminator, 0);
}

TEST(IdentifyGlints, TwoLightsBesideACameraWithASpuriousGlint) {
  expect_two_lights_told_from({360.1, 228.0});  // with light 1's glint, a pair beyond the scale bound
}

TEST(IdentifyGlints, TwoLightsAndASpuriousGlintThatAlsoFitsTheScaleBounds) {
  expect_two_lights_told_from({349.0, 230.0});  // with light 1's glint, 1.8 times the spacing, turned 0.3 rad
}

TEST(IdentifyGlints, RejectsSettingsOutOfRangeNamingThem) {
  std::vector<Glint> glints(2);
  const std::vector<std::optional<Pixel>> expected{Pixel{0, 0}, Pixel{5, 0}};
  for (const auto& [settings, name] : std::vector<std::pair<GlintMatchSettings, std::string>>{
           {{0.9, 0.35, 0.35}, "max_scale"}, {{2, -0.1, 0.35}, "max_rotation_rad"}, {{2, 0.35, 0.5}, "gate_fraction"}}) {
    try {
      identify_glints(glints, expected, settings);
      ADD_FAILURE() << name << " out of range was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
}

TEST(IdentifyGlints, OneGlintOfTwoLightsIsNotPinnedDown) {
  const std::vector<std::optional<Pixel>> expected{Pixel{316.6, 239.5}, Pixel{322.4, 239.6}};
  std::vector<Glint> glints(1);
  glints[0].centre = {316.6, 239.5};
  glints[0].illuminator = 0;
  identify_glints(glints, expected);
  EXPECT_EQ(glints[0].illuminator, -1);
}

TEST(IdentifyGlints, ALightWithoutAPlaceIsNeverMatched) {
  std::vector<std::optional<Pixel>> expected = ring(4);
  expected[1].reset();
  std::mt19937 rng(3);
  std::vector<Glint> glints = seen(ring(4), 1.0, 0.0, 5, 5, 0.2, rng);
  identify_glints(glints, expected);
  EXPECT_EQ(glints[0].illuminator, 0);
  EXPECT_EQ(glints[1].illuminator, -1);  // where light 1 would be: spurious, as far as the layout knows
  EXPECT_EQ(glints[2].illuminator, 2);
  EXPECT_EQ(glints[3].illuminator, 3);
}

}  // namespace
}  // namespace purkinje::trackers
