// Fuzz target: the Wavefront OBJ reader (parse_obj). It documents one
// exception, ObjError; anything else escaping, a crash or a sanitizer
// report is a finding. On success, the mesh must be one the renderer can
// take as it is: a triangle at least, every index in range, every vertex
// finite, no triangle of zero area (obj_file.h, mesh.h).

#include <cmath>
#include <string_view>

#include "fuzz_target.h"
#include "purkinje/models/obj_file.h"

PURKINJE_FUZZ_TARGET(obj) {
  purkinje::ObjMesh mesh;
  try {
    mesh = purkinje::parse_obj(std::string_view(reinterpret_cast<const char*>(data), size));
  } catch (const purkinje::ObjError&) {
    return 0;
  }
  PURKINJE_FUZZ_CHECK(!mesh.triangles.empty());
  for (const purkinje::Point3& p : mesh.vertices) PURKINJE_FUZZ_CHECK(p.is_finite());
  for (const purkinje::Triangle& t : mesh.triangles) {
    for (const std::uint32_t index : t) PURKINJE_FUZZ_CHECK(index < mesh.vertices.size());
    const purkinje::Point3& a = mesh.vertices[t[0]];
    // Zero-area triangles are left out (mesh.h): the renderer takes each one's plane.
    PURKINJE_FUZZ_CHECK(cross(mesh.vertices[t[1]] - a, mesh.vertices[t[2]] - a).norm() > 0);
  }
  return 0;
}
