#pragma once
// Screen-space caches of the fast mode (internal to renderer/): quantities
// that vary slowly over a surface, computed at the nodes of a coarse grid
// over the image and interpolated between the nodes that see the same
// surface close by. See docs/rendering.md.
//
// - DiffuseCache: light bounced off other diffuse surfaces onto the skin,
//   lids, sclera and meshes the camera sees (a few percent of the image,
//   up to 10% in the creases around the eye), as the integrator gathers it.
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
  // Which nodes to find, by lattice index (the node at pixel (i s, j s));
  // empty: all. The others see nothing.
  using Needed = std::function<bool(int i, int j)>;
  // Finds the nodes' diffuse points, in parallel (call from inside the
  // render's task arena).
  ScreenGrid(const Camera& camera, const PixelRegion& region, int spacing_px, const FindDiffusePoint& find,
             const Needed& needed = {});

  int spacing() const { return spacing_; }
  // Nodes are numbered over the whole lattice, found or not.
  std::size_t size() const { return slot_.size(); }
  // What a node sees (nothing where it was not found).
  const DiffusePoint& point(std::size_t node) const;
  // The node's pixel on the whole image (for random numbers): the same for
  // nodes of two grids at one place.
  std::uint64_t key(std::size_t node) const;
  // The lattice index of a node and back; `contains` whether the grid has it.
  int i(std::size_t node) const { return i0_ + static_cast<int>(node % nx_); }
  int j(std::size_t node) const { return j0_ + static_cast<int>(node / nx_); }
  bool contains(int i, int j) const { return i >= i0_ && j >= j0_ && i < i0_ + nx_ && j < j0_ + ny_; }
  std::size_t node(int i, int j) const { return static_cast<std::size_t>(j - j0_) * nx_ + (i - i0_); }

  // The cell around an image position: its top-left node's lattice index
  // and the place in it. False outside the grid (never for a region's own
  // samples, by construction).
  struct Cell {
    int i = 0, j = 0;
    double tx = 0, ty = 0;
  };
  bool locate(const Pixel& image_position, Cell& cell) const;
  // Cells are numbered by their top-left node.
  std::size_t cell_index(const Cell& cell) const { return node(cell.i, cell.j); }

  // The (up to 4) nodes of a cell that serve `p`: the same surface, a
  // normal within 26 degrees, within 2.5 node spacings on the surface.
  // Each with its bilinear weight; returns how many.
  struct Corner {
    std::size_t node;
    double weight;
  };
  int corners(const Cell& cell, const DiffusePoint& p, Corner out[4]) const;
  // Whether a cell's four nodes see one surface and serve each other (a
  // smooth patch, no outline or crease between them).
  bool coherent(const Cell& cell) const;

 private:
  Pixel position(std::size_t node) const;
  bool serves(std::size_t node, const DiffusePoint& p, double& d2) const;

  struct Node {
    DiffusePoint point;
    double inverse_reach_squared = 0;  // 1 / the distance its point serves, squared
  };
  int spacing_ = 8;
  int i0_ = 0, j0_ = 0, nx_ = 0, ny_ = 0;  // node (i, j) sits at pixel ((i0 + i) s, (j0 + j) s)
  static constexpr std::uint32_t kNone = ~std::uint32_t{0};
  std::vector<std::uint32_t> slot_;  // [lattice node]: its place in nodes_, or kNone
  std::vector<Node> nodes_;          // the nodes found
};

// Node spacings of a two-level cache: coarse nodes everywhere, fine nodes
// only in the coarse cells that the cache cannot settle from their four
// corners. `fine_px` divides `coarse_px`; equal spacings make one level.
struct GridSpacing {
  int coarse_px = 8;
  int fine_px = 8;
};

// The two levels and which coarse cells are settled (internal to the caches).
class TwoLevelGrid {
 public:
  // Finds the coarse nodes.
  TwoLevelGrid(const Camera& camera, const PixelRegion& region, const GridSpacing& spacing,
               const FindDiffusePoint& find);
  const ScreenGrid& coarse() const { return coarse_; }
  const ScreenGrid& fine() const { return fine_ ? *fine_ : coarse_; }
  // Settles each coarse cell where `settled(cell)`, then finds the fine
  // nodes of the cells left (one level: everything is settled).
  void refine(const Camera& camera, const PixelRegion& region, const FindDiffusePoint& find,
              const std::function<bool(const ScreenGrid::Cell&)>& settled);
  // The grid whose cell serves `image_position` (the coarse one where
  // settled), and that cell; null outside.
  const ScreenGrid* at(const Pixel& image_position, ScreenGrid::Cell& cell) const;
  // The coarse node at a fine node's place, if there is one.
  std::optional<std::size_t> coarse_node_at(std::size_t fine_node) const;

 private:
  ScreenGrid coarse_;
  int fine_px_ = 8;
  std::optional<ScreenGrid> fine_;  // once refined, with two levels
  std::vector<std::uint8_t> settled_;  // [coarse cell]
};

class DiffuseCache {
 public:
  // Adds per-light irradiance (W/m^2) from diffuse interreflection at a
  // point into `irradiance`; `key` numbers the node for random numbers.
  using Gather = std::function<void(const DiffusePoint& point, std::uint64_t key, double* irradiance)>;
  // The irradiance a point gets directly (all lights, shadows ignored):
  // what the interpolation error is judged against.
  using Direct = std::function<double(const DiffusePoint& point)>;

  // A coarse cell is settled when its corners are coherent and their
  // interreflection (summed over lights) differs by at most `tolerance`
  // times the least direct irradiance among them. Builds in parallel
  // (call from inside the render's task arena).
  DiffuseCache(const Camera& camera, const PixelRegion& region, const GridSpacing& spacing, std::size_t lights,
               const FindDiffusePoint& find, const Gather& gather, const Direct& direct, double tolerance);

  // Per-light irradiance at `p`, seen at `image_position`, interpolated
  // from the nodes that serve it, into `irradiance` (overwritten). False
  // when none does (at creases, thin slivers, edges): the caller gathers.
  bool irradiance(const Pixel& image_position, const DiffusePoint& p, double* irradiance) const;

 private:
  TwoLevelGrid grid_;
  std::size_t lights_ = 0;
  std::vector<double> coarse_, fine_;  // [node][light]
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

  // At most kMaxLights lights; more build nothing and answer unknown. A
  // coarse cell is settled when its corners are coherent and agree on
  // every light.
  static constexpr std::size_t kMaxLights = 64;
  VisibilityCache(const Camera& camera, const PixelRegion& region, const GridSpacing& spacing,
                  std::size_t lights, const FindDiffusePoint& find, const Lit& lit);

  // The lights at `p`, seen at `image_position`, on which the four nodes
  // of its cell agree when all serve the point, or three that serve it
  // when it lies inside their triangle; nothing is known otherwise.
  Agreement at(const Pixel& image_position, const DiffusePoint& p) const;

 private:
  std::optional<TwoLevelGrid> grid_;  // none: too many lights
  std::size_t lights_ = 0;
  std::vector<std::uint64_t> coarse_, fine_;  // [node], bit k: light k
};

}  // namespace purkinje::renderer
