// The tracker assembled once (studies/tracker.h) on the bundled scenes'
// renders: what it finds against the labels, and what knowing the rig adds.

#include "purkinje/studies/tracker.h"

#include <gtest/gtest.h>

#include <cmath>
#include <span>
#include <string>

#include "purkinje/models/scene_file.h"
#include "purkinje/renderer/render.h"

namespace purkinje::studies {
namespace {

struct Rendered {
  Scene scene;
  renderer::RenderResult result;
  trackers::GreyView image() const {
    return trackers::grey_view(std::span<const std::uint16_t>(result.sensor.values), result.sensor.width,
                               result.sensor.height, result.sensor.bits);
  }
};

Rendered render(const std::string& name) {
  Rendered r{load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/" + name + ".json"), {}};
  r.result = renderer::render(r.scene, 0, {});
  return r;
}

TEST(TrackerOnRenders, KnowingTheRigItTellsEachGlintItsLightAndFindsThePupil) {
  for (const std::string name : {"remote", "headset"}) {
    SCOPED_TRACE(name);
    const Rendered r = render(name);
    const Tracker tracker(r.scene.cameras[0], r.scene.illuminators, r.scene.eyes[0]);
    EXPECT_TRUE(tracker.identifies_glints());
    // Both scenes: a point spread of 0.5 px, in focus, point lights.
    EXPECT_DOUBLE_EQ(tracker.glint_settings().spot_sigma_px, 0.5);
    const trackers::Detections found = tracker.track(r.image());
    const EyeInCameraTruth& view = r.result.truth.views.front();
    int told = 0;
    for (const trackers::Glint& g : found.glints) {
      if (g.illuminator < 0) continue;
      ++told;
      const GlintTruth& label = view.glints[g.illuminator];
      ASSERT_EQ(label.status, PathStatus::ok);
      EXPECT_LT(std::hypot(g.centre.u - label.pixel.u, g.centre.v - label.pixel.v), 0.5) << "light " << g.illuminator;
    }
    int visible = 0;
    for (const GlintTruth& label : view.glints) visible += label.status == PathStatus::ok ? 1 : 0;
    EXPECT_EQ(told, visible);
    ASSERT_EQ(found.pupils.size(), 1u);
    ASSERT_TRUE(found.pupils[0].ellipse);
    EXPECT_LT(std::hypot(found.pupils[0].centre.u - view.pupil.ellipse.center.u,
                         found.pupils[0].centre.v - view.pupil.ellipse.center.v),
              1.0);
  }
}

TEST(TrackerOnRenders, KnowingNothingItFindsTheSameGlintsUntold) {
  const Rendered r = render("remote");
  const trackers::Detections found = Tracker().track(r.image());
  EXPECT_FALSE(Tracker().identifies_glints());
  EXPECT_EQ(Tracker().glint_settings().spot_sigma_px, 0);  // estimated per frame
  ASSERT_EQ(found.glints.size(), 2u);                      // the remote's two LEDs
  for (const trackers::Glint& g : found.glints) EXPECT_EQ(g.illuminator, -1);
  EXPECT_EQ(found.pupils.size(), 1u);
}

}  // namespace
}  // namespace purkinje::studies
