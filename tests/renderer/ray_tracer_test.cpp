#include "purkinje/renderer/ray_tracer.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <ctime>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <span>
#include <vector>

#include "surfaces.h"  // the renderer's private header (purkinje::renderer_internal)
#include "embree_isa.h"
#include "purkinje/models/scene_file.h"

namespace purkinje::renderer {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;
using Real = long double;  // reference solutions: independent and more precise than the tracer

Scene scene_of(std::vector<Eye> eyes) {
  Scene scene;
  scene.name = "test";
  scene.eyes = std::move(eyes);
  return scene;
}

// Cornea centre on the world z axis at `z`, looking back at a camera at the
// origin: eye x = world x, eye y = -world y, eye z = -world z.
Eye facing_camera(EyeModel model, double z = 600) {
  return Eye::with_cornea_center(std::move(model), {0, 0, z}, -UnitVector3::unit_z());
}

Point3 eye_to_world_facing(const Point3& e, double z = 600) { return {e.x, -e.y, z - e.z}; }

Ray ray_to(const Point3& from, const Point3& to) { return Ray{from, UnitVector3::normalize(to - from)}; }

Ray ray_along(const Point3& from, const Vector3& direction) {
  return Ray{from, UnitVector3::normalize(direction)};
}

// Nearest root t > 0 of |o + t d - c| = r, in long double.
std::optional<Real> ray_sphere(const Point3& o, const Vector3& d, const Point3& c, double r) {
  const Real ox = Real(o.x) - c.x, oy = Real(o.y) - c.y, oz = Real(o.z) - c.z;
  const Real a = Real(d.x) * d.x + Real(d.y) * d.y + Real(d.z) * d.z;
  const Real b = ox * d.x + oy * d.y + oz * d.z;
  const Real cc = ox * ox + oy * oy + oz * oz - Real(r) * r;
  const Real disc = b * b - a * cc;
  if (disc < 0) return std::nullopt;
  const Real near = (-b - std::sqrt(disc)) / a, far = (-b + std::sqrt(disc)) / a;
  if (near > 0) return near;
  if (far > 0) return far;
  return std::nullopt;
}

Point3 along(const Point3& o, const Vector3& d, Real t) {
  return {static_cast<double>(o.x + t * d.x), static_cast<double>(o.y + t * d.y),
          static_cast<double>(o.z + t * d.z)};
}

void expect_point_near(const Point3& actual, const Point3& expected, double tol_mm) {
  EXPECT_LT(distance(actual, expected), tol_mm)
      << "actual (" << actual.x << ", " << actual.y << ", " << actual.z << "), expected ("
      << expected.x << ", " << expected.y << ", " << expected.z << ")";
}

void expect_direction_near(const Vector3& actual, const Vector3& expected, double tol) {
  EXPECT_LT((actual - expected).norm(), tol)
      << "actual (" << actual.x << ", " << actual.y << ", " << actual.z << "), expected ("
      << expected.x << ", " << expected.y << ", " << expected.z << ")";
}

double limbus_depth(const EyeModel& m) {
  // Sag of the conicoid at the limbus radius, written out here on purpose.
  const double R = m.anterior_cornea.radius_mm, k = 1 + m.anterior_cornea.asphericity;
  const double r = m.limbus_radius_mm;
  return (R - std::sqrt(R * R - k * r * r)) / k;
}

// ---------------------------------------------------------------------------
// The quadratic solver under everything.

TEST(SolveQuadratic, KeepsTheSmallRootExactWhenCoefficientsDifferByManyOrders) {
  double roots[2];
  // t^2 - 2e8 t + 1 = 0: the naive formula returns 0 for the small root.
  ASSERT_EQ(surfaces::solve_quadratic(1, -1e8, 1, roots), 2);
  EXPECT_NEAR(roots[0], 5e-9, 1e-24);
  EXPECT_NEAR(roots[1], 2e8, 1e-6);
}

TEST(SolveQuadratic, HandlesLinearDoubleAndMissingRoots) {
  double roots[2];
  ASSERT_EQ(surfaces::solve_quadratic(0, 2, -8, roots), 1);  // 4 t - 8 = 0
  EXPECT_DOUBLE_EQ(roots[0], 2);
  EXPECT_EQ(surfaces::solve_quadratic(0, 0, 1, roots), 0);
  EXPECT_EQ(surfaces::solve_quadratic(1, 0, 1, roots), 0);  // t^2 + 1
  ASSERT_EQ(surfaces::solve_quadratic(1, 0, 0, roots), 1);  // t^2
  EXPECT_EQ(roots[0], 0);
  ASSERT_EQ(surfaces::solve_quadratic(2, -6, 18, roots), 2);  // 2 (t - 3)^2
  EXPECT_DOUBLE_EQ(roots[0], 3);
  EXPECT_DOUBLE_EQ(roots[1], 3);
  ASSERT_EQ(surfaces::solve_quadratic(-1, 0, 4, roots), 2);  // -t^2 + 4
  EXPECT_DOUBLE_EQ(roots[0], -2);
  EXPECT_DOUBLE_EQ(roots[1], 2);
}

TEST(PalpebralOpening, IsBoundedByTheParabolicMarginsAndClosesAtZero) {
  surfaces::PalpebralOpening open;  // U 4.5, L -5.5, c -1, w 15
  EXPECT_TRUE(open.contains({0, 4.4, 1}));
  EXPECT_FALSE(open.contains({0, 4.6, 1}));
  EXPECT_TRUE(open.contains({0, -5.4, 1}));
  EXPECT_FALSE(open.contains({0, -5.6, 1}));
  // At x = 7.5 the taper is 0.75: upper = -1 + 5.5 * 0.75 = 3.125.
  EXPECT_TRUE(open.contains({7.5, 3.1, 1}));
  EXPECT_FALSE(open.contains({7.5, 3.15, 1}));
  EXPECT_FALSE(open.contains({15.0, -1, 1}));  // the canthus
  EXPECT_FALSE(open.contains({0, 0, -1}));     // behind the head's origin
  open.opening = 0;
  EXPECT_FALSE(open.contains({0, -1, 1}));
  EXPECT_FALSE(open.contains({0, -0.999, 1}));
}

// A point of the lid sphere (radius 13.8, the default eye's 13.5 + 0.3) in
// the head frame, at x and elevation e in the plane x = const.
Point3 lid_point(double x, double elevation_deg) {
  const double rho = std::sqrt(13.8 * 13.8 - x * x);
  return {x, rho * std::sin(elevation_deg * kDegree), rho * std::cos(elevation_deg * kDegree)};
}

TEST(PalpebralOpening, TurnedMarginsMoveAlongTheLidSphere) {
  // Unturned, the upper margin (4.5 mm at x = 0) sits at elevation
  // asin(4.5 / 13.8) = 19.0314 deg, the lower (-5.5) at -23.4876 deg.
  surfaces::PalpebralOpening open;
  EXPECT_TRUE(open.contains(lid_point(0, 18.93)));
  EXPECT_FALSE(open.contains(lid_point(0, 19.13)));
  // Turned up 20 deg: at 39.0314 deg, height 13.8 sin(39.0314 deg) = 8.6905 mm.
  open.upper_turn = surfaces::MarginTurn::by(20 * kDegree);
  EXPECT_TRUE(open.contains(lid_point(0, 38.93)));
  EXPECT_FALSE(open.contains(lid_point(0, 39.13)));
  EXPECT_TRUE(open.contains({0, 8.68, std::sqrt(13.8 * 13.8 - 8.68 * 8.68)}));
  EXPECT_FALSE(open.contains({0, 8.70, std::sqrt(13.8 * 13.8 - 8.70 * 8.70)}));
  // At x = 7.5 the head-fixed upper margin is 3.125 mm high (see above); on
  // the circle x = 7.5 (radius sqrt(13.8^2 - 7.5^2) = 11.5842) that is
  // elevation asin(3.125 / 11.5842) = 15.6504 deg, turned to 35.6504 deg.
  EXPECT_TRUE(open.contains(lid_point(7.5, 35.55)));
  EXPECT_FALSE(open.contains(lid_point(7.5, 35.75)));
  // The lower margin turned down 12 deg: -35.4876 deg.
  open.lower_turn = surfaces::MarginTurn::by(-12 * kDegree);
  EXPECT_TRUE(open.contains(lid_point(0, -35.39)));
  EXPECT_FALSE(open.contains(lid_point(0, -35.59)));
  EXPECT_TRUE(open.contains(lid_point(0, -24)));  // uncovered as the lower lid went down
}

TEST(PalpebralOpening, MarginsThatWouldCrossCloseTheOpeningInstead) {
  // Upper margin turned down 45 deg, lower not: at x = 0 the upper would
  // lie at 19.03 - 45 = -25.97 deg, below the lower (-23.49). Everywhere
  // else too (at the canthi both margins meet at the closing line, turned
  // apart the wrong way): no point of the sphere is in the opening.
  surfaces::PalpebralOpening open;
  open.upper_turn = surfaces::MarginTurn::by(-45 * kDegree);
  for (double x = -13.5; x <= 13.5; x += 0.25) {
    for (double e = -89.5; e <= 89.5; e += 0.25) {
      ASSERT_FALSE(open.contains(lid_point(x, e))) << x << " " << e;
    }
  }
  // Turned down 40 deg it still leaves a sliver: -20.97 to -23.49 deg.
  open.upper_turn = surfaces::MarginTurn::by(-40 * kDegree);
  EXPECT_TRUE(open.contains(lid_point(0, -22)));
  EXPECT_FALSE(open.contains(lid_point(0, -20.5)));
}

TEST(PalpebralOpening, AMarginTurnedFarStillSplitsTheSphereByElevation) {
  // A turn of 90 deg (the limit): the upper margin at 109.03 deg, past the
  // top of the sphere, so every point in front is below it, even those
  // whose turned-back elevation passes -90 deg.
  surfaces::PalpebralOpening open;
  open.upper_turn = surfaces::MarginTurn::by(90 * kDegree);
  for (double e = -23.3; e <= 89.5; e += 0.5) EXPECT_TRUE(open.contains(lid_point(0, e))) << e;
  open.upper_turn = {};
  open.lower_turn = surfaces::MarginTurn::by(-90 * kDegree);  // the lower at -113.49 deg
  for (double e = -89.5; e <= 18.9; e += 0.5) EXPECT_TRUE(open.contains(lid_point(0, e))) << e;
}

TEST(EyelidGazeFollowing, MarginTurnsAreGainTimesElevationBySign) {
  // Elevation of the optical axis in the head frame (y up, z forward).
  EXPECT_NEAR(surfaces::eye_elevation_rad({0, std::sin(30 * kDegree), std::cos(30 * kDegree)}), 30 * kDegree, 1e-15);
  EXPECT_EQ(surfaces::eye_elevation_rad({std::sin(40 * kDegree), 0, std::cos(40 * kDegree)}), 0.0);  // horizontal
  // Yaw 40, pitch 20 (optical_axis_from_yaw_pitch): (sin 40 cos 20, sin 20,
  // cos 40 cos 20) in the head frame, elevation atan(tan 20 / cos 40) = 25.4138 deg.
  const Vector3 o{std::sin(40 * kDegree) * std::cos(20 * kDegree), std::sin(20 * kDegree),
                  std::cos(40 * kDegree) * std::cos(20 * kDegree)};
  EXPECT_NEAR(surfaces::eye_elevation_rad(o) / kDegree, 25.413766880, 1e-8);
  // The default gains: upper 1 both ways, lower 0 up and 0.6 down.
  const Eyelids d;
  const auto turns = [&](double elevation_deg) {
    return surfaces::margin_turns(d.upper_gain_upgaze, d.upper_gain_downgaze, d.lower_gain_upgaze,
                                  d.lower_gain_downgaze, elevation_deg * kDegree);
  };
  EXPECT_NEAR(turns(30).upper_rad, 30 * kDegree, 1e-15);
  EXPECT_EQ(turns(30).lower_rad, 0.0);
  EXPECT_NEAR(turns(-30).upper_rad, -30 * kDegree, 1e-15);
  EXPECT_NEAR(turns(-30).lower_rad, -18 * kDegree, 1e-15);
  EXPECT_EQ(turns(0).upper_rad, 0.0);
  // Limited to +-90 deg.
  EXPECT_DOUBLE_EQ(surfaces::margin_turns(2, 2, 2, 2, 60 * kDegree).upper_rad, std::numbers::pi / 2);
  EXPECT_DOUBLE_EQ(surfaces::margin_turns(2, 2, 2, 2, -60 * kDegree).lower_rad, -std::numbers::pi / 2);
}

// ---------------------------------------------------------------------------
// Cornea.

TEST(RayTracer, AxialRayHitsTheApexWithTheAxisAsNormal) {
  const RayTracer tracer(scene_of({facing_camera(keratometric_eye())}));
  const Hit hit = tracer.intersect(Ray{{0, 0, 0}, UnitVector3::unit_z()});
  ASSERT_EQ(hit.surface, Surface::cornea_anterior);
  EXPECT_EQ(hit.eye, 0);
  // Apex: cornea centre 600 minus R = 7.8 toward the camera.
  EXPECT_NEAR(hit.t, 592.2, 1e-12);
  expect_point_near(hit.point, {0, 0, 592.2}, 1e-12);
  expect_direction_near(hit.normal, {0, 0, -1}, 1e-15);
  EXPECT_TRUE(hit.front_face);
}

TEST(RayTracer, SphericalCorneaHitsMatchTheClosedFormToAPicometre) {
  const RayTracer tracer(scene_of({facing_camera(keratometric_eye())}));
  const Point3 center{0, 0, 600};
  // Rays parallel to the axis at offsets (x, y): z = 600 - sqrt(R^2 - x^2 - y^2).
  for (const auto& [x, y] : std::vector<std::array<double, 2>>{
           {0.5, 0}, {0, -2}, {3, 1.5}, {-4.1, 3.9}, {5.85, 0}, {0, 5.899}}) {
    const Hit hit = tracer.intersect(ray_along({x, y, 0}, {0, 0, 1}));
    ASSERT_EQ(hit.surface, Surface::cornea_anterior) << x << ", " << y;
    const double z = 600 - std::sqrt(7.8 * 7.8 - x * x - y * y);
    expect_point_near(hit.point, {x, y, z}, 2e-12);
    expect_direction_near(hit.normal, (Point3{x, y, z} - center) / 7.8, 1e-12);
  }
  // Oblique rays from the camera toward points on the cap.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> offset(-3.5, 3.5);
  for (int i = 0; i < 200; ++i) {
    const Ray ray = ray_to({0, 0, 0}, {offset(rng), offset(rng), 593});
    const Hit hit = tracer.intersect(ray);
    ASSERT_EQ(hit.surface, Surface::cornea_anterior);
    const auto t = ray_sphere(ray.origin, ray.direction, center, 7.8);
    ASSERT_TRUE(t);
    EXPECT_NEAR(hit.t, static_cast<double>(*t), 2e-12);
    expect_point_near(hit.point, along(ray.origin, ray.direction, *t), 2e-12);
  }
}

// Smallest t > 0 where the world ray meets the conicoid cap of an eye built
// by facing_camera(model, 600), from the conicoid's equation written in
// world coordinates (w = z - (600 - R) is the depth below the apex).
std::optional<Real> ray_conicoid_facing(const Ray& ray, const EyeModel& m) {
  const Real R = m.anterior_cornea.radius_mm, k = 1 + Real(m.anterior_cornea.asphericity);
  const Real ox = ray.origin.x, oy = ray.origin.y, w0 = Real(ray.origin.z) - (600 - R);
  const Real dx = ray.direction.x(), dy = ray.direction.y(), dz = ray.direction.z();
  // (ox + t dx)^2 + (oy + t dy)^2 + k (w0 + t dz)^2 - 2 R (w0 + t dz) = 0
  const Real a = dx * dx + dy * dy + k * dz * dz;
  const Real b = 2 * (ox * dx + oy * dy + k * w0 * dz - R * dz);
  const Real c = ox * ox + oy * oy + k * w0 * w0 - 2 * R * w0;
  const Real disc = b * b - 4 * a * c;
  if (disc < 0) return std::nullopt;
  for (const Real t : {(-b - std::sqrt(disc)) / (2 * a), (-b + std::sqrt(disc)) / (2 * a)}) {
    const Real w = w0 + t * dz;
    if (t > 0 && w >= 0 && w <= limbus_depth(m)) return t;
  }
  return std::nullopt;
}

TEST(RayTracer, ConicoidCorneaHitsMatchTheClosedForm) {
  const EyeModel navarro = navarro_eye();  // R 7.72, Q -0.26
  const RayTracer tracer(scene_of({facing_camera(navarro)}));
  const double R = 7.72, k = 0.74;
  // Parallel rays: the sag w = h^2 / (R + sqrt(R^2 - k h^2)).
  for (const double h : {0.3, 1.0, 2.5, 4.0, 5.5, 5.89}) {
    const Hit hit = tracer.intersect(ray_along({h, 0, 0}, {0, 0, 1}));
    ASSERT_EQ(hit.surface, Surface::cornea_anterior) << h;
    const double w = h * h / (R + std::sqrt(R * R - k * h * h));
    expect_point_near(hit.point, {h, 0, 600 - R + w}, 2e-12);
    // Eye-frame gradient (x, y, R - k w); eye z is world -z.
    expect_direction_near(hit.normal, UnitVector3::normalize({h, 0, -(R - k * w)}), 1e-12);
  }
  // Oblique rays from up to 100 mm off the axis toward points of the cap
  // (every earlier point of such a ray lies in front of the limbus plane,
  // so the cap is the first surface it meets).
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (int i = 0; i < 300; ++i) {
    const double x = 4 * unit(rng), y = 4 * unit(rng), h2 = x * x + y * y;
    const double w = h2 / (R + std::sqrt(R * R - k * h2));
    const Ray ray = ray_to({100 * unit(rng), 100 * unit(rng), 0}, {x, y, 600 - R + w});
    const auto t = ray_conicoid_facing(ray, navarro);
    ASSERT_TRUE(t);
    const Hit hit = tracer.intersect(ray);
    ASSERT_EQ(hit.surface, Surface::cornea_anterior);
    EXPECT_NEAR(hit.t, static_cast<double>(*t), 3e-12);
    expect_point_near(hit.point, along(ray.origin, ray.direction, *t), 3e-12);
  }
}

TEST(RayTracer, HitsOnARotatedConicoidLieOnItToAPicometre) {
  EyeModel m = navarro_eye();
  const Eye eye = Eye::with_rotation_center(m, {30, -20, 550},
                                            optical_axis_from_yaw_pitch(25 * kDegree, -10 * kDegree));
  const RayTracer tracer(scene_of({eye}));
  const double R = m.anterior_cornea.radius_mm, k = 1 + m.anterior_cornea.asphericity;
  std::mt19937_64 rng(3);
  // Points inside the cornea, 1 mm below the apex (the cap is 3.8 mm wide there).
  std::uniform_real_distribution<double> offset(-2.4, 2.4);
  for (int i = 0; i < 200; ++i) {
    const Point3 aim = eye.world_from_eye() * Point3{offset(rng), offset(rng), R - 1.0};
    const Ray ray = ray_to({0, 0, 0}, aim);
    const Hit hit = tracer.intersect(ray);
    ASSERT_EQ(hit.surface, Surface::cornea_anterior);
    const Point3 p = eye.eye_from_world() * hit.point;
    const double w = R - p.z;
    const Vector3 gradient{p.x, p.y, R - k * w};
    // Distance to the surface to first order: F / |grad F|, F = x^2 + y^2 + k w^2 - 2 R w.
    const double f = p.x * p.x + p.y * p.y + k * w * w - 2 * R * w;
    EXPECT_LT(std::abs(f) / (2 * gradient.norm()), 1e-12);
    expect_point_near(hit.point, ray.origin + ray.direction * hit.t, 1e-12);
    expect_direction_near(hit.normal, eye.world_from_eye() * UnitVector3::normalize(gradient), 1e-12);
    EXPECT_LT(dot(hit.normal, ray.direction), 0);
    EXPECT_TRUE(hit.front_face);
  }
}

TEST(RayTracer, GrazingTheApexGivesAFiniteAnswer) {
  const RayTracer tracer(scene_of({facing_camera(keratometric_eye())}));
  // Tangent to the cornea at its apex, and a hair inside and outside.
  for (const double dz : {0.0, 1e-9, -1e-9, 1e-6}) {
    const Hit hit = tracer.intersect(ray_along({-20, 0, 592.2 + dz}, {1, 0, 0}));
    if (hit.surface == Surface::none) continue;
    EXPECT_EQ(hit.surface, Surface::cornea_anterior);
    EXPECT_TRUE(hit.point.is_finite());
    EXPECT_TRUE(hit.normal.vector().is_finite());
    // On the sphere, near the apex.
    EXPECT_NEAR(distance(hit.point, {0, 0, 600}), 7.8, 1e-12);
    EXPECT_LT(std::abs(hit.point.x), 0.2);
  }
  // A ray 1 um inside the apex plane crosses the cap twice, 2 sqrt(2 R 1e-3) apart.
  const Hit in = tracer.intersect(ray_along({-20, 0, 592.201}, {1, 0, 0}));
  ASSERT_EQ(in.surface, Surface::cornea_anterior);
  EXPECT_NEAR(in.point.x, -std::sqrt(7.8 * 7.8 - 7.799 * 7.799), 1e-9);
}

// ---------------------------------------------------------------------------
// Limbus, sclera, iris, pupil.

TEST(RayTracer, JustOutsideTheLimbusTheRayHitsTheLimbalBandOrTheSclera) {
  const EyeModel m = keratometric_eye();  // R 7.8, limbus 5.9, sclera 12 about z = -5.7 (eye frame)
  const RayTracer tracer(scene_of({facing_camera(m)}));
  const double z_L = 7.8 - limbus_depth(m);                   // 5.102
  const double z_m = -5.7 + std::sqrt(12.0 * 12.0 - 5.9 * 5.9);  // 4.749: sphere radius 5.9 here
  ASSERT_LT(z_m, z_L);  // so the band is a cylinder

  // Inside the limbus: cornea. Outside: the sphere, at z = -5.7 + sqrt(144 - h^2).
  EXPECT_EQ(tracer.intersect(ray_along({5.89, 0, 0}, {0, 0, 1})).surface, Surface::cornea_anterior);
  const Hit sclera = tracer.intersect(ray_along({0, 6.0, 0}, {0, 0, 1}));
  ASSERT_EQ(sclera.surface, Surface::sclera);
  const Point3 on_sphere = eye_to_world_facing({0, -6.0, -5.7 + std::sqrt(144.0 - 36.0)});
  expect_point_near(sclera.point, on_sphere, 1e-11);
  const Point3 rotation_center = eye_to_world_facing({0, 0, -5.7});
  expect_direction_near(sclera.normal, (on_sphere - rotation_center) / 12.0, 1e-12);

  // Sideways at the band's mid depth: the cylinder r = 5.9, normal radial.
  const double z_band = 0.5 * (z_L + z_m);
  const Hit band = tracer.intersect(ray_along(eye_to_world_facing({20, 0, z_band}), {-1, 0, 0}));
  ASSERT_EQ(band.surface, Surface::sclera);
  expect_point_near(band.point, eye_to_world_facing({5.9, 0, z_band}), 1e-12);
  expect_direction_near(band.normal, {1, 0, 0}, 1e-12);
  EXPECT_TRUE(band.front_face);
}

TEST(RayTracer, AWideScleraIsJoinedToTheLimbusByAnAnnulus) {
  EyeModel m = keratometric_eye();
  m.sclera_radius_mm = 12.9;  // radius sqrt(12.9^2 - 10.802^2) = 7.05 at the limbus plane
  const RayTracer tracer(scene_of({facing_camera(m)}));
  const double z_L = 7.8 - limbus_depth(m);
  const double rho = std::sqrt(12.9 * 12.9 - (z_L + 5.7) * (z_L + 5.7));
  ASSERT_GT(rho, 5.9);
  for (const double h : {5.95, 6.5, rho - 0.01}) {
    const Hit hit = tracer.intersect(ray_along({h, 0, 0}, {0, 0, 1}));
    ASSERT_EQ(hit.surface, Surface::sclera) << h;
    expect_point_near(hit.point, eye_to_world_facing({h, 0, z_L}), 1e-12);
    expect_direction_near(hit.normal, {0, 0, -1}, 1e-15);
  }
  const Hit sphere = tracer.intersect(ray_along({7.5, 0, 0}, {0, 0, 1}));
  ASSERT_EQ(sphere.surface, Surface::sclera);
  expect_point_near(sphere.point, eye_to_world_facing({7.5, 0, -5.7 + std::sqrt(12.9 * 12.9 - 56.25)}),
                    1e-11);
}

TEST(RayTracer, RayFromInsideTheApexThroughThePupilCentreHitsThePupil) {
  EyeModel m = keratometric_eye();
  m.pupil_decentration_x_mm = 0.4;
  m.pupil_decentration_y_mm = -0.3;
  const Eye eye = Eye::with_rotation_center(m, {10, 5, 620},
                                            optical_axis_from_yaw_pitch(-15 * kDegree, 8 * kDegree));
  const RayTracer tracer(scene_of({eye}));
  const Point3 start = eye.world_from_eye() * Point3{0, 0, 7.8 - 1e-4};
  const Hit hit = tracer.intersect(ray_to(start, eye.pupil_center()));
  ASSERT_EQ(hit.surface, Surface::pupil);
  expect_point_near(hit.point, eye.pupil_center(), 1e-12);
  expect_direction_near(hit.normal, eye.optical_axis(), 1e-12);
  EXPECT_TRUE(hit.front_face);
  // Along the axis: 0.5 mm from the decentred pupil centre, still inside the 2 mm pupil.
  const Hit axial = tracer.intersect(ray_along(start, -eye.optical_axis().vector()));
  ASSERT_EQ(axial.surface, Surface::pupil);
  expect_point_near(axial.point, eye.world_from_eye() * Point3{0, 0, 7.8 - 3.6}, 1e-12);
}

TEST(RayTracer, TheIrisFillsTheAnnulusFromThePupilOutToTheSclera) {
  const EyeModel m = keratometric_eye();  // iris plane z = 4.2, iris 5.5, pupil 2
  const Eye eye = facing_camera(m);
  const RayTracer tracer(scene_of({eye}));
  const Point3 start = eye_to_world_facing({0, 0, 7.8 - 1e-4});
  const double z_I = 4.2;
  for (const double r : {2.01, 3.0, 4.0, 5.4}) {
    for (const double angle : {0.3, 2.0, 4.5}) {
      const Point3 target = eye_to_world_facing({r * std::cos(angle), r * std::sin(angle), z_I});
      const Hit hit = tracer.intersect(ray_to(start, target));
      ASSERT_EQ(hit.surface, Surface::iris) << r << " " << angle;
      expect_point_near(hit.point, target, 1e-12);
      expect_direction_near(hit.normal, {0, 0, -1}, 1e-15);
    }
  }
  EXPECT_EQ(tracer.intersect(ray_to(start, eye_to_world_facing({1.99, 0, z_I}))).surface,
            Surface::pupil);
  // Beyond the iris radius the iris reaches out to the sclera sphere:
  // radius sqrt(144 - (4.2 + 5.7)^2) = 6.78 there. From 1 mm in front of
  // the iris plane, on the axis (the line stays inside the sphere).
  const double wall = std::sqrt(144.0 - 9.9 * 9.9);
  const Point3 chamber = eye_to_world_facing({0, 0, z_I + 1});
  for (const double r : {5.6, 6.5, wall - 1e-3}) {
    const Point3 target = eye_to_world_facing({r, 0, z_I});
    const Hit hit = tracer.intersect(ray_to(chamber, target));
    ASSERT_EQ(hit.surface, Surface::iris) << r;
    expect_point_near(hit.point, target, 1e-12);
  }
}

TEST(RayTracer, PosteriorCorneaIsHitFromInsideTheEye) {
  const EyeModel navarro = navarro_eye();  // anterior 7.72, posterior 6.5 with apex 0.55 deeper
  const Eye eye = facing_camera(navarro);
  const RayTracer tracer(scene_of({eye}));
  const Point3 start = eye_to_world_facing({0, 0, 7.72 - 3.6 + 0.1});
  const Hit posterior = tracer.intersect(ray_along(start, {0, 0, -1}));
  ASSERT_EQ(posterior.surface, Surface::cornea_posterior);
  expect_point_near(posterior.point, {0, 0, 600 - (7.72 - 0.55)}, 1e-12);
  expect_direction_near(posterior.normal, {0, 0, -1}, 1e-15);
  EXPECT_FALSE(posterior.front_face);
  Ray onward = ray_along(start, {0, 0, -1});
  onward.t_min = posterior.t + 1e-9;
  const Hit anterior = tracer.intersect(onward);
  ASSERT_EQ(anterior.surface, Surface::cornea_anterior);
  expect_point_near(anterior.point, {0, 0, 600 - 7.72}, 1e-12);
  EXPECT_FALSE(anterior.front_face);

  // Le Grand (spheres): oblique rays against the posterior sphere, centre
  // at eye z = 7.8 - 0.55 - 6.5 = 0.75, radius 6.5.
  const Eye le_grand = facing_camera(le_grand_eye());
  const RayTracer tracer2(scene_of({le_grand}));
  const Point3 center = eye_to_world_facing({0, 0, 0.75});
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> offset(-1.5, 1.5);
  for (int i = 0; i < 100; ++i) {
    const Point3 from = eye_to_world_facing({offset(rng), offset(rng), 4.4});
    const Point3 to = eye_to_world_facing({2 * offset(rng), 2 * offset(rng), 7.0});
    const Ray ray = ray_to(from, to);
    const auto t = ray_sphere(ray.origin, ray.direction, center, 6.5);
    ASSERT_TRUE(t);
    const Hit hit = tracer2.intersect(ray);
    ASSERT_EQ(hit.surface, Surface::cornea_posterior);
    expect_point_near(hit.point, along(ray.origin, ray.direction, *t), 1e-12);
    EXPECT_FALSE(hit.front_face);
  }
}

// The posterior cornea runs down to the iris plane, and the iris ends where
// it meets it (the chamber angle, sqrt(6.5^2 - 3.45^2) = 5.5089 mm from the
// axis for Navarro's eye): a ray along the axis's direction 5 mm from it
// crosses the anterior cornea, then the posterior one 0.55 + 6.5 -
// sqrt(6.5^2 - 5^2) = 2.8967 mm deep (behind the limbus plane, 2.571 mm:
// it used to stop there, and such rays reached the iris having crossed
// only the anterior surface), then the iris; one 5.7 mm from it crosses
// only the anterior cornea and goes on past the iris's edge into the dark
// inside of the sclera.
TEST(RayTracer, ThePosteriorCorneaReachesTheIrisAtTheChamberAngle) {
  const EyeModel m = navarro_eye();
  const Eye eye = facing_camera(m);
  const RayTracer tracer(scene_of({eye}));
  const auto hits_along = [&](double x) {
    std::vector<Hit> hits;
    Ray ray = ray_along(eye_to_world_facing({x, 0, 20}), {0, 0, 1});
    for (int i = 0; i < 4; ++i) {
      const Hit hit = tracer.intersect(ray);
      hits.push_back(hit);
      if (hit.surface == Surface::none || hit.surface == Surface::iris || hit.surface == Surface::sclera) break;
      ray.t_min = hit.t + 1e-7;
    }
    return hits;
  };
  const std::vector<Hit> inner = hits_along(5.0);
  ASSERT_EQ(inner.size(), 3u);
  EXPECT_EQ(inner[0].surface, Surface::cornea_anterior);
  ASSERT_EQ(inner[1].surface, Surface::cornea_posterior);
  expect_point_near(inner[1].point, eye_to_world_facing({5.0, 0, 7.72 - (0.55 + 6.5 - std::sqrt(6.5 * 6.5 - 25.0))}), 1e-12);
  EXPECT_EQ(inner[2].surface, Surface::iris);
  expect_point_near(inner[2].point, eye_to_world_facing({5.0, 0, 7.72 - 3.6}), 1e-12);

  const double angle = std::sqrt(6.5 * 6.5 - 3.45 * 3.45);
  EXPECT_NEAR(m.iris_outer_radius_mm(), angle, 1e-12);
  const std::vector<Hit> outer = hits_along(5.7);
  ASSERT_EQ(outer.size(), 2u);
  EXPECT_EQ(outer[0].surface, Surface::cornea_anterior);
  EXPECT_EQ(outer[1].surface, Surface::sclera);
  EXPECT_FALSE(outer[1].front_face);
  // Just inside and outside the angle, from within the chamber.
  const Point3 chamber = eye_to_world_facing({0, 0, 7.72 - 3.0});
  EXPECT_EQ(tracer.intersect(ray_to(chamber, eye_to_world_facing({angle - 1e-3, 0, 7.72 - 3.6}))).surface,
            Surface::iris);
  EXPECT_EQ(tracer.intersect(ray_to(chamber, eye_to_world_facing({angle + 1e-3, 0, 7.72 - 3.6}))).surface,
            Surface::cornea_posterior);
}

// ---------------------------------------------------------------------------
// Sealing: from outside, nothing inside the eye is reached without crossing
// the shell (cornea, limbal band, sclera), and no ray leaks out of it.

// Follows the ray from hit to hit and checks the sequence. Returns the first
// hit; `entered` tells whether the ray got into the eye.
Hit follow_through(const RayTracer& tracer, const Ray& ray, bool lids, int trial, bool& entered) {
  Ray r = ray;
  Hit first;
  bool inside = false;
  entered = false;
  for (int step = 0; step < 24; ++step) {
    const Hit hit = tracer.intersect(r);
    if (step == 0) first = hit;
    if (hit.surface == Surface::none) {
      EXPECT_FALSE(inside) << "trial " << trial << ": the ray left the eye through a crack";
      return first;
    }
    EXPECT_TRUE(hit.point.is_finite());
    switch (hit.surface) {
      case Surface::cornea_anterior:
      case Surface::sclera:
        EXPECT_EQ(hit.front_face, !inside) << "trial " << trial << " step " << step;
        inside = hit.front_face;
        entered = entered || inside;
        break;
      case Surface::iris:
      case Surface::pupil:
      case Surface::cornea_posterior:
        EXPECT_TRUE(inside) << "trial " << trial << ": " << to_string(hit.surface)
                            << " reached from outside the shell";
        break;
      case Surface::skin:
        EXPECT_TRUE(lids) << "trial " << trial;
        EXPECT_FALSE(inside) << "trial " << trial << ": skin inside the eye";
        break;
      case Surface::mesh:
      case Surface::lash:
      case Surface::brow:
      case Surface::spectacle_lens:
        ADD_FAILURE() << "trial " << trial << ": these scenes have no meshes, hairs or spectacle lenses";
        break;
      case Surface::none:
        break;
    }
    r.t_min = hit.t + 1e-7;
  }
  ADD_FAILURE() << "trial " << trial << ": more than 24 hits";
  return first;
}

void expect_sealed(const Eye& eye, int trials, std::uint64_t seed) {
  const bool lids = eye.appearance().eyelids.has_value();
  const RayTracer tracer(scene_of({eye}));
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> uniform(0, 1);
  const Point3 rc = eye.rotation_center();
  int entered_count = 0;
  for (int i = 0; i < trials; ++i) {
    const Vector3 out = UnitVector3::normalize({gauss(rng), gauss(rng), gauss(rng)}) * 40.0;
    const Vector3 in = UnitVector3::normalize({gauss(rng), gauss(rng), gauss(rng)}) *
                       (3.0 * std::cbrt(uniform(rng)));
    bool entered = false;
    const Hit first = follow_through(tracer, ray_to(rc + out, rc + in), lids, i, entered);
    ASSERT_NE(first.surface, Surface::none) << "trial " << i;
    const bool shell = first.surface == Surface::cornea_anterior || first.surface == Surface::sclera;
    ASSERT_TRUE(shell || (lids && first.surface == Surface::skin))
        << "trial " << i << ": first hit " << to_string(first.surface);
    entered_count += entered;
  }
  // Every ray aims inside the eye; only the lids may stop it.
  if (!lids) {
    EXPECT_EQ(entered_count, trials);
  }
  EXPECT_GT(entered_count, trials / 4);
}

TEST(RayTracer, RandomRaysFromOutsideMeetTheShellFirstAndNeverLeak) {
  expect_sealed(facing_camera(keratometric_eye()), 1500, 1);
  expect_sealed(facing_camera(navarro_eye()), 1500, 2);
  EyeModel wide = le_grand_eye();
  wide.sclera_radius_mm = 12.9;  // the annulus variant of the limbal band
  expect_sealed(facing_camera(wide), 1000, 3);
}

TEST(RayTracer, ARotatedEyeBehindItsLidsIsStillSealed) {
  Eye eye = Eye::with_rotation_center(navarro_eye(), {0, 0, 610},
                                      optical_axis_from_yaw_pitch(40 * kDegree, 0));
  expect_sealed(eye, 1500, 4);
  EyeAppearance look;
  look.eyelids = Eyelids{};
  eye.set_appearance(look);
  expect_sealed(eye, 1500, 5);
}

TEST(RayTracer, RaysAimedAtTheSeamsFindASurface) {
  // The cap's edge (the limbus circle) and the band's lower edge, from many
  // directions and from far away: rounding must not open a crack.
  const EyeModel m = keratometric_eye();
  const Eye eye = Eye::with_rotation_center(m, {3, -2, 900}, optical_axis_from_yaw_pitch(0.2, -0.1));
  const RayTracer tracer(scene_of({eye}));
  const double z_L = 7.8 - limbus_depth(m);
  const double z_m = -5.7 + std::sqrt(144.0 - 5.9 * 5.9);
  int count = 0;
  for (int i = 0; i < 360; ++i) {
    const double a = i * kDegree;
    for (const double z : {z_L, z_m}) {
      const Point3 seam = eye.world_from_eye() * Point3{5.9 * std::cos(a), 5.9 * std::sin(a), z};
      for (const Point3& from : {Point3{0, 0, 0}, Point3{500, 400, 200}, eye.world_from_eye() *
                                     Point3{30 * std::cos(a), 30 * std::sin(a), z + 2}}) {
        const Hit hit = tracer.intersect(ray_to(from, seam));
        EXPECT_NE(hit.surface, Surface::none) << i << " " << z;
        ++count;
      }
    }
  }
  EXPECT_EQ(count, 360 * 6);
}

// ---------------------------------------------------------------------------
// Eyelids and face.

Eye eye_with_lids(const Eyelids& lids, const Point3& rc = {0, 0, 610}) {
  Eye eye = Eye::with_rotation_center(keratometric_eye(), rc, -UnitVector3::unit_z());
  EyeAppearance look;
  look.eyelids = lids;
  eye.set_appearance(look);
  return eye;
}

// Head frame of the default appearance: x = world x, y (up) = world -y,
// z (forward) = world -z; origin at the centre of rotation.
Point3 head_to_world(const Point3& rc, const Point3& h) { return {rc.x + h.x, rc.y - h.y, rc.z - h.z}; }

TEST(RayTracer, OpenLidsShowTheCorneaAndCoverWhatIsAboveTheUpperMargin) {
  const Eye eye = eye_with_lids(Eyelids{});
  const RayTracer tracer(scene_of({eye}));
  const Point3 rc = eye.rotation_center();
  const Point3 camera{0, 0, 0};
  EXPECT_EQ(tracer.intersect(ray_to(camera, eye.corneal_apex())).surface, Surface::cornea_anterior);

  const double R_l = 13.5 + 0.3;
  // 2 mm above the upper margin (4.5 at x = 0), 2 mm below the lower one (-5.5).
  for (const double y : {6.5, -7.5}) {
    const Point3 on_lid = head_to_world(rc, {0, y, std::sqrt(R_l * R_l - y * y)});
    const Hit hit = tracer.intersect(ray_to(camera, on_lid));
    ASSERT_EQ(hit.surface, Surface::skin) << y;
    expect_point_near(hit.point, on_lid, 1e-11);
    expect_direction_near(hit.normal, (on_lid - rc) / R_l, 1e-12);
    EXPECT_TRUE(hit.front_face);
  }
  // At x = 10 the upper margin is at -1 + 5.5 (1 - (10/15)^2) = 2.0556.
  const double upper = -1 + 5.5 * (1 - 100.0 / 225.0);
  const auto on_sphere = [&](double x, double y) {
    return head_to_world(rc, {x, y, std::sqrt(R_l * R_l - x * x - y * y)});
  };
  EXPECT_EQ(tracer.intersect(ray_to(camera, on_sphere(10, upper + 0.05))).surface, Surface::skin);
  const Hit through = tracer.intersect(ray_to(camera, on_sphere(10, upper - 0.05)));
  EXPECT_TRUE(through.surface == Surface::sclera || through.surface == Surface::cornea_anterior)
      << to_string(through.surface);

  // Near the canthi the opening reaches past the eyeball's silhouette:
  // those rays meet the socket behind the lids, never the background.
  int socket = 0;
  for (int i = 0; i <= 40; ++i) {
    const double x = 11.0 + 1.3 * i / 40.0;  // out to the rim of the lid sphere (12.32)
    for (const double sign : {-1.0, 1.0}) {
      const Hit hit = tracer.intersect(ray_to(camera, head_to_world(rc, {sign * x, -1.0, 8.0})));
      ASSERT_NE(hit.surface, Surface::none) << x;
      if (hit.surface == Surface::skin && !hit.front_face) ++socket;
    }
  }
  EXPECT_GT(socket, 0);
}

TEST(RayTracer, ClosedLidsCoverTheWholeCornea) {
  Eyelids closed;
  closed.opening = 0;
  const Eye eye = eye_with_lids(closed);
  const RayTracer tracer(scene_of({eye}));
  for (int i = 0; i <= 10; ++i) {
    for (int j = 0; j < 24; ++j) {
      // Points of the cap out to the limbus: z = sqrt(R^2 - r^2) in the eye frame.
      const double r = 5.9 * i / 10.0, a = j * 15 * kDegree;
      const Point3 target =
          eye.world_from_eye() * Point3{r * std::cos(a), r * std::sin(a), std::sqrt(7.8 * 7.8 - r * r)};
      EXPECT_EQ(tracer.intersect(ray_to({0, 0, 0}, target)).surface, Surface::skin) << i << " " << j;
    }
  }
  EXPECT_TRUE(tracer.occluded_except_cornea({100, 0, 0}, eye.corneal_apex()));
}

// An eye whose optical axis is turned by yaw and pitch (optical_axis_from_yaw_pitch)
// about the centre of rotation (0, 0, 610), with these lids.
Eye turned_eye_with_lids(const Eyelids& lids, double yaw_deg, double pitch_deg) {
  Eye eye = Eye::with_rotation_center(keratometric_eye(), {0, 0, 610},
                                      optical_axis_from_yaw_pitch(yaw_deg * kDegree, pitch_deg * kDegree));
  EyeAppearance look;
  look.eyelids = lids;
  eye.set_appearance(look);
  return eye;
}

Eyelids head_fixed_lids() {
  Eyelids lids;
  lids.upper_gain_upgaze = lids.upper_gain_downgaze = lids.lower_gain_upgaze = lids.lower_gain_downgaze = 0;
  return lids;
}

// Whether the camera at the origin sees the lid at head-frame point (x,
// elevation) of the lid sphere about (0, 0, 610), hit exactly there.
bool sees_lid_at(const RayTracer& tracer, double x, double elevation_deg) {
  const Point3 target = head_to_world({0, 0, 610}, lid_point(x, elevation_deg));
  const Hit hit = tracer.intersect(ray_to({0, 0, 0}, target));
  return hit.surface == Surface::skin && distance(hit.point, target) < 1e-9;
}

TEST(RayTracer, LidsTurnedUpWithTheGazeLeaveThePupilCentreVisible) {
  // Gaze 30 deg up. The pupil centre is 13.5 - 3.6 = 9.9 mm from the centre
  // of rotation, at head height 9.9 sin 30 = 4.95 mm: above the head-fixed
  // upper margin (4.5 mm), under the lid. With the default upper gain of 1
  // the margin turns up 30 deg too, to elevation 49.03 deg (10.42 mm).
  const Eye with_gaze = turned_eye_with_lids(Eyelids{}, 0, 30);
  const Eye head_fixed = turned_eye_with_lids(head_fixed_lids(), 0, 30);
  EXPECT_NEAR(with_gaze.pupil_center().y, -4.95, 1e-12);
  EXPECT_EQ(RayTracer(scene_of({with_gaze})).intersect(ray_to({0, 0, 0}, with_gaze.pupil_center())).surface,
            Surface::cornea_anterior);
  EXPECT_EQ(RayTracer(scene_of({head_fixed})).intersect(ray_to({0, 0, 0}, head_fixed.pupil_center())).surface,
            Surface::skin);
  // The margins, 0.1 deg either side: the upper at 49.03 deg, the lower
  // (gain 0 in upgaze) where it was, -23.49 deg.
  const RayTracer tracer(scene_of({with_gaze}));
  EXPECT_FALSE(sees_lid_at(tracer, 0, 48.93));
  EXPECT_TRUE(sees_lid_at(tracer, 0, 49.13));
  EXPECT_FALSE(sees_lid_at(tracer, 0, -23.39));
  EXPECT_TRUE(sees_lid_at(tracer, 0, -23.59));
}

TEST(RayTracer, LidsFollowADowngazeTheLowerOneLess) {
  // Gaze 20 deg down: the upper margin turns to 19.03 - 20 = -0.97 deg
  // (height -0.233 mm), the lower by 0.6 x 20 = 12 deg, to -35.49 deg
  // (height -8.011 mm).
  const RayTracer tracer(scene_of({turned_eye_with_lids(Eyelids{}, 0, -20)}));
  EXPECT_FALSE(sees_lid_at(tracer, 0, -1.07));
  EXPECT_TRUE(sees_lid_at(tracer, 0, -0.87));
  EXPECT_FALSE(sees_lid_at(tracer, 0, -35.39));
  EXPECT_TRUE(sees_lid_at(tracer, 0, -35.59));
}

TEST(RayTracer, HorizontalGazeAndZeroGainsLeaveTheMarginsWithTheHead) {
  // Head-fixed margins: the upper at 19.03 deg at x = 0 and, at x = 7.5,
  // 15.65 deg; the lower at -23.49 deg.
  const auto expect_head_fixed_margins = [](const Eye& eye, const std::string& what) {
    const RayTracer tracer(scene_of({eye}));
    EXPECT_FALSE(sees_lid_at(tracer, 0, 18.93)) << what;
    EXPECT_TRUE(sees_lid_at(tracer, 0, 19.13)) << what;
    EXPECT_FALSE(sees_lid_at(tracer, 7.5, 15.55)) << what;
    EXPECT_TRUE(sees_lid_at(tracer, 7.5, 15.75)) << what;
    EXPECT_FALSE(sees_lid_at(tracer, 0, -23.39)) << what;
    EXPECT_TRUE(sees_lid_at(tracer, 0, -23.59)) << what;
  };
  expect_head_fixed_margins(turned_eye_with_lids(Eyelids{}, 0, 0), "straight ahead");
  expect_head_fixed_margins(turned_eye_with_lids(Eyelids{}, 35, 0), "35 deg right");
  expect_head_fixed_margins(turned_eye_with_lids(Eyelids{}, -35, 0), "35 deg left");
  expect_head_fixed_margins(turned_eye_with_lids(head_fixed_lids(), 0, 25), "gain 0, 25 deg up");
  expect_head_fixed_margins(turned_eye_with_lids(head_fixed_lids(), 0, -25), "gain 0, 25 deg down");
}

TEST(RayTracer, RejectsEyelidGainsOutsideZeroToTwo) {
  Eyelids lids;
  lids.lower_gain_downgaze = NAN;
  try {
    RayTracer tracer(scene_of({turned_eye_with_lids(lids, 0, 0)}));
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "RayTracer: eyes[0] (keratometric): eyelids lower_gain_downgaze = nan: must be in [0, 2]");
  }
  lids.lower_gain_downgaze = 0.6;
  lids.upper_gain_upgaze = -0.5;
  EXPECT_THROW(RayTracer(scene_of({turned_eye_with_lids(lids, 0, 0)})), std::invalid_argument);
}

// An eye built in code meets the scene reader's anatomy rules
// (anatomy_problem): a sclera too small to reach the limbus plane, which
// the keratometric eye's limbus (2.698 mm deep, 13.5 - 2.698 = 10.80 mm
// in front of the centre of rotation) needs.
TEST(RayTracer, RefusesAnEyeBuiltInCodeThatBreaksTheAnatomyRules) {
  EyeModel m = keratometric_eye();
  m.sclera_radius_mm = 10.0;
  const std::optional<AnatomyProblem> problem = anatomy_problem(m);
  ASSERT_TRUE(problem);
  EXPECT_EQ(problem->key, "sclera_radius_mm");
  try {
    RayTracer tracer(scene_of({Eye::with_cornea_center(m, {0, 0, 600}, UnitVector3::unit_z())}));
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "RayTracer: eyes[0] (keratometric): sclera_radius_mm = 10: " + problem->rule);
    EXPECT_NE(problem->rule.find("must be > 10.80"), std::string::npos) << problem->rule;
  }
}

TEST(RayTracer, TheFacePlaneSurroundsTheLidsOutTo150Millimetres) {
  const Eye eye = eye_with_lids(Eyelids{});
  const RayTracer tracer(scene_of({eye}));
  const Point3 rc = eye.rotation_center();
  const double z_f = 0.45 * 13.8;
  for (const auto& [x, y] : std::vector<std::array<double, 2>>{{60, 0}, {-30, 40}, {0, -100}}) {
    const Point3 on_face = head_to_world(rc, {x, y, z_f});
    const Hit hit = tracer.intersect(ray_to({0, 0, 0}, on_face));
    ASSERT_EQ(hit.surface, Surface::skin) << x << " " << y;
    expect_point_near(hit.point, on_face, 1e-11);
    expect_direction_near(hit.normal, {0, 0, -1}, 1e-15);
    EXPECT_TRUE(hit.front_face);
  }
  // Where the face plane meets the lid sphere (radius sqrt(R_l^2 - z_f^2)),
  // rays find skin on one side of the seam or the other.
  const double rim = std::sqrt(13.8 * 13.8 - z_f * z_f);
  for (int i = 0; i < 72; ++i) {
    const double a = i * 5 * kDegree;
    const Point3 seam = head_to_world(rc, {rim * std::cos(a), rim * std::sin(a), z_f});
    EXPECT_EQ(tracer.intersect(ray_to({0, 0, 0}, seam)).surface, Surface::skin) << i;
  }
  EXPECT_EQ(tracer.intersect(ray_to({0, 0, 0}, head_to_world(rc, {160, 0, z_f}))).surface,
            Surface::none);
}

TEST(RayTracer, EachEyesFaceStopsHalfWayToTheOtherEye) {
  const Eye right = eye_with_lids(Eyelids{}, {-32, 0, 610});
  const Eye left = eye_with_lids(Eyelids{}, {32, 0, 610});
  const RayTracer tracer(scene_of({right, left}));
  for (int e = 0; e < 2; ++e) {
    const Eye& eye = e == 0 ? right : left;
    const Hit hit = tracer.intersect(ray_to({0, 0, 0}, eye.corneal_apex()));
    ASSERT_EQ(hit.surface, Surface::cornea_anterior) << e;
    EXPECT_EQ(hit.eye, e);
  }
  const double z_f = 0.45 * 13.8;
  const Hit between = tracer.intersect(ray_to({0, 0, 0}, {-5, 0, 610 - z_f}));
  ASSERT_EQ(between.surface, Surface::skin);
  EXPECT_EQ(between.eye, 0);
  EXPECT_EQ(tracer.intersect(ray_to({0, 0, 0}, {5, 0, 610 - z_f})).eye, 1);
}

// ---------------------------------------------------------------------------
// Occlusion.

TEST(RayTracer, OccludedSeesEverySurfaceAndTheExceptionIgnoresOnlyTheCornea) {
  const Eye eye = facing_camera(keratometric_eye());
  const RayTracer tracer(scene_of({eye}));
  const Point3 camera{0, 0, 0};
  EXPECT_FALSE(tracer.occluded(camera, {0, 0, 592.1}));              // in front of the apex
  EXPECT_FALSE(tracer.occluded(camera, eye.corneal_apex()));         // ends on the surface
  EXPECT_FALSE(tracer.occluded(eye.corneal_apex(), camera));         // starts on it
  EXPECT_TRUE(tracer.occluded(camera, eye.pupil_center() + Vector3{0.5, 0, -0.01}));  // cornea
  EXPECT_FALSE(tracer.occluded_except_cornea(camera, eye.pupil_center() + Vector3{0.5, 0, -0.01}));
  EXPECT_TRUE(tracer.occluded_except_cornea(camera, eye.rotation_center()));  // the pupil disc
  EXPECT_TRUE(tracer.occluded_except_cornea(camera, {0, 0, 630}));           // and the sclera
  EXPECT_FALSE(tracer.occluded(camera, camera));
  EXPECT_FALSE(tracer.occluded({20, 0, 0}, {20, 0, 1000}));                  // beside the eye
  // An iris point seen from a light beside the camera: only the cornea between.
  const Point3 iris_point = eye_to_world_facing({3, 1, 4.2});
  EXPECT_TRUE(tracer.occluded({100, 0, 0}, iris_point));
  EXPECT_FALSE(tracer.occluded_except_cornea({100, 0, 0}, iris_point));
  // A segment that ends 1 um short of the apex is clear.
  EXPECT_FALSE(tracer.occluded(camera, {0, 0, 592.2 - 1e-6}));

  const Eye two_surface = facing_camera(navarro_eye());
  const RayTracer tracer2(scene_of({two_surface}));
  const Point3 in_stroma{0, 0, 600 - 7.72 + 0.2};
  EXPECT_TRUE(tracer2.occluded(camera, in_stroma));
  EXPECT_FALSE(tracer2.occluded_except_cornea(camera, in_stroma));
  EXPECT_FALSE(tracer2.occluded_except_cornea(camera, two_surface.pupil_center() + Vector3{0, 0, -0.01}));
  EXPECT_TRUE(tracer2.occluded(camera, two_surface.pupil_center() + Vector3{0, 0, -0.01}));
}

// What blocks a segment, nearest its `to` end (the labels' occluded_by):
// a square mesh halfway to the eye, the eye's pupil disc behind its cornea.
TEST(RayTracer, TheOccluderIsTheBlockerNearestTheSegmentsEnd) {
  const Eye eye = facing_camera(keratometric_eye());
  Scene scene = scene_of({eye});
  Mesh square;
  square.name = "square";
  square.vertices = {{-10, -10, 300}, {10, -10, 300}, {10, 10, 300}, {-10, 10, 300}};
  square.triangles = {{0, 1, 2}, {0, 2, 3}};
  scene.meshes = {square};
  const RayTracer tracer(scene);
  const Point3 camera{0, 0, 0};
  EXPECT_EQ(tracer.occluder_except_cornea(eye.rotation_center(), camera), Surface::mesh);
  EXPECT_EQ(tracer.occluder_except_cornea(camera, eye.rotation_center()), Surface::pupil);
  EXPECT_EQ(tracer.occluder_except_cornea(camera, {0, 0, 592.1}), Surface::mesh);
  EXPECT_EQ(tracer.occluder_except_cornea({20, 0, 0}, {20, 0, 1000}), Surface::none);
  // Only the cornea between: nothing.
  EXPECT_EQ(tracer.occluder_except_cornea({0, 0, 400}, eye.pupil_center() + Vector3{0.5, 0, -0.01}), Surface::none);
  EXPECT_EQ(tracer.occluder_except_cornea(camera, camera), Surface::none);
}

// ---------------------------------------------------------------------------
// Meshes.

// v0 = (0, 0, 100), v1 = (10, 0, 100), v2 = (0, 10, 110): the plane
// z = 100 + y. e1 = (10, 0, 0), e2 = (0, 10, 10), e1 x e2 = (0, -100, 100),
// so the front normal is (0, -1, 1) / sqrt(2). A second triangle lies
// beside it, (20, 0, 100), (30, 0, 100), (20, 10, 100), in the plane z = 100.
Mesh two_triangles() {
  Mesh mesh;
  mesh.name = "test";
  mesh.vertices = {{0, 0, 100}, {10, 0, 100}, {0, 10, 110}, {20, 0, 100}, {30, 0, 100}, {20, 10, 100}};
  mesh.triangles = {{0, 1, 2}, {3, 4, 5}};
  mesh.albedo = 0.5;
  return mesh;
}

Scene scene_of(std::vector<Eye> eyes, std::vector<Mesh> meshes) {
  Scene scene = scene_of(std::move(eyes));
  scene.meshes = std::move(meshes);
  return scene;
}

TEST(RayTracer, RayMeetsAMeshTriangleAtTheHandComputedPointAndNormal) {
  const RayTracer tracer(scene_of({}, {two_triangles()}));
  // Along +z through (2, 3): z = 100 + 3 = 103. Barycentric (0.2, 0.3): inside.
  // From 5 m away, where float would be 0.5 um off.
  const Hit hit = tracer.intersect(Ray{{2, 3, -5000}, UnitVector3::unit_z()});
  ASSERT_EQ(hit.surface, Surface::mesh);
  EXPECT_STREQ(to_string(hit.surface), "mesh");
  EXPECT_EQ(hit.mesh, 0);
  EXPECT_EQ(hit.triangle, 0);
  EXPECT_EQ(hit.eye, -1);
  EXPECT_NEAR(hit.t, 5103, 1e-10);
  expect_point_near(hit.point, {2, 3, 103}, 1e-12);
  expect_direction_near(hit.normal, Vector3{0, -1, 1} / std::sqrt(2.0), 1e-15);
  EXPECT_FALSE(hit.front_face);  // +z meets the side facing away from (0, -1, 1)

  // Obliquely, from the origin toward (2, 3, 103): t = |(2, 3, 103)| = sqrt(10622).
  const Hit oblique = tracer.intersect(ray_to({0, 0, 0}, {2, 3, 103}));
  ASSERT_EQ(oblique.surface, Surface::mesh);
  EXPECT_NEAR(oblique.t, std::sqrt(10622.0), 1e-12);
  expect_point_near(oblique.point, {2, 3, 103}, 1e-12);

  // The second triangle, from the front (-z toward +z is its back: e1 x e2 = +z).
  const Hit second = tracer.intersect(Ray{{22, 3, 300}, -UnitVector3::unit_z()});
  ASSERT_EQ(second.surface, Surface::mesh);
  EXPECT_EQ(second.triangle, 1);
  EXPECT_NEAR(second.t, 200, 1e-12);
  EXPECT_TRUE(second.front_face);
  expect_direction_near(second.normal, {0, 0, 1}, 1e-15);

  // Beside both, or past the hypotenuse (barycentric 0.6 + 0.6 > 1): nothing.
  EXPECT_EQ(tracer.intersect(Ray{{15, 3, 0}, UnitVector3::unit_z()}).surface, Surface::none);
  EXPECT_EQ(tracer.intersect(Ray{{6, 6, 0}, UnitVector3::unit_z()}).surface, Surface::none);
}

TEST(RayTracer, MeshBlocksShadowRaysWithOrWithoutTheCornea) {
  const RayTracer tracer(scene_of({}, {two_triangles()}));
  EXPECT_TRUE(tracer.occluded({2, 3, 0}, {2, 3, 200}));
  EXPECT_TRUE(tracer.occluded_except_cornea({2, 3, 0}, {2, 3, 200}));
  EXPECT_TRUE(tracer.occluded({2, 3, 200}, {2, 3, 0}));
  EXPECT_FALSE(tracer.occluded({15, 3, 0}, {15, 3, 200}));  // between the triangles
  // A segment may start or end on the triangle, as on the analytic surfaces.
  EXPECT_FALSE(tracer.occluded({2, 3, 0}, {2, 3, 103}));
  EXPECT_FALSE(tracer.occluded({2, 3, 103}, {2, 3, 200}));
  EXPECT_FALSE(tracer.occluded({2, 3, 0}, {2, 3, 103 - 1e-6}));
}

TEST(RayTracer, TheNearerOfAMeshAndAnEyeIsHitFirstToDoublePrecision) {
  // The keratometric apex on the axis at z = 600 - 7.8 = 592.2. A large
  // square across the axis a nanometre in front of it, then behind it.
  const auto square_at = [](double z) {
    Mesh m;
    m.vertices = {{-50, -50, z}, {50, -50, z}, {50, 50, z}, {-50, 50, z}};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    return m;
  };
  const Eye eye = facing_camera(keratometric_eye());
  const Ray axis{{0, 0, 0}, UnitVector3::unit_z()};
  {
    const RayTracer tracer(scene_of({eye}, {square_at(592.2 - 1e-6)}));
    const Hit hit = tracer.intersect(axis);
    EXPECT_EQ(hit.surface, Surface::mesh);
    EXPECT_NEAR(hit.t, 592.2 - 1e-6, 1e-12);
    // Past the square: the cornea.
    Ray beyond = axis;
    beyond.t_min = hit.t + 1e-7;
    const Hit cornea = tracer.intersect(beyond);
    EXPECT_EQ(cornea.surface, Surface::cornea_anterior);
    EXPECT_NEAR(cornea.t, 592.2, 1e-12);
    EXPECT_EQ(cornea.eye, 0);
    EXPECT_EQ(cornea.mesh, -1);
  }
  {
    const RayTracer tracer(scene_of({eye}, {square_at(592.2 + 1e-6)}));
    EXPECT_EQ(tracer.intersect(axis).surface, Surface::cornea_anterior);
    // Nothing in front of the apex is hidden by the square behind it.
    EXPECT_FALSE(tracer.occluded({0, 0, 0}, {0, 0, 592.2 - 1e-4}));
    EXPECT_FALSE(tracer.occluded_except_cornea({0, 0, 0}, {0, 0, 592.2}));
  }
}

TEST(RayTracer, RejectsMeshesWithIndicesOutOfRangeOrNonFiniteVertices) {
  Mesh bad = two_triangles();
  bad.name = "frame";
  bad.triangles.push_back({0, 1, 6});
  try {
    RayTracer tracer(scene_of({}, {two_triangles(), bad}));
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "RayTracer: meshes[1] (frame): triangle 2 has vertex index 6, but the mesh has 6 vertices");
  }
  bad = two_triangles();
  bad.vertices[4].y = NAN;
  EXPECT_THROW(RayTracer(scene_of({}, {bad})), std::invalid_argument);
  bad.vertices[4].y = 2e6;  // beyond 1 km
  EXPECT_THROW(RayTracer(scene_of({}, {bad})), std::invalid_argument);
  // A mesh without triangles is nothing to meet, not an error.
  Mesh empty;
  const RayTracer tracer(scene_of({}, {empty}));
  EXPECT_EQ(tracer.intersect(Ray{{2, 3, 0}, UnitVector3::unit_z()}).surface, Surface::none);
}

TEST(RayTracer, RaysAcrossASharedEdgeNeverSlipThroughAMesh) {
  // A 2 x 2 grid of squares, 8 triangles sharing edges and a centre
  // vertex: rays aimed exactly at the shared edges and vertices must hit.
  Mesh grid;
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) grid.vertices.push_back({-10.0 + 10 * i, -10.0 + 10 * j, 300});
  }
  for (std::uint32_t j = 0; j < 2; ++j) {
    for (std::uint32_t i = 0; i < 2; ++i) {
      const std::uint32_t a = 3 * j + i;
      grid.triangles.push_back({a, a + 1, a + 4});
      grid.triangles.push_back({a, a + 4, a + 3});
    }
  }
  const RayTracer tracer(scene_of({}, {grid}));
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> along(-9.99, 9.99);
  for (int k = 0; k < 2000; ++k) {
    // On the edges x = 0, y = 0 and the diagonals x = y, through the centre.
    const double s = along(rng);
    const Point3 target = k % 3 == 0 ? Point3{0, s, 300} : k % 3 == 1 ? Point3{s, 0, 300} : Point3{s, s, 300};
    const Hit hit = tracer.intersect(ray_to({1, -2, 0}, target));
    ASSERT_EQ(hit.surface, Surface::mesh) << k;
    expect_point_near(hit.point, target, 1e-10);
  }
}

// ---------------------------------------------------------------------------
// Scenes without lids, bad input, threads.

TEST(RayTracer, WithoutEyelidsRaysBesideTheEyeHitNothing) {
  const RayTracer tracer(scene_of({facing_camera(keratometric_eye())}));
  EXPECT_EQ(tracer.intersect(ray_to({0, 0, 0}, {20, 0, 600})).surface, Surface::none);
  EXPECT_EQ(tracer.intersect(ray_to({0, 0, 0}, {0, 13, 600})).surface, Surface::none);
  EXPECT_EQ(tracer.intersect(Ray{{0, 0, 0}, -UnitVector3::unit_z()}).surface, Surface::none);
  const Hit none = tracer.intersect(ray_to({0, 0, 0}, {20, 0, 600}));
  EXPECT_EQ(none.eye, -1);

  const RayTracer empty(scene_of({}));
  EXPECT_EQ(empty.intersect(Ray{{0, 0, 0}, UnitVector3::unit_z()}).surface, Surface::none);
  EXPECT_FALSE(empty.occluded({0, 0, 0}, {0, 0, 1000}));
}

TEST(RayTracer, TheRayIntervalLimitsHits) {
  const RayTracer tracer(scene_of({facing_camera(keratometric_eye())}));
  Ray ray{{0, 0, 0}, UnitVector3::unit_z()};
  ray.t_max = 592.0;
  EXPECT_EQ(tracer.intersect(ray).surface, Surface::none);
  ray.t_max = 592.3;
  EXPECT_EQ(tracer.intersect(ray).surface, Surface::cornea_anterior);
  ray.t_min = 592.3;  // past the cornea: the pupil, 4.2 mm in front of the centre
  ray.t_max = std::numeric_limits<double>::infinity();
  const Hit pupil = tracer.intersect(ray);
  EXPECT_EQ(pupil.surface, Surface::pupil);
  EXPECT_NEAR(pupil.t, 595.8, 1e-12);
  ray.t_min = ray.t_max = 1.0;
  EXPECT_EQ(tracer.intersect(ray).surface, Surface::none);
}

TEST(RayTracer, RejectsNonFiniteRaysAndUnbuildableEyes) {
  const RayTracer tracer(scene_of({facing_camera(keratometric_eye())}));
  EXPECT_THROW(tracer.intersect(Ray{{NAN, 0, 0}, UnitVector3::unit_z()}), std::invalid_argument);
  Ray negative{{0, 0, 0}, UnitVector3::unit_z()};
  negative.t_min = -1;
  EXPECT_THROW(tracer.intersect(negative), std::invalid_argument);
  EXPECT_THROW(tracer.occluded({0, 0, INFINITY}, {0, 0, 0}), std::invalid_argument);

  EyeModel beyond = keratometric_eye();
  beyond.limbus_radius_mm = 8.0;  // wider than the 7.8 mm sphere
  try {
    RayTracer bad(scene_of({facing_camera(keratometric_eye()), facing_camera(beyond, 700)}));
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("eyes[1]"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("limbus_radius_mm = 8"), std::string::npos) << e.what();
  }
}

TEST(RayTracer, ConcurrentQueriesAgreeWithSerialOnes) {
  // The coverage run gives each test one thread (tests/one_core.cpp): two
  // threads would lose the plain counters' updates. The other runs (the
  // sanitizer phase among them) test this.
  if (std::getenv("PURKINJE_TEST_CORE_LOCKS") != nullptr) GTEST_SKIP() << "one thread a test under the coverage run";
  const Eye eye = eye_with_lids(Eyelids{});
  const RayTracer tracer(scene_of({eye}));
  std::vector<Ray> rays;
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> offset(-20, 20);
  for (int i = 0; i < 4000; ++i) rays.push_back(ray_to({0, 0, 0}, {offset(rng), offset(rng), 600}));
  std::vector<Hit> serial;
  for (const Ray& r : rays) serial.push_back(tracer.intersect(r));
  std::vector<Hit> parallel(rays.size());
  std::vector<char> blocked(rays.size());
  auto work = [&](std::size_t begin) {
    for (std::size_t i = begin; i < rays.size(); i += 2) {
      parallel[i] = tracer.intersect(rays[i]);
      blocked[i] = tracer.occluded(rays[i].origin, rays[i].origin + rays[i].direction * 700.0);
    }
  };
  std::thread a(work, 0), b(work, 1);
  a.join();
  b.join();
  for (std::size_t i = 0; i < rays.size(); ++i) {
    ASSERT_EQ(parallel[i].surface, serial[i].surface) << i;
    ASSERT_EQ(parallel[i].point, serial[i].point) << i;
    ASSERT_EQ(blocked[i] != 0, serial[i].surface != Surface::none) << i;
  }
}

// Packets share Embree's traversal but must find exactly what one ray at a
// time finds: eyes, lids, meshes, misses, empty intervals, under every
// instruction set this CPU runs (packets of 4, 8 or 16), in spans of every
// length from 1 to 16, so that packets are partly filled and a span may
// end in a thin packet traced ray by ray. Embree's fallback for a width
// without native kernels traces unused lanes too; an unused lane left
// uninitialised once aborted every render without AVX-512.
TEST(RayTracer, PacketsFindTheSameHitsAsOneRayAtATimeUnderEveryIsa) {
  Mesh mesh = two_triangles();
  for (Point3& v : mesh.vertices) v = v + Vector3{-15, -5, 480};  // in front of the eye, in view
  const Scene scene = scene_of({eye_with_lids(Eyelids{})}, {mesh});
  std::vector<Ray> rays;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> offset(-25, 25);
  for (int i = 0; i < 4003; ++i) {
    Ray ray = ray_to({0, 0, 0}, {offset(rng), offset(rng), 600});
    if (i % 97 == 0) ray.t_max = ray.t_min;  // an empty interval: nothing
    if (i % 89 == 0) ray.t_max = 590;        // stops short of the eye
    rays.push_back(ray);
  }
  // From inside the anterior chamber (the apex is at z = 596.5, 1.1 mm
  // deeper 4 mm off the axis), on to the pupil and the iris.
  std::uniform_real_distribution<double> inside(-2.8, 2.8);
  for (int i = 0; i < 288; ++i) rays.push_back({{inside(rng), inside(rng), 598}, UnitVector3::unit_z()});
  const std::vector<std::string> isas = testing::runnable_isas();
  ASSERT_GE(isas.size(), 2u);  // every x86-64 CPU runs SSE2 and SSE4.2 at least
  for (const std::string& isa : isas) {
    SCOPED_TRACE("isa=" + isa);
    const testing::ScopedEmbreeConfig config("isa=" + isa);
    const RayTracer tracer(scene);
    EXPECT_EQ(tracer.packet_width(), isa == "avx512" ? 16 : isa.starts_with("avx") ? 8 : 4);
    std::vector<Hit> packed(rays.size());
    for (std::size_t first = 0, length = 1; first < rays.size(); first += length, length = length % 16 + 1) {
      const std::size_t count = std::min(length, rays.size() - first);
      tracer.intersect(std::span<const Ray>(rays).subspan(first, count),
                       std::span<Hit>(packed).subspan(first, count));
    }
    std::array<int, 8> seen{};
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const Hit one = tracer.intersect(rays[i]);
      ASSERT_EQ(packed[i].surface, one.surface) << i;
      ASSERT_EQ(packed[i].eye, one.eye) << i;
      ASSERT_EQ(packed[i].mesh, one.mesh) << i;
      ASSERT_EQ(packed[i].triangle, one.triangle) << i;
      ASSERT_EQ(packed[i].t, one.t) << i;
      ASSERT_EQ(packed[i].point, one.point) << i;
      ASSERT_EQ(packed[i].normal.vector(), one.normal.vector()) << i;
      ASSERT_EQ(packed[i].front_face, one.front_face) << i;
      ++seen[static_cast<int>(one.surface)];
    }
    // The rays met every kind of surface, and missed too.
    for (const Surface s : {Surface::none, Surface::skin, Surface::sclera, Surface::iris, Surface::pupil,
                            Surface::cornea_anterior, Surface::mesh}) {
      EXPECT_GT(seen[static_cast<int>(s)], 0) << to_string(s);
    }
    std::vector<Hit> too_few(rays.size() - 1);
    EXPECT_THROW(tracer.intersect(std::span<const Ray>(rays), std::span<Hit>(too_few)), std::invalid_argument);
  }
}

// Embree 3 runs an unknown isa as SSE2 and ignores unknown keys; purkinje
// refuses both, and an instruction set the CPU lacks, naming the variable.
TEST(EmbreeDevice, ChecksTheConfigurationAgainstEmbreesKeysAndTheCpu) {
  EXPECT_EQ(embree_device("", "avx2").isa, "avx2");
  EXPECT_EQ(embree_device("", "avx2").config, "");
  EXPECT_EQ(embree_device("isa=sse4.2", "avx512").isa, "sse4.2");
  EXPECT_EQ(embree_device(" isa = avx , threads=2 ", "avx2").isa, "avx");
  EXPECT_EQ(embree_device("max_isa=avx", "avx512").isa, "avx");
  EXPECT_EQ(embree_device("isa=avx2,max_isa=sse2", "avx2").isa, "sse2");
  EXPECT_EQ(embree_device("verbose=0,", "sse2").isa, "sse2");
  const auto refuses = [](const std::string& config, const std::string& cpu, const std::string& rule) {
    try {
      embree_device(config, cpu);
      ADD_FAILURE() << config << " accepted";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(std::string(kEmbreeConfigVariable) + "=\"" + config + "\""), std::string::npos) << what;
      EXPECT_NE(what.find(rule), std::string::npos) << what;
    }
  };
  refuses("isa=bogus", "avx2", "isa 'bogus' is not one of sse2, sse4.2, avx, avx2, avx512");
  refuses("isa=avx512", "avx2", "this one supports up to avx2");
  refuses("max_isa=avx2", "sse4.2", "this one supports up to sse4.2");
  refuses("frobnicate=3", "avx2", "unknown key 'frobnicate'");
  refuses("avx2", "avx2", "'avx2' is not key=value");
  // What the CPU runs is one of Embree's instruction sets, and the
  // environment's configuration reaches every device.
  EXPECT_EQ(embree_device("", cpu_isa()).isa, cpu_isa());
  const testing::ScopedEmbreeConfig bad("isa=avx3");
  EXPECT_THROW(embree_device(), std::invalid_argument);
  EXPECT_THROW(RayTracer(scene_of({facing_camera(keratometric_eye())})), std::invalid_argument);
}

// ---------------------------------------------------------------------------
// The bundled remote scene.

Scene remote_scene_with_lids() {
  Scene scene = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/remote.json");
  for (Eye& eye : scene.eyes) {
    EyeAppearance look = eye.appearance();
    look.eyelids = Eyelids{};
    eye.set_appearance(look);
  }
  return scene;
}

TEST(RayTracer, TheRemoteScenesCameraSeesTheCorneaAndSomethingInEveryPixel) {
  const Scene scene = remote_scene_with_lids();
  const RayTracer tracer(scene);
  const Camera& camera = scene.cameras.at(0);
  const Eye& eye = scene.eyes.at(0);
  // Straight at the pupil centre: through the cornea (refraction is the
  // caller's business, the straight line still meets the cornea first).
  const Hit hit = tracer.intersect(ray_to(camera.center(), eye.pupil_center()));
  EXPECT_EQ(hit.surface, Surface::cornea_anterior);
  // Every pixel of the image sees something: the face fills the frame.
  for (int v = 0; v < camera.intrinsics().height; v += 40) {
    for (int u = 0; u < camera.intrinsics().width; u += 40) {
      const Ray ray{camera.center(), camera.back_project({double(u), double(v)})};
      EXPECT_NE(tracer.intersect(ray).surface, Surface::none) << u << " " << v;
    }
  }
}

// CPU time of the calling thread: steadier than wall time on a shared machine.
double thread_seconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

// Run with --gtest_also_run_disabled_tests in a Release build.
TEST(RayTracer, DISABLED_PrimaryRayThroughputAtTheRemoteScene) {
  const Scene scene = remote_scene_with_lids();
  const RayTracer tracer(scene);
  const Camera& camera = scene.cameras.at(0);
  const int width = camera.intrinsics().width, height = camera.intrinsics().height;
  std::vector<Ray> rays;
  rays.reserve(static_cast<std::size_t>(width) * height);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) rays.push_back({camera.center(), camera.back_project({double(u), double(v)})});
  }
  std::array<long, 7> counts{};
  double best = 0;
  for (int repeat = 0; repeat < 5; ++repeat) {
    counts.fill(0);
    const double start = thread_seconds();
    for (const Ray& ray : rays) ++counts[static_cast<int>(tracer.intersect(ray).surface)];
    const double seconds = thread_seconds() - start;
    best = std::max(best, rays.size() / seconds);
  }
  std::printf("primary rays, per core (thread CPU time): %.2f Mrays/s (%zu rays per image)\n", best / 1e6, rays.size());
  for (int s = 0; s < 7; ++s) {
    std::printf("  %-16s %ld\n", to_string(static_cast<Surface>(s)), counts[s]);
  }
  // The crop around the eye (30 x 30 mm about the centre of rotation),
  // where rays meet several surfaces.
  const Eye& eye = scene.eyes.at(0);
  const Pixel centre = camera.project(eye.rotation_center()).pixel;
  const double half = 15.0 * camera.intrinsics().fx / distance(camera.center(), eye.rotation_center());
  std::vector<Ray> crop;
  for (double v = centre.v - half; v <= centre.v + half; v += 0.25) {
    for (double u = centre.u - half; u <= centre.u + half; u += 0.25) {
      crop.push_back({camera.center(), camera.back_project({u, v})});
    }
  }
  double best_crop = 0;
  for (int repeat = 0; repeat < 5; ++repeat) {
    counts.fill(0);
    const double start = thread_seconds();
    for (const Ray& ray : crop) ++counts[static_cast<int>(tracer.intersect(ray).surface)];
    const double seconds = thread_seconds() - start;
    best_crop = std::max(best_crop, crop.size() / seconds);
  }
  std::printf("primary rays at the eye, per core: %.2f Mrays/s (%zu rays)\n", best_crop / 1e6,
              crop.size());
  for (int s = 0; s < 7; ++s) {
    std::printf("  %-16s %ld\n", to_string(static_cast<Surface>(s)), counts[s]);
  }

  // Shadow rays from the hit points toward the first light.
  const Point3 light = scene.illuminators.at(0).position;
  std::vector<Point3> points;
  for (const Ray& ray : rays) {
    const Hit hit = tracer.intersect(ray);
    if (hit.surface != Surface::none) points.push_back(hit.point + hit.normal.vector() * 1e-6);
  }
  const double start = thread_seconds();
  long blocked = 0;
  for (const Point3& p : points) blocked += tracer.occluded(p, light);
  const double seconds = thread_seconds() - start;
  std::printf("shadow rays, per core: %.2f Mrays/s (%ld of %zu blocked)\n",
              points.size() / seconds / 1e6, blocked, points.size());
}

}  // namespace
}  // namespace purkinje::renderer
