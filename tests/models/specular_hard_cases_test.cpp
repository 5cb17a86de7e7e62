// Hard cases of the specular-path solver, each with an expectation derived
// by hand (a path built backwards from a chosen surface point, symmetry)
// or by an independent method (ray shooting with vector Snell's law).

#include <gtest/gtest.h>

#include <cmath>

#include "purkinje/models/specular.h"
#include "purkinje/models/truth.h"

namespace purkinje {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;

EyeModel sphere_eye() {
  EyeModel m;
  m.anterior_cornea = {7.8, 0.0};
  m.aqueous_index = 1.3375;
  m.limbus_radius_mm = 5.9;
  m.iris_depth_mm = 3.6;
  m.pupil_radius_mm = 2.0;
  return m;
}

// An eye at `centre` looking back at a camera at the origin.
Eye eye_facing_camera(EyeModel m, const Point3& centre) {
  return Eye::with_cornea_center(std::move(m), centre,
                                 UnitVector3::normalize(Point3::origin() - centre));
}

// A point of a sphere eye's cornea at polar angle `polar` from the optical
// axis, toward the eye's +x, with its outward normal and a tangent that
// points away from the apex.
struct SurfacePoint {
  Point3 point;
  UnitVector3 normal = UnitVector3::unit_z();
  UnitVector3 tangent = UnitVector3::unit_x();
};

SurfacePoint sphere_point(const Eye& eye, double polar) {
  const double R = eye.model().anterior_cornea.radius_mm;
  const Vector3 n_eye{std::sin(polar), 0, std::cos(polar)};
  const Vector3 t_eye{std::cos(polar), 0, -std::sin(polar)};
  return {eye.cornea_center() + (eye.world_from_eye() * n_eye) * R,
          UnitVector3::normalize(eye.world_from_eye() * n_eye),
          UnitVector3::normalize(eye.world_from_eye() * t_eye)};
}

// A camera and a light placed so that the law of reflection holds at `s`
// with incidence `incidence`: mirror images about the normal.
struct Mirror {
  Point3 camera, light;
};
Mirror mirror_about(const SurfacePoint& s, double incidence, double camera_distance,
                    double light_distance) {
  const Vector3 to_camera = s.normal * std::cos(incidence) - s.tangent * std::sin(incidence);
  const Vector3 to_light = s.normal * std::cos(incidence) + s.tangent * std::sin(incidence);
  return {s.point + to_camera * camera_distance, s.point + to_light * light_distance};
}

void expect_glint_at(const Eye& eye, const SurfacePoint& s, double incidence, double cam_d,
                     double light_d, PathStatus expected) {
  const Mirror m = mirror_about(s, incidence, cam_d, light_d);
  const Reflection r = solve_reflection(eye, m.light, m.camera);
  ASSERT_EQ(r.status, expected) << to_string(r.status);
  EXPECT_LT(distance(r.point, s.point), 1e-9);
  EXPECT_NEAR(r.incidence_rad, incidence, 1e-10);
  EXPECT_LT(angle_between(r.normal, s.normal), 1e-10);
  EXPECT_LT(reflection_residual_rad(r), 1e-12);
}

TEST(HardCase, GrazingGlintAt85DegreesIsExact) {
  const Eye eye = eye_facing_camera(sphere_eye(), {0, 0, 600});
  expect_glint_at(eye, sphere_point(eye, 10 * kDeg), 85 * kDeg, 600, 300, PathStatus::ok);
}

TEST(HardCase, GrazingGlintAt89DegreesIsExact) {
  const Eye eye = eye_facing_camera(sphere_eye(), {0, 0, 600});
  expect_glint_at(eye, sphere_point(eye, 5 * kDeg), 89 * kDeg, 500, 800, PathStatus::ok);
}

TEST(HardCase, GrazingGlintOnAConicoidIsExact) {
  EyeModel m = sphere_eye();
  m.anterior_cornea.asphericity = -0.26;
  const Eye eye = eye_facing_camera(m, {0, 0, 600});
  // A conicoid point and its normal from the surface equation, by hand:
  // x^2 + (1 + Q) w^2 - 2 R w = 0 at x = 3 mm gives w, and the normal is
  // the gradient (x, R - (1 + Q) w) in (x, z).
  const double R = 7.8, Q = -0.26, x = 3.0;
  const double w = (R - std::sqrt(R * R - (1 + Q) * x * x)) / (1 + Q);
  const Vector3 n_eye = UnitVector3::normalize({x, 0, R - (1 + Q) * w});
  const Vector3 t_eye{n_eye.z, 0, -n_eye.x};
  const SurfacePoint s{eye.world_from_eye() * Point3{x, 0, R - w},
                       UnitVector3::normalize(eye.world_from_eye() * n_eye),
                       UnitVector3::normalize(eye.world_from_eye() * t_eye)};
  const Mirror mm = mirror_about(s, 82 * kDeg, 550, 400);
  const Reflection r = solve_reflection(eye, mm.light, mm.camera);
  ASSERT_EQ(r.status, PathStatus::ok) << to_string(r.status);
  EXPECT_LT(distance(r.point, s.point), 1e-9);
  EXPECT_NEAR(r.incidence_rad, 82 * kDeg, 1e-9);
}

TEST(HardCase, GlintBeyondTheLimbusIsFlaggedOffCornea) {
  // The limbus (radius 5.9 mm on a 7.8 mm sphere) is at asin(5.9 / 7.8) =
  // 49.1 degrees from the optical axis; a glint at 60 degrees is beyond it.
  const Eye eye = eye_facing_camera(sphere_eye(), {0, 0, 600});
  expect_glint_at(eye, sphere_point(eye, 60 * kDeg), 30 * kDeg, 600, 600,
                  PathStatus::off_cornea);
  expect_glint_at(eye, sphere_point(eye, 45 * kDeg), 30 * kDeg, 600, 600, PathStatus::ok);
}

TEST(HardCase, LightDirectlyBehindTheEyeHasNoGlint) {
  const Eye eye = eye_facing_camera(sphere_eye(), {0, 0, 600});
  const Reflection r = solve_reflection(eye, {0, 0, 900}, Point3::origin());
  EXPECT_EQ(r.status, PathStatus::no_solution);
}

TEST(HardCase, LightBehindAndAsideGivesAnOffCorneaGlintAtTheBisector) {
  // Camera and light both 5 m away: the normal bisects their directions
  // from the cornea centre to within (R / 5000) rad. Directions 135 degrees
  // apart give incidence 67.5 degrees, far beyond the limbus.
  const Point3 c{0, 0, 5000};
  const Eye eye = eye_facing_camera(sphere_eye(), c);
  const Vector3 to_light = Vector3{0, std::sin(135 * kDeg), -std::cos(135 * kDeg)};
  const Reflection r = solve_reflection(eye, c + to_light * 5000, Point3::origin());
  ASSERT_EQ(r.status, PathStatus::off_cornea);
  EXPECT_NEAR(r.incidence_rad, 67.5 * kDeg, 7.8 / 5000);
  const Vector3 bisector = UnitVector3::normalize(to_light + Vector3{0, 0, -1});
  EXPECT_LT(angle_between(r.normal, bisector), 7.8 / 5000);
}

TEST(HardCase, LightAtTheCameraCentreReflectsAtTheNearestPoint) {
  // Light and camera coincide: the path retraces itself along the normal
  // through the cornea centre. For an eye looking elsewhere that is still
  // C + R (K - C) / |K - C|.
  const Point3 c{30, -20, 600};
  const Eye eye = Eye::with_cornea_center(sphere_eye(), c, optical_axis_from_yaw_pitch(0.2, 0.1));
  const Reflection r = solve_reflection(eye, Point3::origin(), Point3::origin());
  ASSERT_EQ(r.status, PathStatus::ok);
  const Point3 expected = c + UnitVector3::normalize(Point3::origin() - c) * 7.8;
  EXPECT_LT(distance(r.point, expected), 1e-10);
  EXPECT_NEAR(r.incidence_rad, 0.0, 1e-12);
}

TEST(HardCase, LightAtTheCameraCentreOnAConicoidReflectsAtTheApex) {
  EyeModel m = sphere_eye();
  m.anterior_cornea.asphericity = -0.26;
  const Eye eye = eye_facing_camera(m, {0, 0, 600});
  const Reflection r = solve_reflection(eye, Point3::origin(), Point3::origin());
  ASSERT_EQ(r.status, PathStatus::ok);
  EXPECT_LT(distance(r.point, Point3{0, 0, 600 - 7.8}), 1e-10);
}

TEST(HardCase, EyeAFewMillimetresFromTheCameraIsExact) {
  // Apex 3 mm from the camera centre.
  const Eye eye = eye_facing_camera(sphere_eye(), {0, 0, 10.8});
  const Reflection same = solve_reflection(eye, Point3::origin(), Point3::origin());
  ASSERT_EQ(same.status, PathStatus::ok);
  EXPECT_LT(distance(same.point, Point3{0, 0, 3.0}), 1e-12);
  const SurfacePoint s = sphere_point(eye, 20 * kDeg);
  expect_glint_at(eye, s, 40 * kDeg, 3.0, 2.0, PathStatus::ok);
}

TEST(HardCase, EyeAtFiveMetresIsExact) {
  const Eye eye = eye_facing_camera(sphere_eye(), {0, 0, 5000});
  expect_glint_at(eye, sphere_point(eye, 3 * kDeg), 2 * kDeg, 5000, 5000, PathStatus::ok);
  const Reflection same = solve_reflection(eye, Point3::origin(), Point3::origin());
  EXPECT_LT(distance(same.point, Point3{0, 0, 5000 - 7.8}), 1e-9);
}

TEST(HardCase, PupilPointBeyondTheCriticalAngleIsTotalInternalReflection) {
  // Camera 5 m away along the optical axis. A point 1 um under the surface
  // at 95 degrees from the camera direction: to leave at an exit point at
  // polar angle psi <= 90 it travels a chord that meets the normal there at
  // about 90 - (95 - psi) / 2 = 42.5 + psi / 2 degrees, while an exit
  // toward the far camera needs asin(sin(psi) / 1.3375) degrees, which is
  // smaller for every psi in [0, 90]. No path exists.
  const Eye eye = eye_facing_camera(sphere_eye(), {0, 0, 5000});
  const double depth = 7.8 - 0.001;
  const Point3 inner = eye.cornea_center() +
                       (eye.world_from_eye() * Vector3{std::sin(95 * kDeg), 0, std::cos(95 * kDeg)}) *
                           depth;
  const Refraction r = solve_refraction(eye, inner, Point3::origin());
  EXPECT_EQ(r.status, PathStatus::total_internal_reflection);
}

TEST(HardCase, PupilOfAnEyeTurnedAwayIsPartlyHiddenWithoutNaN) {
  // Turned 90 degrees: the cornea still shows the near side of the pupil
  // (its magnified image stays visible up to about 90 degrees), while the
  // far side's paths leave beyond the limbus. Every border point has a
  // status and the visible ones obey Snell's law.
  Scene scene;
  scene.cameras.emplace_back("c", Intrinsics::from_focal_length(25, 0.005, 2560, 2048),
                             Distortion{}, Pose{});
  scene.eyes.push_back(Eye::with_cornea_center(sphere_eye(), {0, 0, 600},
                                               optical_axis_from_yaw_pitch(90 * kDeg, 0)));
  const SceneTruth truth = compute_truth(scene);
  int hidden = 0, seen = 0;
  for (const PupilBorderPointTruth& b : truth.views[0].pupil.border) {
    if (b.status == PathStatus::ok) {
      ++seen;
      EXPECT_LT(refraction_residual_rad(scene.eyes[0], b.refraction), 1e-12);
      EXPECT_TRUE(std::isfinite(b.pixel.u) && std::isfinite(b.pixel.v));
    } else {
      ++hidden;
      EXPECT_TRUE(b.status == PathStatus::total_internal_reflection ||
                  b.status == PathStatus::off_cornea)
          << to_string(b.status);
    }
  }
  EXPECT_GT(hidden, 0);
  EXPECT_GT(seen, 0);
}

TEST(HardCase, OuterPointInsideTheEyeIsInvalidInput) {
  const Eye eye = eye_facing_camera(sphere_eye(), {0, 0, 600});
  EXPECT_EQ(solve_reflection(eye, {0, 0, 601}, Point3::origin()).status, PathStatus::invalid_input);
  EXPECT_EQ(solve_refraction(eye, {0, 0, 600}, {0, 0, 599}).status, PathStatus::invalid_input);
  EXPECT_EQ(solve_refraction(eye, {0, 0, 0}, {0, 0, 600}).status, PathStatus::invalid_input);
}

// Independent method for an on-axis pupil: shoot rays from the camera
// centre, refract them with the vector form of Snell's law and find by
// bisection the ray that lands on the border point.
double shot_image_u(double fx, double eye_distance, double R, double n, double depth,
                    double pupil_radius) {
  const double zp = eye_distance - (R - depth);  // world z of the pupil plane
  auto landing = [&](double tan_alpha) {
    const Vector3 d = UnitVector3::normalize({tan_alpha, 0, 1});
    // Near intersection with the sphere centred at (0, 0, eye_distance).
    const double b = -d.z * eye_distance;
    const double c = eye_distance * eye_distance - R * R;
    const double t = -b - std::sqrt(b * b - c);
    const Vector3 x = d * t;
    const Vector3 normal = (x - Vector3{0, 0, eye_distance}) / R;  // outward
    const double ci = -dot(d, normal);
    const double eta = 1.0 / n;
    const double ct = std::sqrt(1 - eta * eta * (1 - ci * ci));
    const Vector3 refracted = d * eta + normal * (eta * ci - ct);
    return x.x + refracted.x * (zp - x.z) / refracted.z;
  };
  double lo = 0, hi = R / eye_distance;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (landing(mid) < pupil_radius ? lo : hi) = mid;
  }
  return fx * 0.5 * (lo + hi);
}

void expect_on_axis_pupil(double pupil_radius) {
  EyeModel m = sphere_eye();
  m.pupil_radius_mm = pupil_radius;
  Scene scene;
  const Intrinsics in = Intrinsics::from_focal_length(25, 0.005, 2560, 2048);
  scene.cameras.emplace_back("c", in, Distortion{}, Pose{});
  scene.eyes.push_back(eye_facing_camera(m, {0, 0, 600}));
  const SceneTruth truth = compute_truth(scene);
  const PupilTruth& p = truth.views[0].pupil;
  const double expected = shot_image_u(in.fx, 600, 7.8, 1.3375, 3.6, pupil_radius);
  ASSERT_EQ(p.border[0].status, PathStatus::ok);
  EXPECT_NEAR(p.border[0].pixel.u - in.cx, expected, 1e-8);
  ASSERT_TRUE(p.ellipse_valid);
  EXPECT_NEAR(p.ellipse.center.u, in.cx, 1e-8);
  EXPECT_NEAR(p.ellipse.center.v, in.cy, 1e-8);
  EXPECT_NEAR(p.ellipse.semi_axis_1_px, expected, 1e-7);
  EXPECT_NEAR(p.ellipse.semi_axis_2_px, expected, 1e-7);
}

TEST(HardCase, SmallPupilOfHalfAMillimetreMatchesRayShooting) { expect_on_axis_pupil(0.5); }
TEST(HardCase, LargePupilOfFourAndAHalfMillimetresMatchesRayShooting) { expect_on_axis_pupil(4.5); }

}  // namespace
}  // namespace purkinje
