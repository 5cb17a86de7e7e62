// Scoring detections against labels, on hand-made images whose every
// figure is counted by hand below.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "purkinje/trackers/scoring.h"

namespace purkinje::trackers {
namespace {

GlintTruth glint(int light, PathStatus status, Pixel p) {
  GlintTruth g;
  g.illuminator = light;
  g.status = status;
  g.pixel = p;
  return g;
}

// A pupil label centred at c; `seen` border points visible, the rest under a lid.
PupilTruth pupil(Pixel c, int seen) {
  PupilTruth p;
  p.ellipse_valid = true;
  p.ellipse = {c, 10, 8, 0};
  for (int k = 0; k < 4; ++k) {
    PupilBorderPointTruth b;
    b.status = k < seen ? PathStatus::ok : PathStatus::occluded;
    p.border.push_back(b);
  }
  return p;
}

Glint found(Pixel p, int light = -1) {
  Glint g;
  g.centre = p;
  g.illuminator = light;
  return g;
}

// Image a: two glints seen, one on the sclera, a pupil; b: a glint missed,
// the pupil hidden by a lid; c: no pupil at all.
Score hand_made_score() {
  Scorer scorer;
  EyeInCameraTruth a;
  a.glints = {glint(0, PathStatus::ok, {100, 100}), glint(1, PathStatus::ok, {120, 100}),
              glint(2, PathStatus::off_cornea, {140, 100})};
  a.pupil = pupil({110, 110}, 4);
  Detections in_a;
  in_a.glints = {found({100.3, 100.4}, 0),  // 0.5 px, right light
                 found({121, 100}, 2),      // 1 px, wrong light
                 found({140.5, 100}),       // the sclera's glint: not counted
                 found({200, 200})};        // nothing there
  in_a.pupils = {{{110, 112}, std::nullopt, 0.9}};  // 2 px
  scorer.add("a.png", {a}, in_a);

  EyeInCameraTruth b;
  b.glints = {glint(0, PathStatus::ok, {50, 50})};
  b.pupil = pupil({60, 60}, 0);
  Detections in_b;
  in_b.pupils = {{{60.5, 60}, std::nullopt, std::nullopt}};  // by a hidden pupil: not counted
  scorer.add("b.png", {b}, in_b);

  EyeInCameraTruth c;  // no glint, no pupil ellipse
  Detections in_c;
  in_c.pupils = {{{10, 10}, std::nullopt, std::nullopt}};
  scorer.add("c.png", {c}, in_c);
  return scorer.score();
}

TEST(Scorer, CountsFoundMissedFalseAndUncountedDetections) {
  const Score s = hand_made_score();
  EXPECT_EQ(s.images, 3);
  const FeatureSummary& g = s.glints;
  EXPECT_EQ(g.labelled, 3);  // two in a, one in b
  EXPECT_EQ(g.detected, 4);
  EXPECT_EQ(g.found, 2);
  EXPECT_EQ(g.false_positives, 1);
  EXPECT_EQ(g.not_counted, 1);
  EXPECT_DOUBLE_EQ(g.rate_within(1), 2.0 / 3);  // 0.5 and exactly 1 px
  EXPECT_DOUBLE_EQ(g.rate_within(5), 2.0 / 3);
  EXPECT_DOUBLE_EQ(g.false_positive_rate(), 1.0 / 3);  // of the three counted detections
  EXPECT_EQ(g.identity_told, 2);
  EXPECT_EQ(g.identity_correct, 1);
  EXPECT_DOUBLE_EQ(g.identity_rate(), 0.5);
  EXPECT_EQ(g.error_px.count, 2);
  EXPECT_NEAR(g.error_px.mean, 0.75, 1e-12);  // 100.3 is not exact
  EXPECT_NEAR(g.error_px.median, 0.75, 1e-12);
  EXPECT_DOUBLE_EQ(g.error_px.p95, 1.0);  // nearest rank: the 2nd of 2
  EXPECT_DOUBLE_EQ(g.error_px.max, 1.0);

  const FeatureSummary& p = s.pupils;
  EXPECT_EQ(p.labelled, 1);  // b's is wholly hidden, c has none
  EXPECT_EQ(p.detected, 3);
  EXPECT_EQ(p.found, 1);
  EXPECT_EQ(p.within_1px, 0);
  EXPECT_EQ(p.within_2px, 1);
  EXPECT_EQ(p.false_positives, 1);
  EXPECT_EQ(p.not_counted, 1);
  EXPECT_DOUBLE_EQ(p.false_positive_rate(), 0.5);
  EXPECT_DOUBLE_EQ(p.error_px.median, 2.0);
  EXPECT_EQ(p.identity_told, 0);
}

TEST(Scorer, PairsNearestFirstAndLeavesTheFartherDetectionFalse) {
  Scorer scorer;
  EyeInCameraTruth v;
  v.glints = {glint(0, PathStatus::ok, {10, 10}), glint(1, PathStatus::ok, {14, 10})};
  Detections d;
  d.glints = {found({12.2, 10}), found({13.9, 10}), found({10.1, 10})};
  scorer.add("x", {v}, d);
  const Score s = scorer.score();
  // (13.9) takes light 1 at 0.1 px, (10.1) light 0 at 0.1 px; (12.2) is left.
  EXPECT_EQ(s.glints.found, 2);
  EXPECT_EQ(s.glints.false_positives, 1);
  EXPECT_NEAR(s.glints.error_px.max, 0.1, 1e-12);
  // A detection beyond the radius is a miss and a false positive.
  Scorer tight({0.05});
  tight.add("x", {v}, d);
  EXPECT_EQ(tight.score().glints.found, 0);
  EXPECT_EQ(tight.score().glints.false_positives, 3);
  EXPECT_EQ(tight.score().glints.labelled, 2);
}

TEST(Scorer, RanksTheWorstImagesByWrongThenError) {
  const Score s = hand_made_score();
  // a: a false glint, 2 px worst; b: a missed glint; c: a false pupil.
  EXPECT_EQ(worst_images(s, 2), (std::vector<std::string>{"a.png", "b.png"}));
  EXPECT_EQ(worst_images(s, 10).size(), 3u);
  EXPECT_TRUE(worst_images(s, 0).empty());
}

TEST(Scorer, WritesRowsAndSummariesWithoutNaN) {
  const Score s = hand_made_score();
  const std::string csv = score_csv(s);
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "image,feature,eye,illuminator,outcome,label_u_px,label_v_px,u_px,v_px,error_px,identity,nearest_px,"
            "overlap,axes_error_px,angle_error_deg,on_distractor");
  // A found glint's nearest detection is itself; b.png has no glint detection at all.
  EXPECT_NE(csv.find("\na.png,glint,0,1,found,120,100,121,100,1,wrong,1,,,,\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\na.png,glint,,,false_positive,,,200,200,,,,,,,\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\nb.png,glint,0,0,missed,50,50,,,,,,,,,\n"), std::string::npos) << csv;
  EXPECT_EQ(csv.find("nan"), std::string::npos);

  const nlohmann::json j = nlohmann::json::parse(score_json(s));
  EXPECT_EQ(j["images"], 3);
  EXPECT_DOUBLE_EQ(j["glints"]["identity_rate"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(j["pupils"]["within_px"]["2"].get<double>(), 1.0);
  EXPECT_TRUE(j["pupils"].find("identity_rate") == j["pupils"].end());

  const std::string table = score_table(s);
  EXPECT_NE(table.find("3 images"), std::string::npos) << table;
  EXPECT_EQ(table.find("nan"), std::string::npos) << table;

  // Nothing at all scores as zeros, not NaN.
  const Score empty = Scorer().score();
  EXPECT_EQ(score_json(empty).find("nan"), std::string::npos);
  EXPECT_EQ(score_table(empty).find("nan"), std::string::npos);
}

// A perfect tracker's detections score perfectly.
TEST(Scorer, ExactDetectionsAreTheSeenLabels) {
  EyeInCameraTruth a;
  a.glints = {glint(0, PathStatus::ok, {100, 100}), glint(1, PathStatus::off_cornea, {140, 100}),
              glint(2, PathStatus::ok, {120, 100})};
  a.pupil = pupil({110, 110}, 4);
  EyeInCameraTruth hidden;
  hidden.pupil = pupil({60, 60}, 0);
  const Detections d = exact_detections({a, hidden});
  ASSERT_EQ(d.glints.size(), 2u);
  EXPECT_EQ(d.glints[1].illuminator, 2);
  EXPECT_EQ(d.glints[1].centre.u, 120);
  ASSERT_EQ(d.pupils.size(), 1u);  // the hidden pupil is not seen
  EXPECT_EQ(d.pupils[0].centre.v, 110);
  Scorer scorer;
  scorer.add("a", {a, hidden}, d);
  const Score s = scorer.score();
  EXPECT_EQ(s.glints.found, 2);
  EXPECT_EQ(s.glints.identity_correct, 2);
  EXPECT_EQ(s.pupils.found, 1);
  EXPECT_EQ(s.glints.error_px.max + s.pupils.error_px.max, 0);
}

TEST(Scorer, RejectsABadRadius) {
  EXPECT_THROW(Scorer({0}), std::invalid_argument);
  EXPECT_THROW(Scorer({std::nan("")}), std::invalid_argument);
  EXPECT_THROW(hand_made_score().glints.rate_within(3), std::invalid_argument);
}

// Intersection over union of two ellipses by brute force, independent of
// the scorer's own count: a 1000 x 1000 grid over a box holding both.
double overlap_by_grid(const Ellipse& a, const Ellipse& b) {
  const auto in = [](const Ellipse& e, double u, double v) {
    const double du = u - e.center.u, dv = v - e.center.v;
    const double x = du * std::cos(e.angle_rad) + dv * std::sin(e.angle_rad);
    const double y = -du * std::sin(e.angle_rad) + dv * std::cos(e.angle_rad);
    return (x / e.semi_axis_1_px) * (x / e.semi_axis_1_px) + (y / e.semi_axis_2_px) * (y / e.semi_axis_2_px) <= 1;
  };
  int both = 0, either = 0;
  for (int j = 0; j < 1000; ++j) {
    for (int i = 0; i < 1000; ++i) {
      const double u = 70 + 60.0 * (i + 0.5) / 1000, v = 70 + 60.0 * (j + 0.5) / 1000;
      both += in(a, u, v) && in(b, u, v);
      either += in(a, u, v) || in(b, u, v);
    }
  }
  return static_cast<double>(both) / either;
}

TEST(Scorer, TellsTheFalseGlintsThatLieOnALabelledDistractor) {
  // A scleral highlight at (300, 100) the camera sees, another one hidden
  // at (400, 100): a detection by the first is false and on a distractor,
  // by the second false only; a glint is still paired first.
  EyeInCameraTruth view;
  view.glints = {glint(0, PathStatus::ok, {100, 100})};
  DistractorTruth seen, hidden;
  seen.status = PathStatus::ok;
  seen.pixel = {300, 100};
  hidden.status = PathStatus::occluded;
  hidden.pixel = {400, 100};
  view.distractors = {seen, hidden};
  Detections found_in;
  found_in.glints = {found({100.2, 100}), found({303, 100}), found({400, 100}), found({500, 500})};
  Scorer scorer;
  scorer.add("wet.png", {view}, found_in);
  const Score s = scorer.score();
  EXPECT_EQ(s.glints.found, 1);
  EXPECT_EQ(s.glints.false_positives, 3);
  EXPECT_EQ(s.glints.false_positives_on_distractors, 1);
  int on = 0;
  for (const FeatureScore& f : s.features) {
    if (f.on_distractor) {
      ++on;
      EXPECT_EQ(f.outcome, Outcome::false_positive);
      EXPECT_EQ(f.detection->u, 303);
    }
  }
  EXPECT_EQ(on, 1);
  EXPECT_NE(score_table(s).find("false glints on a labelled distractor (a highlight that is no glint): 1 of 3"), std::string::npos)
      << score_table(s);
  EXPECT_NE(score_csv(s).find("\nwet.png,glint,,,false_positive,,,303,100,,,,,,,1\n"), std::string::npos) << score_csv(s);
  EXPECT_EQ(nlohmann::json::parse(score_json(s))["glints"]["false_positives_on_distractors"], 1);
}

// A circle's label: a pupil of radius r about c, every border point seen.
EyeInCameraTruth round_pupil(Pixel c, double r) {
  EyeInCameraTruth view;
  view.pupil = pupil(c, 4);
  view.pupil.ellipse = {c, r, r, 0};
  return view;
}

// Detectors built for real cameras may fit an ellipse to the iris, which
// is concentric with the pupil: the centre is right, the pupil is not.
// Intersection over union of concentric circles is the ratio of their
// areas: (10 / 30)^2 = 0.111 for a 10 px pupil and a 30 px iris.
TEST(Scorer, AnIrisEllipseConcentricWithThePupilIsNotAPupil) {
  Scorer scorer;
  Detections iris, own;
  iris.pupils = {{{100, 100}, Ellipse{{100, 100}, 30, 30, 0}, std::nullopt}};
  own.pupils = {{{100.2, 100}, Ellipse{{100.2, 100}, 10.5, 9.5, 0.3}, std::nullopt}};
  scorer.add("iris.png", {round_pupil({100, 100}, 10)}, iris);
  scorer.add("pupil.png", {round_pupil({100, 100}, 10)}, own);
  const Score s = scorer.score();
  EXPECT_EQ(s.pupils.labelled, 2);
  EXPECT_EQ(s.pupils.found, 1);
  EXPECT_EQ(s.pupils.wrong_shape, 1);
  EXPECT_DOUBLE_EQ(s.pupils.false_positive_rate(), 0.5);
  for (const FeatureScore& f : s.features) {
    if (f.image == "iris.png" && f.detection) {
      EXPECT_EQ(f.outcome, Outcome::wrong_shape);
      EXPECT_NEAR(*f.overlap, 1.0 / 9, 0.01);
      EXPECT_NEAR(*f.axes_error_px, 20, 1e-12);
      EXPECT_FALSE(f.angle_error_deg) << "a circle's angle means nothing";
    }
    if (f.image == "pupil.png") {
      EXPECT_EQ(f.outcome, Outcome::found);
      // The scorer's 128 x 128 count, within 1% of a finer count's.
      const double expected = overlap_by_grid({{100, 100}, 10, 10, 0}, {{100.2, 100}, 10.5, 9.5, 0.3});
      EXPECT_GT(expected, 0.85);
      EXPECT_NEAR(*f.overlap, expected, 0.01);
      EXPECT_NEAR(*f.axes_error_px, 0.5, 1e-12);
    }
  }
  // Both fits reported, the iris's centre nearer: the pupil's still pairs.
  Detections both;
  both.pupils = {{{100, 100}, Ellipse{{100, 100}, 30, 30, 0}, std::nullopt},
                 {{100.3, 100}, Ellipse{{100.3, 100}, 10, 10, 0}, std::nullopt}};
  Scorer two;
  two.add("both.png", {round_pupil({100, 100}, 10)}, both);
  EXPECT_EQ(two.score().pupils.found, 1);
  EXPECT_EQ(two.score().pupils.wrong_shape, 1);
  EXPECT_NEAR(two.score().pupils.error_px.max, 0.3, 1e-12);
  // With the check off, centres alone decide.
  ScoringSettings centres_only;
  centres_only.min_pupil_overlap = 0;
  Scorer lenient(centres_only);
  lenient.add("iris.png", {round_pupil({100, 100}, 10)}, iris);
  EXPECT_EQ(lenient.score().pupils.found, 1);
}

// The error over the found is over those within the radius only; a
// tracker that finds 2 pupils of 10 looks precise there. The figures over
// all labels count the 8 without a detection.
TEST(Scorer, FiguresOverAllLabelsCountTheMisses) {
  Scorer scorer;
  for (int i = 0; i < 10; ++i) {
    Detections d;
    if (i < 2) d.pupils = {{{100.1, 100}, std::nullopt, std::nullopt}};
    if (i == 2) d.pupils = {{{140, 100}, std::nullopt, std::nullopt}};  // 40 px off: a false positive and a miss
    std::string image = "i";  // appended: g++ 12's false -Wrestrict on "i" + std::string
    image += std::to_string(i) + ".png";
    scorer.add(image, {round_pupil({100, 100}, 10)}, d);
  }
  const Score s = scorer.score();
  EXPECT_NEAR(s.pupils.error_px.median, 0.1, 1e-9);
  EXPECT_EQ(s.pupils.nearest_px.count, 10);
  EXPECT_EQ(s.pupils.nearest_px.none, 7);
  EXPECT_TRUE(std::isinf(s.pupils.nearest_px.median));
  EXPECT_TRUE(std::isinf(s.pupils.nearest_px.max));
  const nlohmann::json j = nlohmann::json::parse(score_json(s));
  EXPECT_TRUE(j["pupils"]["nearest_px"]["median"].is_null());
  EXPECT_EQ(j["pupils"]["nearest_px"]["none"], 7);
  EXPECT_NE(score_table(s).find("over all labels"), std::string::npos);
}

// A pupil-only tracker's glints are not "0 of N found": they are not scored.
TEST(Scorer, AFeatureTheTrackerDoesNotReportIsNotScored) {
  ScoringSettings settings;
  settings.score_glints = false;
  Scorer scorer(settings);
  EyeInCameraTruth view = round_pupil({100, 100}, 10);
  view.glints = {glint(0, PathStatus::ok, {90, 90})};
  Detections d;
  d.pupils = {{{100, 100}, std::nullopt, std::nullopt}};
  scorer.add("a.png", {view}, d);
  const Score s = scorer.score();
  EXPECT_EQ(s.glints.labelled, 0);
  EXPECT_EQ(s.pupils.found, 1);
  EXPECT_NE(score_table(s).find("glints      not in the detections file: not scored"), std::string::npos)
      << score_table(s);
  EXPECT_EQ(nlohmann::json::parse(score_json(s))["glints"]["reported"], false);
}

}  // namespace
}  // namespace purkinje::trackers
