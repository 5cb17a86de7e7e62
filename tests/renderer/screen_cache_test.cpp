// The fast mode's screen-space caches (renderer/src/screen_cache.h) on a
// synthetic scene: a camera looking straight at the plane z = 100 mm, so
// that every pixel's diffuse point is known in closed form.

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <vector>

#include "screen_cache.h"  // the renderer's private header (purkinje::renderer_internal)

namespace purkinje::renderer {
namespace {

constexpr int kSize = 64;
constexpr double kPlaneZ = 100;

Camera test_camera() {
  Intrinsics k;
  k.fx = k.fy = 100;
  k.cx = k.cy = (kSize - 1) / 2.0;
  k.width = k.height = kSize;
  return Camera("cam", k, Distortion{}, Pose{}, Sensor{});
}

// The plane's point seen at an image position; x >= `split_x_mm` belongs to
// another owner (a second surface).
DiffusePoint plane_point(const Camera& camera, const Pixel& p, double split_x_mm = 1e9) {
  const UnitVector3 d = camera.back_project(p);
  const double t = kPlaneZ / d.z();
  DiffusePoint q;
  q.surface = Surface::skin;
  q.point = camera.center() + d * t;
  q.owner = q.point.x >= split_x_mm ? 1 : 0;
  q.normal = {0, 0, -1};
  q.path_mm = t;
  q.cos_view = d.z();
  return q;
}

const PixelRegion kWhole{0, 0, kSize, kSize};
// One level of nodes every 2 px, one every 8 px; two levels as the renderer's
// visibility cache has them.
const GridSpacing kTwoPx{2, 2}, kEightPx{8, 8}, kEightThenTwoPx{8, 2};

// The diffuse cache's settling rule needs a direct irradiance; these tests
// make it large so that only the cell's coherence and the tolerance decide.
double direct_level(const DiffusePoint&) { return 1000.0; }

TEST(VisibilityCache, AgreesWhereAllFourNodesAgreeAndKnowsNothingAtAShadowEdge) {
  const Camera camera = test_camera();
  const auto find = [&](const Pixel& p) { return plane_point(camera, p); };
  // Light 0 is blocked where x > 0 (the right half of the image); light 1
  // lights everything.
  const auto lit = [](const DiffusePoint& p, std::size_t light) { return light == 1 || p.point.x <= 0; };
  const VisibilityCache cache(camera, kWhole, kTwoPx, 2, find, lit);

  const Pixel left{10.3, 20.6}, right{50.2, 33.9}, at_edge{31.9, 40.0};
  const auto left_agreed = cache.at(left, find(left));
  EXPECT_EQ(left_agreed.known, 0b11u);
  EXPECT_EQ(left_agreed.lit, 0b11u);
  const auto right_agreed = cache.at(right, find(right));
  EXPECT_EQ(right_agreed.known, 0b11u);
  EXPECT_EQ(right_agreed.lit, 0b10u);
  // The shadow edge (x = 0 at u = 31.5) runs between the nodes at u = 30
  // and u = 32: light 0 must be traced there, light 1 need not be.
  const auto edge_agreed = cache.at(at_edge, find(at_edge));
  EXPECT_EQ(edge_agreed.known, 0b10u);
  EXPECT_EQ(edge_agreed.lit, 0b10u);
}

TEST(VisibilityCache, KnowsNothingWhereTheNodesSeeAnotherSurface) {
  const Camera camera = test_camera();
  // The plane's right part (x >= 0.5 mm, from u = 32) is another surface.
  const auto find = [&](const Pixel& p) { return plane_point(camera, p, 0.5); };
  const auto lit = [](const DiffusePoint&, std::size_t) { return true; };
  const VisibilityCache cache(camera, kWhole, kTwoPx, 1, find, lit);
  const Pixel near_seam{31.0, 10.0}, far_from_seam{20.0, 10.0};
  EXPECT_EQ(cache.at(near_seam, find(near_seam)).known, 0u);
  EXPECT_EQ(cache.at(far_from_seam, find(far_from_seam)).known, 1u);
}

// At an outline, three nodes may serve a point and the fourth see another
// surface. A shadow edge cannot part a point inside the three's triangle
// from all three, so there they settle it; beyond, toward the fourth node,
// the shadow ray is traced. Each of the cell's four corners in turn sees
// the other surface: of the cell from (30, 10) to (32, 12), only the
// corner beyond a diagonal line (u + v or u - v at a threshold).
TEST(VisibilityCache, ThreeNodesSettleOnlyThePointsInsideTheirTriangle) {
  const Camera camera = test_camera();
  const auto lit = [](const DiffusePoint&, std::size_t) { return true; };
  struct Case {
    double sum_sign, difference_sign, threshold;  // other surface: s (u + v) + d (u - v) >= threshold
    Pixel inside, beyond;                         // both on the plane's surface
  };
  const Case cases[] = {
      {+1, 0, 43.5, {30.6, 10.9}, {31.5, 11.2}},   // corner (32, 12) beyond u + v = 43.5
      {-1, 0, -40.5, {31.4, 11.1}, {30.5, 10.8}},  // corner (30, 10) before u + v = 40.5
      {0, +1, 21.5, {30.6, 11.4}, {31.4, 10.5}},   // corner (32, 10) beyond u - v = 21.5
      {0, -1, -18.5, {31.4, 10.6}, {30.5, 11.4}},  // corner (30, 12) before u - v = 18.5
  };
  for (const Case& c : cases) {
    const auto find = [&](const Pixel& p) {
      DiffusePoint q = plane_point(camera, p);
      q.owner = c.sum_sign * (p.u + p.v) + c.difference_sign * (p.u - p.v) >= c.threshold ? 1 : 0;
      return q;
    };
    const VisibilityCache cache(camera, kWhole, kTwoPx, 1, find, lit);
    ASSERT_EQ(find(c.inside).owner, 0);
    ASSERT_EQ(find(c.beyond).owner, 0);
    EXPECT_EQ(cache.at(c.inside, find(c.inside)).known, 1u) << c.threshold;
    EXPECT_EQ(cache.at(c.inside, find(c.inside)).lit, 1u) << c.threshold;
    EXPECT_EQ(cache.at(c.beyond, find(c.beyond)).known, 0u) << c.threshold;
  }
}

// Every light lights the plane but for a stripe of shadow between image
// columns u0 and u1.
VisibilityCache::Lit shadow_stripe(const Camera& camera, double u0, double u1) {
  const auto x_at = [&](double u) { return (u - camera.intrinsics().cx) / camera.intrinsics().fx * kPlaneZ; };
  const double x0 = x_at(u0), x1 = x_at(u1);
  return [x0, x1](const DiffusePoint& p, std::size_t) { return p.point.x < x0 || p.point.x > x1; };
}

// The known limit (docs/rendering.md): a shadow narrower than the node
// spacing that falls between the nodes is not seen.
TEST(VisibilityCache, AShadowBetweenNodesNarrowerThanTheSpacingIsMissed) {
  const Camera camera = test_camera();
  const auto find = [&](const Pixel& p) { return plane_point(camera, p); };
  // A stripe of shadow 1 px wide centred on u = 41, between the nodes at
  // u = 40 and u = 42.
  const VisibilityCache cache(camera, kWhole, kTwoPx, 1, find, shadow_stripe(camera, 40.5, 41.5));
  const Pixel in_stripe{41.0, 12.0};
  const auto agreed = cache.at(in_stripe, find(in_stripe));
  EXPECT_EQ(agreed.known, 1u);
  EXPECT_EQ(agreed.lit, 1u);  // wrong, as documented
}

// With two levels, the coarse cells about a shadow edge disagree, so the
// fine nodes decide there: the same answers as fine nodes everywhere, from
// fewer shadow tests.
TEST(VisibilityCache, TwoLevelsAnswerAsTheFineLevelAloneAtAShadowEdge) {
  const Camera camera = test_camera();
  const auto find = [&](const Pixel& p) { return plane_point(camera, p); };
  std::atomic<int> fine_calls = 0, two_level_calls = 0;  // the nodes are found in parallel
  std::atomic<int>* calls = &fine_calls;
  const auto lit = [&](const DiffusePoint& p, std::size_t light) { return ++*calls, light == 1 || p.point.x <= 0; };
  const VisibilityCache fine(camera, kWhole, kTwoPx, 2, find, lit);
  calls = &two_level_calls;
  const VisibilityCache two_levels(camera, kWhole, kEightThenTwoPx, 2, find, lit);
  for (const Pixel p : {Pixel{10.3, 20.6}, Pixel{50.2, 33.9}, Pixel{31.9, 40.0}, Pixel{30.6, 2.2}, Pixel{33.1, 60.0}}) {
    const auto a = fine.at(p, find(p)), b = two_levels.at(p, find(p));
    EXPECT_EQ(a.known, b.known) << "at (" << p.u << ", " << p.v << ")";
    EXPECT_EQ(a.lit, b.lit) << "at (" << p.u << ", " << p.v << ")";
  }
  // Coarse nodes at u, v = -8, 0, ..., 64 (10 x 10); then fine nodes only
  // in the column of cells about the edge (u = 24 to 32): 5 columns of 34
  // (v = -2, 0, ..., 64), less the 2 x 9 coarse ones among them. Fine
  // nodes alone: 34 x 34.
  EXPECT_EQ(two_level_calls, 2 * (10 * 10 + 5 * 34 - 2 * 9));
  EXPECT_EQ(fine_calls, 2 * 34 * 34);
}

// The same limit with two levels is the coarse spacing: a shadow that
// falls inside coarse cells whose four corners are all lit is not seen.
// The renderer's coarse spacing is 8 px.
TEST(VisibilityCache, WithTwoLevelsAShadowInsideALitCoarseCellIsMissed) {
  const Camera camera = test_camera();
  const auto find = [&](const Pixel& p) { return plane_point(camera, p); };
  // A stripe of shadow 3 px wide centred on u = 44, between the coarse
  // nodes at u = 40 and u = 48.
  const auto lit = shadow_stripe(camera, 42.5, 45.5);
  const Pixel in_stripe{44.0, 12.0};
  const VisibilityCache fine(camera, kWhole, kTwoPx, 1, find, lit);
  const auto seen = fine.at(in_stripe, find(in_stripe));
  EXPECT_EQ(seen.known & seen.lit, 0u);  // shadowed or traced: never wrongly lit
  const VisibilityCache two_levels(camera, kWhole, kEightThenTwoPx, 1, find, lit);
  const auto missed = two_levels.at(in_stripe, find(in_stripe));
  EXPECT_EQ(missed.known, 1u);
  EXPECT_EQ(missed.lit, 1u);  // wrong, as documented
}

TEST(VisibilityCache, MoreLightsThanItHoldsLeavesEverythingToTheTracer) {
  const Camera camera = test_camera();
  const auto find = [&](const Pixel& p) { return plane_point(camera, p); };
  int calls = 0;
  const auto lit = [&](const DiffusePoint&, std::size_t) { return ++calls, true; };
  const VisibilityCache cache(camera, kWhole, kTwoPx, VisibilityCache::kMaxLights + 1, find, lit);
  EXPECT_EQ(calls, 0);
  const Pixel p{20, 20};
  EXPECT_EQ(cache.at(p, find(p)).known, 0u);
}

TEST(DiffuseCache, InterpolatesAConstantExactlyAndRefusesAnotherSurface) {
  const Camera camera = test_camera();
  const auto find = [&](const Pixel& p) { return plane_point(camera, p, 0.5); };
  // 2 W/m^2 from light 0 and 3 from light 1 on owner 0; owner 1 gets 7 and 9.
  const auto gather = [](const DiffusePoint& p, std::uint64_t, double* e) {
    e[0] += p.owner == 0 ? 2 : 7;
    e[1] += p.owner == 0 ? 3 : 9;
  };
  const DiffuseCache cache(camera, kWhole, kEightPx, 2, find, gather, direct_level, 0.0);
  double e[2];
  const Pixel left{13.7, 21.2};
  ASSERT_TRUE(cache.irradiance(left, find(left), e));
  EXPECT_DOUBLE_EQ(e[0], 2);
  EXPECT_DOUBLE_EQ(e[1], 3);
  // Just right of the seam (u = 32): the nodes at u = 32 and 40 see owner 1.
  const Pixel right{32.2, 21.2};
  ASSERT_TRUE(cache.irradiance(right, find(right), e));
  EXPECT_DOUBLE_EQ(e[0], 7);
  EXPECT_DOUBLE_EQ(e[1], 9);
  // Owner 1 seen where every node around sees owner 0 (as a thin sliver
  // would be): no node serves it, the caller must gather.
  DiffusePoint sliver = find(left);
  sliver.owner = 1;
  EXPECT_FALSE(cache.irradiance(left, sliver, e));
}

// Every quarter pixel of `region`, looked up in the whole image's cache
// and in the region's: both must serve it, with the same value, which
// `also(u, value)` may check further. `checked` counts the lookups.
template <typename Also>
void expect_same_lookups(const DiffuseCache& whole, const DiffuseCache& part, const PixelRegion& region,
                         const FindDiffusePoint& find, int& checked, const Also& also) {
  for (double v = region.y0 - 0.5; v <= region.y1 - 0.5; v += 0.25) {
    for (double u = region.x0 - 0.5; u <= region.x1 - 0.5; u += 0.25) {
      double a = -1, b = -2;
      const Pixel p{u, v};
      ASSERT_TRUE(whole.irradiance(p, find(p), &a)) << "at (" << u << ", " << v << ")";
      ASSERT_TRUE(part.irradiance(p, find(p), &b)) << "at (" << u << ", " << v << ")";
      ASSERT_EQ(a, b) << "at (" << u << ", " << v << ")";
      also(u, a);
      ++checked;
    }
  }
}

// The lattice is anchored at pixel (0, 0) and covers every sample of the
// region's pixels, so a region's lookups are the whole image's.
TEST(DiffuseCache, ARegionLooksUpExactlyWhatTheWholeImageDoes) {
  const Camera camera = test_camera();
  const auto find = [&](const Pixel& p) { return plane_point(camera, p); };
  // Irradiance that differs from node to node, keyed by the node's place.
  const auto gather = [&](const DiffusePoint&, std::uint64_t key, double* e) {
    e[0] += static_cast<double>((key * 2654435761u) % 1000);
  };
  const PixelRegion region{17, 9, 30, 25};
  const DiffuseCache whole(camera, kWhole, kEightPx, 1, find, gather, direct_level, 0.0);
  const DiffuseCache part(camera, region, kEightPx, 1, find, gather, direct_level, 0.0);
  int checked = 0;
  expect_same_lookups(whole, part, region, find, checked, [](double, double) {});
  EXPECT_GT(checked, 3000);
}

// Two levels: where the coarse corners agree within the tolerance, no fine
// node is gathered, and the value is the corners'.
TEST(DiffuseCache, ASmoothFieldSettlesOnTheCoarseNodesAlone) {
  const Camera camera = test_camera();
  const auto find = [&](const Pixel& p) { return plane_point(camera, p); };
  std::atomic<int> gathers = 0;
  // 2 W/m^2 plus a variation of at most 0.5 (0.05% of the direct 1000).
  const auto gather = [&](const DiffusePoint&, std::uint64_t key, double* e) {
    ++gathers;
    e[0] += 2 + 0.5 * static_cast<double>(key % 7) / 6;
  };
  const DiffuseCache cache(camera, kWhole, GridSpacing{16, 8}, 1, find, gather, direct_level, 1e-3);
  EXPECT_EQ(gathers, 6 * 6);  // the coarse nodes at u, v = -16, 0, ..., 64
  double e = 0;
  const Pixel p{21.3, 40.7};
  ASSERT_TRUE(cache.irradiance(p, find(p), &e));
  EXPECT_GE(e, 2.0);
  EXPECT_LE(e, 2.5);
}

// Settled and unsettled cells side by side: a region still looks up exactly
// what the whole image does, on both levels.
TEST(DiffuseCache, WithTwoLevelsARegionLooksUpExactlyWhatTheWholeImageDoes) {
  const Camera camera = test_camera();
  const auto find = [&](const Pixel& p) { return plane_point(camera, p); };
  // Constant left of x = 0 (u = 31.5); right of it, values that differ from
  // node to node by far more than the tolerance.
  const auto gather = [&](const DiffusePoint& p, std::uint64_t key, double* e) {
    e[0] += p.point.x < 0 ? 5.0 : static_cast<double>((key * 2654435761u) % 1000);
  };
  std::atomic<int> gathers_whole = 0;
  const auto counted = [&](const DiffusePoint& p, std::uint64_t key, double* e) { ++gathers_whole, gather(p, key, e); };
  const DiffuseCache whole(camera, kWhole, GridSpacing{16, 4}, 1, find, counted, direct_level, 1e-3);
  // Coarse nodes at u, v = -16, 0, ..., 64 (6 x 6); fine nodes in the
  // cells from u = 16 on (the cell from 16 to 32 has corners on both
  // sides): 13 columns of 18 (v = -4, 0, ..., 64), less the 4 x 5 coarse
  // ones among them.
  EXPECT_EQ(gathers_whole, 6 * 6 + 13 * 18 - 4 * 5);
  const PixelRegion region{9, 9, 47, 25};
  const DiffuseCache part(camera, region, GridSpacing{16, 4}, 1, find, gather, direct_level, 1e-3);
  int checked = 0;
  expect_same_lookups(whole, part, region, find, checked, [](double u, double e) {
    if (u < 15) {
      EXPECT_DOUBLE_EQ(e, 5.0) << "at u = " << u;
    }
  });
  EXPECT_GT(checked, 9000);
}

}  // namespace
}  // namespace purkinje::renderer
