#include "screen_cache.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace purkinje::renderer {

namespace {

// Nodes with normals further apart than this (about 26 deg) see different
// parts of the scene: not interpolated across (creases such as lid and face).
constexpr double kMinNormalCos = 0.9;
// A node's point serves points within this many node spacings (measured on
// the surface, so stretched where the surface is seen obliquely).
constexpr double kReachSpacings = 2.5;
constexpr double kMinCosView = 0.25;

// a / b rounded down (toward minus infinity), b > 0.
int floor_div(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

template <typename Body>
void for_each_node(std::size_t count, const Body& body) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t n = r.begin(); n < r.end(); ++n) body(n);
  });
}

}  // namespace

ScreenGrid::ScreenGrid(const Camera& camera, const PixelRegion& region, int spacing_px,
                       const FindDiffusePoint& find, const Needed& needed)
    : spacing_(spacing_px) {
  const Intrinsics& k = camera.intrinsics();
  const double pixel_angle = 1.0 / std::max(k.fx, k.fy);
  // Samples of pixel x lie in [x - 0.5, x + 0.5]: nodes from the one at
  // or before x0 - 0.5 to the one at or after x1 - 0.5, so that no lookup
  // in the region is clamped and every lookup is the whole image's.
  i0_ = floor_div(region.x0 - 1, spacing_);
  j0_ = floor_div(region.y0 - 1, spacing_);
  nx_ = floor_div(region.x1 + spacing_ - 1, spacing_) - i0_ + 1;
  ny_ = floor_div(region.y1 + spacing_ - 1, spacing_) - j0_ + 1;
  // Only the nodes needed are stored: a fine grid may need few of many.
  slot_.assign(static_cast<std::size_t>(nx_) * ny_, kNone);
  std::vector<std::size_t> lattice_node;
  for (std::size_t n = 0; n < slot_.size(); ++n) {
    if (needed && !needed(i(n), j(n))) continue;
    slot_[n] = static_cast<std::uint32_t>(lattice_node.size());
    lattice_node.push_back(n);
  }
  nodes_.resize(lattice_node.size());
  for_each_node(nodes_.size(), [&](std::size_t slot) {
    Node& node = nodes_[slot];
    node.point = find(position(lattice_node[slot]));
    const double reach =
        kReachSpacings * spacing_ * node.point.path_mm * pixel_angle / std::max(node.point.cos_view, kMinCosView);
    if (reach > 0) node.inverse_reach_squared = 1 / (reach * reach);
  });
}

Pixel ScreenGrid::position(std::size_t node) const {
  return {double(i(node) * spacing_), double(j(node) * spacing_)};
}

std::uint64_t ScreenGrid::key(std::size_t node) const {
  const std::int64_t x = std::int64_t{i(node)} * spacing_, y = std::int64_t{j(node)} * spacing_;
  return static_cast<std::uint64_t>(y + 1) << 32 | static_cast<std::uint32_t>(x + 1);
}

bool ScreenGrid::locate(const Pixel& image_position, Cell& cell) const {
  // On the whole image's lattice, so that the arithmetic is the same
  // whatever the region.
  const auto along = [](double g, int first, int count, int& index, double& t) {
    if (!(g >= first && g < first + count - 1)) return false;  // also NaN
    const double floor_g = std::floor(g);
    index = static_cast<int>(floor_g);
    t = g - floor_g;
    return true;
  };
  return along(image_position.u / spacing_, i0_, nx_, cell.i, cell.tx) &&
         along(image_position.v / spacing_, j0_, ny_, cell.j, cell.ty);
}

const DiffusePoint& ScreenGrid::point(std::size_t node) const {
  static const DiffusePoint nothing;
  return slot_[node] == kNone ? nothing : nodes_[slot_[node]].point;
}

bool ScreenGrid::serves(std::size_t n, const DiffusePoint& p, double& d2) const {
  if (slot_[n] == kNone) return false;
  const Node& node = nodes_[slot_[n]];
  const DiffusePoint& q = node.point;
  if (q.surface == Surface::none || q.surface != p.surface || q.owner != p.owner) return false;
  if (dot(q.normal, p.normal) < kMinNormalCos) return false;
  d2 = (q.point - p.point).squared_norm() * node.inverse_reach_squared;
  return d2 < 1;
}

int ScreenGrid::corners(const Cell& cell, const DiffusePoint& p, Corner out[4]) const {
  int count = 0;
  for (int dj = 0; dj < 2; ++dj) {
    for (int di = 0; di < 2; ++di) {
      const std::size_t n = node(cell.i + di, cell.j + dj);
      double d2;
      if (!serves(n, p, d2)) continue;
      // Never zero, so that a node exactly across the cell still counts.
      out[count++] = {n, (di ? cell.tx : 1 - cell.tx) * (dj ? cell.ty : 1 - cell.ty) * (1 - d2) + 1e-12};
    }
  }
  return count;
}

bool ScreenGrid::coherent(const Cell& cell) const {
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) {
      double d2;
      if (a != b && !serves(node(cell.i + a % 2, cell.j + a / 2), point(node(cell.i + b % 2, cell.j + b / 2)), d2)) {
        return false;
      }
    }
  }
  return true;
}

TwoLevelGrid::TwoLevelGrid(const Camera& camera, const PixelRegion& region, const GridSpacing& spacing,
                           const FindDiffusePoint& find)
    : coarse_(camera, region, spacing.coarse_px, find), fine_px_(spacing.fine_px) {
  if (spacing.fine_px < 1 || spacing.coarse_px % spacing.fine_px != 0) {
    throw std::invalid_argument("GridSpacing: fine_px = " + std::to_string(spacing.fine_px) +
                                " must divide coarse_px = " + std::to_string(spacing.coarse_px));
  }
}

void TwoLevelGrid::refine(const Camera& camera, const PixelRegion& region, const FindDiffusePoint& find,
                          const std::function<bool(const ScreenGrid::Cell&)>& settled) {
  if (fine_px_ == coarse_.spacing()) return;
  settled_.assign(coarse_.size(), 0);
  for_each_node(coarse_.size(), [&](std::size_t n) {
    const ScreenGrid::Cell cell{coarse_.i(n), coarse_.j(n)};
    if (coarse_.contains(cell.i + 1, cell.j + 1)) settled_[n] = settled(cell);
  });
  // A fine node is needed by the unsettled coarse cells it lies in or on.
  const int ratio = coarse_.spacing() / fine_px_;
  const auto unsettled = [&](int ci, int cj) {
    return coarse_.contains(ci, cj) && coarse_.contains(ci + 1, cj + 1) && !settled_[coarse_.node(ci, cj)];
  };
  fine_.emplace(camera, region, fine_px_, find, [&](int i, int j) {
    const int ci = floor_div(i, ratio), cj = floor_div(j, ratio);
    const bool on_i = i % ratio == 0, on_j = j % ratio == 0;
    return unsettled(ci, cj) || (on_i && unsettled(ci - 1, cj)) || (on_j && unsettled(ci, cj - 1)) ||
           (on_i && on_j && unsettled(ci - 1, cj - 1));
  });
}

const ScreenGrid* TwoLevelGrid::at(const Pixel& image_position, ScreenGrid::Cell& cell) const {
  if (!coarse_.locate(image_position, cell)) return nullptr;
  if (!fine_ || settled_[coarse_.cell_index(cell)]) return &coarse_;
  return fine_->locate(image_position, cell) ? &*fine_ : nullptr;
}

std::optional<std::size_t> TwoLevelGrid::coarse_node_at(std::size_t fine_node) const {
  if (!fine_) return fine_node;
  const int ratio = coarse_.spacing() / fine_px_;
  const int i = fine_->i(fine_node), j = fine_->j(fine_node);
  if (i % ratio != 0 || j % ratio != 0 || !coarse_.contains(i / ratio, j / ratio)) return std::nullopt;
  return coarse_.node(i / ratio, j / ratio);
}

DiffuseCache::DiffuseCache(const Camera& camera, const PixelRegion& region, const GridSpacing& spacing,
                           std::size_t lights, const FindDiffusePoint& find, const Gather& gather,
                           const Direct& direct, double tolerance)
    : grid_(camera, region, spacing, find), lights_(lights) {
  const ScreenGrid& coarse = grid_.coarse();
  coarse_.assign(coarse.size() * lights_, 0.0);
  std::vector<double> level(coarse.size(), 0.0), total(coarse.size(), 0.0);
  for_each_node(coarse.size(), [&](std::size_t n) {
    if (coarse.point(n).surface == Surface::none) return;
    double* e = coarse_.data() + n * lights_;
    gather(coarse.point(n), coarse.key(n), e);
    total[n] = std::accumulate(e, e + lights_, 0.0);
    level[n] = direct(coarse.point(n));
  });
  grid_.refine(camera, region, find, [&](const ScreenGrid::Cell& cell) {
    if (!coarse.coherent(cell)) return false;
    double lo = INFINITY, hi = -INFINITY, least_level = INFINITY;
    for (int c = 0; c < 4; ++c) {
      const std::size_t n = coarse.node(cell.i + c % 2, cell.j + c / 2);
      lo = std::min(lo, total[n]);
      hi = std::max(hi, total[n]);
      least_level = std::min(least_level, level[n]);
    }
    return hi - lo <= tolerance * least_level;
  });
  const ScreenGrid& fine = grid_.fine();
  if (&fine == &coarse) return;
  fine_.assign(fine.size() * lights_, 0.0);
  for_each_node(fine.size(), [&](std::size_t n) {
    if (fine.point(n).surface == Surface::none) return;
    double* e = fine_.data() + n * lights_;
    // The same node on both levels: the same gather, done once.
    if (const auto c = grid_.coarse_node_at(n)) {
      std::copy_n(coarse_.data() + *c * lights_, lights_, e);
    } else {
      gather(fine.point(n), fine.key(n), e);
    }
  });
}

bool DiffuseCache::irradiance(const Pixel& image_position, const DiffusePoint& p, double* e) const {
  ScreenGrid::Cell cell;
  const ScreenGrid* grid = grid_.at(image_position, cell);
  if (!grid) return false;
  ScreenGrid::Corner corners[4];
  const int count = grid->corners(cell, p, corners);
  if (count == 0) return false;
  const std::vector<double>& nodes = grid == &grid_.coarse() ? coarse_ : fine_;
  double total = 0;
  const double* node[4];
  for (int c = 0; c < count; ++c) {
    total += corners[c].weight;
    node[c] = nodes.data() + corners[c].node * lights_;
  }
  // Light by light, each sum in a register: summed through `e`, which may
  // alias the nodes for all the compiler knows, every term would be a
  // store and a reload (a tenth of a remote render).
  for (std::size_t l = 0; l < lights_; ++l) {
    double sum = 0;
    for (int c = 0; c < count; ++c) sum += corners[c].weight * node[c][l];
    e[l] = sum / total;
  }
  return true;
}

VisibilityCache::VisibilityCache(const Camera& camera, const PixelRegion& region, const GridSpacing& spacing,
                                 std::size_t lights, const FindDiffusePoint& find, const Lit& lit)
    : lights_(lights) {
  if (lights_ > kMaxLights) return;
  TwoLevelGrid& grid = grid_.emplace(camera, region, spacing, find);
  const auto lit_bits = [&](const ScreenGrid& level, std::size_t n) {
    std::uint64_t bits = 0;
    if (level.point(n).surface == Surface::none) return bits;
    for (std::size_t k = 0; k < lights_; ++k) {
      if (lit(level.point(n), k)) bits |= std::uint64_t{1} << k;
    }
    return bits;
  };
  const ScreenGrid& coarse = grid.coarse();
  coarse_.assign(coarse.size(), 0);
  for_each_node(coarse.size(), [&](std::size_t n) { coarse_[n] = lit_bits(coarse, n); });
  grid.refine(camera, region, find, [&](const ScreenGrid::Cell& cell) {
    if (!coarse.coherent(cell)) return false;
    const std::uint64_t first = coarse_[coarse.node(cell.i, cell.j)];
    return coarse_[coarse.node(cell.i + 1, cell.j)] == first && coarse_[coarse.node(cell.i, cell.j + 1)] == first &&
           coarse_[coarse.node(cell.i + 1, cell.j + 1)] == first;
  });
  const ScreenGrid& fine = grid.fine();
  if (&fine == &coarse) return;
  fine_.assign(fine.size(), 0);
  for_each_node(fine.size(), [&](std::size_t n) {
    const auto c = grid.coarse_node_at(n);
    fine_[n] = c ? coarse_[*c] : lit_bits(fine, n);
  });
}

VisibilityCache::Agreement VisibilityCache::at(const Pixel& image_position, const DiffusePoint& p) const {
  if (!grid_) return {};
  ScreenGrid::Cell cell;
  const ScreenGrid* grid = grid_->at(image_position, cell);
  if (!grid) return {};
  ScreenGrid::Corner corners[4];
  const int count = grid->corners(cell, p, corners);
  if (count < 3) return {};
  if (count == 3) {
    // Three nodes settle the points inside their triangle: a (locally
    // straight) shadow edge cannot part such a point from all three. The
    // fourth does not serve the point (mostly: it sees another surface, at
    // the outlines where most unsettled points lie); this saves a fifth of
    // the headset's shadow rays there. corners() lists a cell's nodes in
    // the order (0, 0), (1, 0), (0, 1), (1, 1): the first out of place is
    // the missing one.
    int missing = 0;
    while (missing < 3 && corners[missing].node == grid->node(cell.i + missing % 2, cell.j + missing / 2)) ++missing;
    const double u = missing % 2 ? cell.tx : 1 - cell.tx, v = missing / 2 ? cell.ty : 1 - cell.ty;
    if (u + v > 1) return {};
  }
  const std::vector<std::uint64_t>& nodes = grid == &grid_->coarse() ? coarse_ : fine_;
  std::uint64_t all = ~std::uint64_t{0}, any = 0;
  for (int i = 0; i < count; ++i) {
    const ScreenGrid::Corner& c = corners[i];
    all &= nodes[c.node];
    any |= nodes[c.node];
  }
  const std::uint64_t mask = lights_ == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << lights_) - 1;
  // Agreed: lit at all of them (all) or at none (~any).
  return {(all | ~any) & mask, all & mask};
}

}  // namespace purkinje::renderer
