#pragma once
// The exact shapes the ray tracer builds for each eye, each in its own
// local frame (the eye frame or the head frame, see scene_geometry.h),
// intersected in double precision. Free of Embree so that the math can be
// tested alone and reused by other back ends.
//
// Every shape answers the first intersection of a ray segment with the
// open parameter interval (t_lo, t_hi). Callers get the best precision by
// first moving the ray origin near the local origin (the shapes' sizes are
// millimetres, the rays may start a metre away): see RayTracer.

#include <algorithm>
#include <cmath>
#include <vector>

#include "purkinje/models/geometry.h"

namespace purkinje::renderer::surfaces {

// Where two pieces of the eye's shell meet (cap and limbal band, band and
// sclera, lid and face, pupil and iris), each piece reaches this far past
// the seam, so that rounding opens no crack between them.
inline constexpr double kSeamOverlapMm = 1e-9;

// A ray segment in a shape's local frame: points origin + t direction with
// t_lo < t < t_hi. direction is of unit length (to rounding).
struct Segment {
  Point3 origin;
  Vector3 direction;
  double t_lo = 0;
  double t_hi = 0;
};

// Real roots of a t^2 + 2 half_b t + c = 0 in ascending order, computed
// without cancellation; a = 0 degrades to the linear equation. Returns the
// number of roots (0, 1 or 2) written to `roots`. Inline: every surface
// test of every ray solves one (a tenth of a headset render).
inline int solve_quadratic(double a, double half_b, double c, double roots[2]) {
  if (a == 0.0) {
    if (half_b == 0.0) return 0;
    roots[0] = -c / (2.0 * half_b);
    return 1;
  }
  const double disc = half_b * half_b - a * c;
  if (!(disc >= 0.0)) return 0;
  // q has the sign of -half_b, so neither root subtracts nearly equal numbers.
  const double q = -(half_b + std::copysign(std::sqrt(disc), half_b));
  if (q == 0.0) {  // half_b = disc = 0, hence c = 0: a double root at 0
    roots[0] = 0.0;
    return 1;
  }
  const double r0 = q / a, r1 = c / q;
  roots[0] = std::min(r0, r1);
  roots[1] = std::max(r0, r1);
  return 2;
}

// Axis-aligned box in a local frame.
struct Box {
  Point3 lo, hi;
};

// The smallest box holding both.
inline Box united(const Box& a, const Box& b) {
  return {{std::min(a.lo.x, b.lo.x), std::min(a.lo.y, b.lo.y), std::min(a.lo.z, b.lo.z)},
          {std::max(a.hi.x, b.hi.x), std::max(a.hi.y, b.hi.y), std::max(a.hi.z, b.hi.z)}};
}

// The conicoid x^2 + y^2 + k w^2 - 2 R w = 0, w = apex_z - z (depth below
// the apex, which sits on the z axis), k = 1 + Q; only the cap with
// 0 <= w <= max_depth_mm. Gradient-based normal: (x, y, R - k w), pointing
// out of the cap's convex side.
struct ConicoidCap {
  double radius_mm = 7.8;
  double k = 1.0;
  double apex_z_mm = 7.8;
  double max_depth_mm = 2.7;

  bool first_hit(const Segment& s, double& t) const;
  Vector3 normal(const Point3& p) const;  // not normalized
  Box bounds() const;
};

// The sphere |p - center| = radius, only where z <= max_z_mm (the sclera:
// everything behind the limbal seam). Normal radial, outward.
struct SphereBelowPlane {
  Point3 center;
  double radius_mm = 12.0;
  double max_z_mm = 0.0;

  bool first_hit(const Segment& s, double& t) const;
  Vector3 normal(const Point3& p) const;
  Box bounds() const;
};

// The cylinder x^2 + y^2 = radius^2 about the z axis, min_z <= z <= max_z
// (the limbal band). Normal radial, outward.
struct Cylinder {
  double radius_mm = 5.9;
  double min_z_mm = 0.0;
  double max_z_mm = 0.0;

  bool first_hit(const Segment& s, double& t) const;
  Vector3 normal(const Point3& p) const;
  Box bounds() const;
};

// A region of the plane z = z_mm: inside the outer circle, outside the hole
// circle (none when hole_radius_mm <= 0) and on the kept side of every
// half-space cut. Normal +z.
struct PlaneRegion {
  struct Cut {  // keeps the points with dot(p, normal) <= offset
    Vector3 normal;
    double offset = 0;
  };
  double z_mm = 0.0;
  double outer_x_mm = 0.0, outer_y_mm = 0.0, outer_radius_mm = 1.0;
  double hole_x_mm = 0.0, hole_y_mm = 0.0, hole_radius_mm = 0.0;
  std::vector<Cut> cuts;

  bool first_hit(const Segment& s, double& t) const;
  Vector3 normal(const Point3&) const { return {0, 0, 1}; }
  Box bounds() const;
  bool contains(double x, double y) const;  // the point (x, y, z_mm)
};

// A turn about the head frame's x axis, positive carrying +z toward +y
// (up): cosine and sine, computed once.
struct MarginTurn {
  double cos = 1.0;
  double sin = 0.0;
  static MarginTurn by(double radians);
};

// Margins of the palpebral opening, heights along the head frame's y axis
// (see Eyelids in appearance.h): with f = opening (1 - (x / half_width)^2),
// upper(x) = closing + (upper - closing) f, lower(x) = closing + (lower - closing) f.
// Each margin is then turned about the x axis with the lid sphere it lies
// on (upper_turn, lower_turn: the lids following the gaze). Where the
// turned margins cross, no point is below the one and above the other:
// the lids meet and the opening is closed there.
struct PalpebralOpening {
  double opening = 1.0;
  double upper_margin_mm = 4.5;
  double lower_margin_mm = -5.5;
  double closing_line_mm = -1.0;
  double half_width_mm = 15.0;
  MarginTurn upper_turn;
  MarginTurn lower_turn;

  // Whether the head-frame point lies in the opening (z > 0, |x| < half
  // width, strictly between the margins). A point is below a margin turned
  // by a when its elevation in its plane x = const, atan2(y, z), is less
  // than the margin's elevation at the point's distance from the x axis,
  // plus a; with no turn this is y < margin height.
  bool contains(const Point3& p) const;
};

// How far each margin turns (radians, positive up) when the eye's optical
// axis points along `optical_axis_head` (head frame: x left-right, y up,
// z forward): gain times the eye's elevation atan2(y, z), the gain chosen
// by the elevation's sign; each turn limited to +-90 deg.
struct MarginTurns {
  double upper_rad = 0.0;
  double lower_rad = 0.0;
};
double eye_elevation_rad(const Vector3& optical_axis_head);
MarginTurns margin_turns(double upper_gain_upgaze, double upper_gain_downgaze, double lower_gain_upgaze,
                         double lower_gain_downgaze, double eye_elevation_rad);

// The lids: the sphere |p| = radius about the head frame's origin (the
// eye's centre of rotation), only where min_z_mm <= z <= max_z_mm, minus
// the opening. Both sides are surfaces. Normal radial, outward.
struct EyelidSphere {
  double radius_mm = 13.8;
  double min_z_mm = 6.21;
  double max_z_mm = 13.8;
  PalpebralOpening opening;

  bool first_hit(const Segment& s, double& t) const;
  Vector3 normal(const Point3& p) const { return p.from_origin(); }
  Box bounds() const;
};

// A spectacle lens's surface (spectacle_lens.h, in the lens frame): the
// sphere of radius R whose vertex lies on the z axis at vertex_z_mm (its
// centre R below), within the elliptic outline x^2/a^2 + y^2/b^2 <= 1.
// Normal out of the glass: the sphere's outward normal for the front
// surface (out_of_glass = 1), inward for the back (-1).
struct LensCap {
  double radius_mm = 100.0;
  double vertex_z_mm = 0.0;
  double semi_x_mm = 25.0, semi_y_mm = 20.0;
  double out_of_glass = 1.0;

  bool first_hit(const Segment& s, double& t) const;
  Vector3 normal(const Point3& p) const { return (p - Point3{0, 0, vertex_z_mm - radius_mm}) * out_of_glass; }
  Box bounds() const;
  // The surface's z at (x, y), inside the sphere's radius.
  double z_at(double x, double y) const;
};

// A spectacle lens's edge: the elliptic cylinder through its outline,
// between its back and front surfaces. Normal out of the glass (outward).
struct LensEdge {
  LensCap front, back;

  bool first_hit(const Segment& s, double& t) const;
  Vector3 normal(const Point3& p) const {
    return {p.x / (front.semi_x_mm * front.semi_x_mm), p.y / (front.semi_y_mm * front.semi_y_mm), 0.0};
  }
  Box bounds() const;
};

}  // namespace purkinje::renderer::surfaces
