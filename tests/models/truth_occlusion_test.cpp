// compute_truth with an occlusion (TruthOptions::occluded): what it marks
// occluded, and the two pupil ellipses. Expected values come from the
// truth without an occlusion and fit_ellipse on the points an independent
// rule keeps, not from the occluded truth itself.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "purkinje/models/scene_file.h"
#include "purkinje/models/truth.h"

namespace purkinje {
namespace {

Scene bundled(const std::string& name) {
  return load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/" + name + ".json");
}

void expect_same_ellipse(const Ellipse& a, const Ellipse& b) {
  EXPECT_EQ(a.center.u, b.center.u);
  EXPECT_EQ(a.center.v, b.center.v);
  EXPECT_EQ(a.semi_axis_1_px, b.semi_axis_1_px);
  EXPECT_EQ(a.semi_axis_2_px, b.semi_axis_2_px);
  EXPECT_EQ(a.angle_rad, b.angle_rad);
}

TEST(TruthOcclusion, NothingBlockedIsTheTruthWithoutOcclusion) {
  const Scene scene = bundled("remote");
  const SceneTruth plain = compute_truth(scene);
  TruthOptions options;
  int asked = 0;
  options.occluded = [&](const Point3&, const Point3&) { return ++asked, Occluder::none; };
  const SceneTruth open = compute_truth(scene, options);
  EXPECT_GT(asked, 36);  // every ok glint's two legs, every ok border point, the centre
  ASSERT_EQ(open.views.size(), plain.views.size());
  const PupilTruth& p = open.views[0].pupil;
  for (std::size_t g = 0; g < plain.views[0].glints.size(); ++g) {
    EXPECT_EQ(open.views[0].glints[g].status, plain.views[0].glints[g].status);
  }
  for (std::size_t k = 0; k < p.border.size(); ++k) EXPECT_EQ(p.border[k].status, plain.views[0].pupil.border[k].status);
  ASSERT_TRUE(p.ellipse_valid && p.visible_ellipse_valid);
  expect_same_ellipse(p.ellipse, plain.views[0].pupil.ellipse);
  expect_same_ellipse(p.visible_ellipse, plain.views[0].pupil.ellipse);
  EXPECT_EQ(p.refracted_center_status, PathStatus::ok);
}

// A lid over the upper half of the eye: whatever lies above the cornea's
// centre (in world y, up) is hidden from the camera, and lights cannot
// reach the glints there either. What blocks a segment is named by its
// end: "skin" toward the camera, "lash" toward a light, so that a glint's
// label shows which leg was asked first.
TEST(TruthOcclusion, ALidOverTheUpperHalfHidesWhatLiesAboveAndLeavesTheWholePupilsEllipse) {
  const Scene scene = bundled("remote");
  const double lid_y = scene.eyes[0].cornea_center().y;
  const auto above = [&](const Point3& p) { return p.y > lid_y; };
  const Point3 camera = scene.cameras[0].center();
  TruthOptions options;
  options.occluded = [&](const Point3& from, const Point3& to) {
    if (!above(from) && !above(to)) return Occluder::none;
    return to == camera ? Occluder::skin : Occluder::lash;
  };
  const SceneTruth plain = compute_truth(scene);
  const SceneTruth lidded = compute_truth(scene, options);

  for (std::size_t g = 0; g < plain.views[0].glints.size(); ++g) {
    const GlintTruth& before = plain.views[0].glints[g];
    // Hidden when its light, its reflection point or the camera lies above.
    const bool blocked = above(scene.illuminators[g].position) || above(before.reflection.point) ||
                         above(scene.cameras[0].center());
    const PathStatus expected = before.status == PathStatus::ok && blocked ? PathStatus::occluded : before.status;
    EXPECT_EQ(lidded.views[0].glints[g].status, expected) << "glint " << g;
    // What the camera sees in front of it first, else what shadows it.
    const Occluder by = expected != PathStatus::occluded                        ? Occluder::none
                        : above(before.reflection.point) || above(camera) ? Occluder::skin
                                                                            : Occluder::lash;
    EXPECT_EQ(lidded.views[0].glints[g].occluder, by) << "glint " << g;
  }
  std::vector<Pixel> below;
  int hidden = 0;
  const PupilTruth& pupil = lidded.views[0].pupil;
  for (std::size_t k = 0; k < pupil.border.size(); ++k) {
    const PupilBorderPointTruth& before = plain.views[0].pupil.border[k];
    ASSERT_EQ(before.status, PathStatus::ok);
    const bool hides = above(before.refraction.anterior_point);
    EXPECT_EQ(pupil.border[k].status, hides ? PathStatus::occluded : PathStatus::ok) << "border point " << k;
    EXPECT_EQ(pupil.border[k].occluder, hides ? Occluder::skin : Occluder::none) << "border point " << k;
    EXPECT_EQ(pupil.border[k].pixel.u, before.pixel.u);
    if (hides) {
      ++hidden;
    } else {
      below.push_back(before.pixel);
    }
  }
  ASSERT_GT(hidden, 6);
  ASSERT_GE(below.size(), 6u);
  // The whole pupil's ellipse does not move; the visible one is the fit to
  // the lower points alone.
  ASSERT_TRUE(pupil.ellipse_valid);
  expect_same_ellipse(pupil.ellipse, plain.views[0].pupil.ellipse);
  const std::optional<Ellipse> visible = fit_ellipse(below);
  ASSERT_TRUE(visible && pupil.visible_ellipse_valid);
  expect_same_ellipse(pupil.visible_ellipse, *visible);
  // The pupil's centre lies on the lid's line: above it or not, by its
  // refracted path's corneal point.
  EXPECT_EQ(pupil.refracted_center_status,
            above(plain.views[0].pupil.refracted_center_path.anterior_point) ? PathStatus::occluded : PathStatus::ok);
}

// With fewer than six visible points there is no visible ellipse, and the
// whole pupil's stays.
TEST(TruthOcclusion, AClosedLidLeavesNoVisibleEllipse) {
  const Scene scene = bundled("headset");
  TruthOptions options;
  options.occluded = [](const Point3&, const Point3&) { return Occluder::skin; };
  const SceneTruth truth = compute_truth(scene, options);
  const PupilTruth& pupil = truth.views[0].pupil;
  EXPECT_TRUE(pupil.ellipse_valid);
  EXPECT_FALSE(pupil.visible_ellipse_valid);
  for (const GlintTruth& g : truth.views[0].glints) EXPECT_NE(g.status, PathStatus::ok);
  for (const PupilBorderPointTruth& b : truth.views[0].pupil.border) EXPECT_NE(b.status, PathStatus::ok);
}

}  // namespace
}  // namespace purkinje
