// The cornea's glint (sphere and conicoid) and its derivatives, against the
// independent reference (et_simul, 50-digit check), the general specular
// solver, hand-solvable layouts and central differences.

#include "purkinje/trackers/cornea_glint.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "purkinje/models/eye.h"
#include "purkinje/models/specular.h"
#include "reference_data.h"

namespace purkinje::trackers {
namespace {

Camera reference_camera() {
  return Camera("reference", Intrinsics::from_focal_length(25, 0.005, 2560, 2048), {}, Pose());
}

TEST(SphereGlint, MatchesTheIndependentReference) {
  int checked = 0;
  for (const testing::CsvRow& row : testing::read_reference("glints_and_pupil.csv")) {
    if (row.num("glint_visible_etsimul") != 1) continue;
    const Point3 center{row.num("cornea_center_x_mm"), row.num("cornea_center_y_mm"),
                        row.num("cornea_center_z_mm")};
    const Point3 light{row.num("light_x_mm"), row.num("light_y_mm"), row.num("light_z_mm")};
    const std::optional<CorneaGlint> g =
        sphere_glint(reference_camera(), center, row.num("cornea_radius_mm"), light);
    ASSERT_TRUE(g) << row.str("case_id");
    EXPECT_NEAR(g->point.x, row.num("glint_x_mm"), 1e-9) << row.str("case_id");
    EXPECT_NEAR(g->point.y, row.num("glint_y_mm"), 1e-9);
    EXPECT_NEAR(g->point.z, row.num("glint_z_mm"), 1e-9);
    EXPECT_NEAR(g->pixel.u, row.num("glint_u_px"), 1e-7);
    EXPECT_NEAR(g->pixel.v, row.num("glint_v_px"), 1e-7);
    ++checked;
  }
  EXPECT_GE(checked, 10);
}

TEST(SphereGlint, ALightAtTheCameraGlintsOnTheLineToTheCentre) {
  // Coaxial light: the normal points at the camera, P = C + R (O - C)/|O - C|.
  const Camera camera = reference_camera();
  const Point3 center{12, -7, 480};
  const std::optional<CorneaGlint> g = sphere_glint(camera, center, 7.8, camera.center());
  ASSERT_TRUE(g);
  const Vector3 toward = (camera.center() - center) / (camera.center() - center).norm();
  EXPECT_NEAR(distance(g->point, center + 7.8 * toward), 0, 1e-12);
  // Seen straight along the line of sight, it is the centre's own pixel.
  EXPECT_NEAR(g->pixel.u, camera.project(center).pixel.u, 1e-9);
  EXPECT_NEAR(g->pixel.v, camera.project(center).pixel.v, 1e-9);
}

TEST(SphereGlint, SymmetricLightAndCameraGlintOnTheAxisBetweenThem) {
  // Light and camera mirror images across the line x = 0 through the
  // centre: the glint is the sphere's point on that line.
  Camera camera("c", Intrinsics::from_focal_length(25, 0.005, 2560, 2048), {},
                camera_looking_at({-30, 0, 0}, {0, 0, 40}, {0, -1, 0}));
  const std::optional<CorneaGlint> g = sphere_glint(camera, {0, 0, 40}, 7.8, {30, 0, 0});
  ASSERT_TRUE(g);
  EXPECT_NEAR(g->point.x, 0, 1e-12);
  EXPECT_NEAR(g->point.y, 0, 1e-12);
  EXPECT_NEAR(g->point.z, 40 - 7.8, 1e-12);
}

TEST(SphereGlint, AgreesWithTheSpecularSolverFromNearToGrazing) {
  const Camera camera = reference_camera();
  EyeModel model = keratometric_eye();
  model.limbus_radius_mm = 7.7;  // a cap almost to the equator, for grazing glints
  model.iris_radius_mm = 6;
  int checked = 0;
  for (const double depth : {25.0, 45.0, 600.0, 2000.0}) {
    const Point3 center{3, -2, depth};
    const Eye eye = Eye::with_cornea_center(model, center, UnitVector3::normalize(camera.center() - center));
    // Lights from beside the camera to far off the axis (incidence near 85 deg at 25 mm).
    for (const double x : {5.0, 40.0, 150.0, 600.0}) {
      for (const double y : {-0.5 * x, 0.3 * x}) {
        const Point3 light{x, y, depth * 0.1};
        const Reflection r = solve_reflection(eye, light, camera.center());
        if (r.status != PathStatus::ok) continue;
        const std::optional<CorneaGlint> g = sphere_glint(camera, center, 7.8, light);
        ASSERT_TRUE(g) << depth << " " << x;
        EXPECT_NEAR(distance(g->point, r.point), 0, 1e-9) << depth << " " << x << " " << r.incidence_rad;
        const std::optional<CorneaGlint> warm = sphere_glint(camera, center, 7.8, light, g->normal);
        ASSERT_TRUE(warm);
        EXPECT_NEAR(distance(warm->point, r.point), 0, 1e-9);
        ++checked;
      }
    }
  }
  EXPECT_GE(checked, 24);
}

// A turned, distorting camera near an eye, for the derivatives' checks.
Camera distorting_camera() {
  const Distortion lens{.k1 = -0.1, .k2 = 0.02, .p1 = 0.001, .p2 = 0, .k3 = 0};
  return Camera("c", Intrinsics::from_focal_length(8, 0.003, 640, 480), lens,
                camera_looking_at({0, 20, 0}, {2, 0, 35}, {0, -1, 0}));
}

// A glint's d(pixel)/d(centre, radius) against central differences of
// `glint_at(centre, radius)`; returns the glint at (center, radius).
std::optional<CorneaGlint> expect_derivatives_match_central_differences(
    const std::function<std::optional<CorneaGlint>(const Point3&, double)>& glint_at, const Point3& center,
    double radius) {
  const std::optional<CorneaGlint> g = glint_at(center, radius);
  EXPECT_TRUE(g);
  if (!g) return g;
  constexpr double h = 1e-5;
  for (int k = 0; k < 4; ++k) {
    Point3 cp = center, cm = center;
    double rp = radius, rm = radius;
    if (k == 3) {
      rp += h, rm -= h;
    } else {
      (k == 0 ? cp.x : k == 1 ? cp.y : cp.z) += h;
      (k == 0 ? cm.x : k == 1 ? cm.y : cm.z) -= h;
    }
    const std::optional<CorneaGlint> p = glint_at(cp, rp);
    const std::optional<CorneaGlint> m = glint_at(cm, rm);
    EXPECT_TRUE(p && m);
    if (!p || !m) return g;
    EXPECT_NEAR(g->d_pixel[k], (p->pixel.u - m->pixel.u) / (2 * h), 1e-5 * std::abs(g->d_pixel[k]) + 1e-6) << k;
    EXPECT_NEAR(g->d_pixel[4 + k], (p->pixel.v - m->pixel.v) / (2 * h), 1e-5 * std::abs(g->d_pixel[4 + k]) + 1e-6)
        << k;
  }
  return g;
}

TEST(SphereGlint, DerivativesMatchCentralDifferences) {
  const Camera camera = distorting_camera();
  const Point3 light{-18, -12, 4};
  const std::optional<CorneaGlint> g = expect_derivatives_match_central_differences(
      [&](const Point3& c, double r) { return sphere_glint(camera, c, r, light); }, {2, 1, 36}, 7.6);
  ASSERT_TRUE(g);
  // A sphere moved along the line of sight changes its glint's pixel little;
  // one moved sideways drags it along: the derivatives must show that.
  EXPECT_GT(std::abs(g->d_pixel[0]), 10.0);
}

TEST(SphereGlint, RefusesLightsInsideBehindAndOnTheFarSide) {
  const Camera camera = reference_camera();
  const Point3 center{0, 0, 600};
  EXPECT_FALSE(sphere_glint(camera, center, 7.8, {0, 0, 603}));       // light inside
  EXPECT_FALSE(sphere_glint(camera, {0, 0, 3}, 7.8, {10, 0, 0}));     // camera inside
  EXPECT_FALSE(sphere_glint(camera, center, 7.8, {0, 0, 1200}));      // light straight behind
  EXPECT_FALSE(sphere_glint(camera, center, -1, {10, 0, 0}));          // no sphere
  EXPECT_FALSE(sphere_glint(camera, {0, 0, -600}, 7.8, {10, 0, -500}));  // glint behind the camera
  // A light just past the limb still has a glint on a sphere (near grazing).
  EXPECT_TRUE(sphere_glint(camera, center, 7.8, {1000, 0, 640}));
}

// The conicoid's glint against the general specular solver (an independent
// method: Levenberg-Marquardt on the surface's own parametrization), for
// Navarro's cornea, a flatter and a steeper one, turned eyes and far
// lights, from near to far.
TEST(ConicoidGlint, AgreesWithTheSpecularSolver) {
  const Camera camera = reference_camera();
  int checked = 0;
  for (const double asphericity : {-0.26, -0.6, 0.3}) {
    EyeModel model = navarro_eye();
    model.anterior_cornea.asphericity = asphericity;
    model.limbus_radius_mm = 6.5;  // a wide cap, for glints far from the apex
    for (const double depth : {30.0, 60.0, 600.0, 2000.0}) {
      const Point3 center{3, -2, depth};
      for (const double turn_deg : {0.0, 12.0, 30.0}) {
        const double t = turn_deg * std::numbers::pi / 180;
        const Vector3 toward = camera.center() - center;
        // The eye looks toward the camera, turned by `t` about the y axis.
        const UnitVector3 axis = UnitVector3::normalize(
            Vector3{toward.x * std::cos(t) + toward.z * std::sin(t), toward.y, -toward.x * std::sin(t) + toward.z * std::cos(t)});
        const Eye eye = Eye::with_cornea_center(model, center, axis);
        for (const double x : {5.0, 40.0, 150.0}) {
          for (const double y : {-0.5 * x, 0.3 * x}) {
            const Point3 light{x, y, depth * 0.1};
            const Reflection r = solve_reflection(eye, light, camera.center());
            if (r.status != PathStatus::ok) continue;
            const std::optional<CorneaGlint> g =
                conicoid_glint(camera, center, axis, model.anterior_cornea, light);
            ASSERT_TRUE(g) << asphericity << " " << depth << " " << turn_deg << " " << x;
            EXPECT_NEAR(distance(g->point, r.point), 0, 1e-9) << asphericity << " " << depth << " " << turn_deg;
            EXPECT_NEAR(angle_between(g->normal.vector(), r.normal.vector()), 0, 1e-9);
            const std::optional<CorneaGlint> warm =
                conicoid_glint(camera, center, axis, model.anterior_cornea, light, g->normal);
            ASSERT_TRUE(warm);
            EXPECT_NEAR(distance(warm->point, r.point), 0, 1e-9);
            ++checked;
          }
        }
      }
    }
  }
  EXPECT_GE(checked, 150);
}

// A conicoid all but a sphere, through the conicoid's own Newton search:
// the sphere's glint.
TEST(ConicoidGlint, ANearSphereGivesTheSphereGlint) {
  const Camera camera = reference_camera();
  const Point3 center{2, 1, 45}, light{-30, 10, 0};
  const UnitVector3 axis = UnitVector3::normalize(Vector3{0.3, -0.2, -1});
  const std::optional<CorneaGlint> s = sphere_glint(camera, center, 7.8, light);
  const std::optional<CorneaGlint> c = conicoid_glint(camera, center, axis, Conicoid{7.8, 1e-9}, light);
  ASSERT_TRUE(s && c);
  EXPECT_LT(distance(s->point, c->point), 1e-8);
}

TEST(ConicoidGlint, OnTheAxisItIsTheApex) {
  // A light at the camera, both on the optical axis: the glint is the apex,
  // whatever the asphericity.
  Camera camera = reference_camera();
  const Point3 center{0, 0, 50};
  const std::optional<CorneaGlint> g = conicoid_glint(camera, center, UnitVector3::normalize(Vector3{0, 0, -1}),
                                                      Conicoid{7.72, -0.26}, {0, 0, 0});
  ASSERT_TRUE(g);
  EXPECT_NEAR(g->point.x, 0, 1e-12);
  EXPECT_NEAR(g->point.y, 0, 1e-12);
  EXPECT_NEAR(g->point.z, 50 - 7.72, 1e-12);
}

TEST(ConicoidGlint, DerivativesMatchCentralDifferences) {
  const Camera camera = distorting_camera();
  const Point3 light{-18, -12, 4};
  // Turned 20 deg away from the camera, so that the glint is far from the apex.
  const UnitVector3 axis = UnitVector3::normalize(Vector3{0.35, -0.6, -1});
  const std::optional<CorneaGlint> g = expect_derivatives_match_central_differences(
      [&](const Point3& c, double r) { return conicoid_glint(camera, c, axis, Conicoid{r, -0.3}, light); },
      {2, 1, 36}, 7.6);
  ASSERT_TRUE(g);
  // The apex radius moves the glint: the derivative the radius's fit needs.
  EXPECT_GT(std::abs(g->d_pixel[3]), 1.0);
}

TEST(ConicoidGlint, RefusesWhatHasNoGlint) {
  const Camera camera = reference_camera();
  const Point3 center{0, 0, 600};
  const UnitVector3 toward_camera = UnitVector3::normalize(Vector3{0, 0, -1});
  EXPECT_FALSE(conicoid_glint(camera, center, toward_camera, Conicoid{7.72, -0.26}, {0, 0, 1200}));  // light behind
  EXPECT_FALSE(conicoid_glint(camera, center, toward_camera, Conicoid{7.72, -1.5}, {10, 0, 0}));     // not an ellipsoid
  EXPECT_FALSE(conicoid_glint(camera, center, toward_camera, Conicoid{-1, -0.26}, {10, 0, 0}));      // no surface
  // An eye looking straight away from the camera: its glint would be on the back of the ellipsoid.
  EXPECT_FALSE(conicoid_glint(camera, center, UnitVector3::unit_z(), Conicoid{7.72, -0.26}, {10, 0, 0}));
}

}  // namespace
}  // namespace purkinje::trackers
