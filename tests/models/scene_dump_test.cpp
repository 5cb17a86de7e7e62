// scene_to_json: a scene written back as a scene file reads back to the
// same scene, bit for bit, and the keys that make that possible (a
// camera's rotation_matrix, an eye's optical_axis, a screen's
// top_left_mm, a mesh's vertices_mm and triangles) read as documented.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "purkinje/models/dataset_spec.h"
#include "purkinje/models/labels.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/models/truth.h"

namespace purkinje {
namespace {

namespace fs = std::filesystem;
const fs::path kSourceDir = PURKINJE_SOURCE_DIR;

std::string parse_error(const std::string& text) {
  try {
    parse_scene(text, "scene.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

// Everything a scene holds, as text: the labels (cameras, lights, eyes
// with their anatomy, appearance and axes, and every glint and pupil
// path, which any bit of a pose or an anatomy moves), the dump itself,
// and the mesh vertices.
void expect_same_scene(const Scene& a, const Scene& b, const std::string& what) {
  EXPECT_EQ(truth_to_json(a, compute_truth(a)), truth_to_json(b, compute_truth(b))) << what;
  EXPECT_EQ(scene_to_json(a), scene_to_json(b)) << what;
  ASSERT_EQ(a.meshes.size(), b.meshes.size()) << what;
  for (std::size_t m = 0; m < a.meshes.size(); ++m) {
    EXPECT_EQ(a.meshes[m].vertices, b.meshes[m].vertices) << what;
    EXPECT_EQ(a.meshes[m].triangles, b.meshes[m].triangles) << what;
  }
  for (std::size_t c = 0; c < a.cameras.size(); ++c) {
    for (int i = 0; i < 9; ++i) {
      EXPECT_EQ(a.cameras[c].world_from_camera().rotation()(i / 3, i % 3),
                b.cameras[c].world_from_camera().rotation()(i / 3, i % 3)) << what;
    }
  }
  for (std::size_t e = 0; e < a.eyes.size(); ++e) {
    EXPECT_EQ(a.eyes[e].model().kappa_horizontal_rad, b.eyes[e].model().kappa_horizontal_rad) << what;
    EXPECT_EQ(a.eyes[e].model().kappa_vertical_rad, b.eyes[e].model().kappa_vertical_rad) << what;
    EXPECT_EQ(a.eyes[e].appearance().head_forward, b.eyes[e].appearance().head_forward) << what;
    EXPECT_EQ(a.eyes[e].appearance().head_up, b.eyes[e].appearance().head_up) << what;
  }
  ASSERT_EQ(a.screen.has_value(), b.screen.has_value()) << what;
  if (a.screen) {
    EXPECT_EQ(a.screen->top_left, b.screen->top_left) << what;
    EXPECT_EQ(a.screen->right, b.screen->right) << what;
    EXPECT_EQ(a.screen->down, b.screen->down) << what;
  }
}

Scene read_back(const Scene& scene) { return parse_scene(scene_to_json(scene), scene.name + " (dump)"); }

TEST(SceneDump, EveryBundledSceneReadsBackBitForBit) {
  std::vector<fs::path> files = {"assets/scenes/remote.json", "assets/scenes/headset.json",
                                 "assets/scenes/remote_glasses.json"};
  for (const auto& entry : fs::directory_iterator(kSourceDir / "assets/scenes/hard")) {
    files.push_back(fs::relative(entry.path(), kSourceDir));
  }
  for (const fs::path& file : files) {
    const Scene scene = load_scene(kSourceDir / file);
    expect_same_scene(scene, read_back(scene), file.string());
  }
}

// Data sets turn heads, eyes and kappa in code, where rounding leaves unit
// vectors a hair off unit length: the reader must keep their bits.
TEST(SceneDump, ScenesDrawnByTheBundledDataSetsReadBackBitForBit) {
  for (const char* file : {"assets/datasets/remote.json", "assets/datasets/headset.json"}) {
    const DatasetSpec spec = load_dataset_spec(kSourceDir / file);
    for (std::uint64_t k = 0; k < 12; ++k) {
      const Scene scene = scene_for_image(spec, draw_image(spec, k));
      expect_same_scene(scene, read_back(scene), std::string(file) + " image " + std::to_string(k));
    }
  }
}

TEST(SceneDump, IsPlainJsonWithEveryValueWritten) {
  const Scene scene = load_scene(kSourceDir / "assets/scenes/remote_glasses.json");
  const std::string text = scene_to_json(scene);
  EXPECT_EQ(text.find("//"), std::string::npos);
  EXPECT_EQ(text.back(), '\n');
  for (const char* key : {"\"rotation_matrix\"", "\"intrinsics_px\"", "\"sensor\"", "\"optical_axis\"",
                          "\"cornea_center_mm\"", "\"kappa_deg\"", "\"appearance\"", "\"vertices_mm\"",
                          "\"triangles\"", "\"posterior_cornea\"", "\"emitter_diameter_mm\""}) {
    EXPECT_NE(text.find(key), std::string::npos) << key;
  }
}

// A file's kappa is d * (pi / 180), and the dump's quotient gives its
// degrees back exactly. Radians set in code may lie between two such
// products (their steps are up to 1.1 ulp apart) and come back within an ulp.
TEST(SceneDump, KappaRadiansSurviveTheTripThroughDegrees) {
  constexpr double kDegree = std::numbers::pi / 180.0;
  Scene scene = load_scene(kSourceDir / "assets/scenes/remote.json");
  int inexact = 0;
  for (int i = 1; i <= 400; ++i) {
    EyeModel model = scene.eyes[0].model();
    const double degrees = std::fmod(i * 0.6180339887498949, 1.0) * 90.0 - 45.0;
    model.kappa_horizontal_rad = degrees * kDegree;
    model.kappa_vertical_rad = std::fmod(i * 0.7548776662466927, 1.0) * 1.5 - 0.75;  // radians set in code
    scene.eyes[0] = Eye::with_cornea_center(model, scene.eyes[0].cornea_center(), scene.eyes[0].optical_axis());
    const Scene back = read_back(scene);
    ASSERT_EQ(back.eyes[0].model().kappa_horizontal_rad, model.kappa_horizontal_rad) << degrees << " deg";
    const double v = model.kappa_vertical_rad, v_back = back.eyes[0].model().kappa_vertical_rad;
    ASSERT_LE(std::abs(v_back - v), std::nextafter(std::abs(v), 1.0) - std::abs(v)) << v << " rad";
    inexact += v_back != v;
  }
  EXPECT_GT(inexact, 0) << "radians between products no longer occur: the ulp bound is untested";
}

TEST(SceneDump, RefusesWhatTheFormatCannotHold) {
  Scene scene = load_scene(kSourceDir / "assets/scenes/remote.json");
  EyeModel custom = scene.eyes[0].model();
  custom.name = "mine";
  scene.eyes[0] = Eye::with_cornea_center(custom, scene.eyes[0].cornea_center(), scene.eyes[0].optical_axis());
  try {
    scene_to_json(scene);
    ADD_FAILURE() << "a model that is no preset was dumped";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "eyes[0]: model \"mine\" is no preset, and a scene file starts every eye from one "
                           "(keratometric, le_grand, navarro)");
  }
  // Torsion: the eye frame's x no longer follows the world's.
  const Eye straight = load_scene(kSourceDir / "assets/scenes/remote.json").eyes[0];
  const Rotation roll = Rotation::from_axis_angle(straight.optical_axis(), 0.1);
  scene.eyes[0] = Eye(straight.model(), Pose(roll * straight.world_from_eye().rotation(),
                                              straight.world_from_eye().translation()));
  EXPECT_THROW(scene_to_json(scene), std::invalid_argument);
}

std::string camera_scene(const std::string& orientation) {
  return R"({ "format": 1,
    "cameras": [ { "resolution_px": [64, 48], "intrinsics_px": { "fx": 2000, "fy": 2000 },
                   "position_mm": [0, 0, 1200], )" + orientation + R"( } ],
    "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} } ] })";
}

TEST(SceneDump, RotationMatrixTurnsTheCameraAsItsRotationVectorDoes) {
  const Scene by_vector = parse_scene(camera_scene(R"("rotation_vector_deg": [0, 180, 0])"), "s.json");
  const Scene by_matrix =
      parse_scene(camera_scene(R"("rotation_matrix": [[-1, 0, 0], [0, 1, 0], [0, 0, -1]])"), "s.json");
  for (int i = 0; i < 9; ++i) {
    EXPECT_NEAR(by_vector.cameras[0].world_from_camera().rotation()(i / 3, i % 3),
                by_matrix.cameras[0].world_from_camera().rotation()(i / 3, i % 3), 1e-15);
  }
  EXPECT_EQ(parse_error(camera_scene(R"("rotation_matrix": [[1, 0, 0], [0, 1, 0], [0, 0, -1]])")),
            "scene.json: cameras[0].rotation_matrix = [[1, 0, 0], [0, 1, 0], [0, 0, -1]]: must be a rotation: "
            "orthonormal columns, right-handed (determinant +1), within 1e-9");
  // Columns of other lengths are no rotation, not a rotation to normalize.
  EXPECT_NE(parse_error(camera_scene(R"("rotation_matrix": [[1, 0, 0], [0, 5, 0], [0, 0, 1]])")).find("must be a rotation"),
            std::string::npos);
  EXPECT_NE(parse_error(camera_scene(R"("rotation_matrix": [[0.5, 0, 0], [0, 0.5, 0], [0, 0, 0.5]])")).find("must be a rotation"),
            std::string::npos);
  EXPECT_EQ(parse_error(camera_scene(R"("rotation_matrix": [[1, 0, 0], [0, 1, 0]])")),
            "scene.json: cameras[0].rotation_matrix = [[1, 0, 0], [0, 1, 0]]: must be a 3 x 3 rotation matrix, "
            "rows [[r00, r01, r02], [r10, r11, r12], [r20, r21, r22]]");
  EXPECT_EQ(parse_error(camera_scene(R"("rotation_matrix": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "look_at_mm": [0, 0, 0])")),
            "scene.json: cameras[0]: give exactly one of look_at_mm, rotation_vector_deg and rotation_matrix, "
            "not several");
  EXPECT_EQ(parse_error(camera_scene(R"("rotation_matrix": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "up": [0, -1, 0])")),
            "scene.json: cameras[0].up = [0, -1, 0]: only used with look_at_mm");
}

std::string eye_scene(const std::string& eye) {
  return R"({ "format": 1,
    "cameras": [ { "resolution_px": [64, 48], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                   "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] } ],
    "eyes": [ )" + eye + " ] }";
}

TEST(SceneDump, OpticalAxisOrientsTheEyeAsYawAndPitchDo) {
  const Scene by_angles = parse_scene(
      eye_scene(R"({ "position": { "rotation_center_mm": [0, 0, 600] }, "orientation": { "yaw_deg": 30, "pitch_deg": 0 } })"),
      "s.json");
  // (sin 30, 0, -cos 30), given at twice unit length: normalized.
  const Scene by_axis = parse_scene(
      eye_scene(R"({ "position": { "rotation_center_mm": [0, 0, 600] }, "orientation": { "optical_axis": [1, 0, -1.7320508075688772] } })"),
      "s.json");
  EXPECT_NEAR(angle_between(by_angles.eyes[0].optical_axis(), by_axis.eyes[0].optical_axis()), 0, 1e-15);
  EXPECT_NEAR(distance(by_angles.eyes[0].cornea_center(), by_axis.eyes[0].cornea_center()), 0, 1e-12);
  EXPECT_EQ(parse_error(eye_scene(R"({ "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": { "optical_axis": [0, 0, -1], "yaw_deg": 3 } })")),
            "scene.json: eyes[0].orientation.yaw_deg = 3: cannot be combined with optical_axis");
  EXPECT_EQ(parse_error(eye_scene(R"({ "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": { "optical_axis": [0, 0, -1], "gaze_target_mm": [0, 0, 0] } })")),
            "scene.json: eyes[0].orientation.optical_axis = [0, 0, -1]: cannot be combined with gaze_target_mm");
  EXPECT_EQ(parse_error(eye_scene(R"({ "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": { "optical_axis": [0, 0, 0] } })")),
            "scene.json: eyes[0].orientation.optical_axis = [0, 0, 0]: must not be the zero vector");
}

TEST(SceneDump, TopLeftPlacesTheScreenAsItsCentreDoes) {
  const std::string base = R"({ "format": 1,
    "cameras": [ { "resolution_px": [64, 48], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                   "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] } ],
    "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} } ], "screen": )";
  const Scene centred = parse_scene(base + R"({ "center_mm": [0, -182, 0], "size_mm": [518, 324] } })", "s.json");
  const Scene corner = parse_scene(base + R"({ "top_left_mm": [-259, -344, 0], "size_mm": [518, 324] } })", "s.json");
  EXPECT_EQ(centred.screen->top_left, corner.screen->top_left);
  EXPECT_EQ(corner.screen->center(), (Point3{0, -182, 0}));
  EXPECT_EQ(parse_error(base + R"({ "center_mm": [0, 0, 0], "top_left_mm": [0, 0, 0], "size_mm": [5, 3] } })"),
            "scene.json: screen: give exactly one of center_mm and top_left_mm, not both");
}

std::string mesh_scene(const std::string& mesh) {
  return R"({ "format": 1,
    "cameras": [ { "resolution_px": [64, 48], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                   "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] } ],
    "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} } ],
    "meshes": [ )" + mesh + " ] }";
}

TEST(SceneDump, InlineMeshesArePlacedAsFileMeshesAre) {
  const Scene scene = parse_scene(mesh_scene(R"({ "name": "card", "albedo": 0.4, "position_mm": [10, 0, 500], "scale": 2,
      "vertices_mm": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [5, 5, 5]], "triangles": [[0, 1, 2], [0, 2, 3], [0, 0, 1]] })"),
                                  "s.json");
  ASSERT_EQ(scene.meshes.size(), 1u);
  const Mesh& mesh = scene.meshes[0];
  EXPECT_EQ(mesh.vertices[2], (Point3{12, 2, 500}));
  EXPECT_EQ(mesh.triangles.size(), 2u);  // the one without area is left out
  EXPECT_EQ(mesh.albedo, 0.4);
  EXPECT_EQ(parse_error(mesh_scene(R"({ "albedo": 0.4, "vertices_mm": [[0, 0, 0], [1, 0, 0], [1, 1, 0]], "triangles": [[0, 1, 3]] })")),
            "scene.json: meshes[0].triangles[0][2] = 3: must be a vertex index from 0 to 2");
  EXPECT_EQ(parse_error(mesh_scene(R"({ "albedo": 0.4, "vertices_mm": [[0, 0, 0], [1, 0, 0], [1, 1, 0]], "triangles": [[0, 1]] })")),
            "scene.json: meshes[0].triangles[0] = [0, 1]: must be an array of 3 vertex indices");
  EXPECT_EQ(parse_error(mesh_scene(R"({ "albedo": 0.4, "vertices_mm": [[0, 0, 0], [1, 0, 0], [1, 1, 0]], "triangles": [] })")),
            "scene.json: meshes[0].triangles = []: must hold at least one triangle");
  EXPECT_EQ(parse_error(mesh_scene(R"({ "albedo": 0.4, "vertices_mm": [[0, 0, 0], [1, 0, 0], [1, 1, 0]] })")),
            "scene.json: meshes[0].triangles: missing required key ([[i, j, k], ...], vertex indices from 0)");
  EXPECT_EQ(parse_error(mesh_scene(R"({ "albedo": 0.4, "file": "x.obj", "vertices_mm": [[0, 0, 0]], "triangles": [[0, 0, 0]] })")),
            "scene.json: meshes[0]: give exactly one of file and vertices_mm, not both");
  EXPECT_EQ(parse_error(mesh_scene(R"({ "albedo": 0.4, "vertices_mm": [[0, 0, 0], [1, 0, 0], [1, 1, 0]], "triangles": [[0, 0, 1]] })")),
            "scene.json: meshes[0].vertices_mm = [[0, 0, 0], [1, 0, 0], [1, 1, 0]]: all 1 triangles have zero area "
            "once placed (scale 1, position_mm [0, 0, 0]): check scale and position_mm");
}

}  // namespace
}  // namespace purkinje
