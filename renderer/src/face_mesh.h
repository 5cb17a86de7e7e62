#pragma once
// The periocular face of one eye (Face in appearance.h) as a triangle mesh
// (internal to renderer/): built per scene, since the lids lie on the eye
// in its current gaze and their margins follow it.
//
// Head frame as the lids' (scene_geometry.h): origin at the centre of
// rotation, z forward out of the face, y up, x = y cross z; n = x for a
// right eye, -x for a left one, so that +n points to the nose.
//
// The mesh is a grid whose columns are lines x = const and whose rows run
// along the palpebral fissure: the upper lid's rows above the upper margin
// y_u(x), the lower lid's below the lower margin y_l(x), each at a distance
// d from its margin. Between the two margins there is no triangle: that
// strip is the opening, through which the eye is seen. Past the canthi
// (|x| >= half width) the margins coincide and the two halves join.
//
// Margins: the Eyelids' parabolas, raised by the canthal tilt toward the
// lateral canthus; their middles (not the canthi, which tendons hold to
// the bone) turn with the eye's elevation: at x the turn's displacement is
// scaled by 1 - (x / half width)^2. Where the turned margins cross, both
// take their mean: the lids meet.
//
// Depth (z) of a vertex at (x, y), d from its margin:
//   U(x, y)   the support: the eye's outer surface (cornea, limbal band or
//             sclera, as they are now) along -z, or the socket's floor z = 0
//             where the ray misses the eye;
//   lid       U + t (t = margin thickness), the upper lid's crease a groove
//             at d = crease height (lower toward the canthi), fading out
//             past the globe so that the face takes over;
//   face      brow ridge, forehead, cheek, the receding side of the head
//             and the nose's side up to the midline (n = midline_mm), a
//             smooth function of (n, y) relative to the corneal apex;
//   skin      the smooth maximum of lid and face (blend width 2 mm: equal
//             to the larger wherever they differ by more);
//   margin    for d < w_m (0.4 mm) a quarter ellipse from the support
//             (0.03 mm inside it, so that no gap opens between lid and eye)
//             up to the skin: a rounded lid margin facing the opening.
// Normals for shading: per vertex, the area-weighted mean of its
// triangles' normals (the mesh is smooth; its facets would show in the
// skin's shading otherwise).

#include <functional>
#include <vector>

#include "purkinje/models/eye.h"
#include "purkinje/models/mesh.h"
#include "surfaces.h"

namespace purkinje::renderer {

// A margin's anterior edge, where its rounding meets the lid's skin (the
// lashes' roots): the mesh's vertices there, one per column inside the
// fissure, from the lateral canthus to the medial.
struct MarginEdge {
  std::vector<Point3> points;        // world
  std::vector<UnitVector3> normals;  // the skin's shading normals
  std::vector<Vector3> rise;         // to the next row, away from the opening
  std::vector<double> fissure;       // -1 at the lateral canthus, 0 middle, 1 medial
};

struct FaceMesh {
  std::vector<Point3> vertices;      // world
  std::vector<Triangle> triangles;   // front faces out of the face
  std::vector<UnitVector3> normals;  // per vertex, world
  MarginEdge upper_edge, lower_edge;
};

// 0 below `from`, 1 above `to`, the cubic 3s^2 - 2s^3 between (the face's
// and the brows' blends).
double smoothstep(double x, double from, double to);

// -1 at the lateral canthus, 0 at the middle, 1 at the medial canthus, at
// head-frame x.
double fissure_coordinate(const Eyelids& lids, const Face& face, double x);

// The margins' heights (head-frame y) at x, as the mesh's row 0 has them:
// where the margins' posterior edges meet the globe.
struct FissureMargins {
  double upper_mm = 0;
  double lower_mm = 0;
};
FissureMargins fissure_margins(const Eyelids& lids, const Face& face, double sclera_radius_mm,
                               const surfaces::MarginTurns& turns, double x);

// `support_depth(x, y)`: the head-frame z where a ray along -z from
// (x, y, far in front) first meets the eye's outer surfaces, or nothing.
using SupportDepth = std::function<std::optional<double>(double x, double y)>;

// The face of `eye` (its appearance has eyelids and a face), its lids'
// margins turned by `turns`; `world_from_head` places the head frame.
// `alone`: no other eye's face continues it past the midline, so it goes
// on there as its own mirror image (without an eye).
FaceMesh build_face_mesh(const Eye& eye, const Pose& world_from_head, const surfaces::MarginTurns& turns,
                         const SupportDepth& support_depth, bool alone);

}  // namespace purkinje::renderer
