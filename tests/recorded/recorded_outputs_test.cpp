// The command line's outputs, byte for byte, against checksums recorded in
// tests/data/recorded_outputs/: a refactor that should change nothing
// (the studies layer, the renderer's seams) proves it here. Each test runs
// the built `purkinje` as a user would and lists every file it wrote with
// its CRC-32 and size.
//
// When an output is meant to change, record it again and say why in the
// commit:
//   PURKINJE_RECORD_OUTPUTS=1 ctest --test-dir build/debug -R RecordedOutputs
// Debug and Release write the same bytes (our code is compiled for the
// x86-64 baseline without fast math); renders are the same under every
// Embree ISA (RenderDeterminism, tests/renderer).

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "purkinje/models/eye.h"
#include "purkinje/models/input_file.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/renderer/render.h"

namespace {

namespace fs = std::filesystem;

const fs::path kExecutable = PURKINJE_EXECUTABLE;
const fs::path kSourceDir = PURKINJE_SOURCE_DIR;
const fs::path kRecorded = kSourceDir / "tests/data/recorded_outputs";

std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string scene(const std::string& name) { return quoted((kSourceDir / "assets/scenes" / name).string()); }

class RecordedOutputs : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("purkinje_recorded_" + std::to_string(::getpid()) + "_" + name());
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }

  static std::string name() { return ::testing::UnitTest::GetInstance()->current_test_info()->name(); }
  std::string in_root(const std::string& folder) const { return quoted((root_ / folder).string()); }

  // Runs `purkinje ARGUMENTS --quiet`; fails the test on a non-zero exit.
  void run(const std::string& arguments) {
    const std::string log = (root_ / "log.txt").string();
    const std::string command = quoted(kExecutable.string()) + " " + arguments + " --quiet >" + quoted(log) + " 2>&1";
    const int status = std::system(command.c_str());
    ASSERT_TRUE(status != -1 && WIFEXITED(status) && WEXITSTATUS(status) == 0)
        << "purkinje " << arguments << " failed:\n"
        << std::ifstream(log).rdbuf();
    fs::remove(log);
  }

  // "crc32 bytes path" per file under the root, sorted by path.
  std::map<std::string, std::string> checksums() const {
    std::map<std::string, std::string> lines;
    for (const auto& entry : fs::recursive_directory_iterator(root_)) {
      if (!entry.is_regular_file()) continue;
      const purkinje::FileCheck check = purkinje::file_check_of_file(entry.path());
      const std::string path = fs::relative(entry.path(), root_).generic_string();
      lines[path] = purkinje::crc32_text(check.crc32) + " " + std::to_string(check.bytes);
    }
    return lines;
  }

  // Compares the outputs with tests/data/recorded_outputs/<test>.txt, or
  // writes that file when PURKINJE_RECORD_OUTPUTS=1. `commands` heads it.
  void expect_recorded(const std::string& commands) {
    const std::map<std::string, std::string> now = checksums();
    ASSERT_FALSE(now.empty()) << "the commands wrote nothing";
    const fs::path file = kRecorded / (name() + ".txt");
    if (const char* record = std::getenv("PURKINJE_RECORD_OUTPUTS"); record && std::string(record) == "1") {
      fs::create_directories(kRecorded);
      std::ofstream out(file);
      out << "# crc32 bytes path of every file written by (scene paths relative to assets/scenes):\n";
      std::istringstream lines(commands);
      for (std::string line; std::getline(lines, line);) out << (line[0] == '(' ? "#   " : "#   purkinje ") << line << "\n";
      for (const auto& [path, check] : now) out << check << " " << path << "\n";
      std::cout << "recorded " << now.size() << " files in " << file << "\n";
      return;
    }
    std::ifstream in(file);
    ASSERT_TRUE(in) << "no recorded checksums at " << file << " (record them with PURKINJE_RECORD_OUTPUTS=1)";
    std::map<std::string, std::string> recorded;
    for (std::string line; std::getline(in, line);) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream fields(line);
      std::string crc, bytes, path;
      fields >> crc >> bytes;
      std::getline(fields >> std::ws, path);
      recorded[path] = crc + " " + bytes;
    }
    std::vector<std::string> differences;
    for (const auto& [path, check] : recorded) {
      const auto it = now.find(path);
      if (it == now.end()) {
        differences.push_back(path + ": recorded (" + check + ") but not written");
      } else if (it->second != check) {
        differences.push_back(path + ": " + it->second + " now, " + check + " recorded");
      }
    }
    for (const auto& [path, check] : now) {
      if (!recorded.count(path)) differences.push_back(path + ": written (" + check + ") but not recorded");
    }
    std::string report;
    for (const std::string& d : differences) report += "  " + d + "\n";
    EXPECT_TRUE(differences.empty()) << differences.size() << " of " << std::max(now.size(), recorded.size())
                                     << " files differ from " << file << " (crc32 bytes):\n"
                                     << report;
  }

  fs::path root_;
};

TEST_F(RecordedOutputs, BundledAndHardScenesRender) {
  std::string commands;
  for (const std::string s : {"remote", "headset", "remote_glasses", "hard/headset_defocused", "hard/headset_half_closed",
                              "hard/headset_noisy", "hard/remote_defocused", "hard/remote_half_closed",
                              "hard/remote_noisy", "hard/headset_mjpeg", "hard/headset_hot_pixels",
                              "hard/headset_saccade", "hard/headset_face", "hard/headset_face_wet"}) {
    ASSERT_NO_FATAL_FAILURE(run("render " + scene(s + ".json") + " -o " + in_root(s)));
    commands += "render " + s + ".json -o " + s + "\n";
  }
  // A wet sclera's highlights: the eye turned (gaze to 45 deg) so that
  // the sclera mirrors the LEDs.
  const std::string wet = "hard/headset_wet.json -o hard/headset_wet --variations 3 --max-gaze-deg 45 --variation-seed 2";
  ASSERT_NO_FATAL_FAILURE(run("render " + scene("hard/headset_wet.json") + " -o " + in_root("hard/headset_wet") +
                              " --variations 3 --max-gaze-deg 45 --variation-seed 2"));
  commands += "render " + wet + "\n";
  expect_recorded(commands);
}

TEST_F(RecordedOutputs, VariationsTrackedAndScored) {
  ASSERT_NO_FATAL_FAILURE(run("render " + scene("remote.json") + " -o " + in_root("set") + " --variations 20"));
  ASSERT_NO_FATAL_FAILURE(
      run("track " + in_root("set") + " -o " + in_root("track") + " --scene " + scene("remote.json")));
  ASSERT_NO_FATAL_FAILURE(
      run("score --detections " + in_root("track/detections.csv") + " " + in_root("set") + " -o " + in_root("score")));
  expect_recorded(
      "render remote.json -o set --variations 20\n"
      "track set -o track --scene remote.json\n"
      "score --detections track/detections.csv set -o score");
}

// 100 random scenes rendered through the library and written as render
// does (PNG, EXR with every AOV, labels): remote (300-800 mm, 2-4 LEDs),
// headset (25-45 mm) and remote with glasses; three eye models, pupils,
// gaze up to 25 degrees, lids open or half closed, iris seeds; a 200 x 160
// crop of each camera; every fifth with 4 samples per pixel and edge
// samples, every tenth in reference mode at 64 x 48. The draws use the
// generator's raw bits, which the standard fixes, not a distribution.
TEST_F(RecordedOutputs, RandomScenesRender) {
  std::mt19937_64 rng(20261127);
  const auto between = [&](double a, double b) { return a + (b - a) * static_cast<double>(rng() >> 11) * 0x1p-53; };
  const char* const bases[] = {"remote", "headset", "remote_glasses"};
  const char* const models[] = {"keratometric", "le_grand", "navarro"};
  for (int i = 0; i < 100; ++i) {
    const std::string base = bases[i % 3];
    purkinje::Scene scene = purkinje::load_scene((kSourceDir / "assets/scenes" / (base + ".json")).string());
    const bool headset = base == "headset";
    purkinje::EyeModel model = *purkinje::eye_model_preset(models[(i / 3) % 3]);
    model.pupil_radius_mm = between(1.0, 4.0);
    const double distance = headset ? between(25, 45) : between(300, 800);
    const purkinje::Point3 cornea{between(-0.05, 0.05) * distance, between(-0.05, 0.05) * distance, distance};
    const double yaw = between(-25, 25) * std::numbers::pi / 180, pitch = between(-25, 25) * std::numbers::pi / 180;
    purkinje::Eye eye =
        purkinje::Eye::with_cornea_center(model, cornea, purkinje::optical_axis_from_yaw_pitch(yaw, pitch));
    purkinje::EyeAppearance look = scene.eyes.front().appearance();
    look.eyelids = purkinje::Eyelids{};
    look.eyelids->opening = i % 4 == 3 ? 0.5 : 1.0;
    look.iris_seed = static_cast<std::uint64_t>(i);
    eye.set_appearance(look);
    scene.eyes = {eye};
    if (base == "remote") {
      scene.illuminators.resize(1);
      const int lights = 2 + i % 3;
      for (int l = 0; l < lights; ++l) {
        purkinje::Illuminator led = scene.illuminators.front();
        led.name = "led" + std::to_string(l);
        led.position = {between(-150, 150), between(-60, 60), between(-20, 20)};
        scene.illuminators.push_back(led);
      }
      scene.illuminators.erase(scene.illuminators.begin());
    }
    purkinje::renderer::RenderOptions options;
    options.seed = static_cast<std::uint64_t>(i);
    const bool reference = i % 10 == 9;
    const int width = reference ? 64 : 200, height = reference ? 48 : 160;
    for (purkinje::Camera& camera : scene.cameras) {
      purkinje::Intrinsics crop = camera.intrinsics();
      crop.cx -= (crop.width - width) / 2;
      crop.cy -= (crop.height - height) / 2;
      crop.width = width;
      crop.height = height;
      camera = purkinje::Camera(camera.name(), crop, camera.distortion(), camera.world_from_camera(), camera.sensor());
    }
    if (reference) {
      options.mode = purkinje::renderer::RenderMode::reference;
      options.samples_per_pixel = 4;
      options.reference_photons_per_light = 20000;
    } else if (i % 5 == 4) {
      options.samples_per_pixel = 4;
      options.edge_samples_per_pixel = 16;
    }
    const std::string stem = "scene" + std::to_string(1000 + i).substr(1);
    const purkinje::renderer::RenderResult result = purkinje::renderer::render(scene, 0, options);
    purkinje::renderer::write_render(root_, stem, scene, result, options);
  }
  expect_recorded("(no command: 100 random scenes rendered through the library, see RandomScenesRender)");
}

TEST_F(RecordedOutputs, CalibrateRemoteOnAGridOfFour) {
  // The figures are matplotlib's drawing, not numbers: left out.
  ASSERT_NO_FATAL_FAILURE(
      run("calibrate " + scene("remote.json") + " -o " + in_root("calibrate") + " --grid 4 --no-figures"));
  expect_recorded("calibrate remote.json -o calibrate --grid 4 --no-figures");
}

TEST_F(RecordedOutputs, CalibrateHeadsetOnAGridOfFour) {
  // The figures are matplotlib's drawing, not numbers: left out.
  ASSERT_NO_FATAL_FAILURE(
      run("calibrate " + scene("headset.json") + " -o " + in_root("calibrate") + " --grid 4 --no-figures"));
  expect_recorded("calibrate headset.json -o calibrate --grid 4 --no-figures");
}

}  // namespace
