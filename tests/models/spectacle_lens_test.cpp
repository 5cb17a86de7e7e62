// Spectacle lenses: their powers, the paths through them and mirrored by
// them (the specular-path solver's Fermat chains), and the labels of an eye
// seen through one. Every path is checked by shooting: a ray traced here
// by hand (sphere intersections, Snell's and the mirror's law in vector
// form) from one end along the solver's direction, which must reach the
// other end.

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <stdexcept>
#include <vector>

#include "purkinje/models/eye.h"
#include "purkinje/models/specular.h"
#include "purkinje/models/truth.h"

namespace purkinje {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;

// ------------------------------------------------------- a ray, by hand

struct Ray3 {
  Point3 origin;
  Vector3 direction;  // unit
};

// The ray's next crossing of a sphere: the far one from inside, the near
// one from outside.
std::optional<Point3> next_crossing(const Ray3& ray, const Point3& centre, double radius) {
  const Vector3 m = ray.origin - centre;
  const double b = dot(m, ray.direction), c = m.squared_norm() - radius * radius;
  const double disc = b * b - c;
  if (disc < 0) return std::nullopt;
  const double t = c < 0 ? -b + std::sqrt(disc) : -b - std::sqrt(disc);
  if (!(t > 1e-9)) return std::nullopt;
  return ray.origin + ray.direction * t;
}

// Snell's law at a sphere from index n1 into n2; nullopt on a miss or
// total internal reflection.
std::optional<Ray3> refract_at(const Ray3& ray, const Point3& centre, double radius, double n1, double n2) {
  const std::optional<Point3> p = next_crossing(ray, centre, radius);
  if (!p) return std::nullopt;
  Vector3 n = (*p - centre) / radius;
  if (dot(n, ray.direction) > 0) n = -n;  // facing the incoming ray
  const double eta = n1 / n2, cos_i = -dot(n, ray.direction);
  const double k = 1 - eta * eta * (1 - cos_i * cos_i);
  if (k < 0) return std::nullopt;
  const Vector3 t = ray.direction * eta + n * (eta * cos_i - std::sqrt(k));
  return Ray3{*p, t / t.norm()};
}

std::optional<Ray3> reflect_at(const Ray3& ray, const Point3& centre, double radius) {
  const std::optional<Point3> p = next_crossing(ray, centre, radius);
  if (!p) return std::nullopt;
  const Vector3 n = (*p - centre) / radius;
  return Ray3{*p, ray.direction - n * (2 * dot(n, ray.direction))};
}

// The distance from a point to the ray's line, ahead of its origin.
double miss(const Ray3& ray, const Point3& p) {
  const Vector3 v = p - ray.origin;
  if (dot(v, ray.direction) < 0) return 1e9;
  return (v - ray.direction * dot(v, ray.direction)).norm();
}

Point3 front_centre(const SpectacleLens& lens) { return lens.world_from_lens * Point3{0, 0, -lens.front_radius_mm}; }
Point3 back_centre(const SpectacleLens& lens) {
  return lens.world_from_lens * Point3{0, 0, -lens.center_thickness_mm - lens.back_radius_mm};
}

// Through both surfaces, from whichever side the ray starts on.
std::optional<Ray3> through(const SpectacleLens& lens, const Ray3& ray, bool from_front) {
  const double n = lens.refractive_index;
  if (from_front) {
    const auto in = refract_at(ray, front_centre(lens), lens.front_radius_mm, 1, n);
    return in ? refract_at(*in, back_centre(lens), lens.back_radius_mm, n, 1) : std::nullopt;
  }
  const auto in = refract_at(ray, back_centre(lens), lens.back_radius_mm, 1, n);
  return in ? refract_at(*in, front_centre(lens), lens.front_radius_mm, n, 1) : std::nullopt;
}

// ------------------------------------------------------- scenes

// A -3 D CR-39 lens on a 4 D base, 2 mm thick, placed with its optical
// axis along world -z (toward a camera at the origin), its back vertex
// `vertex_mm` in front of `apex`, tilted and shifted as glasses sit.
SpectacleLens minus_lens(const Point3& apex, double vertex_mm = 12, double tilt_deg = 8,
                         const Vector3& shift = {1.5, -2, 0}) {
  SpectacleLens lens;
  lens.name = "right";
  lens.refractive_index = 1.498;
  lens.center_thickness_mm = 2;
  lens.front_radius_mm = 1000 * (lens.refractive_index - 1) / 4;
  lens.back_radius_mm = back_radius_for_power_mm(-3, lens.front_radius_mm, 2, lens.refractive_index);
  lens.outline_semi_axes_mm = {25, 20};
  // Lens +z = world -z, lens +y = world -y (up), then a pantoscopic tilt
  // about the lens's x (its lower edge toward the face).
  const Rotation facing = Rotation::from_columns(UnitVector3::unit_x(), -UnitVector3::unit_y(), -UnitVector3::unit_z());
  const Rotation tilt = Rotation::from_axis_angle(UnitVector3::unit_x(), tilt_deg * kDeg);
  const Point3 front_vertex = apex + Vector3{0, 0, -vertex_mm - lens.center_thickness_mm} + shift;
  lens.world_from_lens = Pose(facing * tilt, front_vertex.from_origin());
  check_spectacle_lens(lens);
  return lens;
}

Camera camera_at(const Point3& centre, const Point3& look_at) {
  return Camera("cam", Intrinsics::from_focal_length(16, 0.005, 1600, 1200), {},
                camera_looking_at(centre, look_at, {0, -1, 0}), Sensor{});
}

// A keratometric eye (one spherical surface) `distance` from a camera at
// the origin, turned by `yaw`, lit by three LEDs, behind a minus lens.
Scene glasses_scene(double distance_mm, double yaw_deg, bool with_lens = true) {
  Scene scene;
  scene.cameras.push_back(camera_at({0, 0, 0}, {0, 0, distance_mm}));
  scene.eyes.push_back(Eye::with_cornea_center(keratometric_eye(), {0, 0, distance_mm},
                                               optical_axis_from_yaw_pitch(yaw_deg * kDeg, 5 * kDeg)));
  for (const Point3& p : {Point3{-100, 0, 0}, Point3{100, 0, 0}, Point3{0, 60, 0}}) {
    Illuminator led;
    led.position = p;
    scene.illuminators.push_back(led);
  }
  // The lens sits on the head, which faces the camera whatever the gaze.
  const Point3 apex_in_primary = Point3{0, 0, distance_mm - keratometric_eye().anterior_cornea.radius_mm};
  if (with_lens) scene.spectacle_lenses.push_back(minus_lens(apex_in_primary));
  return scene;
}

// ------------------------------------------------------- powers

TEST(SpectacleLens, BackVertexPowerIsWhereAParaxialRayCrossesTheAxis) {
  // In the lens frame (identity pose): a ray from the far side of the
  // front, parallel to the axis, 1e-4 mm off it.
  for (const double power : {-6.0, -3.0, -0.5, 0.5, 2.0}) {
    SpectacleLens lens;
    lens.refractive_index = 1.498;
    lens.center_thickness_mm = power > 0 ? 3.5 : 2;
    const double base_d = power > 0 ? power / 2 + 6 : power / 4 + 6;  // Vogel's rule
    lens.front_radius_mm = 1000 * (lens.refractive_index - 1) / base_d;
    lens.back_radius_mm = back_radius_for_power_mm(power, lens.front_radius_mm, lens.center_thickness_mm,
                                                   lens.refractive_index);
    check_spectacle_lens(lens);
    const std::optional<Ray3> out = through(lens, {{1e-4, 0, 1000}, {0, 0, -1}}, true);
    ASSERT_TRUE(out);
    // Where the exit ray (or its backward extension) meets x = 0.
    const double s = -out->origin.x / out->direction.x;
    const double z_focus = out->origin.z + s * out->direction.z;
    const double back_focal_mm = -lens.center_thickness_mm - z_focus;  // > 0 behind the back vertex
    EXPECT_NEAR(1000 / back_focal_mm, power, 1e-6) << power;
    EXPECT_NEAR(back_vertex_power_d(lens), power, 1e-12) << power;
  }
  // By hand: F1 = 4 D, F1 / (1 - 0.002 * 4 / 1.498) = 4.02148 D, so
  // F2 = -7.02148 D and R2 = 0.498 / 7.02148 m = 70.92 mm.
  EXPECT_NEAR(back_radius_for_power_mm(-3, 124.5, 2, 1.498), 70.925, 0.005);
}

TEST(SpectacleLens, RejectsABackSurfaceBulgingTowardTheEyeAndAnEdgeThinnerThan0_1mm) {
  // +8 D on a 4 D base needs a convex back surface.
  EXPECT_THROW(back_radius_for_power_mm(8, 124.5, 2, 1.498), std::invalid_argument);
  SpectacleLens plus;
  plus.front_radius_mm = 62.25;  // 8 D
  plus.back_radius_mm = back_radius_for_power_mm(2, plus.front_radius_mm, 3.5, plus.refractive_index);
  plus.center_thickness_mm = 3.5;
  plus.outline_semi_axes_mm = {25, 20};
  EXPECT_NO_THROW(check_spectacle_lens(plus));
  // By hand: F2 = 2 - 8 / (1 - 0.0035 * 8 / 1.498) = -6.1524 D, R2 =
  // 80.94 mm; the sags at 25 mm are 5.241 and 3.958 mm, so the edge is
  // 3.5 - 1.283 = 2.217 mm thick. At a 1.4 mm centre R2 = 82.17 mm, its
  // sag 3.896 mm, the edge 0.055 mm.
  EXPECT_NEAR(lens_thickness_mm(plus, 25, 0), 2.217, 0.001);
  plus.center_thickness_mm = 1.4;
  plus.back_radius_mm = back_radius_for_power_mm(2, plus.front_radius_mm, 1.4, plus.refractive_index);
  EXPECT_THROW(check_spectacle_lens(plus), std::invalid_argument);
  SpectacleLens flat_back;
  flat_back.back_radius_mm = -500;
  EXPECT_THROW(check_spectacle_lens(flat_back), std::invalid_argument);
}

// ------------------------------------------------------- passages

TEST(LensPassage, LeavesInTheDirectionThatAShotRayFollowsToTheOtherEnd) {
  const Point3 apex{0, 0, 592.2};
  const SpectacleLens lens = minus_lens(apex);
  const Point3 far_ends[] = {{0, 0, 0}, {-100, 0, 0}, {100, 40, -30}, {0, 300, 200}};
  int checked = 0;
  for (const Point3& far : far_ends) {
    for (int i = 0; i < 25; ++i) {
      // Points about the cornea, up to 9 mm off the axis.
      const Point3 near = apex + Vector3{9 * std::cos(i * 1.3) * (i % 5) / 4, 9 * std::sin(i * 1.3) * (i % 5) / 4,
                                         (i % 3) * 2.0};
      for (const bool from_near : {true, false}) {
        const Point3& from = from_near ? near : far;
        const Point3& to = from_near ? far : near;
        const LensPassage p = solve_lens_passage(lens, from, to);
        ASSERT_EQ(p.status, PathStatus::ok) << i;
        const std::optional<Ray3> shot = through(lens, {from, p.leaving.vector()}, !from_near);
        ASSERT_TRUE(shot);
        EXPECT_LT(miss(*shot, to), 1e-9 * distance(from, to)) << i;
        EXPECT_LT(distance(shot->origin, p.second), 1e-9) << i;
        EXPECT_LT((shot->direction - p.arriving.vector()).norm(), 1e-12) << i;
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 200);
}

TEST(LensPassage, IsNoSolutionThroughTheEdgeAndInvalidWithBothEndsOnOneSide) {
  const Point3 apex{0, 0, 592.2};
  const SpectacleLens lens = minus_lens(apex, 12, 0, {});
  // 30 mm beside the axis, beyond the 25 mm outline, seen from straight on.
  EXPECT_EQ(solve_lens_passage(lens, apex + Vector3{30, 0, 0}, {30, 0, 0}).status, PathStatus::no_solution);
  // Behind the lens but aimed at the camera past its edge at a grazing slant.
  EXPECT_EQ(solve_lens_passage(lens, apex + Vector3{20, 0, 0}, {2000, 0, 0}).status, PathStatus::no_solution);
  EXPECT_EQ(solve_lens_passage(lens, {0, 0, 0}, {10, 0, 0}).status, PathStatus::invalid_input);
  EXPECT_EQ(solve_lens_passage(lens, apex, apex + Vector3{1, 0, 0}).status, PathStatus::invalid_input);
  EXPECT_EQ(solve_lens_passage(lens, apex, {NAN, 0, 0}).status, PathStatus::invalid_input);
}

// ------------------------------------------------------- labels

TEST(TruthThroughGlasses, AGlintIsWhereACameraRayShotThroughTheLensReachesItsLight) {
  int checked = 0;
  for (const double distance_mm : {250.0, 600.0, 1200.0}) {
    for (const double yaw : {-25.0, 0.0, 20.0}) {
      const Scene scene = glasses_scene(distance_mm, yaw);
      const SceneTruth truth = compute_truth(scene);
      const SceneTruth bare = compute_truth(glasses_scene(distance_mm, yaw, false));
      const Camera& camera = scene.cameras[0];
      const Eye& eye = scene.eyes[0];
      const SpectacleLens& lens = scene.spectacle_lenses[0];
      for (const GlintTruth& g : truth.views[0].glints) {
        if (g.status != PathStatus::ok) continue;
        const Point3& light = scene.illuminators[g.illuminator].position;
        const std::optional<Ray3> in = through(lens, {camera.center(), camera.back_project(g.pixel).vector()}, true);
        ASSERT_TRUE(in);
        const std::optional<Ray3> mirrored = reflect_at(*in, eye.cornea_center(), eye.model().anterior_cornea.radius_mm);
        ASSERT_TRUE(mirrored);
        EXPECT_LT(distance(mirrored->origin, g.reflection.point), 1e-7);
        const std::optional<Ray3> out = through(lens, *mirrored, false);
        ASSERT_TRUE(out);
        EXPECT_LT(miss(*out, light), 1e-6) << distance_mm << " " << yaw << " " << g.illuminator;
        // The lens matters: the same glint without it lies pixels away.
        const GlintTruth& plain = bare.views[0].glints[g.illuminator];
        if (plain.status == PathStatus::ok) {
          EXPECT_GT(std::hypot(g.pixel.u - plain.pixel.u, g.pixel.v - plain.pixel.v), 0.1);
        }
        ++checked;
      }
    }
  }
  EXPECT_GE(checked, 20);
}

TEST(TruthThroughGlasses, APupilPointIsWhereACameraRayShotThroughLensAndCorneaMeetsIt) {
  int checked = 0;
  for (const double distance_mm : {250.0, 600.0}) {
    for (const double yaw : {-25.0, 0.0, 20.0}) {
      const Scene scene = glasses_scene(distance_mm, yaw);
      const SceneTruth truth = compute_truth(scene);
      const Camera& camera = scene.cameras[0];
      const Eye& eye = scene.eyes[0];
      const auto shot_miss = [&](const Pixel& pixel, const Point3& target) {
        const std::optional<Ray3> in = through(scene.spectacle_lenses[0], {camera.center(), camera.back_project(pixel).vector()}, true);
        if (!in) return 1e9;
        const std::optional<Ray3> inside = refract_at(*in, eye.cornea_center(), eye.model().anterior_cornea.radius_mm, 1,
                                                      eye.model().aqueous_index);
        return inside ? miss(*inside, target) : 1e9;
      };
      for (const PupilBorderPointTruth& b : truth.views[0].pupil.border) {
        if (b.status != PathStatus::ok) continue;
        EXPECT_LT(shot_miss(b.pixel, b.border_point), 1e-7);
        ++checked;
      }
      ASSERT_EQ(truth.views[0].pupil.refracted_center_status, PathStatus::ok);
      EXPECT_LT(shot_miss(truth.views[0].pupil.refracted_center, eye.pupil_center()), 1e-7);
    }
  }
  EXPECT_EQ(checked, 6 * 36);
}

TEST(TruthThroughGlasses, GhostsAreWhereACameraRayMirroredByALensSurfaceReachesTheLight) {
  int front = 0, back = 0;
  for (const double distance_mm : {250.0, 600.0, 1200.0}) {
    const Scene scene = glasses_scene(distance_mm, 0);
    const SceneTruth truth = compute_truth(scene);
    const Camera& camera = scene.cameras[0];
    const SpectacleLens& lens = scene.spectacle_lenses[0];
    for (const DistractorTruth& d : truth.views[0].distractors) {
      ASSERT_EQ(d.spectacle_lens, 0);
      if (d.status != PathStatus::ok) continue;
      const Point3& light = scene.illuminators[d.illuminator].position;
      const Ray3 ray{camera.center(), camera.back_project(d.pixel).vector()};
      std::optional<Ray3> out;
      if (d.kind == DistractorKind::spectacle_lens_front) {
        out = reflect_at(ray, front_centre(lens), lens.front_radius_mm);
        ++front;
      } else {
        ASSERT_EQ(d.kind, DistractorKind::spectacle_lens_back);
        const double n = lens.refractive_index;
        const auto in = refract_at(ray, front_centre(lens), lens.front_radius_mm, 1, n);
        ASSERT_TRUE(in);
        const auto mirrored = reflect_at(*in, back_centre(lens), lens.back_radius_mm);
        ASSERT_TRUE(mirrored);
        EXPECT_LT(distance(mirrored->origin, d.reflection.point), 1e-7);
        out = refract_at(*mirrored, front_centre(lens), lens.front_radius_mm, n, 1);
        ++back;
      }
      ASSERT_TRUE(out);
      EXPECT_LT(miss(*out, light), 1e-6) << distance_mm << " " << to_string(d.kind) << " " << d.illuminator;
    }
  }
  EXPECT_GE(front, 6);
  EXPECT_GE(back, 6);
}

TEST(TruthThroughGlasses, ALensThatNoPathCrossesChangesNoGlintOrPupilLabel) {
  Scene scene = glasses_scene(600, 0, false);
  const SceneTruth bare = compute_truth(scene);
  // The lens 70 mm to the side: in front of nothing the camera sees of the eye.
  scene.spectacle_lenses.push_back(minus_lens({70, 0, 592.2}, 12, 0, {}));
  const SceneTruth truth = compute_truth(scene);
  for (std::size_t l = 0; l < scene.illuminators.size(); ++l) {
    EXPECT_EQ(truth.views[0].glints[l].pixel.u, bare.views[0].glints[l].pixel.u);
    EXPECT_EQ(truth.views[0].glints[l].pixel.v, bare.views[0].glints[l].pixel.v);
  }
  for (std::size_t k = 0; k < bare.views[0].pupil.border.size(); ++k) {
    EXPECT_EQ(truth.views[0].pupil.border[k].pixel.u, bare.views[0].pupil.border[k].pixel.u);
  }
  // Its ghosts are all the labels gain.
  ASSERT_FALSE(truth.views[0].distractors.empty());
  for (const DistractorTruth& d : truth.views[0].distractors) EXPECT_EQ(d.spectacle_lens, 0);
}

// ------------------------------------------------------- light through a lens

TEST(LightThroughLens, IsTheParaxialImageOfALightOnTheAxisWithItsVergenceFocusing) {
  // An untilted lens, the light 600 mm in front of its front vertex and the
  // point 12 mm behind its back vertex, both on the axis. Vergences (D):
  // V1 = -1/0.6 at the front, V1' = V1 + F1, V2 = V1' / (1 - t/n V1') at
  // the back, V2' = V2 + F2; the image lies 1/|V2'| in front of the back
  // vertex (V2' < 0: diverging). A ray leaving the light at angle u is at
  // height 0.6 u at the front, (1 - t/n V1') times that at the back and
  // (1 - d V2') times that d behind it, so the solid angle per area at the
  // point is 1 / (0.6 (1 - t/n V1') (1 - d V2'))^2 (in m).
  for (const double power : {-6.0, -3.0, 2.0}) {
    const Point3 apex{0, 0, 592.2};
    SpectacleLens lens = minus_lens(apex, 12, 0, {});
    lens.center_thickness_mm = power > 0 ? 3.5 : 2;
    lens.back_radius_mm = back_radius_for_power_mm(power, lens.front_radius_mm, lens.center_thickness_mm,
                                                   lens.refractive_index);
    const double t = lens.center_thickness_mm / 1000, n = lens.refractive_index, d = 0.012;
    const Point3 front_vertex = lens.world_from_lens * Point3{0, 0, 0};
    const Point3 light = front_vertex + Vector3{0, 0, -600};
    const Point3 near = front_vertex + Vector3{0, 0, 1000 * (t + d)};
    const double f1 = 1000 * (n - 1) / lens.front_radius_mm, f2 = 1000 * (1 - n) / lens.back_radius_mm;
    const double v1 = -1 / 0.6 + f1, v2 = v1 / (1 - t / n * v1) + f2;
    const double image_from_near_mm = 1000 * (d - 1 / v2);  // in front (> 0) when v2 < 0
    const double per_area = 1 / std::pow(0.6 * (1 - t / n * v1) * (1 - d * v2), 2) / 1e6;  // sr / mm^2
    const LightThroughLens l = light_through_lens(lens, light, near);
    ASSERT_EQ(l.status, PathStatus::ok);
    // The plus lens's light converges: a negative vergence.
    EXPECT_NEAR(l.vergence_per_mm * image_from_near_mm, 1, 1e-5) << power;
    EXPECT_NEAR(l.solid_angle_per_area / per_area, 1, 1e-5) << power;
    EXPECT_LT(angle_between(l.passage.leaving, light - near), 1e-12);
  }
}

}  // namespace
}  // namespace purkinje
