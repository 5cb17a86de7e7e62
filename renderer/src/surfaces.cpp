#include "surfaces.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace purkinje::renderer::surfaces {

namespace {

// The first root inside the segment whose point passes `keep`.
template <class Keep>
bool first_kept_root(const Segment& s, double a, double half_b, double c, Keep keep, double& t) {
  double roots[2];
  const int n = solve_quadratic(a, half_b, c, roots);
  for (int i = 0; i < n; ++i) {
    const double r = roots[i];
    if (r > s.t_lo && r < s.t_hi && keep(s.origin + s.direction * r)) {
      t = r;
      return true;
    }
  }
  return false;
}

}  // namespace

bool ConicoidCap::first_hit(const Segment& s, double& t) const {
  const Vector3& d = s.direction;
  const Point3& o = s.origin;
  const double w0 = apex_z_mm - o.z;
  const double a = d.x * d.x + d.y * d.y + k * d.z * d.z;
  const double half_b = o.x * d.x + o.y * d.y - d.z * (k * w0 - radius_mm);
  const double c = o.x * o.x + o.y * o.y + w0 * (k * w0 - 2.0 * radius_mm);
  // w >= 0 drops the far sheet of a hyperboloid (k < 0); for k > 0 the
  // surface has no points with w < 0, so only rounding is tested there.
  const double lo = -kSeamOverlapMm, hi = max_depth_mm + kSeamOverlapMm;
  return first_kept_root(
      s, a, half_b, c,
      [&](const Point3& p) {
        const double w = apex_z_mm - p.z;
        return w >= lo && w <= hi;
      },
      t);
}

Vector3 ConicoidCap::normal(const Point3& p) const {
  return {p.x, p.y, radius_mm - k * (apex_z_mm - p.z)};
}

Box ConicoidCap::bounds() const {
  // r^2(w) = 2 R w - k w^2 grows with w up to the equator w = R / k of an
  // ellipsoid (k > 0) and without bound otherwise.
  double w_widest = max_depth_mm;
  if (k > 0.0) w_widest = std::min(w_widest, radius_mm / k);
  const double r = std::sqrt(std::max(0.0, 2.0 * radius_mm * w_widest - k * w_widest * w_widest));
  return {{-r, -r, apex_z_mm - max_depth_mm}, {r, r, apex_z_mm}};
}

bool SphereBelowPlane::first_hit(const Segment& s, double& t) const {
  const Vector3 oc = s.origin - center;
  const double a = s.direction.squared_norm();
  const double half_b = dot(oc, s.direction);
  const double c = oc.squared_norm() - radius_mm * radius_mm;
  const double top = max_z_mm + kSeamOverlapMm;
  return first_kept_root(s, a, half_b, c, [&](const Point3& p) { return p.z <= top; }, t);
}

Vector3 SphereBelowPlane::normal(const Point3& p) const { return p - center; }

Box SphereBelowPlane::bounds() const {
  const double r = radius_mm;
  return {{center.x - r, center.y - r, center.z - r},
          {center.x + r, center.y + r, std::min(center.z + r, max_z_mm + kSeamOverlapMm)}};
}

bool Cylinder::first_hit(const Segment& s, double& t) const {
  const Vector3& d = s.direction;
  const Point3& o = s.origin;
  const double a = d.x * d.x + d.y * d.y;
  if (a == 0.0) return false;  // parallel to the wall
  const double half_b = o.x * d.x + o.y * d.y;
  const double c = o.x * o.x + o.y * o.y - radius_mm * radius_mm;
  const double lo = min_z_mm - kSeamOverlapMm, hi = max_z_mm + kSeamOverlapMm;
  return first_kept_root(s, a, half_b, c, [&](const Point3& p) { return p.z >= lo && p.z <= hi; },
                         t);
}

Vector3 Cylinder::normal(const Point3& p) const { return {p.x, p.y, 0.0}; }

Box Cylinder::bounds() const {
  const double r = radius_mm;
  return {{-r, -r, min_z_mm}, {r, r, max_z_mm}};
}

bool PlaneRegion::contains(double x, double y) const {
  const double ox = x - outer_x_mm, oy = y - outer_y_mm;
  const double outer = outer_radius_mm + kSeamOverlapMm;
  if (ox * ox + oy * oy > outer * outer) return false;
  if (hole_radius_mm > kSeamOverlapMm) {
    const double hx = x - hole_x_mm, hy = y - hole_y_mm;
    const double hole = hole_radius_mm - kSeamOverlapMm;
    if (hx * hx + hy * hy < hole * hole) return false;
  }
  for (const Cut& cut : cuts) {
    if (cut.normal.x * x + cut.normal.y * y + cut.normal.z * z_mm > cut.offset) return false;
  }
  return true;
}

bool PlaneRegion::first_hit(const Segment& s, double& t) const {
  if (s.direction.z == 0.0) return false;  // in or parallel to the plane
  const double r = (z_mm - s.origin.z) / s.direction.z;
  if (!(r > s.t_lo && r < s.t_hi)) return false;
  if (!contains(s.origin.x + r * s.direction.x, s.origin.y + r * s.direction.y)) return false;
  t = r;
  return true;
}

Box PlaneRegion::bounds() const {
  const double r = outer_radius_mm;
  return {{outer_x_mm - r, outer_y_mm - r, z_mm}, {outer_x_mm + r, outer_y_mm + r, z_mm}};
}

MarginTurn MarginTurn::by(double radians) { return {std::cos(radians), std::sin(radians)}; }

namespace {

// Whether p, turned back by `turn` (its elevation lowered by the margin's
// turn), lies below (sign +1) or above (sign -1) the head-fixed margin
// height m. While the turned point is in front (z > 0) its elevation and
// the margin's both lie in (-90, 90) deg, where comparing sines (y against
// m, at the same distance from the x axis) compares angles; behind, its
// elevation lies beyond +-90 deg (the turn is at most 90 deg, so it stays
// within +-180 deg), below every margin when y < 0, above when y > 0.
bool beyond_margin(const Point3& p, const MarginTurn& turn, double m, double sign) {
  const double y = p.y * turn.cos - p.z * turn.sin;
  const double z = p.y * turn.sin + p.z * turn.cos;
  return z > 0.0 ? sign * y < sign * m : sign * y < 0.0;
}

}  // namespace

bool PalpebralOpening::contains(const Point3& p) const {
  if (!(p.z > 0.0) || !(std::abs(p.x) < half_width_mm)) return false;
  const double u = p.x / half_width_mm;
  const double f = opening * (1.0 - u * u);
  const double upper = closing_line_mm + (upper_margin_mm - closing_line_mm) * f;
  const double lower = closing_line_mm + (lower_margin_mm - closing_line_mm) * f;
  return beyond_margin(p, upper_turn, upper, 1.0) && beyond_margin(p, lower_turn, lower, -1.0);
}

double eye_elevation_rad(const Vector3& optical_axis_head) {
  return std::atan2(optical_axis_head.y, optical_axis_head.z);
}

MarginTurns margin_turns(double upper_gain_upgaze, double upper_gain_downgaze, double lower_gain_upgaze,
                         double lower_gain_downgaze, double eye_elevation_rad) {
  const double e = eye_elevation_rad;
  const double limit = std::numbers::pi / 2;
  const auto turn = [&](double up, double down) { return std::clamp((e >= 0 ? up : down) * e, -limit, limit); };
  return {turn(upper_gain_upgaze, upper_gain_downgaze), turn(lower_gain_upgaze, lower_gain_downgaze)};
}

bool EyelidSphere::first_hit(const Segment& s, double& t) const {
  const Vector3 o = s.origin.from_origin();
  const double a = s.direction.squared_norm();
  const double half_b = dot(o, s.direction);
  const double c = o.squared_norm() - radius_mm * radius_mm;
  const double bottom = min_z_mm - kSeamOverlapMm, top = max_z_mm + kSeamOverlapMm;
  return first_kept_root(
      s, a, half_b, c,
      [&](const Point3& p) { return p.z >= bottom && p.z <= top && !opening.contains(p); }, t);
}

Box EyelidSphere::bounds() const {
  const double r = radius_mm;
  return {{-r, -r, std::max(-r, min_z_mm - kSeamOverlapMm)},
          {r, r, std::min(r, max_z_mm + kSeamOverlapMm)}};
}

double LensCap::z_at(double x, double y) const {
  const double r2 = x * x + y * y;
  return vertex_z_mm - r2 / (radius_mm + std::sqrt(std::max(0.0, radius_mm * radius_mm - r2)));
}

bool LensCap::first_hit(const Segment& s, double& t) const {
  const Vector3& d = s.direction;
  const Vector3 m = s.origin - Point3{0, 0, vertex_z_mm - radius_mm};
  const double a = d.squared_norm(), half_b = dot(m, d), c = m.squared_norm() - radius_mm * radius_mm;
  const double centre_z = vertex_z_mm - radius_mm;
  const double ex = 1 + kSeamOverlapMm / semi_x_mm, ey = 1 + kSeamOverlapMm / semi_y_mm;
  return first_kept_root(
      s, a, half_b, c,
      [&](const Point3& p) {
        const double u = p.x / (semi_x_mm * ex), v = p.y / (semi_y_mm * ey);
        return p.z > centre_z && u * u + v * v <= 1;
      },
      t);
}

Box LensCap::bounds() const {
  const double r = std::max(semi_x_mm, semi_y_mm);
  return {{-semi_x_mm, -semi_y_mm, z_at(r, 0)}, {semi_x_mm, semi_y_mm, vertex_z_mm}};
}

bool LensEdge::first_hit(const Segment& s, double& t) const {
  const Vector3& d = s.direction;
  const Point3& o = s.origin;
  const double ia = 1 / (front.semi_x_mm * front.semi_x_mm), ib = 1 / (front.semi_y_mm * front.semi_y_mm);
  const double a = d.x * d.x * ia + d.y * d.y * ib;
  if (a == 0.0) return false;  // along the axis: parallel to the wall
  const double half_b = o.x * d.x * ia + o.y * d.y * ib;
  const double c = o.x * o.x * ia + o.y * o.y * ib - 1;
  return first_kept_root(
      s, a, half_b, c,
      [&](const Point3& p) {
        return p.z >= back.z_at(p.x, p.y) - kSeamOverlapMm && p.z <= front.z_at(p.x, p.y) + kSeamOverlapMm;
      },
      t);
}

Box LensEdge::bounds() const {
  const Box f = front.bounds(), b = back.bounds();
  return united(f, b);
}

}  // namespace purkinje::renderer::surfaces
