#pragma once
// Pupil detection on grey camera images, real or rendered (trackers/ never
// depends on renderer/). Pixel centres sit at integer coordinates, as in
// every purkinje label.

#include <optional>
#include <span>

#include "purkinje/models/truth.h"
#include "purkinje/trackers/glints.h"
#include "purkinje/trackers/image.h"

namespace purkinje::trackers {

// A pupil as found in an image: its outline, and how much of that outline
// the image's edges support.
struct PupilDetection {
  Ellipse ellipse;        // semi-axis 1 is the major one
  double confidence = 0;  // in [0, 1]: the share of the outline's sectors with edge points on the ellipse
};

// A pupil detector (strategy): purkinje's detectors and users' are scored
// alike.
class PupilDetector {
 public:
  virtual ~PupilDetector() = default;
  // The dark pupil in an image, or nullopt when none is found. `glints`
  // are those found in the same image (may be empty); a detector may mask
  // them out, since their edges are not the pupil's. Throws
  // std::invalid_argument for an image it cannot read, naming the rule.
  virtual std::optional<PupilDetection> detect(const GreyView& image, std::span<const Glint> glints) const = 0;
};

// Coarse to fine, after Swirski, Bulling and Dodgson (2012) and Starburst
// (Li, Winfield and Parkhurst 2005):
//  1. on the image shrunk so that the smallest pupil is still 3 pixels
//     wide, with glints opened away: the darkest regions (within a small
//     step of the darkest level, above the noise) that do not touch the
//     image's border, each one's deepest point and the largest disc about
//     it, widest first;
//  2. from each such point, rays outward; on each, from where it is dark,
//     the first rise to halfway between the pupil's level and the iris's
//     (the level most rays reach), located to a fraction of a pixel where
//     the profile crosses halfway between its two sides (a symmetric blur
//     moves neither), and dropped where a glint lies on it or where it
//     rises to far brighter than the iris (a lid's skin);
//  3. RANSAC ellipses through five of those edge points, the one most
//     points lie on, then a least-squares ellipse through those points;
//  4. rays cast again from that ellipse's centre, and steps 2 and 3 again.
// The confidence is the share of 32 sectors about the ellipse's centre
// that hold an edge point on it: about the share of the outline that no
// lid or glint hides. Of the candidates, the widest well-outlined one wins
// (confidence times the square root of the minor semi-axis): the shadows
// in the eye's corners and along the lids can be as well outlined as the
// pupil, but are narrow.
struct StarburstPupilSettings {
  double min_radius_px = 3;    // the pupil's semi-axes lie in [min, max]
  double max_radius_px = 80;
  int candidates = 3;          // dark regions tried, widest first
  int rays = 64;               // at least 32
  int ransac_iterations = 100;
  double inlier_px = 0.75;     // an edge point this close to the ellipse lies on it
  double min_axis_ratio = 0.25;   // minor / major: a pupil seen up to 75 deg off its axis
  double min_contrast = 0.01;  // of full scale: the pupil is at least this much darker than the iris
  double min_confidence = 0.3;
  double glint_margin_px = 1.5;   // beyond a glint's radius, where its light still spoils an edge
};

class StarburstPupilDetector final : public PupilDetector {
 public:
  // Throws std::invalid_argument for settings out of range, naming the
  // field, its value and the rule.
  explicit StarburstPupilDetector(const StarburstPupilSettings& settings = {});
  std::optional<PupilDetection> detect(const GreyView& image, std::span<const Glint> glints) const override;

 private:
  StarburstPupilSettings settings_;
};

}  // namespace purkinje::trackers
