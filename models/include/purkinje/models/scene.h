#pragma once

#include <string>
#include <vector>

#include "purkinje/models/camera.h"
#include "purkinje/models/eye.h"
#include "purkinje/models/illuminator.h"

namespace purkinje {

struct Scene {
  std::string name;
  std::vector<Camera> cameras;
  std::vector<Eye> eyes;
  std::vector<Illuminator> illuminators;
};

}  // namespace purkinje
