#pragma once
// Screen-space caches of the fast mode (internal to renderer/): quantities
// that vary slowly over a surface, computed at the nodes of a coarse grid
// over the image and interpolated between the nodes that see the same
// surface close by. See docs/rendering.md.
//
// - DiffuseCache: light bounced once off other diffuse surfaces onto the
//   skin, lids, sclera and meshes the camera sees (a few percent of the
//   image, up to 10% in the creases around the eye).
// - VisibilityCache: which lights a point sees (shadows); a point between
//   nodes that agree takes their answer, elsewhere the shadow ray is traced.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
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

// The first diffuse point along the chain of the camera ray through an
// image position.
using FindDiffusePoint = std::function<DiffusePoint(const Pixel& image_position)>;

// Nodes every `spacing_px` pixels on a lattice anchored at pixel (0, 0),
// covering every sample of a region's pixels: a region's lookups are the
// same as the whole image's.
class ScreenGrid {
 public:
  // Finds every node's diffuse point, in parallel (call from inside the
  // render's task arena).
  ScreenGrid(const Camera& camera, const PixelRegion& region, int spacing_px, const FindDiffusePoint& find);

  std::size_t size() const { return nodes_.size(); }
  const DiffusePoint& point(std::size_t node) const { return nodes_[node].point; }
  // The node's place on the whole image's lattice (for random numbers).
  std::uint64_t key(std::size_t node) const;

  // The (up to 4) nodes around `image_position` that serve `p`: the same
  // surface, a normal within 26 degrees, within 2.5 node spacings on the
  // surface. Each with its bilinear weight; returns how many.
  struct Corner {
    std::size_t node;
    double weight;
  };
  int corners(const Pixel& image_position, const DiffusePoint& p, Corner out[4]) const;

 private:
  Pixel position(std::size_t node) const;

  struct Node {
    DiffusePoint point;
    double inverse_reach_squared = 0;  // 1 / the distance its point serves, squared
  };
  int spacing_ = 8;
  int i0_ = 0, j0_ = 0, nx_ = 0, ny_ = 0;  // node (i, j) sits at pixel ((i0 + i) s, (j0 + j) s)
  std::vector<Node> nodes_;
};

class DiffuseCache {
 public:
  // Adds per-light irradiance (W/m^2) from diffuse interreflection at a
  // point into `irradiance`; `key` numbers the node for random numbers.
  using Gather = std::function<void(const DiffusePoint& point, std::uint64_t key, double* irradiance)>;

  // Builds in parallel (call from inside the render's task arena).
  DiffuseCache(const Camera& camera, const PixelRegion& region, int spacing_px, std::size_t lights,
               const FindDiffusePoint& find, const Gather& gather);

  // Per-light irradiance at `p`, seen at `image_position`, interpolated
  // from the nodes that serve it, into `irradiance` (overwritten). False
  // when none does (at creases, thin slivers, edges): the caller gathers.
  bool irradiance(const Pixel& image_position, const DiffusePoint& p, double* irradiance) const;

 private:
  ScreenGrid grid_;
  std::size_t lights_ = 0;
  std::vector<double> irradiance_;  // [node][light]
};

class VisibilityCache {
 public:
  // Whether light k lights the point: it faces the light and nothing
  // blocks the way.
  using Lit = std::function<bool(const DiffusePoint& point, std::size_t light)>;
  // What the nodes around a point agree on: bit k of `known` set when
  // they agree about light k, bit k of `lit` then their answer.
  struct Agreement {
    std::uint64_t known = 0, lit = 0;
  };

  // At most kMaxLights lights; more build nothing and answer unknown.
  static constexpr std::size_t kMaxLights = 64;
  VisibilityCache(const Camera& camera, const PixelRegion& region, int spacing_px, std::size_t lights,
                  const FindDiffusePoint& find, const Lit& lit);

  // The lights at `p`, seen at `image_position`, on which four nodes that
  // serve the point agree; nothing is known when fewer serve it.
  Agreement at(const Pixel& image_position, const DiffusePoint& p) const;

 private:
  std::optional<ScreenGrid> grid_;  // none: too many lights
  std::size_t lights_ = 0;
  std::vector<std::uint64_t> lit_;  // [node], bit k: light k
};

}  // namespace purkinje::renderer
