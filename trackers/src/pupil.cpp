#include "purkinje/trackers/pupil.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <tuple>  // std::tie
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "blobs.h"
#include "grey_mat.h"

namespace purkinje::trackers {

namespace {

// A dark blob of the coarse stage, in full-size pixels.
struct DarkBlob {
  Pixel centre;       // the point deepest inside it
  double radius_px;   // of the largest disc inside it about that point
};

// The noise of an image: the median absolute difference of neighbours
// (edges are too few to move it), as a standard deviation.
double noise_of(const cv::Mat& image) {
  std::vector<float> differences;
  const int step = std::max(1, static_cast<int>(std::sqrt(image.total() / 4096.0)));
  for (int y = step / 2; y < image.rows; y += step) {
    for (int x = step / 2; x + 1 < image.cols; x += step) {
      differences.push_back(std::abs(image.at<float>(y, x + 1) - image.at<float>(y, x)));
    }
  }
  if (differences.empty()) return 0;
  std::nth_element(differences.begin(), differences.begin() + differences.size() / 2, differences.end());
  return 1.4826 * differences[differences.size() / 2] / std::numbers::sqrt2;
}

// Where the pupil may be, on the image shrunk so that the smallest pupil
// is still 3 pixels wide: the darkest pixels (within a small step of the
// darkest 3 x 3 mean, above the noise), in 8-connected regions, each
// region's deepest point and the largest disc about it, widest first. A
// pupil is the darkest thing in an eye image but need not be much darker
// than the iris around it (3% of full scale in the remote scene), so the
// step is small; a region of the pupil and something dark it touches
// (a lid's shadow) has its deepest point in the pupil, the wider of the
// two. Regions that touch the image's border are no pupils (one cut by the
// border cannot be fit) but may be darker: vignetted corners, a headset
// lens's black rim. When every region at the darkest level touches the
// border, the darkest level is sought again without them.
std::vector<DarkBlob> dark_blobs(const cv::Mat& image, const StarburstPupilSettings& s, double full_scale) {
  const int f = std::max(1, static_cast<int>(std::floor(s.min_radius_px / 1.5)));
  const int cols = image.cols / f, rows = image.rows / f;
  if (cols < 3 || rows < 3) return {};
  cv::Mat small;
  if (f == 1) {
    image.convertTo(small, CV_32F);
  } else {
    cv::Mat area;
    cv::resize(image(cv::Rect(0, 0, cols * f, rows * f)), area, {cols, rows}, 0, 0, cv::INTER_AREA);
    area.convertTo(small, CV_32F);
  }
  cv::min(small, full_scale, small);  // larger values are saturated too
  const double step = std::max(s.min_contrast * full_scale, 3 * noise_of(small));  // before the opening flattens it
  // Glints in or on a small pupil would lift its mean: an opening takes
  // away what is bright and narrower than the smallest pupil.
  const int reach = static_cast<int>(std::ceil(s.min_radius_px / f));
  cv::morphologyEx(small, small, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_RECT, {2 * reach + 1, 2 * reach + 1}));
  cv::Mat mean3;
  cv::blur(small, mean3, {3, 3}, {-1, -1}, cv::BORDER_REPLICATE);

  // The regions are labelled from their pixels only: a scan of the whole
  // shrunk frame (cv::connectedComponentsWithStats) took 30% of the time.
  struct Labelling {
    cv::Mat labels;  // all zeros between uses
    std::vector<cv::Point> seeds, stack;
  };
  thread_local Labelling scratch;
  if (scratch.labels.size() != cv::Size(cols, rows)) scratch.labels = cv::Mat::zeros(rows, cols, CV_32S);
  std::vector<DarkBlob> blobs;
  cv::Mat elsewhere;  // not in a dark region found touching the border (empty: everywhere)
  for (int round = 0; round < 4 && blobs.empty(); ++round) {
    double darkest = 0;
    cv::minMaxLoc(mean3, &darkest, nullptr, nullptr, nullptr, elsewhere);
    cv::Mat dark;
    cv::compare(mean3, darkest + step, dark, cv::CMP_LE);
    if (!elsewhere.empty()) dark &= elsewhere;
    cv::Mat depth;  // distance to the nearest pixel not dark
    cv::distanceTransform(dark, depth, cv::DIST_L2, cv::DIST_MASK_3);  // a guide: 3 x 3 is close enough
    scratch.seeds.clear();
    const ClearLabels clear_labels(scratch.labels, scratch.seeds);
    const std::vector<Blob> regions = label_blobs(dark, scratch.labels, scratch.seeds, scratch.stack);
    std::vector<DarkBlob> deepest(regions.size(), DarkBlob{{0, 0}, 0});
    for (const cv::Point& p : scratch.seeds) {
      DarkBlob& b = deepest[scratch.labels.at<int>(p)];
      const float d = depth.at<float>(p);
      // Ties go to the first pixel in row order, as the seeds come.
      if (d > b.radius_px) b = {{double(p.x), double(p.y)}, d};
    }
    std::vector<bool> at_border(regions.size(), false);
    for (std::size_t k = 1; k < regions.size(); ++k) {
      const cv::Rect& box = regions[k].box;
      at_border[k] = box.x == 0 || box.y == 0 || box.br().x == cols || box.br().y == rows;
      if (at_border[k]) continue;
      const DarkBlob& b = deepest[k];
      // Shrunk pixel x covers full-size pixels x f to x f + f - 1.
      blobs.push_back({{b.centre.u * f + 0.5 * (f - 1), b.centre.v * f + 0.5 * (f - 1)}, b.radius_px * f});
    }
    if (!blobs.empty()) break;
    if (elsewhere.empty()) elsewhere = cv::Mat(rows, cols, CV_8U, cv::Scalar(255));
    for (const cv::Point& p : scratch.seeds) {
      if (at_border[scratch.labels.at<int>(p)]) elsewhere.at<std::uint8_t>(p) = 0;
    }
    if (cv::countNonZero(elsewhere) == 0) break;
  }
  // Widest first; ties by place, so that the same image gives the same
  // candidates with any standard library.
  std::sort(blobs.begin(), blobs.end(), [](const DarkBlob& a, const DarkBlob& b) {
    return std::tie(b.radius_px, a.centre.v, a.centre.u) < std::tie(a.radius_px, b.centre.v, b.centre.u);
  });
  if (static_cast<int>(blobs.size()) > s.candidates) blobs.resize(s.candidates);
  return blobs;
}

// The pixels near glints, where an edge may be a glint's.
struct GlintMask {
  std::vector<Pixel> centres;
  std::vector<double> radii2;
  bool covers(double u, double v) const {
    for (std::size_t i = 0; i < centres.size(); ++i) {
      const double du = u - centres[i].u, dv = v - centres[i].v;
      if (du * du + dv * dv <= radii2[i]) return true;
    }
    return false;
  }
};

// A conic a x^2 + b xy + c y^2 + d x + e y + g = 0, with its value and
// gradient: the Sampson distance |F| / |grad F| is close to the distance
// to the curve near it, where inliers are.
struct Conic {
  double a = 0, b = 0, c = 0, d = 0, e = 0, g = -1;
  double value(double x, double y) const { return a * x * x + b * x * y + c * y * y + d * x + e * y + g; }
  double distance(double x, double y) const {
    const double fx = 2 * a * x + b * y + d, fy = b * x + 2 * c * y + e;
    return std::abs(value(x, y)) / std::max(1e-300, std::hypot(fx, fy));
  }
};

Conic conic_of(const Ellipse& el) {
  // ((R^T (p - c))_1 / s1)^2 + ((R^T (p - c))_2 / s2)^2 - 1
  const double cs = std::cos(el.angle_rad), sn = std::sin(el.angle_rad);
  const double i1 = 1 / (el.semi_axis_1_px * el.semi_axis_1_px), i2 = 1 / (el.semi_axis_2_px * el.semi_axis_2_px);
  Conic q;
  q.a = cs * cs * i1 + sn * sn * i2;
  q.b = 2 * cs * sn * (i1 - i2);
  q.c = sn * sn * i1 + cs * cs * i2;
  const double u = el.center.u, v = el.center.v;
  q.d = -(2 * q.a * u + q.b * v);
  q.e = -(q.b * u + 2 * q.c * v);
  q.g = q.a * u * u + q.b * u * v + q.c * v * v - 1;
  return q;
}

// The centre and semi-axes of a conic through points about the origin,
// with the origin inside (g = -1); nothing for anything but an ellipse.
struct ConicEllipse {
  double x0, y0, major, minor;
};
std::optional<ConicEllipse> ellipse_of(const Conic& q) {
  const double det = 4 * q.a * q.c - q.b * q.b;
  if (!(det > 0) || !(q.a + q.c > 0)) return std::nullopt;
  const double x0 = (q.b * q.e - 2 * q.c * q.d) / det, y0 = (q.b * q.d - 2 * q.a * q.e) / det;
  const double k = -(q.g + 0.5 * (q.d * x0 + q.e * y0));  // (p - p0)^T Q (p - p0) = k
  if (!(k > 0)) return std::nullopt;
  const double mean = 0.5 * (q.a + q.c), spread = std::hypot(0.5 * (q.a - q.c), 0.5 * q.b);
  const double lo = mean - spread, hi = mean + spread;  // the eigenvalues of [a b/2; b/2 c]
  if (!(lo > 0)) return std::nullopt;
  return ConicEllipse{x0, y0, std::sqrt(k / lo), std::sqrt(k / hi)};
}

// How much of an outline the edge points on it cover, the confidence: of
// 32 equal sectors about its centre, those with a point on the outline.
// (A count of points would depend on where the rays start: they are
// densest on the part of the outline nearest to it.)
constexpr int kSectors = 32;
class Coverage {
 public:
  Coverage(double x0, double y0) : x0_(x0), y0_(y0) {}
  void add(double x, double y) {
    // Sectors start half a sector off the rays' directions (multiples of
    // 2 pi / 32 for 32 or 64 rays), so that no ray lies on a boundary.
    const double t = std::atan2(y - y0_, x - x0_) * (kSectors / (2 * std::numbers::pi)) + kSectors / 2 + 0.5;
    sectors_ |= 1u << (static_cast<int>(t) % kSectors);
  }
  int sectors() const { return std::popcount(sectors_); }

 private:
  double x0_, y0_;
  std::uint32_t sectors_ = 0;
};

struct Fit {
  Ellipse ellipse;
  int sectors = 0;  // of kSectors
  double confidence() const { return static_cast<double>(sectors) / kSectors; }
  // The pupil is the widest dark region with a well-supported elliptic
  // outline: the shadows in the eye's corners and along the lids' margins
  // can be as well outlined, but are narrow.
  double score() const { return confidence() * std::sqrt(ellipse.semi_axis_2_px); }
};

class StarburstFit {
 public:
  StarburstFit(const cv::Mat& image, std::span<const Glint> glints, const StarburstPupilSettings& s, double full_scale)
      : image_(image), s_(s), full_scale_(full_scale) {
    for (const Glint& g : glints) {
      const double r = std::sqrt(std::max(1, g.area_px) / std::numbers::pi) + s.glint_margin_px;
      mask_.centres.push_back(g.centre);
      mask_.radii2.push_back(r * r);
    }
  }

  // The pupil about a coarse centre and radius: two rounds of rays and fits.
  std::optional<Fit> about(Pixel centre, double radius) {
    std::optional<Fit> found;
    for (int round = 0; round < 2; ++round) {
      if (!cast_rays(centre, radius)) return found;
      std::optional<Fit> f = fit_edges();
      if (!f) return found;
      found = f;
      centre = f->ellipse.center;
      radius = std::sqrt(f->ellipse.semi_axis_1_px * f->ellipse.semi_axis_2_px);
    }
    return found;
  }

 private:
  // The image's value at (u, v), bilinear; false outside.
  bool sample(double u, double v, double& value) const {
    const int x = static_cast<int>(std::floor(u)), y = static_cast<int>(std::floor(v));
    if (x < 0 || y < 0 || x + 1 >= image_.cols || y + 1 >= image_.rows) return false;
    const double fx = u - x, fy = v - y;
    const auto at = [&](int yy, int xx) -> double {
      const double dn = image_.depth() == CV_8U ? image_.at<std::uint8_t>(yy, xx) : image_.at<std::uint16_t>(yy, xx);
      return std::min(dn, full_scale_);  // larger values are saturated too
    };
    const double top = at(y, x) + fx * (at(y, x + 1) - at(y, x));
    const double bottom = at(y + 1, x) + fx * (at(y + 1, x + 1) - at(y + 1, x));
    value = top + fy * (bottom - top);
    return true;
  }

  static constexpr double kStep = 0.5;  // px between samples along a ray

  // Samples along each ray from `centre` out to well beyond `radius`, and
  // the edge point of each ray that has one.
  bool cast_rays(Pixel centre, double radius) {
    centre_ = centre;
    edges_.clear();
    // Far enough for the edge and the level beyond it (3.5 px), from a
    // centre and radius that may be a few pixels off.
    const double reach = std::min(2 * radius, s_.max_radius_px) + 8;
    const int n = static_cast<int>(reach / kStep) + 1;
    profiles_.assign(static_cast<std::size_t>(s_.rays) * n, NAN);  // NaN: outside, or by a glint
    std::vector<double> inside;
    for (int k = 0; k < s_.rays; ++k) {
      const double t = 2 * std::numbers::pi * k / s_.rays, du = std::cos(t), dv = std::sin(t);
      double* p = &profiles_[static_cast<std::size_t>(k) * n];
      for (int i = 0; i < n; ++i) {
        const double u = centre.u + i * kStep * du, v = centre.v + i * kStep * dv;
        double value = 0;
        if (!sample(u, v, value)) break;
        if (mask_.covers(u, v)) continue;
        p[i] = value;
        if (i * kStep <= radius + 2) inside.push_back(value);
      }
    }
    if (inside.size() < 8) return false;
    // The pupil's level and its noise, from the darker half of what lies
    // about as far out as the pupil surely reaches (a glint may hide its
    // middle; the edge's blur and the iris are in the brighter half).
    const auto quantile = [](std::vector<double>& v, double q) {
      const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(v.size() - 1));
      std::nth_element(v.begin(), v.begin() + k, v.end());
      return v[k];
    };
    quantile(inside, 0.5);  // partitions: the darker half first
    inside.resize(inside.size() / 2);
    const double pupil = quantile(inside, 0.5);
    for (double& v : inside) v = std::abs(v - pupil);
    // For Gaussian noise of deviation sigma, the darker half's median
    // absolute deviation from its median is 0.40 sigma.
    const double noise = 2.50 * quantile(inside, 0.5);
    // A rise above the noise, and by at least the least contrast.
    const double step = std::max(s_.min_contrast * full_scale_, 5 * noise);
    // The first rise above the noise may be a faint one (light scattered
    // into the pupil's rim from the iris beside it); the pupil's edge is
    // the rise to the iris's level, the level most rays reach, so the rise
    // sought is half of that. (Rays into a lid reach higher, but start
    // their search only where the ray is dark: from a centre by a lid's
    // edge, those toward the lid find no pupil.)
    std::vector<double> rises;  // to the level beyond each ray's first rise, from the pupil's
    for (int k = 0; k < s_.rays; ++k) {
      double beyond = 0;
      if (edge_along(&profiles_[static_cast<std::size_t>(k) * n], n, pupil, pupil + step, step, beyond)) {
        rises.push_back(beyond - pupil);
      }
    }
    if (rises.size() < 6) return false;
    const double iris = pupil + quantile(rises, 0.5);
    const double rise = pupil + std::max(step, 0.5 * (iris - pupil));
    std::vector<double> beyond_edges;  // the level beyond each edge point
    for (int k = 0; k < s_.rays; ++k) {
      const double* p = &profiles_[static_cast<std::size_t>(k) * n];
      const double t = 2 * std::numbers::pi * k / s_.rays;
      double level = 0;
      if (const auto s = edge_along(p, n, pupil, rise, step, level)) {
        edges_.push_back({centre.u + *s * std::cos(t), centre.v + *s * std::sin(t)});
        beyond_edges.push_back(level);
      }
    }
    // A rise to far brighter than the iris is to a lid's skin (or an
    // unmasked glint): the lid's edge across the pupil, with the pupil's
    // near half, makes a D that an ellipse can follow closely enough to
    // collect more points than the pupil's own outline.
    const double too_bright = iris + 0.5 * (iris - pupil);
    std::size_t kept = 0;
    for (std::size_t i = 0; i < edges_.size(); ++i) {
      if (beyond_edges[i] <= too_bright) edges_[kept++] = edges_[i];
    }
    edges_.resize(kept);
    return edges_.size() >= 6;
  }

  // Where a ray's profile first rises above `rise`: the crossing of the
  // level halfway between the means on either side (2 to 3.5 px from the
  // crossing, the same on both, so that a blur symmetric about the edge
  // moves neither the level nor the crossing), in px from the ray's start;
  // `beyond` is the mean after. Nothing when a glint lies on the edge, or
  // the rise is less than `step`, or there is none.
  std::optional<double> edge_along(const double* p, int n, double pupil, double rise, double step,
                                   double& beyond) const {
    // From where the ray is in the pupil's dark: it may start on the blur
    // of an edge (a lid's) close by.
    int i = 0;
    while (i < n && !(p[i] <= pupil + step)) ++i;
    while (i < n && !(p[i] > rise)) ++i;
    if (i == 0 || i >= n || std::isnan(p[i - 1])) return std::nullopt;
    double level = rise;
    double x = i - 1 + (level - p[i - 1]) / (p[i] - p[i - 1]);  // in samples
    constexpr int kNear = 4, kFar = 7;
    for (int round = 0; round < 2; ++round) {
      const int c = static_cast<int>(std::lround(x));
      double in = 0, out = 0;
      int n_in = 0, n_out = 0;
      for (int j = std::max(0, c - kFar); j <= c + kFar; ++j) {
        // A glint may cover the pupil's side (its level is known anyway),
        // but not the edge or the side beyond it.
        if (j <= c - kNear) {
          if (!std::isnan(p[j])) in += p[j], ++n_in;
          continue;
        }
        if (j >= n || std::isnan(p[j])) return std::nullopt;
        if (j >= c + kNear) out += p[j], ++n_out;
      }
      in = n_in > 0 ? in / n_in : pupil;
      beyond = out / n_out;
      if (beyond - in < step) return std::nullopt;
      level = 0.5 * (in + beyond);
      bool crossed = false;
      for (int j = std::max(1, c - kNear); j <= c + kNear; ++j) {
        if (p[j - 1] < level && p[j] >= level) {
          x = j - 1 + (level - p[j - 1]) / (p[j] - p[j - 1]);
          crossed = true;
          break;
        }
      }
      if (!crossed) return std::nullopt;
    }
    return x * kStep;
  }

  bool plausible(double major, double minor) const {
    return major <= s_.max_radius_px && minor >= s_.min_radius_px && minor >= s_.min_axis_ratio * major;
  }

  // RANSAC over the edge points, then least squares through the inliers.
  std::optional<Fit> fit_edges() {
    const int m = static_cast<int>(edges_.size());
    // Points about the centre, at unit scale, for a well-conditioned solve.
    const double scale = std::max(1.0, std::sqrt(std::max(1e-9, mean_square_radius())));
    std::vector<cv::Point2d> q(m);
    for (int i = 0; i < m; ++i) q[i] = {(edges_[i].u - centre_.u) / scale, (edges_[i].v - centre_.v) / scale};
    std::minstd_rand rng(1);  // the same answer for the same image
    Conic best;
    int best_sectors = 0, best_count = 0;
    double best_sum = INFINITY;
    const double gate = s_.inlier_px / scale;
    for (int it = 0; it < s_.ransac_iterations && best_sectors < kSectors; ++it) {
      int pick[5];
      for (int k = 0; k < 5; ++k) {
        bool fresh = false;
        while (!fresh) {
          pick[k] = static_cast<int>(rng() % m);
          fresh = std::find(pick, pick + k, pick[k]) == pick + k;
        }
      }
      cv::Matx<double, 5, 5> a;
      cv::Vec<double, 5> ones(1, 1, 1, 1, 1), x;
      for (int k = 0; k < 5; ++k) {
        const cv::Point2d& p = q[pick[k]];
        a(k, 0) = p.x * p.x, a(k, 1) = p.x * p.y, a(k, 2) = p.y * p.y, a(k, 3) = p.x, a(k, 4) = p.y;
      }
      if (!cv::solve(a, ones, x, cv::DECOMP_LU)) continue;
      const Conic c{x[0], x[1], x[2], x[3], x[4], -1};
      const std::optional<ConicEllipse> e = ellipse_of(c);
      if (!e || !plausible(e->major * scale, e->minor * scale)) continue;
      int count = 0;
      double sum = 0;
      for (const cv::Point2d& p : q) {
        const double d = c.distance(p.x, p.y);
        if (d < gate) ++count, sum += d;
      }
      if (count > best_count || (count == best_count && sum < best_sum)) {
        // The sectors only tell when to stop: a whole outline cannot be beaten.
        Coverage coverage(e->x0, e->y0);
        for (const cv::Point2d& p : q) {
          if (c.distance(p.x, p.y) < gate) coverage.add(p.x, p.y);
        }
        best = c, best_sectors = coverage.sectors(), best_count = count, best_sum = sum;
      }
    }
    if (best_count < 6) return std::nullopt;
    // Least squares through the inliers, twice: the second time through
    // the points on the first fit.
    std::vector<Pixel> on;
    for (int i = 0; i < m; ++i) {
      if (best.distance(q[i].x, q[i].y) < gate) on.push_back(edges_[i]);
    }
    std::optional<Ellipse> e;
    int sectors = 0;
    for (int round = 0; round < 2; ++round) {
      e = fit_ellipse(on);
      if (!e || !plausible(e->semi_axis_1_px, e->semi_axis_2_px)) return std::nullopt;
      const Conic c = conic_of(*e);
      Coverage coverage(e->center.u, e->center.v);
      on.clear();
      for (const Pixel& p : edges_) {
        if (c.distance(p.u, p.v) < s_.inlier_px) on.push_back(p), coverage.add(p.u, p.v);
      }
      if (on.size() < 6) return std::nullopt;
      sectors = coverage.sectors();
    }
    return Fit{*e, sectors};
  }

  double mean_square_radius() const {
    double sum = 0;
    for (const Pixel& p : edges_) sum += (p.u - centre_.u) * (p.u - centre_.u) + (p.v - centre_.v) * (p.v - centre_.v);
    return sum / edges_.size();
  }

  const cv::Mat& image_;
  const StarburstPupilSettings& s_;
  double full_scale_;
  GlintMask mask_;
  Pixel centre_;
  std::vector<double> profiles_;
  std::vector<Pixel> edges_;
};

}  // namespace

StarburstPupilDetector::StarburstPupilDetector(const StarburstPupilSettings& s) : settings_(s) {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("StarburstPupilSettings: " + what); };
  const auto show = [](double x) { return std::to_string(x); };
  if (!(s.min_radius_px >= 1 && s.max_radius_px >= s.min_radius_px && s.max_radius_px <= 1000)) {
    fail("min_radius_px = " + show(s.min_radius_px) + ", max_radius_px = " + show(s.max_radius_px) +
         ": must satisfy 1 <= min_radius_px <= max_radius_px <= 1000");
  }
  if (s.candidates < 1 || s.candidates > 20) fail("candidates = " + std::to_string(s.candidates) + ": must be in [1, 20]");
  if (s.rays < kSectors || s.rays > 1024) {
    fail("rays = " + std::to_string(s.rays) + ": must be in [32, 1024] (the confidence counts 32 sectors)");
  }
  if (s.ransac_iterations < 1 || s.ransac_iterations > 100000) {
    fail("ransac_iterations = " + std::to_string(s.ransac_iterations) + ": must be in [1, 100000]");
  }
  if (!(s.inlier_px > 0 && s.inlier_px <= 10)) fail("inlier_px = " + show(s.inlier_px) + ": must be in (0, 10]");
  if (!(s.min_axis_ratio > 0 && s.min_axis_ratio <= 1)) {
    fail("min_axis_ratio = " + show(s.min_axis_ratio) + ": must be in (0, 1]");
  }
  if (!(s.min_contrast > 0 && s.min_contrast < 1)) fail("min_contrast = " + show(s.min_contrast) + ": must be in (0, 1)");
  if (!(s.min_confidence >= 0 && s.min_confidence <= 1)) {
    fail("min_confidence = " + show(s.min_confidence) + ": must be in [0, 1]");
  }
  if (!(s.glint_margin_px >= 0 && s.glint_margin_px <= 20)) {
    fail("glint_margin_px = " + show(s.glint_margin_px) + ": must be in [0, 20]");
  }
}

std::optional<PupilDetection> StarburstPupilDetector::detect(const GreyView& view, std::span<const Glint> glints) const {
  const cv::Mat image = mat_of(view, "StarburstPupilDetector");
  const double full_scale = std::ldexp(1.0, view.bits) - 1;
  StarburstFit fit(image, glints, settings_, full_scale);
  std::optional<Fit> best;
  for (const DarkBlob& blob : dark_blobs(image, settings_, full_scale)) {
    const std::optional<Fit> f = fit.about(blob.centre, blob.radius_px);
    if (f && f->confidence() >= settings_.min_confidence && (!best || f->score() > best->score())) best = f;
  }
  if (!best) return std::nullopt;
  return PupilDetection{best->ellipse, best->confidence()};
}

}  // namespace purkinje::trackers
