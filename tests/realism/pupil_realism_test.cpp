// The renderer issue's realism bar: an ordinary OpenCV threshold-and-
// ellipse-fit pupil detector finds the pupil within 2 px of its label in at
// least 99% of 200 random renders (gaze within 30 deg, pupil 1 to 4 mm,
// default noise) of each bundled scene.
//
// Each render is one bundled scene with its eye turned rigidly about its
// centre of rotation so that the gaze (visual axis) moves by a direction
// drawn uniformly over the spherical cap within 30 deg of the scene's own
// gaze, and a pupil radius drawn uniformly from [1, 4] mm; everything else
// (lids, whose margins follow the turned eye's elevation, albedos, iris
// texture, lights, sensor with its noise, sampling) is as the scene and
// the renderer's defaults say. The detector sees only the 8-bit
// sensor image; the label is the refracted pupil ellipse's centre of the
// camera's view.
//
// What the bar measures, and what it found: see docs/rendering.md,
// "Realism". With the lids following vertical gaze (Eyelids in
// appearance.h) the bar is met on both scenes; the assertions below hold
// it on the full 200 renders.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "environment_count.h"
#include "purkinje/models/eye_variation.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/renderer/render.h"
#include "threshold_pupil_detector.h"

namespace purkinje::renderer {
namespace {

constexpr int kBarRenders = 200;
constexpr double kMaxGazeTurnRad = 30 * std::numbers::pi / 180;
constexpr double kDegrees = 180 / std::numbers::pi;

Scene bundled(const std::string& name) {
  return load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/" + name + ".json");
}

// The full 200 unless PURKINJE_REALISM_RENDERS says fewer: .ci/run lowers it
// for the sanitizer and coverage builds, which check the code, not the bar.
int renders_per_scene() {
  return testing::count_from_environment("PURKINJE_REALISM_RENDERS", kBarRenders, 1);
}

// ------------------------------------------------------------ random renders

// The scene's eye turned and its pupil resized (eye_variation.h): the
// gaze uniform over the cap within 30 deg of the scene's, the pupil radius
// uniform in [1, 4] mm.
struct Variant {
  int index = 0;
  EyeVariation eye;
};

std::vector<Variant> variants(std::uint64_t seed, int count) {
  std::vector<Variant> out;
  for (const EyeVariation& e : random_eye_variations(seed, count, {kMaxGazeTurnRad, 1, 4})) {
    out.push_back({static_cast<int>(out.size()), e});
  }
  return out;
}

// The eye region a tracker would crop around the eye before looking for the
// pupil: the box around the limbus's image, with a margin for the cornea's
// bulge. From the scene's geometry, not from the pupil's label.
PixelRegion eye_region(const Scene& scene) {
  const Eye& eye = scene.eyes.at(0);
  const Camera& camera = scene.cameras.at(0);
  const EyeModel& m = eye.model();
  double u0 = std::numeric_limits<double>::infinity(), v0 = u0, u1 = -u0, v1 = -u0;
  for (int k = 0; k < 36; ++k) {
    const double a = k * std::numbers::pi / 18;
    const Point3 limbus = eye.world_from_eye() * Point3{m.limbus_radius_mm * std::cos(a), m.limbus_radius_mm * std::sin(a),
                                                        m.anterior_cornea.radius_mm - m.limbus_depth_mm()};
    const Pixel p = camera.project(limbus).pixel;
    u0 = std::min(u0, p.u), u1 = std::max(u1, p.u), v0 = std::min(v0, p.v), v1 = std::max(v1, p.v);
  }
  const double margin = 0.15 * std::max(u1 - u0, v1 - v0) + 4;
  const Intrinsics& k = camera.intrinsics();
  return {std::clamp(static_cast<int>(std::floor(u0 - margin)), 0, k.width),
          std::clamp(static_cast<int>(std::floor(v0 - margin)), 0, k.height),
          std::clamp(static_cast<int>(std::ceil(u1 + margin)), 0, k.width),
          std::clamp(static_cast<int>(std::ceil(v1 + margin)), 0, k.height)};
}

// The region's pixels that do not see its black surroundings through the
// point-spread function (a Gaussian truncated at ceil(4 sigma) + 1 px in
// sensor_model.cpp): there a region render equals a full render.
cv::Rect detector_crop(const PixelRegion& r, const Sensor& sensor) {
  EXPECT_FALSE(sensor.focus_distance_mm) << "defocus widens the point spread beyond this inset";
  const int inset = static_cast<int>(std::ceil(4 * sensor.psf_sigma_px)) + 2;
  return {r.x0 + inset, r.y0 + inset, r.x1 - r.x0 - 2 * inset, r.y1 - r.y0 - 2 * inset};
}

cv::Mat eight_bit(const SensorImage& s, const cv::Rect& crop) {
  cv::Mat out(crop.height, crop.width, CV_8U);
  const int shift = std::max(0, s.bits - 8);
  for (int y = 0; y < crop.height; ++y) {
    for (int x = 0; x < crop.width; ++x) {
      const auto value = s.values[static_cast<std::size_t>(y + crop.y) * s.width + x + crop.x];
      out.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(value >> shift);
    }
  }
  return out;
}

// -------------------------------------------------------------- measurement

// How much of the pupil the lids leave to the camera (render labels mark a
// border point or the centre hidden by a lid `occluded`). The label itself,
// the ellipse through all 36 border points, is the whole pupil's whatever
// the lids hide.
enum class Visibility { whole, centre_visible, centre_hidden };

struct Outcome {
  Variant variant;
  Visibility visibility = Visibility::whole;
  int hidden_border_points = 0;
  bool found = false;
  double error_px = std::numeric_limits<double>::infinity();  // infinite when nothing was found
};

Outcome measure(const Scene& scene, const Variant& v, std::uint64_t seed) {
  const Scene s = with_eye_variation(scene, v.eye);
  EXPECT_NEAR(angle_between(s.eyes[0].visual_axis(), scene.eyes[0].visual_axis()), v.eye.gaze_turn_rad, 1e-9);
  RenderOptions options;  // default samples per pixel, noise as the scene's sensor says
  options.seed = seed;
  options.region = eye_region(s);
  const RenderResult r = render(s, 0, options);
  const cv::Rect crop = detector_crop(*options.region, s.cameras[0].sensor());
  const auto pupil = realism::detect_pupil(eight_bit(r.sensor, crop));

  const PupilTruth& label = r.truth.views.at(0).pupil;
  EXPECT_TRUE(label.ellipse_valid) << "render " << v.index;
  EXPECT_TRUE(std::isfinite(label.ellipse.center.u) && std::isfinite(label.ellipse.center.v)) << "render " << v.index;
  Outcome o;
  o.variant = v;
  for (const PupilBorderPointTruth& b : label.border) o.hidden_border_points += b.status == PathStatus::occluded;
  o.visibility = label.refracted_center_status == PathStatus::occluded ? Visibility::centre_hidden
                 : o.hidden_border_points > 0                          ? Visibility::centre_visible
                                                                       : Visibility::whole;
  if (pupil) {
    o.found = true;
    const double u = pupil->ellipse.center.x + crop.x, vv = pupil->ellipse.center.y + crop.y;
    EXPECT_TRUE(std::isfinite(u) && std::isfinite(vv)) << "render " << v.index;
    o.error_px = std::hypot(u - label.ellipse.center.u, vv - label.ellipse.center.v);
  }
  return o;
}

struct Figures {
  int renders = 0, within_2px = 0, within_1px = 0, not_found = 0;
  double mean_px = 0, median_px = 0, p95_px = 0, max_px = 0;  // over the renders where a pupil was found
  double fraction_within_2px() const { return renders ? static_cast<double>(within_2px) / renders : 0; }
  double fraction_within_1px() const { return renders ? static_cast<double>(within_1px) / renders : 0; }
};

template <class Keep>
Figures figures(const std::vector<Outcome>& outcomes, Keep keep) {
  Figures f;
  std::vector<double> errors;
  for (const Outcome& o : outcomes) {
    if (!keep(o)) continue;
    ++f.renders;
    f.within_2px += o.error_px <= 2.0;
    f.within_1px += o.error_px <= 1.0;
    if (o.found) errors.push_back(o.error_px); else ++f.not_found;
  }
  if (!errors.empty()) {
    std::sort(errors.begin(), errors.end());
    for (double e : errors) f.mean_px += e / errors.size();
    f.median_px = errors[errors.size() / 2];
    f.p95_px = errors[std::min(errors.size() - 1, static_cast<std::size_t>(std::ceil(0.95 * errors.size())) - 1)];
    f.max_px = errors.back();
  }
  return f;
}

std::string format(double x) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(3) << x;
  return s.str();
}

struct SceneFigures {
  Figures all, whole, centre_visible_or_whole;
};

SceneFigures run_scene(const std::string& name, std::uint64_t variant_seed) {
  const Scene scene = bundled(name);
  const int n = renders_per_scene();
  std::vector<Outcome> outcomes;
  for (const Variant& v : variants(variant_seed, n)) {
    outcomes.push_back(measure(scene, v, variant_seed * 1000 + v.index));
  }
  const SceneFigures f{
      figures(outcomes, [](const Outcome&) { return true; }),
      figures(outcomes, [](const Outcome& o) { return o.visibility == Visibility::whole; }),
      figures(outcomes, [](const Outcome& o) { return o.visibility != Visibility::centre_hidden; })};

  std::cout << "realism " << name << ": " << n << " renders, gaze within 30 deg of the scene's, pupil 1-4 mm, "
            << "default noise and samples per pixel\n"
            << "  subset                          renders  within 2px  within 1px  not found"
            << "  error px (found): mean  median  p95  max\n";
  const auto row = [&](const std::string& subset, const std::string& key, const Figures& x) {
    std::cout << "  " << std::left << std::setw(32) << subset << std::right << std::setw(7) << x.renders
              << std::setw(12) << format(x.fraction_within_2px()) << std::setw(12) << format(x.fraction_within_1px())
              << std::setw(11) << x.not_found << "  " << std::setw(22) << format(x.mean_px) << std::setw(8)
              << format(x.median_px) << std::setw(7) << format(x.p95_px) << std::setw(8) << format(x.max_px) << "\n";
    const std::string prefix = name + "_" + key + "_";
    ::testing::Test::RecordProperty(prefix + "renders", x.renders);
    ::testing::Test::RecordProperty(prefix + "within_2px", format(x.fraction_within_2px()));
    ::testing::Test::RecordProperty(prefix + "within_1px", format(x.fraction_within_1px()));
    ::testing::Test::RecordProperty(prefix + "not_found", x.not_found);
    ::testing::Test::RecordProperty(prefix + "mean_px", format(x.mean_px));
    ::testing::Test::RecordProperty(prefix + "median_px", format(x.median_px));
    ::testing::Test::RecordProperty(prefix + "p95_px", format(x.p95_px));
    ::testing::Test::RecordProperty(prefix + "max_px", format(x.max_px));
  };
  row("all (the bar)", "all", f.all);
  row("pupil wholly visible", "whole", f.whole);
  row("pupil centre visible", "centre_visible", f.centre_visible_or_whole);
  const int centre_hidden = f.all.renders - f.centre_visible_or_whole.renders;
  std::cout << "  pupil centre hidden by a lid: " << centre_hidden << " renders; part of the border hidden: "
            << f.centre_visible_or_whole.renders - f.whole.renders << "\n";
  ::testing::Test::RecordProperty(name + "_centre_hidden", centre_hidden);
  // The misses the lids do not explain away, for the closing note.
  for (const Outcome& o : outcomes) {
    if (o.error_px <= 2.0 || o.visibility == Visibility::centre_hidden) continue;
    std::cout << "  miss: render " << o.variant.index << ", gaze turned " << format(o.variant.eye.gaze_turn_rad * kDegrees)
              << " deg toward " << format(o.variant.eye.turn_direction_rad * kDegrees) << " deg (0 up, 90 world +x), pupil "
              << format(o.variant.eye.pupil_radius_mm) << " mm, " << o.hidden_border_points
              << "/36 border points under a lid: " << (o.found ? format(o.error_px) + " px" : "not found") << "\n";
  }
  return f;
}

// The bar: at least 0.99 of the 200 renders within 2 px, and of the
// subsets the lids leave whole or with the centre visible. It is asserted
// on the full 200 only (PURKINJE_REALISM_RENDERS lowers the count to check
// the code, not the bar); the wholly visible pupils are held to it always.
void expect_realism(const SceneFigures& f) {
  EXPECT_GT(f.whole.renders, 0);
  EXPECT_GE(f.whole.fraction_within_2px(), 0.99);
  if (f.all.renders == kBarRenders) {
    EXPECT_GE(f.all.fraction_within_2px(), 0.99) << "the bar";
    EXPECT_GE(f.centre_visible_or_whole.fraction_within_2px(), 0.99);
    // The lids still take part: some pupils are partly covered (7 remote,
    // 36 headset when measured), so the bar is not met by lids that moved
    // out of the way.
    EXPECT_LT(f.whole.renders, f.all.renders) << "no lid covers any pupil";
  }
}

TEST(PupilRealism, RemoteScene) { expect_realism(run_scene("remote", 1)); }

TEST(PupilRealism, HeadsetScene) { expect_realism(run_scene("headset", 2)); }

// The test renders only the eye region: pixels outside it stay black and
// the point-spread function blurs that black into the region's rim. The
// detector's crop must not see it: there the region render must equal a
// full render, noise included.
TEST(PupilRealism, EyeRegionCropMatchesFullRender) {
  for (const char* name : {"remote", "headset"}) {
    const Scene scene = with_eye_variation(bundled(name), variants(3, 1).front().eye);
    RenderOptions options;
    options.seed = 7;
    options.region = eye_region(scene);
    const cv::Rect crop = detector_crop(*options.region, scene.cameras[0].sensor());
    ASSERT_GT(crop.area(), 1000) << name;
    const cv::Mat region = eight_bit(render(scene, 0, options).sensor, crop);
    options.region.reset();
    const cv::Mat full = eight_bit(render(scene, 0, options).sensor, crop);
    EXPECT_EQ(cv::countNonZero(region != full), 0) << name;
  }
}

}  // namespace
}  // namespace purkinje::renderer
