// Data sets from dataset specs: every drawn value reaches the labels (as
// the physical quantity it changes, not only as a copy) and the table;
// shards together are the whole set byte for byte; a killed run resumes;
// merge refuses what is not N shards of one set.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "purkinje/models/dataset_spec.h"
#include "purkinje/models/input_file.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/studies/generate.h"
#include "purkinje/studies/render_set.h"

namespace purkinje::studies {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

const std::string kSource = PURKINJE_SOURCE_DIR;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("generate_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir;
}

// A spec file in `dir` over a bundled scene.
fs::path write_spec(const fs::path& dir, const std::string& scene, const std::string& body, int count = 3) {
  fs::create_directories(dir);
  const fs::path file = dir / "spec.json";
  std::ofstream(file) << R"({"dataset_format": 1, "name": "t", "scene": ")" << kSource << "/assets/scenes/" << scene
                      << R"(.json", "count": )" << count << (body.empty() ? "" : ", ") << body << "}";
  return file;
}

GenerateOutcome run(const fs::path& spec, const fs::path& out, Shard shard = {}, bool resume = false) {
  GenerateRequest request;
  request.spec_file = spec;
  request.output_dir = out;
  request.shard = shard;
  request.resume = resume;
  return generate(plan_generate(request));
}

std::map<std::string, std::string> folder_bytes(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    files[e.path().filename().string()] = read_input_file(e.path(), std::uintmax_t{1} << 30, "a test file");
  }
  return files;
}

std::vector<std::map<std::string, std::string>> read_table(const fs::path& file) {
  std::ifstream in(file);
  std::string line;
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;
  const auto cells = [](const std::string& text) {
    std::vector<std::string> out;
    std::stringstream s(text);
    for (std::string cell; std::getline(s, cell, ',');) out.push_back(cell);
    if (!text.empty() && text.back() == ',') out.emplace_back();
    return out;
  };
  std::getline(in, line);
  header = cells(line);
  while (std::getline(in, line)) {
    const std::vector<std::string> values = cells(line);
    EXPECT_EQ(values.size(), header.size()) << line;
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < header.size() && i < values.size(); ++i) row[header[i]] = values[i];
    rows.push_back(row);
  }
  return rows;
}

json labels_of(const fs::path& file) { return json::parse(read_input_file(file, 1 << 26, "labels")); }

// Every parameter a scene has, varied at once (docs/dataset-format.md).
const char* const kEveryParameter = R"("gaze": {"cone_deg": 20}, "parameters": {
    "pupil_radius_mm": {"uniform": [1, 3]},
    "eye_offset_x_mm": {"uniform": [-10, 10]}, "eye_offset_y_mm": {"uniform": [-10, 10]},
    "eye_offset_z_mm": {"uniform": [-10, 10]},
    "head_yaw_deg": {"uniform": [-10, 10]}, "head_pitch_deg": {"uniform": [-10, 10]},
    "head_roll_deg": {"uniform": [-10, 10]},
    "lid_opening": {"uniform": [0.5, 1]}, "blink": {"choice": [false, true]}, "iris_seed": {"uniform": [1, 1000]},
    "iris_texture_contrast": {"uniform": [0, 1]}, "iris_albedo": {"uniform": [0.1, 0.4]},
    "sclera_albedo": {"uniform": [0.4, 0.7]}, "skin_albedo": {"uniform": [0.3, 0.6]},
    "fundus_reflectance": {"uniform": [0, 0.2]},
    "cornea_radius_mm": {"uniform": [7.5, 8.1]}, "cornea_asphericity": {"uniform": [-0.5, 0]},
    "posterior_cornea": {"choice": [false, true]},
    "kappa_horizontal_deg": {"uniform": [2, 7]}, "kappa_vertical_deg": {"uniform": [0, 3]},
    "rotation_center_depth_mm": {"uniform": [12.5, 14]},
    "led_power_scale": {"uniform": [0.5, 2]},
    "exposure_s": {"uniform": [0.002, 0.008]}, "gain": {"uniform": [1, 2]},
    "read_noise_e": {"uniform": [2, 8]}, "noise": {"choice": [false, true]},
    "focus_distance_mm": {"uniform": [500, 700]}, "bits": {"choice": [8, 12]},
    "illuminators": {"led_left": {"power_scale": {"uniform": [0.5, 1]}, "on": {"choice": [false, true]}}},
    "meshes": {"glasses_frame": {"on": {"choice": [false, true]}}},
    "spectacle_lenses": {"right_lens": {"on": {"choice": [false, true]}}}})";

constexpr double kDeg = std::numbers::pi / 180;

double vector_angle_deg(const json& a, const json& b) {
  double dot = 0, na = 0, nb = 0;
  for (int i = 0; i < 3; ++i) {
    dot += a[i].get<double>() * b[i].get<double>();
    na += a[i].get<double>() * a[i].get<double>();
    nb += b[i].get<double>() * b[i].get<double>();
  }
  return std::acos(std::clamp(dot / std::sqrt(na * nb), -1.0, 1.0)) / kDeg;
}

class EveryParameter : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fresh_dir("every"));
    const fs::path spec_file = write_spec(*dir_, "remote_glasses", kEveryParameter, 4);
    run(spec_file, *dir_ / "set");
    spec_ = new DatasetSpec(load_dataset_spec(spec_file));
    rows_ = new std::vector<std::map<std::string, std::string>>(read_table(*dir_ / "set" / "table.csv"));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
    delete spec_;
    delete rows_;
  }

  // For each image: the drawn value, the labels' record of it and the
  // table's cell, all equal; then `physical(labels, drawn)` checks the
  // quantity it changed.
  template <class Check>
  void expect_reaches(const std::string& name, Check physical) {
    ASSERT_EQ(rows_->size(), 4u);
    for (std::uint64_t k = 0; k < 4; ++k) {
      const ImageDraw draw = draw_image(*spec_, k);
      double drawn = 0;
      bool found = false;
      for (std::size_t i = 0; i < spec_->parameters.size(); ++i) {
        if (spec_->parameters[i].name == name) {
          drawn = draw.values[i];
          found = true;
        }
      }
      ASSERT_TRUE(found) << name;
      const json labels = labels_of(*dir_ / "set" / ("t_00000" + std::to_string(k) + "_cam0.json"));
      const json& recorded = labels.at("dataset").at("parameters").at(name);
      const double recorded_value = recorded.is_boolean() ? recorded.get<bool>() : recorded.get<double>();
      EXPECT_EQ(recorded_value, drawn) << name << " image " << k;
      const std::string cell = rows_->at(k).at(name);
      const double cell_value = cell == "true" ? 1 : cell == "false" ? 0 : std::stod(cell);
      EXPECT_EQ(cell_value, drawn) << name << " image " << k << ": " << cell;
      physical(labels, drawn);
    }
  }

  static fs::path* dir_;
  static DatasetSpec* spec_;
  static std::vector<std::map<std::string, std::string>>* rows_;
};
fs::path* EveryParameter::dir_ = nullptr;
DatasetSpec* EveryParameter::spec_ = nullptr;
std::vector<std::map<std::string, std::string>>* EveryParameter::rows_ = nullptr;

const json& eye(const json& labels) { return labels.at("eyes").at(0); }
const json& look(const json& labels) { return eye(labels).at("appearance"); }
const json& sensor(const json& labels) { return labels.at("render").at("sensor"); }

TEST_F(EveryParameter, GazeTurnIsTheAngleFromTheScenesGaze) {
  const Scene base = load_scene(kSource + "/assets/scenes/remote_glasses.json");
  const json base_axis = {base.eyes[0].visual_axis().x(), base.eyes[0].visual_axis().y(), base.eyes[0].visual_axis().z()};
  expect_reaches("gaze_turn_deg", [&](const json& l, double v) {
    EXPECT_NEAR(vector_angle_deg(eye(l).at("visual_axis"), base_axis), v, 1e-9);
  });
  expect_reaches("gaze_direction_deg", [](const json&, double v) { EXPECT_TRUE(v >= 0 && v <= 360); });
}

TEST_F(EveryParameter, EyeOffsetsMoveTheRotationCentre) {
  const Scene base = load_scene(kSource + "/assets/scenes/remote_glasses.json");
  const Point3 c = base.eyes[0].rotation_center();
  const double base_xyz[3] = {c.x, c.y, c.z};
  const char* names[3] = {"eye_offset_x_mm", "eye_offset_y_mm", "eye_offset_z_mm"};
  for (int axis = 0; axis < 3; ++axis) {
    expect_reaches(names[axis], [&](const json& l, double v) {
      EXPECT_NEAR(eye(l).at("rotation_center_mm")[axis].get<double>() - base_xyz[axis], v, 1e-9);
    });
  }
}

TEST_F(EveryParameter, HeadAnglesTurnTheHeadFrame) {
  // Yaw then pitch: forward leaves the base's by acos(cos yaw cos pitch).
  std::vector<double> yaw(4);
  int k = 0;
  expect_reaches("head_yaw_deg", [&](const json&, double v) { yaw[k++] = v; });
  k = 0;
  expect_reaches("head_pitch_deg", [&](const json& l, double v) {
    const json base_forward = {0, 0, -1};
    EXPECT_NEAR(std::cos(vector_angle_deg(look(l).at("head_forward"), base_forward) * kDeg),
                std::cos(yaw[k] * kDeg) * std::cos(v * kDeg), 1e-12);
    ++k;
  });
  expect_reaches("head_roll_deg", [](const json& l, double) {
    EXPECT_NEAR(vector_angle_deg(look(l).at("head_forward"), look(l).at("head_up")), 90, 1e-9);
  });
}

TEST_F(EveryParameter, LidsIrisAndAlbedosAreTheDrawnOnes) {
  std::vector<double> blink(4);
  int k = 0;
  expect_reaches("blink", [&](const json&, double v) { blink[k++] = v; });
  k = 0;
  expect_reaches("lid_opening", [&](const json& l, double v) {
    EXPECT_EQ(look(l).at("lid_opening").get<double>(), blink[k++] != 0 ? 0.0 : v);
  });
  expect_reaches("iris_seed", [](const json& l, double v) { EXPECT_EQ(look(l).at("iris_seed").get<double>(), v); });
  for (const char* name : {"iris_texture_contrast", "iris_albedo", "sclera_albedo", "skin_albedo", "fundus_reflectance"}) {
    expect_reaches(name, [&](const json& l, double v) { EXPECT_EQ(look(l).at(name).get<double>(), v) << name; });
  }
}

TEST_F(EveryParameter, TheEyeModelIsTheDrawnOne) {
  expect_reaches("pupil_radius_mm", [](const json& l, double v) { EXPECT_EQ(eye(l).at("pupil_radius_mm").get<double>(), v); });
  expect_reaches("cornea_radius_mm", [](const json& l, double v) { EXPECT_EQ(eye(l).at("cornea_radius_mm").get<double>(), v); });
  expect_reaches("cornea_asphericity", [](const json& l, double v) { EXPECT_EQ(eye(l).at("cornea_asphericity").get<double>(), v); });
  expect_reaches("posterior_cornea", [](const json& l, double v) { EXPECT_EQ(eye(l).at("posterior_cornea").get<bool>(), v != 0); });
  expect_reaches("kappa_horizontal_deg", [](const json& l, double v) {
    EXPECT_NEAR(eye(l).at("kappa_deg").at("horizontal").get<double>(), v, 1e-12);
  });
  expect_reaches("kappa_vertical_deg", [](const json& l, double v) {
    EXPECT_NEAR(eye(l).at("kappa_deg").at("vertical").get<double>(), v, 1e-12);
  });
  expect_reaches("rotation_center_depth_mm", [](const json& l, double v) {
    EXPECT_EQ(eye(l).at("rotation_center_depth_mm").get<double>(), v);
  });
}

TEST_F(EveryParameter, LightsAndSensorAreTheDrawnOnes) {
  const Scene base = load_scene(kSource + "/assets/scenes/remote_glasses.json");
  std::vector<double> power(4), left_scale(4), left_on(4);
  int k = 0;
  expect_reaches("led_power_scale", [&](const json&, double v) { power[k++] = v; });
  k = 0;
  expect_reaches("illuminator.led_left.power_scale", [&](const json&, double v) { left_scale[k++] = v; });
  k = 0;
  expect_reaches("illuminator.led_left.on", [&](const json& l, double v) {
    left_on[k] = v;
    std::map<std::string, double> intensity;
    for (const json& light : l.at("illuminators")) intensity[light.at("name")] = light.at("radiant_intensity_w_sr");
    EXPECT_EQ(intensity.count("led_left"), v != 0 ? 1u : 0u);
    if (v != 0) {
      EXPECT_DOUBLE_EQ(intensity["led_left"], base.illuminators[0].radiant_intensity_w_sr * power[k] * left_scale[k]);
    }
    EXPECT_DOUBLE_EQ(intensity["led_right"], base.illuminators[1].radiant_intensity_w_sr * power[k]);
    ++k;
  });
  // An LED switched off has no glint: the table says so.
  for (std::size_t i = 0; i < 4; ++i) {
    if (left_on[i] == 0) EXPECT_EQ(rows_->at(i).at("glint.led_left.status"), "off");
    else EXPECT_NE(rows_->at(i).at("glint.led_left.status"), "off");
  }
  for (const char* name : {"exposure_s", "gain", "read_noise_e", "focus_distance_mm"}) {
    expect_reaches(name, [&](const json& l, double v) { EXPECT_EQ(sensor(l).at(name).get<double>(), v) << name; });
  }
  expect_reaches("noise", [](const json& l, double v) { EXPECT_EQ(sensor(l).at("noise").get<bool>(), v != 0); });
  expect_reaches("bits", [](const json& l, double v) { EXPECT_EQ(sensor(l).at("bits").get<double>(), v); });
  expect_reaches("mesh.glasses_frame.on", [](const json&, double v) { EXPECT_TRUE(v == 0 || v == 1); });
  // A lens left out mirrors nothing: its ghosts are in the labels or not.
  expect_reaches("spectacle_lens.right_lens.on", [](const json& l, double v) {
    int ghosts = 0;
    for (const json& d : l.at("views").at(0).at("distractors")) ghosts += d.value("spectacle_lens_name", "") == "right_lens";
    EXPECT_EQ(ghosts > 0, v != 0);
  });
}

TEST_F(EveryParameter, TheTableRecordsTheFilesAndTheTruth) {
  for (std::size_t k = 0; k < rows_->size(); ++k) {
    const auto& row = rows_->at(k);
    EXPECT_EQ(row.at("index"), std::to_string(k));
    const json labels = labels_of(*dir_ / "set" / row.at("labels"));
    // Files as the labels check them.
    const FileCheck image = file_check_of_file(*dir_ / "set" / row.at("image"));
    EXPECT_EQ(row.at("image_bytes"), std::to_string(image.bytes));
    EXPECT_EQ(row.at("image_crc32"), crc32_text(image.crc32));
    const FileCheck labels_check = file_check_of_file(*dir_ / "set" / row.at("labels"));
    EXPECT_EQ(row.at("labels_crc32"), crc32_text(labels_check.crc32));
    EXPECT_EQ(row.at("seed"), labels.at("render").at("seed").dump());
    // The pupil centre's pixel, as the labels' view says.
    const json& view = labels.at("views").at(0);
    if (view.at("pupil").at("refracted_center").at("status") == "ok") {
      EXPECT_EQ(std::stod(row.at("pupil.u_px")), view.at("pupil").at("refracted_center").at("u_px").get<double>());
    }
    EXPECT_EQ(std::stod(row.at("eye.pupil_radius_mm")), eye(labels).at("pupil_radius_mm").get<double>());
  }
}

TEST(Generate, ShardsTogetherAreTheWholeSetByteForByte) {
  const fs::path dir = fresh_dir("shards");
  const fs::path spec = write_spec(dir, "remote", R"("gaze": {"cone_deg": 25}, "outputs": {"exr": {"planes": ["Y", "id"]}},
      "parameters": {"pupil_radius_mm": {"uniform": [1, 3]}, "iris_seed": {"uniform": [1, 99]}})", 6);
  const GenerateOutcome whole = run(spec, dir / "whole");
  EXPECT_EQ(whole.rendered, 6u);
  for (std::uint64_t i = 0; i < 4; ++i) EXPECT_EQ(run(spec, dir / "sharded", {i, 4}).rendered, i < 2 ? 2u : 1u);
  EXPECT_FALSE(fs::exists(dir / "sharded" / "table.csv"));
  const MergeOutcome merged = merge_shards(dir / "sharded");
  EXPECT_EQ(merged.shards, 4u);
  EXPECT_EQ(merged.rows, 6u);
  const auto expected = folder_bytes(dir / "whole");
  auto found = folder_bytes(dir / "sharded");
  EXPECT_EQ(expected.size(), 6u * 4 + 2);  // PNG, classes, EXR, labels; table and manifest
  for (const auto& [name, bytes] : expected) {
    ASSERT_TRUE(found.count(name)) << name;
    EXPECT_TRUE(found.at(name) == bytes) << name;
    found.erase(name);
  }
  for (const auto& [name, bytes] : found) EXPECT_NE(name.find(".shard-"), std::string::npos) << name;
  // Merged again (a retry) gives the same bytes.
  merge_shards(dir / "sharded");
  EXPECT_TRUE(folder_bytes(dir / "sharded").at("manifest.json") == expected.at("manifest.json"));
  fs::remove_all(dir);
}

TEST(Generate, ATrialIsTheSetsFirstImages) {
  const fs::path dir = fresh_dir("trial");
  const fs::path spec = write_spec(dir, "remote", R"("parameters": {"pupil_radius_mm": {"uniform": [1, 3]}})", 3);
  run(spec, dir / "set");
  GenerateRequest trial;
  trial.spec_file = spec;
  trial.output_dir = dir / "trial";
  trial.count = 2;  // --count 2
  generate(plan_generate(trial));
  const auto set = folder_bytes(dir / "set");
  for (const auto& [name, bytes] : folder_bytes(dir / "trial")) {
    if (name == "table.csv" || name == "manifest.json") continue;
    EXPECT_TRUE(set.at(name) == bytes) << name;
  }
  EXPECT_FALSE(fs::exists(dir / "trial" / "t_000002_cam0.png"));
  fs::remove_all(dir);
}

TEST(Generate, AKilledRunResumesToTheSameBytes) {
  const fs::path dir = fresh_dir("resume");
  const fs::path spec = write_spec(dir, "remote", R"("parameters": {"pupil_radius_mm": {"uniform": [1, 3]}})", 3);
  run(spec, dir / "set");
  const auto expected = folder_bytes(dir / "set");
  // What a kill leaves: an image gone, one whose file no longer matches
  // its labels, no table or manifest.
  fs::remove(dir / "set" / "t_000000_cam0.png");
  std::ofstream(dir / "set" / "t_000002_cam0_classes.png", std::ios::app) << "x";
  fs::remove(dir / "set" / "table.csv");
  fs::remove(dir / "set" / "manifest.json");
  const GenerateOutcome resumed = run(spec, dir / "set", {}, true);
  EXPECT_EQ(resumed.resumed, 1u);
  EXPECT_EQ(resumed.rendered, 2u);
  EXPECT_TRUE(folder_bytes(dir / "set") == expected);
  fs::remove_all(dir);
}

TEST(Generate, ResumeRefusesAnotherSetsImages) {
  const fs::path dir = fresh_dir("other");
  run(write_spec(dir / "a", "remote", R"("seed": 1)", 1), dir / "set");
  try {
    run(write_spec(dir / "b", "remote", R"("seed": 2)", 1), dir / "set", {}, true);
    FAIL() << "resumed another set";
  } catch (const ResumeRefused& e) {
    EXPECT_NE(std::string(e.what()).find("t_000000_cam0.json: an image of another data set"), std::string::npos)
        << e.what();
  }
  fs::remove_all(dir);
}

TEST(Generate, MergeRefusesWhatIsNotTheShardsOfOneSet) {
  const fs::path dir = fresh_dir("merge");
  const fs::path spec = write_spec(dir, "remote", "", 2);
  const auto message = [&] {
    try {
      merge_shards(dir / "set");
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("(merged)");
  };
  fs::create_directories(dir / "set");
  EXPECT_NE(message().find("no shard manifests (manifest.shard-I-of-N.json)"), std::string::npos) << message();
  run(spec, dir / "set", {0, 2});
  EXPECT_NE(message().find("manifest.shard-1-of-2.json: missing: shard 1 of 2 has not finished"), std::string::npos)
      << message();
  run(spec, dir / "set", {1, 2});
  std::ofstream(dir / "set" / "table.shard-1-of-2.csv", std::ios::app) << "1,cam0\n";
  EXPECT_NE(message().find("table.shard-1-of-2.csv: SHA-1 "), std::string::npos) << message();
  run(write_spec(dir / "other", "remote", R"("seed": 5)", 2), dir / "set", {1, 2});
  EXPECT_NE(message().find("manifest.shard-1-of-2.json: spec_sha1 "), std::string::npos) << message();
  run(spec, dir / "set", {1, 2});
  run(spec, dir / "set", {0, 3});
  EXPECT_NE(message().find("shards of 2 and of 3 shards side by side"), std::string::npos) << message();
  fs::remove(dir / "set" / "manifest.shard-0-of-3.json");
  // A shard number no 64-bit count holds is named; names that only look
  // like a shard manifest's are left alone.
  std::ofstream(dir / "set" / "manifest.shard-0-of-18446744073709551616.json") << "{}";
  EXPECT_NE(message().find("manifest.shard-0-of-18446744073709551616.json: a shard number beyond 18446744073709551615"),
            std::string::npos)
      << message();
  fs::remove(dir / "set" / "manifest.shard-0-of-18446744073709551616.json");
  for (const char* decoy : {"manifest.shard-0-of-3.json.bak", "manifest.shard-x-of-3.json", "manifest.shard-0-of-3-of-4.json",
                            "manifest.shard--of-3.json", "manifest.shard-.json",
                            "manifest.shard-18446744073709551616-of-x.json"}) {
    std::ofstream(dir / "set" / decoy) << "{}";
  }
  EXPECT_EQ(message(), "(merged)");
  fs::remove_all(dir);
}

TEST(Generate, PlanRefusesABadShardBadExrPlanesAndCamerasNamedAlike) {
  const fs::path dir = fresh_dir("plan");
  GenerateRequest request;
  request.spec_file = write_spec(dir, "remote", R"("outputs": {"exr": {"planes": ["Y", "albedo"]}})", 2);
  request.output_dir = dir / "set";
  try {
    plan_generate(request);
    FAIL() << "planned";
  } catch (const DatasetSpecError& e) {
    EXPECT_NE(std::string(e.what()).find("outputs.exr.planes = \"albedo\": the render has no such plane (valid: Y, electrons"),
              std::string::npos)
        << e.what();
  }
  // A light's glint plane, the light switched off in some images.
  request.spec_file = write_spec(dir, "remote", R"("outputs": {"exr": {"planes": ["glint.led_left"]}},
      "parameters": {"illuminators": {"led_left": {"on": {"choice": [true, false]}}}})", 2);
  try {
    plan_generate(request);
    FAIL() << "planned";
  } catch (const DatasetSpecError& e) {
    EXPECT_NE(std::string(e.what()).find("outputs.exr.planes = \"glint.led_left\": its illuminator is switched off"),
              std::string::npos)
        << e.what();
  }
  // Two cameras whose names make the same file names.
  std::ofstream(dir / "two_cameras.json") << R"({"format": 1, "cameras": [
      {"name": "a b", "resolution_px": [64, 48], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
       "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600]},
      {"name": "a_b", "resolution_px": [64, 48], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
       "position_mm": [10, 0, 0], "look_at_mm": [0, 0, 600]}],
      "eyes": [{"position": {"cornea_center_mm": [0, 0, 600]}, "orientation": {}}]})";
  std::ofstream(dir / "two_cameras_spec.json") << R"({"dataset_format": 1, "scene": "two_cameras.json", "count": 1})";
  request.spec_file = dir / "two_cameras_spec.json";
  try {
    plan_generate(request);
    FAIL() << "planned";
  } catch (const DatasetSpecError& e) {
    EXPECT_NE(std::string(e.what()).find("two cameras would both write two_cameras_spec_000000_a_b."), std::string::npos)
        << e.what();
  }
  request.spec_file = write_spec(dir, "remote", "", 2);
  request.shard = {4, 4};
  EXPECT_THROW(plan_generate(request), std::invalid_argument);
  // A shard of a set smaller than the split has no images, and is fine.
  request.shard = {3, 4};
  EXPECT_TRUE(plan_generate(request).images.empty());
  EXPECT_FALSE(fs::exists(dir / "set"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace purkinje::studies
