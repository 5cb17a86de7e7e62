#include "tear_meniscus.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include "face_mesh.h"
#include "purkinje/models/truth.h"
#include "mirror_radiometry.h"
#include "scene_geometry.h"

namespace purkinje::renderer {
namespace {

// The margin's slope by a central difference: T needs only the slope (its
// curvature scales c' without turning it, see frame()), so the solve sees
// rounding of about 1e-16 * |m| / kSlopeStep.
constexpr double kSlopeStepMm = 1e-3;
// The curvature (|c'| only): a wider step, as rounding grows with the order.
constexpr double kCurvatureStepMm = 1e-2;
// The fillet's centres are found this far apart along x.
constexpr double kNodeStepMm = 0.1;
// Sign changes of the bisector's part along the meniscus are looked for at
// this spacing: two highlights closer than this (a fold, where they are
// about to merge and vanish) may be missed.
constexpr double kScanStepMm = 0.05;
// A root of the bisector's part along the meniscus: anything larger is a
// jump between circles, not a highlight.
constexpr double kRootTolerance = 1e-9;
// The meniscus ends this far along the fissure toward each canthus.
constexpr double kFissureReach = 0.9;

Vector3 unit(const Vector3& v) { return v / v.norm(); }

// Which way the opening lies from a lid's margin: +y above the lower
// lid's, -y below the upper lid's.
double opening_side(Lid lid) { return lid == Lid::lower ? 1.0 : -1.0; }

// The wall at x: the margin's height and slope (a central difference) and
// the wall's unit normal into the opening, as build() and frame() must
// both have them, to the bit.
struct Wall {
  double m = 0, m1 = 0, w = 1, nx = 0, ny = 1;
};
Wall wall_at(const std::function<double(double)>& margin, Lid lid, double x) {
  Wall out;
  out.m = margin(x);
  out.m1 = (margin(x + kSlopeStepMm) - margin(x - kSlopeStepMm)) / (2 * kSlopeStepMm);
  out.w = std::sqrt(1 + out.m1 * out.m1);
  const double side = opening_side(lid);
  out.nx = -side * out.m1 / out.w;
  out.ny = side / out.w;
  return out;
}

// Where f is least on [a, b], by `steps` of golden-section search (f
// unimodal there).
template <class F>
double golden_minimum(const F& f, double a, double b, int steps) {
  const double golden = 0.5 * (std::sqrt(5.0) - 1);
  double c = b - golden * (b - a), d = a + golden * (b - a), fc = f(c), fd = f(d);
  for (int k = 0; k < steps && b > a; ++k) {
    if (fc < fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - golden * (b - a);
      fc = f(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + golden * (b - a);
      fd = f(d);
    }
  }
  return 0.5 * (a + b);
}

// The height Z above the head's xy plane where a sphere of radius r about
// (X, Y, Z) touches the shell from outside, by sphere tracing down from
// far in front: each step is the gap, which the shell's distance (1-Lipschitz)
// cannot overshoot. nullopt when the line passes the shell at more than r.
std::optional<double> touching_height(const ShellOffset& shell, double X, double Y, double r) {
  double Z = 100.0;
  for (int i = 0; i < 2000; ++i) {
    const double gap = shell(Point3{X, Y, Z}).norm() - r;
    if (!(gap > 1e-14)) return gap > -1e-9 ? std::optional<double>(Z) : std::nullopt;
    Z -= gap;
    if (Z < -100.0) return std::nullopt;
  }
  return std::nullopt;
}

}  // namespace

struct TearMeniscus::Frame {
  bool valid = false;
  Point3 c;                               // the circle's centre
  UnitVector3 T = UnitVector3::unit_x();  // c' / |c'|
  UnitVector3 U = UnitVector3::unit_y();  // the wall's normal n: N where the fillet touches the wall
  UnitVector3 V = UnitVector3::unit_z();  // T x U
  double theta_globe = 0;  // the angle of N where it touches the shell, from U toward V
};

std::optional<TearMeniscus> TearMeniscus::build(int eye, Lid lid, const Pose& world_from_head, double radius_mm,
                                                std::function<double(double)> margin_mm, const ShellOffset& shell,
                                                double x_lo, double x_hi) {
  if (!(x_hi > x_lo) || !(radius_mm > 0)) return std::nullopt;
  TearMeniscus out;
  out.eye_ = eye;
  out.lid_ = lid;
  out.world_from_head_ = world_from_head;
  out.head_from_world_ = world_from_head.inverse();
  out.r_ = radius_mm;
  out.margin_ = std::move(margin_mm);
  const double r = radius_mm;
  const int count = std::max(2, static_cast<int>(std::ceil((x_hi - x_lo) / kNodeStepMm)) + 1);
  const double step = (x_hi - x_lo) / (count - 1);
  std::vector<std::optional<double>> z(count);
  std::vector<double> centre_x(count, 0.0);
  std::vector<Vector3> to_centre(count, Vector3{0, 0, 0});
  for (int i = 0; i < count; ++i) {
    const double x = x_lo + i * step;
    const Wall wall = wall_at(out.margin_, lid, x);
    const double X = x + r * wall.nx, Y = wall.m + r * wall.ny;
    centre_x[i] = X;
    z[i] = touching_height(shell, X, Y, r);
    if (z[i]) to_centre[i] = unit(shell(Point3{X, Y, *z[i]}));
  }
  // The run of nodes about the fissure's middle (x = 0) where the fillet
  // exists, its centres' x increasing (the wall curves gentler than r).
  const int middle = static_cast<int>(std::lround(std::clamp(-x_lo / step, 0.0, count - 1.0)));
  if (!z[middle]) return std::nullopt;
  int first = middle, last = middle;
  while (first > 0 && z[first - 1] && centre_x[first - 1] < centre_x[first]) --first;
  while (last + 1 < count && z[last + 1] && centre_x[last + 1] > centre_x[last]) ++last;
  if (last - first < 3) return std::nullopt;
  out.wall_lo_ = x_lo + first * step;
  out.wall_hi_ = x_lo + last * step;
  for (int i = first; i <= last; ++i) {
    out.x_.push_back(centre_x[i]);
    out.z_.push_back(*z[i]);
    out.to_centre_.push_back(to_centre[i]);
  }
  // Z over the centres' x (not the wall's: the margin's curvature jumps
  // at its middle, where the fissure's two parabolas meet, and the
  // centres' speed with it; their path does not turn there). A cubic
  // spline with parabolic run-out (the end intervals' second derivative
  // constant, as a fillet's is, rather than 0): Thomas's algorithm.
  const int n = static_cast<int>(out.z_.size());
  std::vector<double> h(n - 1), diagonal(n, 0.0), rhs(n, 0.0);
  for (int i = 0; i + 1 < n; ++i) h[i] = out.x_[i + 1] - out.x_[i];
  for (int i = 1; i + 1 < n; ++i) {
    diagonal[i] = 2 * (h[i - 1] + h[i]);
    rhs[i] = 6 * ((out.z_[i + 1] - out.z_[i]) / h[i] - (out.z_[i] - out.z_[i - 1]) / h[i - 1]);
  }
  diagonal[1] += h[0];          // M_0 = M_1
  diagonal[n - 2] += h[n - 2];  // M_n-1 = M_n-2
  for (int i = 2; i + 1 < n; ++i) {
    const double f = h[i - 1] / diagonal[i - 1];
    diagonal[i] -= f * h[i - 1];
    rhs[i] -= f * rhs[i - 1];
  }
  out.z2_.assign(n, 0.0);
  for (int i = n - 2; i >= 1; --i) out.z2_[i] = (rhs[i] - (i + 2 < n ? h[i] * out.z2_[i + 1] : 0.0)) / diagonal[i];
  out.z2_[0] = out.z2_[1];
  out.z2_[n - 1] = out.z2_[n - 2];
  return out;
}

TearMeniscus::Frame TearMeniscus::frame(double x) const {
  Frame f;
  if (!(x >= wall_lo_ && x <= wall_hi_)) return f;
  const Wall wall = wall_at(margin_, lid_, x);
  const double m = wall.m, m1 = wall.m1, w = wall.w, nx = wall.nx, ny = wall.ny;
  const double k = kCurvatureStepMm;
  const double m2 = (margin_(x + k) - 2 * m + margin_(x - k)) / (k * k);
  const double X = x + r_ * nx;
  // The spline on [X_i, X_i+1].
  const int n = static_cast<int>(z_.size());
  if (!(X >= x_.front() && X <= x_.back()) || !std::isfinite(m)) return f;
  const int i = std::clamp(static_cast<int>(std::upper_bound(x_.begin(), x_.end(), X) - x_.begin()) - 1, 0, n - 2);
  const double span = x_[i + 1] - x_[i], t = X - x_[i], u = x_[i + 1] - X;
  const double a = z_[i] / span - z2_[i] * span / 6, b = z_[i + 1] / span - z2_[i + 1] * span / 6;
  const double Z = (z2_[i] * u * u * u + z2_[i + 1] * t * t * t) / (6 * span) + a * u + b * t;
  const double dZ = (z2_[i + 1] * t * t - z2_[i] * u * u) / (2 * span) + b - a;  // dZ/dX
  f.c = Point3{X, m + r_ * ny, Z};
  // c' is (1 - r k) (1, m', dZ/dX) along the wall, k = +-m'' / w^3 its
  // curvature toward the opening: the wall's normal turns along it and
  // stays perpendicular to c'.
  if (!(1 - r_ * opening_side(lid_) * m2 / (w * w * w) > 0)) return f;  // the wall curves tighter than r: no fillet
  f.T = UnitVector3::normalize(Vector3{1, m1, dZ});
  f.U = UnitVector3::normalize(Vector3{nx, ny, 0});
  f.V = UnitVector3::normalize(cross(f.T, f.U));
  // Where it touches the shell: the nodes' directions, interpolated.
  const double s = t / span;
  const Vector3 g = to_centre_[i] * (1 - s) + to_centre_[i + 1] * s;
  f.theta_globe = std::atan2(dot(g, f.V), dot(g, f.U));
  f.valid = true;
  return f;
}

double TearMeniscus::theta_at(const Frame& f, const Point3& source, const Point3& target, double& along) const {
  double theta = 0.5 * f.theta_globe;
  Vector3 bisector{0, 0, 0};
  for (int i = 0; i < 100; ++i) {
    const Vector3 n = f.U.vector() * std::cos(theta) + f.V.vector() * std::sin(theta);
    const Point3 p = f.c - n * r_;
    bisector = unit(source - p) + unit(target - p);
    const double next = std::atan2(dot(bisector, f.V), dot(bisector, f.U));
    const bool done = std::abs(next - theta) <= 1e-15;
    theta = next;
    if (done) break;
  }
  along = dot(unit(bisector), f.T);
  return theta;
}

Reflection TearMeniscus::highlight_at(double x, const Point3& source, const Point3& target) const {
  Reflection r;
  const Frame f = frame(x);
  if (!f.valid) return r;
  double along = 0;
  const double theta = theta_at(f, source, target, along);
  // On the arc between the wall and the globe.
  const double lo = std::min(0.0, f.theta_globe), hi = std::max(0.0, f.theta_globe);
  if (!(theta > lo && theta < hi)) return r;
  const UnitVector3 n = UnitVector3::normalize(f.U.vector() * std::cos(theta) + f.V.vector() * std::sin(theta));
  const Point3 p = f.c - n.vector() * r_;
  r.status = PathStatus::ok;
  r.point = world_from_head_ * p;
  r.normal = world_from_head_ * n;
  r.incident = world_from_head_ * UnitVector3::normalize(p - source);
  r.reflected = world_from_head_ * UnitVector3::normalize(target - p);
  r.incidence_rad = std::acos(std::clamp(dot(n, UnitVector3::normalize(target - p)), -1.0, 1.0));
  r.on_cap = false;
  return r;
}

// The root of the bisector's part along the meniscus in [a, b], where it
// changes sign (fa at a), by regula falsi with the Illinois rule; no
// solution where the sign changes by a jump (an invalid circle) rather
// than through 0.
Reflection TearMeniscus::refine(double a, double b, double fa, const Point3& source, const Point3& target) const {
  double along = 0;
  bool valid = true;
  const auto F = [&](double x) {
    const Frame f = frame(x);
    valid = valid && f.valid;
    if (f.valid) theta_at(f, source, target, along);
    return along;
  };
  double fb = F(b);
  int side = 0;
  for (int i = 0; i < 200 && b - a > 1e-12 && valid; ++i) {
    double x = (a * fb - b * fa) / (fb - fa);
    if (!(x > a && x < b)) x = 0.5 * (a + b);
    const double fx = F(x);
    if (fx == 0) {
      a = b = x;
      break;
    }
    if ((fx > 0) == (fb > 0)) {
      b = x;
      fb = fx;
      if (side == -1) fa *= 0.5;
      side = -1;
    } else {
      a = x;
      fa = fx;
      if (side == 1) fb *= 0.5;
      side = 1;
    }
  }
  const double x = 0.5 * (a + b);
  if (!(std::abs(F(x)) <= kRootTolerance) || !valid) return {};
  return highlight_at(x, source, target);
}

std::vector<Reflection> TearMeniscus::highlights(const Point3& source_world, const Point3& target_world) const {
  const Point3 source = head_from_world_ * source_world, target = head_from_world_ * target_world;
  std::vector<Reflection> out;
  const int steps = std::max(1, static_cast<int>(std::ceil((wall_hi_ - wall_lo_) / kScanStepMm)));
  double previous_x = 0, previous_f = 0;
  bool previous_valid = false;
  for (int i = 0; i <= steps; ++i) {
    const double x = wall_lo_ + (wall_hi_ - wall_lo_) * i / steps;
    const Frame f = frame(x);
    double along = 0;
    if (f.valid) theta_at(f, source, target, along);
    const bool valid = f.valid && std::isfinite(along);
    // A root on a node is taken there, and not again as the sign change
    // that follows it.
    if (valid && previous_valid && previous_f != 0 && (along == 0 || (along > 0) != (previous_f > 0))) {
      const Reflection h = along == 0 ? highlight_at(x, source, target) : refine(previous_x, x, previous_f, source, target);
      if (h.status == PathStatus::ok && on_surface(head_from_world_ * h.point)) out.push_back(h);
    }
    previous_x = x;
    previous_f = along;
    previous_valid = valid;
  }
  // Along the lid by their points (as a moving eye's are ordered).
  std::stable_sort(out.begin(), out.end(), [&](const Reflection& a, const Reflection& b) {
    return (head_from_world_ * a.point).x < (head_from_world_ * b.point).x;
  });
  return out;
}

double TearMeniscus::wall_x_of(const Point3& p, double* gap_mm) const {
  // The circle through p: its centre is the centre line's nearest point to
  // p (the plane through the nearest centre perpendicular to the line
  // holds p; other planes of circles may hold it too, farther away): a
  // scan within 1 + 2r of p's x (the wall's x and the point's differ by
  // less than 2r), and golden-section search about each of its minima.
  const auto gap = [&](double x) {
    const Frame f = frame(x);
    return f.valid ? distance(p, f.c) : std::numeric_limits<double>::infinity();
  };
  constexpr double kStep = 0.02;
  const double reach = 1 + 2 * r_;
  const double from = std::max(wall_lo_, p.x - reach), to = std::min(wall_hi_, p.x + reach);
  std::vector<double> xs, gaps;
  for (double x = from; x < to; x += kStep) xs.push_back(x);
  xs.push_back(to);
  for (const double x : xs) gaps.push_back(gap(x));
  double best = xs.front(), best_gap = gaps.front();
  for (std::size_t i = 0; i < xs.size(); ++i) {
    const bool minimum = (i == 0 || gaps[i] <= gaps[i - 1]) && (i + 1 == xs.size() || gaps[i] <= gaps[i + 1]);
    if (!minimum || !std::isfinite(gaps[i])) continue;
    const double x = golden_minimum(gap, xs[i > 0 ? i - 1 : i], xs[i + 1 < xs.size() ? i + 1 : i], 60);
    const double g = std::min(gaps[i], gap(x));
    if (g < best_gap) {
      best_gap = g;
      best = g == gaps[i] ? xs[i] : x;
    }
  }
  if (gap_mm) *gap_mm = best_gap;
  return best;
}

bool TearMeniscus::on_surface(const Point3& head_point) const {
  // Where the centre line bends tighter than r (over the limbus's edge)
  // the circles' surface folds through itself: a point inside another
  // circle's sphere lies on a fold in the air, not on the tears.
  double gap = 0;
  wall_x_of(head_point, &gap);
  return gap >= r_ * (1 - 1e-9);
}

double TearMeniscus::circle_of(const Point3& world_point) const { return wall_x_of(head_from_world_ * world_point); }

Reflection TearMeniscus::highlight_near(double x0, const Point3& source_world, const Point3& target_world) const {
  const Point3 source = head_from_world_ * source_world, target = head_from_world_ * target_world;
  double along = 0;
  const auto F = [&](double x) -> std::optional<double> {
    const Frame f = frame(x);
    if (!f.valid) return std::nullopt;
    theta_at(f, source, target, along);
    return along;
  };
  const std::optional<double> f0 = F(x0);
  if (!f0) return {};
  if (*f0 == 0) return highlight_at(x0, source, target);
  // Widening brackets about x0: the nearest sign change.
  for (double d = 1e-3; d < 1.0; d *= 2) {
    for (const double x : {x0 - d, x0 + d}) {
      const std::optional<double> f = F(x);
      if (!f || (*f > 0) == (*f0 > 0)) continue;
      return x < x0 ? refine(x, x0, *f, source, target) : refine(x0, x, *f0, source, target);
    }
  }
  return {};
}

GlintRadiometry meniscus_highlight_radiometry(const TearMeniscus& meniscus, const Illuminator& light,
                                              const Camera& camera, const Reflection& highlight, const Scene* lenses) {
  check_radiometry_inputs(light, camera);
  if (highlight.status != PathStatus::ok) return failed_radiometry(highlight.status);
  // Its circle, once: every neighbour the differences ask for is sought
  // from there.
  const double circle = meniscus.circle_of(highlight.point);
  const Mirror mirror = [&](const Point3& source, const Point3& target) {
    return meniscus.highlight_near(circle, source, target);
  };
  // The highlight as the meniscus itself finds it: a label from elsewhere
  // (or another meniscus) has no radiometry here.
  const Reflection again = lenses && !lenses->spectacle_lenses.empty()
                               ? see_highlight(*lenses, light.position, camera.center(), mirror).reflection
                               : mirror(light.position, camera.center());
  if (again.status != PathStatus::ok || distance(again.point, highlight.point) > 1e-9) {
    return failed_radiometry(PathStatus::not_converged);
  }
  return mirror_radiometry(mirror, fresnel_reflectance(std::cos(highlight.incidence_rad), 1.0, kTearFilmIndex), light,
                           camera, highlight, lenses);
}

ShellOffset eye_shell_offset(const Eye& eye, const Pose& world_from_head) {
  const EyeModel& m = eye.model();
  // The shell is a surface of revolution about the optical axis: in the
  // meridian plane through a point, at distance rho from the axis and
  // depth w below the apex, it is the cap's conic rho^2 = 2 R w - k w^2
  // down to the limbus (w_L, r_L), the limbal band (rho = r_L down to the
  // seam) or the annulus in the limbus plane (out to the sphere), and the
  // sclera's circle (centre on the axis at the centre of rotation's depth)
  // behind the seam.
  const double R = m.anterior_cornea.radius_mm, k = 1 + m.anterior_cornea.asphericity;
  const double w_L = m.limbus_depth_mm(), r_L = m.limbus_radius_mm, seam = m.sclera_seam_depth_mm();
  const double R_s = m.sclera_radius_mm, w_c = m.rotation_center_depth_mm;
  const double seam_rho = std::sqrt(std::max(0.0, R_s * R_s - (w_c - seam) * (w_c - seam)));
  const Pose eye_from_head = eye.eye_from_world() * world_from_head;
  const Pose head_from_eye = eye_from_head.inverse();
  return [=](const Point3& head_point) {
    const Point3 p = eye_from_head * head_point;  // eye frame: apex at z = R on the z axis
    const double rho = std::hypot(p.x, p.y), w = R - p.z;
    double best = std::numeric_limits<double>::infinity(), foot_rho = 0, foot_w = 0;
    const auto consider = [&](double fr, double fw) {
      const double d = (rho - fr) * (rho - fr) + (w - fw) * (w - fw);
      if (d < best) {
        best = d;
        foot_rho = fr;
        foot_w = fw;
      }
    };
    // The cap, by golden-section search over its radius (the squared
    // distance is unimodal from outside a convex arc).
    const auto depth = [&](double q) { return q * q / (R + std::sqrt(R * R - k * q * q)); };
    const auto cap = [&](double q) { return (rho - q) * (rho - q) + (w - depth(q)) * (w - depth(q)); };
    const double q = golden_minimum(cap, 0.0, r_L, 80);
    consider(q, depth(q));
    if (seam > w_L) {
      consider(r_L, std::clamp(w, w_L, seam));  // the band
    } else {
      consider(std::clamp(rho, std::min(r_L, seam_rho), std::max(r_L, seam_rho)), w_L);  // the annulus
    }
    // The sphere behind the seam, or the seam's circle.
    const double dr = rho, dw = w - w_c, len = std::hypot(dr, dw);
    if (len > 0 && w_c + R_s * dw / len >= seam) {
      consider(R_s * dr / len, w_c + R_s * dw / len);
    } else {
      consider(seam_rho, seam);
    }
    const double cos_phi = rho > 0 ? p.x / rho : 1.0, sin_phi = rho > 0 ? p.y / rho : 0.0;
    const Point3 foot{foot_rho * cos_phi, foot_rho * sin_phi, R - foot_w};
    return head_from_eye * (p - foot);
  };
}

std::vector<TearMeniscus> build_tear_menisci(const Scene& scene) {
  std::vector<TearMeniscus> out;
  for (int i = 0; i < static_cast<int>(scene.eyes.size()); ++i) {
    const Eye& eye = scene.eyes[i];
    const EyeAppearance& look = eye.appearance();
    if (!look.face || !look.eyelids || !look.tear_film) continue;
    const double R = eye.model().sclera_radius_mm;
    const HeadPlacement head = head_placement(scene, i);
    // Copies: the meniscus may outlive this scene's eye.
    const auto margins = [lids = *look.eyelids, face = *look.face, R, turns = head.turns](double x) {
      return fissure_margins(lids, face, R, turns, x);
    };
    const Face& face = *look.face;
    const double nasal = face.side == EyeSide::right ? 1.0 : -1.0;
    const double a = -nasal * kFissureReach * face.lateral_canthus_mm;
    const double b = nasal * kFissureReach * look.eyelids->half_width_mm;
    const double lower_r = look.tear_film->meniscus_radius_mm, upper_r = look.tear_film->upper_meniscus_radius_mm;
    // Along the fissure, where the margins stand apart by more than twice
    // the two menisci's radii together (nearer, they would meet): the run
    // about the middle, for both.
    const auto open = [&](double x) {
      const FissureMargins m = margins(x);
      return m.upper_mm - m.lower_mm > 2 * (lower_r + upper_r);
    };
    if (!open(0)) continue;
    double x_lo = 0, x_hi = 0;
    while (x_lo - kScanStepMm >= std::min(a, b) && open(x_lo - kScanStepMm)) x_lo -= kScanStepMm;
    while (x_hi + kScanStepMm <= std::max(a, b) && open(x_hi + kScanStepMm)) x_hi += kScanStepMm;
    const ShellOffset shell = eye_shell_offset(eye, head.world_from_head);
    for (const Lid lid : {Lid::lower, Lid::upper}) {
      const double r = lid == Lid::lower ? lower_r : upper_r;
      if (!(r > 0)) continue;
      const auto margin = [margins, lid](double x) {
        const FissureMargins m = margins(x);
        return lid == Lid::lower ? m.lower_mm : m.upper_mm;
      };
      std::optional<TearMeniscus> meniscus =
          TearMeniscus::build(i, lid, head.world_from_head, r, margin, shell, x_lo, x_hi);
      if (meniscus) out.push_back(std::move(*meniscus));
    }
  }
  return out;
}

}  // namespace purkinje::renderer
