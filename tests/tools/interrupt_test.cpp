// A labelled set's render, and a data set's generate, killed at many
// points (SIGKILL, which nothing can catch, and SIGTERM, which purkinje
// handles), then continued with --resume: the folder ends byte for byte as one uninterrupted run leaves
// it, with no temporary left. The kill points are exact: PURKINJE_STOP_AT
// makes the process raise the signal at the N-th event of a kind
// (models/output_file.h, stop_point).

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "environment_count.h"

namespace {

namespace fs = std::filesystem;

const fs::path kExecutable = PURKINJE_EXECUTABLE;
const fs::path kSourceDir = PURKINJE_SOURCE_DIR;
constexpr int kVariations = 50;

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::map<std::string, std::string> contents(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::directory_iterator(dir)) files[e.path().filename().string()] = read(e.path());
  return files;
}

struct Status {
  bool exited = false;
  int code = -1;    // when exited
  int signal = 0;   // when killed by a signal
};

// purkinje with `arguments`, in `environment` ("VAR=value", or empty),
// its output dropped: how it ended.
Status run(const std::string& arguments, const std::string& environment) {
  const std::string command = (environment.empty() ? "" : "env " + environment + " ") + "'" + kExecutable.string() +
                              "' " + arguments + " > /dev/null 2>&1";
  const int status = std::system(command.c_str());
  Status s;
  // std::system runs sh -c, which may exec the command (then a signal
  // shows as such) or wait for it (then as the exit code 128 + signal).
  if (WIFSIGNALED(status)) {
    s.signal = WTERMSIG(status);
  } else if (WIFEXITED(status)) {
    s.exited = true;
    s.code = WEXITSTATUS(status);
    if (s.code > 128) s.signal = s.code - 128;
  }
  return s;
}

// `purkinje render` of the tiny scene's set into `dir`, with `extra`
// arguments.
Status render_set(const fs::path& dir, const std::string& extra, const std::string& environment = "") {
  return run("render '" + (kSourceDir / "tests/data/tiny_remote.json").string() + "' -o '" + dir.string() +
                 "' --variations " + std::to_string(kVariations) + " " + extra,
             environment);
}

class Interrupted : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = new fs::path(fs::temp_directory_path() / ("purkinje_interrupt_" + std::to_string(::getpid())));
    fs::remove_all(*root_);
    fs::create_directories(*root_);
    ASSERT_EQ(render_set(*root_ / "reference", "").code, 0);
    reference_ = new std::map<std::string, std::string>(contents(*root_ / "reference"));
    ASSERT_EQ(reference_->size(), 3u * kVariations + 1);  // PNG, EXR, labels each, and the index
  }
  static void TearDownTestSuite() {
    fs::remove_all(*root_);
    delete reference_;
    delete root_;
  }

  // Kills a run at `stop` ("EVENT:N:SIGNAL"), checks what the signal left,
  // resumes, and checks the result against the uninterrupted run.
  void kill_and_resume(const std::string& stop, int signal) {
    SCOPED_TRACE(stop);
    const fs::path dir = *root_ / (::testing::UnitTest::GetInstance()->current_test_info()->name() +
                                   std::to_string(++runs_));
    const Status killed = render_set(dir, "", "PURKINJE_STOP_AT=" + stop);
    EXPECT_EQ(killed.signal, signal) << "the run was not stopped where asked (exit " << killed.code << ")";
    const auto partial = contents(dir);
    bool temporaries = false;
    for (const auto& [name, bytes] : partial) temporaries = temporaries || name.find(".tmp.") != std::string::npos;
    // SIGTERM removes the temporaries itself; after SIGKILL --resume does.
    if (signal == SIGTERM) {
      EXPECT_FALSE(temporaries) << "SIGTERM left a temporary";
    }
    // The index holds the variations finished so far, written as they finish.
    EXPECT_EQ(read(dir / "variations.csv").rfind("index,stem,seed,", 0), 0u);

    const Status resumed = render_set(dir, "--resume");
    EXPECT_EQ(resumed.code, 0);
    const auto final_contents = contents(dir);
    EXPECT_EQ(final_contents.size(), reference_->size());
    for (const auto& [name, bytes] : *reference_) {
      const auto it = final_contents.find(name);
      ASSERT_NE(it, final_contents.end()) << name << " missing";
      EXPECT_TRUE(it->second == bytes) << name << " differs from the uninterrupted run's";
    }
  }

  static fs::path* root_;
  static std::map<std::string, std::string>* reference_;
  int runs_ = 0;
};

fs::path* Interrupted::root_ = nullptr;
std::map<std::string, std::string>* Interrupted::reference_ = nullptr;

// Renames: the index's first write, then 3 per variation (PNG, EXR,
// labels last); rename 89 is the 30th unit's PNG. temporary_written
// counts the index's first write too.
const char* const kStopPoints[] = {
    "renamed:2",              // between the first unit's PNG and EXR
    "renamed:3",              // between its EXR and labels
    "temporary_written:40",   // a unit's files written, none renamed
    "unit_written:17",        // a unit in place, its index line not yet
    "renamed:89",             // between a later unit's PNG and EXR
    "renamed:151"};           // every unit in place, the index not yet whole

// All six unless PURKINJE_KILL_POINTS says fewer: .ci/run lowers it for the
// sanitizer and coverage builds, which check the code, not the bar.
int kill_points() { return purkinje::testing::count_from_environment("PURKINJE_KILL_POINTS", 6, 1); }

TEST_F(Interrupted, SigkillAtSixPointsThenResumeGivesTheBytesOfOneRun) {
  for (int i = 0; i < kill_points(); ++i) kill_and_resume(std::string(kStopPoints[i]) + ":KILL", SIGKILL);
}

TEST_F(Interrupted, SigtermAtSixPointsRemovesTemporariesAndResumeGivesTheBytesOfOneRun) {
  for (int i = 0; i < kill_points(); ++i) kill_and_resume(std::string(kStopPoints[i]) + ":TERM", SIGTERM);
}

// A set rendered with other seeds, then a new run killed between the first
// unit's renames: its new PNG lies beside the old run's EXR and labels.
// The labels' checks tell it; --resume renders that unit again, and track
// refuses the mixed unit rather than score it.
TEST_F(Interrupted, AHalfReplacedUnitIsToldByItsLabelsChecks) {
  const fs::path dir = *root_ / "mixed";
  ASSERT_EQ(render_set(dir, "--seed 1000").code, 0);
  EXPECT_EQ(render_set(dir, "", "PURKINJE_STOP_AT=renamed:2:KILL").signal, SIGKILL);
  const std::string track = "'" + kExecutable.string() + "' track '" + (dir / "tiny_v0000_cam0.json").string() +
                            "' -o '" + (*root_ / "mixed_track").string() + "' > /dev/null 2>'" +
                            (*root_ / "track_err.txt").string() + "'";
  const int status = std::system(track.c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1);
  EXPECT_NE(read(*root_ / "track_err.txt").find("does not match its labels"), std::string::npos)
      << read(*root_ / "track_err.txt");
  ASSERT_EQ(render_set(dir, "--resume").code, 0);
  EXPECT_TRUE(contents(dir) == *reference_);
}

// --resume continues the run it is given the options of, no other: an
// index line of other draws is refused; units of another run that the
// index does not list yet (a set rendered without noise, then a run with
// noise killed early) are rendered again, not kept.
TEST_F(Interrupted, ResumeKeepsOnlyUnitsOfTheRunItContinues) {
  const fs::path dir = *root_ / "other";
  EXPECT_EQ(render_set(dir, "", "PURKINJE_STOP_AT=unit_written:5:KILL").signal, SIGKILL);
  const auto before = contents(dir);
  EXPECT_EQ(render_set(dir, "--resume --variation-seed 2").code, 2);
  EXPECT_TRUE(contents(dir) == before);

  const fs::path mixed = *root_ / "noise";
  ASSERT_EQ(render_set(mixed, "--no-noise").code, 0);
  EXPECT_EQ(render_set(mixed, "", "PURKINJE_STOP_AT=unit_written:3:KILL").signal, SIGKILL);
  ASSERT_EQ(render_set(mixed, "--resume").code, 0);
  EXPECT_TRUE(contents(mixed) == *reference_);
}

// Complete units are kept, not rendered again (the same bytes either way:
// only the count tells).
TEST_F(Interrupted, ResumeKeepsTheCompleteUnits) {
  const fs::path dir = *root_ / "kept";
  EXPECT_EQ(render_set(dir, "", "PURKINJE_STOP_AT=unit_written:30:KILL").signal, SIGKILL);
  const fs::path out = *root_ / "kept_stdout.txt";
  const std::string command = "'" + kExecutable.string() + "' render '" +
                              (kSourceDir / "tests/data/tiny_remote.json").string() + "' -o '" + dir.string() +
                              "' --variations " + std::to_string(kVariations) + " --resume --quiet > '" + out.string() +
                              "' 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0);
  EXPECT_NE(read(out).find("resumed: 30 of 50 variations were complete"), std::string::npos) << read(out);
  EXPECT_TRUE(contents(dir) == *reference_);
}

// No index at all (killed before it was first written, or a fresh
// folder), and an index whose last line a kill cut short: resumed twice.
TEST_F(Interrupted, ResumeWithoutAnIndexOrAfterACutLine) {
  const fs::path dir = *root_ / "no_index";
  EXPECT_EQ(render_set(dir, "", "PURKINJE_STOP_AT=renamed:31:KILL").signal, SIGKILL);
  fs::remove(dir / "variations.csv");
  EXPECT_EQ(render_set(dir, "--resume", "PURKINJE_STOP_AT=renamed:31:KILL").signal, SIGKILL);
  std::string index = read(dir / "variations.csv");
  ASSERT_GT(index.size(), 10u);
  std::ofstream(dir / "variations.csv", std::ios::binary | std::ios::trunc) << index.substr(0, index.size() - 5);
  ASSERT_EQ(render_set(dir, "--resume").code, 0);
  EXPECT_TRUE(contents(dir) == *reference_);
}

// ---------------------------------------------------------------- generate

// `purkinje generate` of a spec over the tiny scene (pupil, gaze and iris
// varied, every file kind), killed at many points and resumed; a shard
// killed and resumed, then merged.
constexpr int kImages = 12;

Status generate(const fs::path& spec, const fs::path& dir, const std::string& extra,
                const std::string& environment = "") {
  return run("generate '" + spec.string() + "' -o '" + dir.string() + "' " + extra, environment);
}

class GenerateInterrupted : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = new fs::path(fs::temp_directory_path() / ("purkinje_generate_interrupt_" + std::to_string(::getpid())));
    fs::remove_all(*root_);
    fs::create_directories(*root_);
    spec_ = new fs::path(*root_ / "spec.json");
    std::ofstream(*spec_) << R"({"dataset_format": 1, "name": "tiny", "scene": ")"
                          << (kSourceDir / "tests/data/tiny_remote.json").string() << R"(", "count": )" << kImages
                          << R"(, "gaze": {"cone_deg": 20}, "outputs": {"exr": {"planes": ["Y", "depth"]}},
                                "parameters": {"pupil_radius_mm": {"uniform": [1, 3]}, "iris_seed": {"uniform": [1, 99]}}})";
    ASSERT_EQ(generate(*spec_, *root_ / "reference", "").code, 0);
    reference_ = new std::map<std::string, std::string>(contents(*root_ / "reference"));
    ASSERT_EQ(reference_->size(), 4u * kImages + 2);  // PNG, classes, EXR, labels; table and manifest
  }
  static void TearDownTestSuite() {
    fs::remove_all(*root_);
    delete reference_;
    delete spec_;
    delete root_;
  }

  void expect_reference(const fs::path& dir) {
    const auto found = contents(dir);
    for (const auto& [name, bytes] : *reference_) {
      const auto it = found.find(name);
      ASSERT_NE(it, found.end()) << name << " missing";
      EXPECT_TRUE(it->second == bytes) << name << " differs from the uninterrupted run's";
    }
    for (const auto& [name, bytes] : found) {
      EXPECT_TRUE(reference_->count(name) || name.find(".shard-") != std::string::npos) << name << " left over";
    }
  }

  static fs::path* root_;
  static fs::path* spec_;
  static std::map<std::string, std::string>* reference_;
};

fs::path* GenerateInterrupted::root_ = nullptr;
fs::path* GenerateInterrupted::spec_ = nullptr;
std::map<std::string, std::string>* GenerateInterrupted::reference_ = nullptr;

// Renames: 4 per image (PNG, classes, EXR, labels last), then the table
// and the manifest: rename 2 is between the first image's PNG and
// classes, 4 before its labels, 49 the table with the manifest not yet.
TEST_F(GenerateInterrupted, KilledAnywhereThenResumedGivesTheBytesOfOneRun) {
  const char* const stops[] = {"renamed:2", "renamed:4", "temporary_written:11", "unit_written:7", "renamed:49"};
  int runs = 0;
  for (int i = 0; i < std::min(kill_points(), 5); ++i) {
    const char* stop = stops[i];
    for (const char* signal : {"KILL", "TERM"}) {
      const std::string where = std::string(stop) + ":" + signal;
      SCOPED_TRACE(where);
      const fs::path dir = *root_ / ("killed" + std::to_string(++runs));
      const Status killed = generate(*spec_, dir, "", "PURKINJE_STOP_AT=" + where);
      EXPECT_EQ(killed.signal, std::string(signal) == "KILL" ? SIGKILL : SIGTERM) << "exit " << killed.code;
      EXPECT_FALSE(fs::exists(dir / "manifest.json"));
      ASSERT_EQ(generate(*spec_, dir, "--resume").code, 0);
      expect_reference(dir);
    }
  }
}

TEST_F(GenerateInterrupted, AKilledShardResumesAndTheShardsMergeIntoTheWholeSet) {
  const fs::path dir = *root_ / "shards";
  ASSERT_EQ(generate(*spec_, dir, "--shard 0/3").code, 0);
  EXPECT_EQ(generate(*spec_, dir, "--shard 1/3", "PURKINJE_STOP_AT=unit_written:2:KILL").signal, SIGKILL);
  ASSERT_EQ(generate(*spec_, dir, "--shard 2/3").code, 0);
  const std::string merge = "'" + kExecutable.string() + "' merge '" + dir.string() + "' > /dev/null 2>&1";
  EXPECT_NE(std::system(merge.c_str()), 0);  // shard 1 has not finished
  EXPECT_FALSE(fs::exists(dir / "table.csv"));
  ASSERT_EQ(generate(*spec_, dir, "--shard 1/3 --resume").code, 0);
  ASSERT_EQ(std::system(merge.c_str()), 0);
  expect_reference(dir);
}

}  // namespace
