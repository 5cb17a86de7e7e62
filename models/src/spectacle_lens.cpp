#include "purkinje/models/spectacle_lens.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "purkinje/models/check.h"
#include "purkinje/models/scene.h"

namespace purkinje {
namespace {

using check::format_number;

// Depth of a sphere's cap below its vertex at distance r from the axis;
// NaN beyond the sphere.
double sag_mm(double radius_mm, double r) {
  const double d = radius_mm * radius_mm - r * r;
  if (d < 0) return std::numeric_limits<double>::quiet_NaN();
  return r * r / (radius_mm + std::sqrt(d));  // R - sqrt(R^2 - r^2) without cancellation
}

// Where the segment a + s (b - a), s in (0, 1), crosses the cap of the
// sphere (centre on the lens axis at z = c, radius R, vertex at c + R)
// inside the outline.
bool segment_crosses_cap(const SpectacleLens& lens, const Point3& a, const Point3& b, double c, double R) {
  const Vector3 d = b - a;
  const Vector3 m = a - Point3{0, 0, c};
  const double A = d.squared_norm(), B = dot(m, d), C = m.squared_norm() - R * R;
  const double disc = B * B - A * C;
  if (!(A > 0) || disc < 0) return false;
  const double root = std::sqrt(disc);
  for (const double s : {(-B - root) / A, (-B + root) / A}) {
    if (!(s > 0 && s < 1)) continue;
    const Point3 p = a + d * s;
    if (p.z > c && inside_outline(lens, p)) return true;  // the cap is the sphere's half toward +z
  }
  return false;
}

}  // namespace

const char* to_string(LensSurface s) { return s == LensSurface::front ? "front" : "back"; }

double front_surface_power_d(const SpectacleLens& lens) {
  return 1000.0 * (lens.refractive_index - 1) / lens.front_radius_mm;
}

double back_vertex_power_d(const SpectacleLens& lens) {
  const double n = lens.refractive_index;
  const double f1 = front_surface_power_d(lens);
  const double f2 = 1000.0 * (1 - n) / lens.back_radius_mm;
  return f1 / (1 - lens.center_thickness_mm / 1000.0 * f1 / n) + f2;
}

double back_radius_for_power_mm(double power_d, double front_radius_mm, double center_thickness_mm,
                                double refractive_index) {
  const double n = refractive_index;
  const double f1 = 1000.0 * (n - 1) / front_radius_mm;
  const double f2 = power_d - f1 / (1 - center_thickness_mm / 1000.0 * f1 / n);
  // A meniscus's back surface is concave toward the eye: negative power.
  if (!(f2 < 0)) {
    throw std::invalid_argument("a back vertex power of " + format_number(power_d) + " D with a front of " +
                                format_number(f1) + " D needs a back surface of " + format_number(f2) +
                                " D, not a meniscus (the back surface's power must be negative: raise the "
                                "base curve)");
  }
  return 1000.0 * (1 - n) / f2;
}

double lens_thickness_mm(const SpectacleLens& lens, double x_mm, double y_mm) {
  const double r = std::hypot(x_mm, y_mm);
  return lens.center_thickness_mm + sag_mm(lens.back_radius_mm, r) - sag_mm(lens.front_radius_mm, r);
}

void check_spectacle_lens(const SpectacleLens& lens) {
  const auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
  for (const auto& [name, r] : {std::pair{"front_radius_mm", lens.front_radius_mm},
                                std::pair{"back_radius_mm", lens.back_radius_mm}}) {
    if (!(r > 0 && r <= 1e5)) {
      fail(std::string(name) + " " + format_number(r) +
           " must be in (0, 1e5] mm: both of a spectacle lens's centres lie on the eye's side (a meniscus); "
           "a flat surface is a large radius");
    }
  }
  if (!(lens.center_thickness_mm > 0 && lens.center_thickness_mm <= 30)) {
    fail("center_thickness_mm " + format_number(lens.center_thickness_mm) + " must be in (0, 30] mm");
  }
  if (!(lens.refractive_index > 1 && lens.refractive_index <= 3)) {
    fail("refractive_index " + format_number(lens.refractive_index) + " must be in (1, 3]");
  }
  const double radius = std::min(lens.front_radius_mm, lens.back_radius_mm);
  for (const double a : lens.outline_semi_axes_mm) {
    if (!(a > 0 && a <= 60 && a < radius)) {
      fail("outline semi-axis " + format_number(a) + " mm must be in (0, 60] mm and below both radii (" +
           format_number(radius) + " mm)");
    }
  }
  // The thickness changes monotonically from the centre outward: the
  // outline's farthest point decides the edge.
  const double edge = lens_thickness_mm(lens, std::max(lens.outline_semi_axes_mm[0], lens.outline_semi_axes_mm[1]), 0);
  if (!(edge >= 0.1)) {
    fail("the edge is " + format_number(edge) +
         " mm thick at the outline's farthest point; it must be at least 0.1 mm (a plus lens needs a larger "
         "center_thickness_mm)");
  }
}

LensSide lens_side(const SpectacleLens& lens, const Point3& p) {
  const double r2 = p.x * p.x + p.y * p.y;
  const auto cap_z = [&](double radius, double vertex_z) {
    return r2 < radius * radius ? vertex_z - r2 / (radius + std::sqrt(radius * radius - r2)) : vertex_z - radius;
  };
  if (p.z > cap_z(lens.front_radius_mm, 0)) return LensSide::in_front;
  if (p.z < cap_z(lens.back_radius_mm, -lens.center_thickness_mm)) return LensSide::behind;
  return LensSide::between;
}

void check_spectacle_lens_placement(const Scene& scene, int index) {
  const SpectacleLens& lens = scene.spectacle_lenses.at(index);
  const Pose lens_from_world = lens.world_from_lens.inverse();
  const auto in_glass = [&](const Point3& world) {
    const Point3 p = lens_from_world * world;
    return lens_side(lens, p) == LensSide::between && inside_outline(lens, p);
  };
  for (std::size_t e = 0; e < scene.eyes.size(); ++e) {
    if (in_glass(scene.eyes[e].corneal_apex())) {
      throw std::invalid_argument("it cuts eyes[" + std::to_string(e) + "]'s cornea (the corneal apex lies in its glass)");
    }
  }
  for (std::size_t c = 0; c < scene.cameras.size(); ++c) {
    if (in_glass(scene.cameras[c].center())) {
      throw std::invalid_argument("camera \"" + scene.cameras[c].name() + "\" lies in the lens's glass");
    }
  }
  for (const Illuminator& l : scene.illuminators) {
    if (in_glass(l.position)) throw std::invalid_argument("illuminator \"" + l.name + "\" lies in the lens's glass");
  }
}

bool inside_outline(const SpectacleLens& lens, const Point3& p) {
  const double u = p.x / lens.outline_semi_axes_mm[0], v = p.y / lens.outline_semi_axes_mm[1];
  return u * u + v * v <= 1;
}

bool segment_crosses_lens(const SpectacleLens& lens, const Point3& a_world, const Point3& b_world) {
  const Pose lens_from_world = lens.world_from_lens.inverse();
  const Point3 a = lens_from_world * a_world, b = lens_from_world * b_world;
  return segment_crosses_cap(lens, a, b, -lens.front_radius_mm, lens.front_radius_mm) ||
         segment_crosses_cap(lens, a, b, -lens.center_thickness_mm - lens.back_radius_mm, lens.back_radius_mm);
}

}  // namespace purkinje
