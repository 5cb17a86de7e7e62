#pragma once
// Triangle meshes: arbitrary geometry (a glasses frame, a hand, an
// occluder) where no analytic surface of the eye fits. Plain data: the
// scene reader loads a mesh from a Wavefront OBJ file (obj_file.h) and
// places it in the world; the renderer shades it as a Lambertian surface.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "purkinje/models/geometry.h"

namespace purkinje {

// Three indices into a vertex list, counter-clockwise seen from the
// triangle's front (OBJ's convention): the front normal is
// (v1 - v0) x (v2 - v0).
using Triangle = std::array<std::uint32_t, 3>;

// A mesh placed in the scene.
struct Mesh {
  std::string name;
  std::vector<Point3> vertices;     // world, mm
  std::vector<Triangle> triangles;  // none of zero area
  double albedo = 0.5;              // Lambertian reflectance at the illuminators' wavelength, 0..1
};

}  // namespace purkinje
