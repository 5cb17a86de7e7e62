#include "purkinje/models/scene_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <cstdint>
#include <map>
#include <numbers>
#include <set>
#include <string>

namespace purkinje {
namespace {

namespace fs = std::filesystem;
constexpr double kDegree = std::numbers::pi / 180.0;

const fs::path kSourceDir = PURKINJE_SOURCE_DIR;

// The message of the SceneError that parsing `text` throws; "" if none.
std::string parse_error(const std::string& text, const std::string& source = "scene.json") {
  try {
    parse_scene(text, source);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

// A minimal valid scene with `eye` as its only eye.
std::string scene_with_eye(const std::string& eye) {
  return R"({ "format": 1,
    "cameras": [ { "resolution_px": [640, 480], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                   "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] } ],
    "eyes": [ )" + eye + R"( ] })";
}

TEST(SceneFile, ReadsEveryKeyOfAFullScene) {
  const Scene scene = parse_scene(R"(
    // Comments are allowed anywhere.
    { "format": 1, "name": "bench",
      "cameras": [ { "name": "left", "resolution_px": [1280, 1024],
                     "focal_length_mm": 25, "pixel_pitch_mm": 0.005,
                     "distortion": { "k1": -0.1, "k2": 0.02, "p1": 0.001, "p2": -0.002, "k3": 0.003 },
                     "position_mm": [10, 20, 30], "look_at_mm": [10, 20, 630], "up": [0, -1, 0] } ],
      "illuminators": [ { "name": "ring", "position_mm": [-50, 5, 0], "radiant_intensity_w_sr": 0.02,
                          "wavelength_nm": 940, "emitter_diameter_mm": 0.5 } ],
      "eyes": [ { "model": "le_grand",
                  "cornea": { "radius_mm": 7.7, "asphericity": -0.2, "limbus_radius_mm": 5.8 },
                  "posterior_cornea": { "radius_mm": 6.4, "asphericity": -0.1, "thickness_mm": 0.5, "index": 1.38 },
                  "aqueous_index": 1.335,
                  "iris": { "depth_mm": 3.5, "radius_mm": 5.4 },
                  "pupil": { "radius_mm": 1.5, "decentration_mm": [0.2, -0.1] },
                  "rotation_center_depth_mm": 13, "sclera_radius_mm": 11.5,
                  "kappa_deg": { "horizontal": 4, "vertical": -2 },
                  "position": { "cornea_center_mm": [1, 2, 600] },
                  "orientation": { "yaw_deg": 10, "pitch_deg": -5 } } ] })",
                                  "bench.json");
  EXPECT_EQ(scene.name, "bench");

  ASSERT_EQ(scene.cameras.size(), 1u);
  const Camera& camera = scene.cameras[0];
  EXPECT_EQ(camera.name(), "left");
  EXPECT_EQ(camera.intrinsics().width, 1280);
  EXPECT_EQ(camera.intrinsics().height, 1024);
  EXPECT_NEAR(camera.intrinsics().fx, 5000.0, 1e-9);  // 25 mm / 0.005 mm
  EXPECT_NEAR(camera.intrinsics().fy, 5000.0, 1e-9);
  EXPECT_DOUBLE_EQ(camera.intrinsics().cx, 639.5);  // (1280 - 1) / 2
  EXPECT_DOUBLE_EQ(camera.intrinsics().cy, 511.5);
  EXPECT_DOUBLE_EQ(camera.distortion().k1, -0.1);
  EXPECT_DOUBLE_EQ(camera.distortion().k2, 0.02);
  EXPECT_DOUBLE_EQ(camera.distortion().p1, 0.001);
  EXPECT_DOUBLE_EQ(camera.distortion().p2, -0.002);
  EXPECT_DOUBLE_EQ(camera.distortion().k3, 0.003);
  EXPECT_NEAR(distance(camera.center(), Point3(10, 20, 30)), 0.0, 1e-12);
  // Looking along +z with image up = world -y: the identity rotation.
  const UnitVector3 forward = camera.world_from_camera().rotation().column(2);
  EXPECT_NEAR(forward.z(), 1.0, 1e-12);
  EXPECT_NEAR(camera.world_from_camera().rotation().column(1).y(), 1.0, 1e-12);

  ASSERT_EQ(scene.illuminators.size(), 1u);
  const Illuminator& led = scene.illuminators[0];
  EXPECT_EQ(led.name, "ring");
  EXPECT_EQ(led.position, Point3(-50, 5, 0));
  EXPECT_DOUBLE_EQ(led.radiant_intensity_w_sr, 0.02);
  EXPECT_DOUBLE_EQ(led.wavelength_nm, 940);
  EXPECT_DOUBLE_EQ(led.emitter_diameter_mm, 0.5);

  ASSERT_EQ(scene.eyes.size(), 1u);
  const Eye& eye = scene.eyes[0];
  const EyeModel& m = eye.model();
  EXPECT_EQ(m.name, "le_grand");
  EXPECT_DOUBLE_EQ(m.anterior_cornea.radius_mm, 7.7);
  EXPECT_DOUBLE_EQ(m.anterior_cornea.asphericity, -0.2);
  EXPECT_DOUBLE_EQ(m.limbus_radius_mm, 5.8);
  ASSERT_TRUE(m.posterior_cornea.has_value());
  EXPECT_DOUBLE_EQ(m.posterior_cornea->surface.radius_mm, 6.4);
  EXPECT_DOUBLE_EQ(m.posterior_cornea->surface.asphericity, -0.1);
  EXPECT_DOUBLE_EQ(m.posterior_cornea->thickness_mm, 0.5);
  EXPECT_DOUBLE_EQ(m.posterior_cornea->cornea_index, 1.38);
  EXPECT_DOUBLE_EQ(m.aqueous_index, 1.335);
  EXPECT_DOUBLE_EQ(m.iris_depth_mm, 3.5);
  EXPECT_DOUBLE_EQ(m.iris_radius_mm, 5.4);
  EXPECT_DOUBLE_EQ(m.pupil_radius_mm, 1.5);
  EXPECT_DOUBLE_EQ(m.pupil_decentration_x_mm, 0.2);
  EXPECT_DOUBLE_EQ(m.pupil_decentration_y_mm, -0.1);
  EXPECT_DOUBLE_EQ(m.rotation_center_depth_mm, 13);
  EXPECT_DOUBLE_EQ(m.sclera_radius_mm, 11.5);
  EXPECT_NEAR(m.kappa_horizontal_rad, 4 * kDegree, 1e-15);
  EXPECT_NEAR(m.kappa_vertical_rad, -2 * kDegree, 1e-15);
  EXPECT_NEAR(distance(eye.cornea_center(), Point3(1, 2, 600)), 0.0, 1e-12);
  // o = (sin yaw cos pitch, -sin pitch, -cos yaw cos pitch), by hand.
  const double yaw = 10 * kDegree, pitch = -5 * kDegree;
  EXPECT_NEAR(eye.optical_axis().x(), std::sin(yaw) * std::cos(pitch), 1e-12);
  EXPECT_NEAR(eye.optical_axis().y(), -std::sin(pitch), 1e-12);
  EXPECT_NEAR(eye.optical_axis().z(), -std::cos(yaw) * std::cos(pitch), 1e-12);
}

TEST(SceneFile, FillsDefaultsFromThePresetAndTheFileName) {
  const Scene scene = parse_scene(
      scene_with_eye(R"({ "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} })"),
      "dir/my_scene.json");
  EXPECT_EQ(scene.name, "my_scene");
  EXPECT_EQ(scene.cameras[0].name(), "cam0");
  EXPECT_TRUE(scene.cameras[0].distortion().is_zero());
  EXPECT_TRUE(scene.illuminators.empty());
  const EyeModel& m = scene.eyes[0].model();
  const EyeModel preset = keratometric_eye();
  EXPECT_EQ(m.name, "keratometric");
  EXPECT_EQ(m.anterior_cornea.radius_mm, preset.anterior_cornea.radius_mm);
  EXPECT_FALSE(m.posterior_cornea.has_value());
  EXPECT_EQ(m.pupil_radius_mm, preset.pupil_radius_mm);
  // No orientation keys: looking along world -z.
  EXPECT_NEAR(scene.eyes[0].optical_axis().z(), -1.0, 1e-15);
}

// A minimal valid scene with a screen block.
std::string scene_with_screen(const std::string& screen) {
  return R"({ "format": 1,
    "cameras": [ { "resolution_px": [640, 480], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                   "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] } ],
    "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} } ],
    "screen": )" + screen + " }";
}

TEST(SceneFile, ReadsAScreenByItsCentreAndSize) {
  const Scene none =
      parse_scene(scene_with_eye(R"({ "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} })"), "s.json");
  EXPECT_FALSE(none.screen);
  const Scene scene = parse_scene(scene_with_screen(R"({ "center_mm": [0, -182, 0], "size_mm": [518, 324] })"), "s.json");
  ASSERT_TRUE(scene.screen);
  // Centre less half the width along +x and half the height along +y.
  EXPECT_EQ(scene.screen->top_left, (Point3{-259, -344, 0}));
  EXPECT_EQ(scene.screen->width_mm, 518);
  EXPECT_EQ(scene.screen->height_mm, 324);
  const Point3 centre = scene.screen->center();
  EXPECT_NEAR(distance(centre, {0, -182, 0}), 0, 1e-12);
  // A turned screen: rows along -z, columns along +y.
  const Scene turned = parse_scene(
      scene_with_screen(R"({ "center_mm": [300, 0, 500], "size_mm": [100, 50], "right": [0, 0, -2], "down": [0, 1, 0] })"), "s.json");
  EXPECT_EQ(turned.screen->top_left, (Point3{300, -25, 550}));
}

TEST(SceneFile, RejectsBadScreensByKey) {
  EXPECT_NE(parse_error(scene_with_screen(R"({ "center_mm": [0, 0, 0], "size_mm": [0, 3] })"))
                .find("size_mm"), std::string::npos);
  EXPECT_NE(parse_error(scene_with_screen(R"({ "center_mm": [0, 0, 0], "size_mm": [4] })"))
                .find("must be an array of 2 numbers"), std::string::npos);
  EXPECT_NE(parse_error(scene_with_screen(R"({ "center_mm": [0, 0, 0], "size_mm": [4, 3], "down": [1, 1, 0] })"))
                .find("perpendicular"), std::string::npos);
  EXPECT_NE(parse_error(scene_with_screen(R"({ "size_mm": [4, 3] })")).find("center_mm"), std::string::npos);
  EXPECT_NE(parse_error(scene_with_screen(R"({ "center_mm": [0, 0, 0], "size_mm": [4, 3], "tilt": 1 })"))
                .find("tilt"), std::string::npos);
}

TEST(SceneFile, DefaultIlluminatorValuesMatchTheStruct) {
  const Scene scene = parse_scene(R"({ "format": 1,
    "cameras": [ { "resolution_px": [64, 48], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                   "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 1] } ],
    "illuminators": [ { "position_mm": [1, 2, 3] }, { "position_mm": [4, 5, 6] } ],
    "eyes": [ { "position": { "rotation_center_mm": [0, 0, 600] }, "orientation": {} } ] })",
                                  "s.json");
  const Illuminator defaults;
  ASSERT_EQ(scene.illuminators.size(), 2u);
  EXPECT_EQ(scene.illuminators[0].name, "led0");
  EXPECT_EQ(scene.illuminators[1].name, "led1");
  EXPECT_EQ(scene.illuminators[1].position, Point3(4, 5, 6));
  EXPECT_EQ(scene.illuminators[0].radiant_intensity_w_sr, defaults.radiant_intensity_w_sr);
  EXPECT_EQ(scene.illuminators[0].wavelength_nm, defaults.wavelength_nm);
  EXPECT_EQ(scene.illuminators[0].emitter_diameter_mm, defaults.emitter_diameter_mm);
  EXPECT_NEAR(distance(scene.eyes[0].rotation_center(), Point3(0, 0, 600)), 0.0, 1e-12);
}

TEST(SceneFile, ReadsPixelIntrinsicsWithTheImageCentreAsDefault) {
  const Scene scene = parse_scene(R"({ "format": 1,
    "cameras": [ { "resolution_px": [101, 51], "intrinsics_px": { "fx": 1000, "fy": 1100 },
                   "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 1] },
                 { "resolution_px": [100, 50], "intrinsics_px": { "fx": 900, "fy": 950, "cx": 40, "cy": 30 },
                   "position_mm": [50, 0, 0], "look_at_mm": [50, 0, 1] } ],
    "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} } ] })",
                                  "s.json");
  const Intrinsics& a = scene.cameras[0].intrinsics();
  EXPECT_EQ(a.fx, 1000);
  EXPECT_EQ(a.fy, 1100);
  EXPECT_EQ(a.cx, 50);
  EXPECT_EQ(a.cy, 25);
  const Intrinsics& b = scene.cameras[1].intrinsics();
  EXPECT_EQ(b.cx, 40);
  EXPECT_EQ(b.cy, 30);
  EXPECT_EQ(b.width, 100);
  EXPECT_EQ(b.height, 50);
}

TEST(SceneFile, RotationVectorGivesTheCameraOrientation) {
  // Half a turn about +y: the camera at z = 1200 looks back along -z.
  const Scene scene = parse_scene(R"({ "format": 1,
    "cameras": [ { "resolution_px": [640, 480], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                   "position_mm": [0, 0, 1200], "rotation_vector_deg": [0, 180, 0] } ],
    "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} } ] })",
                                  "s.json");
  const Camera& camera = scene.cameras[0];
  EXPECT_NEAR(distance(camera.center(), Point3(0, 0, 1200)), 0.0, 1e-12);
  const UnitVector3 forward = camera.world_from_camera().rotation().column(2);
  EXPECT_NEAR(forward.z(), -1.0, 1e-12);
  const UnitVector3 right = camera.world_from_camera().rotation().column(0);
  EXPECT_NEAR(right.x(), -1.0, 1e-12);
}

TEST(SceneFile, LookAtPointsTheCameraAtTheTarget) {
  const Scene scene = parse_scene(R"({ "format": 1,
    "cameras": [ { "resolution_px": [640, 480], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                   "position_mm": [0, 300, 0], "look_at_mm": [0, 0, 400] } ],
    "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} } ] })",
                                  "s.json");
  // (0, -300, 400) / 500, a 3-4-5 triangle.
  const UnitVector3 forward = scene.cameras[0].world_from_camera().rotation().column(2);
  EXPECT_NEAR(forward.x(), 0.0, 1e-12);
  EXPECT_NEAR(forward.y(), -0.6, 1e-12);
  EXPECT_NEAR(forward.z(), 0.8, 1e-12);
}

TEST(SceneFile, GazeTargetPutsTheVisualAxisThroughTheTarget) {
  const Point3 target{100, -150, 0};
  for (const char* anchor : {"cornea_center_mm", "rotation_center_mm"}) {
    const Scene scene = parse_scene(
        scene_with_eye(std::string(R"({ "model": "navarro", "position": { ")") + anchor +
                       R"(": [0, 0, 600] }, "orientation": { "gaze_target_mm": [100, -150, 0] } })"),
        "s.json");
    const Eye& eye = scene.eyes[0];
    // The visual axis leaves the cornea centre toward the target.
    EXPECT_LT(angle_between(eye.visual_axis(), target - eye.cornea_center()), 1e-9) << anchor;
    // Navarro's kappa is not zero: the optical axis misses the target.
    EXPECT_GT(angle_between(eye.optical_axis(), target - eye.cornea_center()), 4 * kDegree);
  }
}

TEST(SceneFile, NoneRemovesThePosteriorCornea) {
  const Scene scene = parse_scene(
      scene_with_eye(R"({ "model": "navarro", "posterior_cornea": "none",
                          "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} })"),
      "s.json");
  EXPECT_FALSE(scene.eyes[0].model().posterior_cornea.has_value());
  EXPECT_DOUBLE_EQ(scene.eyes[0].model().anterior_cornea.asphericity, -0.26);  // still Navarro's
}

TEST(SceneFile, PosteriorCorneaCanBeAddedToAOneSurfaceEye) {
  const Scene scene = parse_scene(
      scene_with_eye(R"({ "model": "keratometric", "posterior_cornea": { "thickness_mm": 0.6 },
                          "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} })"),
      "s.json");
  ASSERT_TRUE(scene.eyes[0].model().posterior_cornea.has_value());
  EXPECT_DOUBLE_EQ(scene.eyes[0].model().posterior_cornea->thickness_mm, 0.6);
  EXPECT_DOUBLE_EQ(scene.eyes[0].model().posterior_cornea->surface.radius_mm,
                   PosteriorCornea{}.surface.radius_mm);
}

// ------------------------------------------------------ sensor

// A minimal valid scene whose one camera is `camera`.
std::string scene_with_camera(const std::string& camera) {
  return R"({ "format": 1, "cameras": [ )" + camera + R"( ],
    "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} } ] })";
}

// A camera by focal length (16 mm, 6 um pixels) with the given sensor block.
std::string camera_with_sensor(const std::string& sensor) {
  return scene_with_camera(R"({ "resolution_px": [640, 480], "focal_length_mm": 16,
      "pixel_pitch_mm": 0.006, "sensor": )" + sensor + R"(,
      "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] })");
}

TEST(SceneFile, ReadsEverySensorKey) {
  const Scene scene = parse_scene(camera_with_sensor(R"({
      "f_number": 1.4, "exposure_s": 0.0025, "quantum_efficiency": 0.45, "full_well_e": 20000,
      "read_noise_e": 2.5, "gain": 4, "bits": 12, "psf_sigma_px": 1.25,
      "focus_distance_mm": 550, "noise": false })"),
                                  "s.json");
  const Sensor& sensor = scene.cameras[0].sensor();
  EXPECT_DOUBLE_EQ(sensor.pixel_pitch_mm, 0.006);  // the camera's own
  EXPECT_DOUBLE_EQ(sensor.f_number, 1.4);
  EXPECT_DOUBLE_EQ(sensor.exposure_s, 0.0025);
  EXPECT_DOUBLE_EQ(sensor.quantum_efficiency, 0.45);
  EXPECT_DOUBLE_EQ(sensor.full_well_e, 20000);
  EXPECT_DOUBLE_EQ(sensor.read_noise_e, 2.5);
  EXPECT_DOUBLE_EQ(sensor.gain, 4);
  EXPECT_EQ(sensor.bits, 12);
  EXPECT_DOUBLE_EQ(sensor.psf_sigma_px, 1.25);
  ASSERT_TRUE(sensor.focus_distance_mm.has_value());
  EXPECT_DOUBLE_EQ(*sensor.focus_distance_mm, 550);
  EXPECT_FALSE(sensor.noise);
  EXPECT_NEAR(scene.cameras[0].focal_length_mm(), 16, 1e-12);
}

TEST(SceneFile, ReadsTheSensorsRealismKeysAndWritesThemOnlyWhenSet) {
  const Scene scene = parse_scene(camera_with_sensor(R"({ "corner_illumination": 0.6,
      "hot_pixel_fraction": 0.0005, "hot_pixel_e_per_s": 3e5, "hot_pixel_seed": 9007199254740991,
      "jpeg_quality": 70 })"),
                                  "s.json");
  const Sensor& sensor = scene.cameras[0].sensor();
  EXPECT_EQ(sensor.corner_illumination, 0.6);
  EXPECT_EQ(sensor.hot_pixel_fraction, 0.0005);
  EXPECT_EQ(sensor.hot_pixel_e_per_s, 3e5);
  EXPECT_EQ(sensor.hot_pixel_seed, (std::uint64_t{1} << 53) - 1);
  EXPECT_EQ(sensor.jpeg_quality, 70);
  const Sensor back = parse_scene(scene_to_json(scene), "back.json").cameras[0].sensor();
  EXPECT_EQ(back.corner_illumination, 0.6);
  EXPECT_EQ(back.hot_pixel_fraction, 0.0005);
  EXPECT_EQ(back.hot_pixel_e_per_s, 3e5);
  EXPECT_EQ(back.hot_pixel_seed, (std::uint64_t{1} << 53) - 1);
  EXPECT_EQ(back.jpeg_quality, 70);
  // A scene without them writes none of them (its file reads as before).
  const std::string plain = scene_to_json(parse_scene(camera_with_sensor("{}"), "s.json"));
  for (const char* key : {"corner_illumination", "hot_pixel", "jpeg_quality"}) {
    EXPECT_EQ(plain.find(key), std::string::npos) << key;
  }
}

TEST(SceneFile, AnEyesMotionIsReadAndWrittenOnlyWhenItMoves) {
  const auto eye_with = [](const std::string& motion) {
    return R"({ "format": 1, "cameras": [ { "resolution_px": [640, 480], "focal_length_mm": 16,
        "pixel_pitch_mm": 0.006, "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] } ],
      "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} )" + motion + " } ] }";
  };
  const Scene scene = parse_scene(eye_with(R"(, "motion": { "yaw_deg_s": 450, "pitch_deg_s": -1000 })"), "s.json");
  EXPECT_EQ(scene.eyes[0].motion().yaw_deg_s, 450);
  EXPECT_EQ(scene.eyes[0].motion().pitch_deg_s, -1000);
  const Eye back = parse_scene(scene_to_json(scene), "back.json").eyes[0];
  EXPECT_EQ(back.motion().yaw_deg_s, 450);
  EXPECT_EQ(back.motion().pitch_deg_s, -1000);
  EXPECT_EQ(parse_scene(eye_with(R"(, "motion": { "pitch_deg_s": 20 })"), "s.json").eyes[0].motion().yaw_deg_s, 0);
  const Scene still = parse_scene(eye_with(""), "s.json");
  EXPECT_TRUE(still.eyes[0].motion().still());
  EXPECT_EQ(scene_to_json(still).find("motion"), std::string::npos);
  EXPECT_NE(parse_error(eye_with(R"(, "motion": { "yaw_deg_s": 1500 })")).find(
                "eyes[0].motion.yaw_deg_s = 1500: must be between -1000 and 1000"),
            std::string::npos);
  EXPECT_NE(parse_error(eye_with(R"(, "motion": { "yaw_rate": 10 })")).find("eyes[0].motion.yaw_rate = 10: unknown key"),
            std::string::npos);
}

TEST(SceneFile, WithoutASensorBlockTheCameraHasTheDocumentedDefaults) {
  // The values of the table in docs/scene-format.md, not Sensor{}'s: a
  // changed default must be documented.
  const Scene scene = parse_scene(scene_with_camera(R"({ "resolution_px": [640, 480],
      "focal_length_mm": 12, "pixel_pitch_mm": 0.003,
      "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] })"),
                                  "s.json");
  const Sensor& sensor = scene.cameras[0].sensor();
  EXPECT_DOUBLE_EQ(sensor.pixel_pitch_mm, 0.003);  // the camera's pitch is the sensor's
  EXPECT_NEAR(scene.cameras[0].focal_length_mm(), 12, 1e-12);
  EXPECT_EQ(sensor.f_number, 2.8);
  EXPECT_EQ(sensor.exposure_s, 0.004);
  EXPECT_EQ(sensor.quantum_efficiency, 0.3);
  EXPECT_EQ(sensor.full_well_e, 10000);
  EXPECT_EQ(sensor.read_noise_e, 4);
  EXPECT_EQ(sensor.gain, 1);
  EXPECT_EQ(sensor.bits, 8);
  EXPECT_EQ(sensor.psf_sigma_px, 0.5);
  EXPECT_FALSE(sensor.focus_distance_mm.has_value());
  EXPECT_TRUE(sensor.noise);
  EXPECT_EQ(sensor.corner_illumination, 1);
  EXPECT_EQ(sensor.hot_pixel_fraction, 0);
  EXPECT_EQ(sensor.hot_pixel_e_per_s, 2e6);
  EXPECT_EQ(sensor.hot_pixel_seed, 1u);
  EXPECT_FALSE(sensor.jpeg_quality.has_value());
}

TEST(SceneFile, SensorPitchWithPixelIntrinsicsGivesTheFocalLengthInMm) {
  const Scene scene = parse_scene(scene_with_camera(R"({ "resolution_px": [640, 480],
      "intrinsics_px": { "fx": 2000, "fy": 2000 }, "sensor": { "pixel_pitch_mm": 0.004 },
      "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] })"),
                                  "s.json");
  EXPECT_DOUBLE_EQ(scene.cameras[0].sensor().pixel_pitch_mm, 0.004);
  EXPECT_NEAR(scene.cameras[0].focal_length_mm(), 8, 1e-12);  // 2000 px x 4 um
  EXPECT_EQ(scene.cameras[0].intrinsics().fx, 2000);           // untouched by the pitch
}

TEST(SceneFile, SensorRangesAreInclusiveWhereDocumented) {
  for (const char* ok : {R"({ "quantum_efficiency": 1 })", R"({ "read_noise_e": 0 })",
                         R"({ "psf_sigma_px": 0 })", R"({ "psf_sigma_px": 20 })",
                         R"({ "bits": 8 })", R"({ "bits": 10 })", R"({ "bits": 16 })",
                         R"({ "focus_distance_mm": 16.001 })", R"({ "corner_illumination": 1 })",
                         R"({ "hot_pixel_fraction": 0.01 })", R"({ "hot_pixel_e_per_s": 0 })",
                         R"({ "jpeg_quality": 1 })", R"({ "jpeg_quality": 100 })", R"({})"}) {
    EXPECT_EQ(parse_error(camera_with_sensor(ok)), "") << ok;
  }
  const std::map<std::string, std::string> bad = {
      {R"({ "quantum_efficiency": 0 })", "sensor.quantum_efficiency = 0: must be > 0 and <= 1"},
      {R"({ "exposure_s": 0 })", "sensor.exposure_s = 0: must be > 0"},
      {R"({ "full_well_e": -5 })", "sensor.full_well_e = -5: must be > 0"},
      {R"({ "gain": 0 })", "sensor.gain = 0: must be > 0"},
      {R"({ "bits": 8.5 })", "sensor.bits = 8.5: must be an integer"},
      {R"({ "bits": 0 })", "sensor.bits = 0: must be one of 8, 10, 12, 16"},
      {R"({ "psf_sigma_px": -0.1 })", "sensor.psf_sigma_px = -0.1: must be between 0 and 20"},
      // Exactly at the focal length the thin lens images at infinity.
      {R"({ "focus_distance_mm": 16 })", "sensor.focus_distance_mm = 16: must be > the focal length (16 mm)"},
      {R"({ "focus_distance_mm": -600 })", "sensor.focus_distance_mm = -600: must be > the focal length"},
      {R"({ "noise": 1 })", "sensor.noise = 1: must be true or false"},
      {R"([])", "cameras[0].sensor = []: must be an object"},
      {R"({ "corner_illumination": 0 })", "sensor.corner_illumination = 0: must be > 0 and <= 1"},
      {R"({ "corner_illumination": 1.2 })", "sensor.corner_illumination = 1.2: must be > 0 and <= 1"},
      {R"({ "hot_pixel_fraction": 0.02 })", "sensor.hot_pixel_fraction = 0.02: must be between 0 and 0.01"},
      {R"({ "hot_pixel_e_per_s": -1 })", "sensor.hot_pixel_e_per_s = -1: must be >= 0"},
      {R"({ "hot_pixel_seed": -1 })", "sensor.hot_pixel_seed = -1: must be >= 0"},
      {R"({ "jpeg_quality": 0 })", "sensor.jpeg_quality = 0: must be an integer from 1 to 100"},
      {R"({ "jpeg_quality": 75.5 })", "sensor.jpeg_quality = 75.5: must be an integer"},
      {R"({ "bits": 10, "jpeg_quality": 75 })", "sensor.jpeg_quality = 75: needs 8-bit images (bits = 10)"},
  };
  for (const auto& [sensor, expected] : bad) {
    const std::string message = parse_error(camera_with_sensor(sensor));
    EXPECT_NE(message.find(expected), std::string::npos) << sensor << "\n  message: " << message;
  }
}

TEST(SceneFile, FocusIsCheckedAgainstTheFocalLengthFromPixelIntrinsics) {
  // fx = 2500 px at 4 um: 10 mm. 9.9 mm is inside it, 10.1 mm outside.
  const auto camera = [](const std::string& focus) {
    return scene_with_camera(R"({ "resolution_px": [640, 480], "intrinsics_px": { "fx": 2500, "fy": 2500 },
        "sensor": { "pixel_pitch_mm": 0.004, "focus_distance_mm": )" + focus + R"( },
        "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] })");
  };
  EXPECT_EQ(parse_error(camera("10.1")), "");
  EXPECT_EQ(parse_error(camera("9.9")),
            "scene.json: cameras[0].sensor.focus_distance_mm = 9.9: must be > the focal length (10 mm)");
}

TEST(SceneFile, PixelPitchBesidePixelIntrinsicsPointsToTheSensorKey) {
  const std::string message = parse_error(scene_with_camera(R"({ "resolution_px": [640, 480],
      "intrinsics_px": { "fx": 2000, "fy": 2000 }, "pixel_pitch_mm": 0.004,
      "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] })"));
  EXPECT_EQ(message, "scene.json: cameras[0].pixel_pitch_mm = 0.004: not used with intrinsics_px "
                     "(give focal_length_mm, or sensor.pixel_pitch_mm)");
}

// --------------------------------------------------- appearance and lids

// A minimal eye at 600 mm with `extra` keys appended.
std::string eye_with(const std::string& extra) {
  return scene_with_eye(R"({ "position": { "rotation_center_mm": [0, 0, 600] }, "orientation": {}, )" +
                        extra + " }");
}

TEST(SceneFile, ReadsEveryAppearanceKey) {
  const Scene scene = parse_scene(eye_with(R"("appearance": {
      "iris_albedo": 0.15, "iris_texture_contrast": 0.8, "iris_seed": 9007199254740991,
      "sclera_albedo": 0.7, "skin_albedo": 0.35, "fundus_reflectance": 0.6 })"),
                                  "s.json");
  const EyeAppearance& a = scene.eyes[0].appearance();
  EXPECT_DOUBLE_EQ(a.iris_albedo, 0.15);
  EXPECT_DOUBLE_EQ(a.iris_texture_contrast, 0.8);
  EXPECT_EQ(a.iris_seed, 9007199254740991u);  // 2^53 - 1, the largest allowed, exactly
  EXPECT_DOUBLE_EQ(a.sclera_albedo, 0.7);
  EXPECT_DOUBLE_EQ(a.skin_albedo, 0.35);
  EXPECT_DOUBLE_EQ(a.fundus_reflectance, 0.6);
  EXPECT_FALSE(a.eyelids.has_value());  // appearance alone adds no lids
}

TEST(SceneFile, WithoutAppearanceKeysTheEyeHasTheDocumentedDefaults) {
  const Scene scene = parse_scene(eye_with(R"("appearance": {})"), "s.json");
  const EyeAppearance& a = scene.eyes[0].appearance();
  EXPECT_EQ(a.iris_albedo, 0.25);
  EXPECT_EQ(a.iris_texture_contrast, 0.5);
  EXPECT_EQ(a.iris_seed, 1u);
  EXPECT_EQ(a.sclera_albedo, 0.55);
  EXPECT_EQ(a.skin_albedo, 0.45);
  EXPECT_EQ(a.fundus_reflectance, 0.05);
  EXPECT_EQ(a.head_forward.vector(), Vector3(0, 0, -1));
  EXPECT_EQ(a.head_up.vector(), Vector3(0, -1, 0));
  EXPECT_FALSE(a.eyelids.has_value());
}

TEST(SceneFile, AppearanceBoundsAndSeedSpellings) {
  // Bounds are inclusive; a whole number written as 42.0 or 4.2e1 is still an integer.
  EXPECT_EQ(parse_error(eye_with(R"("appearance": { "iris_albedo": 0, "sclera_albedo": 1,
      "iris_texture_contrast": 0, "fundus_reflectance": 1, "skin_albedo": 1, "iris_seed": 0 })")),
            "");
  for (const char* seed : {"42.0", "4.2e1"}) {
    const Scene scene =
        parse_scene(eye_with(std::string(R"("appearance": { "iris_seed": )") + seed + " }"), "s.json");
    EXPECT_EQ(scene.eyes[0].appearance().iris_seed, 42u) << seed;
  }
  const std::map<std::string, std::string> bad = {
      {R"({ "iris_seed": 1.5 })", "appearance.iris_seed = 1.5: must be an integer"},
      {R"({ "iris_seed": -0.5 })", "appearance.iris_seed = -0.5: must be an integer"},
      {R"({ "iris_seed": -1 })", "appearance.iris_seed = -1: must be >= 0"},
      {R"({ "iris_seed": 1e16 })", "appearance.iris_seed = 1e+16: must be < 2^53"},
      {R"({ "iris_seed": 18446744073709551615 })", "must be < 2^53"},
      {R"({ "iris_seed": "7" })", "appearance.iris_seed = \"7\": must be a number"},
      {R"({ "sclera_albedo": -0.01 })", "appearance.sclera_albedo = -0.01: must be between 0 and 1"},
      {R"({ "fundus_reflectance": 1.01 })", "appearance.fundus_reflectance = 1.01: must be between 0 and 1"},
      {R"({ "iris_albedo_nm": 0.2 })", "appearance.iris_albedo_nm = 0.2: unknown key"},
  };
  for (const auto& [appearance, expected] : bad) {
    const std::string message = parse_error(eye_with(R"("appearance": )" + appearance));
    EXPECT_NE(message.find(expected), std::string::npos) << appearance << "\n  message: " << message;
  }
}

TEST(SceneFile, EmptyEyelidsObjectTurnsOnLidsWithTheDocumentedDefaults) {
  const Scene scene = parse_scene(eye_with(R"("eyelids": {})"), "s.json");
  const EyeAppearance& a = scene.eyes[0].appearance();
  ASSERT_TRUE(a.eyelids.has_value());
  EXPECT_EQ(a.eyelids->opening, 1.0);
  EXPECT_EQ(a.eyelids->upper_margin_mm, 4.5);
  EXPECT_EQ(a.eyelids->lower_margin_mm, -5.5);
  EXPECT_EQ(a.eyelids->closing_line_mm, -1.0);
  EXPECT_EQ(a.eyelids->half_width_mm, 15.0);
  EXPECT_EQ(a.eyelids->upper_gain_upgaze, 1.0);
  EXPECT_EQ(a.eyelids->upper_gain_downgaze, 1.0);
  EXPECT_EQ(a.eyelids->lower_gain_upgaze, 0.0);
  EXPECT_EQ(a.eyelids->lower_gain_downgaze, 0.6);
  // The other appearance keys keep their defaults.
  EXPECT_EQ(a.skin_albedo, 0.45);
}

TEST(SceneFile, ReadsEveryEyelidKey) {
  const Scene scene = parse_scene(eye_with(R"("eyelids": { "opening": 0.25, "upper_margin_mm": 6,
      "lower_margin_mm": -4, "closing_line_mm": 0.5, "half_width_mm": 12.5, "upper_gain_upgaze": 0.9,
      "upper_gain_downgaze": 1.1, "lower_gain_upgaze": 0.2, "lower_gain_downgaze": 0 })"),
                                  "s.json");
  const Eyelids& lids = *scene.eyes[0].appearance().eyelids;
  EXPECT_DOUBLE_EQ(lids.opening, 0.25);
  EXPECT_DOUBLE_EQ(lids.upper_margin_mm, 6);
  EXPECT_DOUBLE_EQ(lids.lower_margin_mm, -4);
  EXPECT_DOUBLE_EQ(lids.closing_line_mm, 0.5);
  EXPECT_DOUBLE_EQ(lids.half_width_mm, 12.5);
  EXPECT_DOUBLE_EQ(lids.upper_gain_upgaze, 0.9);
  EXPECT_DOUBLE_EQ(lids.upper_gain_downgaze, 1.1);
  EXPECT_DOUBLE_EQ(lids.lower_gain_upgaze, 0.2);
  EXPECT_DOUBLE_EQ(lids.lower_gain_downgaze, 0.0);
}

TEST(SceneFile, EyelidHeightsMustCloseBetweenTheMargins) {
  // Fully closed (opening 0) is a valid eye.
  EXPECT_EQ(parse_error(eye_with(R"("eyelids": { "opening": 0 })")), "");
  // The key blamed is the one written; with only the closing line written,
  // the closing line.
  const std::map<std::string, std::string> bad = {
      {R"({ "upper_margin_mm": -1 })", "eyes[0].eyelids.upper_margin_mm = -1: must be > closing_line_mm (-1)"},
      {R"({ "closing_line_mm": 5 })", "eyes[0].eyelids.closing_line_mm = 5: must be < upper_margin_mm (4.5)"},
      {R"({ "closing_line_mm": -6 })", "eyes[0].eyelids.closing_line_mm = -6: must be > lower_margin_mm (-5.5)"},
      {R"({ "lower_margin_mm": -1 })", "eyes[0].eyelids.lower_margin_mm = -1: must be < closing_line_mm (-1)"},
      {R"({ "opening": -0.1 })", "eyes[0].eyelids.opening = -0.1: must be between 0 and 1"},
      {R"({ "half_width_mm": -3 })", "eyes[0].eyelids.half_width_mm = -3: must be > 0"},
      {R"({ "upper_margin_mm": "4.5" })", "eyes[0].eyelids.upper_margin_mm = \"4.5\": must be a number"},
      {R"({ "open": 1 })", "eyes[0].eyelids.open = 1: unknown key"},
      {R"({ "upper_gain_upgaze": -0.1 })", "eyes[0].eyelids.upper_gain_upgaze = -0.1: must be between 0 and 2"},
      {R"({ "upper_gain_downgaze": 2.5 })", "eyes[0].eyelids.upper_gain_downgaze = 2.5: must be between 0 and 2"},
      {R"({ "lower_gain_upgaze": null })", "eyes[0].eyelids.lower_gain_upgaze = null: must be a number"},
      {R"({ "lower_gain_downgaze": "0.6" })", "eyes[0].eyelids.lower_gain_downgaze = \"0.6\": must be a number"},
  };
  for (const auto& [lids, expected] : bad) {
    EXPECT_EQ(parse_error(eye_with(R"("eyelids": )" + lids)).find("scene.json: " + expected), 0u)
        << lids << "\n  message: " << parse_error(eye_with(R"("eyelids": )" + lids));
  }
}

TEST(SceneFile, ReadsEveryFaceKeyAndWritesThemBack) {
  const Scene scene = parse_scene(eye_with(R"("eyelids": {}, "face": { "side": "left", "margin_thickness_mm": 2.2,
      "crease_height_mm": 0, "crease_depth_mm": 1.1, "canthal_tilt_deg": -3, "lateral_canthus_mm": 10.5,
      "brow_prominence_mm": -2, "midline_mm": 33 })"),
                                  "s.json");
  const Face& f = *scene.eyes[0].appearance().face;
  EXPECT_EQ(f.side, EyeSide::left);
  EXPECT_DOUBLE_EQ(f.margin_thickness_mm, 2.2);
  EXPECT_DOUBLE_EQ(f.crease_height_mm, 0);
  EXPECT_DOUBLE_EQ(f.crease_depth_mm, 1.1);
  EXPECT_DOUBLE_EQ(f.canthal_tilt_deg, -3);
  EXPECT_DOUBLE_EQ(f.lateral_canthus_mm, 10.5);
  EXPECT_DOUBLE_EQ(f.brow_prominence_mm, -2);
  EXPECT_DOUBLE_EQ(f.midline_mm, 33);
  const Face back = *parse_scene(scene_to_json(scene), "back.json").eyes[0].appearance().face;
  EXPECT_EQ(back.side, f.side);
  EXPECT_EQ(back.margin_thickness_mm, f.margin_thickness_mm);
  EXPECT_EQ(back.crease_height_mm, f.crease_height_mm);
  EXPECT_EQ(back.crease_depth_mm, f.crease_depth_mm);
  EXPECT_EQ(back.canthal_tilt_deg, f.canthal_tilt_deg);
  EXPECT_EQ(back.lateral_canthus_mm, f.lateral_canthus_mm);
  EXPECT_EQ(back.brow_prominence_mm, f.brow_prominence_mm);
  EXPECT_EQ(back.midline_mm, f.midline_mm);
  // Without "face" the lids keep their sphere.
  EXPECT_FALSE(parse_scene(eye_with(R"("eyelids": {})"), "s.json").eyes[0].appearance().face.has_value());
}

TEST(SceneFile, FaceErrorsNameTheKeyAndTheRule) {
  EXPECT_EQ(parse_error(eye_with(R"("face": {})")).find("scene.json: eyes[0].face"), 0u)
      << parse_error(eye_with(R"("face": {})"));
  EXPECT_NE(parse_error(eye_with(R"("face": {})")).find("only used with eyelids"), std::string::npos);
  const std::map<std::string, std::string> bad = {
      {R"({ "side": "up" })", "eyes[0].face.side = \"up\": must be \"right\" or \"left\""},
      {R"({ "margin_thickness_mm": 0.1 })", "eyes[0].face.margin_thickness_mm = 0.1: must be between 0.5 and 4"},
      {R"({ "lateral_canthus_mm": 25 })", "eyes[0].face.lateral_canthus_mm = 25: must be between 5 and 20"},
      {R"({ "canthal_tilt_deg": 30 })", "eyes[0].face.canthal_tilt_deg = 30: must be between -15 and 15"},
      {R"({ "nose": 1 })", "eyes[0].face.nose = 1: unknown key"},
  };
  for (const auto& [face, expected] : bad) {
    const std::string error = parse_error(eye_with(R"("eyelids": {}, "face": )" + face));
    EXPECT_EQ(error.find("scene.json: " + expected), 0u) << face << "\n  message: " << error;
  }
}

TEST(SceneFile, ReadsEveryLashKeyAndWritesThemBack) {
  const Scene scene = parse_scene(eye_with(R"("eyelids": {}, "face": { "lashes": { "upper_per_mm": 3.5,
      "lower_per_mm": 0, "upper_length_mm": 11, "lower_length_mm": 7.5, "upper_curl_deg": 60, "lower_curl_deg": 10,
      "root_deg": 35, "thickness_mm": 0.12, "albedo": 0.03, "seed": 9007199254740991 } })"),
                                  "s.json");
  const Lashes& l = *scene.eyes[0].appearance().face->lashes;
  EXPECT_DOUBLE_EQ(l.upper_per_mm, 3.5);
  EXPECT_DOUBLE_EQ(l.lower_per_mm, 0);
  EXPECT_DOUBLE_EQ(l.upper_length_mm, 11);
  EXPECT_DOUBLE_EQ(l.lower_length_mm, 7.5);
  EXPECT_DOUBLE_EQ(l.upper_curl_deg, 60);
  EXPECT_DOUBLE_EQ(l.lower_curl_deg, 10);
  EXPECT_DOUBLE_EQ(l.root_deg, 35);
  EXPECT_DOUBLE_EQ(l.thickness_mm, 0.12);
  EXPECT_DOUBLE_EQ(l.albedo, 0.03);
  EXPECT_EQ(l.seed, 9007199254740991u);  // the largest seed a scene file takes (2^53 - 1)
  const Lashes back = *parse_scene(scene_to_json(scene), "back.json").eyes[0].appearance().face->lashes;
  for (const LashKey& key : kLashKeys) EXPECT_EQ(back.*key.member, l.*key.member) << key.name;
  EXPECT_EQ(back.seed, l.seed);
  // "lashes": {} is every default; without it, none.
  const Scene defaults = parse_scene(eye_with(R"("eyelids": {}, "face": { "lashes": {} })"), "s.json");
  EXPECT_EQ(defaults.eyes[0].appearance().face->lashes->upper_length_mm, Lashes{}.upper_length_mm);
  EXPECT_FALSE(parse_scene(eye_with(R"("eyelids": {}, "face": {})"), "s.json").eyes[0].appearance().face->lashes);
}

TEST(SceneFile, LashErrorsNameTheKeyAndTheRule) {
  const std::map<std::string, std::string> bad = {
      {R"({ "upper_per_mm": 11 })", "eyes[0].face.lashes.upper_per_mm = 11: must be between 0 and 10"},
      {R"({ "thickness_mm": 0 })", "eyes[0].face.lashes.thickness_mm = 0: must be between 0.02 and 0.3"},
      {R"({ "upper_curl_deg": -10 })", "eyes[0].face.lashes.upper_curl_deg = -10: must be between 0 and 120"},
      {R"({ "root_deg": 50 })", "eyes[0].face.lashes.root_deg = 50: must be between -45 and 40"},
      {R"({ "seed": -1 })", "eyes[0].face.lashes.seed = -1"},
      {R"({ "colour": 1 })", "eyes[0].face.lashes.colour = 1: unknown key"},
  };
  for (const auto& [lashes, expected] : bad) {
    const std::string error = parse_error(eye_with(R"("eyelids": {}, "face": { "lashes": )" + lashes + " }"));
    EXPECT_EQ(error.find("scene.json: " + expected), 0u) << lashes << "\n  message: " << error;
  }
}

TEST(SceneFile, ReadsEveryBrowKeyAndWritesThemBack) {
  const Scene scene = parse_scene(eye_with(R"("eyelids": {}, "face": { "brows": { "hairs_per_mm2": 2.5,
      "height_mm": 18, "width_mm": 7, "hair_length_mm": 9, "thickness_mm": 0.06, "lift_deg": 30, "curl_deg": 10,
      "albedo": 0.2, "seed": 5 } })"),
                                  "s.json");
  const Brows& b = *scene.eyes[0].appearance().face->brows;
  EXPECT_DOUBLE_EQ(b.hairs_per_mm2, 2.5);
  EXPECT_DOUBLE_EQ(b.height_mm, 18);
  EXPECT_DOUBLE_EQ(b.width_mm, 7);
  EXPECT_DOUBLE_EQ(b.hair_length_mm, 9);
  EXPECT_DOUBLE_EQ(b.thickness_mm, 0.06);
  EXPECT_DOUBLE_EQ(b.lift_deg, 30);
  EXPECT_DOUBLE_EQ(b.curl_deg, 10);
  EXPECT_DOUBLE_EQ(b.albedo, 0.2);
  EXPECT_EQ(b.seed, 5u);
  const Brows back = *parse_scene(scene_to_json(scene), "back.json").eyes[0].appearance().face->brows;
  for (const BrowKey& key : kBrowKeys) EXPECT_EQ(back.*key.member, b.*key.member) << key.name;
  EXPECT_EQ(back.seed, b.seed);
  // "brows": {} is every default; without it, none.
  const Scene defaults = parse_scene(eye_with(R"("eyelids": {}, "face": { "brows": {} })"), "s.json");
  EXPECT_EQ(defaults.eyes[0].appearance().face->brows->hair_length_mm, Brows{}.hair_length_mm);
  EXPECT_FALSE(parse_scene(eye_with(R"("eyelids": {}, "face": {})"), "s.json").eyes[0].appearance().face->brows);
  // Errors name the key and the rule.
  const std::map<std::string, std::string> bad = {
      {R"({ "hairs_per_mm2": 7 })", "eyes[0].face.brows.hairs_per_mm2 = 7: must be between 0 and 6"},
      {R"({ "lift_deg": 2 })", "eyes[0].face.brows.lift_deg = 2: must be between 5 and 60"},
      {R"({ "seed": 0.5 })", "eyes[0].face.brows.seed = 0.5"},
      {R"({ "colour": 1 })", "eyes[0].face.brows.colour = 1: unknown key"},
  };
  for (const auto& [brows, expected] : bad) {
    const std::string error = parse_error(eye_with(R"("eyelids": {}, "face": { "brows": )" + brows + " }"));
    EXPECT_EQ(error.find("scene.json: " + expected), 0u) << brows << "\n  message: " << error;
  }
}

TEST(SceneFile, ReadsTheTissueTexturesAndWritesThemBackOnlyWhenOn) {
  const Scene scene = parse_scene(
      eye_with(R"("appearance": { "skin_texture_contrast": 0.3, "sclera_vessel_contrast": 0.45 })"), "s.json");
  EXPECT_EQ(scene.eyes[0].appearance().skin_texture_contrast, 0.3);
  EXPECT_EQ(scene.eyes[0].appearance().sclera_vessel_contrast, 0.45);
  const Scene back = parse_scene(scene_to_json(scene), "back.json");
  EXPECT_EQ(back.eyes[0].appearance().skin_texture_contrast, 0.3);
  EXPECT_EQ(back.eyes[0].appearance().sclera_vessel_contrast, 0.45);
  const Scene plain = parse_scene(eye_with(R"("appearance": {})"), "s.json");
  EXPECT_EQ(plain.eyes[0].appearance().skin_texture_contrast, 0.0);
  EXPECT_EQ(scene_to_json(plain).find("skin_texture_contrast"), std::string::npos);
  EXPECT_EQ(scene_to_json(plain).find("vessel"), std::string::npos);
  EXPECT_EQ(parse_error(eye_with(R"("appearance": { "skin_texture_contrast": 1.5 })"))
                .find("scene.json: eyes[0].appearance.skin_texture_contrast = 1.5: must be between 0 and 1"),
            0u);
  EXPECT_EQ(parse_error(eye_with(R"("appearance": { "sclera_vessel_contrast": -0.1 })"))
                .find("scene.json: eyes[0].appearance.sclera_vessel_contrast = -0.1: must be between 0 and 1"),
            0u);
}

TEST(SceneFile, ReadsTheIrisFurrowsAndFrecklesAndWritesThemBackOnlyWhenOn) {
  const Scene scene =
      parse_scene(eye_with(R"("appearance": { "iris_furrow_contrast": 0.7, "iris_freckles": 12 })"), "s.json");
  EXPECT_EQ(scene.eyes[0].appearance().iris_furrow_contrast, 0.7);
  EXPECT_EQ(scene.eyes[0].appearance().iris_freckles, 12);
  const Scene back = parse_scene(scene_to_json(scene), "back.json");
  EXPECT_EQ(back.eyes[0].appearance().iris_furrow_contrast, 0.7);
  EXPECT_EQ(back.eyes[0].appearance().iris_freckles, 12);
  const Scene plain = parse_scene(eye_with(R"("appearance": {})"), "s.json");
  EXPECT_EQ(scene_to_json(plain).find("furrow"), std::string::npos);
  EXPECT_EQ(scene_to_json(plain).find("freckles"), std::string::npos);
  const std::map<std::string, std::string> bad = {
      {R"({ "iris_furrow_contrast": 2 })", "eyes[0].appearance.iris_furrow_contrast = 2: must be between 0 and 1"},
      {R"({ "iris_freckles": 21 })", "eyes[0].appearance.iris_freckles = 21: must be between 0 and 20"},
      {R"({ "iris_freckles": 2.5 })", "eyes[0].appearance.iris_freckles = 2.5: must be an integer"},
  };
  for (const auto& [appearance, expected] : bad) {
    const std::string error = parse_error(eye_with(R"("appearance": )" + appearance));
    EXPECT_EQ(error.find("scene.json: " + expected), 0u) << appearance << "\n  message: " << error;
  }
}

TEST(SceneFile, ReadsTheTearFilmAndWritesItBack) {
  const Scene scene = parse_scene(
      eye_with(R"("appearance": { "tear_film": { "sclera_roughness_deg": 3.5, "meniscus_radius_mm": 0.25,
                                                     "upper_meniscus_radius_mm": 0.2 } })"),
      "s.json");
  ASSERT_TRUE(scene.eyes[0].appearance().tear_film);
  EXPECT_EQ(scene.eyes[0].appearance().tear_film->sclera_roughness_deg, 3.5);
  EXPECT_EQ(scene.eyes[0].appearance().tear_film->meniscus_radius_mm, 0.25);
  EXPECT_EQ(scene.eyes[0].appearance().tear_film->upper_meniscus_radius_mm, 0.2);
  const Scene back = parse_scene(scene_to_json(scene), "back.json");
  ASSERT_TRUE(back.eyes[0].appearance().tear_film);
  EXPECT_EQ(back.eyes[0].appearance().tear_film->sclera_roughness_deg, 3.5);
  EXPECT_EQ(back.eyes[0].appearance().tear_film->meniscus_radius_mm, 0.25);
  EXPECT_EQ(back.eyes[0].appearance().tear_film->upper_meniscus_radius_mm, 0.2);
  // {} is every default; without it, a dry sclera, and none written.
  EXPECT_EQ(parse_scene(eye_with(R"("appearance": { "tear_film": {} })"), "s.json").eyes[0].appearance().tear_film->sclera_roughness_deg,
            TearFilm{}.sclera_roughness_deg);
  const Scene dry = parse_scene(eye_with(R"("appearance": {})"), "s.json");
  EXPECT_FALSE(dry.eyes[0].appearance().tear_film);
  EXPECT_EQ(scene_to_json(dry).find("tear_film"), std::string::npos);

  const std::map<std::string, std::string> bad = {
      {R"({ "sclera_roughness_deg": 11 })", "eyes[0].appearance.tear_film.sclera_roughness_deg = 11: must be between 0 and 10"},
      {R"({ "sclera_roughness_deg": -1 })", "eyes[0].appearance.tear_film.sclera_roughness_deg = -1: must be between 0 and 10"},
      {R"({ "meniscus": 1 })", "eyes[0].appearance.tear_film.meniscus = 1: unknown key"},
      {R"({ "meniscus_radius_mm": 1.5 })", "eyes[0].appearance.tear_film.meniscus_radius_mm = 1.5: must be between 0 and 1"},
      {R"({ "meniscus_radius_mm": -0.1 })", "eyes[0].appearance.tear_film.meniscus_radius_mm = -0.1: must be between 0 and 1"},
      {R"({ "upper_meniscus_radius_mm": 1.2 })", "eyes[0].appearance.tear_film.upper_meniscus_radius_mm = 1.2: must be between 0 and 1"},
      {R"(2)", "eyes[0].appearance.tear_film = 2: must be an object"},
  };
  for (const auto& [film, expected] : bad) {
    const std::string error = parse_error(eye_with(R"("appearance": { "tear_film": )" + film + " }"));
    EXPECT_EQ(error.find("scene.json: " + expected), 0u) << film << "\n  message: " << error;
  }
}

TEST(SceneFile, HeadFrameIsNormalizedWithUpMadePerpendicular) {
  // forward [0, 0, -2] -> (0, 0, -1); up [0, -1, -1] has 1 along forward,
  // which is removed: (0, -1, -1) - 1 x (0, 0, -1) = (0, -1, 0).
  {
    const Scene scene = parse_scene(
        eye_with(R"("eyelids": {}, "head": { "forward": [0, 0, -2], "up": [0, -1, -1] })"), "s.json");
    const EyeAppearance& a = scene.eyes[0].appearance();
    EXPECT_NEAR(a.head_forward.x(), 0, 1e-15);
    EXPECT_NEAR(a.head_forward.y(), 0, 1e-15);
    EXPECT_NEAR(a.head_forward.z(), -1, 1e-15);
    EXPECT_NEAR(a.head_up.x(), 0, 1e-15);
    EXPECT_NEAR(a.head_up.y(), -1, 1e-15);
    EXPECT_NEAR(a.head_up.z(), 0, 1e-15);
  }
  // A head turned 45 deg toward +x keeps the default up, already across it.
  {
    const Scene scene =
        parse_scene(eye_with(R"("eyelids": {}, "head": { "forward": [1, 0, -1] })"), "s.json");
    const EyeAppearance& a = scene.eyes[0].appearance();
    EXPECT_NEAR(a.head_forward.x(), std::sqrt(0.5), 1e-15);
    EXPECT_NEAR(a.head_forward.z(), -std::sqrt(0.5), 1e-15);
    EXPECT_NEAR(a.head_up.y(), -1, 1e-15);
  }
  // A head tilted back: forward up and out, up given as world up.
  {
    const Scene scene = parse_scene(
        eye_with(R"("eyelids": {}, "head": { "forward": [0, -3, -4], "up": [0, -1, 0] })"), "s.json");
    const EyeAppearance& a = scene.eyes[0].appearance();
    // f = (0, -0.6, -0.8); up - (up.f) f = (0, -1, 0) - 0.6 (0, -0.6, -0.8) = (0, -0.64, 0.48),
    // of length 0.8: (0, -0.8, 0.6).
    EXPECT_NEAR(a.head_up.y(), -0.8, 1e-15);
    EXPECT_NEAR(a.head_up.z(), 0.6, 1e-15);
    EXPECT_NEAR(dot(a.head_up, a.head_forward), 0, 1e-15);
  }
}

TEST(SceneFile, DegenerateHeadFramesAreRejected) {
  const std::map<std::string, std::string> bad = {
      // Forward along the default up, with no up given: say which up it meets.
      {R"({ "forward": [0, 2, 0] })",
       "eyes[0].head.forward = [0, 2, 0]: is parallel to the default head.up [0, -1, 0]: give \"up\""},
      {R"({ "up": [0, 0, 1] })", "eyes[0].head.up = [0, 0, 1]: must not be parallel to head.forward"},
      // Parallel to within a micro-radian counts as parallel.
      {R"({ "forward": [0, 0, -1], "up": [1e-9, 0, 1] })", "eyes[0].head.up = [1e-09, 0, 1]: must not be parallel"},
      {R"({ "up": [0, 0, 0] })", "eyes[0].head.up = [0, 0, 0]: must not be the zero vector"},
      {R"({ "forward": [0, 0] })", "eyes[0].head.forward = [0, 0]: must be an array of 3 numbers"},
      {R"({ "right": [1, 0, 0] })", "eyes[0].head.right = [1, 0, 0]: unknown key"},
  };
  for (const auto& [head, expected] : bad) {
    const std::string message = parse_error(eye_with(R"("eyelids": {}, "head": )" + head));
    EXPECT_EQ(message.find("scene.json: " + expected), 0u) << head << "\n  message: " << message;
  }
}

TEST(SceneFile, ErrorNamesTheFileThePathTheValueAndTheRule) {
  EXPECT_EQ(parse_error(scene_with_eye(R"({ "cornea": { "radius_mm": -7.8 },
                   "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} })")),
            "scene.json: eyes[0].cornea.radius_mm = -7.8: must be > 0");
}

TEST(SceneFile, UnknownKeyListsTheValidOnes) {
  const std::string message = parse_error(scene_with_eye(R"({ "pupil": { "radius": 2 },
                   "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} })"));
  EXPECT_NE(message.find("eyes[0].pupil.radius = 2: unknown key"), std::string::npos) << message;
  EXPECT_NE(message.find("decentration_mm"), std::string::npos) << message;
  EXPECT_NE(message.find("radius_mm"), std::string::npos) << message;
}

TEST(SceneFile, MisspeltRequiredKeyIsPointedOut) {
  const std::string message = parse_error(scene_with_eye(
      R"({ "position": { "cornea_centre_mm": [0, 0, 600] }, "orientation": {} })"));
  EXPECT_NE(message.find("eyes[0].position: missing required key"), std::string::npos) << message;
  EXPECT_NE(message.find("\"cornea_centre_mm\""), std::string::npos) << message;
}

TEST(SceneFile, SyntaxErrorGivesTheLine) {
  const std::string message = parse_error("{\n  \"format\": 1,\n  \"cameras\": [,]\n}");
  EXPECT_NE(message.find("scene.json: invalid JSON"), std::string::npos) << message;
  EXPECT_NE(message.find("line 3"), std::string::npos) << message;
}

TEST(SceneFile, MissingFileIsASceneErrorNamingIt) {
  const fs::path missing = kSourceDir / "tests/data/no_such_scene.json";
  try {
    load_scene(missing);
    FAIL() << "no exception";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find(missing.string()), std::string::npos) << e.what();
  }
}

TEST(SceneFile, DirectoryIsNotAScene) {
  EXPECT_THROW(load_scene(kSourceDir / "tests"), SceneError);
}

TEST(SceneFile, BundledRemoteSceneLoads) {
  const Scene scene = load_scene(kSourceDir / "assets/scenes/remote.json");
  // The sensor block spells out the defaults.
  const Sensor& sensor = scene.cameras.at(0).sensor();
  EXPECT_DOUBLE_EQ(sensor.pixel_pitch_mm, 0.006);
  EXPECT_EQ(sensor.f_number, 2.8);
  EXPECT_EQ(sensor.exposure_s, 0.004);
  EXPECT_EQ(sensor.bits, 8);
  EXPECT_TRUE(sensor.noise);
  EXPECT_FALSE(sensor.focus_distance_mm.has_value());
  EXPECT_NEAR(scene.cameras.at(0).focal_length_mm(), 16, 1e-12);
  const EyeAppearance& look = scene.eyes.at(0).appearance();
  EXPECT_EQ(look.iris_albedo, 0.2);
  EXPECT_TRUE(look.eyelids.has_value());
  EXPECT_EQ(scene.name, "remote");
  ASSERT_EQ(scene.cameras.size(), 1u);
  EXPECT_EQ(scene.cameras[0].intrinsics().width, 640);
  EXPECT_EQ(scene.cameras[0].intrinsics().height, 480);
  ASSERT_EQ(scene.illuminators.size(), 2u);
  EXPECT_NEAR(scene.illuminators[0].position.x, -100, 1e-12);
  EXPECT_NEAR(scene.illuminators[1].position.x, 100, 1e-12);
  ASSERT_EQ(scene.eyes.size(), 1u);
  EXPECT_NEAR(distance(scene.eyes[0].cornea_center(), scene.cameras[0].center()), 600, 1e-9);
}

TEST(SceneFile, BundledHeadsetSceneLoads) {
  const Scene scene = load_scene(kSourceDir / "assets/scenes/headset.json");
  EXPECT_EQ(scene.name, "headset");
  ASSERT_EQ(scene.cameras.size(), 1u);
  ASSERT_EQ(scene.eyes.size(), 1u);
  const Eye& eye = scene.eyes[0];
  EXPECT_TRUE(eye.appearance().eyelids.has_value());
  EXPECT_DOUBLE_EQ(scene.cameras[0].sensor().pixel_pitch_mm, 0.003);
  EXPECT_NEAR(scene.cameras[0].focal_length_mm(), 1.3, 1e-12);
  EXPECT_EQ(scene.cameras[0].sensor().bits, 8);
  // About 35 mm from camera to cornea.
  EXPECT_NEAR(distance(scene.cameras[0].center(), eye.corneal_apex()), 35, 1.0);
  // A ring of eight LEDs, 16 mm from the lens axis, 27.2 mm in front of the apex.
  ASSERT_EQ(scene.illuminators.size(), 8u);
  for (const Illuminator& led : scene.illuminators) {
    EXPECT_NEAR(std::hypot(led.position.x, led.position.y), 16, 1e-4) << led.name;
    EXPECT_NEAR(eye.corneal_apex().z - led.position.z, 27.2, 1e-9) << led.name;
  }
}

TEST(SceneFile, ExampleInTheFormatDocumentLoads) {
  std::ifstream in(kSourceDir / "docs/scene-format.md");
  ASSERT_TRUE(in) << "docs/scene-format.md";
  std::string text, line;
  bool inside = false;
  while (std::getline(in, line)) {
    if (line == "```jsonc") {
      inside = true;
    } else if (inside && line == "```") {
      break;
    } else if (inside) {
      text += line + "\n";
    }
  }
  ASSERT_FALSE(text.empty());
  const Scene scene = parse_scene(text, "scene-format.md");
  EXPECT_EQ(scene.name, "remote");
  EXPECT_EQ(scene.illuminators.size(), 2u);
  EXPECT_NEAR(distance(scene.eyes[0].rotation_center(), Point3(30, 0, 610)), 0.0, 1e-9);
  EXPECT_EQ(scene.cameras[0].sensor().bits, 10);
  EXPECT_EQ(scene.cameras[0].sensor().focus_distance_mm, 600.0);
  EXPECT_EQ(scene.eyes[0].appearance().iris_seed, 7u);
  ASSERT_TRUE(scene.eyes[0].appearance().eyelids.has_value());
  EXPECT_EQ(scene.eyes[0].appearance().eyelids->opening, 0.8);
}

// ------------------------------------------------------------ meshes

TEST(SceneFile, MeshIsFoundBesideTheSceneAndPlacedByScaleRotationAndPosition) {
  const Scene scene = load_scene(kSourceDir / "tests/data/mesh_scene.json");
  ASSERT_EQ(scene.meshes.size(), 1u);
  const Mesh& mesh = scene.meshes[0];
  EXPECT_EQ(mesh.name, "card");
  EXPECT_DOUBLE_EQ(mesh.albedo, 0.3);
  // The unit square, one quad: two triangles, in the file's order.
  ASSERT_EQ(mesh.vertices.size(), 4u);
  ASSERT_EQ(mesh.triangles.size(), 2u);
  EXPECT_EQ(mesh.triangles[0], (Triangle{0, 1, 2}));
  EXPECT_EQ(mesh.triangles[1], (Triangle{0, 2, 3}));
  // world = [10, 20, 30] + Rz(90 deg) (2 v); Rz(90) takes (x, y, z) to (-y, x, z).
  // (0,0,0) -> (10, 20, 30); (1,0,0) -> (0, 2, 0) -> (10, 22, 30);
  // (1,1,0) -> (-2, 2, 0) -> (8, 22, 30); (0,1,0) -> (-2, 0, 0) -> (8, 20, 30).
  const Point3 expected[] = {{10, 20, 30}, {10, 22, 30}, {8, 22, 30}, {8, 20, 30}};
  for (int i = 0; i < 4; ++i) {
    EXPECT_LT(distance(mesh.vertices[i], expected[i]), 1e-12) << "vertex " << i;
  }
}

// A scene around one mesh entry, read with `folder` for relative files.
std::string scene_with_mesh(const std::string& mesh) {
  return R"({ "format": 1,
    "cameras": [ { "resolution_px": [64, 48], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                   "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] } ],
    "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} } ],
    "meshes": [ )" + mesh + " ] }";
}

std::string mesh_error(const std::string& mesh, const fs::path& folder = kSourceDir / "tests/data") {
  try {
    parse_scene(scene_with_mesh(mesh), "scene.json", folder);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

// Found by fuzzing: a tiny scale rounded every vertex onto position_mm,
// and the scene kept triangles of zero area, whose plane the renderer
// cannot take (mesh.h promises none).
TEST(SceneFile, MeshTrianglesLeftWithoutAreaOncePlacedAreLeftOutOrRefused) {
  EXPECT_EQ(mesh_error(R"({ "file": "meshes/square.obj", "albedo": 0.5, "position_mm": [10, 20, 30],
                            "scale": 1e-300 })"),
            "scene.json: meshes[0].file = \"meshes/square.obj\": all 2 triangles have zero area once placed "
            "(scale 1e-300, position_mm [10, 20, 30]): check scale and position_mm");
  // Far from the origin a sliver rounds flat while a fat triangle keeps
  // its area: only the sliver is left out. (1e-11 mm across 1 mm: a sine
  // above 1e-12 in the file; added to y = 5e5 mm, whose doubles are
  // 5.8e-11 apart, it rounds away.)
  const fs::path dir = fs::path(::testing::TempDir()) / "mesh_rounding";
  fs::create_directories(dir);
  std::ofstream(dir / "two.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1e-11 0\nf 1 2 3\nf 1 2 4\n";
  const Scene near = parse_scene(scene_with_mesh(R"({ "file": "two.obj", "albedo": 0.5 })"), "scene.json", dir);
  EXPECT_EQ(near.meshes.at(0).triangles.size(), 2u);
  const Scene far = parse_scene(
      scene_with_mesh(R"({ "file": "two.obj", "albedo": 0.5, "position_mm": [0, 500000, 0] })"), "scene.json", dir);
  ASSERT_EQ(far.meshes.at(0).triangles.size(), 1u);
  EXPECT_EQ(far.meshes.at(0).triangles[0], (Triangle{0, 1, 2}));
}

TEST(SceneFile, MeshDefaultsAreNoTurnNoShiftUnitScaleAndANumberedName) {
  const Scene scene = parse_scene(scene_with_mesh(R"({ "file": "meshes/square.obj", "albedo": 0 })"),
                                  "scene.json", kSourceDir / "tests/data");
  const Mesh& mesh = scene.meshes.at(0);
  EXPECT_EQ(mesh.name, "mesh0");
  EXPECT_EQ(mesh.albedo, 0.0);
  EXPECT_EQ(mesh.vertices[2], Point3(1, 1, 0));  // as in the file
  // Without meshes the scene has none.
  EXPECT_TRUE(parse_scene(scene_with_eye(R"({ "position": { "cornea_center_mm": [0, 0, 600] },
                                              "orientation": {} })"),
                          "scene.json")
                  .meshes.empty());
}

TEST(SceneFile, MeshFileMayBeAbsoluteAndIsReadRelativeToTheGivenFolderOtherwise) {
  const std::string absolute = (kSourceDir / "tests/data/meshes/square.obj").string();
  EXPECT_EQ(mesh_error(R"({ "file": ")" + absolute + R"(", "albedo": 0.5 })", kSourceDir / "docs"), "");
  // From another folder the relative name finds nothing, and says where it looked.
  EXPECT_EQ(mesh_error(R"({ "file": "meshes/square.obj", "albedo": 0.5 })", kSourceDir / "docs"),
            "scene.json: meshes[0].file = \"meshes/square.obj\": no such file (looked for " +
                (kSourceDir / "docs/meshes/square.obj").string() + ")");
}

TEST(SceneFile, MeshMistakesNameTheKeyTheValueAndTheRule) {
  const std::map<std::string, std::string> bad = {
      {R"({ "file": "meshes/square.obj", "albedo": -0.1 })", "meshes[0].albedo = -0.1: must be between 0 and 1"},
      {R"({ "file": "meshes/square.obj" })",
       "meshes[0].albedo: missing required key (its Lambertian albedo, 0 to 1)"},
      {R"({ "albedo": 0.5 })",
       "meshes[0]: missing required key: give one of file and vertices_mm"},
      {R"({ "file": "", "albedo": 0.5 })", "meshes[0].file = \"\": must not be empty"},
      {R"({ "file": 3, "albedo": 0.5 })", "meshes[0].file = 3: must be a string"},
      {R"({ "name": "", "file": "meshes/square.obj", "albedo": 0.5 })", "meshes[0].name = \"\": must not be empty"},
      {R"({ "file": "meshes/square.obj", "albedo": 0.5, "scale": 0 })", "meshes[0].scale = 0: must be > 0"},
      {R"({ "file": "meshes/square.obj", "albedo": 0.5, "position_mm": [0, 0] })",
       "meshes[0].position_mm = [0, 0]: must be an array of 3 numbers"},
      {R"({ "file": "meshes/square.obj", "albedo": 0.5, "rotation": [0, 0, 90] })",
       "meshes[0].rotation = [0, 0, 90]: unknown key (valid keys here: albedo, file, name, position_mm, "
       "rotation_vector_deg, scale, triangles, vertices_mm)"},
      {R"({ "file": "meshes/square.obj", "albedo": 0.5, "triangles": [[0, 1, 2]] })",
       "meshes[0].triangles = [[0, 1, 2]]: only used with vertices_mm"},
      // 1e300 x 1 mm is a coordinate no tracker sees, and would overflow distances.
      {R"({ "file": "meshes/square.obj", "albedo": 0.5, "scale": 1e300 })",
       "meshes[0].file = \"meshes/square.obj\": vertex 2 lands at [1e+300, 0, 0] mm, beyond +-1e+06 mm (1 km): "
       "check scale and position_mm"},
      {R"({ "file": "meshes/square.obj", "albedo": 0.5 }, { "file": "meshes/square.obj", "albedo": 0.5, "name": "mesh0" })",
       "meshes[1].name = \"mesh0\": duplicate name (mesh names must be unique)"},
      {"[]", "meshes[0] = []: must be an object"},
  };
  for (const auto& [mesh, expected] : bad) {
    EXPECT_EQ(mesh_error(mesh), "scene.json: " + expected) << mesh;
  }
  // The list itself.
  EXPECT_EQ(parse_error(R"({ "format": 1, "meshes": {},
    "cameras": [ { "resolution_px": [64, 48], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                   "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] } ],
    "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} } ] })"),
            "scene.json: meshes = {}: must be an array");
}

TEST(SceneFile, BundledGlassesSceneLoadsTheFrameInFrontOfTheEye) {
  const Scene scene = load_scene(kSourceDir / "assets/scenes/remote_glasses.json");
  EXPECT_EQ(scene.name, "remote_glasses");
  ASSERT_EQ(scene.meshes.size(), 1u);
  const Mesh& frame = scene.meshes[0];
  EXPECT_EQ(frame.name, "glasses_frame");
  // Two rims of 24 segments, each segment 4 quads, and a box for the
  // bridge: (2 x 24 x 4 + 6) quads of 2 triangles; 2 x 24 x 4 + 8 vertices.
  EXPECT_EQ(frame.triangles.size(), 396u);
  EXPECT_EQ(frame.vertices.size(), 200u);
  // The file's depth (z from -1.5 to 1.5) turned to world z 580 +- 1.5,
  // its x from -59 to 59 (lens centre +-32, outer half-width 27) moved by 32.
  for (const Point3& p : frame.vertices) {
    EXPECT_GE(p.z, 578.5 - 1e-9);
    EXPECT_LE(p.z, 581.5 + 1e-9);
    EXPECT_GE(p.x, -27 - 1e-9);
    EXPECT_LE(p.x, 91 + 1e-9);
  }
  // The eye sits behind the middle of the right rim's opening.
  EXPECT_NEAR(scene.eyes[0].cornea_center().x, 0, 1e-12);
  EXPECT_GT(scene.eyes[0].corneal_apex().z - 581.5, 10);
}

// A minimal scene with one spectacle lens given by `lens` (its JSON).
std::string scene_with_lens(const std::string& lens) {
  return R"({ "format": 1,
    "cameras": [ { "resolution_px": [64, 48], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                   "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] } ],
    "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} } ],
    "spectacle_lenses": [ )" + lens + " ] }";
}

TEST(SceneFile, ASpectacleLensIsShapedByItsPrescription) {
  // -3 D on Vogel's base (-3 / 4 + 6 = 5.25 D), 2 mm thick; +2 D on
  // 2 / 2 + 6 = 7 D, thick enough for a 1 mm edge at the 25 mm semi-axis.
  for (const double power : {-3.0, 2.0}) {
    const Scene scene = parse_scene(scene_with_lens(R"({ "position_mm": [0, 0, 578], "rotation_vector_deg": [180, 0, 0],
        "power_d": )" + std::to_string(power) + " }"),
                                    "scene.json", ".");
    ASSERT_EQ(scene.spectacle_lenses.size(), 1u);
    const SpectacleLens& lens = scene.spectacle_lenses[0];
    EXPECT_EQ(lens.name, "lens0");
    EXPECT_NEAR(back_vertex_power_d(lens), power, 1e-12);
    EXPECT_NEAR(front_surface_power_d(lens), power > 0 ? 7 : 5.25, 1e-12);
    if (power < 0) {
      EXPECT_EQ(lens.center_thickness_mm, 2);
    } else {
      EXPECT_NEAR(lens_thickness_mm(lens, 25, 0), 1, 1e-6);
    }
    // Lens +z (out of its front) toward the camera, +y up (world -y).
    EXPECT_NEAR((lens.world_from_lens * Vector3{0, 0, 1}).z, -1, 1e-15);
    EXPECT_NEAR((lens.world_from_lens * Vector3{0, 1, 0}).y, -1, 1e-15);
  }
  // Given by its radii, as a dump writes it.
  const Scene radii = parse_scene(scene_with_lens(R"({ "name": "r", "position_mm": [0, 0, 578], "rotation_vector_deg": [180, 0, 0],
      "front_radius_mm": 100, "back_radius_mm": 80, "center_thickness_mm": 1.5, "refractive_index": 1.586,
      "outline_semi_axes_mm": [20, 15] })"), "scene.json", ".");
  const SpectacleLens& r = radii.spectacle_lenses[0];
  EXPECT_EQ(r.front_radius_mm, 100);
  EXPECT_EQ(r.back_radius_mm, 80);
  EXPECT_EQ(r.refractive_index, 1.586);
  EXPECT_EQ(r.outline_semi_axes_mm[1], 15);
}

TEST(SceneFile, RejectsBadSpectacleLensesByKeyAndRule) {
  const std::string place = R"("position_mm": [0, 0, 578], "rotation_vector_deg": [180, 0, 0], )";
  const std::pair<std::string, std::string> cases[] = {
      {place + R"("power_d": 8, "base_curve_d": 4)", "spectacle_lenses[0].power_d = 8: a back vertex power of 8 D"},
      {place + R"("power_d": -30)", "spectacle_lenses[0].power_d = -30"},
      {place + R"("power_d": -3, "front_radius_mm": 100)", "give exactly one of power_d and front_radius_mm"},
      // Cutting the cornea (its apex at z = 592.2).
      {R"("position_mm": [0, 0, 591], "rotation_vector_deg": [180, 0, 0], "power_d": -3)",
       "spectacle_lenses[0].position_mm: it cuts eyes[0]'s cornea"},
      // The camera in the glass of a lens turned to world +x (the eye is
      // beside its outline).
      {R"("position_mm": [1, 0, 0], "rotation_vector_deg": [0, 90, 0], "power_d": -3)",
       "camera \"cam0\" lies in the lens's glass"},
      {place + R"("front_radius_mm": 100, "back_radius_mm": 80)", "center_thickness_mm"},
      {place + R"("power_d": 4, "center_thickness_mm": 0.5)", "edge"},
      {R"("position_mm": [0, 0, 578], "power_d": -3)", "rotation_vector_deg"},
      {place + R"("power_d": -3, "outline_semi_axes_mm": [25])", "outline_semi_axes_mm"},
      {place + R"("power_d": -3, "refractive_index": 1)", "refractive_index"},
      {place + R"("power_d": -3, "colour": "red")", "colour"},
  };
  for (const auto& [lens, expected] : cases) {
    const std::string error = parse_error(scene_with_lens("{ " + lens + " }"));
    EXPECT_NE(error.find(expected), std::string::npos) << lens << "\n" << error;
    EXPECT_EQ(error.find("scene.json: "), 0u) << error;
  }
  EXPECT_NE(parse_error(scene_with_lens(R"({ "name": "a", )" + place + R"("power_d": -3 }, { "name": "a", )" + place +
                                        R"("power_d": -3 })"))
                .find("duplicate name"),
            std::string::npos);
}

// One mistake per file; the expected message for each. A file without an
// entry here, or an entry without a file, fails MalformedFilesAllHaveExpectations.
const std::map<std::string, std::string> kMalformed = {
    {"hyperboloid_cornea", "eyes[0].cornea.asphericity = -1.5: must be >= -1 (hyperboloidal corneas are not modelled)"},
    {"aqueous_index_below_one", "eyes[0].aqueous_index = 0.9: must be >= 1"},
    {"appearance_albedo_above_one", "eyes[0].appearance.iris_albedo = 1.5: must be between 0 and 1"},
    {"appearance_seed_negative", "eyes[0].appearance.iris_seed = -3: must be >= 0"},
    {"appearance_seed_too_large", "eyes[0].appearance.iris_seed = 9007199254740992: must be < 2^53"},
    {"camera_inside_eye", "cameras[0].position_mm = [0, 0, 600]: lies inside the sclera sphere of eyes[0]"},
    {"coordinate_too_far", "illuminators[0].position_mm = [1e+300, 0, 0]: coordinates must be within +-1e+06"},
    {"duplicate_key", "invalid JSON: duplicate key \"radius_mm\""},
    {"duplicate_names", "illuminators[1].name = \"led0\": duplicate name"},
    {"empty_cameras", "cameras = []: must list at least one entry"},
    {"empty_eyes", "eyes = []: must list at least one entry"},
    {"empty_file", "invalid JSON (byte"},
    {"eyelids_gain_out_of_range", "eyes[0].eyelids.lower_gain_downgaze = 6: must be between 0 and 2"},
    {"eyelids_margins_crossed", "eyes[0].eyelids.lower_margin_mm = 0: must be < closing_line_mm (-1)"},
    {"eyelids_not_an_object", "eyes[0].eyelids = true: must be an object"},
    {"eyelids_opening_out_of_range", "eyes[0].eyelids.opening = 1.5: must be between 0 and 1"},
    {"eyelids_zero_half_width", "eyes[0].eyelids.half_width_mm = 0: must be > 0"},
    {"format_missing", "format: missing required key"},
    {"format_unsupported", "format = 2: unsupported format version"},
    {"gaze_target_too_close", "eyes[0].orientation.gaze_target_mm = [0, 0, 590]: is 10 mm from"},
    {"head_up_parallel_to_forward", "eyes[0].head.up = [0, 0, 2]: must not be parallel to head.forward"},
    {"head_without_eyelids", "eyes[0].head = {...}: only used with eyelids"},
    {"head_zero_forward", "eyes[0].head.forward = [0, 0, 0]: must not be the zero vector"},
    {"huge_number", "invalid JSON at line 9: number overflow parsing '1e999'"},
    {"iris_beyond_limbus", "eyes[0].iris.radius_mm = 6.5: must be <= cornea.limbus_radius_mm (5.9)"},
    {"kappa_unreasonable", "eyes[0].kappa_deg.horizontal = 60: must be between -45 and 45"},
    {"light_inside_eye", "illuminators[0].position_mm = [0, 0, 610]: lies inside the sclera sphere"},
    {"limbus_beyond_conicoid", "eyes[0].cornea.limbus_radius_mm = 5.9: must be < radius_mm / sqrt(1 + asphericity)"},
    {"look_at_equals_position", "cameras[0].look_at_mm = [0, 0, 0]: must differ from position_mm"},
    {"mesh_albedo_above_one", "meshes[0].albedo = 1.2: must be between 0 and 1"},
    {"mesh_face_index_out_of_range",
     "meshes[0].file = \"meshes/face_index_out_of_range.obj\": line 12: face index 40 out of range (file has 8 "
     "vertices)"},
    {"mesh_file_is_a_folder", "meshes[0].file = \"meshes\": is a directory, not an OBJ file"},
    {"mesh_garbage", "meshes[0].file = \"meshes/garbage.obj\": line 1: unknown statement \"This\""},
    {"mesh_missing_file", "meshes[0].file = \"meshes/no_such.obj\": no such file (looked for "},
    {"mesh_no_faces", "meshes[0].file = \"meshes/no_faces.obj\": no faces (no \"f\" statement)"},
    {"mesh_non_finite_vertex",
     "meshes[0].file = \"meshes/non_finite_vertex.obj\": line 3: vertex coordinate \"nan\" is not a finite "
     "number"},
    {"mesh_unknown_key",
     "meshes[0].colour = 0.3: unknown key (valid keys here: albedo, file, name, position_mm, "
     "rotation_vector_deg, scale, triangles, vertices_mm)"},
    {"missing_eye_position", "eyes[0].position: missing required key; found \"positon\""},
    {"missing_pixel_pitch", "cameras[0].pixel_pitch_mm: missing required key"},
    {"negative_cornea_radius", "eyes[0].cornea.radius_mm = -7.8: must be > 0"},
    {"negative_emitter_diameter", "illuminators[0].emitter_diameter_mm = -1: must be >= 0"},
    {"number_as_string", "cameras[0].focal_length_mm = \"16\": must be a number"},
    {"pitch_out_of_range", "eyes[0].orientation.pitch_deg = 95: must be between -89 and 89"},
    {"point_with_two_coordinates", "illuminators[1].position_mm = [100, 0]: must be an array of 3 numbers"},
    {"posterior_bad_string", "eyes[0].posterior_cornea = \"absent\": must be an object or \"none\""},
    {"posterior_crosses_anterior", "eyes[0].posterior_cornea.thickness_mm = 0.55: the posterior cornea crosses the anterior one"},
    {"posterior_index_below_one", "eyes[0].posterior_cornea.index = 0.5: must be >= 1"},
    {"pupil_decentred_past_iris", "eyes[0].pupil.decentration_mm = [4, 0]: moves the pupil's edge to 6 mm"},
    {"rotation_center_in_front_of_limbus",
     "eyes[0].rotation_center_depth_mm = 2.5: must be > the limbus's depth behind the corneal apex (2.698"},
    {"pupil_larger_than_iris", "eyes[0].pupil.radius_mm = 6: must be < iris.radius_mm (5.5)"},
    {"resolution_not_integer", "cameras[0].resolution_px[0] = 640.5: must be an integer"},
    {"resolution_too_big", "cameras[0].resolution_px[0] = 100000: must be <= 65536"},
    {"sclera_short_of_limbus",
     "eyes[0].sclera_radius_mm = 10: must be > 10.80196040752963"},
    {"sensor_bits_unsupported", "cameras[0].sensor.bits = 14: must be one of 8, 10, 12, 16"},
    {"sensor_f_number_zero", "cameras[0].sensor.f_number = 0: must be > 0"},
    {"sensor_focus_inside_focal_length",
     "cameras[0].sensor.focus_distance_mm = 10: must be > the focal length (16 mm)"},
    {"sensor_noise_not_boolean", "cameras[0].sensor.noise = \"yes\": must be true or false"},
    {"sensor_pixel_pitch_with_focal_length",
     "cameras[0].sensor.pixel_pitch_mm = 0.006: allowed only with intrinsics_px"},
    {"sensor_psf_too_wide", "cameras[0].sensor.psf_sigma_px = 25: must be between 0 and 20"},
    {"sensor_quantum_efficiency_above_one",
     "cameras[0].sensor.quantum_efficiency = 1.2: must be > 0 and <= 1"},
    {"sensor_read_noise_negative", "cameras[0].sensor.read_noise_e = -1: must be >= 0"},
    {"sensor_unknown_key",
     "cameras[0].sensor.exposure_ms = 4: unknown key (valid keys here: bits, corner_illumination, exposure_s, "
     "f_number, focus_distance_mm, full_well_e, gain, hot_pixel_e_per_s, hot_pixel_fraction, hot_pixel_seed, "
     "jpeg_quality, noise, pixel_pitch_mm, psf_sigma_px, quantum_efficiency, read_noise_e)"},
    {"syntax_missing_comma", "invalid JSON (byte 213): parse error at line 9, column 22"},
    {"top_level_array", "(top level) = [1, 2, 3]: must be an object"},
    {"two_eye_positions", "eyes[0].position: give exactly one of cornea_center_mm and rotation_center_mm"},
    {"two_intrinsics", "cameras[0]: give exactly one of focal_length_mm and intrinsics_px"},
    {"unknown_nested_key", "eyes[0].cornea.radius = 7.8: unknown key"},
    {"unknown_preset", "eyes[0].model = \"gullstrand\": unknown eye model (valid: keratometric, le_grand, navarro)"},
    {"unknown_top_level_key", "lights = []: unknown key"},
    {"up_parallel_to_view", "cameras[0].up = [0, 0, 1]: must not be parallel to the viewing direction"},
    {"yaw_with_gaze_target", "eyes[0].orientation.yaw_deg = 5: cannot be combined with gaze_target_mm"},
    {"zero_pixel_pitch", "cameras[0].pixel_pitch_mm = 0: must be > 0"},
};

const fs::path kMalformedDir = kSourceDir / "tests/data/malformed";

TEST(SceneFile, MalformedFilesAllHaveExpectations) {
  std::set<std::string> files;
  for (const auto& entry : fs::directory_iterator(kMalformedDir)) {
    if (entry.path().extension() == ".json") files.insert(entry.path().stem().string());
  }
  EXPECT_GE(files.size(), 25u);
  for (const auto& name : files) EXPECT_TRUE(kMalformed.count(name)) << name << ".json has no expected message";
  for (const auto& [name, expected] : kMalformed) EXPECT_TRUE(files.count(name)) << name << ".json is missing";
}

TEST(SceneFile, EachMalformedFileIsRejectedWithItsMessage) {
  for (const auto& [name, expected] : kMalformed) {
    const fs::path file = kMalformedDir / (name + ".json");
    try {
      load_scene(file);
      ADD_FAILURE() << name << ": loaded without error";
    } catch (const SceneError& e) {
      const std::string message = e.what();
      // Every message starts with the file it is about.
      EXPECT_EQ(message.rfind(file.string() + ": ", 0), 0u) << message;
      EXPECT_NE(message.find(expected), std::string::npos)
          << name << "\n  message:  " << message << "\n  expected: " << expected;
    }
  }
}

TEST(SceneFile, MalformedFilesSayWhatIsWrongInALeadingComment) {
  // Each file starts with a comment line saying what is wrong.
  for (const auto& [name, expected] : kMalformed) {
    std::ifstream in(kMalformedDir / (name + ".json"));
    std::string first_line;
    std::getline(in, first_line);
    EXPECT_EQ(first_line.rfind("// ", 0), 0u) << name << ".json has no leading comment";
  }
}

}  // namespace
}  // namespace purkinje

namespace purkinje {
namespace {

TEST(SceneFile, DeeplyNestedValueGivesAMessageNotACrash) {
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  try {
    parse_scene("{\"format\": " + deep + "}", "deep.json");
    FAIL() << "a nested array is not a format version";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("deep.json: format = [[[[...]]]]: must be a number"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace purkinje
