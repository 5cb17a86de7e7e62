// Runs the built `purkinje` executable as a user would.

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

const fs::path kExecutable = PURKINJE_EXECUTABLE;
const fs::path kSourceDir = PURKINJE_SOURCE_DIR;

// Single quotes for the shell; a quote inside becomes '\''.
std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

bool mentions_non_finite(const std::string& text) {
  for (const char* word : {"nan", "NaN", "inf", "Infinity"}) {
    if (text.find(word) != std::string::npos) return true;
  }
  return false;
}

// A PNG's width and height, from its header (for the figures' tests: a
// build without PURKINJE_FIGURES has none).
[[maybe_unused]] std::pair<int, int> png_size(const std::string& png) {
  if (png.size() < 24 || png.substr(1, 3) != "PNG") return {0, 0};
  const auto big_endian = [&](std::size_t at) {
    int v = 0;
    for (std::size_t i = 0; i < 4; ++i) v = v * 256 + static_cast<unsigned char>(png[at + i]);
    return v;
  };
  return {big_endian(16), big_endian(20)};
}

// A CSV's rows as column -> cell (no quoted commas in the columns read:
// quoted cells are kept whole).
std::vector<std::map<std::string, std::string>> csv_rows(const std::string& csv) {
  const auto cells = [](const std::string& line) {
    std::vector<std::string> out(1);
    bool quoted = false;
    for (char c : line) {
      if (c == '"') {
        quoted = !quoted;
      } else if (c == ',' && !quoted) {
        out.emplace_back();
      } else {
        out.back() += c;
      }
    }
    return out;
  };
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = cells(line);
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(in, line)) {
    const std::vector<std::string> row = cells(line);
    std::map<std::string, std::string> named;
    for (std::size_t i = 0; i < header.size() && i < row.size(); ++i) named[header[i]] = row[i];
    rows.push_back(named);
  }
  return rows;
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("purkinje_cli_test_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    output_dir_ = root_ / "out dir";  // a space, to exercise the quoting
    fs::create_directories(output_dir_);
  }
  void TearDown() override { fs::remove_all(root_); }

  // Runs purkinje with `arguments` (already quoted); returns its exit code.
  // Standard output and error land in files outside the output directory.
  int run(const std::string& arguments) {
    const std::string command = quoted(kExecutable.string()) + " " + arguments + " >" +
                                quoted((root_ / "stdout.txt").string()) + " 2>" +
                                quoted((root_ / "stderr.txt").string());
    const int status = std::system(command.c_str());
    if (status == -1 || !WIFEXITED(status)) return -1;
    return WEXITSTATUS(status);
  }
  std::string out() const { return read(root_ / "stdout.txt"); }
  // Less the coverage build's own reports on its counter files ("libgcov
  // profiling error: ... Merge mismatch"), which two purkinje processes
  // ending at once can print (seen at the landed code too, under ctest -j2;
  // cause not found): the command itself writes nothing there.
  std::string err() const {
    std::istringstream all(read(root_ / "stderr.txt"));
    std::string kept, line;
    while (std::getline(all, line)) {
      if (!line.starts_with("libgcov profiling error:")) kept += line + "\n";
    }
    return kept;
  }
  std::vector<std::string> output_dir_entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(output_dir_)) names.push_back(e.path().filename().string());
    return names;
  }

  fs::path root_;
  fs::path output_dir_;
};

TEST_F(Cli, RejectsEveryMalformedSceneWithoutWritingAnything) {
  int files = 0;
  for (const auto& entry : fs::directory_iterator(kSourceDir / "tests/data/malformed")) {
    if (entry.path().extension() != ".json") continue;
    ++files;
    const fs::path output = output_dir_ / "labels.json";
    const int code = run("truth " + quoted(entry.path().string()) + " -o " + quoted(output.string()));
    EXPECT_EQ(code, 1) << entry.path() << "\n" << err();
    // The message names the file; nothing, not even a temporary, is left.
    EXPECT_NE(err().find(entry.path().string()), std::string::npos) << err();
    EXPECT_TRUE(output_dir_entries().empty()) << entry.path();
    EXPECT_TRUE(out().empty()) << entry.path();
  }
  EXPECT_GE(files, 25);
}

TEST_F(Cli, FailedRunLeavesAnExistingOutputUntouched) {
  const fs::path output = output_dir_ / "labels.json";
  std::ofstream(output) << "previous labels";
  const int code = run("truth " + quoted((kSourceDir / "tests/data/malformed/zero_pixel_pitch.json").string()) +
                       " -o " + quoted(output.string()));
  EXPECT_EQ(code, 1);
  EXPECT_EQ(read(output), "previous labels");
  EXPECT_EQ(output_dir_entries().size(), 1u);
}

class BundledScene : public Cli, public ::testing::WithParamInterface<const char*> {};

TEST_P(BundledScene, HasEveryGlintAndThePupilInTheImage) {
  const fs::path scene = kSourceDir / "assets/scenes" / GetParam();
  const fs::path output = output_dir_ / "labels.json";
  ASSERT_EQ(run("truth " + quoted(scene.string()) + " -o " + quoted(output.string())), 0) << err();
  EXPECT_EQ(output_dir_entries(), std::vector<std::string>{"labels.json"});
  const std::string text = read(output);
  EXPECT_FALSE(mentions_non_finite(text));
  const json labels = json::parse(text);

  const std::size_t lights = labels["illuminators"].size();
  EXPECT_GE(lights, 2u);
  ASSERT_EQ(labels["views"].size(), labels["cameras"].size() * labels["eyes"].size());
  for (const json& view : labels["views"]) {
    const json& camera = labels["cameras"][view["camera"].get<std::size_t>()];
    const double width = camera["width_px"], height = camera["height_px"];
    auto in_image = [&](const json& feature) {
      return feature["status"] == "ok" && feature["u_px"].get<double>() >= -0.5 &&
             feature["u_px"].get<double>() <= width - 0.5 &&
             feature["v_px"].get<double>() >= -0.5 && feature["v_px"].get<double>() <= height - 0.5;
    };
    ASSERT_EQ(view["glints"].size(), lights);
    for (const json& glint : view["glints"]) {
      EXPECT_TRUE(in_image(glint)) << glint.dump();
      EXPECT_EQ(glint["on_cap"], true) << glint.dump();
    }
    const json& pupil = view["pupil"];
    EXPECT_EQ(pupil["border"].size(), 36u);  // the default
    for (const json& point : pupil["border"]) EXPECT_TRUE(in_image(point)) << point.dump();
    EXPECT_TRUE(in_image(pupil["refracted_center"])) << pupil["refracted_center"].dump();
    ASSERT_FALSE(pupil["ellipse"].is_null());
    // The ellipse's centre lies near the refracted pupil centre (a circle
    // seen through the cornea is close to, not exactly, an ellipse).
    EXPECT_NEAR(pupil["ellipse"]["center_u_px"].get<double>(),
                pupil["refracted_center"]["u_px"].get<double>(), 2.0);
  }
}

TEST_P(BundledScene, WritesCsvToStandardOutput) {
  const fs::path scene = kSourceDir / "assets/scenes" / GetParam();
  ASSERT_EQ(run("truth " + quoted(scene.string()) + " --format csv --pupil-points 12"), 0) << err();
  std::istringstream in(out());
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header.rfind("camera,camera_name,eye,feature,", 0), 0u) << header;
  int glints = 0, border = 0, rows = 0;
  for (std::string line; std::getline(in, line); ++rows) {
    glints += line.find(",glint,") != std::string::npos;
    border += line.find(",pupil_border,") != std::string::npos;
  }
  EXPECT_GE(glints, 2);
  EXPECT_EQ(border, 12);
  EXPECT_EQ(rows, glints + border + 5);  // ellipse, 2 pupil centres, cornea and rotation centres
  EXPECT_FALSE(mentions_non_finite(out()));
}

TEST_P(BundledScene, PicksCsvFromTheOutputFileExtension) {
  const fs::path scene = kSourceDir / "assets/scenes" / GetParam();
  const fs::path output = output_dir_ / "labels.csv";
  ASSERT_EQ(run("truth " + quoted(scene.string()) + " -o " + quoted(output.string())), 0) << err();
  EXPECT_EQ(read(output).rfind("camera,camera_name,", 0), 0u);
}

INSTANTIATE_TEST_SUITE_P(Scenes, BundledScene, ::testing::Values("remote.json", "headset.json"),
                         [](const auto& info) { return fs::path(info.param).stem().string(); });

TEST_F(Cli, WritesJsonToStandardOutputWithoutOutputOption) {
  ASSERT_EQ(run("truth " + quoted((kSourceDir / "assets/scenes/remote.json").string())), 0) << err();
  const json labels = json::parse(out());
  EXPECT_EQ(labels["scene"], "remote");
  EXPECT_TRUE(err().empty()) << err();
}

TEST_F(Cli, HelpExitsZeroForTheProgramAndEverySubcommand) {
  for (const char* arguments :
       {"--help", "truth --help", "render --help", "track --help", "score --help", "calibrate --help"}) {
    EXPECT_EQ(run(arguments), 0) << arguments;
    EXPECT_NE(out().find("Usage"), std::string::npos) << arguments << ": " << out();
    EXPECT_NE(out().find("Exit codes"), std::string::npos) << arguments << ": " << out();
  }
}

TEST_F(Cli, VersionExitsZero) {
  EXPECT_EQ(run("--version"), 0);
  EXPECT_EQ(out().rfind("purkinje ", 0), 0u) << out();
  EXPECT_NE(out().find("embree: isa "), std::string::npos) << out();
}

TEST_F(Cli, UsageErrorsExitTwo) {
  const std::string scene = quoted((kSourceDir / "assets/scenes/remote.json").string());
  EXPECT_EQ(run(""), 2) << "no subcommand";
  EXPECT_EQ(run("truth"), 2) << "no scene";
  EXPECT_EQ(run("render " + scene), 2) << "render without an output folder";
  EXPECT_EQ(run("render " + scene + " -o " + quoted(output_dir_.string()) + " --samples 0"), 2);
  EXPECT_EQ(run("render " + scene + " -o " + quoted(output_dir_.string()) + " --mode magic"), 2);
  EXPECT_EQ(run("render " + scene + " -o " + quoted(output_dir_.string()) + " --mode reference --photons 0"), 2);
  EXPECT_EQ(run("render " + scene + " -o " + quoted(output_dir_.string()) + " --edge-samples -1"), 2);
  EXPECT_EQ(run("truth " + scene + " --format xml"), 2);
  EXPECT_EQ(run("truth " + scene + " --pupil-points -3"), 2);
  EXPECT_EQ(run("truth " + scene + " --no-such-option"), 2);
  EXPECT_TRUE(output_dir_entries().empty());
}

TEST_F(Cli, MissingSceneFileIsBadInput) {
  EXPECT_EQ(run("truth " + quoted((root_ / "nowhere.json").string())), 1);
  EXPECT_NE(err().find("nowhere.json"), std::string::npos) << err();
}

TEST_F(Cli, UnwritableOutputExitsThreeAndLeavesNothing) {
  const std::string scene = quoted((kSourceDir / "assets/scenes/remote.json").string());
  const fs::path no_dir = output_dir_ / "missing" / "labels.json";
  EXPECT_EQ(run("truth " + scene + " -o " + quoted(no_dir.string())), 3);
  EXPECT_NE(err().find(no_dir.string()), std::string::npos) << err();
  EXPECT_TRUE(output_dir_entries().empty());

  // Standard output that refuses the labels: a full device.
  if (fs::exists("/dev/full")) {
    const std::string command = quoted(kExecutable.string()) + " truth " + scene +
                                " >/dev/full 2>" + quoted((root_ / "stderr.txt").string());
    const int status = std::system(command.c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 3) << err();
  }

  fs::create_directory(output_dir_ / "taken.json");  // a directory where the file should go
  EXPECT_EQ(run("truth " + scene + " -o " + quoted((output_dir_ / "taken.json").string())), 3);
  EXPECT_EQ(output_dir_entries(), std::vector<std::string>{"taken.json"});
}

// ------------------------------------------------------------- render

// A headset render at one sample per pixel takes about a second in Debug.
std::string render_arguments(const fs::path& output) {
  return "render " + quoted((kSourceDir / "assets/scenes/headset.json").string()) + " -o " +
         quoted(output.string()) + " --samples 1";
}

TEST_F(Cli, RenderWritesTheImageItsAovsAndLabels) {
  ASSERT_EQ(run(render_arguments(output_dir_) + " --seed 3"), 0) << err();
  const std::vector<std::string> expected{"headset_eye_cam.exr", "headset_eye_cam.json", "headset_eye_cam.png"};
  std::vector<std::string> names = output_dir_entries();
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, expected);
  EXPECT_NE(out().find("headset_eye_cam.png"), std::string::npos) << out();
  // A PNG file starts with its 8-byte signature.
  EXPECT_EQ(read(output_dir_ / "headset_eye_cam.png").substr(0, 8), std::string("\x89PNG\r\n\x1a\n"));
  const std::string text = read(output_dir_ / "headset_eye_cam.json");
  EXPECT_FALSE(mentions_non_finite(text));
  const json labels = json::parse(text);
  EXPECT_EQ(labels["render"]["files"]["image"], "headset_eye_cam.png");
  EXPECT_EQ(labels["render"]["seed"], 3);
  EXPECT_EQ(labels["render"]["samples_per_pixel"], 1);
  EXPECT_EQ(labels["render"]["edge_samples_per_pixel"], 16);
  EXPECT_EQ(labels["render"]["glints"].size(), 8u);
}

TEST_F(Cli, RenderOfABadSceneExitsOneAndWritesNothing) {
  const fs::path bad = kSourceDir / "tests/data/malformed/sensor_bits_unsupported.json";
  EXPECT_EQ(run("render " + quoted(bad.string()) + " -o " + quoted(output_dir_.string())), 1);
  EXPECT_NE(err().find(bad.string()), std::string::npos) << err();
  EXPECT_TRUE(output_dir_entries().empty());
  EXPECT_EQ(run(render_arguments(output_dir_) + " --camera no_such_camera"), 1);
  EXPECT_NE(err().find("no_such_camera"), std::string::npos) << err();
}

// A bad mesh is found when the scene is read, before any pixel: exit 1,
// the file, key, value and rule on standard error, nothing in the folder.
TEST_F(Cli, RenderWithAMissingOrCorruptMeshExitsOneAndWritesNothing) {
  const fs::path malformed = kSourceDir / "tests/data/malformed";
  const std::pair<const char*, const char*> cases[] = {
      {"mesh_missing_file.json", ": meshes[0].file = \"meshes/no_such.obj\": no such file (looked for "},
      {"mesh_face_index_out_of_range.json",
       ": meshes[0].file = \"meshes/face_index_out_of_range.obj\": line 12: face index 40 out of range "
       "(file has 8 vertices)"},
      {"mesh_garbage.json", ": meshes[0].file = \"meshes/garbage.obj\": line 1: unknown statement \"This\""},
  };
  for (const auto& [name, message] : cases) {
    const fs::path scene = malformed / name;
    EXPECT_EQ(run("render " + quoted(scene.string()) + " -o " + quoted(output_dir_.string()) + " --samples 1"), 1)
        << name << "\n" << err();
    EXPECT_NE(err().find(scene.string() + message), std::string::npos) << err();
    EXPECT_TRUE(output_dir_entries().empty()) << name;
    EXPECT_TRUE(out().empty()) << name << ": " << out();
  }
}

TEST_F(Cli, RendersTheGlassesSceneWithItsFrame) {
  const fs::path scene = kSourceDir / "assets/scenes/remote_glasses.json";
  ASSERT_EQ(run("render " + quoted(scene.string()) + " -o " + quoted(output_dir_.string()) + " --samples 1"), 0)
      << err();
  std::vector<std::string> names = output_dir_entries();
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"remote_glasses_cam0.exr", "remote_glasses_cam0.json",
                                             "remote_glasses_cam0.png"}));
  // The frame leaves both glints in view.
  const json labels = json::parse(read(output_dir_ / "remote_glasses_cam0.json"));
  for (const json& glint : labels["views"][0]["glints"]) EXPECT_EQ(glint["status"], "ok") << glint.dump();
}

// Two cameras whose names differ only in characters that file names drop
// would overwrite each other's files: refused before anything is written.
TEST_F(Cli, RenderRefusesCamerasThatWouldShareFileNames) {
  std::ifstream in(kSourceDir / "assets/scenes/headset.json");
  std::stringstream text;
  text << in.rdbuf();
  std::string scene = text.str();
  const std::string camera = "\"name\": \"eye_cam\",";
  const std::size_t at = scene.find(camera);
  ASSERT_NE(at, std::string::npos);
  const std::size_t open = scene.rfind('{', at);
  const std::size_t close = scene.find("\n    }", at) + 6;
  std::string second = scene.substr(open, close - open);
  second.replace(second.find("eye_cam"), 7, "eye cam");
  scene.insert(close, ",\n    " + second);
  const fs::path file = root_ / "two_cameras.json";
  std::ofstream(file) << scene;
  EXPECT_EQ(run("render " + quoted(file.string()) + " -o " + quoted(output_dir_.string()) + " --samples 1"), 1)
      << err();
  EXPECT_NE(err().find("eye cam"), std::string::npos) << err();
  EXPECT_TRUE(output_dir_entries().empty());
}

TEST_F(Cli, RenderIntoAnUnwritableFolderExitsThree) {
  std::ofstream(output_dir_ / "a_file") << "not a folder";
  EXPECT_EQ(run(render_arguments(output_dir_ / "a_file" / "images")), 3);
  EXPECT_NE(err().find("a_file"), std::string::npos) << err();
  EXPECT_EQ(output_dir_entries(), std::vector<std::string>{"a_file"});
}

// A full disk, simulated by a file-size limit of 32 kB (ulimit -f counts
// 512-byte blocks) with SIGXFSZ ignored, so writes fail with EFBIG.
TEST_F(Cli, RenderOntoAFullDiskExitsThreeAndLeavesNoFile) {
  const std::string command = "bash -c " +
                              quoted("trap '' XFSZ; ulimit -f 64; exec " + quoted(kExecutable.string()) +
                                     " " + render_arguments(output_dir_)) +
                              " >/dev/null 2>" + quoted((root_ / "stderr.txt").string());
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status)) << err();
  EXPECT_EQ(WEXITSTATUS(status), 3) << err();
  EXPECT_NE(err().find("File too large"), std::string::npos) << err();
  EXPECT_TRUE(output_dir_entries().empty());
}

}  // namespace

// A small labelled set: the remote scene's eye turned and its pupil
// resized three times, tracked, then the detections scored again as
// another tracker's would be.
TEST_F(Cli, RendersVariationsThenTracksAndScoresThem) {
  const std::string scene = quoted((kSourceDir / "assets/scenes/remote.json").string());
  const fs::path set = output_dir_ / "set";
  ASSERT_EQ(run("render " + scene + " -o " + quoted(set.string()) + " --variations 3 --seed 5 --edge-samples 0"), 0)
      << err();
  for (const char* stem : {"remote_v0000_cam0", "remote_v0001_cam0", "remote_v0002_cam0"}) {
    for (const char* extension : {".png", ".exr", ".json"}) {
      EXPECT_TRUE(fs::exists(set / (std::string(stem) + extension))) << stem << extension;
    }
  }
  const std::string list = read(set / "variations.csv");
  EXPECT_EQ(std::count(list.begin(), list.end(), '\n'), 4) << list;
  const json labels = json::parse(read(set / "remote_v0001_cam0.json"));
  EXPECT_EQ(labels["render"]["seed"], 6);  // --seed plus the variation's index
  const double pupil = labels["eyes"][0]["pupil_radius_mm"];
  EXPECT_GE(pupil, 1);
  EXPECT_LE(pupil, 4);

  const fs::path tracked = output_dir_ / "tracked";
  ASSERT_EQ(run("track " + quoted(set.string()) + " -o " + quoted(tracked.string()) + " --scene " + scene +
                " --overlays 2"),
            0)
      << err();
  EXPECT_NE(out().find("tracked 3 images"), std::string::npos) << out();
  const json score = json::parse(read(tracked / "score.json"));
  EXPECT_EQ(score["images"], 3);
  EXPECT_GT(score["glints"]["labelled"].get<int>(), 0);
  EXPECT_EQ(score["glints"]["found"], score["glints"]["labelled"]);
  EXPECT_EQ(score["glints"]["false_positives"], 0);
  EXPECT_EQ(score["glints"]["identity_rate"], 1.0);
  EXPECT_LT(score["glints"]["error_px"]["max"].get<double>(), 0.5);
  EXPECT_EQ(score["pupils"]["found"], 3);
  EXPECT_LT(score["pupils"]["error_px"]["max"].get<double>(), 1.0);
  EXPECT_FALSE(mentions_non_finite(read(tracked / "score.json")));
  EXPECT_FALSE(mentions_non_finite(read(tracked / "score.csv")));
  EXPECT_TRUE(fs::exists(tracked / "score.txt"));
  std::size_t overlays = 0;
  for (const auto& e : fs::directory_iterator(tracked / "overlays")) overlays += e.path().extension() == ".png";
  EXPECT_EQ(overlays, 2u);

  // The same detections, read back as another tracker's: the same score.
  const fs::path scored = output_dir_ / "scored";
  ASSERT_EQ(run("score --detections " + quoted((tracked / "detections.csv").string()) + " " + quoted(set.string()) +
                " -o " + quoted(scored.string())),
            0)
      << err();
  EXPECT_EQ(json::parse(read(scored / "score.json")), score);
  EXPECT_FALSE(fs::exists(scored / "detections.csv"));
}

TEST_F(Cli, ScoreNamesTheLineOfAMalformedDetectionAndWritesNothing) {
  const std::string scene = quoted((kSourceDir / "assets/scenes/remote.json").string());
  const fs::path set = output_dir_ / "set";
  ASSERT_EQ(run("render " + scene + " -o " + quoted(set.string()) + " --edge-samples 0"), 0) << err();
  const fs::path detections = root_ / "theirs.csv";
  const fs::path scored = output_dir_ / "scored";
  std::ofstream(detections) << "image,feature,u_px,v_px\nremote_cam0.png,glint,316.6,239.5\n"
                               "remote_cam0.png,pupil,317.7,2x4.9\n";
  EXPECT_EQ(run("score --detections " + quoted(detections.string()) + " " + quoted(set.string()) + " -o " +
                quoted(scored.string())),
            1);
  EXPECT_NE(err().find("theirs.csv:3: column v_px = \"2x4.9\""), std::string::npos) << err();
  EXPECT_FALSE(fs::exists(scored));

  // Rows of an image outside the inputs are left out with a note naming the first.
  std::ofstream(detections) << "image,feature,u_px,v_px\nsomewhere_else.png,glint,316.6,239.5\n";
  EXPECT_EQ(run("score --detections " + quoted(detections.string()) + " " + quoted(set.string()) + " -o " +
                quoted(scored.string())),
            0);
  EXPECT_NE(err().find("1 images of the detections file are not among the labelled ones and were left out, the "
                       "first somewhere_else.png (line 2)"),
            std::string::npos)
      << err();

  // Their detections of one glint only: the other glint missed; a file
  // without pupil rows does not score pupils (they are not "missed").
  std::ofstream(detections) << "image,feature,u_px,v_px\nremote_cam0.png,glint,316.6,239.5\n";
  ASSERT_EQ(run("score --detections " + quoted(detections.string()) + " " + quoted(set.string()) + " -o " +
                quoted(scored.string())),
            0)
      << err();
  const json score = json::parse(read(scored / "score.json"));
  EXPECT_EQ(score["glints"]["labelled"], 2);
  EXPECT_EQ(score["glints"]["found"], 1);
  EXPECT_EQ(score["pupils"]["reported"], false);
  EXPECT_EQ(score["pupils"]["labelled"], 0);
  EXPECT_NE(err().find("no pupil rows: pupils not scored"), std::string::npos) << err();
  EXPECT_NE(read(scored / "score.txt").find("pupils      not in the detections file: not scored"), std::string::npos)
      << read(scored / "score.txt");
  EXPECT_TRUE(score["glints"]["identity_rate"].is_null());  // no light told

  EXPECT_EQ(run("track " + quoted(root_.string() + "/nowhere") + " -o " + quoted(scored.string())), 1);
  EXPECT_NE(err().find("nowhere"), std::string::npos) << err();
}

// The calibration end to end on the headset: renders, detects, calibrates
// and scores, writing a table, its JSON, the frames and the gaze map.
TEST_F(Cli, CalibrateWritesItsTableFramesAndGazeMap) {
  const std::string scene = quoted((kSourceDir / "assets/scenes/headset.json").string());
  ASSERT_EQ(run("calibrate " + scene + " -o " + quoted(output_dir_.string()) + " --grid 2 --fit-radius --noise-frames 3"),
            0)
      << err();
  for (const char* name : {"calibration.txt", "calibration.json", "calibration.csv", "frames.csv"}) {
    EXPECT_TRUE(fs::exists(output_dir_ / name)) << name;
  }
  const json results = json::parse(read(output_dir_ / "calibration.json"));
  ASSERT_EQ(results["runs"].size(), 4u);  // calibration and home, each by both methods
  const json& calibration = results["runs"][0];
  EXPECT_EQ(calibration["case"], "calibration");
  EXPECT_EQ(calibration["results"]["frames_used"], 9);
  EXPECT_NEAR(calibration["results"]["cornea_radius"].get<double>(), 7.8, 0.2);  // the scene's
  EXPECT_EQ(calibration["results"]["tracker_cornea_from"], "the scene's eye");
  // The detectors' noise, measured against the noise frames' labels: some
  // hundredths of a pixel; the saturated glints' own deviations, scaled
  // as measured; the spot's width, the camera's point spread.
  EXPECT_EQ(calibration["results"]["glint_noise_from"], "measured on 3 noise frames");
  EXPECT_GT(calibration["results"]["glint_noise"].get<double>(), 0.005);
  EXPECT_LT(calibration["results"]["glint_noise"].get<double>(), 0.5);
  EXPECT_GT(calibration["results"]["glint_sd_scale"].get<double>(), 0.2);
  EXPECT_LT(calibration["results"]["glint_sd_scale"].get<double>(), 5);
  EXPECT_DOUBLE_EQ(calibration["results"]["glint_spot_sigma"].get<double>(), 0.5);  // headset.json's psf_sigma_px
  const json& home = results["runs"][2];
  EXPECT_EQ(home["case"], "home");
  EXPECT_EQ(home["results"]["gaze_frames"], 4);
  EXPECT_LT(home["results"]["gaze_error_mean"].get<double>(), 1.0);  // degrees
  EXPECT_EQ(home["units"]["gaze_error_mean"], "deg");
  // One line per test frame, with the header.
  const std::string frames = read(output_dir_ / "frames.csv");
  EXPECT_EQ(std::count(frames.begin(), frames.end(), '\n'), 5);
  EXPECT_FALSE(mentions_non_finite(frames + read(output_dir_ / "calibration.txt")));
  EXPECT_NE(out().find("gaze_error_mean"), std::string::npos);
#ifdef PURKINJE_FIGURES
  // The gaze map: a panel per method at the one position, each arrow
  // scaled by its own panel's longest error (figures.json, beside it).
  EXPECT_EQ(png_size(read(output_dir_ / "gaze_error.png")), (std::pair<int, int>{1200, 420}));
  const json figures = json::parse(read(output_dir_ / "figures.json"));
  const json& panels = figures["gaze_error.png"]["panels"];
  ASSERT_EQ(panels.size(), 2u);
  const auto rows = csv_rows(read(output_dir_ / "frames.csv"));
  for (std::size_t m = 0; m < 2; ++m) {
    const std::string prefix = m == 0 ? "model" : "polynomial";
    double longest = 0;
    for (const auto& row : rows) {
      longest = std::max(longest, std::hypot(std::stod(row.at(prefix + "_x_mm")) - std::stod(row.at("target_x_mm")),
                                             std::stod(row.at(prefix + "_y_mm")) - std::stod(row.at("target_y_mm"))));
    }
    EXPECT_NEAR(panels[m]["longest_arrow"].get<double>(), longest, 1e-9 * longest) << m;
  }
#else
  EXPECT_NE(out().find("figures: not drawn"), std::string::npos) << out();
#endif
}

TEST_F(Cli, CalibrateRefusesASceneWithoutAScreenAndBadHeadMoves) {
  const fs::path no_screen = root_ / "no_screen.json";
  std::ofstream(no_screen) << R"({ "format": 1,
    "cameras": [ { "resolution_px": [640, 480], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                   "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] } ],
    "illuminators": [ { "position_mm": [-100, 0, 0] }, { "position_mm": [100, 0, 0] } ],
    "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} } ] })";
  EXPECT_EQ(run("calibrate " + quoted(no_screen.string()) + " -o " + quoted(output_dir_.string())), 1);
  EXPECT_NE(err().find("no \"screen\" block"), std::string::npos) << err();
  const std::string scene = quoted((kSourceDir / "assets/scenes/remote.json").string());
  EXPECT_EQ(run("calibrate " + scene + " -o " + quoted(output_dir_.string()) + " --head-move 100,0"), 2);
  EXPECT_NE(err().find("--head-move \"100,0\""), std::string::npos) << err();
  EXPECT_EQ(run("calibrate " + scene + " -o " + quoted(output_dir_.string()) + " --grid 0"), 2);
  EXPECT_EQ(run("calibrate " + scene + " -o " + quoted(output_dir_.string()) + " --glint-noise 0"), 2);
  EXPECT_EQ(run("calibrate " + scene + " -o " + quoted(output_dir_.string()) + " --tracker-cornea 7.8,-1"), 2);
  EXPECT_NE(err().find("--tracker-cornea \"7.8,-1\""), std::string::npos) << err();
  EXPECT_EQ(run("calibrate " + scene + " -o " + quoted(output_dir_.string()) + " --tracker-cornea 7.8"), 2);
  // A paraboloid cornea in the scene: no ellipsoid for the tracker, said before any rendering.
  const fs::path paraboloid = root_ / "paraboloid.json";
  std::string text = read(kSourceDir / "assets/scenes/remote.json");
  const std::string model = "\"model\": \"navarro\",";
  ASSERT_NE(text.find(model), std::string::npos);
  text.replace(text.find(model), model.size(), model + " \"cornea\": { \"asphericity\": -1 },");
  std::ofstream(paraboloid) << text;
  EXPECT_EQ(run("calibrate " + quoted(paraboloid.string()) + " -o " + quoted(output_dir_.string())), 1);
  EXPECT_NE(err().find("asphericity -1"), std::string::npos) << err();
  EXPECT_TRUE(output_dir_entries().empty());
}

namespace {

class CliProgress : public Cli {};

// Long commands tell k/N, the rate and the time left on stderr; in a log
// (stderr not a terminal, as here) one line per step; --quiet silences it.
TEST_F(CliProgress, LongCommandsShowProgressOnStderrUnlessQuiet) {
  const std::string scene = quoted((kSourceDir / "tests/data/tiny_remote.json").string());
  const std::string set = quoted((output_dir_ / "set").string());
  ASSERT_EQ(run("render " + scene + " -o " + set + " --variations 3"), 0) << err();
  for (const char* line : {"render: 1/3, ", "render: 2/3, ", "render: 3/3, "}) {
    EXPECT_NE(err().find(line), std::string::npos) << err();
  }
  EXPECT_NE(err().find(" per s, ETA "), std::string::npos) << err();
  ASSERT_EQ(run("track " + set + " -o " + quoted((output_dir_ / "track").string())), 0) << err();
  EXPECT_NE(err().find("track: 3/3, "), std::string::npos) << err();
  ASSERT_EQ(run("render " + scene + " -o " + set + " --variations 3 --quiet"), 0) << err();
  EXPECT_EQ(err(), "");
  ASSERT_EQ(run("track " + set + " -o " + quoted((output_dir_ / "track").string()) + " --quiet"), 0) << err();
  EXPECT_EQ(err(), "");
}

TEST_F(Cli, AMistypedSubcommandOrOptionGetsDidYouMean) {
  EXPECT_EQ(run("rendr scene.json"), 2);
  EXPECT_NE(err().find("unknown subcommand 'rendr'; did you mean 'render'?"), std::string::npos) << err();
  EXPECT_EQ(run("frobnicate"), 2);
  EXPECT_NE(err().find("unknown subcommand 'frobnicate' (subcommands: truth render track score calibrate compare generate merge)"),
            std::string::npos)
      << err();
  EXPECT_EQ(run("render --seeed 1 scene.json -o out"), 2);
  EXPECT_NE(err().find("unknown option --seeed; did you mean --seed?"), std::string::npos) << err();
  EXPECT_EQ(run("track set -o out --match-radiu 3"), 2);
  EXPECT_NE(err().find("did you mean --match-radius?"), std::string::npos) << err();
}

}  // namespace

namespace {

// Detections written the way published pupil trackers' tools write them:
// a byte-order mark, spaces after commas, a column of their own, images
// named by the path they were read from or without the extension, (-1, -1)
// for a failed frame, confidence -1 for none, and an image outside the set.
TEST_F(Cli, ScoresDetectionsWrittenTheWayOtherToolkitsWriteThem) {
  const std::string scene = quoted((kSourceDir / "tests/data/tiny_remote.json").string());
  const fs::path set = output_dir_ / "set";
  ASSERT_EQ(run("render " + scene + " -o " + quoted(set.string()) + " --variations 4 --quiet"), 0) << err();
  const json labels = json::parse(read(set / "tiny_v0000_cam0.json"));
  const json& ellipse = labels["views"][0]["pupil"]["ellipse"];
  const double u = ellipse["center_u_px"], v = ellipse["center_v_px"];
  const fs::path detections = root_ / "theirs.csv";
  std::ofstream(detections) << "\xEF\xBB\xBF" << "frame, image, feature, u_px, v_px, confidence\n"
                            << "0, /data/run7/tiny_v0000_cam0.png, pupil, " << u << ", " << v << ", -1\n"
                            << "1, tiny_v0001_cam0, pupil, -1, -1, 0\n"
                            << "2, tiny_v0002_cam0.png, pupil, " << u << ", " << v << ", 0.2\n"
                            << "3, not_in_the_set.png, pupil, 5, 5, 0.9\n";
  const fs::path scored = output_dir_ / "scored";
  ASSERT_EQ(run("score --detections " + quoted(detections.string()) + " " + quoted(set.string()) + " -o " +
                quoted(scored.string()) + " --min-confidence 0.5 --quiet"),
            0)
      << err();
  for (const char* note : {"columns not read: frame", "1 rows say nothing was found", "1 pupils below --min-confidence",
                           "the first not_in_the_set.png (line 5)", "no glint rows: glints not scored"}) {
    EXPECT_NE(err().find(note), std::string::npos) << note << "\n" << err();
  }
  const json score = json::parse(read(scored / "score.json"));
  EXPECT_EQ(score["pupils"]["labelled"], 4);
  EXPECT_EQ(score["pupils"]["found"], 1);  // v0000 by its path; v0002 below the confidence asked
  EXPECT_EQ(score["pupils"]["false_positives"], 0);
  EXPECT_EQ(score["pupils"]["nearest_px"]["none"], 3);
  EXPECT_EQ(score["glints"]["reported"], false);

  ASSERT_EQ(run("score --help"), 0);
  EXPECT_NE(out().find("(0, 0) is the centre of the top-left pixel"), std::string::npos) << out();
}

}  // namespace

namespace {

// The compare study end to end: the remote rig's Navarro eye against a
// tracker's sphere, on small grids.
TEST_F(Cli, CompareWritesItsTablesImagesAndFigures) {
  const std::string scene = quoted((kSourceDir / "assets/scenes/remote.json").string());
  ASSERT_EQ(run("compare " + scene + " -o " + quoted(output_dir_.string()) +
                " --assumed-cornea 7.8,0 --grid 3 --gaze-grid 3 --quiet"),
            0)
      << err();
  for (const char* name : {"displacements.csv", "gaze.csv", "summary.txt", "summary.json", "summary.csv",
                           "world.png", "world.exr", "world.json", "assumed.png", "assumed.exr", "assumed.json"}) {
    EXPECT_TRUE(fs::exists(output_dir_ / name)) << name;
  }
  const json summary = json::parse(read(output_dir_ / "summary.json"));
  const auto result = [&](const std::string& case_name, const std::string& algorithm, const std::string& key) {
    for (const json& r : summary["runs"]) {
      if (r["case"] == case_name && r["algorithm"] == algorithm && r["results"].contains(key)) {
        return r["results"][key].get<double>();
      }
    }
    ADD_FAILURE() << case_name << " / " << algorithm << " / " << key << " missing";
    return -1.0;
  };
  EXPECT_GT(result("displacement", "glint.led_left", "displacement_max"), 0.05);
  EXPECT_GT(result("gaze: home", "model-based", "change_max"), 0.05);
  // The polynomial believes nothing about the rig: calibrated on the same
  // frames, it estimates the same.
  EXPECT_EQ(result("gaze: home", "polynomial", "change_max"), 0.0);
  EXPECT_GT(result("images", "difference (assumed - world)", "electrons_difference_max"), 0.0);
  EXPECT_FALSE(mentions_non_finite(read(output_dir_ / "summary.txt")));
  const auto gaze = csv_rows(read(output_dir_ / "gaze.csv"));
  EXPECT_EQ(gaze.size(), 3u * 2 * 9);  // home and two moves, two methods, 3 x 3 targets
  EXPECT_EQ(gaze.back().at("position"), "moved 0,0,100 mm");
  const auto field = csv_rows(read(output_dir_ / "displacements.csv"));
  EXPECT_EQ(field.size(), 9u * 4);  // two glints, the pupil's centre and ellipse
#ifdef PURKINJE_FIGURES
  EXPECT_EQ(png_size(read(output_dir_ / "displacements.png")), (std::pair<int, int>{1800, 840}));
  EXPECT_EQ(png_size(read(output_dir_ / "gaze_change.png")), (std::pair<int, int>{1200, 1260}));
  EXPECT_EQ(png_size(read(output_dir_ / "gaze_error.png")), (std::pair<int, int>{1200, 1260}));
  // The error map's arrows run from each target to the estimate believing
  // the assumed version: each panel scaled by its own longest.
  for (const json& panel : json::parse(read(output_dir_ / "figures.json"))["gaze_error.png"]["panels"]) {
    const std::string title = panel["title"];
    double longest = 0;
    for (const auto& row : gaze) {
      if (title != row.at("method") + ", " + row.at("position")) continue;
      longest = std::max(longest, std::hypot(std::stod(row.at("believing_assumed_x_mm")) - std::stod(row.at("target_x_mm")),
                                             std::stod(row.at("believing_assumed_y_mm")) - std::stod(row.at("target_y_mm"))));
    }
    EXPECT_NEAR(panel["longest_arrow"].get<double>(), longest, 1e-9 * longest) << title;
  }
  EXPECT_EQ(png_size(read(output_dir_ / "images.png")), (std::pair<int, int>{1500, 900}));
  EXPECT_EQ(read(output_dir_ / "flip.gif").substr(0, 6), "GIF89a");
  // Each panel's arrows are scaled by its own longest (figures.json, from
  // the plot), recomputed here from the tables.
  const json figures = json::parse(read(output_dir_ / "figures.json"));
  std::vector<double> scales;
  for (const json& panel : figures["gaze_change.png"]["panels"]) {
    const std::string title = panel["title"];
    double longest = 0;
    for (const auto& row : gaze) {
      if (title != row.at("method") + ", " + row.at("position")) continue;
      longest = std::max(longest, std::hypot(std::stod(row.at("believing_assumed_x_mm")) -
                                                 std::stod(row.at("believing_world_x_mm")),
                                             std::stod(row.at("believing_assumed_y_mm")) -
                                                 std::stod(row.at("believing_world_y_mm"))));
    }
    EXPECT_NEAR(panel["longest_arrow"].get<double>(), longest, 1e-9 * longest) << title;
    if (longest > 0) scales.push_back(panel["arrow_scale_per_axis_unit"].get<double>());
  }
  ASSERT_EQ(scales.size(), 3u);  // the model-based panels; the polynomial's are empty
  EXPECT_NE(scales[0], scales[1]);
  EXPECT_NE(scales[0], scales[2]);
  for (const json& panel : figures["displacements.png"]["panels"]) {
    const std::string title = panel["title"];
    const std::string feature = title.substr(0, title.find(':'));
    double longest = 0;
    for (const auto& row : field) {
      if (row.at("feature") == feature && !row.at("displacement_px").empty()) {
        longest = std::max(longest, std::stod(row.at("displacement_px")));
      }
    }
    if (title.find("semi-axis") == std::string::npos) {
      EXPECT_NEAR(panel["longest_arrow"].get<double>(), longest, 1e-9 * longest) << title;
    }
  }
  const std::string index = read(output_dir_ / "index.md");
  for (const char* figure : {"displacements.png", "gaze_change.png", "gaze_error.png", "images.png", "flip.gif"}) {
    EXPECT_NE(index.find(std::string("](") + figure + ")"), std::string::npos) << figure;
  }
#else
  EXPECT_NE(out().find("figures: not drawn"), std::string::npos) << out();
#endif
  // Run again into the folder without images, calibration or figures: the
  // last run's files of those are gone, not left beside the new ones.
  ASSERT_EQ(run("compare " + scene + " -o " + quoted(output_dir_.string()) +
                " --grid 2 --no-images --no-calibration --no-figures --quiet"),
            0)
      << err();
  std::vector<std::string> left = output_dir_entries();
  std::sort(left.begin(), left.end());
  EXPECT_EQ(left, (std::vector<std::string>{"displacements.csv", "summary.csv", "summary.json", "summary.txt"}));
}

TEST_F(Cli, CompareRefusesBadOptionsAndVersionsThatCannotBeCompared) {
  const std::string scene = quoted((kSourceDir / "assets/scenes/remote.json").string());
  const std::string out_dir = quoted(output_dir_.string());
  EXPECT_EQ(run("compare " + scene + " -o " + out_dir + " --assumed-cornea 7.8"), 2);
  EXPECT_NE(err().find("--assumed-cornea \"7.8\": must be \"R,Q\""), std::string::npos) << err();
  EXPECT_EQ(run("compare " + scene + " -o " + out_dir + " --assumed-cornea 7.8,-1"), 2);
  EXPECT_NE(err().find("--assumed-cornea \"7.8,-1\": the assumed cornea (R, Q) = (7.8, -1): must have the apex "
                       "radius R in (0, 100) mm and the asphericity Q in (-1, 10)"),
            std::string::npos)
      << err();
  // A cornea whose cap ends inside the limbus: the anatomy's rule, named.
  EXPECT_EQ(run("compare " + scene + " -o " + out_dir + " --assumed-cornea 7.8,3"), 2);
  EXPECT_NE(err().find("the eye's anatomy refuses it: cornea.limbus_radius_mm"), std::string::npos) << err();
  EXPECT_EQ(run("compare " + scene + " -o " + out_dir + " --camera nope"), 2);
  EXPECT_NE(err().find("has no camera of that name"), std::string::npos) << err();
  EXPECT_EQ(run("compare " + scene + " -o " + out_dir + " --head-move 1,2"), 2);
  // Versions with other lights cannot be compared.
  EXPECT_EQ(run("compare " + scene + " " + quoted((kSourceDir / "assets/scenes/headset.json").string()) + " -o " +
                out_dir + " --no-images"),
            1);
  EXPECT_NE(err().find("compare: "), std::string::npos) << err();
  EXPECT_TRUE(output_dir_entries().empty());
  // The output folder is a file.
  EXPECT_EQ(run("compare " + scene + " -o " + scene), 3);
  // Eye models by preset name; a name that is neither a preset nor a file.
  EXPECT_EQ(run("compare " + scene + " -o " + out_dir + " --assumed-eye keratometric --grid 2 --gaze-grid 2 "
                "--no-images --no-figures --quiet"),
            0)
      << err();
  EXPECT_NE(read(output_dir_ / "summary.txt").find("change_max"), std::string::npos);
  fs::remove_all(output_dir_);
  fs::create_directories(output_dir_);
  EXPECT_EQ(run("compare " + scene + " -o " + out_dir + " --assumed-eye navaro"), 1);
  EXPECT_NE(err().find("navaro: cannot open the eye-model file (nor is it a preset"), std::string::npos) << err();
  // Sweeps: the text's form, no assumed version beside, a parameter known.
  EXPECT_EQ(run("compare " + scene + " -o " + out_dir + " --sweep cornea_radius"), 2);
  EXPECT_NE(err().find("must be \"NAME=FROM:TO:STEPS\""), std::string::npos) << err();
  EXPECT_EQ(run("compare " + scene + " " + scene + " -o " + out_dir + " --sweep cornea_radius=7:8:3"), 2);
  EXPECT_NE(err().find("--sweep: the assumed versions are the world with the parameter swept: no ASSUMED"),
            std::string::npos)
      << err();
  EXPECT_EQ(run("compare " + scene + " -o " + out_dir + " --sweep cornea_radius=7:8:3 --samples 4"), 2);
  EXPECT_NE(err().find("excludes"), std::string::npos) << err();
  EXPECT_EQ(run("compare " + scene + " -o " + out_dir + " --sweep corneal_radius=7:8:3"), 2);
  EXPECT_NE(err().find("--sweep \"corneal_radius=7:8:3\": sweep: unknown parameter \"corneal_radius\" (known: "
                       "cornea_radius"),
            std::string::npos)
      << err();
  EXPECT_EQ(run("compare " + scene + " -o " + out_dir + " --sweep cornea_radius=-1:8:3"), 2);
  EXPECT_NE(err().find("cornea_radius = -1: the eye's anatomy refuses it"), std::string::npos) << err();
  EXPECT_EQ(run("compare " + scene + " -o " + out_dir + " --sweep cornea_radius=7:7:3"), 2);
  EXPECT_NE(err().find("must be two different finite numbers"), std::string::npos) << err();
  EXPECT_TRUE(output_dir_entries().empty());
}

}  // namespace
