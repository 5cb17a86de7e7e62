#pragma once
// The fast mode's diffuse interreflection on what the camera sees through
// its pixels (skin, lids, sclera, meshes): irradiance from light that has
// bounced off other diffuse surfaces at least once. It is a few percent of
// the image, up to tens of percent in the creases around the eye, and it
// varies slowly over a surface, so it is computed at the nodes of a coarse
// grid over the image and interpolated between the nodes that see the same
// surface close by (a screen-space irradiance cache). Internal to
// renderer/; see docs/rendering.md.

#include <cstddef>
#include <functional>
#include <vector>

#include "purkinje/models/camera.h"
#include "purkinje/renderer/ray_tracer.h"
#include "purkinje/renderer/render.h"

namespace purkinje::renderer {

// A diffuse point seen along a camera ray's transmitted chain.
struct DiffusePoint {
  Surface surface = Surface::none;  // none: the chain met no diffuse surface
  int owner = -1;                   // the eye, or for Surface::mesh the mesh
  Point3 point;
  Vector3 normal;                   // unit, on the side the ray arrived from
  double path_mm = 0;               // camera to point along the chain
  double cos_view = 1;              // |normal . the arriving ray|
};

class DiffuseCache {
 public:
  // The first diffuse point along the chain of a camera ray through an image position.
  using FindPoint = std::function<DiffusePoint(const Pixel& image_position)>;
  // Adds per-light irradiance (W/m^2) from diffuse interreflection at a
  // point into `irradiance`; `node` numbers the node for random numbers.
  using Gather = std::function<void(const DiffusePoint& point, std::size_t node, double* irradiance)>;

  // Nodes every `spacing_px` pixels, anchored at pixel (0, 0) so that a
  // region's nodes are the same as a whole image's, covering `region`.
  // Builds in parallel (call from inside the render's task arena).
  DiffuseCache(const Camera& camera, const PixelRegion& region, int spacing_px, std::size_t lights,
               const FindPoint& find, const Gather& gather);

  // Per-light irradiance at `p`, seen at `image_position`, interpolated
  // from the surrounding nodes that see the same surface nearby with a
  // similar normal, into `irradiance` (overwritten). False when no such
  // node exists (at creases, thin slivers, edges): the caller gathers.
  bool irradiance(const Pixel& image_position, const DiffusePoint& p, double* irradiance) const;

  std::size_t nodes() const { return points_.size(); }

 private:
  int spacing_ = 8;
  int i0_ = 0, j0_ = 0, nx_ = 0, ny_ = 0;  // node (i, j) sits at pixel ((i0 + i) s, (j0 + j) s)
  std::size_t lights_ = 0;
  double pixel_angle_ = 0;                 // radians per pixel
  std::vector<DiffusePoint> points_;       // [node]
  std::vector<double> irradiance_;         // [node][light]
};

}  // namespace purkinje::renderer
