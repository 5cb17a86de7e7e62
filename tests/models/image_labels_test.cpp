// Reading a rendered image's labels back: the labels of a bundled scene
// (as truth_to_json writes them, with the render block `purkinje render`
// adds) read into the same image-plane values; malformed files name the
// file, key and rule.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "purkinje/models/labels.h"
#include "purkinje/models/scene_file.h"

namespace purkinje {
namespace {

nlohmann::json rendered_labels(const Scene& scene, const SceneTruth& truth) {
  nlohmann::json j = nlohmann::json::parse(truth_to_json(scene, truth));
  j["render"] = {{"camera", 0}, {"files", {{"image", "eye.png"}}}, {"sensor", {{"bits", 10}}}};
  return j;
}

std::filesystem::path write(const nlohmann::json& j, const std::string& name) {
  const std::filesystem::path file = std::filesystem::path(::testing::TempDir()) / name;
  std::ofstream(file) << j.dump();
  return file;
}

// Reading `j` fails with a message naming its file, `key` and `rule`. The
// file is named after the running test: ctest runs tests in parallel.
void expect_error(const nlohmann::json& j, const std::string& key, const std::string& rule) {
  const std::string test = ::testing::UnitTest::GetInstance()->current_test_info()->name();
  const std::filesystem::path file = write(j, "image_labels_bad_" + test + ".json");
  try {
    read_image_labels(file);
    ADD_FAILURE() << key << ": read";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(file.string()), std::string::npos) << what;
    EXPECT_NE(what.find(key), std::string::npos) << what;
    EXPECT_NE(what.find(rule), std::string::npos) << what;
  }
}

TEST(ImageLabels, ReadsBackTheImagePlaneValues) {
  const Scene scene = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/headset.json");
  const SceneTruth truth = compute_truth(scene);
  const std::filesystem::path file = write(rendered_labels(scene, truth), "image_labels_headset.json");
  const ImageLabels labels = read_image_labels(file);
  EXPECT_EQ(labels.image, file.parent_path() / "eye.png");
  EXPECT_EQ(labels.bits, 10);
  EXPECT_EQ(labels.width_px, scene.cameras[0].intrinsics().width);
  EXPECT_EQ(labels.height_px, scene.cameras[0].intrinsics().height);
  ASSERT_EQ(labels.views.size(), 1u);
  const EyeInCameraTruth& read = labels.views[0];
  const EyeInCameraTruth& written = truth.views[0];
  ASSERT_EQ(read.glints.size(), written.glints.size());
  for (std::size_t g = 0; g < read.glints.size(); ++g) {
    EXPECT_EQ(read.glints[g].illuminator, written.glints[g].illuminator);
    EXPECT_EQ(read.glints[g].status, written.glints[g].status);
    if (written.glints[g].status == PathStatus::ok) {
      EXPECT_NEAR(read.glints[g].pixel.u, written.glints[g].pixel.u, 1e-9);
      EXPECT_NEAR(read.glints[g].pixel.v, written.glints[g].pixel.v, 1e-9);
    }
  }
  ASSERT_TRUE(read.pupil.ellipse_valid);
  EXPECT_NEAR(read.pupil.ellipse.center.u, written.pupil.ellipse.center.u, 1e-9);
  EXPECT_NEAR(read.pupil.ellipse.semi_axis_2_px, written.pupil.ellipse.semi_axis_2_px, 1e-9);
  EXPECT_NEAR(read.pupil.ellipse.angle_rad, written.pupil.ellipse.angle_rad, 1e-12);
  ASSERT_EQ(read.pupil.border.size(), written.pupil.border.size());
  EXPECT_EQ(read.pupil.border[5].status, written.pupil.border[5].status);
  EXPECT_EQ(read.pupil.refracted_center_status, written.pupil.refracted_center_status);
}

TEST(ImageLabels, NamesTheFileKeyAndRuleOfABadFile) {
  const Scene scene = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/remote.json");
  const nlohmann::json good = rendered_labels(scene, compute_truth(scene));
  nlohmann::json j = good;
  j["views"][0]["glints"][1]["status"] = "shiny";
  expect_error(j, "views[0].glints[1].status = \"shiny\"", "path status");
  j = good;
  j["views"][0]["glints"][0]["u_px"] = "12";
  expect_error(j, "views[0].glints[0].u_px", "finite number");
  j = good;
  j["views"][0]["glints"][0]["illuminator"] = 7;
  expect_error(j, "views[0].glints[0].illuminator = 7", "integer in [0, 1]");
  j = good;
  j.erase("render");
  expect_error(j, ": render: missing", "labels file of `purkinje render`");
  j = good;
  j["render"]["sensor"]["bits"] = 20;
  expect_error(j, "render.sensor.bits = 20", "[1, 16]");
  j = good;
  j["labels_format"] = 99;
  expect_error(j, "labels_format = 99", "must be 1");
  j = good;
  j["views"][0]["pupil"]["ellipse"]["semi_axis_1_px"] = -1;
  expect_error(j, "semi_axis_1_px", "positive");
  // The image is a name in the labels file's folder: a folder part was
  // read as given (found by fuzzing), reaching images elsewhere.
  const std::vector<std::string> outside = {"../eye.png", "/tmp/eye.png", "sub/eye.png", "eye.png/", "..", ".",
                                            std::string("eye\0.png", 8)};
  for (const std::string& name : outside) {
    j = good;
    j["render"]["files"]["image"] = name;
    expect_error(j, "render.files.image", "a file name in the labels file's folder, without a folder part");
  }

  const std::filesystem::path not_json = std::filesystem::path(::testing::TempDir()) / "image_labels_not.json";
  std::ofstream(not_json) << "{ not json";
  EXPECT_THROW(read_image_labels(not_json), std::runtime_error);
  EXPECT_THROW(read_image_labels("/nonexistent/labels.json"), std::runtime_error);
}

TEST(ImageLabels, ReadsAWetEyesDistractorsAndNamesABadOne) {
  // The headset looking 25 deg aside and 10 up, wet: the sclera mirrors LEDs.
  Scene scene = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/hard/headset_wet.json");
  Eye turned = Eye::with_cornea_center(scene.eyes[0].model(), scene.eyes[0].cornea_center(),
                                       optical_axis_from_yaw_pitch(25 * std::numbers::pi / 180, 10 * std::numbers::pi / 180));
  turned.set_appearance(scene.eyes[0].appearance());
  scene.eyes[0] = turned;
  const SceneTruth truth = compute_truth(scene);
  const std::vector<DistractorTruth>& written = truth.views[0].distractors;
  ASSERT_GE(written.size(), 2u);
  const nlohmann::json good = rendered_labels(scene, truth);
  const ImageLabels labels = read_image_labels(write(good, "image_labels_wet.json"));
  const std::vector<DistractorTruth>& read = labels.views[0].distractors;
  ASSERT_EQ(read.size(), written.size());
  for (std::size_t k = 0; k < read.size(); ++k) {
    EXPECT_EQ(read[k].kind, DistractorKind::sclera);
    EXPECT_EQ(read[k].illuminator, written[k].illuminator);
    EXPECT_EQ(read[k].status, written[k].status);
    EXPECT_NEAR(read[k].pixel.u, written[k].pixel.u, 1e-9);
    EXPECT_NEAR(read[k].pixel.v, written[k].pixel.v, 1e-9);
  }
  // A dry eye's labels have none (and need none).
  const Scene dry = load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/headset.json");
  EXPECT_TRUE(read_image_labels(write(rendered_labels(dry, compute_truth(dry)), "image_labels_dry.json"))
                  .views[0].distractors.empty());

  nlohmann::json j = good;
  j["views"][0]["distractors"][1]["kind"] = "lens";
  expect_error(j, "views[0].distractors[1].kind = \"lens\"", "must be \"sclera\", \"tear_meniscus\", \"upper_tear_meniscus\", \"spectacle_lens_front\" or \"spectacle_lens_back\"");
  j = good;
  j["views"][0]["distractors"][0]["illuminator"] = 8;
  expect_error(j, "views[0].distractors[0].illuminator = 8", "integer in [0, 7]");
  j = good;
  j["views"][0]["distractors"] = 3;
  expect_error(j, "views[0].distractors", "array");
}

// Found by fuzzing (tests/fuzz/corpus/labels/deeply_nested.json): the
// message showed the value with nlohmann's dump(), which recursed once per
// level and overflowed the stack.
TEST(ImageLabels, DeeplyNestedValueGivesAMessageNotACrash) {
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  try {
    parse_image_labels("{\"labels_format\": " + deep + "}", "deep.json");
    ADD_FAILURE() << "a nested array is not a format version";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "deep.json: labels_format = [...]: must be an integer in [0, 1000000]");
  }
  // Values nested 4 deep, as deep as any the reader reads, are still shown whole.
  try {
    parse_image_labels(R"({"labels_format": [[1, {"a": [2]}]]})", "shallow.json");
    ADD_FAILURE() << "an array is not a format version";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()),
              "shallow.json: labels_format = [[1,{\"a\":[2]}]]: must be an integer in [0, 1000000]");
  }
}

}  // namespace
}  // namespace purkinje
