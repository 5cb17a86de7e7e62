// The blob glint detector on the renderer's noisy sensor images, against
// the labels: every visible glint found and told which light made it,
// within 0.1 px of its label on average, and nothing else found (measured
// over 4 noise seeds: remote 0.0063 px, headset 0.014 px, worst 0.054 px).
// The trackers issue's bar, over 500 renders with varied gaze and pupil,
// is for `purkinje track`; this is its everyday check.

#include <gtest/gtest.h>

#include <cmath>
#include <span>
#include <string>
#include <vector>

#include "purkinje/models/rotation.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/renderer/render.h"
#include "purkinje/trackers/glints.h"

namespace purkinje::trackers {
namespace {

void expect_glints_found(const std::string& name) {
  const Scene scene = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/" + name + ".json");
  const BlobGlintDetector detector;
  double sum = 0, worst = 0;
  int visible = 0, found = 0, identified = 0, spurious = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    renderer::RenderOptions options;
    options.seed = seed;  // sensor noise differs; the scene does not
    options.edge_samples_per_pixel = 8;
    const renderer::RenderResult r = renderer::render(scene, 0, options);
    std::vector<Glint> glints =
        detector.detect(grey_view(std::span<const std::uint16_t>(r.sensor.values), r.sensor.width,
                                  r.sensor.height, r.sensor.bits));
    // Identity from the lights' layout on a nominal eye 2 mm and 10 deg
    // away from the true one, as a tracker knows the eye only roughly.
    const Eye& eye = scene.eyes[0];
    const UnitVector3 axis = eye.world_from_eye().rotation() * UnitVector3::unit_z();
    const Eye nominal = Eye::with_cornea_center(eye.model(), eye.cornea_center() + Vector3{1.5, -1.0, 0.8},
                                                rotate(axis, UnitVector3::unit_y(), 0.17));
    identify_glints(glints, nominal_glint_layout(scene.cameras[0], scene.illuminators, nominal));
    std::vector<bool> used(glints.size(), false);
    for (const EyeInCameraTruth& view : r.truth.views) {
      for (const GlintTruth& g : view.glints) {
        if (g.status != PathStatus::ok) continue;
        ++visible;
        int nearest = -1;
        double best = 2.0;  // px: a detection farther off is another glint's or none
        for (std::size_t i = 0; i < glints.size(); ++i) {
          const double d = std::hypot(glints[i].centre.u - g.pixel.u, glints[i].centre.v - g.pixel.v);
          if (!used[i] && d < best) best = d, nearest = static_cast<int>(i);
        }
        if (nearest < 0) continue;
        used[nearest] = true;
        ++found;
        identified += glints[nearest].illuminator == g.illuminator ? 1 : 0;
        sum += best;
        worst = std::max(worst, best);
      }
    }
    for (const bool u : used) spurious += u ? 0 : 1;
  }
  ASSERT_GT(visible, 0);
  EXPECT_EQ(found, visible);
  EXPECT_EQ(identified, found);
  EXPECT_EQ(spurious, 0);
  EXPECT_LT(sum / found, 0.1);
  EXPECT_LT(worst, 0.3);
  ::testing::Test::RecordProperty(name + "_visible", visible);
  ::testing::Test::RecordProperty(name + "_mean_px", std::to_string(sum / found));
  ::testing::Test::RecordProperty(name + "_worst_px", std::to_string(worst));
}

TEST(BlobGlintDetectorOnRenders, FindsTheRemoteScenesGlintsNearTheirLabels) { expect_glints_found("remote"); }
// The headset's glints saturate on the pupil's edge: found by the fit.
TEST(BlobGlintDetectorOnRenders, FindsTheHeadsetScenesGlintsNearTheirLabels) { expect_glints_found("headset"); }

}  // namespace
}  // namespace purkinje::trackers
