#pragma once
// A spherical cornea's glint with its derivatives, for calibration fits:
// where a light's reflection in a sphere appears to a camera, and how that
// pixel moves with the sphere's centre and radius. The general
// specular-path solver handles any corneal surface but has no
// derivatives; for a sphere the law of reflection is a two-unknown Newton
// problem whose derivatives follow from the implicit function theorem.

#include <array>
#include <optional>

#include "purkinje/models/camera.h"
#include "purkinje/models/geometry.h"

namespace purkinje::trackers {

struct SphereGlint {
  Point3 point;                                // on the sphere, world mm
  UnitVector3 normal = UnitVector3::unit_z();  // outward, at point
  Pixel pixel;
  // Row-major 2 x 4: d(u, v) / d(centre x, y, z, radius), px per mm
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
std::optional<SphereGlint> sphere_glint(const Camera& camera, const Point3& center, double radius_mm,
                                        const Point3& light,
                                        const std::optional<UnitVector3>& warm_start = std::nullopt,
                                        bool with_derivatives = true);

}  // namespace purkinje::trackers
