#pragma once
// What the fast and the reference integrators share (internal to
// renderer/): the lights as the integrators see them, what one camera
// sample contributes, what it saw first (for AOVs), and the crossing of a
// corneal interface.

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "purkinje/renderer/ray_tracer.h"
#include "purkinje/renderer/render.h"

namespace purkinje::renderer {

// Scene lengths are mm; irradiance is per m^2.
constexpr double kPerSquareMm = 1e6;
// Secondary rays start this far off the surface they leave (mm); hits are
// exact in double precision, so a nanometre is plenty.
constexpr double kRayOffsetMm = 1e-6;

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

// What the pixel's primary path saw first, for AOVs.
struct PrimaryRecord {
  PixelClass pixel_class = PixelClass::background;
  bool hit = false;
  double depth_mm = 0;
  Vector3 normal;
  bool through_cornea = false;
};
PixelClass class_of(Surface s);
// Fills `record` (when given) from the first hit of a camera ray's
// transmitted chain: depth, normal and class.
void record_hit(const Hit& hit, const Camera& camera, int depth, PrimaryRecord* record);
// The Lambertian albedo at a diffuse hit (the textured iris included), and
// 0 for the inside of the sclera (the eye's dark inside), the pupil,
// the cornea or nothing.
double diffuse_albedo(const Scene& scene, const Hit& hit);

// One camera sample's radiance: the ray through `image_position`, whose
// first hit the caller has found (camera rays are traced in packets).
// `path` numbers the sample uniquely within the image (pixel and sample
// index), for integrators that draw random numbers along the path.
// `reflection_weight` scales what the cornea reflects into the sample: a
// pixel may trace its reflection in one sample for several (the fast
// mode's refined pixels); 0 leaves it to another sample. The reference
// is only ever given 1.
class PathIntegrator {
 public:
  virtual ~PathIntegrator() = default;
  virtual void sample(const Ray& ray, const Hit& first_hit, const Pixel& image_position, std::uint64_t path,
                      Contribution& out, PrimaryRecord& record, double reflection_weight) const = 0;
};

// A ray meeting a corneal interface: which side it comes from, the Fresnel
// reflectance, and the two continuing directions.
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

// The brute-force reference (reference.cpp); render() has checked the options.
std::unique_ptr<PathIntegrator> make_reference_integrator(const Scene& scene, const Camera& camera,
                                                          const RayTracer& tracer,
                                                          const RenderOptions& options);

}  // namespace purkinje::renderer
