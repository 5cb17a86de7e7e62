#include "materials.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "purkinje/renderer/radiometry.h"
#include "purkinje/renderer/sensor_model.h"

namespace purkinje::renderer {
namespace {

// Angular half-width (1/e) of the fundus's retro-reflection lobe: bright
// pupil needs a light within a few degrees of the camera as seen from the eye.
constexpr double kFundusLobeRad = 1.5 * std::numbers::pi / 180;

}  // namespace

Scattering scattering_of(Surface surface) {
  switch (surface) {
    case Surface::none: return Scattering::none;
    case Surface::skin:
    case Surface::sclera:
    case Surface::mesh:
    case Surface::lash:
    case Surface::brow: return Scattering::diffuse;
    case Surface::iris: return Scattering::iris;
    case Surface::pupil: return Scattering::pupil;
    case Surface::cornea_anterior:
    case Surface::cornea_posterior:
    case Surface::spectacle_lens: return Scattering::interface;
  }
  return Scattering::none;
}

std::vector<Light> lights_of(const Scene& scene, const Camera& camera) {
  std::vector<Light> lights;
  for (const Illuminator& l : scene.illuminators) {
    lights.push_back({l.position, l.radiant_intensity_w_sr,
                      electrons_per_unit_radiance(camera.sensor(), l.wavelength_nm),
                      0.5 * l.emitter_diameter_mm});
  }
  return lights;
}

namespace {
// Whether any eye's face has the hairs `hairs` points to.
template <class Hairs>
bool some_face_has(const Scene& scene, std::optional<Hairs> Face::*hairs) {
  return std::any_of(scene.eyes.begin(), scene.eyes.end(), [&](const Eye& eye) {
    const auto& face = eye.appearance().face;
    return face && (*face.*hairs).has_value();
  });
}
}  // namespace

bool scene_has_lashes(const Scene& scene) { return some_face_has(scene, &Face::lashes); }
bool scene_has_brows(const Scene& scene) { return some_face_has(scene, &Face::brows); }

bool scene_has_distractors(const Scene& scene) {
  if (!scene.spectacle_lenses.empty()) return true;
  for (const Eye& eye : scene.eyes) {
    if (eye.appearance().tear_film) return true;
  }
  return false;
}

PixelClass class_of(Surface s) {
  switch (s) {
    case Surface::skin: return PixelClass::skin;
    // Glasses, hands, occluders: not part of the eye, so in the
    // segmentation with what surrounds it.
    case Surface::mesh: return PixelClass::skin;
    case Surface::sclera: return PixelClass::sclera;
    case Surface::iris: return PixelClass::iris;
    case Surface::pupil: return PixelClass::pupil;
    case Surface::lash: return PixelClass::lash;
    case Surface::brow: return PixelClass::brow;
    default: return PixelClass::background;
  }
}

void record_hit(const Hit& hit, const Camera& camera, int depth, PrimaryRecord* record) {
  if (!record) return;
  // The camera sees through spectacle lenses: the first surface beyond
  // them is what it sees first.
  if (depth == record->lens_crossings) {
    if (hit.surface == Surface::spectacle_lens) {
      ++record->lens_crossings;
    } else if (hit.surface != Surface::none) {
      record->hit = true;
      record->depth_mm = (camera.camera_from_world() * hit.point).z;
      record->normal = hit.normal;
      record->through_cornea = hit.surface == Surface::cornea_anterior;
    }
  }
  record->pixel_class = class_of(hit.surface);
}

double diffuse_albedo(const Scene& scene, const Hit& hit) {
  switch (hit.surface) {
    case Surface::skin:
      // The lids' inner side: real lids rest on the globe, so what lies
      // behind their margins is dark, not a lit gap between lid and eye.
      return hit.front_face ? textured_skin_albedo(scene.eyes[hit.eye], hit.point) : 0.0;
    case Surface::mesh:
      return scene.meshes[hit.mesh].albedo;
    case Surface::lash:
      // Inside a lash (a ray from its own surface inward): nothing returns.
      return hit.front_face ? scene.eyes[hit.eye].appearance().face->lashes->albedo : 0.0;
    case Surface::brow:
      return hit.front_face ? scene.eyes[hit.eye].appearance().face->brows->albedo : 0.0;
    case Surface::sclera:
      return hit.front_face ? textured_sclera_albedo(scene.eyes[hit.eye], hit.point) : 0.0;
    case Surface::iris: {
      const Eye& eye = scene.eyes[hit.eye];
      const Point3 local = eye.eye_from_world() * hit.point;
      return iris_albedo(eye.model(), eye.appearance(), local.x, local.y);
    }
    default:
      return 0;
  }
}

InterfaceCrossing cross_interface(const Scene& scene, const Ray& ray, const Hit& hit) {
  double n_outer = 1.0, n_inner = 1.0;
  if (hit.surface == Surface::spectacle_lens) {
    n_inner = scene.spectacle_lenses[hit.lens].refractive_index;  // its normal points out of the glass
  } else {
    const EyeModel& m = scene.eyes[hit.eye].model();
    n_inner = anterior_inner_index(m);
    if (hit.surface == Surface::cornea_posterior) {
      n_outer = m.posterior_cornea->cornea_index;
      n_inner = m.aqueous_index;
    }
  }
  const Vector3 d = ray.direction.vector();
  const bool entering = dot(d, hit.normal.vector()) < 0;
  const double n1 = entering ? n_outer : n_inner;
  const double n2 = entering ? n_inner : n_outer;
  InterfaceCrossing c;
  c.facing = entering ? hit.normal.vector() : -hit.normal.vector();
  c.eta = n1 / n2;
  const double cos_i = std::clamp(-dot(d, c.facing), 0.0, 1.0);
  c.reflectance = fresnel_reflectance(cos_i, n1, n2);
  if (c.reflectance < 1.0) {
    const double k = 1.0 - c.eta * c.eta * (1.0 - cos_i * cos_i);
    c.transmitted = UnitVector3::try_normalize(d * c.eta + c.facing * (c.eta * cos_i - std::sqrt(std::max(k, 0.0))));
  }
  c.reflected = UnitVector3::try_normalize(d + c.facing * (2.0 * cos_i));
  return c;
}

// Retro-reflection from the fundus: of the light entering the pupil, a
// fraction fundus_reflectance returns through it into a narrow Gaussian
// lobe about the direction back to its source. Seen at an angle alpha
// from that direction, a pupil point under irradiance E has radiance
// rho E exp(-(alpha/alpha0)^2) / (pi alpha0^2), the lobe's solid angle
// being pi alpha0^2. Far from the camera's axis (alpha >> alpha0) the
// pupil stays dark.
double bright_pupil_radiance(const Eye& eye, const Point3& light, const Point3& camera_center,
                             double irradiance_w_m2) {
  const double rho = eye.appearance().fundus_reflectance;
  if (!(rho > 0) || !(irradiance_w_m2 > 0)) return 0;
  const Point3 c = eye.cornea_center();
  const double x = angle_between(light - c, camera_center - c) / kFundusLobeRad;
  if (x > 6) return 0;  // exp(-36): nothing
  return rho * irradiance_w_m2 * std::exp(-x * x) / (std::numbers::pi * kFundusLobeRad * kFundusLobeRad);
}

}  // namespace purkinje::renderer
