#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "purkinje/models/eye.h"
#include "purkinje/models/geometry.h"
#include "purkinje/models/rotation.h"

namespace purkinje {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(UnitVector, CannotHoldANonUnitVector) {
  EXPECT_THROW(UnitVector3::from({1, 1, 0}), std::invalid_argument);
  try {
    UnitVector3::from({3, 4, 0});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("norm 5"), std::string::npos) << e.what();
  }
  EXPECT_EQ(UnitVector3::from({0, 0, 1}).z(), 1.0);
}

TEST(UnitVector, NormalizesOrSaysWhyNot) {
  const UnitVector3 u = UnitVector3::normalize({3, 4, 0});
  EXPECT_DOUBLE_EQ(u.x(), 0.6);
  EXPECT_DOUBLE_EQ(u.y(), 0.8);
  EXPECT_FALSE(UnitVector3::try_normalize({0, 0, 0}).has_value());
  EXPECT_FALSE(UnitVector3::try_normalize({INFINITY, 0, 0}).has_value());
  EXPECT_THROW(UnitVector3::normalize({0, 0, 0}), std::invalid_argument);
}

TEST(Geometry, PointMinusPointIsAVector) {
  const Point3 a{1, 2, 3}, b{4, 6, 3};
  const Vector3 d = b - a;
  EXPECT_EQ(d, (Vector3{3, 4, 0}));
  EXPECT_DOUBLE_EQ(distance(a, b), 5.0);
  EXPECT_EQ(a + d, b);
  EXPECT_EQ(b - d, a);
  EXPECT_EQ(cross(Vector3{1, 0, 0}, Vector3{0, 1, 0}), (Vector3{0, 0, 1}));
}

TEST(Geometry, AngleBetweenIsAccurateNearZeroAndPi) {
  EXPECT_NEAR(angle_between({1, 0, 0}, {1, 1e-12, 0}), 1e-12, 1e-24);
  EXPECT_NEAR(angle_between({1, 0, 0}, {-1, 1e-12, 0}), kPi - 1e-12, 1e-15);
  EXPECT_NEAR(angle_between({1, 0, 0}, {0, 2, 0}), kPi / 2, 1e-15);
}

TEST(Rotation, RotatesRightHandedAroundTheAxis) {
  const Vector3 r = rotate(Vector3{1, 0, 0}, UnitVector3::unit_z(), kPi / 2);
  EXPECT_NEAR(r.x, 0, 1e-15);
  EXPECT_NEAR(r.y, 1, 1e-15);
  const Rotation q = Rotation::from_axis_angle(UnitVector3::unit_x(), kPi / 2);
  const Vector3 y = q * Vector3{0, 1, 0};
  EXPECT_NEAR(y.z, 1, 1e-15);
}

TEST(Rotation, RotationVectorRoundTripsIncludingNearPi) {
  for (double angle : {0.0, 1e-9, 0.3, 2.0, kPi - 1e-7}) {
    const Vector3 w = UnitVector3::normalize({1, -2, 0.5}) * angle;
    const Vector3 back = Rotation::from_rotation_vector(w).rotation_vector();
    EXPECT_LT((back - w).norm(), 1e-9) << angle;
  }
}

TEST(Rotation, ComposesAndInverts) {
  const Rotation a = Rotation::from_rotation_vector({0.1, 0.2, -0.3});
  const Rotation b = Rotation::from_rotation_vector({-0.5, 0.0, 0.4});
  const Vector3 v{1, 2, 3};
  EXPECT_LT(((a * b) * v - a * (b * v)).norm(), 1e-14);
  EXPECT_LT((a.inverse() * (a * v) - v).norm(), 1e-14);
  EXPECT_THROW(Rotation::from_columns(UnitVector3::unit_x(), UnitVector3::unit_x(),
                                      UnitVector3::unit_z()),
               std::invalid_argument);
}

TEST(Pose, NamesDestinationFromSource) {
  // world_from_eye maps the eye origin to the eye's position.
  const Pose world_from_eye(Rotation::from_axis_angle(UnitVector3::unit_y(), kPi), {0, 0, 600});
  const Pose eye_from_world = world_from_eye.inverse();
  const Point3 apex_in_world = world_from_eye * Point3{0, 0, 7.8};
  EXPECT_NEAR(apex_in_world.z, 600 - 7.8, 1e-12);
  const Point3 back = eye_from_world * apex_in_world;
  EXPECT_NEAR(back.z, 7.8, 1e-12);
  const Pose identity = eye_from_world * world_from_eye;
  EXPECT_LT(identity.translation().norm(), 1e-12);
}

TEST(Eye, YawAndPitchFollowTheDocumentedConvention) {
  const UnitVector3 o = optical_axis_from_yaw_pitch(0, 0);
  EXPECT_EQ(o.z(), -1.0);
  // yaw = atan2(o_x, -o_z), pitch = asin(-o_y), as the reference README.
  const UnitVector3 p = optical_axis_from_yaw_pitch(0.3, 0.2);
  EXPECT_NEAR(std::atan2(p.x(), -p.z()), 0.3, 1e-15);
  EXPECT_NEAR(std::asin(-p.y()), 0.2, 1e-15);
}

EyeModel eye_with_kappa() {
  EyeModel m;
  m.kappa_horizontal_rad = 5 * kPi / 180;
  m.kappa_vertical_rad = 1.5 * kPi / 180;
  return m;
}

TEST(Eye, LandmarksLieAlongTheOpticalAxis) {
  EyeModel m;
  const Eye eye = Eye::with_cornea_center(m, {0, 0, 600}, optical_axis_from_yaw_pitch(0, 0));
  EXPECT_NEAR(eye.corneal_apex().z, 600 - 7.8, 1e-12);
  EXPECT_NEAR(eye.pupil_center().z, 600 - 7.8 + 3.6, 1e-12);
  EXPECT_NEAR(eye.rotation_center().z, 600 - 7.8 + 13.5, 1e-12);
  // Border angle 0 toward eye +x = world +x; 90 degrees toward eye +y = up = world -y.
  EXPECT_NEAR(eye.pupil_border_point(0).x, 2.0, 1e-12);
  EXPECT_NEAR(eye.pupil_border_point(kPi / 2).y, -2.0, 1e-12);
  // The limbus of a 7.8 mm sphere of radius 5.9 mm lies 7.8 - sqrt(7.8^2 - 5.9^2) deep.
  EXPECT_NEAR(m.limbus_depth_mm(), 7.8 - std::sqrt(7.8 * 7.8 - 5.9 * 5.9), 1e-12);
  EXPECT_TRUE(eye.on_cap(eye.corneal_apex()));
  EXPECT_FALSE(eye.on_cap(Point3{7.8, 0, 600}));
}

TEST(Eye, RotationCentrePlacementKeepsTheCorneaInFront) {
  const Eye eye = Eye::with_rotation_center(EyeModel{}, {10, 0, 600},
                                            optical_axis_from_yaw_pitch(0.4, 0));
  EXPECT_NEAR(distance(eye.rotation_center(), Point3{10, 0, 600}), 0, 1e-12);
  EXPECT_NEAR(distance(eye.corneal_apex(), eye.rotation_center()), 13.5, 1e-12);
}

TEST(Eye, KappaSeparatesVisualFromOpticalAxis) {
  const Eye eye = Eye::with_cornea_center(eye_with_kappa(), {0, 0, 600},
                                          optical_axis_from_yaw_pitch(0, 0));
  // cos(angle) = cos(h) cos(v) for the documented kappa parametrization.
  EXPECT_NEAR(std::cos(angle_between(eye.visual_axis(), eye.optical_axis())),
              std::cos(5 * kPi / 180) * std::cos(1.5 * kPi / 180), 1e-14);
  // Positive horizontal kappa turns toward eye +x (world +x here), positive vertical up (-y).
  EXPECT_GT(eye.visual_axis().x(), 0);
  EXPECT_LT(eye.visual_axis().y(), 0);
}

TEST(Eye, FixatingPutsTheTargetOnTheVisualAxis) {
  const Point3 target{150, -80, 0};
  for (const Point3& rc : {Point3{0, 0, 600}, Point3{30, 20, 35}}) {
    const Eye eye = Eye::fixating(eye_with_kappa(), rc, target);
    const Vector3 to_target = target - eye.cornea_center();
    EXPECT_LT(angle_between(eye.visual_axis(), to_target), 1e-12);
    EXPECT_LT(distance(eye.rotation_center(), rc), 1e-12);
  }
  const Eye e2 = Eye::fixating_from_cornea_center(eye_with_kappa(), {0, 0, 600}, target);
  EXPECT_LT(angle_between(e2.visual_axis(), target - Point3{0, 0, 600}), 1e-12);
}

TEST(Eye, RefusesTargetsTooCloseToFixate) {
  EXPECT_THROW(Eye::fixating(EyeModel{}, {0, 0, 600}, {0, 0, 595}), std::invalid_argument);
  EXPECT_THROW(Eye::fixating_from_cornea_center(EyeModel{}, {0, 0, 600}, {0, 0, 600}),
               std::invalid_argument);
}

TEST(Eye, FrameFallsBackWhenLookingAlongWorldX) {
  const Rotation r = world_from_eye_rotation(UnitVector3::unit_x());
  EXPECT_NEAR(r.column(2).x(), 1.0, 1e-15);
  EXPECT_NEAR(dot(r.column(0), r.column(2)), 0.0, 1e-15);
}

}  // namespace
}  // namespace purkinje
