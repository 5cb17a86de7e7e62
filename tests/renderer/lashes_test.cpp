// Eyelashes (Lashes in appearance.h, lashes.h): the capsules they are made
// of against closed forms, the lashes a margin grows against the rules of
// lashes.h, and the lashes of a face as the ray tracer meets them.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "lashes.h"
#include "purkinje/models/eye.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/models/scene.h"
#include "purkinje/renderer/ray_tracer.h"
#include "purkinje/renderer/render.h"
#include "scene_geometry.h"

namespace purkinje::renderer {
namespace {

constexpr double kDegree = std::numbers::pi / 180;

// One capsule along +z from the origin, 10 mm long, radius 0.5.
PlacedHairs one_capsule() { return PlacedHairs(Surface::lash, 0, {{Point3{0, 0, 0}, Point3{0, 0, 10}, 0.5}}); }

Lane lane_from(const Point3& origin, const Vector3& direction, double t_lo = 0, double t_hi = INFINITY) {
  Lane lane;
  lane.origin = origin;
  lane.direction = direction;
  lane.t_lo = t_lo;
  lane.t_hi = t_hi;
  return lane;
}

TEST(Lashes, ACapsuleIsMetWhereItsClosedFormSays) {
  const PlacedHairs capsule = one_capsule();
  double t = 0;
  // Across the side, 0.3 mm off the axis: it enters at x = sqrt(0.5^2 -
  // 0.3^2) = 0.4, where the normal is (0.8, 0.6, 0).
  ASSERT_TRUE(capsule.hit(lane_from({10, 0.3, 5}, {-1, 0, 0}), 0, t));
  EXPECT_NEAR(t, 9.6, 1e-13);
  const UnitVector3 n = capsule.normal(0, Point3{0.4, 0.3, 5});
  EXPECT_NEAR(n.x(), 0.8, 1e-15);
  EXPECT_NEAR(n.y(), 0.6, 1e-15);
  EXPECT_NEAR(n.z(), 0.0, 1e-15);
  // The same from a metre away: solved from the closest approach, no
  // cancellation.
  ASSERT_TRUE(capsule.hit(lane_from({1000, 0.3, 5}, {-1, 0, 0}), 0, t));
  EXPECT_NEAR(t, 999.6, 1e-12);
  // Down the axis onto the tip's hemisphere, 0.2 mm off the axis:
  // z = 10 + sqrt(0.25 - 0.04).
  ASSERT_TRUE(capsule.hit(lane_from({0, 0.2, 20}, {0, 0, -1}), 0, t));
  EXPECT_NEAR(t, 10 - std::sqrt(0.21), 1e-13);
  // Up the axis onto the root's hemisphere at z = -0.5.
  ASSERT_TRUE(capsule.hit(lane_from({0, 0, -5}, {0, 0, 1}), 0, t));
  EXPECT_NEAR(t, 4.5, 1e-13);
  // Past the side (0.6 mm off the axis), past the tip's hemisphere.
  EXPECT_FALSE(capsule.hit(lane_from({10, 0.6, 5}, {-1, 0, 0}), 0, t));
  EXPECT_FALSE(capsule.hit(lane_from({10, 0, 10.6}, {-1, 0, 0}), 0, t));
  // Beside the tip, but over its hemisphere: 0.3 mm past the tip, 0.3 off
  // the axis in y; x = sqrt(0.25 - 0.09 - 0.09).
  ASSERT_TRUE(capsule.hit(lane_from({10, 0.3, 10.3}, {-1, 0, 0}), 0, t));
  EXPECT_NEAR(t, 10 - std::sqrt(0.07), 1e-13);
  // From inside (a ray leaving the lash's own surface inward): its far side.
  ASSERT_TRUE(capsule.hit(lane_from({0, 0, 5}, {1, 0, 0}), 0, t));
  EXPECT_NEAR(t, 0.5, 1e-15);
  // Only within (t_lo, t_hi): the near crossing cut off leaves the far one.
  EXPECT_FALSE(capsule.hit(lane_from({10, 0.3, 5}, {-1, 0, 0}, 0, 9.5), 0, t));
  ASSERT_TRUE(capsule.hit(lane_from({10, 0.3, 5}, {-1, 0, 0}, 9.7), 0, t));
  EXPECT_NEAR(t, 10.4, 1e-13);
  // Bounds: the axis's box padded by the radius and a little more.
  const Box b = capsule.bounds(0);
  EXPECT_LT(b.lo.x, -0.5);
  EXPECT_GT(b.lo.x, -0.502);
  EXPECT_LT(b.hi.z, 10.502);
  EXPECT_GT(b.hi.z, 10.5);
}

// A straight margin along +x, 30 mm long, from the lateral canthus (u = -1)
// to the medial (u = 1), normal +z, rising +y (an upper lid's).
MarginEdge straight_edge(double rise_y = 1) {
  MarginEdge edge;
  for (int i = 0; i <= 120; ++i) {
    const double x = -15 + 0.25 * i;
    edge.points.push_back({x, 0, 0});
    edge.normals.push_back(UnitVector3::unit_z());
    edge.rise.push_back({0, rise_y * 0.25, 0.01});
    edge.fissure.push_back(x / 15);
  }
  return edge;
}

TEST(Lashes, AMarginGrowsItsLashesByTheRules) {
  Lashes lashes;
  lashes.upper_per_mm = 4;
  lashes.upper_curl_deg = 60;
  lashes.lower_curl_deg = 90;
  lashes.root_deg = 20;
  const std::vector<HairSegment> upper = build_lashes(lashes, straight_edge(), true, 0);
  // The lashed part: u from -0.97 to 0.6 of 15 mm, 23.55 mm: 94 lashes.
  ASSERT_EQ(upper.size(), 94u * kLashSegments);
  const double r0 = 0.5 * lashes.thickness_mm;
  for (std::size_t k = 0; k < upper.size(); k += kLashSegments) {
    const HairSegment& root = upper[k];
    // Rooted on the lashed part of the edge, sunk by its radius.
    EXPECT_GE(root.a.x, -0.97 * 15 - 1e-9);
    EXPECT_LE(root.a.x, 0.6 * 15 + 1e-9);
    EXPECT_NEAR(root.a.y, 0, 1e-12);
    EXPECT_NEAR(root.a.z, -r0, 1e-12);
    double length = 0;
    for (int j = 0; j < kLashSegments; ++j) {
      const HairSegment& s = upper[k + j];
      if (j > 0) {
        EXPECT_EQ(s.a, upper[k + j - 1].b);  // a chain
      }
      EXPECT_NEAR(s.radius_mm, r0 * (1 - 2.0 / 3 * (j + 0.5) / kLashSegments), 1e-15);
      length += (s.b - s.a).norm();
    }
    // Length: 0.55 to 1 of 9.5 mm, +-12%; chords a little under the arc.
    EXPECT_GT(length, 0.55 * 0.88 * lashes.upper_length_mm * 0.99);
    EXPECT_LT(length, 1.12 * lashes.upper_length_mm);
    // Leaving forward, tilted 20 +- 5 deg toward the opening, bending up by
    // 60 +- 12 deg: the first chord (1/12 of the bend on) below the
    // normal, the last (11/12 on) at least 19 deg above it.
    const Vector3 first = upper[k].b - upper[k].a;
    const Vector3 last = upper[k + kLashSegments - 1].b - upper[k + kLashSegments - 1].a;
    EXPECT_GT(first.z, 0);
    EXPECT_LT(std::atan2(first.y, first.z), 0);
    EXPECT_GT(std::atan2(last.y, last.z), 15 * kDegree);
  }
  // A lower lid's edge rises toward -y: bent by 90 +- 18 deg, its lashes
  // end below their roots (their chords' angles from the normal run from
  // -19 deg to 41 deg at the least).
  const std::vector<HairSegment> lower = build_lashes(lashes, straight_edge(-1), false, 1);
  ASSERT_EQ(lower.size(), static_cast<std::size_t>(std::lround(lashes.lower_per_mm * 23.55)) * kLashSegments);
  for (std::size_t k = 0; k < lower.size(); k += kLashSegments) {
    const HairSegment& tip = lower[k + kLashSegments - 1];
    EXPECT_LT(tip.b.y - lower[k].a.y, 0);
  }
  // Seeded: the same seed and stream, the same lashes; another seed, others.
  const std::vector<HairSegment> again = build_lashes(lashes, straight_edge(), true, 0);
  EXPECT_EQ(again.back().b, upper.back().b);
  lashes.seed = 2;
  EXPECT_NE(build_lashes(lashes, straight_edge(), true, 0).back().b, upper.back().b);
  // None at zero density.
  lashes.upper_per_mm = 0;
  EXPECT_TRUE(build_lashes(lashes, straight_edge(), true, 0).empty());
}

// The face of face_test.cpp's kind (head frame = world, forward +z, up +y)
// with lashes: looking down -z just above the upper margin's middle meets
// lashes, and they move up with the lid when the eye looks up.
Scene lashed_face(double pitch_deg) {
  EyeModel model = *eye_model_preset("keratometric");
  const double p = pitch_deg * kDegree;
  Eye eye = Eye::with_rotation_center(model, Point3{0, 0, 0}, UnitVector3::normalize({0, std::sin(p), std::cos(p)}));
  EyeAppearance look;
  look.head_forward = UnitVector3::unit_z();
  look.head_up = UnitVector3::unit_y();
  look.eyelids = Eyelids{};
  look.face = Face{};
  look.face->lashes = Lashes{};
  eye.set_appearance(look);
  Scene scene;
  scene.eyes = {eye};
  return scene;
}

// The share of lines of sight along -z over a band of heights that meet a lash.
double lash_share(const RayTracer& tracer, double y0, double y1) {
  int lashes = 0, rays = 0;
  for (double x = -6; x <= 6; x += 0.05) {
    for (double y = y0; y <= y1; y += 0.05) {
      Ray ray;
      ray.origin = {x, y, 100};
      ray.direction = -UnitVector3::unit_z();
      const Hit hit = tracer.intersect(ray);
      lashes += hit.surface == Surface::lash;
      ++rays;
      if (hit.surface == Surface::lash) {
        EXPECT_EQ(hit.eye, 0);
        EXPECT_TRUE(hit.front_face);
      }
    }
  }
  return static_cast<double>(lashes) / rays;
}

TEST(Lashes, AFacesLashesStandAboveItsMarginsAndFollowTheLid) {
  const RayTracer level(lashed_face(0));
  // Seen from the front, the upper lashes hang in front of the lid above
  // the margin (4.5 mm) and cover some of it; none stand in front of the
  // pupil's middle.
  EXPECT_GT(lash_share(level, 5, 9), 0.1);
  EXPECT_EQ(lash_share(level, -1, 1), 0);
  // The eye looks up 20 deg: the margin's middle rises by about
  // 14 sin(20 deg) = 4.8 mm, and its lashes with it: more lashes high up.
  const RayTracer up(lashed_face(20));
  EXPECT_GT(lash_share(up, 10, 13), lash_share(level, 10, 13) + 0.05);
}

// The fast mode's queries: seen through the lashes, or the lashes alone.
TEST(Lashes, QueriesCanLookThroughTheLashesOrAtThemAlone) {
  const RayTracer tracer(lashed_face(0));
  ASSERT_TRUE(tracer.has_hair());
  Ray ray;
  ray.direction = -UnitVector3::unit_z();
  Hit hit;
  for (double x = 0; x < 3 && hit.surface != Surface::lash; x += 0.01) {
    ray.origin = {x, 7, 100};
    hit = tracer.intersect(ray);
  }
  ASSERT_EQ(hit.surface, Surface::lash);
  const Hit behind = tracer.intersect_except_hair(ray);
  EXPECT_EQ(behind.surface, Surface::skin);
  EXPECT_GT(behind.t, hit.t);
  // A segment from in front of the lash to just in front of the skin
  // behind it: only the lash blocks it.
  const Point3 front = ray.origin;
  const Point3 near_skin = behind.point + Vector3{0, 0, 0.01};
  EXPECT_TRUE(tracer.occluded(front, near_skin));
  EXPECT_TRUE(tracer.occluded_by_hair(front, near_skin));
  EXPECT_FALSE(tracer.occluded_except_hair(front, near_skin));
  // Through the skin as well: blocked with or without the lashes.
  EXPECT_TRUE(tracer.occluded_except_hair(front, behind.point - Vector3{0, 0, 1}));
  // Without lashes nothing is a lash.
  Scene bare = lashed_face(0);
  EyeAppearance look = bare.eyes[0].appearance();
  look.face->lashes.reset();
  bare.eyes[0].set_appearance(look);
  const RayTracer plain(bare);
  EXPECT_FALSE(plain.has_hair());
  EXPECT_FALSE(plain.occluded_by_hair(front, near_skin));
  EXPECT_EQ(plain.intersect(ray).surface, Surface::skin);
}

// A light's map of the hairs' shadows answers as the hairs' own tree does,
// at every point of a box round the lids (some of them in the lashes'
// shadows, most not), for lights before the face near and far and one
// behind it; a light among the lashes has no map (no plane shows them all
// from there) and asks the tree.
TEST(Lashes, ALightsMapOfTheHairsShadowsAnswersAsTheirTreeDoes) {
  Scene scene = lashed_face(0);
  EyeAppearance look = scene.eyes[0].appearance();
  look.face->brows = Brows{};
  scene.eyes[0].set_appearance(look);
  const RayTracer tracer(scene);
  for (const Point3 light : {Point3{10, -20, 40}, Point3{-30, 40, 600}, Point3{0, 0, -100}, Point3{0, 7, 13}}) {
    SCOPED_TRACE(testing::Message() << "light (" << light.x << ", " << light.y << ", " << light.z << ")");
    const HairShadows map = tracer.hair_shadows(light);
    EXPECT_EQ(map.mapped(), light.z != 13);
    int shaded = 0, points = 0, disagree = 0;
    for (double x = -16; x <= 16; x += 0.37) {
      for (double y = -8; y <= 30; y += 0.29) {
        for (double z = 0; z <= 22; z += 1.3) {
          const Point3 p{x, y, z};
          const bool by_tree = tracer.occluded_by_hair(p, light);
          disagree += map.occluded(p) != by_tree;
          shaded += by_tree;
          ++points;
        }
      }
    }
    EXPECT_EQ(disagree, 0) << "of " << points;
    EXPECT_GT(shaded, 200) << "of " << points;  // a test that could fail
  }
  EXPECT_THROW(tracer.hair_shadows(Point3{NAN, 0, 0}), std::invalid_argument);
  EXPECT_THROW(tracer.hair_shadows(Point3{0, 0, 100}).occluded(Point3{0, INFINITY, 0}), std::invalid_argument);
  // Without hairs nothing shades.
  const RayTracer bare{Scene{}};
  EXPECT_FALSE(bare.hair_shadows(Point3{0, 0, 100}).mapped());
  EXPECT_FALSE(bare.hair_shadows(Point3{0, 0, 100}).occluded(Point3{0, 0, 0}));
}

// The fast mode's visibility cache interpolates shadows between nodes
// that look through the lashes; the lashes' own thin shadows are traced
// per sample. On the headset's upper lid, under its lashes' shadows, the
// fast mode's skin agrees with the reference's on average (measured:
// -0.4%; +7.3% with the lashes' shadows left to the cache).
TEST(Lashes, TheFastModeCastsTheLashesShadowsAsTheReferenceDoes) {
  Scene scene = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/headset.json");
  EyeAppearance look = scene.eyes[0].appearance();
  look.face = Face{};
  look.face->lashes = Lashes{};
  scene.eyes[0].set_appearance(look);
  RenderOptions options;
  options.noise = false;
  options.edge_samples_per_pixel = 0;
  options.region = PixelRegion{140, 90, 260, 150};
  options.samples_per_pixel = 16;
  const RenderResult fast = render(scene, 0, options);
  options.mode = RenderMode::reference;
  options.samples_per_pixel = 64;
  options.seed = 3;
  const RenderResult reference = render(scene, 0, options);
  const ImagePlane* id = nullptr;
  for (const NamedPlane& p : reference.aovs) {
    if (p.name == "id") id = &p.plane;
  }
  ASSERT_NE(id, nullptr);
  double f = 0, g = 0;
  int skin = 0;
  for (int y = 90; y < 150; ++y) {
    for (int x = 140; x < 260; ++x) {
      if (id->at(x, y) != static_cast<float>(PixelClass::skin)) continue;
      f += fast.electrons.at(x, y);
      g += reference.electrons.at(x, y);
      ++skin;
    }
  }
  ASSERT_GT(skin, 3000);
  EXPECT_NEAR(f / g, 1.0, 0.02);
}

}  // namespace
}  // namespace purkinje::renderer
