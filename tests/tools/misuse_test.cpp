// Misuse of the command line, case by case: each is refused with its exit
// code and a message naming what was wrong, and leaves the workspace as it
// was: nothing written, nothing replaced, no temporary left, no device
// node turned into a file. docs/cli.md ("Reliability") lists the same
// cases; keep the two together.

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

const fs::path kExecutable = PURKINJE_EXECUTABLE;
const fs::path kSourceDir = PURKINJE_SOURCE_DIR;

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// Every entry under `root`, with its type and, for regular files, contents.
std::map<std::string, std::string> snapshot(const fs::path& root) {
  std::map<std::string, std::string> entries;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    const fs::file_status s = e.symlink_status();
    std::string what = std::to_string(static_cast<int>(s.type()));
    if (s.type() == fs::file_type::regular) {
      what += ':';  // then the contents (":" + read(): g++ 12's false -Wrestrict)
      what += read(e.path());
    }
    entries[fs::relative(e.path(), root).string()] = what;
  }
  return entries;
}

struct Case {
  const char* name;
  const char* command;  // {W} is the workspace, quoted
  int exit_code;
  const char* message;  // a part of what stderr must say
};

// The workspace every case runs in, made once: the remote scene, a set of
// two renders, a FIFO, a regular file, a symbolic link, a scene whose mesh
// is /dev/zero, a scene file named as a render's output, a labels file
// with a number beyond double's range, and a detections file.
class Misuse : public ::testing::TestWithParam<Case> {
 public:
  static void SetUpTestSuite() {
    workspace_ = new fs::path(fs::temp_directory_path() / ("purkinje_misuse_" + std::to_string(::getpid())));
    const fs::path& w = *workspace_;
    fs::remove_all(w);
    fs::create_directories(w / "empty");
    fs::copy_file(kSourceDir / "assets/scenes/remote.json", w / "scene.json");
    fs::copy_file(kSourceDir / "assets/scenes/remote.json", w / "remote_cam0.json");
    ASSERT_EQ(run_in(w, "render {W}/scene.json -o {W}/set --variations 2"), 0);
    ASSERT_EQ(::mkfifo((w / "fifo").c_str(), 0600), 0);
    std::ofstream(w / "file.txt") << "a regular file\n";
    fs::create_symlink(w / "file.txt", w / "link.txt");
    std::ofstream(w / "mesh_zero.json")
        << R"({"format": 1, "cameras": [{"resolution_px": [64, 48], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600]}],
              "eyes": [{"position": {"cornea_center_mm": [0, 0, 600]}, "orientation": {}}],
              "meshes": [{"name": "zero", "file": "/dev/zero", "albedo": 0.5}]})";
    fs::create_directories(w / "bad_labels");
    fs::copy_file(w / "set/remote_v0000_cam0.png", w / "bad_labels/x.png");
    std::ofstream(w / "bad_labels/x.json") << R"({"labels_format": 1e400})";
    std::ofstream(w / "detections.csv") << "image,feature,u_px,v_px\nremote_v0000_cam0.png,pupil,300,200\n";
    fs::copy_file(w / "detections.csv", w / "score.csv");
    // Dataset specs over the scene: a good one, one named as an image the
    // set would write, one with an unknown parameter, one no eye can have.
    const std::string spec = R"({"dataset_format": 1, "name": "t", "scene": "scene.json", "count": 2)";
    std::ofstream(w / "spec.json") << spec << "}";
    std::ofstream(w / "t_000000_cam0.json") << spec << "}";
    std::ofstream(w / "bad_spec.json") << spec << R"(, "parameters": {"pupil_size": 2}})";
    std::ofstream(w / "no_eye_spec.json") << spec << R"(, "parameters": {"pupil_radius_mm": {"uniform": [5.95, 6]}}})";
  }
  static void TearDownTestSuite() {
    fs::remove_all(*workspace_);
    delete workspace_;
  }

 protected:
  // Runs purkinje with `command` ({W} replaced); stderr lands in `err`.
  static int run_in(const fs::path& w, std::string command, std::string* err = nullptr) {
    for (std::size_t at; (at = command.find("{W}")) != std::string::npos;) command.replace(at, 3, quoted(w.string()));
    const fs::path err_file = fs::temp_directory_path() / ("purkinje_misuse_err_" + std::to_string(::getpid()));
    std::string line = command;
    std::string env;
    if (line.rfind("env ", 0) == 0) {  // "env VAR=value purkinje-arguments"
      const std::size_t space = line.find(' ', 4);
      env = line.substr(0, space) + " ";
      line = line.substr(space + 1);
    }
    const std::string shell =
        env + quoted(kExecutable.string()) + " " + line + " >/dev/null 2>" + quoted(err_file.string());
    const int status = std::system(shell.c_str());
    if (err) *err = read(err_file);
    fs::remove(err_file);
    if (status == -1 || !WIFEXITED(status)) return -1;
    return WEXITSTATUS(status);
  }

  static fs::path* workspace_;
};

fs::path* Misuse::workspace_ = nullptr;

TEST_P(Misuse, IsRefusedAndChangesNothing) {
  const Case& c = GetParam();
  const fs::path& w = *workspace_;
  const auto before = snapshot(w);
  std::string err;
  EXPECT_EQ(run_in(w, c.command, &err), c.exit_code) << c.command << "\n" << err;
  EXPECT_NE(err.find(c.message), std::string::npos) << c.command << "\nstderr: " << err;
  EXPECT_EQ(snapshot(w), before) << c.command << ": the workspace changed";
  struct stat full {};
  ASSERT_EQ(::stat("/dev/full", &full), 0);
  EXPECT_TRUE(S_ISCHR(full.st_mode)) << "/dev/full is no longer a device";
}

INSTANTIATE_TEST_SUITE_P(
    Cases, Misuse,
    ::testing::Values(
        // Outputs that are inputs, devices, FIFOs, links or of the wrong kind.
        Case{"TruthOntoADevice", "truth {W}/scene.json -o /dev/full", 3, "/dev/full: is a character device: not replaced"},
        Case{"TruthOntoItsScene", "truth {W}/scene.json -o {W}/scene.json", 2, "is an input of this command"},
        Case{"TruthOntoItsSceneByAnotherPath", "truth {W}/scene.json -o {W}/empty/../scene.json", 2,
             "is an input of this command"},
        Case{"TruthOntoAFifo", "truth {W}/scene.json -o {W}/fifo", 3, "is a FIFO (named pipe): not replaced"},
        Case{"TruthOntoAFolder", "truth {W}/scene.json -o {W}/empty", 3, "is a folder: not replaced"},
        Case{"TruthOntoASymbolicLink", "truth {W}/scene.json -o {W}/link.txt", 3, "is a symbolic link: not replaced"},
        Case{"TruthOntoAMissingFolderPath", "truth {W}/scene.json -o {W}/missing/", 3, "names a folder, not a file"},
        Case{"RenderIntoAFile", "render {W}/scene.json -o {W}/file.txt", 3, "exists and is not a folder"},
        Case{"RenderIntoADevice", "render {W}/scene.json -o /dev/null", 3, "exists and is not a folder"},
        Case{"RenderOverItsScene", "render {W}/remote_cam0.json -o {W}", 2, "is an input of this command"},
        Case{"TrackIntoItsSet", "track {W}/set -o {W}/set", 2, "is an input folder of this command"},
        Case{"TrackIntoTheFolderOfItsLabels", "track {W}/set/remote_v0000_cam0.json -o {W}/set", 2,
             "is an input folder of this command"},
        Case{"TrackIntoAFile", "track {W}/set -o {W}/file.txt", 3, "exists and is not a folder"},
        Case{"ScoreIntoItsSet", "score --detections {W}/detections.csv {W}/set -o {W}/set", 2,
             "is an input folder of this command"},
        Case{"ScoreOverItsDetections", "score --detections {W}/score.csv {W}/set -o {W}", 2,
             "is an input of this command"},
        Case{"CalibrateIntoAFile", "calibrate {W}/scene.json -o {W}/file.txt", 3, "exists and is not a folder"},
        // Inputs that are not regular files, or not what they claim.
        Case{"SceneFromADevice", "truth /dev/zero", 1, "/dev/zero: cannot read: is a character device"},
        Case{"SceneFromAFifo", "truth {W}/fifo", 1, "cannot read: is a FIFO (named pipe), not a scene file"},
        Case{"SceneFromAFolder", "truth {W}/empty", 1, "cannot read: is a directory"},
        Case{"MeshFromDevZero", "render {W}/mesh_zero.json -o {W}/out", 1, "is a character device, not an OBJ file"},
        Case{"LabelsWithANumberBeyondDouble", "track {W}/bad_labels -o {W}/out", 1, "x.json: not JSON"},
        Case{"DetectionsFromAFifo", "score --detections {W}/fifo {W}/set -o {W}/out", 1,
             "is a FIFO (named pipe), not a detections file"},
        Case{"DetectionsFromDevZero", "score --detections /dev/zero {W}/set -o {W}/out", 1,
             "is a character device, not a detections file"},
        Case{"EmbreeConfigurationUnknown", "env PURKINJE_EMBREE_CONFIG=isa=bogus render {W}/scene.json -o {W}/out", 1,
             "PURKINJE_EMBREE_CONFIG=\"isa=bogus\""},
        // Options out of range, not finite, or not numbers.
        Case{"TrackMatchRadiusNaN", "track {W}/set -o {W}/out --match-radius nan", 2, "must be a finite number"},
        Case{"ScoreMatchRadiusNaN", "score --detections {W}/detections.csv {W}/set -o {W}/out --match-radius nan", 2,
             "must be a finite number"},
        Case{"SeedNegative", "render {W}/scene.json -o {W}/out --seed -1", 2, "--seed: must be an integer from 0"},
        Case{"SeedTwoToThe64", "render {W}/scene.json -o {W}/out --seed 18446744073709551616", 2,
             "--seed: must be an integer from 0"},
        Case{"SeedInExponentForm", "render {W}/scene.json -o {W}/out --seed 1e23", 2, "--seed: must be an integer"},
        Case{"VariationSeedNegative", "render {W}/scene.json -o {W}/out --variations 2 --variation-seed -5", 2,
             "--variation-seed: must be an integer"},
        Case{"CalibrateSeedNegative", "calibrate {W}/scene.json -o {W}/out --seed -1", 2, "--seed: must be an integer"},
        Case{"MinPupilNaN", "render {W}/scene.json -o {W}/out --variations 2 --min-pupil-mm nan", 2,
             "--min-pupil-mm: must be a finite number"},
        Case{"PupilRangeReversed", "render {W}/scene.json -o {W}/out --variations 2 --min-pupil-mm 3 --max-pupil-mm 2",
             2, "--min-pupil-mm 3 is above --max-pupil-mm 2"},
        Case{"MaxGazeOverflowing", "render {W}/scene.json -o {W}/out --variations 2 --max-gaze-deg 1e999", 2,
             "--max-gaze-deg: must be a finite number"},
        Case{"GlintNoiseInfinite", "calibrate {W}/scene.json -o {W}/out --glint-noise inf", 2,
             "--glint-noise: must be a finite number"},
        Case{"HeadMoveNaN", "calibrate {W}/scene.json -o {W}/out --head-move nan,0,0", 2, "--head-move"},
        Case{"PupilPointsNegative", "truth {W}/scene.json --pupil-points -1", 2, "--pupil-points"},
        Case{"OverlaysNegative", "track {W}/set -o {W}/out --overlays -1", 2, "--overlays"},
        Case{"SamplesZero", "render {W}/scene.json -o {W}/out --samples 0", 2, "--samples"},
        Case{"RenderWithoutAnOutput", "render {W}/scene.json", 2, "--output is required"},
        Case{"GenerateIntoAFile", "generate {W}/spec.json -o {W}/file.txt", 3, "exists and is not a folder"},
        Case{"GenerateOverItsSpec", "generate {W}/t_000000_cam0.json -o {W}", 2, "is an input of this command"},
        Case{"GenerateFromAFifo", "generate {W}/fifo -o {W}/out", 1, "cannot read: is a FIFO (named pipe)"},
        Case{"GenerateAnUnknownParameter", "generate {W}/bad_spec.json -o {W}/out", 1,
             "bad_spec.json: parameters.pupil_size = 2: unknown key"},
        Case{"GenerateAnEyeNoneCanHave", "generate {W}/no_eye_spec.json -o {W}/out", 1, "no_eye_spec.json: image 0: "},
        Case{"GenerateShardBeyondItsCount", "generate {W}/spec.json -o {W}/out --shard 4/4", 2,
             "--shard 4/4: must be I/N with 0 <= I < N"},
        Case{"GenerateShardNotNumbers", "generate {W}/spec.json -o {W}/out --shard one/4", 2, "--shard one/4: must be"},
        Case{"GenerateCountZero", "generate {W}/spec.json -o {W}/out --count 0", 2, "--count"},
        Case{"MergeWithoutShards", "merge {W}/empty", 1, "no shard manifests (manifest.shard-I-of-N.json)"},
        Case{"MergeAFile", "merge {W}/file.txt", 1, "file.txt: cannot list"}),
    [](const ::testing::TestParamInfo<Case>& info) { return std::string(info.param.name); });

}  // namespace
