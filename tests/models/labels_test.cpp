#include "purkinje/models/labels.h"
#include "purkinje/models/output_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "purkinje/models/scene_file.h"

namespace purkinje {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Scene two_light_scene() {
  return parse_scene(R"({ "format": 1, "name": "labels",
    "cameras": [ { "name": "cam, left", "resolution_px": [640, 480], "focal_length_mm": 16,
                   "pixel_pitch_mm": 0.006, "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] } ],
    "illuminators": [ { "name": "a", "position_mm": [-100, 0, 0] }, { "name": "b", "position_mm": [100, 0, 0] } ],
    "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} } ] })",
                     "labels.json");
}

// A hand-made truth: one glint found, one not (its fields left NaN, as a
// careless solver might), a pupil with one border point of each kind.
SceneTruth hand_made_truth() {
  SceneTruth truth;
  EyeTruth eye;
  eye.cornea_center = {0, 0, 600};
  eye.rotation_center = {0, 0, 605.7};
  eye.pupil_center = {0, 0, 596.4};
  eye.optical_axis = -UnitVector3::unit_z();
  eye.visual_axis = -UnitVector3::unit_z();
  eye.cornea_radius_mm = 7.8;
  eye.pupil_radius_mm = kNaN;  // must come out as null, not NaN
  truth.eyes.push_back(eye);

  EyeInCameraTruth view;
  GlintTruth found;
  found.illuminator = 0;
  found.status = PathStatus::ok;
  found.pixel = {316.5, 239.25};
  found.reflection.status = PathStatus::ok;
  found.reflection.point = {-0.6, 0, 592.2};
  found.reflection.incidence_rad = 0.1;
  found.reflection.on_cap = true;
  GlintTruth lost;
  lost.illuminator = 1;
  lost.status = PathStatus::no_solution;
  lost.pixel = {kNaN, kNaN};
  lost.reflection.status = PathStatus::no_solution;
  lost.reflection.point = {kNaN, kNaN, kNaN};
  lost.reflection.incidence_rad = kNaN;
  view.glints = {found, lost};

  PupilBorderPointTruth seen;
  seen.angle_rad = 0;
  seen.border_point = {2, 0, 596.4};
  seen.status = PathStatus::ok;
  seen.pixel = {328, 239.5};
  seen.refraction.status = PathStatus::ok;
  seen.refraction.anterior_point = {2.2, 0, 592.6};
  PupilBorderPointTruth hidden;
  hidden.angle_rad = 3.141592653589793;
  hidden.border_point = {-2, 0, 596.4};
  hidden.status = PathStatus::total_internal_reflection;
  hidden.pixel = {kNaN, kNaN};
  hidden.refraction.status = PathStatus::total_internal_reflection;
  hidden.refraction.anterior_point = {kNaN, kNaN, kNaN};
  hidden.refraction.inner_angle_rad = kNaN;
  view.pupil.border = {seen, hidden};
  view.pupil.ellipse_valid = false;
  view.pupil.ellipse.semi_axis_1_px = kNaN;
  view.pupil.refracted_center_status = PathStatus::no_solution;
  view.pupil.refracted_center = {kNaN, kNaN};
  view.pupil.unrefracted_center.status = ProjectionStatus::behind_camera;
  view.pupil.unrefracted_center.pixel = {kNaN, kNaN};
  view.cornea_center.pixel = {319.5, 239.5};
  view.rotation_center.pixel = {319.5, 239.5};
  truth.views.push_back(view);
  return truth;
}

bool mentions_non_finite(const std::string& text) {
  for (const char* word : {"nan", "NaN", "inf", "Infinity"}) {
    if (text.find(word) != std::string::npos) return true;
  }
  return false;
}

TEST(Labels, JsonWritesNullWhereAStatusHasNoValue) {
  const Scene scene = two_light_scene();
  const std::string text = truth_to_json(scene, hand_made_truth());
  EXPECT_FALSE(mentions_non_finite(text)) << text;
  const json j = json::parse(text);

  EXPECT_EQ(j["labels_format"], 1);
  EXPECT_EQ(j["scene"], "labels");
  EXPECT_EQ(j["cameras"][0]["name"], "cam, left");
  EXPECT_DOUBLE_EQ(j["cameras"][0]["cx_px"].get<double>(), 319.5);
  EXPECT_EQ(j["illuminators"].size(), 2u);
  EXPECT_TRUE(j["eyes"][0]["pupil_radius_mm"].is_null());
  EXPECT_DOUBLE_EQ(j["eyes"][0]["cornea_radius_mm"].get<double>(), 7.8);

  const json& glints = j["views"][0]["glints"];
  ASSERT_EQ(glints.size(), 2u);
  EXPECT_EQ(glints[0]["status"], "ok");
  EXPECT_EQ(glints[0]["illuminator_name"], "a");
  EXPECT_DOUBLE_EQ(glints[0]["u_px"].get<double>(), 316.5);
  EXPECT_DOUBLE_EQ(glints[0]["v_px"].get<double>(), 239.25);
  EXPECT_DOUBLE_EQ(glints[0]["point_mm"][2].get<double>(), 592.2);
  EXPECT_NEAR(glints[0]["incidence_deg"].get<double>(), 0.1 * 180 / 3.141592653589793, 1e-12);
  EXPECT_EQ(glints[0]["on_cap"], true);
  EXPECT_EQ(glints[1]["status"], "no_solution");
  for (const char* field : {"u_px", "v_px", "point_mm", "normal", "incident", "reflected",
                            "incidence_deg", "on_cap"}) {
    EXPECT_TRUE(glints[1][field].is_null()) << field;
  }

  const json& pupil = j["views"][0]["pupil"];
  ASSERT_EQ(pupil["border"].size(), 2u);
  EXPECT_DOUBLE_EQ(pupil["border"][0]["u_px"].get<double>(), 328);
  EXPECT_EQ(pupil["border"][1]["status"], "total_internal_reflection");
  EXPECT_TRUE(pupil["border"][1]["u_px"].is_null());
  EXPECT_TRUE(pupil["border"][1]["cornea_point_mm"].is_null());
  EXPECT_DOUBLE_EQ(pupil["border"][1]["angle_deg"].get<double>(), 180);
  // The 3D border point exists whatever its image does.
  EXPECT_DOUBLE_EQ(pupil["border"][1]["border_point_mm"][0].get<double>(), -2);
  EXPECT_TRUE(pupil["ellipse"].is_null());
  EXPECT_TRUE(pupil["refracted_center"]["u_px"].is_null());
  EXPECT_EQ(pupil["unrefracted_center"]["status"], "behind_camera");
  EXPECT_TRUE(pupil["unrefracted_center"]["u_px"].is_null());
}

// A hidden glint or pupil point keeps its pixel (where it would be seen)
// and says what hid it; the pupil's centre too. Other statuses have no
// occluded_by.
TEST(Labels, AnOccludedFeatureKeepsItsPixelAndSaysWhatHidIt) {
  SceneTruth truth = hand_made_truth();
  EyeInCameraTruth& view = truth.views[0];
  view.glints[0].status = PathStatus::occluded;
  view.glints[0].occluder = Occluder::lash;
  view.pupil.border[0].status = PathStatus::occluded;
  view.pupil.border[0].occluder = Occluder::skin;
  view.pupil.refracted_center_status = PathStatus::occluded;
  view.pupil.refracted_center_occluder = Occluder::mesh;
  const json out = json::parse(truth_to_json(two_light_scene(), truth))["views"][0];
  EXPECT_EQ(out["glints"][0]["occluded_by"], "lash");
  EXPECT_EQ(out["glints"][0]["u_px"].get<double>(), 316.5);
  EXPECT_EQ(out["glints"][0]["v_px"].get<double>(), 239.25);
  EXPECT_FALSE(out["glints"][1].contains("occluded_by"));
  EXPECT_EQ(out["pupil"]["border"][0]["occluded_by"], "skin");
  EXPECT_EQ(out["pupil"]["border"][0]["u_px"].get<double>(), 328);
  EXPECT_FALSE(out["pupil"]["border"][1].contains("occluded_by"));
  EXPECT_EQ(out["pupil"]["refracted_center"]["occluded_by"], "mesh");
}

TEST(Labels, TheEyesFaceIsWrittenAsTheSceneGivesIt) {
  EXPECT_TRUE(json::parse(truth_to_json(two_light_scene(), hand_made_truth()))["eyes"][0]["appearance"]["face"].is_null());
  const Scene scene = parse_scene(R"({ "format": 1, "name": "face",
    "cameras": [ { "resolution_px": [640, 480], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                   "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] } ],
    "illuminators": [ { "name": "a", "position_mm": [-100, 0, 0] }, { "name": "b", "position_mm": [100, 0, 0] } ],
    "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {}, "eyelids": {},
                "face": { "side": "left", "canthal_tilt_deg": -3.5, "crease_height_mm": 0 } } ] })",
                                  "face.json");
  const json face = json::parse(truth_to_json(scene, hand_made_truth()))["eyes"][0]["appearance"]["face"];
  EXPECT_EQ(face["side"], "left");
  EXPECT_EQ(face["canthal_tilt_deg"].get<double>(), -3.5);
  EXPECT_EQ(face["crease_height_mm"].get<double>(), 0);
  EXPECT_EQ(face["midline_mm"].get<double>(), 31.5);  // the default
  EXPECT_TRUE(face["lashes"].is_null());
  EXPECT_TRUE(face["brows"].is_null());
  EXPECT_EQ(face.size(), 10u);  // side, the 7 keys, lashes, brows
}

TEST(Labels, TheEyesLashesAreWrittenAsTheSceneGivesThem) {
  const Scene scene = parse_scene(R"({ "format": 1, "name": "lashes",
    "cameras": [ { "resolution_px": [640, 480], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                   "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] } ],
    "illuminators": [ { "name": "a", "position_mm": [-100, 0, 0] }, { "name": "b", "position_mm": [100, 0, 0] } ],
    "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {}, "eyelids": {},
                "face": { "lashes": { "albedo": 0.04, "seed": 12 } } } ] })",
                                  "lashes.json");
  const json lashes = json::parse(truth_to_json(scene, hand_made_truth()))["eyes"][0]["appearance"]["face"]["lashes"];
  EXPECT_EQ(lashes["albedo"].get<double>(), 0.04);
  EXPECT_EQ(lashes["seed"].get<std::uint64_t>(), 12u);
  EXPECT_EQ(lashes["upper_length_mm"].get<double>(), Lashes{}.upper_length_mm);
  EXPECT_EQ(lashes.size(), kLashKeys.size() + 1);
}

TEST(Labels, TheEyesBrowsAreWrittenAsTheSceneGivesThem) {
  const Scene scene = parse_scene(R"({ "format": 1, "name": "brows",
    "cameras": [ { "resolution_px": [640, 480], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                   "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] } ],
    "illuminators": [ { "name": "a", "position_mm": [-100, 0, 0] }, { "name": "b", "position_mm": [100, 0, 0] } ],
    "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {}, "eyelids": {},
                "face": { "brows": { "albedo": 0.25, "seed": 12 } } } ] })",
                                  "brows.json");
  const json face = json::parse(truth_to_json(scene, hand_made_truth()))["eyes"][0]["appearance"]["face"];
  const json& brows = face["brows"];
  EXPECT_EQ(brows["albedo"].get<double>(), 0.25);
  EXPECT_EQ(brows["seed"].get<std::uint64_t>(), 12u);
  EXPECT_EQ(brows["hair_length_mm"].get<double>(), Brows{}.hair_length_mm);
  EXPECT_EQ(brows.size(), kBrowKeys.size() + 1);
  EXPECT_TRUE(face["lashes"].is_null());
}

TEST(Labels, TheIrisFurrowsAndFrecklesAreWrittenOnlyWhenOn) {
  Scene scene = two_light_scene();
  const json plain = json::parse(truth_to_json(scene, hand_made_truth()))["eyes"][0]["appearance"];
  EXPECT_FALSE(plain.contains("iris_furrow_contrast"));
  EXPECT_FALSE(plain.contains("iris_freckles"));
  EyeAppearance look = scene.eyes[0].appearance();
  look.iris_furrow_contrast = 0.6;
  look.iris_freckles = 4;
  scene.eyes[0].set_appearance(look);
  const json on = json::parse(truth_to_json(scene, hand_made_truth()))["eyes"][0]["appearance"];
  EXPECT_EQ(on["iris_furrow_contrast"].get<double>(), 0.6);
  EXPECT_EQ(on["iris_freckles"].get<int>(), 4);
}

TEST(Labels, CsvHasOneRowPerFeatureAndEmptyCellsForMissingValues) {
  const std::string text = truth_to_csv(two_light_scene(), hand_made_truth());
  EXPECT_FALSE(mentions_non_finite(text)) << text;
  std::istringstream in(text);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  // Header, 2 glints, 2 border points, ellipse, two pupil centres, cornea
  // and rotation centres.
  ASSERT_EQ(lines.size(), 1u + 2 + 2 + 1 + 2 + 2);
  EXPECT_EQ(lines[0].rfind("camera,camera_name,eye,feature,index,name,status,u_px,v_px,", 0), 0u);
  // The camera's name has a comma, so it is quoted.
  EXPECT_EQ(lines[1].rfind("0,\"cam, left\",0,glint,0,a,ok,316.5,239.25,-0.6,0,592.2,1,", 0), 0u)
      << lines[1];
  EXPECT_EQ(lines[2].rfind("0,\"cam, left\",0,glint,1,b,no_solution,,,,,,,", 0), 0u) << lines[2];
  EXPECT_NE(lines[4].find("pupil_border,1,,total_internal_reflection,,,-2,0,596.4,,,180,"),
            std::string::npos)
      << lines[4];
  EXPECT_NE(lines[5].find("pupil_ellipse,,,no_fit,"), std::string::npos) << lines[5];
}

class AtomicWrite : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("purkinje_labels_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
            "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::vector<std::string> entries() const {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir_)) out.push_back(e.path().filename().string());
    return out;
  }
  static std::string read(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }

  fs::path dir_;
};

TEST_F(AtomicWrite, WritesTheWholeContentsAndNoTemporaryFile) {
  const std::string contents(100000, 'x');
  write_file_atomically(dir_ / "out.json", contents);
  EXPECT_EQ(read(dir_ / "out.json"), contents);
  EXPECT_EQ(entries(), std::vector<std::string>{"out.json"});
}

TEST_F(AtomicWrite, ReplacesAnExistingFile) {
  write_file_atomically(dir_ / "out.json", "old and longer");
  write_file_atomically(dir_ / "out.json", "new");
  EXPECT_EQ(read(dir_ / "out.json"), "new");
  EXPECT_EQ(entries().size(), 1u);
}

TEST_F(AtomicWrite, FailsNamingTheMissingFolder) {
  const fs::path target = dir_ / "missing" / "out.json";
  try {
    write_file_atomically(target, "x");
    FAIL() << "no exception";
  } catch (const OutputError& e) {
    EXPECT_EQ(std::string(e.what()),
              target.string() + ": cannot write: the folder " + (dir_ / "missing").string() + "/ does not exist");
  }
  EXPECT_TRUE(entries().empty());
}

TEST_F(AtomicWrite, LeavesNoTemporaryFileWhenTheTargetIsADirectory) {
  fs::create_directory(dir_ / "out.json");
  EXPECT_THROW(write_file_atomically(dir_ / "out.json", "x"), std::runtime_error);
  EXPECT_EQ(entries(), std::vector<std::string>{"out.json"});
  EXPECT_TRUE(fs::is_directory(dir_ / "out.json"));
}

}  // namespace
}  // namespace purkinje
