#pragma once
// Glint detection on grey camera images: real ones or rendered ones alike
// (trackers/ never depends on renderer/). Pixel centres sit at integer
// coordinates, (0, 0) the top-left pixel's centre, as in every purkinje
// label and as in OpenCV.

#include <optional>
#include <vector>

#include "purkinje/models/camera.h"
#include "purkinje/models/eye.h"
#include "purkinje/models/illuminator.h"
#include "purkinje/trackers/image.h"

namespace purkinje::trackers {

// A glint as found in an image.
struct Glint {
  Pixel centre;              // sub-pixel
  double energy_dn = 0;      // summed brightness above the local background
  double peak_dn = 0;        // the brightest pixel above the local background
  int area_px = 0;           // pixels above the detection threshold
  bool saturated = false;    // some pixel at the image's largest value
  int illuminator = -1;      // which light made it, once matched (-1: not matched)
  // The centre's standard deviation along u and v, px, where the detector
  // estimates it (a saturated glint's spot fit: the pixels' noise and the
  // unseen background under the spot); 0: not estimated.
  double centre_sd_u_px = 0, centre_sd_v_px = 0;
};

// A glint detector (strategy): the detectors of purkinje and of users are
// scored alike (see scoring).
class GlintDetector {
 public:
  virtual ~GlintDetector() = default;
  // Glints in an image, brightest (by energy) first. Throws
  // std::invalid_argument for an image it cannot read, naming the rule.
  virtual std::vector<Glint> detect(const GreyView& image) const = 0;
};

// Glints as small bright blobs above the local background: a white
// top-hat (the image minus its opening by a square wider than any glint)
// leaves what is small and bright; blobs above a threshold that stand out
// from all around them are glints, and each one's centre is the centroid
// of its top-hat brightness (less the level around it) over a disc about
// the centre, found again twice: a disc cuts a symmetric spot's tails
// evenly. A saturated glint's clipped plateau is symmetric only on an
// even background; on an edge (the pupil's) its brighter side reaches
// farther, so a saturated glint's centre comes from a fit of a
// pixel-integrated Gaussian to its unclipped flanks above the background
// (a clipped pixel only bounds it from below). The background under the
// spot is unseen: each pixel's is the median of the nearest pixels seen
// around it, which on the pupil's edge lie on its own side, and two such
// estimates (from just outside the spot's core, and from beyond its
// flank) bracket it; the centre is the mean of the two fits, and their
// difference enters the centre's standard deviation. All saturated
// glints of a frame share one width (the camera's point spread).
struct BlobGlintSettings {
  int background_radius_px = 6;   // the opening's square is 2r + 1 wide: glints are narrower
  // Blobs are what stands above the local background by more than both:
  double threshold = 0.12;        // this fraction of the image's full scale,
  double relative_threshold = 0.25;  // and this fraction of the brightest blob's peak (iris texture is
                                    // bright at close range, but far less so than glints)
  int min_area_px = 1;
  int max_area_px = 400;          // larger bright regions are not glints (specular skin, glasses)
  int centroid_margin_px = 1;     // the centroid's disc reaches this far beyond the blob's radius
  // A lone bright pixel (a hot pixel) is no glint: optics spread a point
  // over its neighbours. A blob none of whose local maxima has four
  // neighbours holding together this fraction of its height above the
  // background (the median of the ring two pixels out; a neighbour below
  // it counts as none) is dropped. A pixel-integrated Gaussian spot centred on a pixel gives
  // them 0.21 of it at sigma 0.3 px, 0.92 at 0.5 px (the bundled
  // cameras'); 0.1 is sigma 0.25 px. 0: keep all; at most 4.
  double min_neighbour_share = 0.1;
  // A saturated glint's spot: the Gaussian's standard deviation in px (the
  // camera's point spread, when the tracker knows it), or 0: the median of
  // the frame's saturated glints' own fits. 0 or in [0.1, 10].
  double spot_sigma_px = 0;
  // The sensor's noise, in electrons: with the scatter of the background
  // seen around it (less that background's own noise: the texture
  // beneath), what weighs each pixel in a saturated glint's spot fit, and
  // so the centre's standard deviation. A pixel of v DN holds
  // v x full_scale_e / (2^bits - 1) electrons: its shot noise, the read
  // noise and the rounding's 1/12 DN^2. The defaults are the bundled
  // sensors' (a 10000 e- full well at unit gain, 4 e- read noise).
  double full_scale_e = 10000;  // electrons at the image's largest value (full well / gain), > 0
  double read_noise_e = 4;      // RMS, >= 0
};

// The settings for images from `camera` of an eye whose cornea is near
// `nominal_cornea`, for a tracker that knows its camera: the sensor's
// noise (which weighs a saturated glint's pixels), and the spot's width
// when it is the camera's point spread wherever the eye is (no defocus at
// that depth, point lights); else the detector estimates the width from
// each frame. The other settings are the defaults.
BlobGlintSettings glint_settings_for(const Camera& camera, const std::vector<Illuminator>& lights,
                                     const Point3& nominal_cornea);

class BlobGlintDetector final : public GlintDetector {
 public:
  explicit BlobGlintDetector(const BlobGlintSettings& settings = {});
  std::vector<Glint> detect(const GreyView& image) const override;

 private:
  BlobGlintSettings settings_;
};

// Which light made which glint. The glints of a set of lights form a
// pattern that moves, scales and turns a little with the eye; `expected`
// holds, per light, where its glint would be on a nominal eye (see
// nominal_glint_layout; nullopt: the light has none there). The similarity transform of that pattern (scale
// within [1 / max_scale, max_scale], rotation within max_rotation_rad)
// that brings the most expected glints near detected ones wins, and each
// expected glint takes the nearest detection within the gate: a fraction
// of the smallest distance between two transformed expected glints, so
// that neighbours are never confused. Glints left over (spurious ones)
// keep illuminator -1, and so do all when fewer than two expected glints
// are found (the pattern is then not pinned down) or two lights share a
// place. Among transforms that bring as many, the one whose glints sit
// closest, scaled and turned least, wins: with two lights every pair of
// detections fits exactly, and only that prior tells them apart. Only the
// 2n + 4 brightest detections of n lights are tried (detect() orders them
// so); the search costs (2n + 4)^2 n^3 distance checks, 3.4 million for
// n = 8. Throws std::invalid_argument for settings out of range.
struct GlintMatchSettings {
  double max_scale = 2.0;          // >= 1
  double max_rotation_rad = 0.35;  // in [0, pi]; under half the angle between neighbours of a ring of 8
  double gate_fraction = 0.35;     // in (0, 0.5): below half, no detection is near two expected glints
};
void identify_glints(std::vector<Glint>& glints, const std::vector<std::optional<Pixel>>& expected,
                     const GlintMatchSettings& settings = {});

// Where each light's glint is on `nominal_eye` seen by `camera`, from the
// specular-path solver; a light without a glint on that eye's cornea gets
// no place (nullopt) and is never matched.
std::vector<std::optional<Pixel>> nominal_glint_layout(const Camera& camera,
                                                       const std::vector<Illuminator>& lights,
                                                       const Eye& nominal_eye);

}  // namespace purkinje::trackers
