// Detections files (another tracker's output, and ours): hand-written
// files, well-formed and malformed, each error naming the line.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <stdexcept>
#include <string>

#include "purkinje/trackers/detections_file.h"

namespace purkinje::trackers {
namespace {

class DetectionsCsv : public ::testing::Test {
 protected:
  std::filesystem::path write(const std::string& contents) {
    const std::filesystem::path file = std::filesystem::path(::testing::TempDir()) /
                                       (std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) +
                                        std::to_string(count_++) + ".csv");
    std::ofstream(file, std::ios::binary) << contents;
    return file;
  }
  // The error's text, or "" when the file is read.
  std::string error_of(const std::string& contents) {
    try {
      read_detections_csv(write(contents));
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }

 private:
  int count_ = 0;
};

TEST_F(DetectionsCsv, ReadsColumnsInAnyOrderWithOptionalOnesLeftOutOrEmpty) {
  const auto d = read_detections_csv(write(
      "feature,v_px,u_px,image,confidence,illuminator\r\n"
      "glint,239.5,316.25,eye_1.png,,3\r\n"
      "\r\n"
      "pupil,234.75,317.5,eye_1.png,0.97,\r\n"
      "glint,10,20,\"a, b.png\",,\r\n"));
  ASSERT_EQ(d.size(), 2u);
  const Detections& e = d.at("eye_1.png");
  ASSERT_EQ(e.glints.size(), 1u);
  EXPECT_EQ(e.glints[0].centre.u, 316.25);
  EXPECT_EQ(e.glints[0].centre.v, 239.5);
  EXPECT_EQ(e.glints[0].illuminator, 3);
  ASSERT_EQ(e.pupils.size(), 1u);
  EXPECT_EQ(e.pupils[0].centre.u, 317.5);
  EXPECT_FALSE(e.pupils[0].ellipse);
  EXPECT_EQ(e.pupils[0].confidence, 0.97);
  EXPECT_EQ(d.at("a, b.png").glints.at(0).illuminator, -1);
}

TEST_F(DetectionsCsv, RoundTripsItsOwnFormat) {
  std::map<std::string, Detections> d;
  Glint g;
  g.centre = {1.5, 2.25};
  g.illuminator = 1;
  d["x.png"].glints = {g};
  d["x.png"].pupils = {{{3.125, 4.5}, Ellipse{{3.125, 4.5}, 10, 8, 0.5}, 0.75}};
  d["y \"q\".png"].pupils = {{{7, 8}, std::nullopt, std::nullopt}};
  const auto back = read_detections_csv(write(detections_csv(d)));
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back.at("x.png").glints.at(0).centre.v, 2.25);
  EXPECT_EQ(back.at("x.png").glints.at(0).illuminator, 1);
  const PupilFound& p = back.at("x.png").pupils.at(0);
  ASSERT_TRUE(p.ellipse);
  EXPECT_EQ(p.ellipse->semi_axis_1_px, 10);
  EXPECT_NEAR(p.ellipse->angle_rad, 0.5, 1e-9);
  EXPECT_EQ(p.confidence, 0.75);
  EXPECT_FALSE(back.at("y \"q\".png").pupils.at(0).ellipse);
}

TEST_F(DetectionsCsv, NamesTheLineColumnAndRuleOfAMalformedRow) {
  const std::string header = "image,feature,u_px,v_px,illuminator,semi_axis_1_px,semi_axis_2_px,angle_deg,confidence\n";
  const std::string good = "a.png,glint,1,2,,,,,\n";
  const auto expect_error = [&](const std::string& contents, const std::string& where, const std::string& rule) {
    const std::string e = error_of(contents);
    EXPECT_NE(e.find(where), std::string::npos) << "expected \"" << where << "\" in: " << e;
    EXPECT_NE(e.find(rule), std::string::npos) << "expected \"" << rule << "\" in: " << e;
  };
  expect_error(header + good + "a.png,glint,abc,2,,,,,\n", ".csv:3: column u_px = \"abc\"", "finite number");
  expect_error(header + good + "a.png,glint,1,nan,,,,,\n", ":3: column v_px = \"nan\"", "finite number");
  expect_error(header + good + "a.png,blink,1,2,,,,,\n", ":3: column feature = \"blink\"", "glint or pupil");
  expect_error(header + "a.png,glint,1,2\n", ":2: 4 cells", "the header has 9");
  expect_error(header + ",glint,1,2,,,,,\n", ":2: column image", "must name an image");
  expect_error(header + "a.png,glint,1,2,,,,,0.5\n", ":2: column confidence", "pupil's column");
  expect_error(header + "a.png,pupil,1,2,0,,,,\n", ":2: column illuminator", "glint's column");
  expect_error(header + "a.png,pupil,1,2,,5,,,\n", ":2: column semi_axis_2_px", "positive number");
  expect_error(header + "a.png,pupil,1,2,,5,4,,\n", ":2: column angle_deg", "must be a number");
  expect_error(header + "a.png,pupil,1,2,,-5,4,0,\n", ":2: column semi_axis_1_px = \"-5\"", "positive");
  expect_error(header + "a.png,pupil,1,2,,,,,1.5\n", ":2: column confidence = \"1.5\"", "[0, 1]");
  expect_error(header + "a.png,glint,1,2,-1,,,,\n", ":2: column illuminator = \"-1\"", "integer from 0");
  expect_error(header + "a.png,glint,1,2,1.5,,,,\n", ":2: column illuminator = \"1.5\"", "integer from 0");
  expect_error(header + "\"a.png,glint,1,2,,,,,\n", ":2:", "not closed");
  expect_error("image,feature,u_px\n", ":1: header", "v_px is missing");
  expect_error("image,feature,u_px,v_px,u_px\n", ":1: header", "\"u_px\" twice");
  expect_error("", ".csv", "header row");
  EXPECT_EQ(error_of(header + good), "");
  EXPECT_THROW(read_detections_csv("/nonexistent/detections.csv"), std::runtime_error);
}

}  // namespace
// Trackers mark a frame where they found nothing in different ways:
// PuRe and ElSe write (-1, -1), others leave the centre empty or write nan.
TEST_F(DetectionsCsv, FailedFramesAsTrackersWriteThemAreFramesWithNothingFound) {
  const DetectionsFile f = parse_detections_file(
      "image,feature,u_px,v_px,confidence\n"
      "a.png,pupil,-1,-1,0\n"
      "b.png,pupil,,,\n"
      "c.png,pupil,nan,nan,-1\n"
      "d.png,pupil,10,20,-1\n",
      "t.csv");
  EXPECT_EQ(f.failure_rows, 3);
  EXPECT_TRUE(f.images.at("a.png").pupils.empty());
  EXPECT_TRUE(f.images.at("b.png").pupils.empty());
  EXPECT_TRUE(f.images.at("c.png").pupils.empty());
  ASSERT_EQ(f.images.at("d.png").pupils.size(), 1u);
  EXPECT_FALSE(f.images.at("d.png").pupils[0].confidence) << "confidence -1 is none";
  EXPECT_TRUE(f.has_pupils);
  EXPECT_FALSE(f.has_glints);
  EXPECT_EQ(f.line_of.at("c.png"), 4);
  // -1 as a float, and confidence -1.0, read alike.
  const DetectionsFile g = parse_detections_file(
      "image,feature,u_px,v_px,confidence\ne.png,pupil,-1.0,-1.0,\nf.png,pupil,3,4,-1.0\n", "t.csv");
  EXPECT_EQ(g.failure_rows, 1);
  EXPECT_FALSE(g.images.at("f.png").pupils.at(0).confidence);
  // Half a centre is an error, not a failure.
  EXPECT_NE(error_of("image,feature,u_px,v_px\na.png,pupil,,3\n").find(":2: column u_px"), std::string::npos);
}

// A spreadsheet's byte-order mark, spaces after commas, and columns of the
// tracker's own (timestamps, ids) are read past.
TEST_F(DetectionsCsv, ReadsPastAByteOrderMarkSpacesAndColumnsItDoesNotKnow) {
  const DetectionsFile f = parse_detections_file(
      "\xEF\xBB\xBFtimestamp_s, image, feature, u_px, v_px, frame_id\n"
      "0.033, a.png, pupil, 10.5, 20.25, 7\n",
      "t.csv");
  EXPECT_EQ(f.ignored_columns, (std::vector<std::string>{"timestamp_s", "frame_id"}));
  ASSERT_EQ(f.images.at("a.png").pupils.size(), 1u);
  EXPECT_EQ(f.images.at("a.png").pupils[0].centre.u, 10.5);
  EXPECT_EQ(f.images.at("a.png").pupils[0].centre.v, 20.25);
  // Inside quotes, spaces are the cell's.
  const DetectionsFile q = parse_detections_file("image,feature,u_px,v_px\n\" my eye.png \", pupil,1,2\n", "t.csv");
  EXPECT_TRUE(q.images.count(" my eye.png "));
}

TEST_F(DetectionsCsv, RefusesAnEllipseAngleBeyondAFullTurn) {
  const std::string header = "image,feature,u_px,v_px,semi_axis_1_px,semi_axis_2_px,angle_deg\n";
  EXPECT_NE(error_of(header + "a.png,pupil,1,2,5,4,400\n").find(":2: column angle_deg = \"400\": must be in [-360, 360]"),
            std::string::npos)
      << error_of(header + "a.png,pupil,1,2,5,4,400\n");
  EXPECT_EQ(error_of(header + "a.png,pupil,1,2,5,4,-359\n"), "");
}

}  // namespace purkinje::trackers
