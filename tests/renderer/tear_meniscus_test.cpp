// The lids' tear menisci: their highlights on a straight margin (a torus:
// the fillet's centres run on a circle about the head's vertical axis)
// against the law of reflection on the fillet's circle solved by hand,
// their power against Coddington's equations, and in rendered images
// where the labels put them with the electrons they give. The upper lid's
// cases are the lower's mirrored top to bottom (y to -y), the hand
// solutions with them.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "mirror_radiometry.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/models/truth.h"
#include "purkinje/renderer/render.h"
#include "tear_meniscus.h"

namespace purkinje::renderer {
namespace {

constexpr double kGlobe = 12.0, kRadius = 0.3, kMargin = -6.0;
constexpr Lid kLids[] = {Lid::lower, Lid::upper};

// +1 for the lower lid, -1 for the upper: the lower lid's case mirrored.
double sign(Lid lid) { return lid == Lid::lower ? 1.0 : -1.0; }
Point3 mirrored(Lid lid, const Point3& p) { return {p.x, sign(lid) * p.y, p.z}; }
Vector3 mirrored(Lid lid, const Vector3& v) { return {v.x, sign(lid) * v.y, v.z}; }
const char* name(Lid lid) { return lid == Lid::lower ? "lower" : "upper"; }

const ShellOffset kSphere = [](const Point3& p) {
  const Vector3 v = p.from_origin();
  return v - v * (kGlobe / v.norm());
};

// Head frame = world; the margin at y = -6 (the upper lid's at +6) along
// the whole lid, on a globe that is a sphere of radius 12 about the origin.
TearMeniscus straight_meniscus(Lid lid) {
  const double margin = sign(lid) * kMargin;
  return TearMeniscus::build(0, lid, Pose(), kRadius, [margin](double) { return margin; }, kSphere, -8, 8).value();
}

// The fillet's circle in the plane x = 0: centre r into the opening from
// the wall and r out of the globe.
Point3 circle_centre(Lid lid) {
  const double y = sign(lid) * (kMargin + kRadius);
  return {0, y, std::sqrt((kGlobe + kRadius) * (kGlobe + kRadius) - y * y)};
}

// The point on the circle (in the plane x = 0) that mirrors `source` to
// `target` (both in that plane), by bisection on the angle between the
// normal and the two directions, from the wall's contact toward the globe's.
Point3 mirror_point_by_hand(Lid lid, const Point3& source, const Point3& target) {
  const Point3 c = circle_centre(lid);
  // N = +y at the lower wall (-y at the upper), as the angle of N in the (z, y) plane.
  const double wall = std::atan2(sign(lid), 0.0);
  const Vector3 g = c.from_origin() / c.from_origin().norm();
  const double globe = std::atan2(g.y, g.z);
  const auto point = [&](double a) {
    const Vector3 n{0, std::sin(a), std::cos(a)};
    return std::pair{c - n * kRadius, n};
  };
  const auto imbalance = [&](double a) {
    const auto [p, n] = point(a);
    const Vector3 s = (source - p) / (source - p).norm(), t = (target - p) / (target - p).norm();
    // Positive when the normal leans toward the target.
    return std::acos(dot(n, s)) - std::acos(dot(n, t));
  };
  double lo = globe, hi = wall;
  const double f_lo = imbalance(lo);
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if ((imbalance(mid) > 0) == (f_lo > 0)) lo = mid; else hi = mid;
  }
  return point(0.5 * (lo + hi)).first;
}

TEST(TearMeniscus, MirrorsTheLightWhereTheLawOfReflectionHoldsOnTheFillet) {
  for (const Lid lid : kLids) {
  const TearMeniscus meniscus = straight_meniscus(lid);
  EXPECT_EQ(meniscus.lid(), lid);
  // Light and camera in the plane x = 0, in front and below (as a
  // headset's) or level (as a remote tracker's): the highlight lies where
  // the margin crosses that plane, by symmetry.
  for (const auto& [below_source, below_target] : {std::pair{Point3{0, -20, 40}, Point3{0, -12, 45}},
                                                   std::pair{Point3{0, -300, 600}, Point3{0, -150, 600}},
                                                   std::pair{Point3{0, -30, 20}, Point3{0, 5, 40}}}) {
    const Point3 source = mirrored(lid, below_source), target = mirrored(lid, below_target);
    const std::vector<Reflection> found = meniscus.highlights(source, target);
    ASSERT_EQ(found.size(), 1u) << name(lid) << source.z;
    const Reflection& r = found[0];
    EXPECT_EQ(r.status, PathStatus::ok);
    EXPECT_NEAR(r.point.x, 0, 1e-10);
    const Point3 expected = mirror_point_by_hand(lid, source, target);
    EXPECT_LT(distance(r.point, expected), 1e-9) << name(lid) << source.z;
    // On the circle, its normal toward the centre.
    EXPECT_NEAR(distance(r.point, circle_centre(lid)), kRadius, 1e-12);
    EXPECT_LT(distance(r.point + r.normal.vector() * kRadius, circle_centre(lid)), 1e-12);
    // The directions and the incidence as labelled.
    EXPECT_LT((r.incident.vector() - (r.point - source) / (r.point - source).norm()).norm(), 1e-12);
    EXPECT_NEAR(std::cos(r.incidence_rad), dot(r.normal, r.reflected), 1e-12);
    EXPECT_NEAR(dot(r.normal, -r.incident.vector()), dot(r.normal, r.reflected), 1e-12);
    // Found again from nearby.
    const Reflection again = meniscus.highlight_near(meniscus.circle_of(r.point + Vector3{0.2, 0, 0}), source, target);
    EXPECT_LT(distance(again.point, r.point), 1e-10);
  }
  }
}

TEST(TearMeniscus, HasNoHighlightWhereTheBisectorLeavesTheFilletsArc) {
  for (const Lid lid : kLids) {
    const TearMeniscus meniscus = straight_meniscus(lid);
    // From past the wall's normal (+y at the lower lid) and behind: the
    // bisector points past the wall's contact; from straight across, past
    // the globe's.
    EXPECT_TRUE(meniscus.highlights(mirrored(lid, Point3{0, 40, 5}), mirrored(lid, Point3{0, 60, 10})).empty());
    EXPECT_TRUE(meniscus.highlights(mirrored(lid, Point3{0, -60, -5}), mirrored(lid, Point3{0, -50, -2})).empty());
  }
}

TEST(TearMeniscus, ItsHighlightsPowerIsCoddingtonsForTheTorus) {
  for (const Lid lid : kLids) {
  const TearMeniscus meniscus = straight_meniscus(lid);
  const Illuminator led{"led", mirrored(lid, Point3{0, -20, 40}), 0.3, 850, 0};
  const Point3 centre = mirrored(lid, Point3{0, -12, 45});
  const Reflection first = meniscus.highlights(led.position, centre).at(0);
  // A camera aimed at the highlight: its aperture faces the reflected ray.
  Sensor sensor;
  sensor.pixel_pitch_mm = 0.006;
  const Camera camera("cam", Intrinsics::from_focal_length(16, 0.006, 640, 480), {},
                      camera_looking_at(centre, first.point, mirrored(lid, Vector3{0, -1, 0})), sensor);
  const std::vector<Reflection> found = meniscus.highlights(led.position, camera.center());
  ASSERT_EQ(found.size(), 1u) << name(lid);
  const Reflection& r = found[0];
  const GlintRadiometry g = meniscus_highlight_radiometry(meniscus, led, camera, r);
  ASSERT_EQ(g.status, PathStatus::ok);

  // Coddington: the reflected beam's focal lines lie a_t and a_s behind
  // the mirror, 1/a = 1/d_s + 2 k_t / cos i in the plane of incidence
  // (here the fillet's circle, k_t = -1/r: concave) and 1/d_s + 2 k_s cos i
  // across it (along the lid: the torus's parallel, k_s = (N . e) / D, e
  // the unit vector from the axis to the point, D its distance). The
  // solid angle at the LED per unit aperture area is then
  // 1 / (d_s^2 |1 + d_c / a_t| |1 + d_c / a_s|).
  const double cos_i = std::cos(r.incidence_rad);
  const double d_s = distance(led.position, r.point), d_c = distance(camera.center(), r.point);
  const double D = std::hypot(r.point.x, r.point.z);
  const Vector3 e{r.point.x / D, 0, r.point.z / D};
  const double k_t = -1 / kRadius, k_s = dot(r.normal.vector(), e) / D;
  const double tangential = 1 + d_c * (1 / d_s + 2 * k_t / cos_i);
  const double sagittal = 1 + d_c * (1 / d_s + 2 * k_s * cos_i);
  const double omega_per_area = 1 / (d_s * d_s * std::abs(tangential * sagittal));
  const double aperture = camera.focal_length_mm() / camera.sensor().f_number;
  const double expected = led.radiant_intensity_w_sr * fresnel_reflectance(cos_i, 1.0, kTearFilmIndex) *
                          omega_per_area * 0.25 * std::numbers::pi * aperture * aperture;
  // The meniscus is the pipe about a spline through the fillet's centres
  // 0.1 mm apart: its curvature along the lid is the torus's to about 1e-5.
  EXPECT_NEAR(g.power_w / expected, 1, 1e-4) << name(lid);
  EXPECT_NEAR(g.fresnel, fresnel_reflectance(cos_i, 1.0, kTearFilmIndex), 1e-15);
  }
}

// The headset face with a wet eye, its lids opened off the cornea (the
// menisci lie on the globe's sphere) and every albedo 0: only glints and
// highlights light the image; no lashes.
Scene wet_dark_face() {
  Scene scene = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/hard/headset_face.json");
  EyeAppearance look = scene.eyes[0].appearance();
  look.iris_albedo = look.sclera_albedo = look.skin_albedo = look.fundus_reflectance = 0;
  look.tear_film = TearFilm{};
  look.eyelids->lower_margin_mm = -7.5;
  look.eyelids->upper_margin_mm = 7.0;
  look.face->lashes.reset();
  scene.eyes[0].set_appearance(look);
  return scene;
}

// The distractors' plane (their share of each pixel's light).
const ImagePlane& distractor_mask(const RenderResult& result) {
  for (const NamedPlane& p : result.aovs) {
    if (p.name == "distractor") return p.plane;
  }
  throw std::runtime_error("no distractor AOV");
}

// The light the distractors' plane gives the image, over the electrons
// their labels give.
double imaged_over_labelled(const RenderResult& result) {
  const ImagePlane& mask = distractor_mask(result);
  double labelled = 0, imaged = 0;
  for (const GlintImage& d : result.distractors) labelled += d.electrons;
  for (std::size_t i = 0; i < mask.values.size(); ++i) imaged += double(mask.values[i]) * result.electrons.values[i];
  return imaged / labelled;
}

TEST(TearMeniscusHighlights, LieWhereTheLabelsSayWithTheirElectrons) {
  const Scene scene = wet_dark_face();
  RenderOptions options;
  options.noise = false;
  const RenderResult result = render(scene, 0, options);
  const std::vector<DistractorTruth>& truth = result.truth.views[0].distractors;
  ASSERT_EQ(truth.size(), result.distractors.size());
  const ImagePlane* mask = &distractor_mask(result);
  const ImagePlane& e = result.electrons;

  // Every highlight's light in the image is what its label gives.
  const auto meniscus = [](const DistractorTruth& d) {
    return d.kind == DistractorKind::tear_meniscus || d.kind == DistractorKind::upper_tear_meniscus;
  };
  for (const DistractorKind kind : {DistractorKind::tear_meniscus, DistractorKind::upper_tear_meniscus}) {
    int seen = 0;
    for (const DistractorTruth& d : truth) seen += d.kind == kind && d.status == PathStatus::ok;
    ASSERT_GE(seen, 2) << to_string(kind);
  }
  EXPECT_NEAR(imaged_over_labelled(result), 1, 1e-4);

  // Each seen meniscus highlight's centroid (its mask's light within 4 px,
  // the point spread's reach) is its label's pixel; those alone there.
  int alone[2] = {0, 0};
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const DistractorTruth& d = truth[k];
    if (!meniscus(d) || d.status != PathStatus::ok) continue;
    bool crowded = false;
    for (std::size_t j = 0; j < truth.size(); ++j) {
      crowded |= j != k && truth[j].status == PathStatus::ok &&
                 std::hypot(truth[j].pixel.u - d.pixel.u, truth[j].pixel.v - d.pixel.v) < 10;
    }
    if (crowded) continue;
    ++alone[d.kind == DistractorKind::upper_tear_meniscus];
    double sum = 0, su = 0, sv = 0;
    for (int y = static_cast<int>(d.pixel.v) - 4; y <= static_cast<int>(d.pixel.v) + 4; ++y) {
      for (int x = static_cast<int>(d.pixel.u) - 4; x <= static_cast<int>(d.pixel.u) + 4; ++x) {
        const double w = double(mask->at(x, y)) * e.at(x, y);
        sum += w;
        su += w * x;  // pixel centres at integer coordinates
        sv += w * y;
      }
    }
    EXPECT_NEAR(sum / result.distractors[k].electrons, 1, 1e-3) << d.illuminator;
    EXPECT_NEAR(su / sum, d.pixel.u, 0.02) << d.illuminator;
    EXPECT_NEAR(sv / sum, d.pixel.v, 0.02) << d.illuminator;
  }
  EXPECT_GE(alone[0], 2);
  EXPECT_GE(alone[1], 2);
}

TEST(TearMeniscus, OnACurvedMarginItsHighlightsObeyTheLawOfReflectionOnTheExactFillet) {
  // The margin a parabola m = -6 + 0.02 x^2 on the spherical globe: the
  // fillet's centres are ((x, m) + r n, sqrt((R + r)^2 - X^2 - Y^2)) in
  // closed form, n = (-m', 1) / sqrt(1 + m'^2). Lights and cameras off the
  // plane x = 0: each highlight found lies r from that curve, and the
  // normal from its nearest centre bisects the directions to the light and
  // the camera.
  // The upper lid's margin is the mirror image, 6 - 0.02 x^2.
  for (const Lid lid : kLids) {
  const auto margin = [](double x) { return kMargin + 0.02 * x * x; };
  const double s = sign(lid);
  const TearMeniscus meniscus =
      TearMeniscus::build(0, lid, Pose(), kRadius, [&](double x) { return s * margin(x); }, kSphere, -9, 9).value();
  const auto centre = [&](double x) {
    const double m1 = 0.04 * x, w = std::sqrt(1 + m1 * m1);
    const double X = x - kRadius * m1 / w, Y = margin(x) + kRadius / w;
    return mirrored(lid, Point3{X, Y, std::sqrt((kGlobe + kRadius) * (kGlobe + kRadius) - X * X - Y * Y)});
  };
  // Also a light and a camera either side of the fillet's mid-arc normal
  // at x = 6 and at x = -7 (their normals by hand: halfway between the
  // wall's, about (-+0.23, 0.97, 0), and the globe's, about
  // (+-0.48, -0.41, 0.78)), 40 mm away: highlights far from the middle.
  std::vector<std::pair<Point3, Point3>> layouts = {{Point3{8, -20, 40}, Point3{-3, -12, 45}},
                                                    {Point3{-150, -300, 600}, Point3{40, -150, 600}}};
  for (const double side : {6.0, -7.0}) {
    const Point3 at{side, -5.3, 9.5};
    const Vector3 h = Vector3{0.25 * side / std::abs(side), 0.56, 0.78} / Vector3{0.25, 0.56, 0.78}.norm();
    const Vector3 e = cross(h, Vector3{0, 0, 1}) / cross(h, Vector3{0, 0, 1}).norm();
    layouts.push_back({at + (h + e * 0.2) * 40, at + (h - e * 0.2) * 40});
  }
  for (auto& [source, target] : layouts) {
    source = mirrored(lid, source);
    target = mirrored(lid, target);
  }
  int found = 0, far_out = 0;
  for (const auto& [source, target] : layouts) {
    for (const Reflection& r : meniscus.highlights(source, target)) {
      ++found;
      if (std::abs(r.point.x) > 4) ++far_out;
      // The nearest centre, by golden-section search.
      double a = r.point.x - 1, b = r.point.x + 1;
      const double g = 0.5 * (std::sqrt(5.0) - 1);
      for (int i = 0; i < 100; ++i) {
        const double c = b - g * (b - a), d = a + g * (b - a);
        if (distance(r.point, centre(c)) < distance(r.point, centre(d))) b = d; else a = c;
      }
      const Point3 nearest = centre(0.5 * (a + b));
      EXPECT_NEAR(distance(r.point, nearest), kRadius, 1e-7) << name(lid) << r.point.x;
      const Vector3 n = (nearest - r.point) / kRadius;
      const Vector3 bisector = (source - r.point) / (source - r.point).norm() + (target - r.point) / (target - r.point).norm();
      EXPECT_LT((n - bisector / bisector.norm()).norm(), 1e-6) << r.point.x;
      // Found again from its own point when the target moves a little (as
      // the radiometry's differences move it), close by.
      const Reflection again = meniscus.highlight_near(meniscus.circle_of(r.point), source, target + Vector3{0.01, 0.01, 0});
      ASSERT_EQ(again.status, PathStatus::ok) << r.point.x;
      EXPECT_LT(distance(again.point, r.point), 0.05) << r.point.x;
    }
  }
  EXPECT_GE(found, 4) << name(lid);
  EXPECT_GE(far_out, 2) << name(lid);  // away from the middle, where the wall's and the point's x differ
  }
}

TEST(TearMeniscus, NeedsAMarginThatCurvesGentlerThanItsRadiusTowardTheOpening) {
  // A margin that bends toward the opening tighter than r (a parabola of
  // curvature 4 / mm at its middle, 1 / r = 3.3 / mm) leaves no room for the
  // fillet there: its circles' centres would run backwards. Bent as
  // tightly away from the opening, it has one. The lower lid's opening is
  // above its margin, the upper's below.
  for (const Lid lid : kLids) {
    for (const double toward : {1.0, -1.0}) {
      const double s = sign(lid), bend = 2.0 * toward * s;
      const auto margin = [s, bend](double x) { return s * kMargin + bend * x * x; };
      const std::optional<TearMeniscus> meniscus = TearMeniscus::build(0, lid, Pose(), kRadius, margin, kSphere, -2, 2);
      EXPECT_EQ(meniscus.has_value(), toward < 0) << name(lid) << toward;
    }
  }
}

TEST(TearMeniscus, TouchesTheCorneaWhereTheLidCrossesIt) {
  // The headset face's lower margin lies over the cornea in the middle
  // (5.5 mm below the centre, inside the limbus), and so does the upper's:
  // the fillet's centres are r from the shell there, the cap's conicoid;
  // the shell's distance checked against a march along the normal of the
  // cornea's sphere.
  Scene scene = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/hard/headset_face.json");
  EyeAppearance look = scene.eyes[0].appearance();
  look.tear_film = TearFilm{};
  scene.eyes[0].set_appearance(look);
  const std::vector<TearMeniscus> menisci = build_tear_menisci(scene);
  ASSERT_EQ(menisci.size(), 2u);
  const Eye& eye = scene.eyes[0];
  const Camera& camera = scene.cameras[0];
  for (const TearMeniscus& meniscus : menisci) {
  int on_cornea = 0;
  for (const Illuminator& led : scene.illuminators) {
    for (const Reflection& r : meniscus.highlights(led.position, camera.center())) {
      // The fillet's centre and the keratometric cornea's sphere.
      const Point3 centre = r.point + r.normal.vector() * meniscus.radius_mm();
      const Vector3 out = centre - eye.cornea_center();
      const double to_cornea = out.norm() - eye.model().anterior_cornea.radius_mm;
      // Where it touches the cornea's sphere: inside the limbus by 0.2 mm,
      // the cap is the nearest of the shell.
      const Point3 touch = eye.eye_from_world() * (eye.cornea_center() + out * (eye.model().anterior_cornea.radius_mm / out.norm()));
      if (std::hypot(touch.x, touch.y) < eye.model().limbus_radius_mm - 0.2) {
        ++on_cornea;
        EXPECT_NEAR(to_cornea, meniscus.radius_mm(), 1e-6) << name(meniscus.lid()) << led.name;
      }
    }
  }
  EXPECT_GE(on_cornea, 3) << name(meniscus.lid());
  }
}

TEST(TearMeniscusHighlights, AMovingEyesHighlightsAreTheWholeExposures) {
  // 400 deg/s of yaw during the exposure: the menisci's highlights move
  // along the lid, and some exist at some instants only. Every highlight
  // drawn is labelled, with the electrons of the whole exposure, each
  // light's along the lid.
  Scene scene = wet_dark_face();
  scene.eyes[0].set_motion({400, 0});
  RenderOptions options;
  options.noise = false;
  const RenderResult result = render(scene, 0, options);
  const std::vector<DistractorTruth>& truth = result.truth.views[0].distractors;
  ASSERT_EQ(truth.size(), result.distractors.size());
  ASSERT_FALSE(truth.empty());
  EXPECT_NEAR(imaged_over_labelled(result), 1, 1e-3);
  // The sclera's, then the lower lid's meniscus's, then the upper's, each
  // by light (docs/labels.md); both lids' there.
  const auto rank = [](const DistractorTruth& d) {
    const int kind = d.kind == DistractorKind::sclera ? 0 : d.kind == DistractorKind::tear_meniscus ? 1 : 2;
    return kind * 100 + d.illuminator;
  };
  for (std::size_t k = 1; k < truth.size(); ++k) EXPECT_LE(rank(truth[k - 1]), rank(truth[k])) << k;
  for (const DistractorKind kind : {DistractorKind::tear_meniscus, DistractorKind::upper_tear_meniscus}) {
    EXPECT_TRUE(std::any_of(truth.begin(), truth.end(), [&](const DistractorTruth& d) { return d.kind == kind; }))
        << to_string(kind);
  }
}

TEST(TearMeniscusHighlights, AreNoneWithoutAFaceOrWithARadiusOf0) {
  Scene scene = wet_dark_face();
  EyeAppearance look = scene.eyes[0].appearance();
  const auto lids = [&](double lower_mm, double upper_mm) {
    look.tear_film->meniscus_radius_mm = lower_mm;
    look.tear_film->upper_meniscus_radius_mm = upper_mm;
    scene.eyes[0].set_appearance(look);
    std::vector<Lid> out;
    for (const TearMeniscus& m : build_tear_menisci(scene)) out.push_back(m.lid());
    return out;
  };
  EXPECT_EQ(lids(0, 0), std::vector<Lid>{});
  EXPECT_EQ(lids(0.3, 0), std::vector<Lid>{Lid::lower});
  EXPECT_EQ(lids(0, 0.25), std::vector<Lid>{Lid::upper});
  EXPECT_EQ(lids(0.3, 0.25), (std::vector<Lid>{Lid::lower, Lid::upper}));
  // The headset with spherical lids and no face: no margin, no meniscus.
  Scene plain = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/hard/headset_wet.json");
  EXPECT_TRUE(build_tear_menisci(plain).empty());
}

}  // namespace
}  // namespace purkinje::renderer
