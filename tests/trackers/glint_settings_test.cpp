// What a tracker that knows its camera tells the glint detector
// (`purkinje calibrate`, `purkinje track --scene`); expected values read off
// the bundled scene files.

#include <gtest/gtest.h>

#include <filesystem>

#include "purkinje/models/scene_file.h"
#include "purkinje/trackers/glints.h"

namespace purkinje::trackers {
namespace {

const std::filesystem::path kScenes = std::filesystem::path(PURKINJE_SOURCE_DIR) / "assets/scenes";

TEST(GlintSettingsFor, AFocusedCameraWithPointLightsTellsItsPointSpreadAndSensorNoise) {
  // remote_noisy.json: psf_sigma_px 0.5, no focus distance, full well
  // 10000 e at gain 1, read noise 40 e.
  const Scene scene = load_scene(kScenes / "hard/remote_noisy.json");
  const BlobGlintSettings s =
      glint_settings_for(scene.cameras[0], scene.illuminators, scene.eyes[0].cornea_center());
  EXPECT_DOUBLE_EQ(s.spot_sigma_px, 0.5);
  EXPECT_DOUBLE_EQ(s.full_scale_e, 10000);
  EXPECT_DOUBLE_EQ(s.read_noise_e, 40);
}

TEST(GlintSettingsFor, GainShrinksTheFullScale) {
  const Scene scene = load_scene(kScenes / "remote.json");
  const Camera& c = scene.cameras[0];
  Sensor sensor = c.sensor();
  sensor.gain = 4;  // the ADC's full range is a quarter of the full well
  const Camera amplified(c.name(), c.intrinsics(), c.distortion(), c.world_from_camera(), sensor);
  EXPECT_DOUBLE_EQ(glint_settings_for(amplified, scene.illuminators, scene.eyes[0].cornea_center()).full_scale_e,
                   sensor.full_well_e / 4);
}

TEST(GlintSettingsFor, DefocusOrSizedLightsLeaveTheSpotsWidthToTheDetector) {
  // headset_defocused.json: focused 22 mm from the camera, the eye about 35 mm.
  const Scene defocused = load_scene(kScenes / "hard/headset_defocused.json");
  EXPECT_EQ(glint_settings_for(defocused.cameras[0], defocused.illuminators, defocused.eyes[0].cornea_center())
                .spot_sigma_px,
            0);
  Scene sized = load_scene(kScenes / "headset.json");
  EXPECT_DOUBLE_EQ(glint_settings_for(sized.cameras[0], sized.illuminators, sized.eyes[0].cornea_center()).spot_sigma_px,
                   0.5);
  sized.illuminators[3].emitter_diameter_mm = 1;  // one LED is a disc: its glint is wider than the point spread
  EXPECT_EQ(glint_settings_for(sized.cameras[0], sized.illuminators, sized.eyes[0].cornea_center()).spot_sigma_px, 0);
}

TEST(GlintSettingsFor, ACorneaAtTheCameraGetsNoPointSpread) {
  const Scene scene = load_scene(kScenes / "remote.json");
  // The cornea at the camera's centre: no depth to compute a point spread at.
  const Point3 at_camera = scene.cameras[0].world_from_camera() * Point3::origin();
  EXPECT_EQ(glint_settings_for(scene.cameras[0], scene.illuminators, at_camera).spot_sigma_px, 0);
}

}  // namespace
}  // namespace purkinje::trackers
