// Scleral highlights in the image: where the labels put them, with the
// electrons the labels give, spread as their radiometry says, kept to the
// sclera the camera sees, and a mask of their share of the light.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <numbers>
#include <string>
#include <vector>

#include "purkinje/models/scene_file.h"
#include "purkinje/models/truth.h"
#include "purkinje/renderer/render.h"

namespace purkinje::renderer {
namespace {

// The bundled headset with every albedo 0 (only glints and highlights
// light the image), a wet sclera, the eye turned so that its sclera
// mirrors several LEDs.
Scene wet_dark_headset(double roughness_deg, double yaw_rad = 0.44, double pitch_rad = 0.17) {
  Scene scene = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/headset.json");
  const Eye& eye = scene.eyes[0];
  Eye turned = Eye::with_cornea_center(eye.model(), eye.cornea_center(), optical_axis_from_yaw_pitch(yaw_rad, pitch_rad));
  EyeAppearance look = eye.appearance();
  look.iris_albedo = look.sclera_albedo = look.skin_albedo = look.fundus_reflectance = 0;
  look.tear_film = TearFilm{roughness_deg};
  turned.set_appearance(look);
  scene.eyes[0] = turned;
  return scene;
}

const ImagePlane& aov(const RenderResult& result, const std::string& name) {
  for (const NamedPlane& p : result.aovs) {
    if (p.name == name) return p.plane;
  }
  throw std::runtime_error("no AOV " + name);
}

TEST(ScleralHighlights, LieWhereTheLabelsSayWithTheirElectronsAndSpread) {
  const Scene scene = wet_dark_headset(1.0);
  RenderOptions options;
  options.noise = false;
  const RenderResult result = render(scene, 0, options);
  const ImagePlane& mask = aov(result, "distractor");
  const ImagePlane& sclera = aov(result, "sclera");
  const ImagePlane& e = result.electrons;
  const std::vector<DistractorTruth>& truth = result.truth.views[0].distractors;
  ASSERT_EQ(truth.size(), result.distractors.size());

  // The highlights' light in the image is what their labels give.
  double labelled = 0, imaged = 0, beyond = 0;
  for (const GlintImage& d : result.distractors) labelled += d.electrons;
  for (std::size_t i = 0; i < e.values.size(); ++i) imaged += double(mask.values[i]) * e.values[i];
  EXPECT_GT(labelled, 0);
  EXPECT_NEAR(imaged / labelled, 1, 1e-4);

  // None of it lies farther than 3 px from the sclera the camera sees
  // (the point spread's reach at sigma 0.5).
  for (int y = 0; y < e.height; ++y) {
    for (int x = 0; x < e.width; ++x) {
      bool near_sclera = false;
      for (int dy = -3; dy <= 3 && !near_sclera; ++dy) {
        for (int dx = -3; dx <= 3 && !near_sclera; ++dx) {
          const int xx = x + dx, yy = y + dy;
          near_sclera = xx >= 0 && yy >= 0 && xx < e.width && yy < e.height && sclera.at(xx, yy) > 0;
        }
      }
      if (!near_sclera) beyond += double(mask.at(x, y)) * e.at(x, y);
    }
  }
  EXPECT_LT(beyond, 1e-6 * labelled);

  // led4's highlight alone (the others' lie 20 px off), wholly on seen
  // sclera: its centroid is its label, its spread its covariance plus
  // the point spread's and the pixel's.
  Scene one = scene;
  one.illuminators = {scene.illuminators[4]};
  const RenderResult single = render(one, 0, options);
  ASSERT_EQ(single.distractors.size(), 1u);
  const DistractorTruth& d = single.truth.views[0].distractors[0];
  ASSERT_EQ(d.status, PathStatus::ok);
  const GlintRadiometry& r = single.distractors[0].radiometry;
  const double var_u = r.roughness_cov_px2[0] + r.source_cov_px2[0], var_v = r.roughness_cov_px2[2] + r.source_cov_px2[2];
  EXPECT_GT(var_u, 1);  // a spread spot, not a point
  const int reach = static_cast<int>(5 * std::sqrt(std::max(var_u, var_v) + 0.25)) + 3;
  const ImagePlane& one_mask = aov(single, "distractor");
  const ImagePlane& one_sclera = aov(single, "sclera");
  double total = 0, su = 0, sv = 0, suu = 0, svv = 0;
  for (int y = static_cast<int>(d.pixel.v) - reach; y <= static_cast<int>(d.pixel.v) + reach; ++y) {
    for (int x = static_cast<int>(d.pixel.u) - reach; x <= static_cast<int>(d.pixel.u) + reach; ++x) {
      ASSERT_EQ(one_sclera.at(x, y), 1.0f) << x << ", " << y;
      const double light = double(one_mask.at(x, y)) * single.electrons.at(x, y);
      total += light;
      su += light * x;
      sv += light * y;
      suu += light * x * x;
      svv += light * y * y;
    }
  }
  const double u = su / total, v = sv / total;
  EXPECT_NEAR(total / single.distractors[0].electrons, 1, 1e-4);
  EXPECT_NEAR(u, d.pixel.u, 0.02);
  EXPECT_NEAR(v, d.pixel.v, 0.02);
  // Point spread sigma 0.5 px (the headset's): 0.25 px^2; the pixel 1/12.
  EXPECT_NEAR((suu / total - u * u) / (var_u + 0.25 + 1.0 / 12), 1, 0.02);
  EXPECT_NEAR((svv / total - v * v) / (var_v + 0.25 + 1.0 / 12), 1, 0.02);

  // A dry eye's image has no distractor mask.
  Scene dry = scene;
  EyeAppearance look = dry.eyes[0].appearance();
  look.tear_film.reset();
  dry.eyes[0].set_appearance(look);
  const RenderResult dry_result = render(dry, 0, options);
  EXPECT_TRUE(dry_result.distractors.empty());
  EXPECT_THROW(aov(dry_result, "distractor"), std::runtime_error);
}

TEST(ScleralHighlights, AMovingEyesHighlightsAreTheWholeExposures) {
  // 1000 deg/s at 33.75 deg of yaw: during the 1 ms exposure a highlight
  // crosses the seam with the cornea, so that it exists at some instants
  // and not at mid-exposure. Every highlight drawn is labelled, with the
  // electrons of the whole exposure.
  Scene scene = wet_dark_headset(2.0, 33.75 * std::numbers::pi / 180, 10 * std::numbers::pi / 180);
  scene.eyes[0].set_motion({1000, 0});
  RenderOptions options;
  options.noise = false;
  const RenderResult result = render(scene, 0, options);
  const ImagePlane& mask = aov(result, "distractor");
  double labelled = 0, imaged = 0;
  for (const GlintImage& d : result.distractors) labelled += d.electrons;
  for (std::size_t i = 0; i < mask.values.size(); ++i) imaged += double(mask.values[i]) * result.electrons.values[i];
  EXPECT_GT(labelled, 0);
  EXPECT_NEAR(imaged / labelled, 1, 1e-3);
  // One is labelled that the still eye at mid-exposure does not have.
  Scene still = scene;
  still.eyes[0].set_motion({});
  const SceneTruth mid = compute_truth(still);
  const std::vector<DistractorTruth>& moving = result.truth.views[0].distractors;
  ASSERT_EQ(moving.size(), result.distractors.size());
  EXPECT_GT(moving.size(), mid.views[0].distractors.size());
  for (std::size_t k = 0; k < moving.size(); ++k) {
    EXPECT_EQ(moving[k].illuminator, result.distractors[k].illuminator);
    if (k > 0) {
      EXPECT_LT(moving[k - 1].illuminator, moving[k].illuminator);
    }
  }
}

TEST(ScleralHighlights, ARoughnessOutOfRangeIsRefusedBeforeRendering) {
  for (const double roughness : {-1.0, 10.5, std::numeric_limits<double>::quiet_NaN()}) {
    const Scene scene = wet_dark_headset(roughness);
    RenderResult result;
    result.camera = 7;
    try {
      render(scene, 0, RenderOptions{}, result);
      ADD_FAILURE() << roughness;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("eyes[0].appearance.tear_film.sclera_roughness_deg"), std::string::npos)
          << e.what();
    }
    EXPECT_EQ(result.camera, 7);  // untouched
  }
}

}  // namespace
}  // namespace purkinje::renderer
