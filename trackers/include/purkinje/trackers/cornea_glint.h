#pragma once
// A cornea's glint with its derivatives, for calibration fits: where a
// light's reflection in a sphere or a conicoid appears to a camera, and
// how that pixel moves with the cornea's centre and radius. The general
// specular-path solver handles any corneal surface but has no
// derivatives; here the law of reflection is a small Newton problem whose
// derivatives follow from the implicit function theorem.

#include <array>
#include <optional>

#include "purkinje/models/camera.h"
#include "purkinje/models/eye.h"
#include "purkinje/models/geometry.h"

namespace purkinje::trackers {

struct CorneaGlint {
  Point3 point;                                // on the cornea, world mm
  UnitVector3 normal = UnitVector3::unit_z();  // outward, at point
  Pixel pixel;
  // Row-major 2 x 4: d(u, v) / d(centre x, y, z, radius), px per mm; the
  // radius is the apex's for a conicoid
  // (zeros unless asked for).
  std::array<double, 8> d_pixel{};
};

// The glint of `light` in the sphere (`center`, `radius_mm`) seen by
// `camera`. `warm_start`, when given, is a normal near the answer (the
// last one, in a fit); otherwise the search starts from the bisector of
// the directions from the centre to the light and the camera. nullopt
// when the light or the camera is not outside the sphere, when the glint
// is behind the camera, or when the reflection cannot be found.
// Derivatives cost about a third of the time: a fit's residual-only
// evaluations go without.
std::optional<CorneaGlint> sphere_glint(const Camera& camera, const Point3& center, double radius_mm,
                                        const Point3& light,
                                        const std::optional<UnitVector3>& warm_start = std::nullopt,
                                        bool with_derivatives = true);

// The glint of `light` in a conicoid cornea (EyeModel's Conicoid: apex
// radius and asphericity Q > -1) whose centre of apex curvature is
// `center` and whose apex lies toward `optical_axis` from it. Real
// corneas flatten away from the apex (Q about -0.26), and a sphere fitted
// to their glints is off by millimetres in depth, by an amount that
// changes with gaze: the optical axis is part of the model. Q = 0 is
// sphere_glint. Newton's method on the glint point from the apex
// sphere's glint; `warm_start` as there. nullopt as there, and when the
// glint would lie behind the conicoid's equator.
std::optional<CorneaGlint> conicoid_glint(const Camera& camera, const Point3& center, const UnitVector3& optical_axis,
                                          const Conicoid& cornea, const Point3& light,
                                          const std::optional<UnitVector3>& warm_start = std::nullopt,
                                          bool with_derivatives = true);

}  // namespace purkinje::trackers
