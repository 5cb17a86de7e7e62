// Eyebrows (Brows in appearance.h, brows.h): the hairs a face grows
// against the band and the rules brows.h states, found on the face as the
// ray tracer meets it, and their own class in rendered images.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "brows.h"
#include "purkinje/models/eye.h"
#include "purkinje/models/scene.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/renderer/ray_tracer.h"
#include "purkinje/renderer/render.h"
#include "scene_geometry.h"

namespace purkinje::renderer {
namespace {

constexpr double kDegree = std::numbers::pi / 180;

// A right eye's face with brows, its head frame the world's (forward +z,
// up +y, the centre of rotation at the origin; nasal is +x).
Scene browed_face(const Brows& brows) {
  Eye eye = Eye::with_rotation_center(*eye_model_preset("keratometric"), Point3{0, 0, 0}, UnitVector3::unit_z());
  EyeAppearance look;
  look.head_forward = UnitVector3::unit_z();
  look.head_up = UnitVector3::unit_y();
  look.eyelids = Eyelids{};
  look.face = Face{};
  look.face->brows = brows;
  eye.set_appearance(look);
  Scene scene;
  scene.eyes = {eye};
  return scene;
}

// The brows' hairs of a scene's geometry, each a chain of kBrowSegments.
std::vector<HairSegment> brow_segments(const Scene& scene) {
  const SceneGeometry geometry = build_scene_geometry(scene);
  for (const auto& hairs : geometry.hairs) {
    if (hairs->kind() == Surface::brow) return hairs->segments();
  }
  return {};
}

double smoothstep(double x, double from, double to) {
  const double s = std::clamp((x - from) / (to - from), 0.0, 1.0);
  return s * s * (3 - 2 * s);
}

// The band as brows.h states it, at fraction s from head to tail.
struct Band {
  const Brows& brows;
  double head = Eyelids{}.half_width_mm;
  double tail = -Face{}.lateral_canthus_mm - 14;
  double lower(double s) const { return brows.height_mm + 2.5 * (1 - std::pow((s - 0.52) / 0.52, 2)); }
  double height(double s) const { return brows.width_mm * (1 - 0.6 * s); }
  double s_at(double x) const { return (head - x) / (head - tail); }
  // The mean of the feathering's keep probability over the band's area.
  double mean_keep() const {
    double kept = 0, area = 0;
    for (int i = 0; i < 400; ++i) {
      const double s = (i + 0.5) / 400;
      for (int j = 0; j < 400; ++j) {
        const double across = (j + 0.5) / 400;
        const double edge = std::min(across, 1 - across);
        kept += height(s) * smoothstep(s, -0.02, 0.15) * smoothstep(edge, -0.1, 0.2);
        area += height(s);
      }
    }
    return kept / area;
  }
};

TEST(Brows, AFaceGrowsItsBrowsInTheBandOnItsSkin) {
  const Brows brows;
  const Scene scene = browed_face(brows);
  const std::vector<HairSegment> segments = brow_segments(scene);
  ASSERT_EQ(segments.size() % kBrowSegments, 0u);
  const std::size_t hairs = segments.size() / kBrowSegments;
  const Band band{brows};

  // How many: the density times the band's area (its length times the
  // mean height, 1 - 0.3 of width_mm), each kept with the feathering's
  // probability: within 4 standard deviations of the binomial's mean.
  const double drawn = std::round(brows.hairs_per_mm2 * (band.head - band.tail) * brows.width_mm * 0.7);
  const double p = band.mean_keep();
  EXPECT_NEAR(static_cast<double>(hairs), drawn * p, 4 * std::sqrt(drawn * p * (1 - p)));
  EXPECT_GT(hairs, 250u);  // anthropometry: 250-600 a brow
  RecordProperty("hairs", static_cast<int>(hairs));

  const RayTracer tracer(scene);
  const double r0 = 0.5 * brows.thickness_mm;
  int head_hairs = 0, tail_hairs = 0;
  double worst_gap = 0;
  double tail_down = 0, tail_lateral = 0;
  for (std::size_t k = 0; k < segments.size(); k += kBrowSegments) {
    const HairSegment& first = segments[k];
    // The root (sunk by r0 along the skin's normal) lies in the band.
    const double s = band.s_at(first.a.x);
    ASSERT_GE(s, -1e-3);
    ASSERT_LE(s, 1 + 1e-3);
    EXPECT_GE(first.a.y, band.lower(s) - 0.05);
    EXPECT_LE(first.a.y, band.lower(s) + band.height(s) + 0.05);
    // On the skin the ray tracer meets looking down -z: just behind it.
    Ray down;
    down.origin = {first.a.x, first.a.y, 100};
    down.direction = -UnitVector3::unit_z();
    const Hit skin = tracer.intersect_except_hair(down);
    ASSERT_EQ(skin.surface, Surface::skin);
    const double sunk = (skin.point.z - first.a.z) * std::abs(skin.normal.z());
    EXPECT_NEAR(sunk, r0, 0.01) << "hair " << k / kBrowSegments;
    // Leaving the skin lift_deg (+-5) above it, less an eighth of its curl
    // (+-30%), the first chord's middle: within a degree of that range.
    const Vector3 chord = first.b - first.a;
    const double lift = std::asin(dot(chord, skin.normal.vector()) / chord.norm()) / kDegree;
    EXPECT_GE(lift, brows.lift_deg - 5 - 1.3 * brows.curl_deg / 8 - 1);
    EXPECT_LE(lift, brows.lift_deg + 5 + 1);
    // Every chord's end in front of the skin, and the tip no higher above
    // it (along the skin's normal) than its chords' rises at their largest
    // elevations (lift + 5 deg less 0.7 of the curl to the chord's middle,
    // chords of 1.2 times the hair's length over 4) allow, plus 0.3 mm for
    // the ridge's curve under a chord.
    double rise = 0;
    for (int j = 0; j < kBrowSegments; ++j) {
      const double elevation = std::max(brows.lift_deg + 5 - 0.7 * brows.curl_deg * (j + 0.5) / kBrowSegments, 0.0);
      rise += 1.2 * brows.hair_length_mm / kBrowSegments * std::sin(elevation * kDegree);
      const Point3& end = segments[k + j].b;
      down.origin = {end.x, end.y, 100};
      const Hit behind = tracer.intersect_except_hair(down);
      EXPECT_GT(end.z, behind.point.z - 1e-9) << "hair " << k / kBrowSegments << " chord " << j;
      if (j == kBrowSegments - 1) {
        const double gap = (end.z - behind.point.z) * std::abs(behind.normal.z());
        EXPECT_LT(gap, rise + 0.3) << "hair " << k / kBrowSegments << " floats off the skin";
        worst_gap = std::max(worst_gap, gap);
      }
    }
    // Growth: up at the head; lateral (-x for a right eye) and down at the
    // tail, on average (there the skin turns back around the side of the
    // head, and the hairs lying on it with it: a third of their length
    // goes backward).
    if (s < 0.05) {
      ++head_hairs;
      EXPECT_GT(chord.y, 0) << "a hair at the head points down";
    }
    if (s > 0.95) {
      ++tail_hairs;
      tail_down += chord.y / chord.norm();
      tail_lateral += -chord.x / chord.norm();
    }
  }
  RecordProperty("worst_tip_gap_mm", std::to_string(worst_gap));
  EXPECT_GT(head_hairs, 0);
  ASSERT_GT(tail_hairs, 3);
  EXPECT_LT(tail_down / tail_hairs, -0.1);
  EXPECT_GT(tail_lateral / tail_hairs, 0.5);
}

TEST(Brows, SeededAndSparedWhereThereAreNone) {
  Brows brows;
  const std::vector<HairSegment> one = brow_segments(browed_face(brows));
  ASSERT_FALSE(one.empty());
  EXPECT_EQ(brow_segments(browed_face(brows)).back().b, one.back().b);
  brows.seed = 2;
  EXPECT_NE(brow_segments(browed_face(brows)).back().b, one.back().b);
  brows.hairs_per_mm2 = 0;
  EXPECT_TRUE(brow_segments(browed_face(brows)).empty());
  // A face of the other side grows them mirrored: the head on the nasal
  // side (+x for a right eye, -x for a left one).
  Scene left = browed_face(Brows{});
  EyeAppearance look = left.eyes[0].appearance();
  look.face->side = EyeSide::left;
  left.eyes[0].set_appearance(look);
  const std::vector<HairSegment> mirrored = brow_segments(left);
  ASSERT_FALSE(mirrored.empty());
  double right_x = 0, left_x = 0;
  for (const HairSegment& s : one) right_x += s.a.x;
  for (const HairSegment& s : mirrored) left_x += s.a.x;
  EXPECT_LT(right_x / one.size(), 0);  // the band reaches further laterally than nasally
  EXPECT_GT(left_x / mirrored.size(), 0);
  // And grow mirrored: along the body and tail laterally, -x for the right
  // eye and +x for the left, on average over the hairs rooted laterally.
  const auto lateral_growth = [](const std::vector<HairSegment>& hairs, double side) {
    double sum = 0;
    int n = 0;
    for (std::size_t k = 0; k < hairs.size(); k += kBrowSegments) {
      if (side * hairs[k].a.x > -5) continue;  // medial: the head's hairs point up
      sum += side * (hairs[k].b.x - hairs[k].a.x) / (hairs[k].b - hairs[k].a).norm();
      ++n;
    }
    return n > 0 ? sum / n : 0.0;
  };
  EXPECT_LT(lateral_growth(one, 1), -0.5);
  EXPECT_LT(lateral_growth(mirrored, -1), -0.5);
}

// The bundled remote_face (brows on both eyes): brow pixels are their own
// class with their own coverage plane, dark hairs on lighter skin, and
// the brows hide nothing the labels list.
TEST(Brows, AreTheirOwnClassInTheImageAndHideNoLabel) {
  Scene scene = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/remote_face.json");
  ASSERT_TRUE(scene.eyes[0].appearance().face->brows);
  RenderOptions options;
  options.noise = false;
  // The right eye's brow and eye (the image's left half).
  options.region = PixelRegion{360, 300, 640, 520};
  const RenderResult result = render(scene, 0, options);
  const ImagePlane *id = nullptr, *coverage = nullptr;
  for (const NamedPlane& p : result.aovs) {
    if (p.name == "id") id = &p.plane;
    if (p.name == "brow") coverage = &p.plane;
  }
  ASSERT_NE(id, nullptr);
  ASSERT_NE(coverage, nullptr);
  int brow = 0;
  double brow_electrons = 0, skin_electrons = 0;
  int skin = 0;
  for (int y = 300; y < 520; ++y) {
    for (int x = 360; x < 640; ++x) {
      const auto c = static_cast<PixelClass>(static_cast<int>(id->at(x, y)));
      if (c == PixelClass::brow) {
        ++brow;
        brow_electrons += result.electrons.at(x, y);
        EXPECT_GT(coverage->at(x, y), 0.0f);
      } else {
        EXPECT_LT(coverage->at(x, y), 1.0f);
      }
      if (c == PixelClass::skin) {
        ++skin;
        skin_electrons += result.electrons.at(x, y);
      }
    }
  }
  EXPECT_GT(brow, 200);
  EXPECT_LT(brow_electrons / brow, 0.8 * skin_electrons / skin);
  for (const EyeInCameraTruth& view : result.truth.views) {
    for (const GlintTruth& g : view.glints) EXPECT_NE(g.occluder, Occluder::brow);
    for (const PupilBorderPointTruth& b : view.pupil.border) EXPECT_NE(b.occluder, Occluder::brow);
  }
}

}  // namespace
}  // namespace purkinje::renderer
