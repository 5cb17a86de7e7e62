#pragma once
// A lid's tear meniscus (TearFilm::meniscus_radius_mm for the lower lid,
// upper_meniscus_radius_mm for the upper), internal to renderer/:
// modelled for its highlights, the LEDs' images in its concave strip of
// tears, which glint detectors may take for glints.
//
// Geometry, in the head frame of face_mesh.h (origin at the centre of
// rotation, y up, z out of the face). The lid margin's posterior face is
// the wall {(x, m(x), z)}, vertical as the face mesh's margin is where it
// leaves the globe (m: the margin's height, fissure_margins). The
// globe is the eye's outer shell as traced: the corneal cap, the limbal
// band, the sclera's sphere. The meniscus is the fillet of radius r
// between the two: the envelope of the spheres of radius r that touch
// both, whose centres run along
//   c(x) = ((x, m(x)) + r n(x), Z(x)),
// n the wall's unit normal into the opening (in the xy plane: up from the
// lower lid, down from the upper), Z where the
// sphere touches the shell from outside: found at nodes 0.1 mm apart along
// x (sphere tracing down the head's z) and joined by a cubic spline over
// the centres' x, so that the meniscus is smooth where the shell is not
// (the cap's rim, the limbal band; there it strays from the exact fillet
// by up to a few hundredths of a millimetre) and within 1e-7 mm of it
// where the shell is smooth (tests). The surface is the pipe about c: p = c - r N, N perpendicular to
// c' on the short arc from n (where it touches the wall) to the direction
// from the shell's nearest point to c (where it touches the shell).
//
// A highlight is where N bisects the directions to the light and to the
// camera: on each circle (fixed x) the normal's angle follows from the
// bisector by a quickly contracting iteration (the point moves by r, the
// bisector by r / distance), and along x the bisector's component along c'
// must vanish, found by scanning for sign changes and refining them. Where
// the centre line bends tighter than r (over the limbus's edge) the
// circles' surface folds through itself: a highlight inside another
// circle's sphere lies on a fold in the air, not on the tears, and is
// dropped.
//
// Left out: the light the tears refract (what lies under them is drawn as
// if dry), the meniscus's thinning toward the canthi (it ends at 90% of
// the way to each canthus, or where the margins close in).

#include <functional>
#include <optional>
#include <vector>

#include "purkinje/models/geometry.h"
#include "purkinje/models/rotation.h"
#include "purkinje/models/scene.h"
#include "purkinje/models/specular.h"
#include "purkinje/models/truth.h"
#include "purkinje/renderer/radiometry.h"

namespace purkinje::renderer {

// The vector from the eye's outer shell's nearest point to a head-frame
// point outside it (head frame).
using ShellOffset = std::function<Vector3(const Point3& head_point)>;

// Which lid's margin a meniscus lies along.
enum class Lid { lower, upper };
// Its highlights' kind in the labels.
inline DistractorKind meniscus_kind(Lid lid) {
  return lid == Lid::lower ? DistractorKind::tear_meniscus : DistractorKind::upper_tear_meniscus;
}

class TearMeniscus {
 public:
  // The meniscus along [x_lo, x_hi] (head-frame x), or the run of it about
  // the middle where the fillet exists (its sphere touches the shell in
  // front of the wall's foot); nullopt when it exists nowhere.
  // `margin_mm(x)`: `lid`'s margin's height, smooth over the range and
  // 0.02 mm past it; `eye` indexes scene.eyes.
  static std::optional<TearMeniscus> build(int eye, Lid lid, const Pose& world_from_head, double radius_mm,
                                           std::function<double(double)> margin_mm, const ShellOffset& shell,
                                           double x_lo, double x_hi);

  int eye() const { return eye_; }
  Lid lid() const { return lid_; }
  double radius_mm() const { return r_; }

  // Every highlight of a point light at `source` seen from `target`
  // (world): reflections with status ok (on_cap false), in order of their
  // points' head-frame x.
  std::vector<Reflection> highlights(const Point3& source, const Point3& target) const;
  // Where along the lid a world point near the meniscus lies: the wall's
  // x of the circle through it (the centre line's nearest point, within
  // 1 + 2r of the point's own x).
  double circle_of(const Point3& world_point) const;
  // The highlight nearest the circle at `wall_x` (circle_of a highlight's
  // point; found again within 0.5 mm along the lid) for a source or target
  // moved a little: status no_solution when none is there.
  Reflection highlight_near(double wall_x, const Point3& source, const Point3& target) const;

 private:
  TearMeniscus() = default;
  struct Frame;  // the circle at x: centre, tangent, normal basis, arc
  Frame frame(double x) const;
  // The normal's angle on the circle at x where it bisects the directions
  // to `source` and `target` (head frame), and the bisector's part along
  // the tangent there.
  double theta_at(const Frame& f, const Point3& source, const Point3& target, double& along) const;
  Reflection highlight_at(double x, const Point3& source, const Point3& target) const;
  Reflection refine(double a, double b, double fa, const Point3& source, const Point3& target) const;
  // circle_of for a head-frame point; `gap_mm`, if given, gets its
  // distance from the centre line.
  double wall_x_of(const Point3& p, double* gap_mm = nullptr) const;
  // Whether a head-frame point on some circle is on the tears' surface:
  // no other circle's sphere holds it.
  bool on_surface(const Point3& head_point) const;

  int eye_ = 0;
  Lid lid_ = Lid::lower;
  Pose world_from_head_, head_from_world_;
  double r_ = 0;
  std::function<double(double)> margin_;
  // Where along the wall (head-frame x) it runs, and its nodes: the
  // centres' x and Z, the spline's second derivatives of Z over x, and the
  // unit vectors from the shell to the centres.
  double wall_lo_ = 0, wall_hi_ = 0;
  std::vector<double> x_, z_, z2_;
  std::vector<Vector3> to_centre_;
};

// The eye's outer shell (as scene_geometry traces it) seen from the head
// frame of `world_from_head`.
ShellOffset eye_shell_offset(const Eye& eye, const Pose& world_from_head);

// Power and the LED disc's image of a highlight on `meniscus` (as
// glint_radiometry's, from the meniscus's own reflections), off the tears
// (kTearFilmIndex). No roughness spread: a free surface of liquid is
// optically smooth. Through `lenses` as glint_radiometry.
GlintRadiometry meniscus_highlight_radiometry(const TearMeniscus& meniscus, const Illuminator& light,
                                              const Camera& camera, const Reflection& highlight,
                                              const Scene* lenses = nullptr);

// The tear menisci of `scene`'s eyes that have a face and a tear film
// with menisci: by eye, the lower lid's before the upper's.
std::vector<TearMeniscus> build_tear_menisci(const Scene& scene);

}  // namespace purkinje::renderer
