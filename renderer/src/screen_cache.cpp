#include "screen_cache.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace purkinje::renderer {

namespace {

// Nodes with normals further apart than this (about 26 deg) see different
// parts of the scene: not interpolated across (creases such as lid and face).
constexpr double kMinNormalCos = 0.9;
// A node's point serves points within this many node spacings (measured on
// the surface, so stretched where the surface is seen obliquely).
constexpr double kReachSpacings = 2.5;
constexpr double kMinCosView = 0.25;

template <typename Body>
void for_each_node(std::size_t count, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t n = r.begin(); n < r.end(); ++n) body(n);
  });
}

}  // namespace

ScreenGrid::ScreenGrid(const Camera& camera, const PixelRegion& region, int spacing_px,
                       const FindDiffusePoint& find)
    : spacing_(spacing_px) {
  const Intrinsics& k = camera.intrinsics();
  const double pixel_angle = 1.0 / std::max(k.fx, k.fy);
  // Samples of pixel x lie in [x - 0.5, x + 0.5]: nodes from the one at
  // or before x0 - 0.5 to the one at or after x1 - 0.5, so that no lookup
  // in the region is clamped and every lookup is the whole image's.
  const auto floor_div = [](int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); };
  i0_ = floor_div(region.x0 - 1, spacing_);
  j0_ = floor_div(region.y0 - 1, spacing_);
  nx_ = floor_div(region.x1 + spacing_ - 1, spacing_) - i0_ + 1;
  ny_ = floor_div(region.y1 + spacing_ - 1, spacing_) - j0_ + 1;
  nodes_.resize(static_cast<std::size_t>(nx_) * ny_);
  for_each_node(nodes_.size(), [&](std::size_t n) {
    Node& node = nodes_[n];
    node.point = find(position(n));
    const double reach =
        kReachSpacings * spacing_ * node.point.path_mm * pixel_angle / std::max(node.point.cos_view, kMinCosView);
    if (reach > 0) node.inverse_reach_squared = 1 / (reach * reach);
  });
}

Pixel ScreenGrid::position(std::size_t node) const {
  const int i = static_cast<int>(node % nx_), j = static_cast<int>(node / nx_);
  return {double((i0_ + i) * spacing_), double((j0_ + j) * spacing_)};
}

std::uint64_t ScreenGrid::key(std::size_t node) const {
  const std::int64_t i = i0_ + static_cast<std::int64_t>(node % nx_);
  const std::int64_t j = j0_ + static_cast<std::int64_t>(node / nx_);
  return static_cast<std::uint64_t>(j + 1) << 32 | static_cast<std::uint32_t>(i + 1);
}

int ScreenGrid::corners(const Pixel& image_position, const DiffusePoint& p, Corner out[4]) const {
  // The cell and the place in it on the whole image's lattice, so that
  // the arithmetic is the same whatever the region. Outside the lattice
  // nothing serves; a region's own samples never are, by construction.
  const auto locate = [](double g, int first, int count, int& cell, double& t) {
    if (!(g >= first && g < first + count - 1)) return false;  // also NaN
    const double floor_g = std::floor(g);
    cell = static_cast<int>(floor_g) - first;
    t = g - floor_g;
    return true;
  };
  int ia, ja;
  double tx, ty;
  if (!locate(image_position.u / spacing_, i0_, nx_, ia, tx) || !locate(image_position.v / spacing_, j0_, ny_, ja, ty)) {
    return 0;
  }
  int count = 0;
  for (int dj = 0; dj < 2; ++dj) {
    for (int di = 0; di < 2; ++di) {
      const int i = ia + di, j = ja + dj;
      const std::size_t n = static_cast<std::size_t>(j) * nx_ + i;
      const DiffusePoint& q = nodes_[n].point;
      if (q.surface != p.surface || q.owner != p.owner) continue;
      if (dot(q.normal, p.normal) < kMinNormalCos) continue;
      const double d2 = (q.point - p.point).squared_norm() * nodes_[n].inverse_reach_squared;
      if (d2 >= 1) continue;
      // Never zero, so that a node exactly across the cell still counts.
      out[count++] = {n, (di ? tx : 1 - tx) * (dj ? ty : 1 - ty) * (1 - d2) + 1e-12};
    }
  }
  return count;
}

DiffuseCache::DiffuseCache(const Camera& camera, const PixelRegion& region, int spacing_px, std::size_t lights,
                           const FindDiffusePoint& find, const Gather& gather)
    : grid_(camera, region, spacing_px, find), lights_(lights) {
  irradiance_.assign(grid_.size() * lights_, 0.0);
  for_each_node(grid_.size(), [&](std::size_t n) {
    if (grid_.point(n).surface != Surface::none) gather(grid_.point(n), grid_.key(n), irradiance_.data() + n * lights_);
  });
}

bool DiffuseCache::irradiance(const Pixel& image_position, const DiffusePoint& p, double* e) const {
  ScreenGrid::Corner corners[4];
  const int count = grid_.corners(image_position, p, corners);
  if (count == 0) return false;
  std::fill(e, e + lights_, 0.0);
  double total = 0;
  for (int c = 0; c < count; ++c) {
    total += corners[c].weight;
    const double* node = irradiance_.data() + corners[c].node * lights_;
    for (std::size_t l = 0; l < lights_; ++l) e[l] += corners[c].weight * node[l];
  }
  for (std::size_t l = 0; l < lights_; ++l) e[l] /= total;
  return true;
}

VisibilityCache::VisibilityCache(const Camera& camera, const PixelRegion& region, int spacing_px,
                                 std::size_t lights, const FindDiffusePoint& find, const Lit& lit)
    : lights_(lights) {
  if (lights_ > kMaxLights) return;
  const ScreenGrid& grid = grid_.emplace(camera, region, spacing_px, find);
  lit_.assign(grid.size(), 0);
  for_each_node(grid.size(), [&](std::size_t n) {
    if (grid.point(n).surface == Surface::none) return;
    for (std::size_t k = 0; k < lights_; ++k) {
      if (lit(grid.point(n), k)) lit_[n] |= std::uint64_t{1} << k;
    }
  });
}

VisibilityCache::Agreement VisibilityCache::at(const Pixel& image_position, const DiffusePoint& p) const {
  if (!grid_) return {};
  ScreenGrid::Corner corners[4];
  if (grid_->corners(image_position, p, corners) < 4) return {};
  std::uint64_t all = ~std::uint64_t{0}, any = 0;
  for (const ScreenGrid::Corner& c : corners) {
    all &= lit_[c.node];
    any |= lit_[c.node];
  }
  const std::uint64_t mask = lights_ == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << lights_) - 1;
  // Agreed: lit at all four (all) or at none (~any).
  return {(all | ~any) & mask, all & mask};
}

}  // namespace purkinje::renderer
