#include "purkinje/trackers/scoring.h"
#include "purkinje/models/check.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <numbers>
#include <optional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "purkinje/models/csv.h"

namespace purkinje::trackers {

const char* to_string(Feature f) { return f == Feature::glint ? "glint" : "pupil"; }

const char* to_string(Outcome o) {
  switch (o) {
    case Outcome::found: return "found";
    case Outcome::missed: return "missed";
    case Outcome::false_positive: return "false_positive";
    case Outcome::not_counted: return "not_counted";
    case Outcome::wrong_shape: return "wrong_shape";
  }
  return "unknown";
}

namespace {

double distance(const Pixel& a, const Pixel& b) { return std::hypot(a.u - b.u, a.v - b.v); }

// A pupil the camera sees some of: a border point not hidden.
bool seen(const PupilTruth& pupil) {
  return std::any_of(pupil.border.begin(), pupil.border.end(),
                     [](const PupilBorderPointTruth& b) { return b.status == PathStatus::ok; });
}

struct Label {
  Pixel pixel;
  int eye = -1, illuminator = -1;
  bool counted = true;  // false: there, but left out of the score
  std::optional<Ellipse> outline;  // a pupil's
};

bool inside(const Ellipse& e, double u, double v) {
  const double du = u - e.center.u, dv = v - e.center.v;
  const double c = std::cos(e.angle_rad), s = std::sin(e.angle_rad);
  const double x = (du * c + dv * s) / e.semi_axis_1_px, y = (-du * s + dv * c) / e.semi_axis_2_px;
  return x * x + y * y <= 1;
}

// Intersection over union of two ellipses, counted on a grid over the box
// that holds both, at least 16 cells across the smallest semi-axis (up to
// 1024 x 1024): within about 1% of the exact figure, whatever the shapes.
double overlap(const Ellipse& a, const Ellipse& b) {
  const double ra = std::max(a.semi_axis_1_px, a.semi_axis_2_px), rb = std::max(b.semi_axis_1_px, b.semi_axis_2_px);
  const double u0 = std::min(a.center.u - ra, b.center.u - rb), u1 = std::max(a.center.u + ra, b.center.u + rb);
  const double v0 = std::min(a.center.v - ra, b.center.v - rb), v1 = std::max(a.center.v + ra, b.center.v + rb);
  const double smallest = std::min({a.semi_axis_1_px, a.semi_axis_2_px, b.semi_axis_1_px, b.semi_axis_2_px});
  const int kCells = std::clamp(static_cast<int>(std::ceil(16 * std::max(u1 - u0, v1 - v0) / smallest)), 128, 1024);
  int both = 0, either = 0;
  for (int j = 0; j < kCells; ++j) {
    const double v = v0 + (j + 0.5) * (v1 - v0) / kCells;
    for (int i = 0; i < kCells; ++i) {
      const double u = u0 + (i + 0.5) * (u1 - u0) / kCells;
      const bool in_a = inside(a, u, v), in_b = inside(b, u, v);
      both += in_a && in_b;
      either += in_a || in_b;
    }
  }
  return either > 0 ? static_cast<double>(both) / either : 0.0;
}

// The found ellipse against the label's: overlap, the larger semi-axis
// error (axes matched by size) and the angle's error where it means
// something (the label more than 5% from a circle).
void compare_outlines(FeatureScore& f, const Ellipse& label, const Ellipse& found) {
  f.overlap = overlap(label, found);
  const double l1 = std::max(label.semi_axis_1_px, label.semi_axis_2_px);
  const double l2 = std::min(label.semi_axis_1_px, label.semi_axis_2_px);
  const double f1 = std::max(found.semi_axis_1_px, found.semi_axis_2_px);
  const double f2 = std::min(found.semi_axis_1_px, found.semi_axis_2_px);
  f.axes_error_px = std::max(std::abs(l1 - f1), std::abs(l2 - f2));
  if (l2 < 0.95 * l1) {
    // The angle of each major axis, modulo 180 deg.
    const auto major = [](const Ellipse& e) {
      return e.semi_axis_1_px >= e.semi_axis_2_px ? e.angle_rad : e.angle_rad + std::numbers::pi / 2;
    };
    double d = std::fmod(std::abs(major(label) - major(found)) * 180 / std::numbers::pi, 180.0);
    f.angle_error_deg = std::min(d, 180 - d);
  }
}

// Pairs detections with labels nearest first within the radius; writes
// each label's and detection's score, and returns for each detection the
// label it was paired with (-1: none).
// `fits(label, detection)`: whether a pair within the radius may pair at
// all (a pupil's outline must overlap the label's): a pair that may not
// leaves both free for the others, so a concentric iris fit cannot take
// the label from the right pupil.
template <class Fits>
std::vector<int> pair_nearest(const std::vector<Label>& labels, const std::vector<Pixel>& detections, double radius,
                              const Fits& fits) {
  struct Pair {
    double distance;
    int label, detection;
  };
  std::vector<Pair> pairs;
  for (int l = 0; l < static_cast<int>(labels.size()); ++l) {
    if (!labels[l].counted) continue;
    for (int d = 0; d < static_cast<int>(detections.size()); ++d) {
      const double r = distance(labels[l].pixel, detections[d]);
      if (r <= radius && fits(l, d)) pairs.push_back({r, l, d});
    }
  }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) {
    return std::tie(a.distance, a.label, a.detection) < std::tie(b.distance, b.label, b.detection);
  });
  std::vector<int> paired(detections.size(), -1);
  std::vector<bool> label_used(labels.size(), false);
  for (const Pair& p : pairs) {
    if (label_used[p.label] || paired[p.detection] >= 0) continue;
    label_used[p.label] = true;
    paired[p.detection] = p.label;
  }
  return paired;
}

void tally(FeatureSummary& s, const FeatureScore& f) {
  switch (f.outcome) {
    case Outcome::found:
      ++s.labelled, ++s.detected, ++s.found;
      s.within_1px += *f.error_px <= 1;
      s.within_2px += *f.error_px <= 2;
      s.within_5px += *f.error_px <= 5;
      if (f.identity_correct) ++s.identity_told, s.identity_correct += *f.identity_correct;
      break;
    case Outcome::missed: ++s.labelled; break;
    case Outcome::false_positive:
      ++s.detected, ++s.false_positives;
      s.false_positives_on_distractors += f.on_distractor;
      break;
    case Outcome::not_counted: ++s.detected, ++s.not_counted; break;
    case Outcome::wrong_shape: ++s.detected, ++s.wrong_shape; break;
  }
}

// Scores one feature of one image: labels (counted or not) against detections.
void score_feature(Score& score, FeatureSummary& summary, const std::string& image, Feature feature,
                   const std::vector<Label>& labels, const std::vector<Pixel>& detections,
                   const std::vector<int>& told_illuminator, const std::vector<std::optional<Ellipse>>& outlines,
                   const std::vector<Pixel>& distractors) {
  // A pupil detection's outline against a label's, when both are known.
  std::vector<std::vector<std::optional<double>>> overlaps(labels.size(),
                                                           std::vector<std::optional<double>>(detections.size()));
  for (std::size_t l = 0; l < labels.size(); ++l) {
    for (std::size_t d = 0; d < detections.size(); ++d) {
      if (labels[l].outline && d < outlines.size() && outlines[d] &&
          distance(labels[l].pixel, detections[d]) <= score.settings.match_radius_px) {
        overlaps[l][d] = overlap(*labels[l].outline, *outlines[d]);
      }
    }
  }
  const auto fits = [&](std::size_t l, std::size_t d) {
    return !overlaps[l][d] || *overlaps[l][d] >= score.settings.min_pupil_overlap;
  };
  const std::vector<int> paired = pair_nearest(labels, detections, score.settings.match_radius_px, fits);
  std::vector<bool> label_found(labels.size(), false);
  // The nearest detection that could be this label's (a wrong outline cannot).
  const auto nearest = [&](std::size_t l) -> std::optional<double> {
    std::optional<double> best;
    for (std::size_t d = 0; d < detections.size(); ++d) {
      if (fits(l, d)) best = std::min(best.value_or(INFINITY), distance(labels[l].pixel, detections[d]));
    }
    return best;
  };
  for (std::size_t d = 0; d < detections.size(); ++d) {
    FeatureScore f;
    f.image = image;
    f.feature = feature;
    f.detection = detections[d];
    if (paired[d] >= 0) {
      const Label& l = labels[paired[d]];
      label_found[paired[d]] = true;
      f.eye = l.eye, f.illuminator = l.illuminator, f.label = l.pixel;
      f.outcome = Outcome::found;
      f.error_px = distance(l.pixel, detections[d]);
      f.nearest_px = nearest(paired[d]);
      if (feature == Feature::glint && told_illuminator[d] >= 0) f.identity_correct = told_illuminator[d] == l.illuminator;
      if (l.outline && d < outlines.size() && outlines[d]) compare_outlines(f, *l.outline, *outlines[d]);
    } else if (const auto wrong = std::find_if(overlaps.begin(), overlaps.end(),
                                               [&](const auto& row) { return row[d] && *row[d] < score.settings.min_pupil_overlap; });
               wrong != overlaps.end()) {
      // Its centre is by a label, its outline is not the label's (an iris
      // fit for a pupil): a wrong detection, and the label stays missed.
      const Label& l = labels[static_cast<std::size_t>(wrong - overlaps.begin())];
      f.eye = l.eye, f.label = l.pixel;
      f.outcome = Outcome::wrong_shape;
      compare_outlines(f, *l.outline, *outlines[d]);
    } else {
      f.outcome = Outcome::false_positive;
      for (const Label& l : labels) {
        if (!l.counted && distance(l.pixel, detections[d]) <= score.settings.match_radius_px) {
          f.outcome = Outcome::not_counted;
          f.eye = l.eye, f.illuminator = l.illuminator, f.label = l.pixel;
          break;
        }
      }
      if (f.outcome == Outcome::false_positive) {
        f.on_distractor = std::any_of(distractors.begin(), distractors.end(), [&](const Pixel& p) {
          return distance(p, detections[d]) <= score.settings.match_radius_px;
        });
      }
    }
    tally(summary, f);
    score.features.push_back(f);
  }
  for (std::size_t l = 0; l < labels.size(); ++l) {
    if (!labels[l].counted || label_found[l]) continue;
    FeatureScore f;
    f.image = image;
    f.feature = feature;
    f.eye = labels[l].eye, f.illuminator = labels[l].illuminator, f.label = labels[l].pixel;
    f.outcome = Outcome::missed;
    f.nearest_px = nearest(l);
    tally(summary, f);
    score.features.push_back(f);
  }
}

ErrorStatistics statistics(std::vector<double> errors) {
  ErrorStatistics s;
  s.count = static_cast<int>(errors.size());
  if (errors.empty()) return s;
  std::sort(errors.begin(), errors.end());
  double sum = 0;
  for (const double e : errors) sum += e;
  s.mean = sum / errors.size();
  const std::size_t n = errors.size();
  s.median = n % 2 ? errors[n / 2] : 0.5 * (errors[n / 2 - 1] + errors[n / 2]);
  // The nearest-rank 95th percentile: at least 95% of the errors are at or below it.
  s.p95 = errors[static_cast<std::size_t>(std::ceil(0.95 * n)) - 1];
  s.max = errors.back();
  return s;
}

NearestStatistics nearest_statistics(std::vector<double> distances) {
  NearestStatistics s;
  s.count = static_cast<int>(distances.size());
  if (distances.empty()) return s;
  std::sort(distances.begin(), distances.end());
  s.none = static_cast<int>(std::count(distances.begin(), distances.end(), INFINITY));
  const std::size_t n = distances.size();
  s.median = n % 2 ? distances[n / 2] : 0.5 * (distances[n / 2 - 1] + distances[n / 2]);
  s.p95 = distances[static_cast<std::size_t>(std::ceil(0.95 * n)) - 1];
  s.max = distances.back();
  return s;
}

void update_statistics(Score& score) {
  std::vector<double> found[2], nearest[2], overlaps;
  for (const FeatureScore& f : score.features) {
    const int k = f.feature == Feature::glint ? 0 : 1;
    if (f.outcome == Outcome::found) found[k].push_back(*f.error_px);
    if (f.outcome == Outcome::found || f.outcome == Outcome::missed) nearest[k].push_back(f.nearest_px.value_or(INFINITY));
    if (f.overlap) overlaps.push_back(*f.overlap);
  }
  score.glints.error_px = statistics(std::move(found[0]));
  score.pupils.error_px = statistics(std::move(found[1]));
  score.glints.nearest_px = nearest_statistics(std::move(nearest[0]));
  score.pupils.nearest_px = nearest_statistics(std::move(nearest[1]));
  score.pupils.overlap = statistics(std::move(overlaps));
}

double fraction(int part, int whole) { return whole > 0 ? static_cast<double>(part) / whole : 0.0; }

}  // namespace

double FeatureSummary::rate_within(int px) const {
  if (px == 1) return fraction(within_1px, labelled);
  if (px == 2) return fraction(within_2px, labelled);
  if (px == 5) return fraction(within_5px, labelled);
  throw std::invalid_argument("FeatureSummary::rate_within: " + std::to_string(px) + " px: must be 1, 2 or 5");
}
double FeatureSummary::false_positive_rate() const {
  return fraction(false_positives + wrong_shape, detected - not_counted);
}
double FeatureSummary::identity_rate() const { return fraction(identity_correct, found); }

Detections exact_detections(const std::vector<EyeInCameraTruth>& views) {
  Detections d;
  for (const EyeInCameraTruth& view : views) {
    for (const GlintTruth& g : view.glints) {
      if (g.status != PathStatus::ok) continue;
      Glint found;
      found.centre = g.pixel;
      found.illuminator = g.illuminator;
      d.glints.push_back(found);
    }
    if (view.pupil.ellipse_valid && seen(view.pupil)) {
      d.pupils.push_back({view.pupil.ellipse.center, view.pupil.ellipse, 1.0});
    }
  }
  return d;
}

Scorer::Scorer(const ScoringSettings& settings) {
  if (!(settings.match_radius_px > 0 && settings.match_radius_px <= 1000)) {
    throw std::invalid_argument("ScoringSettings: match_radius_px = " + check::format_number(settings.match_radius_px) +
                                ": must be in (0, 1000]");
  }
  if (!(settings.min_pupil_overlap >= 0 && settings.min_pupil_overlap <= 1)) {
    throw std::invalid_argument("ScoringSettings: min_pupil_overlap = " + check::format_number(settings.min_pupil_overlap) +
                                ": must be in [0, 1]");
  }
  score_.settings = settings;
}

void Scorer::add(const std::string& image, const std::vector<EyeInCameraTruth>& views, const Detections& found) {
  ++score_.images;
  std::vector<Label> glints, pupils;
  std::vector<Pixel> distractors;
  for (const EyeInCameraTruth& view : views) {
    for (const DistractorTruth& d : view.distractors) {
      if (d.status == PathStatus::ok) distractors.push_back(d.pixel);
    }
    for (const GlintTruth& g : view.glints) {
      // A glint on the sclera or at a lid's edge may show: a detection
      // there is neither right nor wrong.
      const bool counted = g.status == PathStatus::ok;
      if (counted || g.status == PathStatus::off_cornea || g.status == PathStatus::occluded) {
        glints.push_back({g.pixel, view.eye, g.illuminator, counted, std::nullopt});
      }
    }
    if (view.pupil.ellipse_valid) {
      pupils.push_back({view.pupil.ellipse.center, view.eye, -1, seen(view.pupil), view.pupil.ellipse});
    }
  }
  std::vector<Pixel> glint_centres, pupil_centres;
  std::vector<int> told;
  std::vector<std::optional<Ellipse>> outlines;
  for (const Glint& g : found.glints) glint_centres.push_back(g.centre), told.push_back(g.illuminator);
  for (const PupilFound& p : found.pupils) pupil_centres.push_back(p.centre), outlines.push_back(p.ellipse);
  if (score_.settings.score_glints) score_feature(score_, score_.glints, image, Feature::glint, glints, glint_centres, told, {}, distractors);
  if (score_.settings.score_pupils) {
    score_feature(score_, score_.pupils, image, Feature::pupil, pupils, pupil_centres, {}, outlines, {});
  }
}

Score Scorer::score() const {
  Score s = score_;
  update_statistics(s);
  return s;
}

std::vector<std::string> worst_images(const Score& score, int n) {
  struct Badness {
    int wrong = 0;     // misses and false positives
    double worst = 0;  // largest error among the found
  };
  std::map<std::string, Badness> by_image;
  std::vector<std::string> order;
  for (const FeatureScore& f : score.features) {
    auto [it, fresh] = by_image.try_emplace(f.image);
    if (fresh) order.push_back(f.image);
    if (f.outcome == Outcome::missed || f.outcome == Outcome::false_positive || f.outcome == Outcome::wrong_shape) {
      ++it->second.wrong;
    }
    if (f.error_px) it->second.worst = std::max(it->second.worst, *f.error_px);
  }
  std::stable_sort(order.begin(), order.end(), [&](const std::string& a, const std::string& b) {
    const Badness &x = by_image.at(a), &y = by_image.at(b);
    return std::tie(x.wrong, x.worst) > std::tie(y.wrong, y.worst);
  });
  if (static_cast<int>(order.size()) > n) order.resize(std::max(0, n));
  return order;
}

namespace {

std::string fixed(double x, int digits = 3) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << x;
  return s.str();
}

}  // namespace

std::string score_table(const Score& score) {
  std::ostringstream out;
  out << score.images << " images; a detection within " << fixed(score.settings.match_radius_px, 1)
      << " px of a label is paired with it";
  if (score.settings.min_pupil_overlap > 0) {
    out << "; a pupil's ellipse, when given, must overlap the label's by " << fixed(score.settings.min_pupil_overlap, 2);
  }
  out << "\n\n";
  out << "feature  labelled  detected  within 1 px  2 px    5 px    false pos.  error px: mean   median  p95     max"
         "     identity\n";
  const auto row = [&](const char* name, const FeatureSummary& s, bool reported, bool identity) {
    out << std::left << std::setw(9) << name << std::right;
    if (!reported) {
      out << "   not in the detections file: not scored\n";
      return;
    }
    out << std::setw(8) << s.labelled << std::setw(10)
        << s.detected << std::setw(13) << fixed(s.rate_within(1)) << std::setw(8) << fixed(s.rate_within(2))
        << std::setw(8) << fixed(s.rate_within(5)) << std::setw(12) << fixed(s.false_positive_rate())
        << std::setw(16) << fixed(s.error_px.mean) << std::setw(8) << fixed(s.error_px.median) << std::setw(8)
        << fixed(s.error_px.p95) << std::setw(8) << fixed(s.error_px.max);
    if (identity && s.identity_told > 0) {
      out << std::setw(13) << fixed(s.identity_rate());
    } else {
      out << std::setw(13) << "-";
    }
    out << "\n";
  };
  row("glints", score.glints, score.settings.score_glints, true);
  row("pupils", score.pupils, score.settings.score_pupils, false);
  out << "\nwithin: of the labelled; false pos.: of the counted detections; error: of the found (within the "
         "radius); identity: right light among the found glints\n";
  // Over every label, misses included: a tracker that often fails cannot
  // look precise here.
  const auto far = [](double x) { return std::isfinite(x) ? fixed(x) : std::string("none"); };
  out << "\nover all labels, the nearest detection however far (none: no detection in the image):\n";
  out << "feature  labelled  without a detection  median px  p95 px  max px\n";
  const auto all_row = [&](const char* name, const FeatureSummary& s, bool reported) {
    if (!reported) return;
    out << std::left << std::setw(9) << name << std::right << std::setw(8) << s.nearest_px.count << std::setw(21)
        << s.nearest_px.none << std::setw(11) << far(s.nearest_px.median) << std::setw(8) << far(s.nearest_px.p95)
        << std::setw(8) << far(s.nearest_px.max) << "\n";
  };
  all_row("glints", score.glints, score.settings.score_glints);
  all_row("pupils", score.pupils, score.settings.score_pupils);
  if (score.settings.score_pupils && score.pupils.overlap.count > 0) {
    out << "\npupil outlines (detections with an ellipse, paired by centre): overlap with the label's median "
        << fixed(score.pupils.overlap.median) << ", mean " << fixed(score.pupils.overlap.mean) << "; "
        << score.pupils.wrong_shape << " of " << score.pupils.overlap.count
        << " overlap less than " << fixed(score.settings.min_pupil_overlap, 2)
        << " (counted as missed and as false positives: the wrong outline, an iris for a pupil)\n";
  }
  if (score.glints.false_positives_on_distractors > 0) {
    out << "false glints on a labelled distractor (a highlight that is no glint): " << score.glints.false_positives_on_distractors
        << " of " << score.glints.false_positives << "\n";
  }
  if (score.glints.not_counted + score.pupils.not_counted > 0) {
    out << "not counted (by a glint on the sclera or under a lid, or a hidden pupil): "
        << score.glints.not_counted << " glint and " << score.pupils.not_counted << " pupil detections\n";
  }
  return out.str();
}

std::string score_csv(const Score& score) {
  std::ostringstream out;
  out << "image,feature,eye,illuminator,outcome,label_u_px,label_v_px,u_px,v_px,error_px,identity,nearest_px,"
         "overlap,axes_error_px,angle_error_deg,on_distractor\n";
  const auto number = [](double x) {
    std::ostringstream s;
    s << std::setprecision(10) << x;
    return s.str();
  };
  const auto optional = [&](const std::optional<double>& x) { return x ? number(*x) : std::string(); };
  for (const FeatureScore& f : score.features) {
    out << csv_cell(f.image) << ',' << to_string(f.feature) << ',' << (f.eye >= 0 ? std::to_string(f.eye) : "")
        << ',' << (f.illuminator >= 0 ? std::to_string(f.illuminator) : "") << ',' << to_string(f.outcome) << ','
        << (f.label ? number(f.label->u) + ',' + number(f.label->v) : ",") << ','
        << (f.detection ? number(f.detection->u) + ',' + number(f.detection->v) : ",") << ','
        << optional(f.error_px) << ','
        << (f.identity_correct ? (*f.identity_correct ? "correct" : "wrong") : "") << ','
        << optional(f.nearest_px) << ',' << optional(f.overlap) << ',' << optional(f.axes_error_px) << ','
        << optional(f.angle_error_deg) << ',' << (f.on_distractor ? "1" : "") << '\n';
  }
  return out.str();
}

std::string score_json(const Score& score) {
  using json = nlohmann::json;
  const auto finite = [](double x) { return std::isfinite(x) ? json(x) : json(nullptr); };
  const auto summary = [&](const FeatureSummary& s, bool reported, bool identity) {
    json j;
    j["reported"] = reported;
    j["labelled"] = s.labelled;
    j["detected"] = s.detected;
    j["found"] = s.found;
    j["within_px"] = {{"1", s.rate_within(1)}, {"2", s.rate_within(2)}, {"5", s.rate_within(5)}};
    j["false_positives"] = s.false_positives;
    j["false_positive_rate"] = s.false_positive_rate();
    j["not_counted"] = s.not_counted;
    if (identity) j["false_positives_on_distractors"] = s.false_positives_on_distractors;  // glints only
    j["error_px"] = {{"count", s.error_px.count}, {"mean", s.error_px.mean}, {"median", s.error_px.median},
                     {"p95", s.error_px.p95},     {"max", s.error_px.max}};
    // null: beyond every detection (the share without one reaches it).
    j["nearest_px"] = {{"count", s.nearest_px.count}, {"none", s.nearest_px.none},
                       {"median", finite(s.nearest_px.median)}, {"p95", finite(s.nearest_px.p95)},
                       {"max", finite(s.nearest_px.max)}};
    if (identity) {
      j["identity_told"] = s.identity_told;
      j["identity_correct"] = s.identity_correct;
      j["identity_rate"] = s.identity_told > 0 ? json(s.identity_rate()) : json(nullptr);
    } else {
      j["wrong_shape"] = s.wrong_shape;
      j["overlap"] = {{"count", s.overlap.count}, {"mean", s.overlap.mean}, {"median", s.overlap.median},
                      {"max", s.overlap.max}};
    }
    return j;
  };
  json root;
  root["images"] = score.images;
  root["match_radius_px"] = score.settings.match_radius_px;
  root["min_pupil_overlap"] = score.settings.min_pupil_overlap;
  root["glints"] = summary(score.glints, score.settings.score_glints, true);
  root["pupils"] = summary(score.pupils, score.settings.score_pupils, false);
  return root.dump(2) + "\n";
}

}  // namespace purkinje::trackers
