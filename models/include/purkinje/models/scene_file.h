#pragma once
// JSON scene files (comments allowed), format version 1. Every key is
// documented in docs/scene-format.md. Errors name the file, the key path,
// the value and the rule:
//   scene.json: eyes[0].cornea.radius_mm = -7.8: must be > 0

#include <filesystem>
#include <stdexcept>
#include <string>

#include "purkinje/models/scene.h"

namespace purkinje {

class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline constexpr int kSceneFormatVersion = 1;

// Reads and validates a scene file, and the mesh files it names (relative
// to the scene file's folder); throws SceneError.
Scene load_scene(const std::filesystem::path& file);
// Parses scene text; `source_name` is used in error messages, and relative
// mesh file names are resolved against `folder` (empty: the current one).
Scene parse_scene(const std::string& text, const std::string& source_name,
                  const std::filesystem::path& folder = {});

// The scene as a scene file in plain JSON (no comments), ending in a
// newline: parse_scene reads it back to the same scene bit for bit. Every
// value is written, numbers exactly; cameras by their intrinsics and
// rotation matrix, eyes by cornea centre and optical axis, the screen by
// its top-left corner, meshes inline in world coordinates. Throws
// std::invalid_argument for what the format cannot hold: an eye model
// that is no preset's (a file starts each eye from one), or an eye turned
// about its optical axis.
std::string scene_to_json(const Scene& scene);

}  // namespace purkinje
