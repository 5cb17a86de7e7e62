// Light reaching the iris through the cornea (IrisIrradianceCache); the
// iris's own albedo, a material, is iris_texture.cpp's.
//
// Irradiance at an iris-plane point p from a point light L through the
// cornea: E = I T dOmega/dA. The path L -> X (anterior cornea) -> p comes
// from the specular-path solver; T is the product of the Fresnel
// transmittances along it. dOmega/dA = c dA_X / (|X - L|^2 dA_p), with c
// the cosine of incidence at X: the ratio of surface areas is the inverse
// Jacobian determinant of the forward map X -> p (the ray from L through X,
// refracted to the iris plane), taken by central differences of a forward
// trace through the analytic surfaces around the solved path. Four traces
// cost well under a microsecond, against four more solves (1-6 us each),
// and are accurate to ~1e-9; differences between neighbouring grid nodes
// would cost nothing but are biased by the grid's spacing (second order,
// ~1e-3 at 33 nodes) and one-sided at the lit region's border.
//
// What is interpolated: E = S c T(c), with c the cosine of incidence and
// T(c) the anterior transmittance. Both T and dOmega/dA vanish like c at
// the light's horizon on the cornea, so E has no simple form there; but the
// spread S and the chart point (u, v) of the anterior crossing (its
// eye-frame x and y) vary smoothly everywhere. The cache interpolates S and
// (u, v) (Catmull-Rom) and computes c and whether the crossing lies inside
// the limbus exactly from (u, v): the shadow edges at the limbus and at the
// horizon fall where they should inside a cell, not smeared over one.
// For that the forward map continues smoothly past every end of the
// physical paths: beyond the limbus, beyond the horizon (c < 0, the ray
// refracted as if c were positive) and beyond the posterior cornea's rim
// in the iris plane. Nodes just beyond the paths get those continuations
// (Newton on the forward map from a neighbour), else extrapolations.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "purkinje/models/check.h"
#include "purkinje/renderer/radiometry.h"

namespace purkinje::renderer {
namespace {

// Scene lengths are mm; irradiance is per m^2.
constexpr double kPerSquareMm = 1e6;
// Step (mm) of the forward map's central differences on the cornea: the
// truncation error is ~1e-9 relative and rounding stays below it.
constexpr double kJacobianStepMm = 1e-4;
// A traced ray must reproduce the solver's path to this (mm).
constexpr double kPathAgreementMm = 1e-6;
// Newton on the forward map stops within this distance of its target (mm).
constexpr double kContinuationToleranceMm = 1e-9;

// A conicoid x^2 + y^2 + (1 + Q) w^2 - 2 R w = 0 in the eye frame, w = apex_z - z.
struct EyeSurface {
  double apex_z = 0;
  double radius = 0;
  double one_plus_q = 1;

  Vector3 outward_normal(const Vector3& p) const {
    const double w = apex_z - p.z;
    const Vector3 n{p.x, p.y, radius - one_plus_q * w};
    return n / n.norm();
  }
};

// Where the ray o + t d meets `s` nearest to `near` (a point on the surface
// close to the ray). Solved from the foot of `near` on the ray so that the
// quadratic's small root is well conditioned.
bool hit_near(const EyeSurface& s, const Vector3& o, const Vector3& d, const Vector3& near,
              Vector3& hit) {
  const Vector3 f = o + d * dot(near - o, d);
  const double w0 = s.apex_z - f.z;
  const double k = s.one_plus_q;
  const double a = d.x * d.x + d.y * d.y + k * d.z * d.z;
  const double b = 2.0 * (f.x * d.x + f.y * d.y) - 2.0 * k * w0 * d.z + 2.0 * s.radius * d.z;
  const double c = f.x * f.x + f.y * f.y + k * w0 * w0 - 2.0 * s.radius * w0;
  const double disc = b * b - 4.0 * a * c;
  if (!(disc >= 0.0)) return false;
  const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
  if (q == 0.0) return false;
  double t = c / q;
  if (a != 0.0 && std::abs(q / a) < std::abs(t)) t = q / a;
  hit = f + d * t;
  return hit.is_finite();
}

// Snell's law for unit `d` meeting a surface of unit normal `n` (facing
// the incoming side when c = -d.n > 0), from index ratio eta = n1 / n2.
// For c < 0 (a ray that would meet the surface from behind) it gives the
// analytic continuation of the refracted direction, smooth through c = 0.
bool refract(const Vector3& d, const Vector3& n, double c, double eta, Vector3& out) {
  const double k = 1.0 - eta * eta * (1.0 - c * c);
  if (!(k >= 0.0)) return false;
  out = d * eta + n * (eta * c - std::sqrt(k));
  out = out / out.norm();
  return true;
}

// A ray from the light through anterior-cornea point (u, v, z(u, v)), eye
// frame, refracted to the iris plane.
struct TracedRay {
  double u = 0, v = 0;        // chart point: the anterior crossing's eye-frame x and y
  Vector3 anterior, posterior;
  double cos_anterior = 1, cos_posterior = 1;  // incidence cosines (signed, see refract)
  double area_factor = 1;     // surface area per chart area, sqrt(1 + |grad z|^2)
  double distance = 0;        // light to anterior crossing
  double x = 0, y = 0;        // where it meets the iris plane
};

// The cornea and iris plane of one eye, in its own frame.
struct EyeOptics {
  EyeSurface front;
  std::optional<EyeSurface> back;
  double n_front = 1;    // just inside the anterior surface
  double n_aqueous = 1;  // behind the posterior surface (two-surface eyes)
  double iris_z = 0;
  double limbus_depth = 0;
  double inside_radius = 0;  // of the iris-plane disc inside every corneal surface (< 0: none)

  explicit EyeOptics(const EyeModel& m) {
    const double R = m.anterior_cornea.radius_mm;
    front = {R, R, 1.0 + m.anterior_cornea.asphericity};
    if (m.posterior_cornea) {
      back = EyeSurface{R - m.posterior_cornea->thickness_mm, m.posterior_cornea->surface.radius_mm,
                        1.0 + m.posterior_cornea->surface.asphericity};
    }
    n_front = anterior_inner_index(m);
    n_aqueous = m.aqueous_index;
    iris_z = R - m.iris_depth_mm;
    limbus_depth = m.limbus_depth_mm();
    double r2 = inside_radius2(front);
    if (back) r2 = std::min(r2, inside_radius2(*back));
    inside_radius = r2 > 0 ? std::sqrt(r2) : -1.0;
  }

  // Squared radius of the disc of the iris plane inside `s` (<= 0: none).
  double inside_radius2(const EyeSurface& s) const {
    const double w = s.apex_z - iris_z;
    return w > 0 ? 2.0 * s.radius * w - s.one_plus_q * w * w : -1.0;
  }

  // The ray through chart point (u, v); `near_posterior` is a point of the
  // posterior cornea near where it crosses it.
  bool trace(const Vector3& light, double u, double v, const Vector3& near_posterior,
             TracedRay& out) const {
    const double r2 = u * u + v * v;
    const double disc = front.radius * front.radius - front.one_plus_q * r2;
    if (!(disc > 0)) return false;
    const double q = std::sqrt(disc);
    out.u = u;
    out.v = v;
    out.anterior = {u, v, front.apex_z - r2 / (front.radius + q)};
    out.area_factor = std::sqrt(1.0 + r2 / disc);
    Vector3 d = out.anterior - light;
    out.distance = d.norm();
    d = d / out.distance;
    const Vector3 n1 = front.outward_normal(out.anterior);
    out.cos_anterior = -dot(d, n1);
    Vector3 dir;
    if (!refract(d, n1, out.cos_anterior, 1.0 / n_front, dir)) return false;
    Vector3 p = out.anterior;
    if (back) {
      if (!hit_near(*back, p, dir, near_posterior, out.posterior)) return false;
      const Vector3 n2 = back->outward_normal(out.posterior);
      out.cos_posterior = -dot(dir, n2);
      Vector3 next;
      if (!refract(dir, n2, out.cos_posterior, n_front / n_aqueous, next)) return false;
      p = out.posterior;
      dir = next;
    }
    if (!(dir.z < 0.0)) return false;
    const double t = (iris_z - p.z) / dir.z;
    out.x = p.x + dir.x * t;
    out.y = p.y + dir.y * t;
    return std::isfinite(out.x) && std::isfinite(out.y);
  }
};

// A ray and the Jacobian of its iris-plane point (x, y) with respect to
// its chart point (u, v).
struct Differential {
  TracedRay ray;
  double xu = 0, xv = 0, yu = 0, yv = 0;
  double determinant() const { return xu * yv - xv * yu; }
};

bool differentiate(const EyeOptics& optics, const Vector3& light, double u, double v,
                   const Vector3& near_posterior, Differential& out) {
  if (!optics.trace(light, u, v, near_posterior, out.ray)) return false;
  const double h = kJacobianStepMm;
  TracedRay a, b;
  if (!optics.trace(light, u + h, v, out.ray.posterior, a) ||
      !optics.trace(light, u - h, v, out.ray.posterior, b)) {
    return false;
  }
  out.xu = (a.x - b.x) / (2 * h);
  out.yu = (a.y - b.y) / (2 * h);
  if (!optics.trace(light, u, v + h, out.ray.posterior, a) ||
      !optics.trace(light, u, v - h, out.ray.posterior, b)) {
    return false;
  }
  out.xv = (a.x - b.x) / (2 * h);
  out.yv = (a.y - b.y) / (2 * h);
  return true;
}

// Newton on the forward map from a neighbouring node's ray to the ray that
// meets the iris plane at (x, y), possibly past the end of the physical
// paths (see the top of this file). Fails where the continuation does not
// exist either (the chart's end, total internal reflection inside).
bool continue_to(const EyeOptics& optics, const Vector3& light, Differential& d, double x,
                 double y) {
  for (int iteration = 0; iteration < 12; ++iteration) {
    const double rx = x - d.ray.x, ry = y - d.ray.y;
    if (std::hypot(rx, ry) < kContinuationToleranceMm) return true;
    const double det = d.determinant();
    if (!(std::abs(det) > 0)) return false;
    const double du = (d.yv * rx - d.xv * ry) / det, dv = (d.xu * ry - d.yu * rx) / det;
    Differential next;
    if (!differentiate(optics, light, d.ray.u + du, d.ray.v + dv, d.ray.posterior, next)) {
      return false;
    }
    d = next;
  }
  return false;
}

struct Sample {
  bool has_path = false;   // a solved path, or its continuation (see continue_to)
  bool extrapolated = false;
  bool hidden = false;     // from the light by the caller's visibility test
  double irradiance = 0;   // W/m^2 (paths)
  double spread = 0;       // S = E / (c T(c)), W/m^2
  double u = 0, v = 0;     // chart point of the anterior crossing (see TracedRay)
  double cap_margin = -1;  // mm inside the limbus where the path crosses the cornea
  Differential path;
  bool known() const { return has_path || extrapolated; }
};

// E = I T dOmega/dA along a differential ray, or its continuation.
bool set_irradiance(const EyeOptics& optics, const Differential& d, double intensity, Sample& s) {
  const TracedRay& r = d.ray;
  const double c = r.cos_anterior;
  const double t_back =
      optics.back ? 1.0 - fresnel_reflectance(r.cos_posterior, optics.n_front, optics.n_aqueous) : 1.0;
  const double spread = intensity * t_back * r.area_factor /
                        (r.distance * r.distance * std::abs(d.determinant())) * kPerSquareMm;
  const double e = c > 0 ? spread * c * (1.0 - fresnel_reflectance(c, 1.0, optics.n_front)) : 0.0;
  if (!std::isfinite(spread) || !(spread >= 0) || !std::isfinite(e)) return false;
  s.has_path = true;
  s.irradiance = e;
  s.spread = spread;
  s.u = r.u;
  s.v = r.v;
  s.cap_margin = optics.limbus_depth - (optics.front.apex_z - r.anterior.z);
  s.path = d;
  return true;
}

// The exact irradiance at eye-frame iris-plane point (x, y), from the
// specular-path solver.
Sample solve_node(const Eye& eye, const EyeOptics& optics, const Point3& light_world,
                  const Vector3& light_eye, double intensity, double x, double y) {
  Sample s;
  const Point3 inner = eye.world_from_eye() * Point3{x, y, optics.iris_z};
  const Refraction r = solve_refraction(eye, inner, light_world);
  if (r.status != PathStatus::ok && r.status != PathStatus::off_cornea) return s;
  if (optics.back && !r.posterior_point) return s;
  const Vector3 anterior = (eye.eye_from_world() * r.anterior_point).from_origin();
  const Vector3 posterior =
      r.posterior_point ? (eye.eye_from_world() * *r.posterior_point).from_origin() : Vector3{};
  Differential d;
  if (!differentiate(optics, light_eye, anterior.x, anterior.y, posterior, d)) return s;
  // The chart holds the front of the cornea only: a path over its back (a
  // light behind the eye) or any other disagreement is no path here.
  if ((d.ray.anterior - anterior).norm() > kPathAgreementMm ||
      std::hypot(d.ray.x - x, d.ray.y - y) > kPathAgreementMm) {
    return s;
  }
  set_irradiance(optics, d, intensity, s);
  return s;
}


// Catmull-Rom weights at fraction t between the middle two of four nodes.
void cubic_weights(double t, double w[4]) {
  const double t2 = t * t, t3 = t2 * t;
  w[0] = 0.5 * (-t3 + 2 * t2 - t);
  w[1] = 0.5 * (3 * t3 - 5 * t2 + 2);
  w[2] = 0.5 * (-3 * t3 + 4 * t2 + t);
  w[3] = 0.5 * (t3 - t2);
}

// Rings of nodes beyond the paths that get values: the cubic's stencil
// reaches two nodes out of a cell, whose corners may be a ring out already
// where the lit region pokes between nodes.
constexpr int kFilledRings = 3;

}  // namespace

double refracted_irradiance_w_m2(const Eye& eye, const Point3& light, double radiant_intensity_w_sr,
                                 const Point3& iris_plane_point, const IrisIrradianceCache::Visibility& visible) {
  const EyeModel& m = eye.model();
  const EyeOptics optics(m);
  const Point3 p = eye.eye_from_world() * iris_plane_point;
  if (!(p.x * p.x + p.y * p.y < optics.inside_radius * optics.inside_radius) || !(optics.inside_radius > 0)) {
    return 0;
  }
  const Sample s = solve_node(eye, optics, light, (eye.eye_from_world() * light).from_origin(), radiant_intensity_w_sr,
                              p.x, p.y);
  if (!s.has_path || !(s.cap_margin > 0) || !(s.irradiance > 0)) return 0;
  if (visible && !visible(light, eye.world_from_eye() * (Point3::origin() + s.path.ray.anterior))) return 0;
  return s.irradiance;
}

IrisIrradianceCache::IrisIrradianceCache(const Eye& eye, const Point3& light_position,
                                         double radiant_intensity_w_sr, int resolution,
                                         const Visibility& visible)
    : eye_from_world_(eye.eye_from_world()),
      world_from_eye_(eye.world_from_eye()),
      light_world_(light_position),
      visible_(visible),
      resolution_(resolution) {
  if (resolution < 2) {
    throw std::invalid_argument("IrisIrradianceCache: resolution = " + std::to_string(resolution) +
                                ": must be >= 2");
  }
  if (!std::isfinite(radiant_intensity_w_sr) || radiant_intensity_w_sr < 0) {
    throw std::invalid_argument("IrisIrradianceCache: radiant_intensity_w_sr = " +
                                check::format_number(radiant_intensity_w_sr) +
                                ": must be finite and >= 0");
  }
  if (!light_position.is_finite()) {
    throw std::invalid_argument("IrisIrradianceCache: light_position is not finite");
  }
  const EyeModel& m = eye.model();
  const EyeOptics optics(m);
  iris_plane_z_mm_ = optics.iris_z;
  half_size_mm_ = m.iris_outer_radius_mm();
  const int n = resolution;
  const std::size_t count = static_cast<std::size_t>(n) * n;
  light_mm_ = eye_from_world_ * light_position;
  apex_z_mm_ = optics.front.apex_z;
  anterior_radius_mm_ = optics.front.radius;
  anterior_one_plus_q_ = optics.front.one_plus_q;
  limbus_depth_mm_ = optics.limbus_depth;
  inside_radius_mm_ = optics.inside_radius;
  anterior_inner_index_ = optics.n_front;
  nodes_.assign(count, GridNode{});
  if (radiant_intensity_w_sr == 0) return;

  const Vector3 light_eye = (eye_from_world_ * light_position).from_origin();
  const double spacing = 2.0 * half_size_mm_ / (n - 1);
  const auto coordinate = [&](int i) { return -half_size_mm_ + spacing * i; };
  const auto index = [n](int i, int j) { return static_cast<std::size_t>(j) * n + i; };
  std::vector<Sample> samples(count);
  tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& rows) {
    for (int j = rows.begin(); j != rows.end(); ++j) {
      for (int i = 0; i < n; ++i) {
        Sample& s = samples[index(i, j)];
        s = solve_node(eye, optics, light_position, light_eye, radiant_intensity_w_sr, coordinate(i), coordinate(j));
        if (visible && s.irradiance > 0 && s.cap_margin > 0 &&
            std::hypot(coordinate(i), coordinate(j)) < optics.inside_radius) {
          s.hidden = !visible(light_position, world_from_eye_ * (Point3::origin() + s.path.ray.anterior));
        }
      }
    }
  });

  // Values for the nodes just beyond the paths, ring by ring, each ring
  // from the previous state only (so the order, and the thread count, do
  // not matter): the paths' continuation where it exists, else a linear
  // extrapolation from the known nodes around. Beside hidden nodes only, a
  // node is hidden too: the light's path to it would pass the same obstacle.
  for (int ring = 0; ring < kFilledRings; ++ring) {
    std::vector<int> frontier;
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        if (samples[index(i, j)].known()) continue;
        bool next_to_known = false;
        for (int dj = -1; dj <= 1 && !next_to_known; ++dj) {
          for (int di = -1; di <= 1 && !next_to_known; ++di) {
            const int i1 = i + di, j1 = j + dj;
            next_to_known = i1 >= 0 && i1 < n && j1 >= 0 && j1 < n && samples[index(i1, j1)].known();
          }
        }
        if (next_to_known) frontier.push_back(static_cast<int>(index(i, j)));
      }
    }
    std::vector<Sample> filled(frontier.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, frontier.size()),
                      [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t f = range.begin(); f != range.end(); ++f) {
        const int i = frontier[f] % n, j = frontier[f] / n;
        Sample& out = filled[f];
        // Sums of (spread, u, v): linear extrapolations along the eight
        // directions, and the known neighbours themselves.
        double line[3] = {0, 0, 0}, near[3] = {0, 0, 0};
        int lines = 0, nears = 0;
        bool all_hidden = true;
        for (int dj = -1; dj <= 1; ++dj) {
          for (int di = -1; di <= 1; ++di) {
            const int i1 = i + di, j1 = j + dj, i2 = i + 2 * di, j2 = j + 2 * dj;
            if ((di == 0 && dj == 0) || i1 < 0 || i1 >= n || j1 < 0 || j1 >= n) continue;
            const Sample& a = samples[index(i1, j1)];
            if (!a.known()) continue;
            all_hidden = all_hidden && a.hidden;
            if (!out.has_path && a.has_path) {
              Differential d = a.path;
              if (continue_to(optics, light_eye, d, coordinate(i), coordinate(j))) {
                set_irradiance(optics, d, radiant_intensity_w_sr, out);
              }
            }
            near[0] += a.spread;
            near[1] += a.u;
            near[2] += a.v;
            ++nears;
            if (i2 < 0 || i2 >= n || j2 < 0 || j2 >= n) continue;
            const Sample& b = samples[index(i2, j2)];
            if (!b.known()) continue;
            line[0] += 2 * a.spread - b.spread;
            line[1] += 2 * a.u - b.u;
            line[2] += 2 * a.v - b.v;
            ++lines;
          }
        }
        out.hidden = all_hidden;
        if (out.has_path) continue;
        const double* sum = lines > 0 ? line : near;
        const double k = 1.0 / (lines > 0 ? lines : nears);
        out.extrapolated = true;
        out.spread = sum[0] * k;
        out.u = sum[1] * k;
        out.v = sum[2] * k;
      }
    });
    for (std::size_t f = 0; f < frontier.size(); ++f) samples[frontier[f]] = filled[f];
  }

  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const Sample& s = samples[index(i, j)];
      if (!s.known()) continue;
      nodes_[index(i, j)] = {s.spread, s.u, s.v, true, !s.hidden};
    }
  }
}

double IrisIrradianceCache::irradiance_w_m2(const Point3& iris_plane_point) const {
  const Point3 p = eye_from_world_ * iris_plane_point;
  // Light reaches only the part of the plane inside the cornea.
  if (!(p.x * p.x + p.y * p.y < inside_radius_mm_ * inside_radius_mm_) || !(inside_radius_mm_ > 0)) {
    return 0;
  }
  return continued_irradiance_w_m2(iris_plane_point);
}

double IrisIrradianceCache::continued_irradiance_w_m2(const Point3& iris_plane_point) const {
  const Point3 p = eye_from_world_ * iris_plane_point;
  const double scale = (resolution_ - 1) / (2.0 * half_size_mm_);
  const double gx = (p.x + half_size_mm_) * scale, gy = (p.y + half_size_mm_) * scale;
  const double last = resolution_ - 1;
  if (!(gx >= 0 && gx <= last && gy >= 0 && gy <= last)) return 0;  // also rejects NaN
  const int i = std::min(static_cast<int>(gx), resolution_ - 2);
  const int j = std::min(static_cast<int>(gy), resolution_ - 2);
  double wx[4], wy[4];
  cubic_weights(gx - i, wx);
  cubic_weights(gy - j, wy);
  double spread = 0, u = 0, v = 0;
  bool any_lit = false, any_hidden = false;
  for (int b = 0; b < 4; ++b) {
    const std::size_t row = static_cast<std::size_t>(std::clamp(j - 1 + b, 0, resolution_ - 1));
    double spread_row = 0, u_row = 0, v_row = 0;
    for (int a = 0; a < 4; ++a) {
      const GridNode& node = nodes_[row * resolution_ + std::clamp(i - 1 + a, 0, resolution_ - 1)];
      if (!node.known) return 0;  // two cells or more beyond the lit region
      any_lit = any_lit || node.lit;
      any_hidden = any_hidden || !node.lit;
      spread_row += wx[a] * node.spread_w_m2;
      u_row += wx[a] * node.chart_u_mm;
      v_row += wx[a] * node.chart_v_mm;
    }
    spread += wy[b] * spread_row;
    u += wy[b] * u_row;
    v += wy[b] * v_row;
  }
  if (!any_lit || !(spread > 0)) return 0;
  // The anterior crossing, exactly where the interpolated chart point says.
  const double r2 = u * u + v * v, R = anterior_radius_mm_, k = anterior_one_plus_q_;
  const double disc = R * R - k * r2;
  if (!(disc > 0)) return 0;
  const double w = r2 / (R + std::sqrt(disc));  // depth below the apex
  if (!(w < limbus_depth_mm_)) return 0;
  const Vector3 normal{u, v, R - k * w};
  const Point3 crossing{u, v, apex_z_mm_ - w};
  const Vector3 from_light = crossing - light_mm_;
  const double c = -dot(from_light, normal) / (from_light.norm() * normal.norm());
  if (!(c > 0)) return 0;
  if (any_hidden && visible_ && !visible_(light_world_, world_from_eye_ * crossing)) return 0;
  return spread * c * (1.0 - fresnel_reflectance(c, 1.0, anterior_inner_index_));
}

}  // namespace purkinje::renderer
