// What a real camera adds beyond noise: lens vignetting, hot pixels, MJPEG
// compression (models/sensor.h), and motion blur from an eye that turns
// during the exposure (models/eye.h). Expected values by hand, from
// OpenCV's own JPEG round trip, or from the labels' geometry.

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "purkinje/models/scene_file.h"
#include "purkinje/models/truth.h"
#include "purkinje/renderer/image_io.h"
#include "purkinje/renderer/render.h"
#include "purkinje/renderer/sensor_model.h"

namespace purkinje::renderer {
namespace {

// A 640 x 480 camera whose principal point is off centre, at (300, 200):
// its farthest pixel edge corner is (639.5, 479.5), 339.5 and 279.5 px away.
Camera camera_with(const Sensor& sensor) {
  Intrinsics k;
  k.fx = k.fy = 800;
  k.cx = 300;
  k.cy = 200;
  k.width = 640;
  k.height = 480;
  return Camera("cam", k, Distortion{}, Pose{}, sensor);
}

TEST(LensIllumination, FallsQuadraticallyToTheCornerValue) {
  Sensor sensor;
  sensor.corner_illumination = 0.4;
  const Camera camera = camera_with(sensor);
  const double far2 = 339.5 * 339.5 + 279.5 * 279.5;
  EXPECT_DOUBLE_EQ(lens_illumination(camera, 300, 200), 1.0);
  EXPECT_NEAR(lens_illumination(camera, 639.5, 479.5), 0.4, 1e-15);
  // Halfway to that corner: 1 - 0.6 / 4.
  EXPECT_NEAR(lens_illumination(camera, 300 + 339.5 / 2, 200 + 279.5 / 2), 0.85, 1e-15);
  // The nearest corner, (-0.5, -0.5): 300.5 and 200.5 px away.
  EXPECT_NEAR(lens_illumination(camera, -0.5, -0.5), 1 - 0.6 * (300.5 * 300.5 + 200.5 * 200.5) / far2, 1e-15);
  sensor.corner_illumination = 1;
  EXPECT_EQ(lens_illumination(camera_with(sensor), 639.5, 479.5), 1.0);
  sensor.corner_illumination = 0;
  EXPECT_THROW(lens_illumination(camera_with(sensor), 0, 0), std::invalid_argument);
}

TEST(HotPixels, AreAFixedPatternOfTheGivenFractionAndCharge) {
  Sensor sensor;
  sensor.hot_pixel_fraction = 0.001;
  sensor.hot_pixel_e_per_s = 1e6;
  sensor.exposure_s = 0.002;
  const std::vector<HotPixel> hot = hot_pixels(sensor, 1000, 1000);
  // Binomial(1e6, 1e-3): mean 1000, sigma 31.6; within 4 sigma.
  EXPECT_NEAR(static_cast<double>(hot.size()), 1000, 127);
  double sum = 0;
  std::set<std::pair<int, int>> places;
  for (const HotPixel& p : hot) {
    EXPECT_GE(p.dark_e, 1000);  // 1e6 e/s x 2 ms x [0.5, 1.5)
    EXPECT_LT(p.dark_e, 3000);
    sum += p.dark_e;
    places.insert({p.x, p.y});
    ASSERT_TRUE(p.x >= 0 && p.x < 1000 && p.y >= 0 && p.y < 1000);
  }
  EXPECT_EQ(places.size(), hot.size());
  // Mean 2000 e, sigma of the mean 1000 / sqrt(12 n) ~ 9 e.
  EXPECT_NEAR(sum / static_cast<double>(hot.size()), 2000, 40);
  // The same pixels again; another seed, other pixels; none at fraction 0.
  const std::vector<HotPixel> again = hot_pixels(sensor, 1000, 1000);
  ASSERT_EQ(again.size(), hot.size());
  for (std::size_t i = 0; i < hot.size(); ++i) {
    EXPECT_TRUE(again[i].x == hot[i].x && again[i].y == hot[i].y && again[i].dark_e == hot[i].dark_e);
  }
  sensor.hot_pixel_seed = 2;
  int shared = 0;
  for (const HotPixel& p : hot_pixels(sensor, 1000, 1000)) shared += static_cast<int>(places.count({p.x, p.y}));
  EXPECT_LT(shared, 10);  // ~1 expected by chance
  sensor.hot_pixel_fraction = 0;
  EXPECT_TRUE(hot_pixels(sensor, 1000, 1000).empty());
  sensor.hot_pixel_fraction = 0.02;
  EXPECT_THROW(hot_pixels(sensor, 10, 10), std::invalid_argument);
}

TEST(HotPixels, AddTheirChargeToTheImageWithoutNoiseAndWithIt) {
  Sensor sensor;
  sensor.hot_pixel_fraction = 0.01;
  sensor.hot_pixel_e_per_s = 1e6;
  sensor.exposure_s = 0.002;
  sensor.bits = 16;
  sensor.full_well_e = 65535;  // DN = electrons
  sensor.noise = false;
  ImagePlane light(200, 100);
  std::fill(light.values.begin(), light.values.end(), 100.0f);
  const std::vector<HotPixel> hot = hot_pixels(sensor, 200, 100);
  ASSERT_GT(hot.size(), 100u);
  const SensorImage image = expose(light, sensor, 7);
  std::vector<double> expected(light.values.size(), 100);
  for (const HotPixel& p : hot) expected[static_cast<std::size_t>(p.y) * 200 + p.x] += p.dark_e;
  for (std::size_t i = 0; i < expected.size(); ++i) ASSERT_EQ(image.values[i], std::round(expected[i])) << i;
  // With noise: Poisson about light + dark (sigma ~ 45 e): within 6 sigma.
  sensor.noise = true;
  sensor.read_noise_e = 0;
  const SensorImage noisy = expose(light, sensor, 7);
  for (const HotPixel& p : hot) {
    const double mean = 100 + p.dark_e;
    EXPECT_NEAR(noisy.values[static_cast<std::size_t>(p.y) * 200 + p.x], mean, 6 * std::sqrt(mean));
  }
}

// An 8-bit test card: a gradient, a disc (an edge at every angle) and fine
// stripes, whose blocks JPEG quantizes differently.
SensorImage test_card() {
  SensorImage image;
  image.width = 96;
  image.height = 72;
  image.bits = 8;
  image.values.resize(96 * 72);
  for (int y = 0; y < 72; ++y) {
    for (int x = 0; x < 96; ++x) {
      int v = 30 + 2 * x;
      if ((x - 50) * (x - 50) + (y - 36) * (y - 36) < 400) v = 220;
      if (y > 60) v = (x % 3 == 0) ? 240 : 20;
      image.values[static_cast<std::size_t>(y) * 96 + x] = static_cast<unsigned short>(v);
    }
  }
  return image;
}

// What OpenCV (libjpeg, its standard tables scaled to the quality) makes of
// the same image.
std::vector<unsigned short> through_opencv(const SensorImage& image, int quality) {
  cv::Mat grey(image.height, image.width, CV_8UC1);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      grey.at<unsigned char>(y, x) = static_cast<unsigned char>(image.values[static_cast<std::size_t>(y) * image.width + x]);
    }
  }
  std::vector<unsigned char> bytes;
  cv::imencode(".jpg", grey, bytes, {cv::IMWRITE_JPEG_QUALITY, quality});
  const cv::Mat decoded = cv::imdecode(bytes, cv::IMREAD_GRAYSCALE);
  std::vector<unsigned short> out;
  for (int y = 0; y < decoded.rows; ++y) {
    for (int x = 0; x < decoded.cols; ++x) out.push_back(decoded.at<unsigned char>(y, x));
  }
  return out;
}

double mean_absolute_change(const SensorImage& a, const SensorImage& b) {
  double sum = 0;
  for (std::size_t i = 0; i < a.values.size(); ++i) sum += std::abs(double(a.values[i]) - double(b.values[i]));
  return sum / static_cast<double>(a.values.size());
}

TEST(CompressJpeg, GivesLibjpegsPixelsAtTheQualityAsked) {
  const SensorImage card = test_card();
  double previous_change = 1e9;
  for (int quality : {10, 50, 75, 95}) {
    SensorImage image = card;
    compress_jpeg(image, quality);
    EXPECT_EQ(image.values, through_opencv(card, quality)) << "quality " << quality;
    const double change = mean_absolute_change(image, card);
    EXPECT_GT(change, 0) << quality;
    EXPECT_LT(change, previous_change) << quality;  // less loss at higher quality
    previous_change = change;
  }
}

TEST(CompressJpeg, RejectsDeepImagesAndQualitiesOutOfRange) {
  SensorImage image = test_card();
  EXPECT_THROW(compress_jpeg(image, 0), std::invalid_argument);
  EXPECT_THROW(compress_jpeg(image, 101), std::invalid_argument);
  image.bits = 10;
  EXPECT_THROW(compress_jpeg(image, 75), std::invalid_argument);
}

Scene bundled(const std::string& name) {
  return load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/" + name + ".json");
}

Scene with_sensor(Scene scene, const Sensor& sensor) {
  Camera& c = scene.cameras.at(0);
  c = Camera(c.name(), c.intrinsics(), c.distortion(), c.world_from_camera(), sensor);
  return scene;
}

// The lens's vignetting scales every pixel's light and every glint by
// lens_illumination at its place: the ratio of two renders of one scene,
// with and without it, is the closed form wherever the light is not
// clipped (no noise; radiance is untouched).
TEST(LensIllumination, ScalesTheRenderedLightAndTheGlints) {
  const Scene plain = bundled("headset");
  Sensor sensor = plain.cameras[0].sensor();
  sensor.corner_illumination = 0.5;
  const Scene vignetted = with_sensor(plain, sensor);
  RenderOptions options;
  options.noise = false;
  options.edge_samples_per_pixel = 0;
  const RenderResult a = render(plain, 0, options), b = render(vignetted, 0, options);
  // The light is blurred after the vignetting: a pixel's ratio mixes its
  // neighbours' factors, which differ from its own by at most the factor's
  // slope, 2 (1 - corner) rho / far <= 1 / far = 1 / 283 per pixel here.
  const Camera& camera = vignetted.cameras[0];
  int compared = 0;
  for (int y = 5; y < a.electrons.height - 5; y += 7) {
    for (int x = 5; x < a.electrons.width - 5; x += 7) {
      if (!(a.electrons.at(x, y) > 10)) continue;
      EXPECT_NEAR(b.electrons.at(x, y) / a.electrons.at(x, y), lens_illumination(camera, x, y), 1.0 / 283) << x << ", " << y;
      ++compared;
    }
  }
  EXPECT_GT(compared, 1000);
  EXPECT_EQ(a.radiance.values, b.radiance.values);
  ASSERT_EQ(a.glints.size(), b.glints.size());
  int glints = 0;
  for (std::size_t i = 0; i < a.glints.size(); ++i) {
    if (a.glints[i].status != PathStatus::ok) continue;
    const Pixel p = a.truth.views[0].glints[a.glints[i].illuminator].pixel;
    EXPECT_NEAR(b.glints[i].electrons / a.glints[i].electrons, lens_illumination(camera, p.u, p.v), 1e-12);
    ++glints;
  }
  EXPECT_GT(glints, 4);
}

const ImagePlane& aov(const RenderResult& result, const std::string& name) {
  for (const NamedPlane& p : result.aovs) {
    if (p.name == name) return p.plane;
  }
  throw std::runtime_error("no AOV " + name);
}

// A saccade's glints are streaks: with only the glints lit (every albedo
// 0), each streak's centroid is the time average of its glint's labelled
// position over the exposure (from the truth of the eye at 201 instants,
// not the renderer's own instants), and its variance along the motion
// that of a uniform segment as long as the glint's travel, L^2 / 12, plus
// the point spread's and the pixel's. The labels are the mid-exposure
// eye's.
TEST(MotionBlur, AGlintsStreakIsItsPathOverTheExposure) {
  Scene scene = bundled("headset");
  Eye& eye = scene.eyes[0];
  EyeAppearance dark = eye.appearance();
  dark.iris_albedo = dark.sclera_albedo = dark.skin_albedo = dark.fundus_reflectance = 0;
  eye.set_appearance(dark);
  eye.set_motion({800, 300});
  Sensor sensor = scene.cameras[0].sensor();
  sensor.exposure_s = 0.004;  // 3.4 deg of turn
  scene = with_sensor(scene, sensor);
  const double exposure = sensor.exposure_s;
  RenderOptions options;
  options.noise = false;
  options.edge_samples_per_pixel = 0;
  const RenderResult result = render(scene, 0, options);
  Scene still = scene;
  still.eyes[0].set_motion({});
  const SceneTruth mid = compute_truth(still);
  const RenderResult spots = render(still, 0, options);

  // Each glint's path: its label at 201 instants across the exposure.
  const std::size_t lights = scene.illuminators.size();
  constexpr int kInstants = 201;
  std::vector<double> mean_u(lights), mean_v(lights);
  std::vector<Pixel> first(lights), last(lights);
  std::vector<bool> seen(lights, true);
  for (int k = 0; k < kInstants; ++k) {
    Scene at = still;
    at.eyes[0] = scene.eyes[0].at_time((static_cast<double>(k) / (kInstants - 1) - 0.5) * exposure);
    const SceneTruth truth = compute_truth(at);
    for (std::size_t l = 0; l < lights; ++l) {
      const GlintTruth& g = truth.views[0].glints[l];
      seen[l] = seen[l] && g.status == PathStatus::ok;
      mean_u[l] += g.pixel.u / kInstants;
      mean_v[l] += g.pixel.v / kInstants;
      if (k == 0) first[l] = g.pixel;
      if (k == kInstants - 1) last[l] = g.pixel;
    }
  }
  // The labels are the eye's at mid-exposure.
  for (std::size_t l = 0; l < lights; ++l) {
    EXPECT_EQ(result.truth.views[0].glints[l].pixel.u, mid.views[0].glints[l].pixel.u);
  }

  const ImagePlane& e = result.electrons;
  // A plane's centroid and variance along (du, dv) / length in a window.
  struct Spread {
    double u = 0, v = 0, along = 0;
  };
  const auto spread = [](const ImagePlane& plane, double u, double v, double reach, double du, double dv) {
    const double length = std::hypot(du, dv);
    const int x0 = static_cast<int>(u - reach), x1 = static_cast<int>(u + reach) + 1;
    const int y0 = static_cast<int>(v - reach), y1 = static_cast<int>(v + reach) + 1;
    double total = 0, su = 0, sv = 0;
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        total += plane.at(x, y);
        su += plane.at(x, y) * x;
        sv += plane.at(x, y) * y;
      }
    }
    Spread s{su / total, sv / total, 0};
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const double t = ((x - s.u) * du + (y - s.v) * dv) / length;
        s.along += plane.at(x, y) * t * t / total;
      }
    }
    return s;
  };
  int checked = 0;
  double longest = 0, worst_px = 0;
  for (std::size_t l = 0; l < lights; ++l) {
    if (!seen[l]) continue;
    const double du = last[l].u - first[l].u, dv = last[l].v - first[l].v, length = std::hypot(du, dv);
    longest = std::max(longest, length);
    // A window around the streak that no other glint's streak reaches.
    const double reach = length / 2 + 4;
    bool alone = true;
    for (std::size_t m = 0; m < lights; ++m) {
      if (m != l && seen[m] && std::hypot(mean_u[m] - mean_u[l], mean_v[m] - mean_v[l]) < 2 * reach + 2) alone = false;
    }
    if (!alone) continue;
    const Spread streak = spread(e, mean_u[l], mean_v[l], reach, du, dv);
    // The streak holds the glint's electrons over the exposure, as its
    // label says (a spot's tails beyond 5 sigma and the window aside).
    double streak_electrons = 0;
    for (int y = static_cast<int>(mean_v[l] - reach); y <= static_cast<int>(mean_v[l] + reach) + 1; ++y) {
      for (int x = static_cast<int>(mean_u[l] - reach); x <= static_cast<int>(mean_u[l] + reach) + 1; ++x) {
        streak_electrons += e.at(x, y);
      }
    }
    EXPECT_NEAR(streak_electrons, result.glints[l].electrons, 1e-3 * result.glints[l].electrons) << "light " << l;
    EXPECT_NEAR(streak.u, mean_u[l], 0.05) << "light " << l;
    EXPECT_NEAR(streak.v, mean_v[l], 0.05) << "light " << l;
    // The still glint's own spread (point spread, pixel, LED), plus the
    // segment's.
    const Pixel at = mid.views[0].glints[l].pixel;
    const Spread spot = spread(spots.electrons, at.u, at.v, reach, du, dv);
    // n instants, n >= 2 x the apex's travel + 1 >= 2 L + 1 (a glint moves
    // less than the apex), give L^2 (1 - 1/n^2) / 12: within 2% here.
    EXPECT_NEAR(streak.along, spot.along + length * length / 12, 0.02 * length * length / 12) << "light " << l;
    // The glint mask covers the streak (only glints are lit): all of it.
    const ImagePlane& mask = aov(result, "glint");
    for (int y = static_cast<int>(mean_v[l] - reach); y <= static_cast<int>(mean_v[l] + reach) + 1; ++y) {
      for (int x = static_cast<int>(mean_u[l] - reach); x <= static_cast<int>(mean_u[l] + reach) + 1; ++x) {
        if (e.at(x, y) > 1) {
          EXPECT_GT(mask.at(x, y), 0.999) << x << ", " << y;
        }
      }
    }
    worst_px = std::max(worst_px, std::hypot(streak.u - mean_u[l], streak.v - mean_v[l]));
    ++checked;
  }
  EXPECT_GE(checked, 3);
  EXPECT_GT(longest, 3);  // streaks, not spots
  RecordProperty("streaks", checked);
  RecordProperty("longest_px", std::to_string(longest));
  RecordProperty("worst_centroid_px", std::to_string(worst_px));
}

TEST(MotionBlur, AnEyeThatMovesTooFarDuringTheExposureIsRefused) {
  Scene scene = bundled("headset");
  scene.eyes[0].set_motion({1000, 0});
  Sensor sensor = scene.cameras[0].sensor();
  sensor.exposure_s = 0.5;
  scene = with_sensor(scene, sensor);
  RenderResult result;
  try {
    render(scene, 0, {}, result);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("render: eyes[0] moves"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("motion blur renders at most 128 px"), std::string::npos) << error.what();
  }
  EXPECT_TRUE(result.sensor.values.empty());  // untouched
}

// A scene built in code breaks the scene file's rules: refused before
// anything is rendered, naming the key, value and rule.
TEST(SensorRealism, BadSettingsInCodeAreRefusedBeforeRendering) {
  const Scene base = bundled("headset");
  const std::vector<std::pair<std::function<void(Scene&)>, std::string>> cases = {
      {[](Scene& s) { Sensor x = s.cameras[0].sensor(); x.corner_illumination = 0; s = with_sensor(s, x); },
       "render: cameras[0].sensor.corner_illumination = 0: must be > 0 and <= 1"},
      {[](Scene& s) { Sensor x = s.cameras[0].sensor(); x.hot_pixel_fraction = 0.5; s = with_sensor(s, x); },
       "render: cameras[0].sensor.hot_pixel_fraction = 0.5: must be between 0 and 0.01"},
      {[](Scene& s) { Sensor x = s.cameras[0].sensor(); x.hot_pixel_e_per_s = -1; s = with_sensor(s, x); },
       "render: cameras[0].sensor.hot_pixel_e_per_s = -1: must be finite and >= 0"},
      {[](Scene& s) { Sensor x = s.cameras[0].sensor(); x.jpeg_quality = 0; s = with_sensor(s, x); },
       "render: cameras[0].sensor.jpeg_quality = 0: must be an integer from 1 to 100"},
      {[](Scene& s) { Sensor x = s.cameras[0].sensor(); x.jpeg_quality = 80; x.bits = 12; s = with_sensor(s, x); },
       "render: cameras[0].sensor.jpeg_quality = 80: needs 8-bit images (bits = 12)"},
      {[](Scene& s) { s.eyes[0].set_motion({std::nan(""), 0}); },
       "render: eyes[0].motion.yaw_deg_s = nan: must be between -1000 and 1000"},
      {[](Scene& s) { s.eyes[0].set_motion({0, 2000}); },
       "render: eyes[0].motion.pitch_deg_s = 2000: must be between -1000 and 1000"},
  };
  for (const auto& [spoil, message] : cases) {
    Scene scene = base;
    spoil(scene);
    RenderResult result;
    try {
      render(scene, 0, {}, result);
      ADD_FAILURE() << "no exception: " << message;
    } catch (const std::invalid_argument& error) {
      EXPECT_NE(std::string(error.what()).find(message), std::string::npos) << error.what();
    }
    EXPECT_TRUE(result.sensor.values.empty() && result.electrons.values.empty()) << message;
  }
}

}  // namespace
}  // namespace purkinje::renderer
