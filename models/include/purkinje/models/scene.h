#pragma once

#include <optional>
#include <string>
#include <vector>

#include "purkinje/models/camera.h"
#include "purkinje/models/eye.h"
#include "purkinje/models/illuminator.h"
#include "purkinje/models/mesh.h"
#include "purkinje/models/screen.h"
#include "purkinje/models/spectacle_lens.h"

namespace purkinje {

struct Scene {
  std::string name;
  std::vector<Camera> cameras;
  std::vector<Eye> eyes;
  std::vector<Illuminator> illuminators;
  std::vector<Mesh> meshes;  // optional geometry beside the eyes (glasses' frames, occluders)
  // Glasses' lenses: every path between an eye and a camera or light that
  // crosses one is refracted by it, and each mirrors the lights (ghosts).
  std::vector<SpectacleLens> spectacle_lenses;
  std::optional<Screen> screen;  // what the eye looks at, for gaze; not rendered
};

}  // namespace purkinje
