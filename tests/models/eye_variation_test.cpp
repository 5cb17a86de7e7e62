// Eyes turned and pupils resized about a scene's own (the sweeps behind the
// bars): checked against the geometry they promise, not against their own
// draws.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "purkinje/models/eye_variation.h"
#include "purkinje/models/scene_file.h"

namespace purkinje {
namespace {

constexpr double kDeg = std::numbers::pi / 180;

Scene bundled(const std::string& name) {
  return load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/" + name + ".json");
}

// An eye in motion turns its optical axis's yaw and pitch at the rates
// given, about its centre of rotation, keeping its look and its motion.
TEST(EyeMotion, AtATimeTheAxisHasMovedByTheRatesAboutTheRotationCentre) {
  EyeModel model;
  Eye eye = Eye::with_rotation_center(model, {5, -3, 600}, optical_axis_from_yaw_pitch(10 * kDeg, 5 * kDeg));
  EyeAppearance look;
  look.iris_albedo = 0.3;
  eye.set_appearance(look);
  eye.set_motion({300, -100});
  const Eye later = eye.at_time(0.002);  // 0.6 deg more yaw, 0.2 deg less pitch
  const UnitVector3 expected = optical_axis_from_yaw_pitch(10.6 * kDeg, 4.8 * kDeg);
  EXPECT_NEAR(angle_between(later.optical_axis(), expected), 0, 1e-12);
  EXPECT_NEAR(distance(later.rotation_center(), eye.rotation_center()), 0, 1e-12);
  EXPECT_EQ(later.appearance().iris_albedo, 0.3);
  EXPECT_EQ(later.motion().yaw_deg_s, 300);
  EXPECT_EQ(later.motion().pitch_deg_s, -100);
  // Backwards in time the other way; no time, or no motion, no turn.
  EXPECT_NEAR(angle_between(eye.at_time(-0.002).optical_axis(), optical_axis_from_yaw_pitch(9.4 * kDeg, 5.2 * kDeg)), 0,
              1e-12);
  EXPECT_EQ(eye.at_time(0).optical_axis().vector(), eye.optical_axis().vector());
  eye.set_motion({});
  EXPECT_TRUE(eye.motion().still());
  EXPECT_EQ(eye.at_time(0.002).optical_axis().vector(), eye.optical_axis().vector());
}

// An eye whose frame is twisted about its axis (as a varied eye's is)
// keeps its twist while it turns: its frame moves continuously.
TEST(EyeMotion, ATwistedEyeKeepsItsTwistWhileItTurns) {
  Scene scene = bundled("remote");
  Eye eye = with_eye_variation(scene, {30 * kDeg, 45 * kDeg, 2}).eyes[0];
  eye.set_motion({500, 200});
  const Eye soon = eye.at_time(1e-6);
  // 1e-6 s at 539 deg/s: 9.4e-6 rad of turn; each frame axis moves no more.
  const double turn = std::hypot(500, 200) * kDeg * 1e-6;
  for (const UnitVector3& axis : {UnitVector3::unit_x(), UnitVector3::unit_y(), UnitVector3::unit_z()}) {
    const UnitVector3 before = eye.world_from_eye().rotation() * axis, after = soon.world_from_eye().rotation() * axis;
    EXPECT_LE(angle_between(before, after), turn * 1.0001);
  }
  EXPECT_NEAR(distance(soon.rotation_center(), eye.rotation_center()), 0, 1e-12);
}

// A varied eye keeps its motion.
TEST(EyeVariation, KeepsTheEyesMotion) {
  Scene scene = bundled("remote");
  scene.eyes[0].set_motion({250, 40});
  const Eye t = with_eye_variation(scene, {10 * kDeg, 0, 2}).eyes[0];  // a copy: the scene is a temporary
  EXPECT_EQ(t.motion().yaw_deg_s, 250);
  EXPECT_EQ(t.motion().pitch_deg_s, 40);
}

TEST(EyeVariation, TurnsTheGazeByTheAngleTowardTheDirectionAboutTheRotationCentre) {
  const Scene scene = bundled("remote");
  const Eye& eye = scene.eyes[0];
  const UnitVector3 gaze = eye.visual_axis();
  const UnitVector3 up = UnitVector3::normalize(eye.appearance().head_up.vector() -
                                                gaze.vector() * dot(eye.appearance().head_up, gaze));
  for (const double direction : {0.0, 90 * kDeg, 200 * kDeg}) {
    const Scene turned = with_eye_variation(scene, {20 * kDeg, direction, 2.5});
    const Eye& t = turned.eyes[0];
    EXPECT_NEAR(angle_between(t.visual_axis(), gaze), 20 * kDeg, 1e-12) << direction;
    // The new gaze leans toward `direction` in the plane across the old
    // gaze: along up by cos(direction) sin(20 deg), along up x gaze by
    // sin(direction) sin(20 deg).
    const UnitVector3 side = UnitVector3::normalize(cross(up, gaze));
    EXPECT_NEAR(dot(t.visual_axis(), up), std::cos(direction) * std::sin(20 * kDeg), 1e-12) << direction;
    EXPECT_NEAR(dot(t.visual_axis(), side), std::sin(direction) * std::sin(20 * kDeg), 1e-12) << direction;
    EXPECT_NEAR(distance(t.rotation_center(), eye.rotation_center()), 0, 1e-9) << direction;
    EXPECT_DOUBLE_EQ(t.model().pupil_radius_mm, 2.5);
    EXPECT_EQ(turned.cameras.size(), scene.cameras.size());
    EXPECT_EQ(turned.illuminators.size(), scene.illuminators.size());
  }
  EXPECT_THROW(with_eye_variation(scene, {0, 0, 2}, 1), std::out_of_range);
  // A pupil of no size, or beyond the iris, and a turn that is not a number.
  EXPECT_THROW(with_eye_variation(scene, {}), std::invalid_argument);
  EXPECT_THROW(with_eye_variation(scene, {0, 0, eye.model().iris_radius_mm}), std::invalid_argument);
  EXPECT_THROW(with_eye_variation(scene, {std::nan(""), 0, 2}), std::invalid_argument);
}

TEST(EyeVariation, DrawsGazeUniformlyOverTheCapAndPupilsWithinTheRange) {
  const EyeVariationRange range{25 * kDeg, 1.5, 3.5};
  const auto draws = random_eye_variations(42, 4000, range);
  ASSERT_EQ(draws.size(), 4000u);
  double mean_one_minus_cos = 0, mean_pupil = 0, mean_cos_direction = 0;
  for (const EyeVariation& v : draws) {
    ASSERT_GE(v.gaze_turn_rad, 0);
    ASSERT_LE(v.gaze_turn_rad, range.max_gaze_turn_rad);
    ASSERT_GE(v.pupil_radius_mm, 1.5);
    ASSERT_LT(v.pupil_radius_mm, 3.5);
    mean_one_minus_cos += (1 - std::cos(v.gaze_turn_rad)) / draws.size();
    mean_pupil += v.pupil_radius_mm / draws.size();
    mean_cos_direction += std::cos(v.turn_direction_rad) / draws.size();
  }
  // Uniform over the cap: 1 - cos(turn) uniform in [0, 1 - cos 25 deg].
  // Standard errors: 0.0007, 0.009 and 0.011; bounds at 4 of them.
  EXPECT_NEAR(mean_one_minus_cos, (1 - std::cos(25 * kDeg)) / 2, 0.003);
  EXPECT_NEAR(mean_pupil, 2.5, 0.04);
  EXPECT_NEAR(mean_cos_direction, 0, 0.045);
  // Reproducible from the seed, and a different seed draws differently.
  EXPECT_EQ(random_eye_variations(42, 1, range)[0].gaze_turn_rad, draws[0].gaze_turn_rad);
  EXPECT_NE(random_eye_variations(43, 1, range)[0].gaze_turn_rad, draws[0].gaze_turn_rad);
}

TEST(EyeVariation, RejectsRangesOutOfBoundsNamingTheField) {
  const auto rejects = [](const EyeVariationRange& r, int count, const std::string& field) {
    try {
      random_eye_variations(1, count, r);
      ADD_FAILURE() << field << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  rejects({100 * kDeg, 1, 4}, 1, "max_gaze_turn_rad");
  rejects({-1 * kDeg, 1, 4}, 1, "max_gaze_turn_rad");
  rejects({30 * kDeg, 0, 4}, 1, "min_pupil_radius_mm");
  rejects({30 * kDeg, 4, 1}, 1, "max_pupil_radius_mm");
  rejects({}, -1, "count");
}

}  // namespace
}  // namespace purkinje
