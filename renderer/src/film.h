#pragma once
// The film (internal to renderer/): the image planes one render fills and
// the memory they reuse. The driver stores each pixel's samples here; the
// film keeps the radiance, the diffuse light's electrons, and the AOVs
// (depth, normal, class id, per-class and cornea coverage), tells the
// adaptive pass which pixels to refine, and hands its planes over as the
// result's named AOVs.

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "materials.h"
#include "purkinje/renderer/image.h"
#include "purkinje/renderer/render.h"

namespace purkinje::renderer {

// Image memory to reuse: fresh memory costs a page fault per 4 KB when
// first written, a tenth of a remote render. A render takes its planes
// from the previous result's and from what this thread's earlier renders
// left (their scratch planes), and leaves its own scratch planes for the
// next; never more than kKeptScratchBytes per thread.
class PlanePool {
 public:
  PlanePool(int width, int height);
  ~PlanePool();
  PlanePool(const PlanePool&) = delete;
  PlanePool& operator=(const PlanePool&) = delete;

  // A plane of zeros of the image's size.
  ImagePlane take();
  void give(ImagePlane& plane);

 private:
  static constexpr std::size_t kKeptScratchBytes = std::size_t{64} << 20;
  int width_, height_;
  std::vector<std::vector<float>> spare_;
};

// Why refinement() refines a pixel.
enum class Refine : std::uint8_t { no = 0, texture, outline, strong_edge };

// The segmentation's classes: background, skin, sclera, iris, pupil, lash, brow.
constexpr int kClasses = 7;

class Film {
 public:
  explicit Film(PlanePool& pool);

  // A pixel's planes from its samples' sum (`vignetting` scales the
  // electrons), the record of the class most of them saw, and how many saw
  // each class and the cornea.
  void store(int x, int y, const Contribution& sum, int samples, double vignetting, const PrimaryRecord& record,
             const std::array<int, kClasses>& counts, int cornea_hits);
  // What a lone centre sample stored at (x, y) said, read back so that a
  // refined pixel keeps it as one of its samples.
  struct Centre {
    Contribution sum;
    PrimaryRecord record;
    bool through_cornea = false;
  };
  Centre centre(int x, int y, double vignetting) const;
  PixelClass pixel_class(int x, int y) const { return static_cast<PixelClass>(id_.at(x, y)); }
  // Back to zero (a traced margin outside the rendered region).
  void clear(int x, int y);

  // The pixels of `region` its first pass undersamples, and why; the
  // neighbours come from `traced` (the region and a margin of one pixel).
  std::vector<Refine> refinement(const PixelRegion& region, const PixelRegion& traced) const;

  // The planes, handed over once the pixels are done: the radiance, the
  // diffuse electrons (before the optics), and the AOVs in their order
  // (depth, N.x, N.y, N.z, id, skin, sclera, iris, pupil, lash if
  // `lashes`, brow if `brows`, cornea), the background's coverage (and the
  // lashes' and brows' without them) going back to the pool.
  ImagePlane take_radiance() { return std::move(radiance_); }
  // The fraction of each pixel's samples that saw a class first.
  const ImagePlane& coverage(PixelClass c) const { return coverage_[static_cast<int>(c)]; }
  ImagePlane& diffuse_electrons() { return diffuse_electrons_; }
  void add_aovs(std::vector<NamedPlane>& aovs, PlanePool& pool, bool lashes, bool brows);

 private:
  ImagePlane radiance_, diffuse_electrons_, depth_, nx_, ny_, nz_, id_;
  std::array<ImagePlane, kClasses> coverage_;
  ImagePlane cornea_;
};

}  // namespace purkinje::renderer
