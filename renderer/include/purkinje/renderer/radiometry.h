#pragma once
// Radiometry of light paths through and off the cornea, from the
// specular-path solver: Fresnel factors, glint power, and the irradiance
// that reaches the iris plane through the cornea (the caustic), cached on
// a grid so that shading an iris pixel costs a lookup.

#include <functional>
#include <vector>

#include "purkinje/models/camera.h"
#include "purkinje/models/eye.h"
#include "purkinje/models/illuminator.h"
#include "purkinje/models/scene.h"
#include "purkinje/models/specular.h"

namespace purkinje::renderer {

// Unpolarized Fresnel reflectance for light in a medium of index n1
// meeting one of index n2 at incidence angle acos(cos_incidence); 1 beyond
// the critical angle.
double fresnel_reflectance(double cos_incidence, double n1, double n2);

// Index just inside the anterior cornea: cornea_index for two-surface
// eyes, aqueous_index otherwise.
double anterior_inner_index(const EyeModel& model);

// The glint of `light` in `eye` as `camera` sees it.
struct GlintRadiometry {
  PathStatus status = PathStatus::no_solution;  // the reflection's status
  double fresnel = 0;        // reflectance at the glint point
  double power_w = 0;        // optical power entering the camera's aperture
  // Covariance (u-u, u-v, v-v) in px^2 of the LED's own image: its emitting
  // disc, seen in the convex mirror and imaged by the camera (0 for a point LED).
  double source_cov_px2[3] = {0, 0, 0};
  // The same of a rough mirror's spread (a scleral highlight's facets
  // tilted about the sphere's normal; 0 for the cornea).
  double roughness_cov_px2[3] = {0, 0, 0};
};
// From the solver's reflection toward the camera centre. The spreading of
// the reflected beam is measured from the solver itself: reflections
// toward points around the aperture give the solid angle, seen from the
// LED, of the rays that enter it, so it holds for any cornea shape. With
// `lenses` (a scene with spectacle lenses), as the camera sees the glint
// through them (its label's reflection, compute_truth's): the light's
// spreading through the lenses measured the same way, times their
// surfaces' Fresnel transmittance.
GlintRadiometry glint_radiometry(const Eye& eye, const Illuminator& light, const Camera& camera,
                                 const Reflection& reflection, const Scene* lenses = nullptr);
// A scleral highlight (DistractorTruth, kind sclera) the same way, off the
// tear film (kTearFilmIndex) on the sclera's sphere, with its roughness's
// spread: to first order in the facets' tilt d (a tangent vector), the
// highlight moves on the sphere by -M^-1 d, with M = I/R + [P_s/d_s +
// P_c/d_c] / |s + c| on the tangent plane (s, c: unit vectors to the
// light and the camera at distances d_s, d_c; P = I minus the projection
// on them), so that an isotropic tilt of sigma per axis spreads it by
// sigma^2 M^-2 there; the camera's projection carries that to pixels. The
// power is the mirror's (a narrow lobe only moves where the light leaves).
// Through `lenses` as glint_radiometry (the roughness's spread projected
// as without them: a lens's few percent of magnification ignored).
GlintRadiometry scleral_highlight_radiometry(const Eye& eye, const TearFilm& film, const Illuminator& light,
                                             const Camera& camera, const Reflection& reflection,
                                             const Scene* lenses = nullptr);

// Irradiance (W/m^2) on the iris plane of one eye from one point light,
// through the cornea: I * T * dOmega/dA, with T the Fresnel transmittance
// of every corneal interface crossed and dOmega/dA the solid angle at the
// light per unit iris-plane area. Computed exactly by the solver at the
// nodes of a square grid over the iris plane (covering the iris and the
// pupil) and interpolated between them (see GridNode).
class IrisIrradianceCache {
 public:
  // `visible(a, b)`: whether the segment from the light to a point on the
  // anterior cornea is unobstructed (eyelids, skin); may be empty (always
  // visible). It is kept and called by lookups too, from any thread: what
  // it refers to must outlive the cache. `resolution`: nodes per side (>= 2).
  using Visibility = std::function<bool(const Point3& light, const Point3& cornea_point)>;
  IrisIrradianceCache(const Eye& eye, const Point3& light_position, double radiant_intensity_w_sr,
                      int resolution, const Visibility& visible = {});

  // At a world point on (or within rounding of) the iris plane; 0 outside the grid.
  double irradiance_w_m2(const Point3& iris_plane_point) const;
  // The same without the last step, the dark beyond the rim of the disc
  // inside the cornea (inside_radius_mm): there the paths' continuation, so
  // that a table built from these values interpolates no rim and can cut
  // at it exactly itself.
  double continued_irradiance_w_m2(const Point3& iris_plane_point) const;
  // Radius of the iris plane's disc inside every corneal surface (eye
  // frame, about the optical axis); <= 0: none.
  double inside_radius_mm() const { return inside_radius_mm_; }
  // Half the side of the grid's square, in mm (eye frame, centred on the optical axis).
  double half_size_mm() const { return half_size_mm_; }
  int resolution() const { return resolution_; }

 private:
  Pose eye_from_world_;
  Pose world_from_eye_;
  Point3 light_world_;
  Visibility visible_;
  double iris_plane_z_mm_ = 0;  // eye frame
  double half_size_mm_ = 0;
  int resolution_ = 0;
  // Interpolated per node: the spread S and the chart point (u, v), the
  // eye-frame x and y where the path crosses the anterior cornea. At a
  // lookup, the cosine of incidence c there and whether it lies inside the
  // limbus follow exactly from (u, v), and E = S c (1 - Fresnel reflectance
  // at c). S and (u, v) are smooth everywhere, also where c falls to 0 at
  // the light's horizon on the cornea and E has no simple form. Nodes just
  // beyond the paths hold their continuation or an extrapolation, so that
  // the lit region's edges fall exactly inside cells. Nodes farther out
  // hold nothing (known = false), and a lookup that needs one is dark.
  // S ignores shadows: each node says whether the light reaches it (lit),
  // and where a lookup's nodes disagree (an eyelid's shadow edge crosses
  // them) the light is asked for exactly at the interpolated crossing, so
  // that shadow edges are sharp where they should be instead of smeared
  // over the interpolation's nodes.
  struct GridNode {
    double spread_w_m2 = 0;
    double chart_u_mm = 0;
    double chart_v_mm = 0;
    bool known = false;
    bool lit = true;
  };
  // Eye frame: the light, the anterior cornea and the disc of the iris
  // plane inside the cornea.
  Point3 light_mm_;
  double apex_z_mm_ = 0;
  double anterior_radius_mm_ = 0;
  double anterior_one_plus_q_ = 1;
  double limbus_depth_mm_ = 0;
  double inside_radius_mm_ = -1;
  double anterior_inner_index_ = 1;
  std::vector<GridNode> nodes_;  // row-major, y rows of x columns
};

// The same irradiance at one iris-plane point, solved there (no cache):
// along the one path that refracts through the cornea without reflecting
// inside it, 0 where none reaches the point (beyond the limbus's shadow,
// the light's horizon or the chamber angle) or `visible` says the light is
// hidden from the path's anterior crossing. A few microseconds.
double refracted_irradiance_w_m2(const Eye& eye, const Point3& light, double radiant_intensity_w_sr,
                                 const Point3& iris_plane_point,
                                 const IrisIrradianceCache::Visibility& visible = {});

// Procedural iris albedo at a point of the iris plane given in the eye
// frame (mm), for the eye's appearance: radial fibres, crypts, a darker
// collarette and limbal ring, from a seeded hash (no global state). The
// mean over the iris is about appearance.iris_albedo; values stay in [0, 1].
double iris_albedo(const EyeModel& model, const EyeAppearance& appearance, double x_mm, double y_mm);

}  // namespace purkinje::renderer
