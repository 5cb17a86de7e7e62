#pragma once
// Scoring a tracker's detections against an image set's labels: purkinje's
// detectors and any other tracker's alike (`purkinje track`, `purkinje
// score`; docs/trackers.md, "Scoring").
//
// Per image, detections are paired with labels nearest first within
// `match_radius_px`: a glint with a glint the camera sees on the cornea
// (status ok), a pupil with a pupil the camera sees some of (a fitted
// ellipse and at least one border point not hidden). A detection left
// over is a false positive, unless it lies within the radius of a glint
// the labels say is there but not counted (on the sclera, or under a
// lid's edge) or of a wholly hidden pupil: then it is left out of the
// score. A label left over is a miss. A false glint by a distractor the
// labels list (a scleral highlight the camera sees) stays false, and is
// told apart.

#include <optional>
#include <string>
#include <vector>

#include "purkinje/models/truth.h"
#include "purkinje/trackers/glints.h"

namespace purkinje::trackers {

// A pupil as a tracker reports it: its centre, and its outline and
// confidence when the tracker gives them.
struct PupilFound {
  Pixel centre;
  std::optional<Ellipse> ellipse;
  std::optional<double> confidence;
};

// What a tracker found in one image.
struct Detections {
  std::vector<Glint> glints;  // centre, and the light when the tracker tells it (illuminator -1: not told)
  std::vector<PupilFound> pupils;
};

// What a perfect tracker would find: the labels' glints the camera sees on
// the cornea, each told its light, and the ellipse of each pupil the
// camera sees some of, with confidence 1. Calibration from exact features
// starts here.
Detections exact_detections(const std::vector<EyeInCameraTruth>& views);

struct ScoringSettings {
  double match_radius_px = 5;  // the field's usual figure; in (0, 1000]
  // A pupil whose tracker gives its ellipse is found only when that
  // ellipse overlaps the label's by at least this much (intersection over
  // union): an ellipse fitted to the iris, concentric with the pupil,
  // overlaps a 2 mm pupil's by about 0.1. In [0, 1]; 0: centres only.
  double min_pupil_overlap = 0.5;
  // Features the tracker reports at all: a pupil-only tracker's glints
  // are not scored as missed (the table says they were not reported).
  bool score_glints = true, score_pupils = true;
};

enum class Feature { glint, pupil };
enum class Outcome {
  found,           // paired with a label within the radius
  missed,          // a label no detection was paired with
  false_positive,  // a detection no label was paired with
  not_counted,     // a detection by a label the score leaves out
  wrong_shape,     // a pupil detection by a label whose ellipse overlaps it too little (the label: missed)
};
const char* to_string(Feature f);
const char* to_string(Outcome o);

// One label or detection of one image, and how it fared.
struct FeatureScore {
  std::string image;
  Feature feature = Feature::glint;
  int eye = -1;          // the label's (-1: none)
  int illuminator = -1;  // a glint label's light (-1: none)
  std::optional<Pixel> label, detection;
  Outcome outcome = Outcome::missed;
  std::optional<double> error_px;  // when found
  std::optional<bool> identity_correct;  // a found glint whose light the tracker told
  // A label's: the distance to the nearest detection of its feature in its
  // image whatever the radius; absent when there is none.
  std::optional<double> nearest_px;
  // A pupil detection with an ellipse, paired by its centre: overlap with
  // the label's ellipse (intersection over union), the larger error of the
  // two semi-axes, and the angle's error (0 to 90 deg; absent for a label
  // within 5% of a circle, whose angle means nothing).
  std::optional<double> overlap, axes_error_px, angle_error_deg;
  // A false glint within the radius of a distractor the labels list as
  // seen (a scleral highlight): what fooled the detector.
  bool on_distractor = false;
};

struct ErrorStatistics {
  int count = 0;
  double mean = 0, median = 0, p95 = 0, max = 0;  // 0 when count is 0
};

// Over every label, misses included: the distance to the nearest detection
// of its kind in its image, however far, and infinite where the image has
// none. A tracker that often fails cannot look precise here.
struct NearestStatistics {
  int count = 0;  // labels
  int none = 0;   // labels in images without a detection of their kind
  double median = 0, p95 = 0, max = 0;  // infinite where the share of `none` reaches them
};

struct FeatureSummary {
  int labelled = 0;  // labels counted
  int detected = 0;  // detections made, counted or not
  int found = 0, within_1px = 0, within_2px = 0, within_5px = 0;
  int false_positives = 0, not_counted = 0;
  int false_positives_on_distractors = 0;  // glints: of the false positives, those on a labelled distractor
  int wrong_shape = 0;                  // pupils: paired by centre, outline not the label's
  ErrorStatistics error_px;             // over the found
  NearestStatistics nearest_px;         // over all labels
  ErrorStatistics overlap;              // pupils with an ellipse, paired by centre: intersection over union
  int identity_told = 0, identity_correct = 0;  // glints only
  // Fractions, 0 when there is nothing to divide by.
  double rate_within(int px) const;     // 1, 2 or 5 px: of the labelled
  double false_positive_rate() const;   // of the counted detections
  double identity_rate() const;         // correct among the found
};

struct Score {
  int images = 0;
  ScoringSettings settings;
  std::vector<FeatureScore> features;  // in the order the images were added
  FeatureSummary glints, pupils;
};

class Scorer {
 public:
  // Throws std::invalid_argument for settings out of range.
  explicit Scorer(const ScoringSettings& settings = {});
  // One image: its labels' views (this camera's eyes) and what was found.
  void add(const std::string& image, const std::vector<EyeInCameraTruth>& views, const Detections& found);
  // The score so far, with its error statistics.
  Score score() const;

 private:
  Score score_;
};

// The images that fared worst, worst first, at most n: most misses and
// false positives, then the largest error.
std::vector<std::string> worst_images(const Score& score, int n);

// The score as a text table (with the settings), as CSV (one row per label
// and detection; docs/trackers.md lists the columns) and as JSON (the
// summaries). Every number is finite; what does not exist is empty or null.
std::string score_table(const Score& score);
std::string score_csv(const Score& score);
std::string score_json(const Score& score);

}  // namespace purkinje::trackers
