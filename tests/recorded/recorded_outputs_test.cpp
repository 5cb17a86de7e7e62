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
#include <sstream>
#include <string>
#include <vector>

#include "purkinje/models/input_file.h"

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
      for (std::string line; std::getline(lines, line);) out << "#   purkinje " << line << "\n";
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
                              "hard/remote_noisy"}) {
    ASSERT_NO_FATAL_FAILURE(run("render " + scene(s + ".json") + " -o " + in_root(s)));
    commands += "render " + s + ".json -o " + s + "\n";
  }
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

TEST_F(RecordedOutputs, CalibrateRemoteOnAGridOfFour) {
  ASSERT_NO_FATAL_FAILURE(run("calibrate " + scene("remote.json") + " -o " + in_root("calibrate") + " --grid 4"));
  expect_recorded("calibrate remote.json -o calibrate --grid 4");
}

TEST_F(RecordedOutputs, CalibrateHeadsetOnAGridOfFour) {
  ASSERT_NO_FATAL_FAILURE(run("calibrate " + scene("headset.json") + " -o " + in_root("calibrate") + " --grid 4"));
  expect_recorded("calibrate headset.json -o calibrate --grid 4");
}

}  // namespace
