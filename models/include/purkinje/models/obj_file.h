#pragma once
// Wavefront OBJ files: the polygons, as triangles. A strict reader of the
// subset that mesh exporters (Blender, MakeHuman, MeshLab) write: vertices
// (`v`) and faces (`f`, any of the index forms `i`, `i/j`, `i//k`, `i/j/k`,
// negative indices counting back); texture coordinates and normals are
// skipped (shading uses each triangle's own plane); groups,
// objects, smoothing groups and materials are skipped; lines and points
// have no area and are skipped. Anything else (free-form curves and
// surfaces, unknown statements) is an error, as is any malformed number or
// index, so a corrupt file never loads as a wrong shape. Why not a library:
// docs/scene-format.md, "Meshes".

#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "purkinje/models/mesh.h"

namespace purkinje {

// What was wrong, as "line 12: face index 40 out of range (file has 8
// vertices)"; the caller adds which file.
class ObjError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Vertices and triangles in the file's own units and frame.
struct ObjMesh {
  std::vector<Point3> vertices;     // every `v`, in file order
  std::vector<Triangle> triangles;  // polygons split into fans; zero-area triangles left out
};

// Polygons are split into a fan from their first vertex, which is exact
// for convex polygons; a polygon the fan would fold over (concave) is an
// error. Throws ObjError when the text has no face, or only faces of zero
// area.
ObjMesh parse_obj(std::string_view text);
// Throws ObjError when the file cannot be read, or as parse_obj.
ObjMesh load_obj(const std::filesystem::path& file);

}  // namespace purkinje
