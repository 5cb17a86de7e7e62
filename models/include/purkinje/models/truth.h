#pragma once
// Ground truth for a scene, per camera and eye: glints, the refracted pupil
// and the eye's axes, as the camera sees them.

#include <functional>
#include <optional>
#include <vector>

#include "purkinje/models/camera.h"
#include "purkinje/models/scene.h"
#include "purkinje/models/specular.h"

namespace purkinje {

struct Ellipse {
  Pixel center;
  double semi_axis_1_px = 0;  // along angle_rad
  double semi_axis_2_px = 0;
  double angle_rad = 0;       // of semi-axis 1 from +u toward +v, in (-pi/2, pi/2]
};

// What hides a point (status occluded): the lids and the skin around
// them, an eyelash, one of the scene's meshes (glasses, occluders), or an
// eye's own surfaces met off the point's path (a sclera, an iris).
enum class Occluder { none, skin, lash, brow, mesh, eye };
const char* to_string(Occluder o);

struct GlintTruth {
  int illuminator = 0;
  PathStatus status = PathStatus::no_solution;
  // For status occluded: what the camera sees in front of the glint, or
  // else what shadows it from its light.
  Occluder occluder = Occluder::none;
  Pixel pixel;               // valid when status is ok or outside_image
  Reflection reflection;     // 3D point, normal, directions, incidence, on_cap
};

// A highlight that is no Purkinje image: a light mirrored by something
// other than the cornea, which a glint detector may take for a glint.
// Labels list them so that such false positives can be scored.
enum class DistractorKind {
  sclera,         // the tear film over the sclera (EyeAppearance::tear_film)
  tear_meniscus,  // the lower lid's tear meniscus (TearFilm::meniscus_radius_mm);
                  // found by the renderer, which builds the lid margins
  spectacle_lens_front,  // a glasses lens's front surface (Scene::spectacle_lenses)
  spectacle_lens_back,   // its back surface, seen through the front one
  upper_tear_meniscus,   // the upper lid's (TearFilm::upper_meniscus_radius_mm)
};
const char* to_string(DistractorKind kind);

struct DistractorTruth {
  DistractorKind kind = DistractorKind::sclera;
  int illuminator = 0;
  // ok, occluded, outside_image or behind_camera: only highlights whose
  // mirror point exists are listed. A render may set not_converged (its
  // radiometry failed: not drawn) or list a moving eye's highlight that
  // exists during part of the exposure only (docs/labels.md).
  PathStatus status = PathStatus::no_solution;
  // For status occluded: Occluder::eye when the cornea (or the eye's
  // shell) stands in the way, else as GlintTruth's; what the camera sees
  // in front of it first, then what shadows it.
  Occluder occluder = Occluder::none;
  Pixel pixel;            // where the camera sees the mirror point (not behind the camera)
  Reflection reflection;  // on the mirror: point, its normal, directions
  // For a spectacle lens's ghost: the lens's index in the scene.
  int spectacle_lens = -1;
};

struct PupilBorderPointTruth {
  double angle_rad = 0;      // around the pupil, from eye +x toward eye +y
  Point3 border_point;       // the 3D point on the pupil's edge
  PathStatus status = PathStatus::no_solution;
  Occluder occluder = Occluder::none;  // for status occluded: what the camera sees in front of it
  Pixel pixel;
  Refraction refraction;
};

struct PupilTruth {
  std::vector<PupilBorderPointTruth> border;
  bool ellipse_valid = false;  // needs at least 6 border points whose path exists
  // Fitted (Halir-Flusser) to the border pixels whose refracted path exists
  // and lies in the image, whether or not a lid hides them: the whole
  // pupil's outline.
  Ellipse ellipse;
  // Fitted to the border pixels the camera sees (status ok, after the
  // scene's occlusion): what a detector can fit. Without an occlusion in
  // TruthOptions it is the whole pupil's.
  bool visible_ellipse_valid = false;
  Ellipse visible_ellipse;
  // The pupil centre seen through the cornea (its own refracted path).
  PathStatus refracted_center_status = PathStatus::no_solution;
  Occluder refracted_center_occluder = Occluder::none;  // for status occluded
  Pixel refracted_center;
  Refraction refracted_center_path;
  // The pupil centre projected straight, without the cornea.
  Projection unrefracted_center;
};

struct EyeInCameraTruth {
  int camera = 0;
  int eye = 0;
  std::vector<GlintTruth> glints;  // one per illuminator, in scene order
  // For an eye with a tear film: its scleral highlights, in illuminator
  // order; then the ghosts of the spectacle lenses in front of this eye
  // (those whose back vertex lies nearer its corneal apex than any other
  // eye's), by lens, surface (front, back) and illuminator.
  std::vector<DistractorTruth> distractors;
  PupilTruth pupil;
  Projection cornea_center;
  Projection rotation_center;
};

struct EyeTruth {
  Point3 cornea_center;
  Point3 rotation_center;
  Point3 pupil_center;
  UnitVector3 optical_axis = UnitVector3::unit_z();
  UnitVector3 visual_axis = UnitVector3::unit_z();
  double cornea_radius_mm = 0;
  double pupil_radius_mm = 0;
};

struct SceneTruth {
  std::vector<EyeTruth> eyes;
  std::vector<EyeInCameraTruth> views;  // camera-major: (camera 0, eye 0), (camera 0, eye 1), ...
};

// What of the scene as rendered (lids, skin, lashes, brows, meshes; not the
// cornea, whose paths the solver has already followed) blocks the straight
// path between two points: the blocker nearest `to`, or Occluder::none.
// The renderer's ray tracer supplies it.
using Occlusion = std::function<Occluder(const Point3& from, const Point3& to)>;

struct TruthOptions {
  int pupil_border_points = 36;
  // When given, a glint whose light or view is blocked, and a pupil point
  // or refracted centre the camera cannot see, has status occluded.
  Occlusion occluded;
};

SceneTruth compute_truth(const Scene& scene, const TruthOptions& options = {});

// The label of a highlight (status ok) that `eye`'s `kind` of mirror
// forms of `light` toward `camera`: its pixel and status (ok,
// outside_image, behind_camera, or occluded: the cornea standing out of
// the globe, then `options.occluded`, on the way to the camera first and
// then to the light).
DistractorTruth distractor_truth(DistractorKind kind, const Reflection& highlight, const Scene& scene,
                                 const Eye& eye, int light, const Camera& camera, const TruthOptions& options);
// The same for a highlight seen through the scene's spectacle lenses
// (see_highlight, declared below): its pixel where the camera's leg leaves
// its lens, occlusion along each leg.
struct SeenHighlight;
DistractorTruth distractor_truth(DistractorKind kind, const SeenHighlight& highlight, const Scene& scene,
                                 const Eye& eye, int light, const Camera& camera, const TruthOptions& options);

// A path's leg from a point of an eye to a camera or a light outside it:
// straight, or through the spectacle lens its straight segment crosses
// (the first listed, when several do).
struct Leg {
  PathStatus status = PathStatus::ok;  // ok, or why the path has no such leg
  int lens = -1;                       // into Scene::spectacle_lenses, when one is crossed
  std::optional<LensPassage> passage;  // through it (status ok), from the eye's side
};

// A mirror's highlight as a camera sees it through the scene's spectacle
// lenses (compute_truth's glints and scleral highlights): the mirror's own
// path, run at virtual ends along its legs' true first segments until it
// stops moving (within 1e-11 mm), and the legs.
struct SeenHighlight {
  Reflection reflection;  // on the mirror; its status the path's (a leg's when that fails)
  Leg to_camera, to_light;
  // Where the camera sees the highlight: where its leg leaves the lens.
  Point3 seen_at() const { return to_camera.passage ? to_camera.passage->second : reflection.point; }
  // The direction in which its light leaves the illuminator.
  UnitVector3 from_light() const { return to_light.passage ? -to_light.passage->arriving : reflection.incident; }
};
SeenHighlight see_highlight(const Scene& scene, const Point3& light, const Point3& camera_center, const Mirror& mirror);

// The eye a spectacle lens sits in front of: the one whose corneal apex
// lies nearest its back vertex (-1 without eyes).
int eye_behind(const Scene& scene, int lens);

// Image of a point inside the eye seen through the cornea by `camera`, and
// through any of the scene's spectacle lenses that the path crosses.
struct RefractedImage {
  PathStatus status = PathStatus::no_solution;
  Pixel pixel;
  Refraction path;
};
RefractedImage image_through_cornea(const Eye& eye, const Camera& camera, const Point3& inner);
RefractedImage image_through_cornea(const Scene& scene, const Eye& eye, const Camera& camera, const Point3& inner);

// Direct least-squares ellipse fit (Halir and Flusser 1998). Needs at least
// 6 points not on a conic degenerate; nullopt otherwise.
std::optional<Ellipse> fit_ellipse(const std::vector<Pixel>& points);

}  // namespace purkinje
