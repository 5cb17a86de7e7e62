#pragma once
// The specular-path solver: the point on a corneal surface where a light
// path obeys the law of reflection (glints) or Snell's law (the pupil and
// iris seen through the cornea, light reaching the iris). All inputs and
// outputs are in world coordinates, millimetres and radians.
//
// A path that does not exist is a status, never a NaN.

#include <functional>
#include <optional>

#include "purkinje/models/eye.h"
#include "purkinje/models/geometry.h"
#include "purkinje/models/spectacle_lens.h"

namespace purkinje {

enum class PathStatus {
  ok,
  no_solution,                // no stationary path on the visible part of the surface
  total_internal_reflection,  // the path would have to leave the cornea beyond the critical angle
  off_cornea,                 // the path exists but crosses the surface beyond the limbus
  behind_camera,
  outside_image,
  occluded,
  not_converged,              // iteration stopped without meeting the tolerance
  invalid_input,              // e.g. an outer point inside the eye, a pupil point outside the cornea
};
const char* to_string(PathStatus s);

// Light from `source` reflected by the anterior cornea toward `target`.
struct Reflection {
  PathStatus status = PathStatus::no_solution;
  Point3 point;  // on the anterior cornea
  UnitVector3 normal = UnitVector3::unit_z();     // outward surface normal at point
  UnitVector3 incident = UnitVector3::unit_z();   // from source to point
  UnitVector3 reflected = UnitVector3::unit_z();  // from point to target
  double incidence_rad = 0;                        // between -incident and normal
  bool on_cap = false;
  int iterations = 0;
};

// Light from `inner` (inside the eye, e.g. a pupil-border point) refracted
// by the cornea toward `outer` (a camera centre or a light).
struct Refraction {
  PathStatus status = PathStatus::no_solution;
  Point3 anterior_point;                  // where the path crosses the anterior cornea
  std::optional<Point3> posterior_point;  // and the posterior one, for two-surface eyes
  UnitVector3 anterior_normal = UnitVector3::unit_z();  // outward
  UnitVector3 inner_direction = UnitVector3::unit_z();  // inside the eye, toward anterior_point
  UnitVector3 outer_direction = UnitVector3::unit_z();  // from anterior_point to outer
  double inner_angle_rad = 0;  // angle to the normal inside the anterior surface
  double outer_angle_rad = 0;  // angle to the normal in air
  bool on_cap = false;
  int iterations = 0;
};

// A mirror as its solver finds its reflections: from a source toward a
// target (status ok, or off_cornea where the surface goes on smoothly).
using Mirror = std::function<Reflection(const Point3& source, const Point3& target)>;

// Law of reflection, anterior cornea only (the first Purkinje image).
// `source` and `target` must lie outside the cornea.
Reflection solve_reflection(const Eye& eye, const Point3& source, const Point3& target);

// Law of reflection on a mirror sphere; `source` and `target` outside it.
// Status ok, no_solution (no point both ends see) or invalid_input (an
// end not outside the sphere, or not finite); on_cap is false.
Reflection solve_sphere_reflection(const Point3& center, double radius_mm, const Point3& source,
                                   const Point3& target);

// Law of reflection on the eye's sclera: its sphere about the centre of
// rotation, behind the seam with the cornea (EyeModel::sclera_seam_depth_mm).
// no_solution where the sphere's mirror point lies in front of the seam
// (under the cornea), or as solve_sphere_reflection.
Reflection solve_scleral_reflection(const Eye& eye, const Point3& source, const Point3& target);

// Snell's law at the anterior cornea, and also at the posterior cornea when
// the eye model has one. `inner` must lie inside the aqueous humour.
Refraction solve_refraction(const Eye& eye, const Point3& inner, const Point3& outer);

// Light from `from` to `to` through both surfaces of a spectacle lens, one
// end in front of it (outside the front surface's sphere), the other behind
// it (inside the back surface's sphere), either way round.
struct LensPassage {
  // ok; no_solution (the path would cross a surface outside the outline,
  // or there is none); not_converged; invalid_input (the ends not on
  // opposite sides, or not finite).
  PathStatus status = PathStatus::no_solution;
  Point3 first, second;  // where the path crosses the lens's surfaces, `from`'s side first
  // Their normals, out of the glass.
  UnitVector3 first_normal = UnitVector3::unit_z(), second_normal = UnitVector3::unit_z();
  UnitVector3 leaving = UnitVector3::unit_z();   // the direction in which the path leaves `from`
  UnitVector3 inside = UnitVector3::unit_z();    // in the glass, from first to second
  UnitVector3 arriving = UnitVector3::unit_z();  // and arrives at `to`
  int iterations = 0;
};
LensPassage solve_lens_passage(const SpectacleLens& lens, const Point3& from, const Point3& to);

// A point light as seen through a spectacle lens from a point behind it
// (`near`): the path of its light there (`passage`, from `near` to the
// light), the rays' vergence there, and the solid angle at the light per
// unit area there across the rays, so that the irradiance there is
// I T solid_angle_per_area for a light of intensity I and the surfaces'
// Fresnel transmittance T (the caller's, from `passage`). From central
// differences of passages 1e-4 of the distance to the light beside `near`
// (their truncation is about (step / lens radius)^2: 1e-6 on the axis).
struct LightThroughLens {
  PathStatus status = PathStatus::no_solution;  // the passages': ok, or why not
  LensPassage passage;
  // 1/mm: > 0 for light diverging from the lens's (virtual) image of the
  // light 1/vergence in front of `near`, < 0 for light converging to a
  // real image behind it (a plus lens stronger than the light's own
  // vergence); an oblique lens's two principal vergences averaged.
  double vergence_per_mm = 0;
  double solid_angle_per_area = 0;  // sr/mm^2
};
LightThroughLens light_through_lens(const SpectacleLens& lens, const Point3& light, const Point3& near);

// Light from `source` mirrored by one surface of a spectacle lens toward
// `target`, both in front of the lens: a ghost image of the light. The
// back surface mirrors from inside the glass, the light crossing the front
// surface on its way in and out.
struct LensReflection {
  // ok; no_solution (no mirror point inside the outline, or the path
  // would cross the front surface outside it); not_converged;
  // invalid_input (an end not in front of the lens, or not finite).
  PathStatus status = PathStatus::no_solution;
  LensSurface surface = LensSurface::front;
  // At the mirroring surface (outward normal, toward +z of the lens);
  // for the back surface its directions are those inside the glass.
  Reflection mirror;
  // Where the light crosses the front surface on its way in and out (the
  // mirror point itself for the front surface).
  Point3 entry, exit;
  UnitVector3 from_source = UnitVector3::unit_z();  // in air, toward entry
  UnitVector3 to_target = UnitVector3::unit_z();    // in air, from exit
};
LensReflection solve_lens_reflection(const SpectacleLens& lens, LensSurface surface, const Point3& source,
                                     const Point3& target);

// Residuals for tests and diagnostics (radians).
// Angle between the reflected direction and the mirror image of the incident one.
double reflection_residual_rad(const Reflection& r);
// Angle between the outer direction and Snell's refraction of the inner one
// (at the anterior surface), for the eye's indices.
double refraction_residual_rad(const Eye& eye, const Refraction& r);

}  // namespace purkinje
