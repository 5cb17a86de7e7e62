#include "purkinje/models/camera.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>

namespace purkinje {
namespace {

// The reference camera of tests/data/reference: f = 25 mm, 5 um pixels.
Intrinsics reference_intrinsics() { return Intrinsics::from_focal_length(25, 0.005, 2560, 2048); }

Camera camera_at_origin(const Distortion& distortion = {}) {
  return Camera("cam", reference_intrinsics(), distortion, Pose());
}

// A small camera whose image edges are easy to reach by hand.
Camera small_camera() {
  Intrinsics in;
  in.fx = in.fy = 100;
  in.cx = 49.5;
  in.cy = 39.5;
  in.width = 100;
  in.height = 80;
  return Camera("small", in, {}, Pose());
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no exception)";
}

TEST(Intrinsics, FromFocalLengthPutsThePrincipalPointAtTheImageCentre) {
  const Intrinsics in = reference_intrinsics();
  EXPECT_DOUBLE_EQ(in.fx, 5000);
  EXPECT_DOUBLE_EQ(in.fy, 5000);
  // Pixel centres are integers: the centre of a 2560-wide image is 1279.5.
  EXPECT_DOUBLE_EQ(in.cx, 1279.5);
  EXPECT_DOUBLE_EQ(in.cy, 1023.5);
  EXPECT_EQ(in.width, 2560);
  EXPECT_EQ(in.height, 2048);
}

TEST(Intrinsics, FromFocalLengthRejectsNonPositiveValuesByName) {
  EXPECT_NE(message_of([] { Intrinsics::from_focal_length(-25, 0.005, 10, 10); })
                .find("focal_length_mm = -25"),
            std::string::npos);
  EXPECT_NE(message_of([] { Intrinsics::from_focal_length(25, 0, 10, 10); }).find("pixel_pitch_mm"),
            std::string::npos);
  EXPECT_NE(message_of([] { Intrinsics::from_focal_length(25, 0.005, 0, 10); }).find("width"),
            std::string::npos);
}

TEST(ProjectionStatus, HasSnakeCaseNames) {
  EXPECT_STREQ(to_string(ProjectionStatus::ok), "ok");
  EXPECT_STREQ(to_string(ProjectionStatus::behind_camera), "behind_camera");
  EXPECT_STREQ(to_string(ProjectionStatus::outside_image), "outside_image");
}

TEST(Camera, ProjectsAPointOnTheOpticalAxisToTheImageCentre) {
  const Projection p = camera_at_origin().project({0, 0, 600});
  EXPECT_EQ(p.status, ProjectionStatus::ok);
  EXPECT_DOUBLE_EQ(p.pixel.u, (2560 - 1) / 2.0);
  EXPECT_DOUBLE_EQ(p.pixel.v, (2048 - 1) / 2.0);
}

TEST(Camera, ProjectsLikeAPinhole) {
  // u = 5000 * 10 / 500 + 1279.5, v = 5000 * -5 / 500 + 1023.5.
  const Projection p = camera_at_origin().project({10, -5, 500});
  EXPECT_EQ(p.status, ProjectionStatus::ok);
  EXPECT_NEAR(p.pixel.u, 1379.5, 1e-9);
  EXPECT_NEAR(p.pixel.v, 973.5, 1e-9);
}

TEST(Camera, DistortsWithTheBrownConradyPolynomial) {
  const Distortion d{.k1 = 0.1, .k2 = 0.01, .p1 = 0.001, .p2 = 0.002, .k3 = 0.001};
  const Camera camera = camera_at_origin(d);
  // x = 0.1, y = 0.2: r2 = 0.05, radial = 1 + 0.005 + 0.000025 + 0.000000125;
  // xd = 0.1 radial + 2 p1 x y + p2 (r2 + 2 x^2) = 0.1005025125 + 0.00004 + 0.00014
  // yd = 0.2 radial + p1 (r2 + 2 y^2) + 2 p2 x y = 0.201005025 + 0.00013 + 0.00008
  double xd = 0, yd = 0;
  camera.distort(0.1, 0.2, xd, yd);
  EXPECT_NEAR(xd, 0.1006825125, 1e-15);
  EXPECT_NEAR(yd, 0.201215025, 1e-15);

  const Projection p = camera.project({0.1 * 300, 0.2 * 300, 300});
  EXPECT_NEAR(p.pixel.u, 5000 * 0.1006825125 + 1279.5, 1e-9);
  EXPECT_NEAR(p.pixel.v, 5000 * 0.201215025 + 1023.5, 1e-9);
}

TEST(Camera, ProjectionDerivativesOfAPinholeAreFOverZ) {
  // u = fx x / z + cx: du/dx = 5000 / 500 = 10, du/dz = -5000 * 10 / 500^2
  // = -0.2; v likewise with y = -5: dv/dy = 10, dv/dz = 0.1.
  std::array<double, 6> d{};
  const Projection p = camera_at_origin().project({10, -5, 500}, d);
  EXPECT_NEAR(p.pixel.u, 1379.5, 1e-9);
  const double expected[6] = {10, 0, -0.2, 0, 10, 0.1};
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(d[i], expected[i], 1e-12) << i;
}

TEST(Camera, ProjectionDerivativesMatchDifferencesThroughATurnedDistortingLens) {
  const Distortion distortion{.k1 = -0.2, .k2 = 0.05, .p1 = 0.002, .p2 = -0.001, .k3 = 0.01};
  const Camera camera("cam", reference_intrinsics(), distortion,
                      camera_looking_at({40, -30, -20}, {5, 8, 560}, {0.2, -1, 0.1}));
  const Point3 point{30, 45, 540};
  std::array<double, 6> d{};
  ASSERT_EQ(camera.project(point, d).status, ProjectionStatus::ok);
  constexpr double h = 1e-4;
  for (int k = 0; k < 3; ++k) {
    Point3 plus = point, minus = point;
    (k == 0 ? plus.x : k == 1 ? plus.y : plus.z) += h;
    (k == 0 ? minus.x : k == 1 ? minus.y : minus.z) -= h;
    const Pixel a = camera.project(plus).pixel, b = camera.project(minus).pixel;
    EXPECT_NEAR(d[k], (a.u - b.u) / (2 * h), 1e-6) << k;
    EXPECT_NEAR(d[3 + k], (a.v - b.v) / (2 * h), 1e-6) << k;
  }
  std::array<double, 6> behind{1, 1, 1, 1, 1, 1};
  EXPECT_EQ(camera_at_origin().project({0, 0, -5}, behind).status, ProjectionStatus::behind_camera);
  for (const double e : behind) EXPECT_EQ(e, 0);
}

TEST(Camera, ZeroDistortionLeavesCoordinatesUnchanged) {
  double xd = 0, yd = 0, x = 0, y = 0;
  camera_at_origin().distort(0.3, -0.2, xd, yd);
  EXPECT_EQ(xd, 0.3);
  EXPECT_EQ(yd, -0.2);
  camera_at_origin().undistort(0.3, -0.2, x, y);
  EXPECT_EQ(x, 0.3);
  EXPECT_EQ(y, -0.2);
}

TEST(Camera, UndistortInvertsDistort) {
  const Distortion d{.k1 = -0.28, .k2 = 0.07, .p1 = 0.0012, .p2 = -0.0009, .k3 = -0.01};
  const Camera camera = camera_at_origin(d);
  for (double x = -0.25; x <= 0.25; x += 0.05) {
    for (double y = -0.2; y <= 0.2; y += 0.05) {
      double xd = 0, yd = 0, xu = 0, yu = 0;
      camera.distort(x, y, xd, yd);
      camera.undistort(xd, yd, xu, yu);
      EXPECT_NEAR(xu, x, 1e-14) << x << ", " << y;
      EXPECT_NEAR(yu, y, 1e-14) << x << ", " << y;
    }
  }
}

TEST(Camera, BackProjectionRoundTripsThroughStrongDistortionOverTheImage) {
  // Barrel distortion of a short lens: about 9 % at the image corner.
  Intrinsics in;
  in.fx = in.fy = 1000;
  in.cx = 639.5;
  in.cy = 511.5;
  in.width = 1280;
  in.height = 1024;
  const Distortion d{.k1 = -0.3, .k2 = 0.1, .p1 = 0.001, .p2 = -0.0015, .k3 = -0.02};
  const Pose world_from_camera(Rotation::from_axis_angle(UnitVector3::normalize({1, 2, 3}), 0.4),
                               {5, -3, 10});
  const Camera camera("wide", in, d, world_from_camera);
  double worst_px = 0;
  for (double u = -0.5; u <= 1279.5; u += 1279.0 / 16) {
    for (double v = -0.5; v <= 1023.5; v += 1023.0 / 16) {
      const UnitVector3 ray = camera.back_project({u, v});
      const Projection p = camera.project(camera.center() + 250.0 * ray);
      ASSERT_NE(p.status, ProjectionStatus::behind_camera);
      worst_px = std::max(worst_px, std::hypot(p.pixel.u - u, p.pixel.v - v));
    }
  }
  EXPECT_LT(worst_px, 1e-9);
}

TEST(Camera, BackProjectsTheImageCentreAlongTheOpticalAxis) {
  const UnitVector3 ray = camera_at_origin().back_project({1279.5, 1023.5});
  EXPECT_NEAR(ray.x(), 0, 1e-15);
  EXPECT_NEAR(ray.y(), 0, 1e-15);
  EXPECT_NEAR(ray.z(), 1, 1e-15);
  // A pinhole ray through pixel (u, v) is ((u - cx) / fx, (v - cy) / fy, 1).
  const UnitVector3 off_axis = camera_at_origin().back_project({1279.5 + 500, 1023.5 - 1000});
  const double norm = std::sqrt(0.1 * 0.1 + 0.2 * 0.2 + 1);
  EXPECT_NEAR(off_axis.x(), 0.1 / norm, 1e-15);
  EXPECT_NEAR(off_axis.y(), -0.2 / norm, 1e-15);
  EXPECT_NEAR(off_axis.z(), 1 / norm, 1e-15);
}

TEST(Camera, BackProjectionStaysFiniteWhereTheLensModelFolds) {
  // With k1 = -1 the radial map r (1 - r^2) peaks at r = 1/sqrt(3) (rd ~ 0.385);
  // a pixel beyond that has no preimage, yet a finite ray must come back.
  const Distortion d{.k1 = -1};
  const Camera camera = camera_at_origin(d);
  for (const Pixel pixel : {Pixel{1279.5 + 5000 * 0.6, 1023.5}, Pixel{1e6, -1e6}, Pixel{-5e4, 2e3}}) {
    const UnitVector3 ray = camera.back_project(pixel);
    EXPECT_TRUE(ray.vector().is_finite());
    EXPECT_NEAR(ray.vector().norm(), 1, 1e-12);
  }
}

TEST(Camera, PointsInOrBehindTheCameraPlaneAreBehindCamera) {
  const Camera camera = camera_at_origin();
  EXPECT_EQ(camera.project({1, 2, 0}).status, ProjectionStatus::behind_camera);
  EXPECT_EQ(camera.project({0, 0, -600}).status, ProjectionStatus::behind_camera);
  EXPECT_EQ(camera.project({0, 0, 1e-9}).status, ProjectionStatus::ok);
}

TEST(Camera, PixelsBeyondTheSensorEdgesAreOutsideImageButStillComputed) {
  const Camera camera = small_camera();
  // The sensor spans u in [-0.5, 99.5] and v in [-0.5, 79.5].
  // u = 100 x / z + 49.5: x / z = -0.5 lands exactly on the left edge.
  EXPECT_EQ(camera.project({-0.5, 0, 1}).status, ProjectionStatus::ok);
  EXPECT_EQ(camera.project({0.5, 0, 1}).status, ProjectionStatus::ok);   // u = 99.5
  EXPECT_EQ(camera.project({0, 0.4, 1}).status, ProjectionStatus::ok);   // v = 79.5
  EXPECT_EQ(camera.project({0, -0.4, 1}).status, ProjectionStatus::ok);  // v = -0.5

  const Projection left = camera.project({-0.51, 0, 1});
  EXPECT_EQ(left.status, ProjectionStatus::outside_image);
  EXPECT_NEAR(left.pixel.u, -1.5, 1e-12);
  EXPECT_NEAR(left.pixel.v, 39.5, 1e-12);
  const Projection below = camera.project({0, 0.41, 1});
  EXPECT_EQ(below.status, ProjectionStatus::outside_image);
  EXPECT_NEAR(below.pixel.v, 80.5, 1e-12);
  EXPECT_EQ(camera.project({0.6, 0, 1}).status, ProjectionStatus::outside_image);
  EXPECT_EQ(camera.project({0, -0.6, 1}).status, ProjectionStatus::outside_image);
}

TEST(Camera, StoresTheInverseOfItsPose) {
  const Pose world_from_camera(Rotation::from_axis_angle(UnitVector3::unit_y(), 0.3), {1, 2, 3});
  const Camera camera("posed", reference_intrinsics(), {}, world_from_camera);
  const Point3 p{4, -5, 6};
  const Point3 back = camera.world_from_camera() * (camera.camera_from_world() * p);
  EXPECT_NEAR(back.x, p.x, 1e-12);
  EXPECT_NEAR(back.y, p.y, 1e-12);
  EXPECT_NEAR(back.z, p.z, 1e-12);
  EXPECT_EQ(camera.center(), Point3(1, 2, 3));
  EXPECT_EQ(camera.name(), "posed");
}

TEST(Camera, RejectsNonPositiveFocalLengthsByName) {
  Intrinsics in = reference_intrinsics();
  in.fx = 0;
  const std::string message = message_of([&] { Camera("left", in, {}, Pose()); });
  EXPECT_NE(message.find("left"), std::string::npos) << message;
  EXPECT_NE(message.find("fx = 0"), std::string::npos) << message;
}

TEST(CameraLookingAt, ProjectsItsTargetToThePrincipalPoint) {
  const Point3 position{40, -25, -10};
  const Point3 target{-3, 8, 620};
  const Camera camera("posed", reference_intrinsics(), {},
                      camera_looking_at(position, target, {0, -1, 0}));
  const Projection p = camera.project(target);
  EXPECT_EQ(p.status, ProjectionStatus::ok);
  EXPECT_NEAR(p.pixel.u, 1279.5, 1e-9);
  EXPECT_NEAR(p.pixel.v, 1023.5, 1e-9);
  EXPECT_NEAR(distance(camera.center(), position), 0, 1e-12);
}

TEST(CameraLookingAt, KeepsTheImageUpAlongUp) {
  // Camera at the world origin looking down +z with world up = -y: exactly
  // the OpenCV camera frame, so the pose is the identity.
  const Pose pose = camera_looking_at({0, 0, 0}, {0, 0, 10}, {0, -1, 0});
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(pose.rotation()(r, c), r == c ? 1 : 0, 1e-15);
  }
  // Looking along world +x with up = +z, image right is forward x up =
  // (1, 0, 0) x (0, 0, 1) = (0, -1, 0), and image down is -z.
  const Pose side = camera_looking_at({0, 0, 0}, {5, 0, 0}, {0, 0, 1});
  const UnitVector3 x_axis = side.rotation().column(0);
  const UnitVector3 y_axis = side.rotation().column(1);
  EXPECT_NEAR(x_axis.y(), -1, 1e-15);
  EXPECT_NEAR(y_axis.z(), -1, 1e-15);
  // A point above the target appears above the image centre (smaller v).
  const Camera camera("side", reference_intrinsics(), {}, side);
  EXPECT_LT(camera.project({5, 0, 0.1}).pixel.v, 1023.5);
  EXPECT_NEAR(camera.project({5, 0, 0.1}).pixel.u, 1279.5, 1e-9);
}

TEST(CameraLookingAt, UsesOnlyTheComponentOfUpAcrossTheView) {
  // An up vector tilted toward the view gives the same pose as its projection.
  const Pose tilted = camera_looking_at({1, 2, 3}, {1, 2, 13}, {0, -2, 5});
  const Pose straight = camera_looking_at({1, 2, 3}, {1, 2, 13}, {0, -1, 0});
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(tilted.rotation()(r, c), straight.rotation()(r, c), 1e-15);
    }
  }
}

TEST(CameraLookingAt, RejectsATargetAtThePosition) {
  const std::string message = message_of([] { camera_looking_at({1, 2, 3}, {1, 2, 3}, {0, -1, 0}); });
  EXPECT_NE(message.find("target"), std::string::npos) << message;
  EXPECT_NE(message.find("equals position"), std::string::npos) << message;
}

TEST(CameraLookingAt, RejectsAnUpParallelToTheView) {
  const std::string message = message_of([] { camera_looking_at({0, 0, 0}, {0, 0, 10}, {0, 0, -3}); });
  EXPECT_NE(message.find("up (0, 0, -3)"), std::string::npos) << message;
  EXPECT_NE(message.find("parallel"), std::string::npos) << message;
  EXPECT_THROW(camera_looking_at({0, 0, 0}, {0, 0, 10}, {0, 0, 0}), std::invalid_argument);
}

}  // namespace
}  // namespace purkinje
