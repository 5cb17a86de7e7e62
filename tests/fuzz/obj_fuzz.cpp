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
  check_mesh_promises(mesh);
  return 0;
}
