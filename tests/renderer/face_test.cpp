// The periocular face (Face in appearance.h, face_mesh.h) as the ray
// tracer meets it: lids a margin thickness above the globe, an opening
// between the margins where the Eyelids put them (turned with the gaze by
// the closed form of appearance.h), and no crack anywhere.
//
// The head frame is the world frame here (head forward +z, up +y) and the
// centre of rotation the origin, so that rays along -z at (x, y) are the
// head frame's lines of sight.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "purkinje/models/eye.h"
#include "purkinje/models/scene.h"
#include "purkinje/renderer/ray_tracer.h"

namespace purkinje::renderer {
namespace {

constexpr double kDegree = std::numbers::pi / 180;

Scene face_scene(double pitch_deg = 0, double yaw_deg = 0, double opening = 1, double margin_thickness_mm = 1.8) {
  EyeModel model = *eye_model_preset("keratometric");
  // Up is +y, so a positive pitch looks up.
  const double p = pitch_deg * kDegree, w = yaw_deg * kDegree;
  const UnitVector3 axis = UnitVector3::normalize({std::sin(w) * std::cos(p), std::sin(p), std::cos(w) * std::cos(p)});
  Eye eye = Eye::with_rotation_center(model, Point3{0, 0, 0}, axis);
  EyeAppearance look;
  look.head_forward = UnitVector3::unit_z();
  look.head_up = UnitVector3::unit_y();
  look.eyelids = Eyelids{};
  look.eyelids->opening = opening;
  look.face = Face{};
  look.face->margin_thickness_mm = margin_thickness_mm;
  eye.set_appearance(look);
  Scene scene;
  scene.eyes = {eye};
  return scene;
}

Hit look_down_z(const RayTracer& tracer, double x, double y) {
  Ray ray;
  ray.origin = {x, y, 100};
  ray.direction = -UnitVector3::unit_z();
  return tracer.intersect(ray);
}

bool sees_eye(const Hit& hit) {
  return hit.surface == Surface::cornea_anterior || hit.surface == Surface::sclera;
}

// Where, going up along x, the line of sight passes from the eye to the
// lid (bisection between a height that sees the eye and one that does not).
double margin_seen_at(const RayTracer& tracer, double x, double eye_y, double lid_y) {
  EXPECT_TRUE(sees_eye(look_down_z(tracer, x, eye_y)));
  EXPECT_EQ(look_down_z(tracer, x, lid_y).surface, Surface::skin);
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (eye_y + lid_y);
    (sees_eye(look_down_z(tracer, x, mid)) ? eye_y : lid_y) = mid;
  }
  return 0.5 * (eye_y + lid_y);
}

TEST(Face, TheUpperLidLiesOnTheGlobeAMarginThicknessAbove) {
  // 3 mm thick, so that the lid stands more than the 2 mm blend above the
  // face's orbit level at these points (face_mesh.cpp) and the crease
  // (7 mm above the margin, cut at 4 widths) is far.
  constexpr double t = 3.0;
  const Scene scene = face_scene(0, 0, 1, t);
  const RayTracer tracer(scene);
  const double R_s = scene.eyes[0].model().sclera_radius_mm;
  for (const auto& [x, y] : {std::pair{0.0, 6.5}, std::pair{0.0, 7.0}, std::pair{-4.0, 7.0}, std::pair{4.0, 7.0}}) {
    const Hit hit = look_down_z(tracer, x, y);
    ASSERT_EQ(hit.surface, Surface::skin) << x << ", " << y;
    EXPECT_TRUE(hit.front_face);
    // The sclera's sphere about the centre of rotation, plus t; the mesh's
    // flat 0.25 x 0.25 mm triangles fall short of that sphere of 15 mm by at
    // most their circumradius squared over its diameter, 0.18^2 / 30 =
    // 1.1e-3 mm.
    EXPECT_NEAR(hit.point.z, std::sqrt(R_s * R_s - x * x - y * y) + t, 3e-3) << x << ", " << y;
    EXPECT_GT(hit.normal.z(), 0.5);
  }
}

TEST(Face, TheOpeningLiesBetweenTheMarginsAndTurnsWithTheGaze) {
  {
    const RayTracer tracer(face_scene());
    // Primary position: the Eyelids' margins at the middle, 4.5 and -5.5 mm
    // (the margin's wall rises 0.03 mm inside the globe, so the eye shows
    // about 1e-3 mm past its foot).
    EXPECT_NEAR(margin_seen_at(tracer, 0, 3.0, 6.0), 4.5, 2e-3);
    EXPECT_NEAR(margin_seen_at(tracer, 0, -4.0, -7.0), -5.5, 2e-3);
  }
  {
    // 20 deg down: the upper margin turns by 20 deg (gain 1), the lower by
    // 12 deg (gain 0.6), each on the sphere of radius 12 + 1.8 mm about the
    // centre of rotation: y' = m cos a + sqrt(13.8^2 - m^2) sin a.
    const RayTracer tracer(face_scene(-20));
    const double r = 13.8;
    const double upper = 4.5 * std::cos(20 * kDegree) - std::sqrt(r * r - 4.5 * 4.5) * std::sin(20 * kDegree);
    const double lower = -5.5 * std::cos(12 * kDegree) - std::sqrt(r * r - 5.5 * 5.5) * std::sin(12 * kDegree);
    EXPECT_NEAR(upper, -0.23327, 1e-4);  // the hand calculation
    EXPECT_NEAR(lower, -8.01127, 1e-4);
    EXPECT_NEAR(margin_seen_at(tracer, 0, -4.0, 2.0), upper, 5e-3);
    EXPECT_NEAR(margin_seen_at(tracer, 0, -4.0, -10.0), lower, 5e-3);
  }
}

TEST(Face, ClosedLidsHideTheEye) {
  const RayTracer tracer(face_scene(0, 0, 0));
  // Along the closing line (y = -1 at the middle, raised by the canthal
  // tilt toward the lateral canthus at x = -11 for a right eye).
  for (double x = -10.5; x <= 14.5; x += 0.25) {
    const double y = -1.0 - std::tan(4 * kDegree) * x;
    for (double dy : {-0.3, -0.01, 0.0, 0.01, 0.3}) {
      EXPECT_EQ(look_down_z(tracer, x, y + dy).surface, Surface::skin) << x << ", " << y + dy;
    }
  }
}

// Watertight: every line of sight across the face meets it, the eye or
// the socket's floor, in any gaze, open or closed; none reaches the
// background through a crack between lid and eye, at the canthi or where
// the lids join.
TEST(Face, NoLineOfSightThroughTheFaceReachesTheBackground) {
  struct Case {
    double pitch, yaw, opening;
  };
  for (const Case c : {Case{0, 0, 1}, Case{35, 0, 1}, Case{-35, 0, 1}, Case{0, 35, 1}, Case{0, -35, 1},
                       Case{20, -30, 0.5}, Case{0, 0, 0}}) {
    const RayTracer tracer(face_scene(c.pitch, c.yaw, c.opening));
    int misses = 0;
    // Finely about the opening, coarsely out to the mesh's ends.
    for (double x = -18; x <= 18; x += 0.1) {
      for (double y = -14; y <= 14; y += 0.1) misses += look_down_z(tracer, x, y).surface == Surface::none;
    }
    for (double x = -55; x <= 90; x += 1.0) {
      for (double y = -45; y <= 55; y += 1.0) misses += look_down_z(tracer, x, y).surface == Surface::none;
    }
    EXPECT_EQ(misses, 0) << "pitch " << c.pitch << ", yaw " << c.yaw << ", opening " << c.opening;
  }
}

TEST(Face, AFaceAloneGoesOnPastTheMidlineWithTwoFacesEachEndsThere) {
  // One eye: the face is mirrored past the midline (31.5 mm to the nose,
  // +x for a right eye), so the other orbit's place is skin.
  {
    const RayTracer tracer(face_scene());
    EXPECT_EQ(look_down_z(tracer, 63, 0).surface, Surface::skin);
  }
  // Two eyes: each face ends at the midline; together they cover it.
  Scene scene = face_scene();
  Eye left = scene.eyes[0];
  EyeAppearance look = left.appearance();
  look.face->side = EyeSide::left;
  left = Eye::with_rotation_center(left.model(), Point3{63, 0, 0}, UnitVector3::unit_z());
  left.set_appearance(look);
  scene.eyes.push_back(left);
  const RayTracer tracer(scene);
  for (double x = 20; x <= 43; x += 0.05) {
    const Hit hit = look_down_z(tracer, x, -10);
    ASSERT_EQ(hit.surface, Surface::skin) << x;
    // On the midline itself both faces' edges lie; which one a ray along
    // it meets is Embree's kernel's choice.
    if (std::abs(x - 31.5) > 1e-6) {
      EXPECT_EQ(hit.eye, x < 31.5 ? 0 : 1) << x;
    }
  }
}

}  // namespace
}  // namespace purkinje::renderer
