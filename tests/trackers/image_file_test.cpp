// Image files as the trackers read them, and the overlays they draw.

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "purkinje/trackers/image_file.h"

namespace purkinje::trackers {
namespace {

std::filesystem::path temp(const std::string& name) { return std::filesystem::path(::testing::TempDir()) / name; }

// A 12-bit sensor's values kept in a 16-bit PNG's high bits, as `purkinje
// render` writes them, come back as 12-bit values.
TEST(GreyImageFile, ShiftsHighBitsDownToTheSensorsBits) {
  cv::Mat m(3, 4, CV_16U);
  for (int i = 0; i < 12; ++i) m.at<std::uint16_t>(i / 4, i % 4) = static_cast<std::uint16_t>((i * 341) << 4);
  const std::filesystem::path file = temp("grey_12bit.png");
  ASSERT_TRUE(cv::imwrite(file.string(), m));
  const GreyImage image = read_grey_image(file, 12);
  EXPECT_EQ(image.width, 4);
  EXPECT_EQ(image.height, 3);
  EXPECT_EQ(image.bits, 12);
  for (int i = 0; i < 12; ++i) EXPECT_EQ(image.pixels[i], i * 341) << i;
  const GreyView view = image.view();
  EXPECT_EQ(view.bits, 12);
  EXPECT_EQ(view.bytes_per_pixel, 2);
}

TEST(GreyImageFile, ReadsEightBitFilesAndRefusesWhatItCannotRead) {
  cv::Mat m(2, 2, CV_8U, cv::Scalar(200));
  const std::filesystem::path file = temp("grey_8bit.png");
  ASSERT_TRUE(cv::imwrite(file.string(), m));
  EXPECT_EQ(read_grey_image(file, 8).pixels[3], 200);
  const auto refuses = [](const std::filesystem::path& f, int bits, const std::string& rule) {
    try {
      read_grey_image(f, bits);
      ADD_FAILURE() << f << " read";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(f.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(rule), std::string::npos) << e.what();
    }
  };
  refuses(file, 10, "expected a 16-bit file");
  refuses(file, 0, "bits = 0");
  refuses(temp("nowhere.png"), 8, "cannot be read");
  const std::filesystem::path text = temp("not_an_image.png");
  std::ofstream(text) << "not a PNG";
  refuses(text, 8, "cannot be read");
}

// An overlay shows the part of the image around the labels and detections,
// enlarged, with the labels in green and the detections in red.
TEST(Overlay, DrawsLabelsInGreenAndDetectionsInRedAroundThem) {
  GreyImage image;
  image.width = 400, image.height = 300, image.bits = 8;
  image.pixels.assign(400 * 300, 100);
  EyeInCameraTruth view;
  GlintTruth g;
  g.status = PathStatus::ok;
  g.pixel = {200, 150};
  view.glints = {g};
  view.pupil.ellipse_valid = true;
  view.pupil.ellipse = {{205, 152}, 10, 8, 0.3};
  Detections found;
  Glint d;
  d.centre = {201, 151};
  found.glints = {d};
  found.pupils = {{{206, 153}, Ellipse{{206, 153}, 10, 8, 0.3}, 0.9}};
  const std::filesystem::path file = temp("overlay.png");
  write_overlay(file, image, {view}, found);
  const cv::Mat drawn = cv::imread(file.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(drawn.empty());
  // The labels and detections span 195..216 x 142..163 px; with a margin of
  // 24 px the crop is 70 x 70 px (within the image), enlarged 8 times (the
  // most; 640 px across would take 9): 560 x 560.
  EXPECT_EQ(drawn.cols, 560);
  EXPECT_EQ(drawn.rows, 560);
  int green = 0, red = 0;
  for (int y = 0; y < drawn.rows; ++y) {
    for (int x = 0; x < drawn.cols; ++x) {
      const cv::Vec3b p = drawn.at<cv::Vec3b>(y, x);
      green += p[1] > 150 && p[2] < 80;
      red += p[2] > 200 && p[1] < 80;
    }
  }
  EXPECT_GT(green, 100);
  EXPECT_GT(red, 100);
  EXPECT_THROW(write_overlay(temp("no_folder") / "x.png", image, {view}, found), std::runtime_error);
}

}  // namespace
}  // namespace purkinje::trackers
