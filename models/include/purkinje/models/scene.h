#pragma once

#include <optional>
#include <string>
#include <vector>

#include "purkinje/models/camera.h"
#include "purkinje/models/eye.h"
#include "purkinje/models/illuminator.h"
#include "purkinje/models/mesh.h"
#include "purkinje/models/screen.h"

namespace purkinje {

struct Scene {
  std::string name;
  std::vector<Camera> cameras;
  std::vector<Eye> eyes;
  std::vector<Illuminator> illuminators;
  std::vector<Mesh> meshes;  // optional geometry beside the eyes (glasses, occluders)
  std::optional<Screen> screen;  // what the eye looks at, for gaze; not rendered
};

}  // namespace purkinje
