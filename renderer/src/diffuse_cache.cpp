#include "diffuse_cache.h"

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

}  // namespace

DiffuseCache::DiffuseCache(const Camera& camera, const PixelRegion& region, int spacing_px,
                           std::size_t lights, const FindPoint& find, const Gather& gather)
    : spacing_(spacing_px), lights_(lights) {
  const Intrinsics& k = camera.intrinsics();
  pixel_angle_ = 1.0 / std::max(k.fx, k.fy);
  const auto first = [&](int a) { return a / spacing_; };  // a >= 0
  const auto last = [&](int b) { return (b - 1 + spacing_ - 1) / spacing_; };
  i0_ = first(region.x0);
  j0_ = first(region.y0);
  nx_ = last(region.x1) - i0_ + 1;
  ny_ = last(region.y1) - j0_ + 1;
  const std::size_t count = static_cast<std::size_t>(nx_) * ny_;
  points_.resize(count);
  irradiance_.assign(count * lights_, 0.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t n = r.begin(); n < r.end(); ++n) {
      const int i = static_cast<int>(n % nx_), j = static_cast<int>(n / nx_);
      const int u = (i0_ + i) * spacing_, v = (j0_ + j) * spacing_;
      points_[n] = find({double(u), double(v)});
      if (points_[n].surface == Surface::none) continue;
      // Random numbers keyed by the node's place in the whole image.
      const std::size_t key = static_cast<std::size_t>(v) * k.width + u;
      gather(points_[n], key, &irradiance_[n * lights_]);
    }
  });
}

bool DiffuseCache::irradiance(const Pixel& image_position, const DiffusePoint& p, double* e) const {
  const double fx = std::clamp(image_position.u / spacing_ - i0_, 0.0, nx_ - 1.0);
  const double fy = std::clamp(image_position.v / spacing_ - j0_, 0.0, ny_ - 1.0);
  const int ia = std::min(static_cast<int>(fx), std::max(nx_ - 2, 0));
  const int ja = std::min(static_cast<int>(fy), std::max(ny_ - 2, 0));
  const double tx = fx - ia, ty = fy - ja;
  std::fill(e, e + lights_, 0.0);
  double total = 0;
  for (int dj = 0; dj < 2; ++dj) {
    for (int di = 0; di < 2; ++di) {
      const int i = ia + di, j = ja + dj;
      if (i >= nx_ || j >= ny_) continue;
      const std::size_t n = static_cast<std::size_t>(j) * nx_ + i;
      const DiffusePoint& q = points_[n];
      if (q.surface != p.surface || q.owner != p.owner) continue;
      if (dot(q.normal, p.normal) < kMinNormalCos) continue;
      const double reach = kReachSpacings * spacing_ * q.path_mm * pixel_angle_ / std::max(q.cos_view, kMinCosView);
      const double d2 = (q.point - p.point).squared_norm() / (reach * reach);
      if (d2 >= 1) continue;
      const double w = (di ? tx : 1 - tx) * (dj ? ty : 1 - ty) * (1 - d2) + 1e-12;
      total += w;
      for (std::size_t l = 0; l < lights_; ++l) e[l] += w * irradiance_[n * lights_ + l];
    }
  }
  if (total <= 0) return false;
  for (std::size_t l = 0; l < lights_; ++l) e[l] /= total;
  return true;
}

}  // namespace purkinje::renderer
