// Distractors: the highlights a wet sclera mirrors (compute_truth with an
// eye's tear film), the cornea that can hide them (Eye::cap_crosses,
// against a brute-force march along the segment), and their labels.

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include <nlohmann/json.hpp>

#include "purkinje/models/labels.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/models/truth.h"

namespace purkinje {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;

// Whether the segment crosses the cap by marching: a sign change of the
// cap's implicit function between two samples whose depths both lie on
// the cap (0 <= w <= limbus depth).
bool marched_cap_crossing(const Eye& eye, const Point3& from, const Point3& to, int samples) {
  const EyeModel& m = eye.model();
  const double R = m.anterior_cornea.radius_mm, k = 1 + m.anterior_cornea.asphericity, d_L = m.limbus_depth_mm();
  const Point3 a = eye.eye_from_world() * from, b = eye.eye_from_world() * to;
  double previous = 0;
  bool previous_on_cap = false;
  for (int i = 0; i <= samples; ++i) {
    const double t = static_cast<double>(i) / samples;
    const Point3 p = a + (b - a) * t;
    const double w = R - p.z;
    const double f = p.x * p.x + p.y * p.y + k * w * w - 2 * R * w;
    const bool on_cap = w >= 0 && w <= d_L;
    if (i > 0 && on_cap && previous_on_cap && (f < 0) != (previous < 0)) return true;
    previous = f;
    previous_on_cap = on_cap;
  }
  return false;
}

TEST(EyeCap, CrossesWhereAMarchAlongTheSegmentFindsTheCap) {
  for (const EyeModel& model : {keratometric_eye(), navarro_eye()}) {
    const Eye eye = Eye::with_cornea_center(model, {0, 0, 600}, UnitVector3::normalize({0.2, -0.1, -1}));
    // Through the apex, and 10 mm beside it (beyond the limbus).
    EXPECT_TRUE(eye.cap_crosses(eye.corneal_apex() + Vector3{0, 0, -50}, eye.cornea_center()));
    EXPECT_FALSE(eye.cap_crosses(eye.corneal_apex() + Vector3{10, 0, -50}, eye.corneal_apex() + Vector3{10, 0, 50}));
    // Random segments about the cornea, ends within 15 mm of its centre.
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> offset(-15, 15);
    int crossing = 0;
    for (int i = 0; i < 400; ++i) {
      const Point3 from = eye.cornea_center() + Vector3{offset(rng), offset(rng), offset(rng)};
      const Point3 to = eye.cornea_center() + Vector3{offset(rng), offset(rng), offset(rng)};
      const bool expected = marched_cap_crossing(eye, from, to, 20000);
      EXPECT_EQ(eye.cap_crosses(from, to), expected) << i;
      crossing += expected;
    }
    EXPECT_GT(crossing, 40);
    EXPECT_LT(crossing, 360);
  }
}

Camera camera_at(const Point3& centre, const Point3& look_at) {
  return Camera("cam", Intrinsics::from_focal_length(16, 0.005, 1600, 1200), {},
                camera_looking_at(centre, look_at, {0, -1, 0}), Sensor{});
}

// An eye at (0, 0, 600) looking down -z, wet; a point of its sclera's
// sphere `angle` from the axis toward +x, and a light and camera mirrored
// about its normal at `incidence`, the camera on the apex's side.
struct WetScene {
  Scene scene;
  Point3 point;
};
WetScene mirrored_about_sclera(double angle, double incidence, bool wet = true) {
  Eye eye = Eye::with_cornea_center(keratometric_eye(), {0, 0, 600}, UnitVector3::normalize({0, 0, -1}));
  EyeAppearance look;
  if (wet) look.tear_film = TearFilm{};
  eye.set_appearance(look);
  const Vector3 n{std::sin(angle), 0, -std::cos(angle)};          // world: eye +z is world -z
  const Vector3 away{std::cos(angle), 0, std::sin(angle)};         // the meridian's tangent, away from the apex
  const Point3 point = eye.rotation_center() + n * 12;
  const Point3 light = point + (n * std::cos(incidence) + away * std::sin(incidence)) * 500;
  const Point3 camera = point + (n * std::cos(incidence) - away * std::sin(incidence)) * 600;
  Scene scene;
  scene.cameras.push_back(camera_at(camera, point));
  Illuminator led;
  led.name = "led";
  led.position = light;
  scene.illuminators.push_back(led);
  scene.eyes.push_back(eye);
  return {scene, point};
}

TEST(Distractors, AWetScleraMirrorsALightWhereTheLawOfReflectionHoldsOnIt) {
  const WetScene wet = mirrored_about_sclera(45 * kDeg, 30 * kDeg);
  const SceneTruth truth = compute_truth(wet.scene);
  ASSERT_EQ(truth.views[0].distractors.size(), 1u);
  const DistractorTruth& d = truth.views[0].distractors[0];
  EXPECT_EQ(d.kind, DistractorKind::sclera);
  EXPECT_EQ(d.status, PathStatus::ok) << to_string(d.status);
  EXPECT_LT(distance(d.reflection.point, wet.point), 1e-9);
  EXPECT_NEAR(d.reflection.incidence_rad, 30 * kDeg, 1e-12);
  EXPECT_LT(reflection_residual_rad(d.reflection), 1e-12);
  // Aimed at the point: the principal point ((1600 - 1) / 2, (1200 - 1) / 2).
  EXPECT_NEAR(d.pixel.u, 799.5, 1e-6);
  EXPECT_NEAR(d.pixel.v, 599.5, 1e-6);
  // The corneal glint of the same light is another point, near the limbus.
  EXPECT_GT(distance(truth.views[0].glints[0].reflection.point, d.reflection.point), 3);

  // A dry sclera mirrors nothing.
  EXPECT_TRUE(compute_truth(mirrored_about_sclera(45 * kDeg, 30 * kDeg, false).scene).views[0].distractors.empty());
  // Where the sphere lies under the cornea (20 deg < the seam's 29.4), no highlight.
  EXPECT_TRUE(compute_truth(mirrored_about_sclera(20 * kDeg, 30 * kDeg).scene).views[0].distractors.empty());
}

TEST(Distractors, TheCorneaHidesAHighlightByTheLimbusSeenAcrossIt) {
  // 0.1 rad behind the seam (29.4 deg from the axis), seen from the apex's
  // side. At 85 deg incidence the line of sight passes 7.60 mm from the
  // cornea's centre, 2.6 mm in front of the point: through the cap
  // (R = 7.8): hidden. At 60 deg it passes 8.00 mm from it, behind the
  // point: clear of the cornea.
  const double point_angle = std::asin(5.9 / 12) + 0.1;
  const SceneTruth grazing = compute_truth(mirrored_about_sclera(point_angle, 85 * kDeg).scene);
  ASSERT_EQ(grazing.views[0].distractors.size(), 1u);
  EXPECT_EQ(grazing.views[0].distractors[0].status, PathStatus::occluded);
  EXPECT_EQ(grazing.views[0].distractors[0].occluder, Occluder::eye);
  const SceneTruth clear = compute_truth(mirrored_about_sclera(point_angle, 60 * kDeg).scene);
  ASSERT_EQ(clear.views[0].distractors.size(), 1u);
  EXPECT_EQ(clear.views[0].distractors[0].status, PathStatus::ok);
  // Other occluders come from TruthOptions, as for glints.
  TruthOptions lid;
  lid.occluded = [](const Point3&, const Point3&) { return Occluder::skin; };
  const SceneTruth hidden = compute_truth(mirrored_about_sclera(point_angle, 60 * kDeg).scene, lid);
  EXPECT_EQ(hidden.views[0].distractors[0].status, PathStatus::occluded);
  EXPECT_EQ(hidden.views[0].distractors[0].occluder, Occluder::skin);
}

TEST(Distractors, LabelsListThemOnlyForAWetEye) {
  const WetScene wet = mirrored_about_sclera(45 * kDeg, 30 * kDeg);
  const SceneTruth truth = compute_truth(wet.scene);
  const nlohmann::json labels = nlohmann::json::parse(truth_to_json(wet.scene, truth));
  const nlohmann::json& d = labels["views"][0]["distractors"];
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0]["kind"], "sclera");
  EXPECT_EQ(d[0]["illuminator_name"], "led");
  EXPECT_EQ(d[0]["status"], "ok");
  EXPECT_NEAR(d[0]["u_px"].get<double>(), 799.5, 1e-6);
  EXPECT_NEAR(d[0]["incidence_deg"].get<double>(), 30, 1e-9);
  EXPECT_EQ(labels["eyes"][0]["appearance"]["tear_film"]["sclera_roughness_deg"], 2.0);
  const std::string csv = truth_to_csv(wet.scene, truth);
  EXPECT_NE(csv.find(",distractor,0,led,ok,"), std::string::npos) << csv;

  const WetScene dry = mirrored_about_sclera(45 * kDeg, 30 * kDeg, false);
  const nlohmann::json dry_labels = nlohmann::json::parse(truth_to_json(dry.scene, compute_truth(dry.scene)));
  EXPECT_FALSE(dry_labels["views"][0].contains("distractors"));
  EXPECT_FALSE(dry_labels["eyes"][0]["appearance"].contains("tear_film"));
  EXPECT_EQ(truth_to_csv(dry.scene, compute_truth(dry.scene)).find("distractor"), std::string::npos);
}

}  // namespace
}  // namespace purkinje
