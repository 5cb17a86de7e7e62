#pragma once
// Glint detection on grey camera images: real ones or rendered ones alike
// (trackers/ never depends on renderer/). Pixel centres sit at integer
// coordinates, (0, 0) the top-left pixel's centre, as in every purkinje
// label and as in OpenCV.

#include <opencv2/core/mat.hpp>

#include <vector>

#include "purkinje/models/camera.h"

namespace purkinje::trackers {

// A glint as found in an image.
struct Glint {
  Pixel centre;              // sub-pixel
  double energy_dn = 0;      // summed brightness above the local background
  double peak_dn = 0;        // the brightest pixel above the local background
  int area_px = 0;           // pixels above the detection threshold
  bool saturated = false;    // some pixel at the image's largest value
  int illuminator = -1;      // which light made it, once matched (-1: not matched)
};

// A glint detector (strategy): the detectors of purkinje and of users are
// scored alike (see scoring).
class GlintDetector {
 public:
  virtual ~GlintDetector() = default;
  // Glints in a single-channel 8- or 16-bit image, brightest (by energy)
  // first. Throws std::invalid_argument for any other image.
  virtual std::vector<Glint> detect(const cv::Mat& image) const = 0;
};

// Glints as small bright blobs above the local background: a white
// top-hat (the image minus its opening by a disc larger than any glint)
// leaves what is small and bright; blobs above a threshold that stand out
// from all around them are glints, and each one's centre is the centroid
// of its top-hat brightness (less the level around it) over a disc about
// the centre, found again twice: a disc cuts a symmetric spot's tails
// evenly. A saturated glint's clipped plateau is symmetric only on an
// even background; on an edge (the pupil's) its brighter side reaches
// farther, so a saturated glint's centre comes from a fit of a
// pixel-integrated Gaussian to its unclipped flanks above the background
// (a clipped pixel only bounds it from below).
struct BlobGlintSettings {
  int background_radius_px = 6;   // the opening's disc: glints are narrower than its diameter
  // Blobs are what stands above the local background by more than both:
  double threshold = 0.12;        // this fraction of the image's full scale,
  double relative_threshold = 0.25;  // and this fraction of the brightest blob's peak (iris texture is
                                    // bright at close range, but far less so than glints)
  int min_area_px = 1;
  int max_area_px = 400;          // larger bright regions are not glints (specular skin, glasses)
  int centroid_margin_px = 1;     // the centroid's disc reaches this far beyond the blob's radius
};

class BlobGlintDetector final : public GlintDetector {
 public:
  explicit BlobGlintDetector(const BlobGlintSettings& settings = {});
  std::vector<Glint> detect(const cv::Mat& image) const override;

 private:
  BlobGlintSettings settings_;
};

}  // namespace purkinje::trackers
