#include "purkinje/models/specular.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "purkinje/models/optimizer.h"

// Two methods, one principle (Fermat): a light path through specular
// surface points is a stationary point of its optical length.
//
// Spheres: the path lies in the plane through the sphere's centre and the
// two end points, so one angle theta in that plane is unknown. The
// derivative of the optical length along the arc is smooth and changes sign
// across the visible arc; a safeguarded Newton iteration on it converges to
// machine precision in a handful of steps and cannot leave the bracket (so
// it cannot find the back of the cornea).
//
// Conicoids and two-surface eyes: each surface point is parametrized by its
// eye-frame (x, y) (the cap is a graph over the iris plane), and the
// gradient of the optical length in those coordinates is driven to zero by
// the optimizer facade, with the exact Hessian as Jacobian, starting from
// the sphere solution.

namespace purkinje {

const char* to_string(PathStatus s) {
  switch (s) {
    case PathStatus::ok: return "ok";
    case PathStatus::no_solution: return "no_solution";
    case PathStatus::total_internal_reflection: return "total_internal_reflection";
    case PathStatus::off_cornea: return "off_cornea";
    case PathStatus::behind_camera: return "behind_camera";
    case PathStatus::outside_image: return "outside_image";
    case PathStatus::occluded: return "occluded";
    case PathStatus::not_converged: return "not_converged";
    case PathStatus::invalid_input: return "invalid_input";
  }
  return "unknown";
}

namespace {

constexpr double kPi = 3.14159265358979323846;

// A conicoid in the eye frame: apex at (0, 0, apex_z), axis along -z into the eye.
struct Surface {
  double apex_z = 0;
  Conicoid shape;

  double radius() const { return shape.radius_mm; }
  double one_plus_q() const { return 1.0 + shape.asphericity; }
  // Negative inside, zero on the surface, positive outside (in the region
  // in front of the surface's far end, which is all the solver uses).
  double implicit(const Vector3& p) const {
    const double w = apex_z - p.z;
    return p.x * p.x + p.y * p.y + one_plus_q() * w * w - 2.0 * radius() * w;
  }
  Vector3 normal(const Vector3& p) const {  // outward, unit
    const double w = apex_z - p.z;
    return UnitVector3::normalize({p.x, p.y, radius() - one_plus_q() * w}).vector();
  }
};

// A surface point from chart coordinates (x, y), with the first and second
// derivatives of z needed for the exact Hessian.
struct ChartPoint {
  Vector3 X;
  double zx = 0, zy = 0, zxx = 0, zxy = 0, zyy = 0;
};

bool chart_point(const Surface& s, double x, double y, ChartPoint& out) {
  const double r2 = x * x + y * y;
  const double R = s.radius();
  const double disc = R * R - s.one_plus_q() * r2;
  if (!(disc > 0.0)) return false;
  const double q = std::sqrt(disc);
  const double w = r2 / (R + q);         // depth from the apex
  const double w1 = 0.5 / q;             // dw/d(r2)
  const double w2 = s.one_plus_q() / (4.0 * q * q * q);  // d2w/d(r2)2
  out.X = {x, y, s.apex_z - w};
  out.zx = -2.0 * x * w1;
  out.zy = -2.0 * y * w1;
  out.zxx = -(4.0 * x * x * w2 + 2.0 * w1);
  out.zyy = -(4.0 * y * y * w2 + 2.0 * w1);
  out.zxy = -4.0 * x * y * w2;
  return true;
}

// ---------------------------------------------------------------------------
// Sphere: one unknown angle in the plane of the centre and the end points.

struct Plane2 {
  Vector3 u, w;  // orthonormal, u toward the outer end point
};

struct ArcResult {
  bool found = false;
  bool tir = false;
  double theta = 0;
  int iterations = 0;
};

// Derivative along the arc of sum_i n_i |E_i - X(theta)| and its derivative,
// for X(theta) = R (cos, sin) in 2-D plane coordinates.
struct ArcPath {
  double R;
  double ax, ay, na;  // end point A (outer) and the index of its segment
  double bx, by, nb;  // end point B and the index of its segment

  void eval(double theta, double& d, double& dd) const {
    const double c = std::cos(theta), s = std::sin(theta);
    const double x = R * c, y = R * s;
    const double tx = -R * s, ty = R * c;  // dX/dtheta; d2X/dtheta2 = -X
    double ex = ax - x, ey = ay - y;
    const double la = std::hypot(ex, ey);
    ex /= la;
    ey /= la;
    double fx = bx - x, fy = by - y;
    const double lb = std::hypot(fx, fy);
    fx /= lb;
    fy /= lb;
    const double at = ex * tx + ey * ty, bt = fx * tx + fy * ty;
    d = -(na * at + nb * bt);
    dd = na * (R * R - at * at) / la + nb * (R * R - bt * bt) / lb +
         (na * (ex * x + ey * y) + nb * (fx * x + fy * y));
  }
  double derivative(double theta) const {
    double d, dd;
    eval(theta, d, dd);
    return d;
  }
};

// Safeguarded Newton for the root of a derivative that is negative at lo
// and positive at hi.
ArcResult newton_in_bracket(const ArcPath& path, double lo, double hi, double start) {
  ArcResult r;
  double theta = std::clamp(start, lo, hi);
  for (int i = 0; i < 100; ++i) {
    r.iterations = i + 1;
    double d, dd;
    path.eval(theta, d, dd);
    if (d == 0.0) break;
    if (d < 0) lo = theta; else hi = theta;
    double next = theta - d / dd;
    if (!(next > lo && next < hi) || !(dd > 0)) next = 0.5 * (lo + hi);
    const double step = std::abs(next - theta);
    theta = next;
    if (step <= 4e-16 * std::max(1.0, std::abs(theta)) || hi - lo <= 4e-16) break;
  }
  r.found = true;
  r.theta = theta;
  return r;
}

// The in-plane frame for a sphere centred at the origin: u toward `outer`,
// w toward `other` (any perpendicular when they are parallel).
Plane2 plane_for(const Vector3& outer, const Vector3& other) {
  const UnitVector3 u = UnitVector3::normalize(outer);
  Vector3 w = other - u.vector() * dot(other, u);
  if (w.norm() <= 1e-14 * std::max(1.0, other.norm())) {
    const Vector3 any = std::abs(u.x()) < 0.9 ? Vector3{1, 0, 0} : Vector3{0, 1, 0};
    w = any - u.vector() * dot(any, u);
  }
  return {u.vector(), UnitVector3::normalize(w).vector()};
}

// Reflection on a sphere centred at the eye-frame origin.
bool sphere_reflection(double R, const Vector3& source, const Vector3& target, Vector3& point,
                       int& iterations) {
  const Plane2 p = plane_for(target, source);
  const double gamma = std::atan2(dot(source, p.w), dot(source, p.u));  // in [0, pi]
  if (gamma > kPi - 1e-12) return false;  // source exactly behind: only a grazing limit
  const ArcPath path{R, dot(source, p.u), dot(source, p.w), 1.0, target.norm(), 0.0, 1.0};
  double theta = 0;
  if (gamma > 0) {
    const ArcResult r = newton_in_bracket(path, 0.0, gamma, 0.5 * gamma);
    theta = r.theta;
    iterations = r.iterations;
  }
  point = (p.u * std::cos(theta) + p.w * std::sin(theta)) * R;
  return true;
}

// Refraction on a sphere centred at the origin: inner point (index n_in)
// to outer point (index 1). Returns false with tir set when no path leaves
// through the visible arc.
bool sphere_refraction(double R, double n_in, const Vector3& inner, const Vector3& outer,
                       Vector3& point, bool& tir, int& iterations) {
  tir = false;
  const Plane2 p = plane_for(outer, inner);
  const double dk = outer.norm();
  const ArcPath path{R, dk, 0.0, 1.0, dot(inner, p.u), dot(inner, p.w), n_in};
  const double theta_max = std::acos(std::clamp(R / dk, -1.0, 1.0));  // the horizon seen from outer
  // Start of the bracket: where the straight line from inner to outer
  // leaves the sphere; refraction into air bends the path beyond it.
  const Vector3 dir = UnitVector3::normalize(outer - inner).vector();
  const double b = dot(inner, dir), c = inner.squared_norm() - R * R;
  const Vector3 xs = inner + dir * (-b + std::sqrt(std::max(0.0, b * b - c)));
  double lo = std::max(0.0, std::atan2(dot(xs, p.w), dot(xs, p.u)));
  if (path.derivative(lo) >= 0.0) lo = 0.0;
  double theta = 0.0;
  if (path.derivative(0.0) < 0.0) {
    // Leave the horizon itself out: there the exit is grazing.
    const double hi = theta_max * (1.0 - 1e-15);
    // A nearly tangent straight line can put lo past hi by rounding.
    lo = std::min(lo, hi);
    if (path.derivative(hi) <= 0.0) {
      tir = true;
      return false;
    }
    const ArcResult r = newton_in_bracket(path, lo, hi, lo);
    theta = r.theta;
    iterations = r.iterations;
  }
  point = (p.u * std::cos(theta) + p.w * std::sin(theta)) * R;
  return true;
}

// ---------------------------------------------------------------------------
// General surfaces: stationary optical length over chart coordinates.

// A chain of points end_a, X_1 .. X_m, end_b with segment indices n_0..n_m.
// Fills the chart gradient (2m) and row-major Hessian (2m x 2m).
template <int M>
bool chain_gradient(const std::array<Surface, M>& surfaces, const Vector3& end_a,
                    const Vector3& end_b, const std::array<double, M + 1>& n, const double* xy,
                    double* grad, double* hess) {
  std::array<ChartPoint, M> cp;
  for (int i = 0; i < M; ++i)
    if (!chart_point(surfaces[i], xy[2 * i], xy[2 * i + 1], cp[i])) return false;
  std::array<Vector3, M + 2> pts;
  pts[0] = end_a;
  for (int i = 0; i < M; ++i) pts[i + 1] = cp[i].X;
  pts[M + 1] = end_b;

  // World-space gradient g_i and Hessian blocks per segment.
  std::array<Vector3, M> g{};
  std::array<std::array<double, 9>, M + 1> seg_m{};  // n (I - d d^T) / |d| per segment
  for (int s = 0; s <= M; ++s) {
    const Vector3 d = pts[s + 1] - pts[s];
    const double len = d.norm();
    if (!(len > 0)) return false;
    const Vector3 e = d / len;
    // d/dX of n|X - A| is n unit(X - A).
    if (s >= 1) g[s - 1] -= e * n[s];  // pts[s] = X_s is the start of segment s
    if (s < M) g[s] += e * n[s];       // pts[s + 1] = X_{s+1} is its end
    const double k = n[s] / len;
    const double ev[3] = {e.x, e.y, e.z};
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) seg_m[s][3 * r + c] = k * ((r == c ? 1.0 : 0.0) - ev[r] * ev[c]);
  }
  // Chart Jacobians: columns (1, 0, zx) and (0, 1, zy).
  auto jac = [&](int i, int col, int row) {
    if (row == 2) return col == 0 ? cp[i].zx : cp[i].zy;
    return row == col ? 1.0 : 0.0;
  };
  const int N = 2 * M;
  for (int i = 0; i < M; ++i) {
    grad[2 * i] = g[i].x + g[i].z * cp[i].zx;
    grad[2 * i + 1] = g[i].y + g[i].z * cp[i].zy;
  }
  if (!hess) return true;
  for (int a = 0; a < N * N; ++a) hess[a] = 0;
  // Point X_i touches segments i (as its end) and i + 1 (as its start).
  for (int i = 0; i < M; ++i) {
    for (int j = 0; j < M; ++j) {
      std::array<double, 9> block{};
      if (i == j) {
        for (int a = 0; a < 9; ++a) block[a] = seg_m[i][a] + seg_m[i + 1][a];
      } else if (std::abs(i - j) == 1) {
        const int s = std::max(i, j);  // the segment joining X_i and X_j
        for (int a = 0; a < 9; ++a) block[a] = -seg_m[s][a];
      } else {
        continue;
      }
      for (int ca = 0; ca < 2; ++ca)
        for (int cb = 0; cb < 2; ++cb) {
          double h = 0;
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) h += jac(i, ca, r) * block[3 * r + c] * jac(j, cb, c);
          hess[(2 * i + ca) * N + 2 * j + cb] += h;
        }
    }
    // Curvature of the chart: g_z times the second derivatives of z.
    hess[(2 * i) * N + 2 * i] += g[i].z * cp[i].zxx;
    hess[(2 * i) * N + 2 * i + 1] += g[i].z * cp[i].zxy;
    hess[(2 * i + 1) * N + 2 * i] += g[i].z * cp[i].zxy;
    hess[(2 * i + 1) * N + 2 * i + 1] += g[i].z * cp[i].zyy;
  }
  return true;
}

template <int M>
bool solve_chain(const std::array<Surface, M>& surfaces, const Vector3& end_a,
                 const Vector3& end_b, const std::array<double, M + 1>& n,
                 std::array<double, 2 * M>& xy, int& iterations) {
  optimizer::Options options;
  options.max_iterations = 50;
  options.gradient_tolerance = 1e-30;
  options.parameter_tolerance = 1e-17;
  options.function_tolerance = 1e-30;
  const auto residuals = [&](const double* x, double* r, double* J) {
    return chain_gradient<M>(surfaces, end_a, end_b, n, x, r, J);
  };
  const optimizer::Summary summary = optimizer::solve(2 * M, xy, residuals, options);
  iterations = summary.iterations;
  // Accept by the size of the stationarity residual, not by the solver's
  // reason for stopping: ~1e-13 of the path's scale is machine precision.
  std::array<double, 2 * M> grad;
  if (!chain_gradient<M>(surfaces, end_a, end_b, n, xy.data(), grad.data(), nullptr))
    return false;
  double gmax = 0;
  for (double v : grad) gmax = std::max(gmax, std::abs(v));
  return gmax < 1e-11;
}

// Chart coordinates of a start point, pulled inside the chart's domain
// (oblate conicoids end at their equator, r = R / sqrt(1 + Q)).
std::array<double, 2> chart_start(const Surface& s, const Vector3& p) {
  const double r = std::hypot(p.x, p.y);
  const double limit = s.one_plus_q() > 0 ? 0.999 * s.radius() / std::sqrt(s.one_plus_q()) : r;
  const double k = r > limit ? limit / r : 1.0;
  return {p.x * k, p.y * k};
}

Surface anterior_surface(const EyeModel& m) {
  return {m.anterior_cornea.radius_mm, m.anterior_cornea};
}

Surface posterior_surface(const EyeModel& m) {
  return {m.anterior_cornea.radius_mm - m.posterior_cornea->thickness_mm,
          m.posterior_cornea->surface};
}

// The intersection of the segment from `from` (inside `s`'s outer side) to
// `to` with the surface, by bisection on the implicit function.
bool segment_hits(const Surface& s, const Vector3& from, const Vector3& to, Vector3& hit) {
  double fa = s.implicit(from), fb = s.implicit(to);
  if ((fa < 0) == (fb < 0)) return false;
  double lo = 0, hi = 1;
  for (int i = 0; i < 200 && hi - lo > 1e-16; ++i) {
    const double mid = 0.5 * (lo + hi);
    const double fm = s.implicit(from + (to - from) * mid);
    if ((fm < 0) == (fa < 0)) lo = mid; else hi = mid;
  }
  hit = from + (to - from) * (0.5 * (lo + hi));
  return true;
}

Vector3 world_vector(const Eye& eye, const Vector3& v) { return eye.world_from_eye() * v; }
Point3 world_point(const Eye& eye, const Vector3& p) {
  return eye.world_from_eye() * (Point3::origin() + p);
}

}  // namespace

Reflection solve_reflection(const Eye& eye, const Point3& source_w, const Point3& target_w) {
  Reflection out;
  const EyeModel& m = eye.model();
  const Surface s = anterior_surface(m);
  const Vector3 source = (eye.eye_from_world() * source_w).from_origin();
  const Vector3 target = (eye.eye_from_world() * target_w).from_origin();
  if (!source.is_finite() || !target.is_finite() || s.implicit(source) <= 0 ||
      s.implicit(target) <= 0) {
    out.status = PathStatus::invalid_input;
    return out;
  }
  const double R = m.anterior_cornea.radius_mm;
  Vector3 x;
  if (!sphere_reflection(R, source, target, x, out.iterations)) {
    out.status = PathStatus::no_solution;
    return out;
  }
  if (!m.anterior_cornea.is_sphere()) {
    std::array<double, 2> xy = chart_start(s, x);
    int it = 0;
    if (!solve_chain<1>({s}, source, target, {1.0, 1.0}, xy, it)) {
      // An oblate cornea is a graph over the iris plane only up to its
      // equator; a path that needs more lies far beyond the limbus.
      out.status = std::hypot(xy[0], xy[1]) > m.limbus_radius_mm ? PathStatus::no_solution
                                                                  : PathStatus::not_converged;
      out.iterations += it;
      return out;
    }
    out.iterations += it;
    ChartPoint cp;
    chart_point(s, xy[0], xy[1], cp);
    x = cp.X;
  }
  const Vector3 n = s.normal(x);
  const Vector3 to_source = source - x, to_target = target - x;
  // Both ends must see the point from the outer side of the surface.
  if (!(dot(to_source, n) > 0) || !(dot(to_target, n) > 0)) {
    out.status = PathStatus::no_solution;
    return out;
  }
  out.point = world_point(eye, x);
  out.normal = UnitVector3::normalize(world_vector(eye, n));
  out.incident = UnitVector3::normalize(world_vector(eye, -to_source));
  out.reflected = UnitVector3::normalize(world_vector(eye, to_target));
  out.incidence_rad = angle_between(-out.incident.vector(), out.normal);
  out.on_cap = eye.on_cap(out.point);
  out.status = out.on_cap ? PathStatus::ok : PathStatus::off_cornea;
  return out;
}

Reflection solve_sphere_reflection(const Point3& center, double radius_mm, const Point3& source_w,
                                   const Point3& target_w) {
  Reflection out;
  const Vector3 source = source_w - center, target = target_w - center;
  if (!source.is_finite() || !target.is_finite() || !(radius_mm > 0) || !(source.norm() > radius_mm) ||
      !(target.norm() > radius_mm)) {
    out.status = PathStatus::invalid_input;
    return out;
  }
  Vector3 x;
  if (!sphere_reflection(radius_mm, source, target, x, out.iterations)) {
    out.status = PathStatus::no_solution;
    return out;
  }
  const Vector3 n = x / radius_mm;
  const Vector3 to_source = source - x, to_target = target - x;
  if (!(dot(to_source, n) > 0) || !(dot(to_target, n) > 0)) {
    out.status = PathStatus::no_solution;
    return out;
  }
  out.point = center + x;
  out.normal = UnitVector3::normalize(n);
  out.incident = UnitVector3::normalize(-to_source);
  out.reflected = UnitVector3::normalize(to_target);
  out.incidence_rad = angle_between(-out.incident.vector(), out.normal);
  out.status = PathStatus::ok;
  return out;
}

Reflection solve_scleral_reflection(const Eye& eye, const Point3& source, const Point3& target) {
  const EyeModel& m = eye.model();
  Reflection out = solve_sphere_reflection(eye.rotation_center(), m.sclera_radius_mm, source, target);
  if (out.status != PathStatus::ok) return out;
  // Eye frame: the seam's plane z = R - seam depth; the sphere is the
  // sclera only behind it.
  const Point3 p = eye.eye_from_world() * out.point;
  if (!(m.anterior_cornea.radius_mm - p.z >= m.sclera_seam_depth_mm())) out.status = PathStatus::no_solution;
  return out;
}

Refraction solve_refraction(const Eye& eye, const Point3& inner_w, const Point3& outer_w) {
  Refraction out;
  const EyeModel& m = eye.model();
  const Surface front = anterior_surface(m);
  const Vector3 inner = (eye.eye_from_world() * inner_w).from_origin();
  const Vector3 outer = (eye.eye_from_world() * outer_w).from_origin();
  const bool two_surfaces = m.posterior_cornea.has_value();
  if (!inner.is_finite() || !outer.is_finite() || front.implicit(outer) <= 0 ||
      front.implicit(inner) >= 0 ||
      (two_surfaces && posterior_surface(m).implicit(inner) >= 0)) {
    out.status = PathStatus::invalid_input;
    return out;
  }
  const double R = m.anterior_cornea.radius_mm;
  // Initial guess (and the answer for one spherical surface): the sphere of
  // the anterior apex with the aqueous index behind it.
  Vector3 x1;
  bool tir = false;
  if (!sphere_refraction(R, m.aqueous_index, inner, outer, x1, tir, out.iterations)) {
    // A sphere with no exit path can still have one after asphericity or a
    // second surface bends it, but near its own horizon only; the sphere's
    // verdict stands for spheres and is a start from the horizon otherwise.
    if (m.anterior_cornea.is_sphere() && !two_surfaces) {
      out.status = PathStatus::total_internal_reflection;
      return out;
    }
    const Plane2 p = plane_for(outer, inner);
    const double theta_max = std::acos(std::clamp(R / outer.norm(), -1.0, 1.0)) * (1 - 1e-3);
    x1 = (p.u * std::cos(theta_max) + p.w * std::sin(theta_max)) * R;
  }
  Vector3 x2;
  if (two_surfaces) {
    const Surface back = posterior_surface(m);
    if (!segment_hits(back, x1, inner, x2)) {
      x2 = inner + (x1 - inner) * 0.5;  // still a usable start
    }
    std::array<double, 4> xy{x1.x, x1.y, x2.x, x2.y};
    int it = 0;
    const bool ok = solve_chain<2>({front, back}, outer, inner,
                                   {1.0, m.posterior_cornea->cornea_index, m.aqueous_index}, xy,
                                   it);
    out.iterations += it;
    if (!ok) {
      out.status = tir ? PathStatus::total_internal_reflection : PathStatus::not_converged;
      return out;
    }
    ChartPoint c1, c2;
    chart_point(front, xy[0], xy[1], c1);
    chart_point(back, xy[2], xy[3], c2);
    x1 = c1.X;
    x2 = c2.X;
    const Vector3 n2 = back.normal(x2);
    // The path must cross the posterior surface outward.
    if (!(dot(x1 - x2, n2) > 0) || !(dot(x2 - inner, n2) > 0)) {
      out.status = PathStatus::no_solution;
      return out;
    }
    out.posterior_point = world_point(eye, x2);
  } else if (!m.anterior_cornea.is_sphere()) {
    std::array<double, 2> xy = chart_start(front, x1);
    int it = 0;
    const bool ok = solve_chain<1>({front}, outer, inner, {1.0, m.aqueous_index}, xy, it);
    out.iterations += it;
    if (!ok) {
      out.status = tir ? PathStatus::total_internal_reflection : PathStatus::not_converged;
      return out;
    }
    ChartPoint c1;
    chart_point(front, xy[0], xy[1], c1);
    x1 = c1.X;
  }
  const Vector3 n1 = front.normal(x1);
  const Vector3 previous = two_surfaces ? x2 : inner;
  if (!(dot(outer - x1, n1) > 0) || !(dot(x1 - previous, n1) > 0)) {
    out.status = PathStatus::no_solution;
    return out;
  }
  out.anterior_point = world_point(eye, x1);
  out.anterior_normal = UnitVector3::normalize(world_vector(eye, n1));
  out.inner_direction = UnitVector3::normalize(world_vector(eye, x1 - previous));
  out.outer_direction = UnitVector3::normalize(world_vector(eye, outer - x1));
  out.inner_angle_rad = angle_between(out.inner_direction, out.anterior_normal);
  out.outer_angle_rad = angle_between(out.outer_direction, out.anterior_normal);
  out.on_cap = eye.on_cap(out.anterior_point);
  out.status = out.on_cap ? PathStatus::ok : PathStatus::off_cornea;
  return out;
}

namespace {

// A spectacle lens's surfaces in its own frame (spectacle_lens.h): the
// solver's conicoids with their apices on the lens axis, curving away
// from +z as the cornea's do from the eye's +z.
struct LensFrame {
  const SpectacleLens* lens_ref;
  Pose lens_from_world;
  Surface front, back;
  double n = 1;

  explicit LensFrame(const SpectacleLens& lens)
      : lens_ref(&lens),
        lens_from_world(lens.world_from_lens.inverse()),
        front{0.0, Conicoid{lens.front_radius_mm, 0.0}},
        back{-lens.center_thickness_mm, Conicoid{lens.back_radius_mm, 0.0}},
        n(lens.refractive_index) {}
  Vector3 local(const Point3& world) const { return (lens_from_world * world).from_origin(); }
  bool in_front(const Vector3& p) const { return lens_side(*lens_ref, Point3::origin() + p) == LensSide::in_front; }
  bool behind(const Vector3& p) const { return lens_side(*lens_ref, Point3::origin() + p) == LensSide::behind; }
};

// Where the segment from a to b first crosses the cap of `s` (a sphere:
// the half toward its apex), if it does.
bool cap_crossing(const Surface& s, const Vector3& a, const Vector3& b, Vector3& hit) {
  const Vector3 c{0, 0, s.apex_z - s.radius()};
  const Vector3 d = b - a, m = a - c;
  const double A = d.squared_norm(), B = dot(m, d), C = m.squared_norm() - s.radius() * s.radius();
  const double disc = B * B - A * C;
  if (!(A > 0) || disc < 0) return false;
  for (const double t : {(-B - std::sqrt(disc)) / A, (-B + std::sqrt(disc)) / A}) {
    if (!(t >= 0 && t <= 1)) continue;
    const Vector3 p = a + d * t;
    if (p.z > c.z) {
      hit = p;
      return true;
    }
  }
  return false;
}

Point3 lens_world(const SpectacleLens& lens, const Vector3& p) {
  return lens.world_from_lens * (Point3::origin() + p);
}

// A chart point on a lens surface, inside the outline.
bool lens_chart_point(const SpectacleLens& lens, const Surface& s, double x, double y, Vector3& out) {
  ChartPoint c;
  if (!chart_point(s, x, y, c)) return false;
  out = c.X;
  return inside_outline(lens, Point3::origin() + c.X);
}

}  // namespace

namespace {

// solve_lens_passage, started from `start` (chart coordinates on the
// front and back surfaces) when given instead of the straight segment's
// crossings: a neighbour of a solved passage converges in fewer steps.
LensPassage passage(const SpectacleLens& lens, const Point3& from_w, const Point3& to_w,
                    const std::array<double, 4>* start) {
  LensPassage out;
  const LensFrame f(lens);
  const Vector3 from = f.local(from_w), to = f.local(to_w);
  if (!from.is_finite() || !to.is_finite() || !((f.in_front(from) && f.behind(to)) ||
                                                (f.in_front(to) && f.behind(from)))) {
    out.status = PathStatus::invalid_input;
    return out;
  }
  const bool from_in_front = f.in_front(from);
  const Vector3& outer = from_in_front ? from : to;
  const Vector3& inner = from_in_front ? to : from;
  // Start where the straight segment crosses the surfaces.
  std::array<double, 4> xy{};
  if (start) {
    xy = *start;
  } else {
    Vector3 h1, h2;
    if (!cap_crossing(f.front, outer, inner, h1) || !cap_crossing(f.back, outer, inner, h2)) return out;
    const std::array<double, 2> c1 = chart_start(f.front, h1), c2 = chart_start(f.back, h2);
    xy = {c1[0], c1[1], c2[0], c2[1]};
  }
  if (!solve_chain<2>({f.front, f.back}, outer, inner, {1.0, f.n, 1.0}, xy, out.iterations)) {
    // The spheres go on past the outline, and the solver can leave it
    // toward a path that only they have: then there is none through the
    // lens. Not converged within it is the solver's failure.
    Vector3 x1, x2;
    const bool inside = lens_chart_point(lens, f.front, xy[0], xy[1], x1) && lens_chart_point(lens, f.back, xy[2], xy[3], x2);
    out.status = inside ? PathStatus::not_converged : PathStatus::no_solution;
    return out;
  }
  Vector3 x1, x2;
  if (!lens_chart_point(lens, f.front, xy[0], xy[1], x1) || !lens_chart_point(lens, f.back, xy[2], xy[3], x2)) {
    return out;  // through the edge: no_solution
  }
  // Each surface crossed from its outer side inward (toward -z).
  const Vector3 n1 = f.front.normal(x1), n2 = f.back.normal(x2);
  if (!(dot(x1 - outer, n1) < 0) || !(dot(x2 - x1, n1) < 0) || !(dot(x2 - x1, n2) < 0) ||
      !(dot(inner - x2, n2) < 0)) {
    return out;
  }
  const Point3 p1 = lens_world(lens, x1), p2 = lens_world(lens, x2);
  // Out of the glass: the front sphere's outward normal, the back's inward.
  const UnitVector3 m1 = UnitVector3::normalize(lens.world_from_lens * n1);
  const UnitVector3 m2 = UnitVector3::normalize(lens.world_from_lens * -n2);
  out.first = from_in_front ? p1 : p2;
  out.second = from_in_front ? p2 : p1;
  out.first_normal = from_in_front ? m1 : m2;
  out.second_normal = from_in_front ? m2 : m1;
  out.leaving = UnitVector3::normalize(out.first - from_w);
  out.inside = UnitVector3::normalize(out.second - out.first);
  out.arriving = UnitVector3::normalize(to_w - out.second);
  out.status = PathStatus::ok;
  return out;
}

}  // namespace

LensPassage solve_lens_passage(const SpectacleLens& lens, const Point3& from, const Point3& to) {
  return passage(lens, from, to, nullptr);
}

LightThroughLens light_through_lens(const SpectacleLens& lens, const Point3& light, const Point3& near) {
  LightThroughLens out;
  out.passage = solve_lens_passage(lens, near, light);
  out.status = out.passage.status;
  if (out.status != PathStatus::ok) return out;
  // The neighbours start from this passage: light on the front side, so
  // its second point is on the front surface, its first on the back.
  const Pose lens_from_world = lens.world_from_lens.inverse();
  const Point3 on_front = lens_from_world * out.passage.second, on_back = lens_from_world * out.passage.first;
  const std::array<double, 4> start{on_front.x, on_front.y, on_back.x, on_back.y};
  const UnitVector3 d0 = out.passage.leaving;
  const UnitVector3 e1 = UnitVector3::normalize(cross(d0, std::abs(d0.x()) < 0.9 ? Vector3{1, 0, 0} : Vector3{0, 1, 0}));
  const UnitVector3 e2 = UnitVector3::normalize(cross(d0, e1));
  const double h = 1e-4 * distance(near, light);
  // Per axis: how the leaving direction at `near` and the arriving one at
  // the light turn as `near` moves across.
  Vector3 leaving_rate[2], arriving_rate[2];
  for (int axis = 0; axis < 2; ++axis) {
    const UnitVector3& e = axis == 0 ? e1 : e2;
    const LensPassage plus = passage(lens, near + e * h, light, &start);
    const LensPassage minus = passage(lens, near - e * h, light, &start);
    if (plus.status != PathStatus::ok || minus.status != PathStatus::ok) {
      out.status = plus.status != PathStatus::ok ? plus.status : minus.status;
      return out;
    }
    leaving_rate[axis] = (plus.leaving.vector() - minus.leaving.vector()) / (2 * h);
    arriving_rate[axis] = (plus.arriving.vector() - minus.arriving.vector()) / (2 * h);
  }
  // Directions from a point at distance s along d0 turn by -e / s per unit
  // of sideways move: the vergence 1/s.
  out.vergence_per_mm = -0.5 * (dot(leaving_rate[0], e1) + dot(leaving_rate[1], e2));
  out.solid_angle_per_area = std::abs(dot(cross(arriving_rate[0], arriving_rate[1]), out.passage.arriving));
  if (!std::isfinite(out.vergence_per_mm) || !std::isfinite(out.solid_angle_per_area)) {
    out.status = PathStatus::no_solution;
  }
  return out;
}

LensReflection solve_lens_reflection(const SpectacleLens& lens, LensSurface surface, const Point3& source_w,
                                     const Point3& target_w) {
  LensReflection out;
  out.surface = surface;
  const LensFrame f(lens);
  const Vector3 source = f.local(source_w), target = f.local(target_w);
  if (!source.is_finite() || !target.is_finite() || !f.in_front(source) || !f.in_front(target)) {
    out.status = PathStatus::invalid_input;
    return out;
  }
  const Point3 front_centre = lens_world(lens, {0, 0, -lens.front_radius_mm});
  const Point3 back_centre = lens_world(lens, {0, 0, -lens.center_thickness_mm - lens.back_radius_mm});
  if (surface == LensSurface::front) {
    // A convex mirror: the sphere's solution, on the cap within the outline.
    out.mirror = solve_sphere_reflection(front_centre, lens.front_radius_mm, source_w, target_w);
    if (out.mirror.status != PathStatus::ok) {
      out.status = out.mirror.status;
      return out;
    }
    const Point3 p = f.lens_from_world * out.mirror.point;
    if (!(p.z > -lens.front_radius_mm) || !inside_outline(lens, p)) return out;
    out.entry = out.exit = out.mirror.point;
    out.from_source = out.mirror.incident;
    out.to_target = out.mirror.reflected;
    out.status = PathStatus::ok;
    return out;
  }
  // The back surface: target -> front (x1) -> back (q) -> front (x3) ->
  // source, started from the back sphere's own mirror point as if the
  // glass did not bend the light.
  const Reflection guess = solve_sphere_reflection(back_centre, lens.back_radius_mm, source_w, target_w);
  const Vector3 q0 = guess.status == PathStatus::ok ? f.local(guess.point) : Vector3{0, 0, -lens.center_thickness_mm};
  Vector3 h1, h3;
  if (!cap_crossing(f.front, target, q0, h1) || !cap_crossing(f.front, source, q0, h3)) return out;
  const std::array<double, 2> c1 = chart_start(f.front, h1), cq = chart_start(f.back, q0),
                              c3 = chart_start(f.front, h3);
  std::array<double, 6> xy{c1[0], c1[1], cq[0], cq[1], c3[0], c3[1]};
  int iterations = 0;
  if (!solve_chain<3>({f.front, f.back, f.front}, target, source, {1.0, f.n, f.n, 1.0}, xy, iterations)) {
    out.mirror.iterations = iterations;
    out.status = PathStatus::not_converged;
    return out;
  }
  Vector3 x1, q, x3;
  if (!lens_chart_point(lens, f.front, xy[0], xy[1], x1) || !lens_chart_point(lens, f.back, xy[2], xy[3], q) ||
      !lens_chart_point(lens, f.front, xy[4], xy[5], x3)) {
    return out;
  }
  // In through the front, mirrored on the glass's side of the back, out
  // through the front.
  const Vector3 n1 = f.front.normal(x1), nq = f.back.normal(q), n3 = f.front.normal(x3);
  if (!(dot(x1 - target, n1) < 0) || !(dot(q - x1, n1) < 0) || !(dot(x1 - q, nq) > 0) || !(dot(x3 - q, nq) > 0) ||
      !(dot(x3 - q, n3) > 0) || !(dot(source - x3, n3) > 0)) {
    return out;
  }
  Reflection& m = out.mirror;
  m.point = lens_world(lens, q);
  m.normal = UnitVector3::normalize(lens.world_from_lens * nq);
  m.incident = UnitVector3::normalize(lens.world_from_lens * (q - x3));
  m.reflected = UnitVector3::normalize(lens.world_from_lens * (x1 - q));
  m.incidence_rad = angle_between(-m.incident.vector(), m.normal);
  m.iterations = iterations;
  m.status = PathStatus::ok;
  out.entry = lens_world(lens, x3);
  out.exit = lens_world(lens, x1);
  out.from_source = UnitVector3::normalize(out.entry - source_w);
  out.to_target = UnitVector3::normalize(target_w - out.exit);
  out.status = PathStatus::ok;
  return out;
}

double reflection_residual_rad(const Reflection& r) {
  const Vector3 d = r.incident.vector();
  const Vector3 n = r.normal.vector();
  const Vector3 mirrored = d - n * (2.0 * dot(d, n));
  return angle_between(mirrored, r.reflected);
}

double refraction_residual_rad(const Eye& eye, const Refraction& r) {
  const EyeModel& m = eye.model();
  const double n_in = m.posterior_cornea ? m.posterior_cornea->cornea_index : m.aqueous_index;
  const Vector3 d = r.inner_direction.vector();
  const Vector3 n = r.anterior_normal.vector();
  const double ci = dot(d, n);
  const double k = 1.0 - n_in * n_in * (1.0 - ci * ci);
  if (k < 0) return kPi;  // Snell has no transmitted ray here
  const Vector3 t = d * n_in - n * (n_in * ci - std::sqrt(k));
  return angle_between(t, r.outer_direction);
}

}  // namespace purkinje
