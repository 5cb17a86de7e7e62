#pragma once
// The materials both integrators shade with (internal to renderer/): what
// each surface does to light (scattering_of), the Lambertian albedos (the
// textured iris's included), the corneal interfaces' Fresnel split, the
// fundus's retro-reflection (bright pupil), the lights as the integrators
// see them, and what a sample contributes and saw first. How a diffuse
// surface's light is estimated (caches or paths) is the integrator's.

#include <numbers>
#include <optional>
#include <vector>

#include "purkinje/models/scene.h"
#include "purkinje/renderer/ray_tracer.h"
#include "purkinje/renderer/render.h"

namespace purkinje::renderer {

// Scene lengths are mm; irradiance is per m^2.
constexpr double kPerSquareMm = 1e6;
// A Lambertian surface's radiance per irradiance and albedo.
constexpr double kInvPi = 1.0 / std::numbers::pi;

struct Light {
  Point3 position;
  double intensity_w_sr = 0;
  double electrons_per_radiance = 0;  // for this light's wavelength
  double emitter_radius_mm = 0;       // 0: a point
};
std::vector<Light> lights_of(const Scene& scene, const Camera& camera);

// What a path contributes: physical radiance, and the electrons it yields
// (radiance weighted by each light's wavelength response).
struct Contribution {
  double radiance = 0;
  double electrons = 0;
  void add(double radiance_from_light, const Light& light) { add(radiance_from_light, light.electrons_per_radiance); }
  void add(double radiance_from_lights, double electrons_per_radiance) {
    radiance += radiance_from_lights;
    electrons += radiance_from_lights * electrons_per_radiance;
  }
};

// What the pixel's primary path saw first (through any spectacle lens),
// for AOVs.
struct PrimaryRecord {
  PixelClass pixel_class = PixelClass::background;
  bool hit = false;
  double depth_mm = 0;
  Vector3 normal;
  bool through_cornea = false;
  int lens_crossings = 0;  // spectacle lens surfaces crossed before it
};
PixelClass class_of(Surface s);
// Whether any eye of the scene has lashes (its images then have a lash
// class and coverage plane), or brows (a brow class and plane).
bool scene_has_lashes(const Scene& scene);
bool scene_has_brows(const Scene& scene);
// Lashes and brows: thin hairs, seen through by the fast mode's caches.
constexpr bool is_hair(Surface s) { return s == Surface::lash || s == Surface::brow; }
// Whether the scene mirrors lights other than in corneas: an eye with a
// tear film (a wet sclera's highlights) or a spectacle lens (its ghosts);
// its images then have a distractor mask.
bool scene_has_distractors(const Scene& scene);
// Fills `record` (when given) from the first hit of a camera ray's
// transmitted chain beyond any spectacle lens: depth, normal and class.
void record_hit(const Hit& hit, const Camera& camera, int depth, PrimaryRecord* record);
// The Lambertian albedo at a diffuse hit (the textured iris included), and
// 0 for the inside of the sclera (the eye's dark inside), the pupil,
// the cornea or nothing.
double diffuse_albedo(const Scene& scene, const Hit& hit);

// The skin's and the sclera's albedo textures (tissue_texture.cpp): the
// skin's in about [-1.9, 0.45], the sclera's [-1.4, 0.12], mean 0; the
// albedo is the appearance's times 1 + contrast x texture. Skin in the
// head frame's (x, y) in mm (0 beyond 1e9 mm or for a non-finite point);
// sclera by the turn about the eye's axis and the polar angle from it,
// about the centre of rotation, its vessels fading in from
// `seam_polar_rad` (the seam with the cornea's polar angle) on.
double skin_texture(std::uint64_t seed, double x_mm, double y_mm);
double sclera_texture(std::uint64_t seed, double turn, double polar_rad, double seam_polar_rad);
// The albedo at a world point of the eye's skin or sclera.
double textured_skin_albedo(const Eye& eye, const Point3& world);
double textured_sclera_albedo(const Eye& eye, const Point3& world);

// A ray meeting a corneal or spectacle lens interface: which side it comes
// from, the Fresnel reflectance, and the two continuing directions.
struct InterfaceCrossing {
  double reflectance = 1;             // 1: total internal reflection
  double eta = 1;                     // n1 / n2 (incident over transmitted index)
  Vector3 facing;                     // the normal on the incident side
  std::optional<UnitVector3> reflected, transmitted;
};
InterfaceCrossing cross_interface(const Scene& scene, const Ray& ray, const Hit& hit);

// Radiance emitted back by the fundus through the pupil (bright pupil) under
// irradiance `irradiance_w_m2` from `light`, toward the camera at
// `camera_center`; see docs/rendering.md.
double bright_pupil_radiance(const Eye& eye, const Point3& light, const Point3& camera_center,
                             double irradiance_w_m2);
// Adds, for a pupil hit, every light's bright-pupil radiance times
// `weight`; `irradiance(k)` is the irradiance there from light k (from
// whichever estimate the integrator keeps).
template <typename IrradianceOf>
void add_bright_pupil(const Eye& eye, const std::vector<Light>& lights, const Point3& camera_center,
                      double weight, const IrradianceOf& irradiance, Contribution& out) {
  for (std::size_t k = 0; k < lights.size(); ++k) {
    out.add(weight * bright_pupil_radiance(eye, lights[k].position, camera_center, irradiance(k)), lights[k]);
  }
}

// How many interface crossings a specular chain may make: an integrator's
// own `base` for the eyes, four more with spectacle lenses (a lens crossed
// on the way in and out).
inline int specular_depth(const Scene& scene, int base) {
  return base + (scene.spectacle_lenses.empty() ? 0 : 4);
}

// What a surface does to light, for the integrators' one switch each.
enum class Scattering {
  none,       // nothing hit
  diffuse,    // Lambertian: skin, lids, sclera, meshes (albedo 0 on an inner side)
  iris,       // Lambertian and textured, lit through the cornea
  pupil,      // dark but for the fundus's retro-reflection
  interface,  // a corneal surface: Fresnel reflection and refraction
};
Scattering scattering_of(Surface surface);

// The side of a diffuse hit's surface that faces the ray.
inline Vector3 facing_normal(const Hit& hit) { return hit.front_face ? hit.normal.vector() : -hit.normal.vector(); }

// Radiance a Lambertian point of `scaled_albedo` (the path's weight
// included) sends toward the camera under `light`, at `d2` mm^2 from it
// and `cos_theta` to its normal.
inline double lambert_radiance(double scaled_albedo, const Light& light, double cos_theta, double d2) {
  return scaled_albedo * kInvPi * light.intensity_w_sr * cos_theta / d2 * kPerSquareMm;
}

}  // namespace purkinje::renderer
