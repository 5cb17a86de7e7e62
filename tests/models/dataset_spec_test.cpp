// Dataset specs: the reader's rules (each malformed spec gets its
// message), the draws (checked against the distributions' closed forms,
// not against their own output), and the scene each image's draws make.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "purkinje/models/dataset_spec.h"

namespace purkinje {
namespace {

constexpr double kDeg = std::numbers::pi / 180;

const std::string kFolder = std::string(PURKINJE_SOURCE_DIR) + "/assets/datasets";

// A spec over the bundled remote scene with `body` (keys after "count").
DatasetSpec spec_with(const std::string& body, int count = 1000) {
  const std::string text = R"({"dataset_format": 1, "name": "t", "scene": "../scenes/remote.json", "count": )" +
                           std::to_string(count) + (body.empty() ? "" : ", " + body) + "}";
  return parse_dataset_spec(text, "t.json", kFolder);
}

std::string message_of(const std::string& body) {
  try {
    spec_with(body);
  } catch (const DatasetSpecError& e) {
    return e.what();
  }
  return "(accepted)";
}

double column(const DatasetSpec& spec, const ImageDraw& d, const std::string& name) {
  for (std::size_t i = 0; i < spec.parameters.size(); ++i) {
    if (spec.parameters[i].name == name) return d.values[i];
  }
  ADD_FAILURE() << "no parameter " << name;
  return 0;
}

double normal_pdf(double x) { return std::exp(-0.5 * x * x) / std::sqrt(2 * std::numbers::pi); }
double normal_cdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

TEST(DatasetSpec, InverseNormalCdfMatchesTabulatedQuantiles) {
  // Quantiles to 16 digits from tables (Wichura 1988, AS 241's checks).
  EXPECT_NEAR(inverse_normal_cdf(0.5), 0.0, 1e-15);
  EXPECT_NEAR(inverse_normal_cdf(0.975), 1.959963984540054, 1e-14);
  EXPECT_NEAR(inverse_normal_cdf(0.025), -1.959963984540054, 1e-14);
  EXPECT_NEAR(inverse_normal_cdf(0.8413447460685429), 1.0, 1e-13);
  EXPECT_NEAR(inverse_normal_cdf(1e-10), -6.361340902404056, 1e-12);
  // Deep in the tail, where no table reaches: the CDF of the result gives p back.
  for (const double p : {1e-300, 1e-100, 1e-20}) {
    EXPECT_NEAR(normal_cdf(inverse_normal_cdf(p)) / p, 1.0, 1e-12) << p;
  }
  EXPECT_TRUE(std::isinf(inverse_normal_cdf(0.0)));
  EXPECT_TRUE(std::isnan(inverse_normal_cdf(1.5)));
}

TEST(DatasetSpec, DrawsAreAFunctionOfSeedIndexAndNameAlone) {
  const DatasetSpec one = spec_with(R"("parameters": {"pupil_radius_mm": {"uniform": [1, 4]}})");
  const DatasetSpec two = spec_with(R"("parameters": {"pupil_radius_mm": {"uniform": [1, 4]},
                                                      "iris_albedo": {"uniform": [0.1, 0.4]}})");
  // Another parameter, or drawing in another order (a shard), changes nothing.
  for (std::uint64_t k : {999u, 3u, 0u, 500u}) {
    const ImageDraw a = draw_image(one, k), b = draw_image(two, k);
    EXPECT_EQ(column(one, a, "pupil_radius_mm"), column(two, b, "pupil_radius_mm")) << k;
    EXPECT_EQ(a.seed, b.seed) << k;
    EXPECT_LT(a.seed, std::uint64_t{1} << 53);
  }
  EXPECT_NE(draw_image(one, 1).values[0], draw_image(one, 2).values[0]);
  EXPECT_NE(draw_image(one, 1).seed, draw_image(one, 2).seed);
  // Another seed, other draws.
  const DatasetSpec reseeded = spec_with(R"("seed": 2, "parameters": {"pupil_radius_mm": {"uniform": [1, 4]}})");
  EXPECT_NE(draw_image(one, 1).values[0], draw_image(reseeded, 1).values[0]);
}

TEST(DatasetSpec, UniformNormalChoiceAndCapFollowTheirLaws) {
  const DatasetSpec spec = spec_with(R"("gaze": {"cone_deg": 30}, "parameters": {
      "pupil_radius_mm": {"uniform": [1, 4]},
      "iris_seed": {"uniform": [10, 13]},
      "sclera_albedo": {"normal": {"mean": 0.5, "sd": 0.1, "min": 0.45, "max": 0.9}},
      "cornea_radius_mm": {"normal": {"mean": 7.8, "sd": 0.2, "min": 6.8, "max": 8.8}},
      "bits": {"choice": [8, 12], "weights": [3, 1]}})");
  const int n = 20000;
  double pupil = 0, albedo = 0, albedo_min = 1, albedo_max = 0, radius = 0, radius_sq = 0, inner_cap = 0;
  std::map<double, int> seeds, bits;
  for (int k = 0; k < n; ++k) {
    const ImageDraw d = draw_image(spec, static_cast<std::uint64_t>(k));
    const double p = column(spec, d, "pupil_radius_mm");
    ASSERT_TRUE(p >= 1 && p <= 4);
    pupil += p;
    const double a = column(spec, d, "sclera_albedo");
    albedo += a;
    albedo_min = std::min(albedo_min, a);
    albedo_max = std::max(albedo_max, a);
    const double r = column(spec, d, "cornea_radius_mm");
    radius += r;
    radius_sq += r * r;
    ++seeds[column(spec, d, "iris_seed")];
    ++bits[column(spec, d, "bits")];
    const double turn = column(spec, d, "gaze_turn_deg");
    ASSERT_TRUE(turn >= 0 && turn <= 30);
    if (turn <= 15) ++inner_cap;
    const double direction = column(spec, d, "gaze_direction_deg");
    ASSERT_TRUE(direction >= 0 && direction <= 360);
  }
  // Means within 5 standard errors of the closed forms.
  EXPECT_NEAR(pupil / n, 2.5, 5 * 3 / std::sqrt(12.0 * n));
  // A normal truncated to [alpha, beta] (in sd): mean mu + sd (phi(alpha) - phi(beta)) / (Phi(beta) - Phi(alpha)).
  const double alpha = -0.5, beta = 4;
  const double truncated_mean = 0.5 + 0.1 * (normal_pdf(alpha) - normal_pdf(beta)) / (normal_cdf(beta) - normal_cdf(alpha));
  EXPECT_NEAR(albedo / n, truncated_mean, 5 * 0.1 / std::sqrt(n));
  EXPECT_GE(albedo_min, 0.45);
  EXPECT_LE(albedo_max, 0.9);
  EXPECT_NEAR(radius / n, 7.8, 5 * 0.2 / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(radius_sq / n - (radius / n) * (radius / n)), 0.2, 0.01);
  // Integers 10..13 equally likely; weights 3:1.
  ASSERT_EQ(seeds.size(), 4u);
  for (const auto& [seed, count] : seeds) EXPECT_NEAR(count, n / 4.0, 5 * std::sqrt(n * 0.25 * 0.75)) << seed;
  EXPECT_NEAR(bits[8], 0.75 * n, 5 * std::sqrt(n * 0.75 * 0.25));
  EXPECT_EQ(bits[8] + bits[12], n);
  // Uniform over the cap: the share within 15 deg is its solid angle's.
  const double inner_share = (1 - std::cos(15 * kDeg)) / (1 - std::cos(30 * kDeg));
  EXPECT_NEAR(inner_cap / n, inner_share, 5 * std::sqrt(inner_share * (1 - inner_share) / n));
}

TEST(DatasetSpec, GridsFormAProductTheLastVaryingFastest) {
  const DatasetSpec spec = spec_with(R"("parameters": {
      "pupil_radius_mm": {"grid": [1, 2, 3]},
      "iris_albedo": {"grid": {"from": 0.1, "to": 0.3, "steps": 2}}})");
  const std::vector<std::pair<double, double>> expected = {{1, 0.1}, {1, 0.3}, {2, 0.1}, {2, 0.3}, {3, 0.1}, {3, 0.3}};
  for (std::uint64_t k = 0; k < 12; ++k) {
    const ImageDraw d = draw_image(spec, k);
    EXPECT_EQ(column(spec, d, "pupil_radius_mm"), expected[k % 6].first) << k;
    EXPECT_DOUBLE_EQ(column(spec, d, "iris_albedo"), expected[k % 6].second) << k;
  }
}

// Found by fuzzing (tests/fuzz/corpus/dataset_spec): a grid's last step
// rounding past its end, a product of grids wrapping past 2^64, a normal
// truncated to a sliver of its sd.
TEST(DatasetSpec, GridEndsAreExactAndHugeProductsAndSliversDrawInRange) {
  const DatasetSpec ends = spec_with(R"("parameters": {"lid_opening": {"grid": {"from": 0.2, "to": 1, "steps": 7}},
                                                       "iris_albedo": {"grid": {"from": 0.2, "to": 0, "steps": 4}}})");
  EXPECT_EQ(ends.parameters[0].distribution.values.back(), 1.0);
  EXPECT_EQ(ends.parameters[1].distribution.values.back(), 0.0);
  for (const VariedParameter& p : ends.parameters) {
    for (double v : p.distribution.values) EXPECT_TRUE(v >= 0 && v <= 1) << p.name << " " << v;
  }
  const DatasetSpec product = spec_with(R"("parameters": {
      "iris_albedo": {"grid": {"from": 0, "to": 1, "steps": 65536}},
      "sclera_albedo": {"grid": {"from": 0, "to": 1, "steps": 65536}},
      "skin_albedo": {"grid": {"from": 0, "to": 1, "steps": 65536}},
      "fundus_reflectance": {"grid": {"from": 0, "to": 1, "steps": 65536}}})");
  // Its size is beyond any index (2^64 wrapped to 0 before): image k takes entry k, the last varying fastest.
  const ImageDraw d = draw_image(product, 65537);
  EXPECT_EQ(column(product, d, "skin_albedo"), 1.0 / 65535);  // 65537 = 1 * 65536 + 1
  EXPECT_EQ(column(product, d, "fundus_reflectance"), 1.0 / 65535);
  const DatasetSpec sliver = spec_with(R"("parameters": {"iris_albedo": {"normal": {"mean": 0.5, "sd": 1e20, "min": 0, "max": 1}}})");
  double sum = 0;
  for (std::uint64_t k = 0; k < 2000; ++k) {
    const double v = draw_image(sliver, k).values[0];
    ASSERT_TRUE(v >= 0 && v <= 1);
    sum += v;
  }
  EXPECT_NEAR(sum / 2000, 0.5, 5 * std::sqrt(1 / 12.0 / 2000));  // uniform, not always an end
}

TEST(DatasetSpec, AnEyeMovedOntoTheCameraIsRefusedAndFarTailsStillVary) {
  const DatasetSpec onto = spec_with(R"("parameters": {"eye_offset_z_mm": -595})");
  try {
    scene_for_image(onto, draw_image(onto, 0));
    ADD_FAILURE() << "accepted";
  } catch (const DatasetSpecError& e) {
    EXPECT_NE(std::string(e.what()).find("camera 'cam0' lies within"), std::string::npos) << e.what();
  }
  // 40 sd out, where the CDF underflows: the tail's exponential, mean
  // about a + 1/a.
  const DatasetSpec tail = spec_with(R"("parameters": {"eye_offset_x_mm": {"normal": {"mean": 0, "sd": 1, "min": 40, "max": 41}}})");
  double sum = 0, low = 41, high = 40;
  for (std::uint64_t k = 0; k < 4000; ++k) {
    const double v = draw_image(tail, k).values[0];
    sum += v;
    low = std::min(low, v);
    high = std::max(high, v);
  }
  EXPECT_NEAR(sum / 4000, 40 + 1.0 / 40, 0.003);
  EXPECT_LT(low, 40.001);
  EXPECT_GT(high, 40.1);
}

TEST(DatasetSpec, ScreenTargetsAreFixated) {
  const DatasetSpec spec = spec_with(R"("gaze": {"screen": {"grid": [3, 2]}},
                                        "parameters": {"eye_offset_x_mm": {"uniform": [-40, 40]}})");
  const Screen& screen = *spec.scene.screen;
  for (std::uint64_t k = 0; k < 6; ++k) {
    const ImageDraw d = draw_image(spec, k);
    const Scene scene = scene_for_image(spec, d);
    const Point3 target = screen.at({column(spec, d, "screen_x_mm"), column(spec, d, "screen_y_mm")});
    const Eye& eye = scene.eyes[0];
    // The visual axis from the cornea centre passes through the target.
    const Vector3 to_target = target - eye.cornea_center();
    EXPECT_LT(angle_between(eye.visual_axis(), UnitVector3::normalize(to_target)), 1e-9) << k;
    EXPECT_NEAR(eye.rotation_center().x - spec.scene.eyes[0].rotation_center().x, column(spec, d, "eye_offset_x_mm"),
                1e-9);
  }
  // Cell centres: (column + 0.5) / columns of the width.
  EXPECT_DOUBLE_EQ(column(spec, draw_image(spec, 0), "screen_x_mm"), screen.width_mm / 6);
  EXPECT_DOUBLE_EQ(column(spec, draw_image(spec, 0), "screen_y_mm"), screen.height_mm / 4);
}

// Each parameter's drawn value lands in the scene where the renderer and
// the labels read it.
TEST(DatasetSpec, EveryParameterReachesTheScene) {
  const DatasetSpec spec = spec_with(R"("gaze": {"cone_deg": 20}, "parameters": {
      "pupil_radius_mm": {"uniform": [1, 3]},
      "eye_offset_x_mm": {"uniform": [-10, 10]}, "eye_offset_y_mm": {"uniform": [-10, 10]},
      "eye_offset_z_mm": {"uniform": [-10, 10]},
      "head_yaw_deg": {"uniform": [-10, 10]}, "head_pitch_deg": {"uniform": [-10, 10]},
      "head_roll_deg": {"uniform": [-10, 10]},
      "lid_opening": {"uniform": [0.5, 1]}, "iris_seed": {"uniform": [1, 1000]},
      "iris_texture_contrast": {"uniform": [0, 1]}, "iris_albedo": {"uniform": [0.1, 0.4]},
      "sclera_albedo": {"uniform": [0.4, 0.7]}, "skin_albedo": {"uniform": [0.3, 0.6]},
      "fundus_reflectance": {"uniform": [0, 0.2]},
      "cornea_radius_mm": {"uniform": [7.5, 8.1]}, "cornea_asphericity": {"uniform": [-0.5, 0]},
      "posterior_cornea": false,
      "kappa_horizontal_deg": {"uniform": [2, 7]}, "kappa_vertical_deg": {"uniform": [0, 3]},
      "rotation_center_depth_mm": {"uniform": [12, 15]},
      "led_power_scale": {"uniform": [0.5, 2]},
      "exposure_s": {"uniform": [0.002, 0.008]}, "gain": {"uniform": [1, 2]},
      "read_noise_e": {"uniform": [2, 8]}, "noise": false, "focus_distance_mm": {"uniform": [500, 700]},
      "bits": 12, "corner_illumination": {"uniform": [0.5, 1]}, "hot_pixel_fraction": {"uniform": [0, 0.001]},
      "illuminators": {"led_left": {"power_scale": {"uniform": [0.5, 1]}}, "led_right": {"on": false}}})");
  EXPECT_GE(spec.parameters.size(), 30u);
  const Scene& base = spec.scene;
  for (std::uint64_t k : {0u, 7u}) {
    const ImageDraw d = draw_image(spec, k);
    const Scene s = scene_for_image(spec, d);
    const auto v = [&](const char* name) { return column(spec, d, name); };
    const Eye& eye = s.eyes[0];
    const EyeModel& m = eye.model();
    EXPECT_NEAR(angle_between(eye.visual_axis(), base.eyes[0].visual_axis()), v("gaze_turn_deg") * kDeg, 1e-9);
    EXPECT_EQ(m.pupil_radius_mm, v("pupil_radius_mm"));
    const Vector3 moved = eye.rotation_center() - base.eyes[0].rotation_center();
    EXPECT_NEAR(moved.x, v("eye_offset_x_mm"), 1e-9);
    EXPECT_NEAR(moved.y, v("eye_offset_y_mm"), 1e-9);
    EXPECT_NEAR(moved.z, v("eye_offset_z_mm"), 1e-9);
    // The head turns: its forward leaves the base's by the composed angle.
    const EyeAppearance& a = eye.appearance();
    const double yaw = v("head_yaw_deg") * kDeg, pitch = v("head_pitch_deg") * kDeg;
    EXPECT_NEAR(dot(a.head_forward, base.eyes[0].appearance().head_forward), std::cos(yaw) * std::cos(pitch), 1e-12);
    EXPECT_NEAR(dot(a.head_up, base.eyes[0].appearance().head_up) > 0, 1, 0);
    EXPECT_EQ(a.eyelids->opening, v("lid_opening"));
    EXPECT_EQ(a.iris_seed, static_cast<std::uint64_t>(v("iris_seed")));
    EXPECT_EQ(a.iris_texture_contrast, v("iris_texture_contrast"));
    EXPECT_EQ(a.iris_albedo, v("iris_albedo"));
    EXPECT_EQ(a.sclera_albedo, v("sclera_albedo"));
    EXPECT_EQ(a.skin_albedo, v("skin_albedo"));
    EXPECT_EQ(a.fundus_reflectance, v("fundus_reflectance"));
    EXPECT_EQ(m.anterior_cornea.radius_mm, v("cornea_radius_mm"));
    EXPECT_EQ(m.anterior_cornea.asphericity, v("cornea_asphericity"));
    EXPECT_FALSE(m.posterior_cornea.has_value());
    EXPECT_EQ(m.aqueous_index, 1.3375);
    EXPECT_NEAR(m.kappa_horizontal_rad, v("kappa_horizontal_deg") * kDeg, 1e-15);
    EXPECT_NEAR(m.kappa_vertical_rad, v("kappa_vertical_deg") * kDeg, 1e-15);
    EXPECT_EQ(m.rotation_center_depth_mm, v("rotation_center_depth_mm"));
    ASSERT_EQ(s.illuminators.size(), 1u);  // led_right off
    EXPECT_EQ(s.illuminators[0].name, "led_left");
    EXPECT_DOUBLE_EQ(s.illuminators[0].radiant_intensity_w_sr,
                     base.illuminators[0].radiant_intensity_w_sr * v("led_power_scale") *
                         v("illuminator.led_left.power_scale"));
    const Sensor& sensor = s.cameras[0].sensor();
    EXPECT_EQ(sensor.exposure_s, v("exposure_s"));
    EXPECT_EQ(sensor.gain, v("gain"));
    EXPECT_EQ(sensor.read_noise_e, v("read_noise_e"));
    EXPECT_FALSE(sensor.noise);
    EXPECT_EQ(*sensor.focus_distance_mm, v("focus_distance_mm"));
    EXPECT_EQ(sensor.bits, 12);
    EXPECT_EQ(sensor.corner_illumination, v("corner_illumination"));
    EXPECT_EQ(sensor.hot_pixel_fraction, v("hot_pixel_fraction"));
    EXPECT_FALSE(sensor.jpeg_quality.has_value());
  }
  // A saccade: the drawn speed along the drawn direction (0: yaw, 90: pitch).
  const DatasetSpec moving = spec_with(R"("parameters": {"gaze_speed_deg_s": {"uniform": [100, 600]},
      "gaze_speed_direction_deg": {"uniform": [0, 360]}})");
  for (std::uint64_t k : {0u, 1u}) {
    const ImageDraw d = draw_image(moving, k);
    const Eye eye = scene_for_image(moving, d).eyes[0];
    const double speed = column(moving, d, "gaze_speed_deg_s"), a = column(moving, d, "gaze_speed_direction_deg") * kDeg;
    // The axis turns at the drawn speed, in the drawn direction: measured
    // over 1 ms either side, from the turned axes themselves.
    const UnitVector3 before = eye.at_time(-1e-3).optical_axis(), after = eye.at_time(1e-3).optical_axis();
    EXPECT_NEAR(angle_between(before, after) / 2e-3, speed * kDeg, 1e-4 * speed * kDeg);
    EXPECT_NEAR(eye.motion().pitch_deg_s, speed * std::sin(a), 1e-9);
    EXPECT_EQ(eye.motion().yaw_deg_s > 0, std::cos(a) > 0);
  }
  // JPEG only at 8 bits (the other test's bits are 12).
  const DatasetSpec jpeg = spec_with(R"("parameters": {"jpeg_quality": {"choice": [40, 90]}})");
  for (std::uint64_t k : {0u, 1u, 2u}) {
    const ImageDraw d = draw_image(jpeg, k);
    EXPECT_EQ(scene_for_image(jpeg, d).cameras[0].sensor().jpeg_quality, column(jpeg, d, "jpeg_quality"));
  }
}

TEST(DatasetSpec, BlinksCloseTheLidsAndMeshesSwitchOff) {
  const DatasetSpec spec = parse_dataset_spec(R"({"dataset_format": 1, "scene": "../scenes/remote_glasses.json",
      "count": 10, "parameters": {"blink": true, "meshes": {"glasses_frame": {"on": false}}}})",
                                              "g.json", kFolder);
  const Scene s = scene_for_image(spec, draw_image(spec, 3));
  EXPECT_EQ(s.eyes[0].appearance().eyelids->opening, 0.0);
  EXPECT_TRUE(s.meshes.empty());
  EXPECT_FALSE(spec.scene.meshes.empty());
  EXPECT_EQ(spec.name, "g");  // the file's stem when no name is given
}

TEST(DatasetSpec, TheFaceParametersReachTheFirstEyesFaceOnly) {
  const DatasetSpec spec = parse_dataset_spec(R"({"dataset_format": 1, "scene": "../scenes/remote_face.json",
      "count": 10, "parameters": {"margin_thickness_mm": {"uniform": [1, 2.5]},
      "crease_height_mm": {"choice": [0, 9]}, "crease_depth_mm": {"uniform": [0.2, 1]},
      "canthal_tilt_deg": {"uniform": [-5, 10]}, "lateral_canthus_mm": {"uniform": [9, 13]},
      "brow_prominence_mm": {"normal": {"mean": 2, "sd": 3, "min": -8, "max": 12}}}})",
                                              "f.json", kFolder);
  for (std::uint64_t k : {0u, 5u}) {
    const ImageDraw d = draw_image(spec, k);
    const Scene s = scene_for_image(spec, d);
    const Face& face = *s.eyes[0].appearance().face;
    for (const char* name : {"margin_thickness_mm", "crease_height_mm", "crease_depth_mm", "canthal_tilt_deg",
                             "lateral_canthus_mm", "brow_prominence_mm"}) {
      const auto key = std::find_if(kFaceKeys.begin(), kFaceKeys.end(), [&](const FaceKey& f) { return f.name == name; });
      ASSERT_NE(key, kFaceKeys.end()) << name;
      EXPECT_EQ(face.*key->member, column(spec, d, name)) << name;
    }
    // The midline stays (the other eye's face shares it), and so does the
    // other eye's face.
    EXPECT_EQ(face.midline_mm, spec.scene.eyes[0].appearance().face->midline_mm);
    EXPECT_EQ(s.eyes[1].appearance().face->crease_height_mm, spec.scene.eyes[1].appearance().face->crease_height_mm);
  }
}

TEST(DatasetSpec, TheLashParametersReachTheFirstEyesLashes) {
  const DatasetSpec spec = parse_dataset_spec(R"({"dataset_format": 1, "scene": "../scenes/remote_face.json", "count": 10,
      "parameters": {"lash_upper_per_mm": {"uniform": [2, 6]}, "lash_lower_per_mm": {"uniform": [0, 4]},
      "lash_upper_length_mm": {"uniform": [7, 12]}, "lash_lower_length_mm": {"uniform": [5, 8]},
      "lash_upper_curl_deg": {"uniform": [10, 70]}, "lash_lower_curl_deg": {"uniform": [0, 40]},
      "lash_root_deg": {"uniform": [0, 40]}, "lash_thickness_mm": {"uniform": [0.06, 0.15]},
      "lash_albedo": {"choice": [0.03, 0.1]}, "lash_seed": {"choice": [3, 4]}}})",
                                              "f.json", kFolder);
  for (std::uint64_t k : {0u, 7u}) {
    const ImageDraw d = draw_image(spec, k);
    const Scene scene = scene_for_image(spec, d);
    const Lashes& lashes = *scene.eyes[0].appearance().face->lashes;
    for (const LashKey& key : kLashKeys) {
      EXPECT_EQ(lashes.*key.member, column(spec, d, "lash_" + std::string(key.name))) << key.name;
    }
    EXPECT_EQ(static_cast<double>(lashes.seed), column(spec, d, "lash_seed"));
    // The other eye's lashes stay as the scene has them.
    EXPECT_EQ(scene.eyes[1].appearance().face->lashes->seed, 2u);
  }
}

TEST(DatasetSpec, TheBrowParametersReachTheFirstEyesBrows) {
  const DatasetSpec spec = parse_dataset_spec(R"({"dataset_format": 1, "scene": "../scenes/remote_face.json", "count": 10,
      "parameters": {"brows_hairs_per_mm2": {"uniform": [0.5, 3]}, "brows_height_mm": {"uniform": [14, 20]},
      "brows_width_mm": {"uniform": [6, 12]}, "brows_hair_length_mm": {"uniform": [6, 10]},
      "brows_thickness_mm": {"uniform": [0.05, 0.1]}, "brows_lift_deg": {"uniform": [10, 30]},
      "brows_curl_deg": {"uniform": [0, 30]}, "brows_albedo": {"choice": [0.1, 0.3]}, "brows_seed": {"choice": [3, 4]}}})",
                                              "f.json", kFolder);
  for (std::uint64_t k : {0u, 7u}) {
    const ImageDraw d = draw_image(spec, k);
    const Scene scene = scene_for_image(spec, d);
    const Brows& brows = *scene.eyes[0].appearance().face->brows;
    for (const BrowKey& key : kBrowKeys) {
      EXPECT_EQ(brows.*key.member, column(spec, d, "brows_" + std::string(key.name))) << key.name;
    }
    EXPECT_EQ(static_cast<double>(brows.seed), column(spec, d, "brows_seed"));
    // The other eye's brows stay as the scene has them.
    EXPECT_EQ(scene.eyes[1].appearance().face->brows->seed, 2u);
  }
  // A scene without brows refuses them, naming the parameter.
  try {
    parse_dataset_spec(R"({"dataset_format": 1, "scene": "../scenes/headset.json", "count": 10,
        "parameters": {"brows_albedo": {"uniform": [0.1, 0.3]}}})",
                       "f.json", kFolder);
    FAIL() << "accepted brows for a scene without them";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("brows_albedo"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no brows"), std::string::npos) << e.what();
  }
}

TEST(DatasetSpec, TheTearFilmsRoughnessAndMeniscusReachTheFirstEye) {
  const DatasetSpec spec = parse_dataset_spec(R"({"dataset_format": 1, "scene": "../scenes/hard/headset_wet.json",
      "count": 10, "parameters": {"sclera_roughness_deg": {"uniform": [0, 6]}, "meniscus_radius_mm": {"uniform": [0.2, 0.4]},
      "upper_meniscus_radius_mm": {"uniform": [0.1, 0.3]}}})",
                                              "f.json", kFolder);
  for (std::uint64_t k : {0u, 7u}) {
    const ImageDraw d = draw_image(spec, k);
    const Scene scene = scene_for_image(spec, d);
    EXPECT_EQ(scene.eyes[0].appearance().tear_film->sclera_roughness_deg, column(spec, d, "sclera_roughness_deg"));
    EXPECT_EQ(scene.eyes[0].appearance().tear_film->meniscus_radius_mm, column(spec, d, "meniscus_radius_mm"));
    EXPECT_EQ(scene.eyes[0].appearance().tear_film->upper_meniscus_radius_mm, column(spec, d, "upper_meniscus_radius_mm"));
  }
}

TEST(DatasetSpec, TheTissueTexturesReachTheFirstEye) {
  const DatasetSpec spec = spec_with(R"("parameters": {"skin_texture_contrast": {"uniform": [0, 0.5]},
      "sclera_vessel_contrast": {"choice": [0.2, 0.6]}})");
  for (std::uint64_t k : {0u, 3u}) {
    const ImageDraw d = draw_image(spec, k);
    const Scene scene = scene_for_image(spec, d);
    const EyeAppearance& a = scene.eyes[0].appearance();
    EXPECT_EQ(a.skin_texture_contrast, column(spec, d, "skin_texture_contrast"));
    EXPECT_EQ(a.sclera_vessel_contrast, column(spec, d, "sclera_vessel_contrast"));
  }
}

TEST(DatasetSpec, TheIrisFurrowsAndFrecklesReachTheFirstEye) {
  const DatasetSpec spec = spec_with(R"("parameters": {"iris_furrow_contrast": {"uniform": [0, 1]},
      "iris_freckles": {"choice": [0, 7, 20]}})");
  for (std::uint64_t k : {0u, 3u, 5u}) {
    const ImageDraw d = draw_image(spec, k);
    const Scene scene = scene_for_image(spec, d);
    const EyeAppearance& a = scene.eyes[0].appearance();
    EXPECT_EQ(a.iris_furrow_contrast, column(spec, d, "iris_furrow_contrast"));
    EXPECT_EQ(a.iris_freckles, column(spec, d, "iris_freckles"));
  }
}

TEST(DatasetSpec, ADrawNoEyeCanHaveIsNamedWithItsImageAndValues) {
  // A pupil of 6 mm in an iris of 5.9: the anatomy rule, at image 0.
  const DatasetSpec spec = spec_with(R"("parameters": {"pupil_radius_mm": {"uniform": [5.95, 6]}})");
  try {
    scene_for_image(spec, draw_image(spec, 0));
    FAIL() << "accepted";
  } catch (const DatasetSpecError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("t.json: image 0: "), std::string::npos) << m;
    EXPECT_NE(m.find("pupil"), std::string::npos) << m;
    EXPECT_NE(m.find("(drawn: pupil_radius_mm = "), std::string::npos) << m;
  }
}

struct Malformed {
  const char* body;
  const char* message;
};

// Each rule of docs/dataset-format.md broken once, with the message's
// telling part (file, key path, value, rule).
const Malformed kMalformed[] = {
    {R"("camera": "cam9")", "t.json: camera = \"cam9\": the scene has no such camera (it has cam0)"},
    {R"("seed": -1)", "t.json: seed = -1: must be >= 0"},
    {R"("seed": 1.5)", "t.json: seed = 1.5: must be an integer"},
    {R"("render": {"samples_per_pixel": 0})", "render.samples_per_pixel = 0: must be in [1, 1048576]"},
    {R"("render": {"samples": 4})", "render.samples = 4: unknown key (valid keys here: edge_samples_per_pixel, samples_per_pixel)"},
    {R"("outputs": {"image": false, "segmentation": false})", "outputs: writes no image: turn on image, segmentation or exr"},
    {R"("outputs": {"exr": {"compression": "lzma"}})", "outputs.exr.compression = \"lzma\": unknown OpenEXR compression"},
    {R"("outputs": {"exr": {"planes": []}})", "outputs.exr.planes = []: must list at least one plane"},
    {R"("outputs": {"png": true})", "outputs.png = true: unknown key"},
    {R"("gaze": {"cone_deg": 95})", "gaze.cone_deg = 95: must be between 0 and 90"},
    {R"("gaze": {"cone_deg": 10, "screen": "uniform"})", "gaze: give exactly one of cone_deg and screen, not both"},
    {R"("gaze": {"screen": "random"})", "gaze.screen = \"random\": must be \"uniform\" or {\"grid\": [columns, rows]}"},
    {R"("gaze": {"screen": {"grid": [0, 3]}})", "gaze.screen.grid = [0, 3]: columns and rows must be in [1, 1000]"},
    {R"("gaze": {"cone_deg": 10}, "parameters": {"gaze_turn_deg": 3})", "parameters.gaze_turn_deg = 3: given by gaze too: give it once"},
    {R"("parameters": {"screen_x_mm": 10, "gaze_turn_deg": 3})", "gaze is given by a turn and by a screen target: give one"},
    {R"("parameters": {"screen_x_mm": {"uniform": [0, 600]}})", "parameters.screen_x_mm: reaches 600: must stay on the screen, [0, 518] mm"},
    {R"("parameters": {"pupil_size": 2})", "parameters.pupil_size = 2: unknown key"},
    {R"("parameters": {"pupil_radius_mm": {"uniform": [4, 1]}})", "parameters.pupil_radius_mm.uniform = [4, 1]: the low end must not exceed the high one"},
    {R"("parameters": {"pupil_radius_mm": {"uniform": [1]}})", "parameters.pupil_radius_mm.uniform = [1]: must be [low, high]"},
    {R"("parameters": {"pupil_radius_mm": {"uniform": [0, 3]}})", "parameters.pupil_radius_mm.uniform[0] = 0: must be in (0, 10] (pupil_radius_mm)"},
    {R"("parameters": {"pupil_radius_mm": {"normal": {"mean": 2, "sd": 0}}})", "parameters.pupil_radius_mm.normal.sd = 0: must be > 0"},
    {R"("parameters": {"pupil_radius_mm": {"normal": {"mean": 2, "sd": 1, "min": 3, "max": 2}}})", "parameters.pupil_radius_mm.normal: min must be below max"},
    {R"("parameters": {"pupil_radius_mm": {"normal": {"mean": 2, "sd": 1}}})", "parameters.pupil_radius_mm.normal.min: required: pupil_radius_mm must stay above 0"},
    {R"("parameters": {"pupil_radius_mm": {"uniform": [1, 2], "choice": [1]}})", "parameters.pupil_radius_mm = {...}: give exactly one of fixed, uniform, normal, choice, grid"},
    {R"("parameters": {"pupil_radius_mm": {"between": [1, 2]}})", "give exactly one of fixed, uniform, normal, choice, grid"},
    {R"("parameters": {"pupil_radius_mm": {"uniform": [1, 2], "weights": [1]}})", "parameters.pupil_radius_mm.weights: weights go with choice only"},
    {R"("parameters": {"pupil_radius_mm": {"choice": [1, 2], "weights": [1]}})", "parameters.pupil_radius_mm.weights = [1]: must give one weight per choice (2)"},
    {R"("parameters": {"pupil_radius_mm": {"choice": [1, 2], "weights": [0, 0]}})", "parameters.pupil_radius_mm.weights = [0, 0]: must not all be 0"},
    {R"("parameters": {"pupil_radius_mm": {"choice": []}})", "parameters.pupil_radius_mm.choice = []: must list at least one value"},
    {R"("parameters": {"blink": {"uniform": [0, 1]}})", "parameters.blink.uniform = [0, 1]: draw blink with choice: it takes true or false"},
    {R"("parameters": {"blink": 1})", "parameters.blink = 1: must be true or false"},
    {R"("parameters": {"iris_seed": 2.5})", "parameters.iris_seed = 2.5: must be an integer (iris_seed)"},
    {R"("parameters": {"iris_seed": {"normal": {"mean": 5, "sd": 1}}})", "a normal draws real numbers; iris_seed takes integers"},
    {R"("parameters": {"bits": 9})", "parameters.bits = 9: must be one of 8, 10, 12, 16 (bits)"},
    {R"("parameters": {"lid_opening": 1.5})", "parameters.lid_opening = 1.5: must be in [0, 1] (lid_opening)"},
    {R"("parameters": {"canthal_tilt_deg": {"uniform": [0, 20]}})", "parameters.canthal_tilt_deg.uniform[1] = 20: must be in [-15, 15] (canthal_tilt_deg)"},
    {R"("parameters": {"crease_height_mm": 3})", "parameters.crease_height_mm: the scene's first eye has no face (scene-format.md: face)"},
    {R"("parameters": {"lash_albedo": 0.05})", "parameters.lash_albedo: the scene's first eye has no lashes (scene-format.md: lashes)"},
    {R"("parameters": {"sclera_roughness_deg": 1})", "parameters.sclera_roughness_deg: the scene's first eye has no tear film (scene-format.md: tear film)"},
    {R"("parameters": {"sclera_roughness_deg": 12})", "parameters.sclera_roughness_deg = 12: must be in [0, 10] (sclera_roughness_deg)"},
    {R"("parameters": {"meniscus_radius_mm": 0.3})", "parameters.meniscus_radius_mm: the scene's first eye has no tear film (scene-format.md: tear film)"},
    {R"("parameters": {"meniscus_radius_mm": 2})", "parameters.meniscus_radius_mm = 2: must be in [0, 1] (meniscus_radius_mm)"},
    {R"("parameters": {"upper_meniscus_radius_mm": 0.2})", "parameters.upper_meniscus_radius_mm: the scene's first eye has no tear film (scene-format.md: tear film)"},
    {R"("parameters": {"midline_mm": 30})", "parameters.midline_mm = 30: unknown key"},
    {R"("parameters": {"iris_albedo": {"grid": {"from": 0.1, "to": 0.2, "steps": 0}}})", "parameters.iris_albedo.grid.steps = 0: must be in [1, 1000000]"},
    {R"("parameters": {"illuminators": {"led_middle": {"on": false}}})", "parameters.illuminators.led_middle = {...}: unknown key (valid keys here: led_left, led_right)"},
    {R"("parameters": {"illuminators": {"led_left": {"off": true}}})", "parameters.illuminators.led_left.off = true: unknown key (valid keys here: on, power_scale)"},
    {R"("parameters": {"meshes": {"glasses": {"on": false}}})", "parameters.meshes.glasses = {...}: unknown key"},
    {R"("parameters": {"exposure_s": 0})", "parameters.exposure_s = 0: must be in (0, 10] (exposure_s)"},
    {R"("outputs": {"exr": {"planes": ["Y", "Y"]}})", "outputs.exr.planes[1] = \"Y\": is listed twice"},
    {R"("parameters": {"pupil_radius_mm": {"choice": [1, 2, 3], "weights": [1e308, 1e308, 0]}})",
     "parameters.pupil_radius_mm.weights = [1e+308, 1e+308, 0]: must have a finite sum"},
    {R"("parameters": {"focus_distance_mm": {"uniform": [10, 600]}})",
     "parameters.focus_distance_mm: reaches 10 mm: must stay beyond camera 'cam0''s focal length, 16 mm"},
    {R"("parameters": {"gaze_speed_direction_deg": 90})",
     "parameters.gaze_speed_direction_deg: a direction without gaze_speed_deg_s: give the speed too"},
    {R"("parameters": {"gaze_speed_deg_s": 1200})", "parameters.gaze_speed_deg_s = 1200: must be in [0, 1000] (gaze_speed_deg_s)"},
    {R"("parameters": {"jpeg_quality": 0})", "parameters.jpeg_quality = 0: must be in [1, 100] (jpeg_quality)"},
    {R"("parameters": {"jpeg_quality": 80, "bits": {"choice": [8, 10]}})",
     "parameters.jpeg_quality: camera 'cam0' would get a JPEG of more than 8 bits: JPEG holds 8 bits"},
    {R"("parameters": {"corner_illumination": 0})", "parameters.corner_illumination = 0: must be in (0, 1] (corner_illumination)"},
    {R"("parameters": {"kappa_horizontal_deg": "5"})", "parameters.kappa_horizontal_deg = \"5\": must be a number"},
};

TEST(DatasetSpec, EachMalformedSpecGetsItsMessage) {
  EXPECT_GE(std::size(kMalformed), 25u);
  for (const Malformed& m : kMalformed) {
    const std::string message = message_of(m.body);
    EXPECT_NE(message.find(m.message), std::string::npos) << m.body << "\n  got: " << message;
  }
}

TEST(DatasetSpec, TheFileAndItsTopLevelAreChecked) {
  const auto fails_with = [](const std::string& text, const std::string& expected) {
    try {
      parse_dataset_spec(text, "s.json", kFolder);
      ADD_FAILURE() << text << ": accepted";
    } catch (const DatasetSpecError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << text << "\n  got: " << e.what();
    }
  };
  fails_with(R"({"dataset_format": 2, "scene": "../scenes/remote.json", "count": 1})",
             "s.json: dataset_format = 2: unsupported dataset format version (this program reads 1)");
  fails_with(R"({"scene": "../scenes/remote.json", "count": 1})",
             "s.json: dataset_format: missing required key (the dataset format version, 1)");
  fails_with(R"({"dataset_format": 1, "count": 1})", "s.json: scene: missing required key");
  fails_with(R"({"dataset_format": 1, "scene": "../scenes/nowhere.json", "count": 1})",
             "s.json: scene = \"../scenes/nowhere.json\": ");
  fails_with(R"({"dataset_format": 1, "scene": "../scenes/remote.json", "count": 0})",
             "s.json: count = 0: must be in [1, 2^40]");
  fails_with(R"({"dataset_format": 1, "scene": "../scenes/remote.json", "count": 1, "count": 2})",
             "s.json: invalid JSON: duplicate key \"count\"");
  fails_with(R"({"dataset_format": 1, "scene": "../scenes/remote.json", "count": 1,})", "s.json: invalid JSON");
  fails_with(R"({"dataset_format": 1, "scene": "../scenes/remote.json", "count": 1, "name": ""})",
             "s.json: name = \"\": must not be empty");
  try {
    load_dataset_spec("/nonexistent/spec.json");
    ADD_FAILURE() << "accepted";
  } catch (const DatasetSpecError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/spec.json: cannot read: "), std::string::npos) << e.what();
  }
}

TEST(DatasetSpec, TheBundledSpecsReadAndEveryImageHasAnEye) {
  for (const char* name : {"remote", "headset"}) {
    const DatasetSpec spec = load_dataset_spec(kFolder + "/" + name + ".json");
    EXPECT_GE(spec.parameters.size(), 15u) << name;
    for (std::uint64_t k = 0; k < 200; ++k) EXPECT_NO_THROW(scene_for_image(spec, draw_image(spec, k))) << name << k;
  }
}

}  // namespace
}  // namespace purkinje
