// The lens's aperture and point spread (models/camera_optics.h): thin-lens
// blur circles worked by hand.

#include "purkinje/models/camera_optics.h"

#include <gtest/gtest.h>

#include <functional>
#include <optional>
#include <stdexcept>
#include <string>

namespace purkinje {
namespace {

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no exception)";
}

Camera focusing_camera(std::optional<double> focus_mm) {
  Sensor s;
  s.pixel_pitch_mm = 0.005;
  s.f_number = 2.5;
  s.psf_sigma_px = 0.7;
  s.focus_distance_mm = focus_mm;
  Intrinsics in;
  in.fx = in.fy = 5000;  // f = 5000 * 0.005 = 25 mm
  in.cx = 319.5;
  in.cy = 239.5;
  in.width = 640;
  in.height = 480;
  return Camera("cam", in, {}, Pose(), s);
}

TEST(PointSpread, DefocusFollowsTheThinLensBlurCircle) {
  const Camera camera = focusing_camera(600.0);
  EXPECT_DOUBLE_EQ(aperture_diameter_mm(camera), 10.0);  // 25 mm / 2.5
  // b = A f |z - z_f| / (z (z_f - f)) = 10 * 25 * 100 / (500 * 575)
  //   = 0.08695652 mm = 17.391304 px; radius 8.695652 px.
  const PointSpread near = point_spread(camera, 500);
  EXPECT_NEAR(near.defocus_radius_px, 8.695652, 1e-6);
  EXPECT_DOUBLE_EQ(near.sigma_px, 0.7);
  // b depends on |1/z - 1/z_f|: 1/600 - 1/750 = 1/500 - 1/600.
  EXPECT_NEAR(point_spread(camera, 750).defocus_radius_px, 8.695652, 1e-6);
  EXPECT_EQ(point_spread(camera, 600).defocus_radius_px, 0.0);
}

TEST(PointSpread, NoFocusDistanceMeansNoDefocus) {
  const PointSpread psf = point_spread(focusing_camera(std::nullopt), 50);
  EXPECT_EQ(psf.defocus_radius_px, 0.0);
  EXPECT_DOUBLE_EQ(psf.sigma_px, 0.7);
}

TEST(PointSpread, RejectsImpossibleFocusAndDepth) {
  EXPECT_NE(message_of([] { point_spread(focusing_camera(20.0), 500); }).find("sensor.focus_distance_mm = 20"),
            std::string::npos);
  EXPECT_NE(message_of([] { point_spread(focusing_camera(600.0), 0); }).find("depth_mm = 0"),
            std::string::npos);
  EXPECT_NE(message_of([] { point_spread(focusing_camera(600.0), -5); }).find("depth_mm"), std::string::npos);
}

TEST(PointSpread, ReportsNumbersAsTheyReadBack) {
  // check::format_number: the shortest text of the double, not to_string's six decimals.
  EXPECT_NE(message_of([] { point_spread(focusing_camera(600.0), -1e-9); }).find("depth_mm = -1e-09"),
            std::string::npos);
}

}  // namespace
}  // namespace purkinje
