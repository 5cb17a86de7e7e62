#pragma once
// Radiometry of a highlight off any smooth mirror (internal to renderer/):
// the glint's, a wet sclera's and a tear meniscus's highlights share it.

#include <functional>

#include "purkinje/models/scene.h"
#include "purkinje/renderer/radiometry.h"

namespace purkinje::renderer {

using purkinje::Mirror;  // specular.h

// Power and the LED disc's image for a reflection (status ok) off
// `mirror`, of Fresnel reflectance `reflectance` there, from central
// differences of the mirror's own reflections: how the incident direction
// turns as the target slides over the aperture, and how the image moves
// as the source slides over the LED's disc. With `lenses` (a scene with
// spectacle lenses), the highlight as the camera sees it through them
// (see_highlight): the light's direction as it leaves the LED differenced,
// the image where the camera's leg leaves its lens, the power times the
// legs' Fresnel transmittance.
GlintRadiometry mirror_radiometry(const Mirror& mirror, double reflectance, const Illuminator& light,
                                  const Camera& camera, const Reflection& reflection,
                                  const Scene* lenses = nullptr);

// A spectacle lens's ghost of `light` (solve_lens_reflection toward the
// camera's centre, status ok): mirror_radiometry of the lens surface's own
// reflections, seen where they leave the front surface; the back surface's
// reflectance times the front's transmittance in and out.
GlintRadiometry ghost_radiometry(const SpectacleLens& lens, LensSurface surface, const Illuminator& light,
                                 const Camera& camera);

// A rough mirror's spread (px^2: u-u, u-v, v-v) of the highlight at
// `reflection`, for facets tilted by a Gaussian of `sigma_rad` per axis:
// to first order a tilt d (a tangent vector) moves the highlight by
// -M^-1 d, M = S + [P_s/d_s + P_c/d_c] / |s + c| on the tangent plane, so
// the spread there is sigma^2 M^-2, carried to pixels by the camera's
// projection. `shape` is the surface's shape operator S in the orthonormal
// tangent basis (t1, t2) as {S11, S12, S22}, with the normal out of the
// mirror (toward the light): 1/R for a convex sphere of radius R, negative
// where the surface is concave. False when the spread has no finite value
// (M singular: a caustic) or the point projects behind the camera.
bool roughness_spread(const double shape[3], const UnitVector3& t1, const UnitVector3& t2, double sigma_rad,
                      const Illuminator& light, const Camera& camera, const Reflection& reflection,
                      double cov_px2[3]);

// Any unit vector perpendicular to d.
UnitVector3 perpendicular(const UnitVector3& d);

// A radiometry that failed with `status`.
GlintRadiometry failed_radiometry(PathStatus status);

// Throws std::invalid_argument for a light or camera whose radiometry
// cannot be computed (negative intensity or emitter, a non-positive
// f-number or pixel pitch).
void check_radiometry_inputs(const Illuminator& light, const Camera& camera);

}  // namespace purkinje::renderer
