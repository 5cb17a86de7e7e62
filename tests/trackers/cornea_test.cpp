// The cornea's centre from glints, against the scenes' exact glints: the
// estimate must come back to the true centre from a start millimetres away
// (the calibration issue's bar: 1e-6 mm from exact features), and say when
// the glints do not pin it down.

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "purkinje/models/scene_file.h"
#include "purkinje/models/truth.h"
#include "purkinje/trackers/cornea.h"
#include "purkinje/trackers/scoring.h"

namespace purkinje::trackers {
namespace {

Scene bundled(const std::string& name) {
  return load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/" + name + ".json");
}

// The scene's exact glints, each told its light.
std::vector<Glint> exact_glints(const Scene& scene) { return exact_detections(compute_truth(scene).views).glints; }

// The remote rig with a spherical cornea (the estimator's model) where the
// scene's eye has its cornea.
Scene remote_with_spherical_cornea() {
  Scene scene = bundled("remote");
  const Eye& eye = scene.eyes[0];
  Eye sphere = Eye::with_cornea_center(keratometric_eye(), eye.cornea_center(),
                                       eye.world_from_eye().rotation() * UnitVector3::unit_z());
  sphere.set_appearance(eye.appearance());
  scene.eyes = {sphere};
  return scene;
}

void expect_exact_centre(const Scene& scene) {
  const std::vector<Glint> glints = exact_glints(scene);
  ASSERT_GE(glints.size(), 2u);
  const Point3 truth = scene.eyes[0].cornea_center();
  const CorneaCenterEstimate e =
      estimate_cornea_center(scene.cameras[0], scene.illuminators, glints, truth + Vector3{2, -1.5, 3});
  EXPECT_TRUE(e.converged);
  EXPECT_TRUE(e.warnings.empty()) << e.warnings.front();
  EXPECT_EQ(e.glints_used, static_cast<int>(glints.size()));
  EXPECT_LT(distance(e.center, truth), 1e-6);
  EXPECT_LT(e.rms_residual_px, 1e-6);
  ::testing::Test::RecordProperty("error_mm", std::to_string(distance(e.center, truth)));
  ::testing::Test::RecordProperty("condition", std::to_string(e.condition));
  ASSERT_TRUE(e.covariance_mm2);
  const std::array<double, 9>& c = *e.covariance_mm2;
  for (int a = 0; a < 3; ++a) {
    EXPECT_GT(c[4 * a], 0);
    for (int b = 0; b < 3; ++b) EXPECT_NEAR(c[3 * a + b], c[3 * b + a], 1e-12 * (c[0] + c[4] + c[8]));
  }
}

TEST(CorneaCenter, ComesBackToTheTrueCentreFromTheHeadsetsExactGlints) {
  expect_exact_centre(bundled("headset"));  // a spherical cornea, R = 7.8 mm, eight lights
}

TEST(CorneaCenter, ComesBackToTheTrueCentreFromTheRemotesExactGlints) {
  expect_exact_centre(remote_with_spherical_cornea());  // two lights at 600 mm
}

// From 600 mm with two lights, the glints' spacing is what tells depth:
// it changes little with it, so depth is the weak direction.
TEST(CorneaCenter, DepthIsTheWeakDirectionFromAfar) {
  const Scene scene = remote_with_spherical_cornea();
  const CorneaCenterEstimate e =
      estimate_cornea_center(scene.cameras[0], scene.illuminators, exact_glints(scene), scene.eyes[0].cornea_center());
  ASSERT_TRUE(e.covariance_mm2);
  const std::array<double, 9>& c = *e.covariance_mm2;
  const Vector3 view = scene.eyes[0].cornea_center() - scene.cameras[0].center();
  const Vector3 d = view / view.norm();
  double along = 0;  // d^T C d
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) along += d[a] * c[3 * a + b] * d[b];
  }
  const double total = c[0] + c[4] + c[8];
  EXPECT_GT(along, 0.9 * total);  // nearly all of the variance lies along the line of sight
  ::testing::Test::RecordProperty("depth_share", std::to_string(along / total));
  ::testing::Test::RecordProperty("depth_sd_mm", std::to_string(std::sqrt(along)));
}

TEST(CorneaCenter, SaysWhenTheGlintsDoNotPinTheCentreDown) {
  const Scene scene = bundled("headset");
  std::vector<Glint> glints = exact_glints(scene);
  const Point3 start = scene.eyes[0].cornea_center() + Vector3{1, 1, 1};
  // One glint: two numbers for three unknowns.
  const CorneaCenterEstimate one =
      estimate_cornea_center(scene.cameras[0], scene.illuminators, {glints.front()}, start);
  EXPECT_FALSE(one.covariance_mm2);
  ASSERT_FALSE(one.warnings.empty());
  EXPECT_NE(one.warnings.front().find("not determined"), std::string::npos);
  EXPECT_EQ(distance(one.center, start), 0);
  // Glints without their light are left out.
  std::vector<Glint> untold = glints;
  for (Glint& g : untold) g.illuminator = -1;
  EXPECT_EQ(estimate_cornea_center(scene.cameras[0], scene.illuminators, untold, start).glints_used, 0);
  // Two lights at one place give the same glint twice: still two numbers.
  std::vector<Illuminator> twins = scene.illuminators;
  twins[1].position = twins[0].position;
  std::vector<Glint> same{glints[0], glints[0]};
  same[0].illuminator = 0;
  same[1].illuminator = 1;
  const CorneaCenterEstimate twin = estimate_cornea_center(scene.cameras[0], twins, same, start);
  EXPECT_FALSE(twin.covariance_mm2);
  EXPECT_FALSE(twin.warnings.empty());
}

TEST(CorneaCenter, RejectsBadSettingsAndUnknownLights) {
  const Scene scene = bundled("headset");
  const std::vector<Glint> glints = exact_glints(scene);
  const Point3 start = scene.eyes[0].cornea_center();
  EXPECT_THROW(estimate_cornea_center(scene.cameras[0], scene.illuminators, glints, start, {0, 0.1, 1e8}),
               std::invalid_argument);
  EXPECT_THROW(estimate_cornea_center(scene.cameras[0], scene.illuminators, glints, start, {7.8, 0, 1e8}),
               std::invalid_argument);
  std::vector<Glint> stray = glints;
  stray[0].illuminator = 99;
  EXPECT_THROW(estimate_cornea_center(scene.cameras[0], scene.illuminators, stray, start), std::invalid_argument);
}

}  // namespace
}  // namespace purkinje::trackers
