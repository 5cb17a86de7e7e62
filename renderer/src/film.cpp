#include "film.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace purkinje::renderer {
namespace {

// Adaptive sampling (RenderOptions::edge_samples_per_pixel, see
// Film::refinement): a pixel whose radiance bends by more than kEdgeContrast of
// its local level is refined; by more than kStrongEdgeContrast (a lit
// surface against a dark one, as at the lids' margins), it gets all the
// edge rays, which there still leave the most error per pixel; outlines
// and weaker bends get half of them, and the iris's texture a third: its
// error is the iris caches' interpolation more than its sampling
// (headset, iris pixels: 1.9% of the iris's mean at 4 rays, 1.4% at 24).
constexpr double kEdgeContrast = 0.02;
constexpr double kStrongEdgeContrast = 0.5;

std::vector<std::vector<float>>& kept_planes() {
  thread_local std::vector<std::vector<float>> planes;
  return planes;
}

}  // namespace

PlanePool::PlanePool(int width, int height) : width_(width), height_(height) {
  for (std::vector<float>& v : kept_planes()) spare_.push_back(std::move(v));
  kept_planes().clear();
}

PlanePool::~PlanePool() {
  std::size_t bytes = 0;
  for (std::vector<float>& v : spare_) {
    bytes += v.capacity() * sizeof(float);
    if (bytes > kKeptScratchBytes) break;
    kept_planes().push_back(std::move(v));
  }
}

ImagePlane PlanePool::take() {
  ImagePlane plane;
  plane.width = width_;
  plane.height = height_;
  if (!spare_.empty()) {
    plane.values = std::move(spare_.back());
    spare_.pop_back();
  }
  plane.values.assign(static_cast<std::size_t>(width_) * height_, 0.0f);
  return plane;
}

void PlanePool::give(ImagePlane& plane) {
  if (plane.values.capacity() > 0) spare_.push_back(std::move(plane.values));
  plane = {};
}

Film::Film(PlanePool& pool) {
  radiance_ = pool.take();
  diffuse_electrons_ = pool.take();
  depth_ = pool.take(), nx_ = pool.take(), ny_ = pool.take(), nz_ = pool.take();
  id_ = pool.take();
  for (ImagePlane& c : coverage_) c = pool.take();
  cornea_ = pool.take();
}

void Film::store(int x, int y, const Contribution& sum, int samples, double vignetting, const PrimaryRecord& r,
                 const std::array<int, kClasses>& counts, int cornea_hits) {
  radiance_.at(x, y) = static_cast<float>(sum.radiance / samples);
  diffuse_electrons_.at(x, y) = static_cast<float>(sum.electrons / samples * vignetting);
  id_.at(x, y) = static_cast<float>(static_cast<int>(r.pixel_class));
  depth_.at(x, y) = r.hit ? static_cast<float>(r.depth_mm) : 0.0f;
  nx_.at(x, y) = static_cast<float>(r.normal.x);
  ny_.at(x, y) = static_cast<float>(r.normal.y);
  nz_.at(x, y) = static_cast<float>(r.normal.z);
  for (int c = 0; c < kClasses; ++c) coverage_[c].at(x, y) = static_cast<float>(counts[c]) / samples;
  cornea_.at(x, y) = static_cast<float>(cornea_hits) / samples;
}

Film::Centre Film::centre(int x, int y, double vignetting) const {
  Centre c;
  c.record.pixel_class = pixel_class(x, y);
  c.record.depth_mm = depth_.at(x, y);
  c.record.hit = c.record.pixel_class != PixelClass::background;
  c.record.normal = {nx_.at(x, y), ny_.at(x, y), nz_.at(x, y)};
  c.through_cornea = cornea_.at(x, y) > 0;
  c.sum.radiance = radiance_.at(x, y);
  c.sum.electrons = diffuse_electrons_.at(x, y) / vignetting;
  return c;
}

void Film::clear(int x, int y) {
  for (ImagePlane* plane : {&radiance_, &diffuse_electrons_, &depth_, &nx_, &ny_, &nz_, &id_, &cornea_}) {
    plane->at(x, y) = 0;
  }
  for (ImagePlane& c : coverage_) c.at(x, y) = 0;
}

// The pixels of `region` whose first pass undersamples them: where the
// class changes (an outline), samples disagree on it, or the radiance
// bends by more than kEdgeContrast of its local level (texture, shadow
// edges; strong edges beyond kStrongEdgeContrast). The second difference
// is zero on a gradient, which a lone centre sample gets right, so smooth
// skin is left alone. Neighbours come from `traced`, the region and a
// margin of one pixel, so that a region is decided as in the whole image.
std::vector<Refine> Film::refinement(const PixelRegion& region, const PixelRegion& traced) const {
  const ImagePlane& radiance = radiance_;
  const ImagePlane& id = id_;
  const std::array<ImagePlane, kClasses>& coverage = coverage_;
  const auto inside = [&](int u, int v) { return u >= traced.x0 && v >= traced.y0 && u < traced.x1 && v < traced.y1; };
  std::vector<Refine> edges(radiance.values.size(), Refine::no);
  for (int y = region.y0; y < region.y1; ++y) {
    for (int x = region.x0; x < region.x1; ++x) {
      bool outline = coverage[static_cast<int>(id.at(x, y))].at(x, y) < 1.0f;
      double bend = 0;  // the largest second difference, over the local level
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (!inside(x + dx, y + dy)) continue;
          if (id.at(x + dx, y + dy) != id.at(x, y)) outline = true;
          if (!inside(x - dx, y - dy)) continue;
          const double a = radiance.at(x + dx, y + dy), b = radiance.at(x, y), d = radiance.at(x - dx, y - dy);
          const double level = (a + b + d) / 3;
          if (level > 0) bend = std::max(bend, std::abs(a - 2 * b + d) / level);
        }
      }
      edges[static_cast<std::size_t>(y) * radiance.width + x] = bend > kStrongEdgeContrast ? Refine::strong_edge
                                                                : outline                   ? Refine::outline
                                                                : bend > kEdgeContrast      ? Refine::texture
                                                                                            : Refine::no;
    }
  }
  return edges;
}

void Film::add_aovs(std::vector<NamedPlane>& aovs, PlanePool& pool, bool lashes, bool brows) {
  pool.give(coverage_[0]);  // the background's: only adaptive sampling needed it
  aovs.push_back({"depth", std::move(depth_)});
  aovs.push_back({"N.x", std::move(nx_)});
  aovs.push_back({"N.y", std::move(ny_)});
  aovs.push_back({"N.z", std::move(nz_)});
  aovs.push_back({"id", std::move(id_)});
  aovs.push_back({"skin", std::move(coverage_[1])});
  aovs.push_back({"sclera", std::move(coverage_[2])});
  aovs.push_back({"iris", std::move(coverage_[3])});
  aovs.push_back({"pupil", std::move(coverage_[4])});
  // A class of hairs only in images of scenes that have them.
  for (const auto& [name, c, present] : {std::tuple{"lash", 5, lashes}, std::tuple{"brow", 6, brows}}) {
    if (present) {
      aovs.push_back({name, std::move(coverage_[c])});
    } else {
      pool.give(coverage_[c]);
    }
  }
  aovs.push_back({"cornea", std::move(cornea_)});
}

}  // namespace purkinje::renderer
