#pragma once

#include <string>

#include "purkinje/models/geometry.h"

namespace purkinje {

// A near-infrared point light (an LED).
struct Illuminator {
  std::string name;
  Point3 position;                   // mm, world
  double radiant_intensity_w_sr = 0.01;  // W/sr toward the eye
  double wavelength_nm = 850.0;
  double emitter_diameter_mm = 0.0;  // 0 = ideal point
};

}  // namespace purkinje
