// Fuzz target: the scene reader (parse_scene). It documents one exception,
// SceneError; anything else escaping, a crash or a sanitizer report is a
// finding. On success, the scene must hold what parse_scene promises (a
// validated scene, docs/scene-format.md): an eye and a camera at least,
// every position finite, cameras with positive finite focal lengths, and
// meshes with finite vertices, indices in range and no triangle of zero
// area.
//
// Mesh files named by a scene are resolved against a folder this target
// makes once in the temporary directory, so that a relative name never
// reaches a file of the tree or of the user. It holds a small valid mesh,
// square.obj, and a FIFO, fifo.obj: the corpus names both (a FIFO mesh
// file blocked the reader forever before it refused non-regular files).
// Absolute names reach the real file system; the reader opens them
// read-only and refuses anything but a regular file of sane size.


#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "fuzz_target.h"
#include "purkinje/models/scene_file.h"

namespace {

// A unit square in the z = 0 plane, two triangles.
constexpr const char* kSquareObj =
    "v 0 0 0\n"
    "v 1 0 0\n"
    "v 1 1 0\n"
    "v 0 1 0\n"
    "f 1 2 3 4\n";

const std::filesystem::path& mesh_folder() {
  static const FuzzFolder folder("scene", {{"square.obj", kSquareObj}}, "fifo.obj");
  return folder.path();
}

}  // namespace

PURKINJE_FUZZ_TARGET(scene) {
  purkinje::Scene scene;
  try {
    scene = purkinje::parse_scene(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json",
                                  mesh_folder());
  } catch (const purkinje::SceneError&) {
    return 0;
  }
  PURKINJE_FUZZ_CHECK(!scene.eyes.empty());
  PURKINJE_FUZZ_CHECK(!scene.cameras.empty());
  for (const purkinje::Eye& eye : scene.eyes) {
    PURKINJE_FUZZ_CHECK(eye.cornea_center().is_finite() && eye.rotation_center().is_finite());
    PURKINJE_FUZZ_CHECK(eye.corneal_apex().is_finite() && eye.pupil_center().is_finite());
  }
  for (const purkinje::Camera& camera : scene.cameras) {
    PURKINJE_FUZZ_CHECK(camera.center().is_finite());
    const purkinje::Intrinsics& k = camera.intrinsics();
    PURKINJE_FUZZ_CHECK(k.width >= 1 && k.height >= 1);
    PURKINJE_FUZZ_CHECK(k.fx > 0 && k.fy > 0 && std::isfinite(k.fx) && std::isfinite(k.fy));
    PURKINJE_FUZZ_CHECK(std::isfinite(k.cx) && std::isfinite(k.cy));
  }
  for (const purkinje::Illuminator& light : scene.illuminators) {
    PURKINJE_FUZZ_CHECK(light.position.is_finite());
    PURKINJE_FUZZ_CHECK(light.radiant_intensity_w_sr >= 0 && std::isfinite(light.radiant_intensity_w_sr));
  }
  if (scene.screen) PURKINJE_FUZZ_CHECK(scene.screen->center().is_finite());
  for (const purkinje::Mesh& mesh : scene.meshes) {
    PURKINJE_FUZZ_CHECK(mesh.albedo >= 0 && mesh.albedo <= 1);
    check_mesh_promises(mesh);
  }
  return 0;
}
