#pragma once
// The scene's lights as points behind spectacle lenses see them (internal
// to renderer/). A lens bends an LED's light on its way to the eye and the
// face behind it: there the light seems to come from the lens's image of
// the LED, dimmed by the surfaces' Fresnel transmittance and spread or
// gathered by the lens's power (a -3 D lens 12 mm from the eye: about 8%
// and 7% less irradiance; the image 200 mm away instead of 600 mm).
// Both integrators light through a lens with this image instead of
// tracing refracted shadow rays (spectacle lenses never occlude, see
// RayTracer::occluded).
//
// The image moves across the region behind a lens (prism, aberrations: a
// single image found at the eye's apex is 3-5% off 12 mm away with a
// -3 to -6 D lens), so each (lens, light) keeps a field: exact at the
// nodes of a grid on the plane through the eye's apex across the lens's
// axis (models' light_through_lens: the light's direction, vergence and
// irradiance there), a point's taken from where the ray that lights it
// (the line from it along the apex's direction) crosses that plane,
// interpolated bilinearly and carried along the ray to the point by the
// vergence (irradiance as 1 / (1 + vergence * depth)^2).

#include <vector>

#include "materials.h"
#include "purkinje/models/specular.h"
#include "purkinje/models/scene.h"
#include "scene_geometry.h"

namespace purkinje::renderer {

// A passage's Fresnel transmittance through a lens of index `n`: into the
// glass at one surface, out at the other (the same either way along it).
double lens_transmittance(const LensPassage& passage, double n);

class SeenLights {
 public:
  // Keeps a pointer to `lights`, which must outlive it.
  SeenLights(const Scene& scene, const std::vector<Light>& lights);
  SeenLights(const SeenLights&) = delete;
  SeenLights& operator=(const SeenLights&) = delete;

  // Light k as `p` sees it: the light, or, where the straight segment
  // from `p` to it crosses a spectacle lens (the first listed, as the
  // truth's legs take), a point light in the direction its light comes
  // from through the lens, as far as the lens's image of it (as far in
  // front as a converging beam's real image lies behind; 1e6 mm for a
  // collimated one), of the intensity that gives `p` its irradiance, its
  // emitter keeping its angular size.
  Light at(const Point3& p, std::size_t k) const {
    if (fields_.empty()) return (*lights_)[k];
    return through_lens(p, k);
  }

  // One lens's images of one light (public for tests).
  struct Field;
  const std::vector<Field>& fields() const { return fields_; }

 private:
  Light through_lens(const Point3& p, std::size_t k) const;

  const std::vector<Light>* lights_;
  std::vector<Field> fields_;  // [lens][light], lens-major; empty without lenses
};

struct SeenLights::Field {
  Frame lens;                        // the lens frame
  surfaces::LensCap front, back;     // in it
  Point3 light;                      // world
  Point3 light_local;                // lens frame
  double plane_z = 0;                // lens frame: the grid's plane
  double half_x = 0, half_y = 0, step_x = 1, step_y = 1;
  int nx = 0, ny = 0;
  struct Node {
    bool valid = false;
    Vector3 direction;      // world, toward where the light comes from
    double vergence = 0;    // 1/mm
    double irradiance = 0;  // per unit intensity: transmittance times solid angle per area (1/mm^2)
  };
  std::vector<Node> nodes;
  Node centre;                  // at the eye's apex, on the plane
  Point3 central_image_local;   // its image (or as far along its ray), lens frame

  Field(const SpectacleLens& lens, const Point3& light, const Point3& near, double spacing_mm);
  // Whether the straight segment from `p` to the light crosses the lens.
  bool crosses(const Point3& p) const;
  // The node values for `p` (behind the lens), how far behind the plane
  // along its ray it lies, and where that ray crosses the plane.
  Node at(const Point3& p, double& depth_mm, Point3& on_plane) const;
};

}  // namespace purkinje::renderer
