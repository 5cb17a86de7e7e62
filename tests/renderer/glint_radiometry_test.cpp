// Glint radiometry and Fresnel reflectance against expectations derived by
// hand: Fresnel's equations at special angles, the astigmatic convex mirror
// (Coddington's equations), the far-field law of a curved mirror (Gaussian
// curvature), the mirror equation for the image of the LED's disc; and an
// independent Monte Carlo that shoots rays at a spherical cornea.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

#include "purkinje/models/camera.h"
#include "purkinje/models/eye.h"
#include "purkinje/models/illuminator.h"
#include "purkinje/models/specular.h"
#include "purkinje/renderer/radiometry.h"

namespace purkinje::renderer {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;

double sq(double x) { return x * x; }

// ---------------------------------------------------------------------------
// Fresnel reflectance

TEST(FresnelReflectance, AtNormalIncidenceIsTheSquaredIndexContrast) {
  for (const double n : {1.3375, 1.376, 1.5}) {
    const double expected = sq((n - 1) / (n + 1));
    EXPECT_NEAR(fresnel_reflectance(1.0, 1.0, n), expected, 1e-16) << n;
    EXPECT_NEAR(fresnel_reflectance(1.0, n, 1.0), expected, 1e-16) << n;
  }
  // 2.08% for the keratometric index, 2.50% for the cornea's own.
  EXPECT_NEAR(fresnel_reflectance(1.0, 1.0, 1.3375), 0.020847, 1e-6);
  EXPECT_NEAR(fresnel_reflectance(1.0, 1.0, 1.376), 0.025043, 1e-6);
}

TEST(FresnelReflectance, MatchesTextbookValuesForGlassAt45Degrees) {
  // n = 1.5 at 45 degrees: Rs = 9.20%, Rp = 0.85% (and Rp = Rs^2 exactly at
  // 45 degrees, Abeles' relation), so R = (Rs + Rs^2) / 2.
  const double sin_t = std::sin(45 * kDeg) / 1.5, cos_t = std::sqrt(1 - sin_t * sin_t);
  const double rs = (std::cos(45 * kDeg) - 1.5 * cos_t) / (std::cos(45 * kDeg) + 1.5 * cos_t);
  EXPECT_NEAR(sq(rs), 0.0920, 1e-4);
  EXPECT_NEAR(fresnel_reflectance(std::cos(45 * kDeg), 1.0, 1.5), 0.5 * (sq(rs) + sq(sq(rs))),
              1e-15);
}

TEST(FresnelReflectance, AtBrewstersAngleOnlyTheSPolarizationReflects) {
  // At tan(theta_B) = n2 / n1 the refracted ray is perpendicular to the
  // reflected one: rp = 0, cos(theta_t) = sin(theta_B), and
  // rs = (n1^2 - n2^2) / (n1^2 + n2^2).
  const std::pair<double, double> media[] = {{1.0, 1.3375}, {1.0, 1.376}, {1.376, 1.0}};
  for (const auto& [n1, n2] : media) {
    const double brewster = std::atan2(n2, n1);
    const double rs = (n1 * n1 - n2 * n2) / (n1 * n1 + n2 * n2);
    EXPECT_NEAR(fresnel_reflectance(std::cos(brewster), n1, n2), 0.5 * rs * rs, 1e-15)
        << n1 << " -> " << n2;
  }
}

TEST(FresnelReflectance, ReachesOneAtGrazingIncidence) {
  EXPECT_NEAR(fresnel_reflectance(0.0, 1.0, 1.3375), 1.0, 1e-15);
  // Rising monotonically from Brewster's angle to grazing.
  double previous = fresnel_reflectance(std::cos(std::atan(1.3375)), 1.0, 1.3375);
  for (double deg = 54; deg <= 89.99; deg += 0.5) {
    const double r = fresnel_reflectance(std::cos(deg * kDeg), 1.0, 1.3375);
    EXPECT_GT(r, previous) << deg;
    previous = r;
  }
  // Near grazing, to first order in c = cos(theta): rs ~ -1 + 2 c / (n ct),
  // rp ~ -1 + 2 n c / ct with ct = sqrt(1 - 1 / n^2), so
  // 1 - R ~ 2 c (n + 1 / n) / ct (1.1% at 89.9 degrees for n = 1.3375).
  const double n = 1.3375, c = std::cos(89.9 * kDeg);
  const double first_order = 2 * c * (n + 1 / n) / std::sqrt(1 - 1 / (n * n));
  EXPECT_NEAR((1 - fresnel_reflectance(c, 1.0, n)) / first_order, 1.0, 0.01);
}

TEST(FresnelReflectance, IsOneBeyondTheCriticalAngleFromInside) {
  const double n = 1.3375, critical = std::asin(1 / n);
  EXPECT_EQ(fresnel_reflectance(std::cos(critical + 1e-9), n, 1.0), 1.0);
  EXPECT_EQ(fresnel_reflectance(std::cos(critical + 0.3), n, 1.0), 1.0);
  EXPECT_EQ(fresnel_reflectance(0.0, n, 1.0), 1.0);
  // Continuous at the critical angle: just inside it nearly everything reflects.
  EXPECT_LT(fresnel_reflectance(std::cos(critical - 1e-3), n, 1.0), 1.0);
  EXPECT_GT(fresnel_reflectance(std::cos(critical - 1e-8), n, 1.0), 0.99);
  // The cosine's sign (which side the direction points) does not matter.
  EXPECT_EQ(fresnel_reflectance(-0.7, n, 1.0), fresnel_reflectance(0.7, n, 1.0));
}

TEST(FresnelReflectance, IsSymmetricUnderSwappingTheMediaAtSnellConjugateAngles) {
  const double n1 = 1.0, n2 = 1.376;
  for (double deg = 0; deg < 90; deg += 5) {
    const double theta1 = deg * kDeg;
    const double theta2 = std::asin(n1 * std::sin(theta1) / n2);
    EXPECT_NEAR(fresnel_reflectance(std::cos(theta1), n1, n2),
                fresnel_reflectance(std::cos(theta2), n2, n1), 1e-15)
        << deg;
  }
}

// ---------------------------------------------------------------------------
// Scenes built backwards from a chosen point of the cornea, so that the
// glint point, incidence and distances are known without the solver.

// An eye at (0, 0, 600) looking down world -z: eye +x is world +x.
Eye eye_at_600(const EyeModel& model) {
  return Eye::with_cornea_center(model, {0, 0, 600}, UnitVector3::normalize({0, 0, -1}));
}

// A point of the anterior cornea in the meridian toward eye +x, at `rho`
// from the optical axis, with its outward normal, the meridian's tangent
// (away from the apex) and the principal radii of curvature there. For
// x^2 + y^2 + (1 + Q) w^2 - 2 R w = 0: the normal is along
// (x, y, R - (1 + Q) w) (eye z = R - w); the sagittal radius is the normal's
// length to the axis, R_s = sqrt(R^2 - Q rho^2); the meridian's own radius
// is R_t = R_s^3 / R^2 (an ellipse's: R at the apex, R / (1 + Q)^1.5 at
// the equator). A sphere has R_s = R_t = R.
struct SurfacePoint {
  Point3 point;
  UnitVector3 normal = UnitVector3::unit_z();
  UnitVector3 tangent = UnitVector3::unit_x();
  double sagittal_radius = 0, tangential_radius = 0;
};

SurfacePoint cornea_point(const Eye& eye, double rho) {
  const double R = eye.model().anterior_cornea.radius_mm;
  const double Q = eye.model().anterior_cornea.asphericity;
  const double w = (R - std::sqrt(R * R - (1 + Q) * rho * rho)) / (1 + Q);
  const Vector3 n = UnitVector3::normalize({rho, 0, R - (1 + Q) * w}).vector();
  const double Rs = std::sqrt(R * R - Q * rho * rho);
  return {eye.world_from_eye() * Point3{rho, 0, R - w},
          UnitVector3::normalize(eye.world_from_eye() * n),
          UnitVector3::normalize(eye.world_from_eye() * Vector3{n.z, 0, -n.x}), Rs,
          Rs * Rs * Rs / (R * R)};
}

// LED and camera on either side of the normal, in the meridional plane, at
// incidence `incidence`: the law of reflection holds at `s` by construction.
struct Layout {
  Point3 light, camera;
};
Layout mirror_about(const SurfacePoint& s, double incidence, double light_distance,
                    double camera_distance) {
  const Vector3 to_light = s.normal * std::cos(incidence) + s.tangent * std::sin(incidence);
  const Vector3 to_camera = s.normal * std::cos(incidence) - s.tangent * std::sin(incidence);
  return {s.point + to_light * light_distance, s.point + to_camera * camera_distance};
}

constexpr double kPitchMm = 0.003;

Camera make_camera(const Point3& center, const Point3& look_at, double focal_mm, double f_number) {
  Sensor sensor;
  sensor.pixel_pitch_mm = kPitchMm;
  sensor.f_number = f_number;
  return Camera("cam", Intrinsics::from_focal_length(focal_mm, kPitchMm, 1280, 1024), {},
                camera_looking_at(center, look_at, {0, -1, 0}), sensor);
}

double aperture_area_mm2(double focal_mm, double f_number) {
  return 0.25 * kPi * sq(focal_mm / f_number);
}

Illuminator led_at(const Point3& position, double intensity_w_sr, double diameter_mm = 0) {
  Illuminator led;
  led.name = "led";
  led.position = position;
  led.radiant_intensity_w_sr = intensity_w_sr;
  led.emitter_diameter_mm = diameter_mm;
  return led;
}

// Coddington's equations for a mirror: a pencil from a point at distance
// d_s, reflected at incidence theta by a surface with principal radii R_t
// (in the plane of incidence) and R_s, seems to come from virtual foci
// a_t, a_s behind the glint point,
//   1 / a_t = 1 / d_s + 2 / (R_t cos theta),  1 / a_s = 1 / d_s + 2 cos theta / R_s.
struct Foci {
  double tangential, sagittal;
};
Foci virtual_foci(double d_s, double theta, double R_t, double R_s) {
  return {1 / (1 / d_s + 2 / (R_t * std::cos(theta))), 1 / (1 / d_s + 2 * std::cos(theta) / R_s)};
}

// Just after reflection the irradiance across the ray is the incident one,
// rho I / d_s^2 (the mirror element's projected area is the same both ways);
// the tube then widens by (a_t + d)(a_s + d) / (a_t a_s) over a distance d.
// A small aperture of area A tilted by gamma to the ray collects E A cos(gamma).
double mirror_power(double rho_I, double d_s, double d_c, const Foci& f, double area,
                    double cos_gamma) {
  const double irradiance = rho_I / (d_s * d_s) * f.tangential * f.sagittal /
                            ((f.tangential + d_c) * (f.sagittal + d_c));
  return irradiance * area * cos_gamma;
}

struct Case {
  double rho_mm;         // glint point's distance from the optical axis
  double incidence_rad;
  double light_mm, camera_mm;  // distances from the glint point
  double look_offset_mm;  // camera aims this far (world y) beside the glint point
  double focal_mm, f_number;
};

struct Measured {
  GlintRadiometry glint;
  double expected_power_w = 0;
  double fresnel = 0;
};

Measured measure_against_mirror(const EyeModel& model, const Case& c, double intensity = 0.01) {
  const Eye eye = eye_at_600(model);
  const SurfacePoint s = cornea_point(eye, c.rho_mm);
  const Layout layout = mirror_about(s, c.incidence_rad, c.light_mm, c.camera_mm);
  const Point3 aim = s.point + Vector3{0, c.look_offset_mm, 0};
  const Camera camera = make_camera(layout.camera, aim, c.focal_mm, c.f_number);
  const Illuminator led = led_at(layout.light, intensity);
  const Reflection r = solve_reflection(eye, led.position, camera.center());
  EXPECT_EQ(r.status, PathStatus::ok) << to_string(r.status);
  EXPECT_LT(distance(r.point, s.point), 1e-9);

  Measured m;
  m.glint = glint_radiometry(eye, led, camera, r);
  m.fresnel = fresnel_reflectance(std::cos(c.incidence_rad), 1.0, anterior_inner_index(model));
  const double cos_gamma = dot(UnitVector3::normalize(aim - layout.camera),
                                 UnitVector3::normalize(s.point - layout.camera));
  m.expected_power_w = mirror_power(
      intensity * m.fresnel, c.light_mm, c.camera_mm,
      virtual_foci(c.light_mm, c.incidence_rad, s.tangential_radius, s.sagittal_radius),
      aperture_area_mm2(c.focal_mm, c.f_number), cos_gamma);
  return m;
}

void expect_mirror_power(const EyeModel& model, const Case& c, double relative_tolerance) {
  const Measured m = measure_against_mirror(model, c);
  ASSERT_EQ(m.glint.status, PathStatus::ok) << to_string(m.glint.status);
  // Relative: near grazing the reflectance is steep in the angle.
  EXPECT_NEAR(m.glint.fresnel / m.fresnel, 1, 1e-13);
  EXPECT_GT(m.glint.power_w, 0);
  EXPECT_NEAR(m.glint.power_w / m.expected_power_w - 1, 0, relative_tolerance)
      << "power " << m.glint.power_w << " W, closed form " << m.expected_power_w << " W";
}

// The method differentiates solved reflections; the closed forms are exact
// for the derivative, so they agree far below the 1% bar. 2e-6 leaves room
// for the solver's last digits; measured errors are 1e-9 to 1e-7.
constexpr double kMirrorTolerance = 2e-6;

// ---------------------------------------------------------------------------
// Glint power: spherical cornea

TEST(GlintPower, NearTheAxisAtRemoteDistanceMatchesTheConvexMirror) {
  // Glint at the apex, LED 3 degrees beside the camera's line, 600 mm.
  expect_mirror_power(keratometric_eye(), {0.0, 1.5 * kDeg, 600, 600, 0, 16, 2.8},
                      kMirrorTolerance);
}

TEST(GlintPower, AtFortyFiveDegreesIncidenceMatchesTheAstigmaticMirror) {
  // Camera aimed 20 mm beside the glint: the aperture is tilted to the ray.
  expect_mirror_power(keratometric_eye(), {2.5, 45 * kDeg, 500, 650, 20, 16, 2.8},
                      kMirrorTolerance);
}

TEST(GlintPower, AtHeadsetDistanceMatchesTheAstigmaticMirror) {
  // 30 mm: the aperture (1.5 mm / f2 = 0.75 mm) spans 1.4 degrees, so the
  // power it collects differs from its centre's irradiance times its area
  // by (r / d)^2 ~ 1e-4. Both sides here are the centre's value; the
  // Monte Carlo test below integrates over the disc.
  expect_mirror_power(keratometric_eye(), {2.0, 25 * kDeg, 30, 35, 5, 1.5, 2.0}, kMirrorTolerance);
}

TEST(GlintPower, AtEightyNineDegreesIncidenceMatchesTheAstigmaticMirror) {
  // The tangential focus collapses onto the surface (a_t ~ R cos(theta) / 2).
  expect_mirror_power(keratometric_eye(), {4.0, 89 * kDeg, 300, 600, 5, 16, 2.8}, 1e-5);
  expect_mirror_power(keratometric_eye(), {5.0, 89.5 * kDeg, 30, 30, 5, 1.5, 2.0}, 1e-5);
}

TEST(GlintPower, ReachesTheFarFieldLawForDistantLightAndCamera) {
  // With d_s, d_c >> R both foci sit at a_t a_s = R^2 / 4, whatever the
  // incidence: P = rho I R^2 / (4 d_s^2 d_c^2) A (camera aimed at the glint).
  const double R = 7.8, d = 1e5, intensity = 0.01, focal = 50, f_number = 4;
  for (const double incidence : {0.1, 0.5, 1.0}) {
    const Measured m = measure_against_mirror(
        keratometric_eye(), {1.0, incidence, d, d, 0, focal, f_number}, intensity);
    const double far_field = m.fresnel * intensity * R * R / (4 * d * d * d * d) *
                             aperture_area_mm2(focal, f_number);
    // Finite distance shrinks a_t a_s and grows (a + d)^2, each by a
    // fraction R / d to first order: -2 R / d = -1.6e-4 (as measured).
    EXPECT_NEAR(m.glint.power_w / far_field - 1, 0, 1e-3) << incidence;
  }
}

TEST(GlintPower, WithTheLedAtTheCameraCentreMatchesTheMirrorEquation) {
  // Normal incidence: both foci at 1 / a = 1 / d + 2 / R.
  const EyeModel model = keratometric_eye();
  const Eye eye = eye_at_600(model);
  const SurfacePoint s = cornea_point(eye, 1.0);
  for (const double d : {10.0, 30.0, 600.0}) {
    const Point3 c = s.point + s.normal * d;
    const Camera camera = make_camera(c, s.point, 8, 2.8);
    const Illuminator led = led_at(c, 0.01);
    const Reflection r = solve_reflection(eye, led.position, camera.center());
    ASSERT_EQ(r.status, PathStatus::ok);
    const GlintRadiometry g = glint_radiometry(eye, led, camera, r);
    ASSERT_EQ(g.status, PathStatus::ok);
    const double a = 1 / (1 / d + 2 / 7.8);
    const double rho = sq(0.3375 / 2.3375);
    const double expected = rho * 0.01 / (d * d) * sq(a / (a + d)) * aperture_area_mm2(8, 2.8);
    EXPECT_NEAR(g.power_w / expected - 1, 0, kMirrorTolerance) << d;
  }
}

// A counter-based stream (splitmix64): deterministic, no global state.
struct SplitMix64 {
  std::uint64_t state;
  double uniform() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return static_cast<double>(z >> 11) * 0x1.0p-53;
  }
};

TEST(GlintPower, MatchesMonteCarloRayShootingOverTheWholeAperture) {
  // Rays from the LED over a patch of directions around the glint, each
  // reflected off the sphere by the vector law and counted if it crosses
  // the aperture disc. This integrates over the aperture, so it also checks
  // that the centre's value stands for the disc at 30 mm.
  const EyeModel model = keratometric_eye();
  const Eye eye = eye_at_600(model);
  const double R = model.anterior_cornea.radius_mm;
  const double n_inner = anterior_inner_index(model);
  const SurfacePoint s = cornea_point(eye, 2.0);
  const double incidence = 20 * kDeg, d_s = 25, d_c = 30, focal = 1.5, f_number = 2.0;
  const Layout layout = mirror_about(s, incidence, d_s, d_c);
  const Point3 aim = s.point + Vector3{0, 4, 0};  // aperture tilted ~7.6 degrees to the ray
  const Camera camera = make_camera(layout.camera, aim, focal, f_number);
  const Illuminator led = led_at(layout.light, 0.02);
  const Reflection r = solve_reflection(eye, led.position, camera.center());
  ASSERT_EQ(r.status, PathStatus::ok);
  const GlintRadiometry g = glint_radiometry(eye, led, camera, r);
  ASSERT_EQ(g.status, PathStatus::ok);

  // Directions d = normalize(c + u e_t + v e_s) (gnomonic: dOmega =
  // du dv / (1 + u^2 + v^2)^1.5) over a rectangle 1.25 times the pre-image
  // of the aperture that the virtual foci predict: an aperture offset q
  // turns the incident direction by q a / ((a + d_c) d_s).
  const Vector3 c = UnitVector3::normalize(s.point - layout.light).vector();
  const Vector3 e_s = UnitVector3::normalize(cross(s.normal, c)).vector();
  const Vector3 e_t = cross(e_s, c);
  const Foci foci = virtual_foci(d_s, incidence, R, R);
  const double aperture_radius = 0.5 * focal / f_number;
  const double U = 1.25 * aperture_radius * foci.tangential / ((foci.tangential + d_c) * d_s);
  const double V = 1.25 * aperture_radius * foci.sagittal / ((foci.sagittal + d_c) * d_s);
  const Point3 sphere_center = eye.cornea_center();
  const Point3 aperture_center = camera.center();
  const Vector3 axis = UnitVector3::normalize(aim - layout.camera).vector();

  // Jittered strata, in independent replicas whose spread gives the error.
  constexpr int kReplicas = 8, kStrata = 220;
  double sum = 0, sum_sq = 0, widest_u = 0, widest_v = 0;
  for (int rep = 0; rep < kReplicas; ++rep) {
    SplitMix64 rng{0x5EED0000ull + static_cast<std::uint64_t>(rep)};
    double power = 0;
    for (int i = 0; i < kStrata; ++i) {
      for (int j = 0; j < kStrata; ++j) {
        const double u = U * (-1 + 2 * (i + rng.uniform()) / kStrata);
        const double v = V * (-1 + 2 * (j + rng.uniform()) / kStrata);
        const Vector3 d = UnitVector3::normalize(c + e_t * u + e_s * v).vector();
        // Nearest intersection with the sphere.
        const Vector3 oc = layout.light - sphere_center;
        const double b = dot(oc, d), disc = b * b - (oc.squared_norm() - R * R);
        if (disc <= 0) continue;
        const double t = -b - std::sqrt(disc);
        if (t <= 0) continue;
        const Point3 p = layout.light + d * t;
        const Vector3 normal = (p - sphere_center) / R;
        const double cos_i = -dot(d, normal);
        const Vector3 reflected = d + normal * (2 * cos_i);
        // Crossing of the aperture plane.
        const double along = dot(reflected, axis);
        if (!(along < 0)) continue;  // the reflected ray must travel toward the camera
        const double t2 = dot(aperture_center - p, axis) / along;
        if (t2 <= 0) continue;
        if ((p + reflected * t2 - aperture_center).squared_norm() >= sq(aperture_radius)) continue;
        power += fresnel_reflectance(cos_i, 1.0, n_inner) / std::pow(1 + u * u + v * v, 1.5);
        widest_u = std::max(widest_u, std::abs(u) / U);
        widest_v = std::max(widest_v, std::abs(v) / V);
      }
    }
    power *= led.radiant_intensity_w_sr * (2 * U / kStrata) * (2 * V / kStrata);
    sum += power;
    sum_sq += power * power;
  }
  // The sampled patch holds the whole pre-image.
  EXPECT_LT(widest_u, 0.95);
  EXPECT_LT(widest_v, 0.95);
  const double mean = sum / kReplicas;
  const double standard_error =
      std::sqrt(std::max(0.0, sum_sq / kReplicas - mean * mean) / (kReplicas - 1));
  // 4 standard errors, plus the disc's departure from its centre's value,
  // of order (r / d_c)^2 = 1.6e-4.
  EXPECT_NEAR(g.power_w, mean, 4 * standard_error + 2e-4 * mean)
      << "relative difference " << g.power_w / mean - 1 << ", standard error "
      << standard_error / mean;
  // The comparison means something (measured: 1.5e-4, difference -0.9e-4).
  EXPECT_LT(standard_error / mean, 3e-4);
}

// ---------------------------------------------------------------------------
// Glint power: aspheric and two-surface corneas

EyeModel prolate_eye() {
  EyeModel m = keratometric_eye();
  m.anterior_cornea.asphericity = -0.26;
  return m;
}

TEST(GlintPower, OnAConicoidMatchesCoddingtonWithItsPrincipalRadii) {
  // In the meridional plane the plane of incidence holds a principal
  // direction, so Coddington's equations hold with R_t and R_s there.
  expect_mirror_power(prolate_eye(), {2.5, 45 * kDeg, 500, 650, 20, 16, 2.8}, kMirrorTolerance);
  expect_mirror_power(prolate_eye(), {3.0, 30 * kDeg, 30, 35, 5, 1.5, 2.0}, kMirrorTolerance);
  expect_mirror_power(prolate_eye(), {4.5, 60 * kDeg, 40, 25, 3, 1.5, 2.0}, kMirrorTolerance);
}

TEST(GlintPower, OnNavarrosTwoSurfaceCorneaUsesTheCorneasIndexAndPrincipalRadii) {
  const EyeModel navarro = navarro_eye();
  ASSERT_TRUE(navarro.posterior_cornea.has_value());
  const Measured m = measure_against_mirror(navarro, {3.5, 40 * kDeg, 500, 650, 20, 16, 2.8});
  EXPECT_EQ(anterior_inner_index(navarro), navarro.posterior_cornea->cornea_index);
  EXPECT_NEAR(m.glint.fresnel, m.fresnel, 1e-15);
  EXPECT_TRUE(std::isfinite(m.glint.power_w));
  EXPECT_GT(m.glint.power_w, 0);
  EXPECT_NEAR(m.glint.power_w / m.expected_power_w - 1, 0, kMirrorTolerance);
  expect_mirror_power(navarro, {4.0, 35 * kDeg, 25, 30, 5, 1.5, 2.0}, kMirrorTolerance);
}

// Far field of any smooth mirror: normals over an area dA span a solid
// angle K dA (Gauss map), and reflection maps it onto 4 cos(theta) K dA of
// reflected directions while the area intercepts rho E cos(theta) dA, so
// the reflected intensity is rho E / (4 K) at any incidence:
// P = rho I / (4 K d_s^2 d_c^2) A.
void expect_far_field_curvature_law(const EyeModel& model, double rho_mm, double incidence) {
  const Eye eye = eye_at_600(model);
  const SurfacePoint s = cornea_point(eye, rho_mm);
  const double d = 1e5, intensity = 0.01, focal = 50, f_number = 4;
  const Layout layout = mirror_about(s, incidence, d, d);
  const Camera camera = make_camera(layout.camera, s.point, focal, f_number);
  const Illuminator led = led_at(layout.light, intensity);
  const Reflection r = solve_reflection(eye, led.position, camera.center());
  ASSERT_EQ(r.status, PathStatus::ok);
  const GlintRadiometry g = glint_radiometry(eye, led, camera, r);
  ASSERT_EQ(g.status, PathStatus::ok);
  const double gaussian_curvature = 1 / (s.sagittal_radius * s.tangential_radius);
  const double rho = fresnel_reflectance(std::cos(incidence), 1.0, anterior_inner_index(model));
  const double far_field = rho * intensity / (4 * gaussian_curvature * sq(d) * sq(d)) *
                           aperture_area_mm2(focal, f_number);
  EXPECT_TRUE(std::isfinite(g.power_w));
  EXPECT_NEAR(g.power_w / far_field - 1, 0, 1e-3) << "rho " << rho_mm << " incidence " << incidence;
}

TEST(GlintPower, OnAConicoidFollowsTheFarFieldGaussianCurvatureLaw) {
  // At the apex K = 1 / R^2: the same power as a sphere of the apex radius.
  expect_far_field_curvature_law(prolate_eye(), 0.0, 0.0);
  // Off the apex the prolate cornea flattens: K = R^2 / R_s^4 < 1 / R^2.
  expect_far_field_curvature_law(prolate_eye(), 4.0, 0.0);
  expect_far_field_curvature_law(prolate_eye(), 4.0, 50 * kDeg);
  expect_far_field_curvature_law(navarro_eye(), 0.0, 0.0);
  expect_far_field_curvature_law(navarro_eye(), 3.0, 30 * kDeg);
}

// ---------------------------------------------------------------------------
// The LED's own image

TEST(SourceCovariance, OfASmallLedAtNormalIncidenceMatchesTheMirrorImage) {
  // LED at the camera centre, both d from the glint on its normal, camera
  // aimed at it. The mirror equation 1 / a = 1 / d + 2 / R puts the virtual
  // image of the disc (diameter D) a behind the surface, magnified a / d;
  // the camera, a + d from it, sees f_px D a / (d (a + d)) pixels. A
  // uniform disc has variance (radius)^2 / 4 per axis.
  const EyeModel model = keratometric_eye();
  const Eye eye = eye_at_600(model);
  const SurfacePoint s = cornea_point(eye, 1.0);
  const double d = 600, D = 0.6, focal = 16, f_px = focal / kPitchMm;
  const Point3 c = s.point + s.normal * d;
  const Camera camera = make_camera(c, s.point, focal, 2.8);
  const Illuminator led = led_at(c, 0.01, D);
  const Reflection r = solve_reflection(eye, led.position, camera.center());
  ASSERT_EQ(r.status, PathStatus::ok);
  const GlintRadiometry g = glint_radiometry(eye, led, camera, r);
  ASSERT_EQ(g.status, PathStatus::ok);

  const double a = 1 / (1 / d + 2 / 7.8);
  const double size_px = f_px * D * a / (d * (a + d));
  const double variance = sq(size_px / 2) / 4;
  EXPECT_NEAR(g.source_cov_px2[0] / variance - 1, 0, 1e-5);
  EXPECT_NEAR(g.source_cov_px2[2] / variance - 1, 0, 1e-5);
  EXPECT_NEAR(g.source_cov_px2[1] / variance, 0, 1e-6);
  // The far-field reading, an image D R / (2 d) seen from d, is 1.3% too
  // large at 600 mm (a = R / 2 and a + d = d each drop 0.65%).
  const double far_size_px = f_px * (D * 7.8 / (2 * d)) / d;
  EXPECT_NEAR(4 * std::sqrt(g.source_cov_px2[0]) / far_size_px - 1, 0, 0.02);
}

TEST(SourceCovariance, AtObliqueIncidenceIsNarrowerInThePlaneOfIncidence) {
  // The tangential and sagittal magnifications a_t / d_s and a_s / d_s,
  // seen from a_t + d_c and a_s + d_c. The plane of incidence is world x-z,
  // which the camera images along u.
  const EyeModel model = keratometric_eye();
  const std::tuple<double, double, double> layouts[] = {{30 * kDeg, 500.0, 600.0},
                                                        {60 * kDeg, 30.0, 35.0}};
  for (const auto& [incidence, d_s, d_c] : layouts) {
    const Eye eye = eye_at_600(model);
    const SurfacePoint s = cornea_point(eye, 2.0);
    const Layout layout = mirror_about(s, incidence, d_s, d_c);
    const double focal = 8, f_px = focal / kPitchMm, D = 1.0;
    const Camera camera = make_camera(layout.camera, s.point, focal, 2.8);
    const Illuminator led = led_at(layout.light, 0.01, D);
    const Reflection r = solve_reflection(eye, led.position, camera.center());
    ASSERT_EQ(r.status, PathStatus::ok);
    const GlintRadiometry g = glint_radiometry(eye, led, camera, r);
    ASSERT_EQ(g.status, PathStatus::ok);
    const Foci f = virtual_foci(d_s, incidence, 7.8, 7.8);
    const double j_t = f_px * f.tangential / (d_s * (f.tangential + d_c));
    const double j_s = f_px * f.sagittal / (d_s * (f.sagittal + d_c));
    const double disc_variance = sq(D / 2) / 4;
    EXPECT_NEAR(g.source_cov_px2[0] / (disc_variance * j_t * j_t) - 1, 0, 1e-5) << incidence;
    EXPECT_NEAR(g.source_cov_px2[2] / (disc_variance * j_s * j_s) - 1, 0, 1e-5) << incidence;
    EXPECT_NEAR(g.source_cov_px2[1] / g.source_cov_px2[2], 0, 1e-6) << incidence;
    EXPECT_LT(g.source_cov_px2[0], g.source_cov_px2[2]);
  }
}

TEST(SourceCovariance, IsZeroForAPointLed) {
  const Measured m =
      measure_against_mirror(keratometric_eye(), {2.0, 20 * kDeg, 500, 600, 0, 8, 2.8});
  ASSERT_EQ(m.glint.status, PathStatus::ok);
  for (const double c : m.glint.source_cov_px2) EXPECT_EQ(c, 0.0);
}

// ---------------------------------------------------------------------------
// Paths that do not exist

void expect_no_power(const GlintRadiometry& g, PathStatus expected) {
  EXPECT_EQ(g.status, expected) << to_string(g.status);
  EXPECT_EQ(g.power_w, 0.0);
  EXPECT_EQ(g.fresnel, 0.0);
  for (const double c : g.source_cov_px2) EXPECT_EQ(c, 0.0);
}

TEST(GlintRadiometry, OffTheCorneaCarriesNoPower) {
  // A glint beyond the limbus (7.8 sin 55 deg = 6.4 mm > 5.9 mm).
  const Eye eye = eye_at_600(keratometric_eye());
  const SurfacePoint s = cornea_point(eye, 7.8 * std::sin(55 * kDeg));
  const Layout layout = mirror_about(s, 20 * kDeg, 500, 600);
  const Camera camera = make_camera(layout.camera, s.point, 16, 2.8);
  const Illuminator led = led_at(layout.light, 0.01, 1.0);
  const Reflection r = solve_reflection(eye, led.position, camera.center());
  ASSERT_EQ(r.status, PathStatus::off_cornea);
  expect_no_power(glint_radiometry(eye, led, camera, r), PathStatus::off_cornea);
}

TEST(GlintRadiometry, ALightBehindTheEyeCarriesNoPower) {
  const Eye eye = eye_at_600(keratometric_eye());
  const Camera camera = make_camera({0, 0, 0}, {0, 0, 600}, 16, 2.8);
  const Illuminator led = led_at({0, 0, 1200}, 0.01, 1.0);
  const Reflection r = solve_reflection(eye, led.position, camera.center());
  ASSERT_NE(r.status, PathStatus::ok);
  expect_no_power(glint_radiometry(eye, led, camera, r), r.status);
}

TEST(GlintRadiometry, PassesEveryFailedStatusThroughWithoutNumbers) {
  const Eye eye = eye_at_600(keratometric_eye());
  const Camera camera = make_camera({0, 0, 0}, {0, 0, 600}, 16, 2.8);
  const Illuminator led = led_at({50, 0, 0}, 0.01, 1.0);
  for (const PathStatus status :
       {PathStatus::no_solution, PathStatus::total_internal_reflection, PathStatus::off_cornea,
        PathStatus::not_converged, PathStatus::invalid_input, PathStatus::occluded}) {
    Reflection r;
    r.status = status;
    r.incidence_rad = std::numeric_limits<double>::quiet_NaN();
    expect_no_power(glint_radiometry(eye, led, camera, r), status);
  }
  // A reflection that claims ok off the cap is off the cornea.
  Reflection r = solve_reflection(eye, led.position, camera.center());
  ASSERT_EQ(r.status, PathStatus::ok);
  r.on_cap = false;
  expect_no_power(glint_radiometry(eye, led, camera, r), PathStatus::off_cornea);
}

TEST(GlintRadiometry, RejectsNonPhysicalLightsAndApertures) {
  const Eye eye = eye_at_600(keratometric_eye());
  const Camera camera = make_camera({0, 0, 0}, {0, 0, 600}, 16, 2.8);
  const Illuminator led = led_at({50, 0, 0}, 0.01, 1.0);
  const Reflection r = solve_reflection(eye, led.position, camera.center());
  ASSERT_EQ(r.status, PathStatus::ok);

  Illuminator negative = led;
  negative.radiant_intensity_w_sr = -1;
  EXPECT_THROW(glint_radiometry(eye, negative, camera, r), std::invalid_argument);
  Illuminator nan_disc = led;
  nan_disc.emitter_diameter_mm = std::numeric_limits<double>::quiet_NaN();
  try {
    glint_radiometry(eye, nan_disc, camera, r);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("led"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("emitter_diameter_mm"), std::string::npos) << e.what();
  }
  Sensor closed;
  closed.f_number = 0;
  const Camera no_aperture("cam", camera.intrinsics(), {}, camera.world_from_camera(), closed);
  EXPECT_THROW(glint_radiometry(eye, led, no_aperture, r), std::invalid_argument);
  // A dark LED is legal: no power, still a glint.
  Illuminator dark = led;
  dark.radiant_intensity_w_sr = 0;
  const GlintRadiometry g = glint_radiometry(eye, dark, camera, r);
  EXPECT_EQ(g.status, PathStatus::ok);
  EXPECT_EQ(g.power_w, 0.0);
}

// ---------------------------------------------------------------------------
// Scleral highlights: the tear film on the sclera's sphere (R = 12 mm about
// the centre of rotation), a mirror like the cornea with the film's index,
// its facets tilted by the roughness.

// A point of the sclera's sphere `angle` from the optical axis, in the
// meridian toward eye +x, with its normal and meridional tangent.
SurfacePoint sclera_point(const Eye& eye, double angle) {
  const double R = eye.model().sclera_radius_mm;
  const Vector3 u = eye.world_from_eye() * Vector3{std::sin(angle), 0, std::cos(angle)};
  const Vector3 t = eye.world_from_eye() * Vector3{std::cos(angle), 0, -std::sin(angle)};
  return {eye.rotation_center() + u * R, UnitVector3::normalize(u), UnitVector3::normalize(t), R, R};
}

struct ScleralCase {
  double angle_rad;  // of the highlight point from the optical axis, about the centre of rotation
  double incidence_rad;
  double light_mm, camera_mm;
  double focal_mm;
};

struct ScleralMeasured {
  GlintRadiometry highlight;
  Reflection reflection;
  Camera camera;
  Illuminator led;
};

ScleralMeasured measure_sclera(const Eye& eye, const ScleralCase& c, const TearFilm& film, double diameter_mm = 0) {
  const SurfacePoint s = sclera_point(eye, c.angle_rad);
  const Layout layout = mirror_about(s, c.incidence_rad, c.light_mm, c.camera_mm);
  ScleralMeasured m{{}, {}, make_camera(layout.camera, s.point, c.focal_mm, 2.8), led_at(layout.light, 0.01, diameter_mm)};
  m.reflection = solve_scleral_reflection(eye, m.led.position, m.camera.center());
  EXPECT_EQ(m.reflection.status, PathStatus::ok) << to_string(m.reflection.status);
  EXPECT_LT(distance(m.reflection.point, s.point), 1e-9);
  m.highlight = scleral_highlight_radiometry(eye, film, m.led, m.camera, m.reflection);
  return m;
}

const ScleralCase kScleralCases[] = {
    {50 * kDeg, 30 * kDeg, 500, 650, 16},  // remote, oblique
    {40 * kDeg, 25 * kDeg, 30, 35, 1.5},   // headset
    {60 * kDeg, 70 * kDeg, 400, 600, 16},  // near grazing
};

TEST(ScleralHighlight, CarriesTheConvexMirrorsPowerWithTheTearFilmsReflectance) {
  const Eye eye = eye_at_600(keratometric_eye());
  for (const ScleralCase& c : kScleralCases) {
    const ScleralMeasured m = measure_sclera(eye, c, TearFilm{});
    ASSERT_EQ(m.highlight.status, PathStatus::ok) << to_string(m.highlight.status);
    const double fresnel = fresnel_reflectance(std::cos(c.incidence_rad), 1.0, kTearFilmIndex);
    EXPECT_NEAR(m.highlight.fresnel / fresnel, 1, 1e-13);
    // Camera aimed at the point: the aperture faces the ray.
    const double expected = mirror_power(0.01 * fresnel, c.light_mm, c.camera_mm,
                                         virtual_foci(c.light_mm, c.incidence_rad, 12, 12),
                                         aperture_area_mm2(c.focal_mm, 2.8), 1.0);
    EXPECT_NEAR(m.highlight.power_w / expected - 1, 0, kMirrorTolerance) << c.incidence_rad;
  }
  // About 2% at normal incidence ((0.333 / 2.333)^2), less than the cornea's.
  EXPECT_NEAR(fresnel_reflectance(1.0, 1.0, kTearFilmIndex), 0.02037, 1e-5);
}

TEST(ScleralHighlight, ItsRoughnessSpreadsItAsTheTiltedFacetsMoveItToFirstOrder) {
  // Closed form of the first-order spread with the camera aimed at the
  // point, the plane of incidence along u: on the tangent plane
  // M_t = 1/R + cos(theta) (1/d_s + 1/d_c) / 2 and
  // M_s = 1/R + (1/d_s + 1/d_c) / (2 cos(theta)), a tilt of sigma moves the
  // point sigma / M, which the camera sees foreshortened by cos(theta)
  // along the plane of incidence: sigma_u = f_px cos(theta) sigma / (d_c M_t),
  // sigma_v = f_px sigma / (d_c M_s).
  const Eye eye = eye_at_600(keratometric_eye());
  const TearFilm film{2.0};
  const double sigma = 2.0 * kDeg, R = 12;
  for (const ScleralCase& c : kScleralCases) {
    const ScleralMeasured m = measure_sclera(eye, c, film);
    ASSERT_EQ(m.highlight.status, PathStatus::ok);
    const double cos_t = std::cos(c.incidence_rad), f_px = c.focal_mm / kPitchMm;
    const double m_t = 1 / R + cos_t * (1 / c.light_mm + 1 / c.camera_mm) / 2;
    const double m_s = 1 / R + (1 / c.light_mm + 1 / c.camera_mm) / (2 * cos_t);
    const double sigma_u = f_px * cos_t * sigma / (c.camera_mm * m_t), sigma_v = f_px * sigma / (c.camera_mm * m_s);
    // The projection's derivative is taken by differences: 1e-6 relative.
    EXPECT_NEAR(m.highlight.roughness_cov_px2[0] / (sigma_u * sigma_u) - 1, 0, 1e-5) << c.incidence_rad;
    EXPECT_NEAR(m.highlight.roughness_cov_px2[2] / (sigma_v * sigma_v) - 1, 0, 1e-5) << c.incidence_rad;
    EXPECT_NEAR(m.highlight.roughness_cov_px2[1] / (sigma_u * sigma_v), 0, 1e-5) << c.incidence_rad;
  }

  // Independently: tilt every facet by a small d along each tangent and
  // find the point where the tilted normal halves light and camera by
  // Newton on the sphere; the pixels it moves to, per unit tilt, give the
  // covariance sigma^2 K K^T (the tilt is isotropic, sigma per axis).
  const ScleralCase oblique{50 * kDeg, 30 * kDeg, 60, 45, 4};
  const ScleralMeasured m = measure_sclera(eye, oblique, film);
  ASSERT_EQ(m.highlight.status, PathStatus::ok);
  const Point3 centre = eye.rotation_center();
  const UnitVector3 n0 = m.reflection.normal;
  const UnitVector3 t1 = UnitVector3::normalize(cross(n0, Vector3{0, 1, 0}));
  const UnitVector3 t2 = UnitVector3::normalize(cross(n0, t1));
  const auto point_at = [&](double a, double b) {
    return centre + UnitVector3::normalize(n0.vector() + t1 * a + t2 * b) * R;
  };
  const auto residual = [&](const Vector3& tilt, double a, double b, double out[2]) {
    const Point3 x = point_at(a, b);
    const Vector3 facet = UnitVector3::normalize(x - centre).vector() + tilt;
    const Vector3 half = UnitVector3::normalize(m.led.position - x).vector() +
                         UnitVector3::normalize(m.camera.center() - x).vector();
    const Vector3 diff = UnitVector3::normalize(facet).vector() - UnitVector3::normalize(half).vector();
    out[0] = dot(diff, t1);
    out[1] = dot(diff, t2);
  };
  const double tilt = 1e-5;
  double k[2][2];  // pixel per unit tilt: rows u, v; columns tilt along t1, t2
  for (int axis = 0; axis < 2; ++axis) {
    const Vector3 d = (axis == 0 ? t1 : t2) * tilt;
    double a = 0, b = 0;
    for (int it = 0; it < 20; ++it) {
      double r[2], ra[2], rb[2];
      const double h = 1e-7;
      residual(d, a, b, r);
      residual(d, a + h, b, ra);
      residual(d, a, b + h, rb);
      const double j00 = (ra[0] - r[0]) / h, j10 = (ra[1] - r[1]) / h, j01 = (rb[0] - r[0]) / h, j11 = (rb[1] - r[1]) / h;
      const double det = j00 * j11 - j01 * j10;
      a -= (j11 * r[0] - j01 * r[1]) / det;
      b -= (-j10 * r[0] + j00 * r[1]) / det;
    }
    const Projection moved = m.camera.project(point_at(a, b));
    const Projection still = m.camera.project(m.reflection.point);
    k[0][axis] = (moved.pixel.u - still.pixel.u) / tilt;
    k[1][axis] = (moved.pixel.v - still.pixel.v) / tilt;
  }
  const double s2 = sigma * sigma;
  const double cov_uu = s2 * (k[0][0] * k[0][0] + k[0][1] * k[0][1]);
  const double cov_uv = s2 * (k[0][0] * k[1][0] + k[0][1] * k[1][1]);
  const double cov_vv = s2 * (k[1][0] * k[1][0] + k[1][1] * k[1][1]);
  EXPECT_NEAR(m.highlight.roughness_cov_px2[0] / cov_uu - 1, 0, 1e-3);
  EXPECT_NEAR(m.highlight.roughness_cov_px2[2] / cov_vv - 1, 0, 1e-3);
  EXPECT_NEAR(m.highlight.roughness_cov_px2[1], cov_uv, 1e-3 * std::sqrt(cov_uu * cov_vv));
}

TEST(ScleralHighlight, AMirrorSclerasHighlightIsTheLedsImageAlone) {
  const Eye eye = eye_at_600(keratometric_eye());
  const ScleralMeasured m = measure_sclera(eye, kScleralCases[0], TearFilm{0.0}, 1.0);
  ASSERT_EQ(m.highlight.status, PathStatus::ok);
  for (const double c : m.highlight.roughness_cov_px2) EXPECT_EQ(c, 0.0);
  // The disc's image as the cornea's test derives it, with R = 12.
  const ScleralCase& c = kScleralCases[0];
  const Foci f = virtual_foci(c.light_mm, c.incidence_rad, 12, 12);
  const double f_px = c.focal_mm / kPitchMm;
  const double j_t = f_px * f.tangential / (c.light_mm * (f.tangential + c.camera_mm));
  EXPECT_NEAR(m.highlight.source_cov_px2[0] / (sq(0.5) / 4 * j_t * j_t) - 1, 0, 1e-5);
}

TEST(ScleralReflection, IsOnlyWhereTheSphereIsSclera) {
  // Behind the seam (13.5 - sqrt(12^2 - 5.9^2) = 3.05 mm below the apex for
  // the keratometric eye) the sphere is sclera; in front of it, cornea.
  const EyeModel model = keratometric_eye();
  EXPECT_NEAR(model.sclera_seam_depth_mm(), 13.5 - std::sqrt(144 - 5.9 * 5.9), 1e-12);
  const Eye eye = eye_at_600(model);
  // The seam lies sqrt(144 - 5.9^2) = 10.45 mm above the centre of
  // rotation: 29.4 deg from the axis.
  const double seam_angle = std::asin(5.9 / 12);
  for (const double angle : {seam_angle - 0.01, seam_angle + 0.01}) {
    const SurfacePoint s = sclera_point(eye, angle);
    const Layout layout = mirror_about(s, 20 * kDeg, 500, 600);
    const Reflection r = solve_scleral_reflection(eye, layout.light, layout.camera);
    const Reflection sphere = solve_sphere_reflection(eye.rotation_center(), 12, layout.light, layout.camera);
    EXPECT_EQ(sphere.status, PathStatus::ok);
    EXPECT_LT(distance(sphere.point, s.point), 1e-9);
    EXPECT_LT(reflection_residual_rad(sphere), 1e-12);
    EXPECT_EQ(r.status, angle > seam_angle ? PathStatus::ok : PathStatus::no_solution) << angle;
    EXPECT_FALSE(r.on_cap);
  }
  // An end inside the sphere has no path.
  EXPECT_EQ(solve_sphere_reflection({0, 0, 0}, 12, {0, 0, 5}, {0, 0, 100}).status, PathStatus::invalid_input);
}

}  // namespace
}  // namespace purkinje::renderer
