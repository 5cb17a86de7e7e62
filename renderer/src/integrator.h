#pragma once
// The integrator interface (internal to renderer/): what one camera
// sample contributes, estimated by the fast (fast_integrator.cpp) or the
// reference (reference.cpp) integrator over the shared materials
// (materials.h).

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "materials.h"
#include "purkinje/renderer/ray_tracer.h"
#include "purkinje/renderer/render.h"

namespace purkinje::renderer {

// Secondary rays start this far off the surface they leave (mm); hits are
// exact in double precision, so a nanometre is plenty.
constexpr double kRayOffsetMm = 1e-6;

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

// Fast mode (fast_integrator.cpp): Fresnel-weighted splitting at the
// cornea, direct light with shadow rays, the iris's light from exact
// caches, interreflection from screen-space caches covering `traced`
// (gathered per sample where they do not serve).
std::unique_ptr<PathIntegrator> make_fast_integrator(const Scene& scene, const Camera& camera,
                                                     const RayTracer& tracer, const RenderOptions& options,
                                                     const PixelRegion& traced);

// The brute-force reference (reference.cpp); render() has checked the options.
std::unique_ptr<PathIntegrator> make_reference_integrator(const Scene& scene, const Camera& camera,
                                                          const RayTracer& tracer,
                                                          const RenderOptions& options);

}  // namespace purkinje::renderer
