#include "purkinje/trackers/cornea_glint.h"

#include <Eigen/Dense>

#include <cmath>

namespace purkinje::trackers {

namespace {

using Vec3 = Eigen::Vector3d;

Vec3 eigen(const Point3& p) { return {p.x, p.y, p.z}; }

// The light's glint lies in the plane through the centre, the light and
// the camera. With e1 toward the light and e2 toward the camera's side,
// the normal is (cos t, sin t), the light at distance a along e1 and the
// camera at distance b at angle g. The law of reflection is
//   f(t) = b sin(g - t) / |B - P| - a sin t / |A - P| = 0,
// positive at t = 0 and negative at t = g: one root, bracketed, found by
// Newton's method kept inside the bracket. It runs on tau = tan(t / 2),
// so that cos t = (1 - tau^2) / (1 + tau^2) and sin t = 2 tau / (1 + tau^2)
// cost no trigonometry.
struct PlanarLayout {
  double a, b, cos_g, sin_g, radius;

  // f at tau, and df/dtau.
  double f(double tau, double& derivative) const {
    const double w = 1 / (1 + tau * tau);
    const double c = (1 - tau * tau) * w, s = 2 * tau * w;
    const double cu = cos_g * c + sin_g * s, su = sin_g * c - cos_g * s;  // of u = g - t
    // Reciprocals once: divisions are the slow part of this loop.
    const double ia = 1 / std::sqrt(a * a + radius * radius - 2 * a * radius * c);  // 1 / |A - P|
    const double ib = 1 / std::sqrt(b * b + radius * radius - 2 * b * radius * cu);
    const double df_dt =
        -b * ib * (cu - b * radius * su * su * ib * ib) - a * ia * (c - a * radius * s * s * ia * ia);
    derivative = df_dt * 2 * w;  // dt/dtau = 2 / (1 + tau^2)
    return b * su * ib - a * s * ia;
  }
};

// The unit normal at the glint, or false when there is none.
bool glint_normal(const Vec3& c, double radius, const Vec3& l, const Vec3& o,
                  const std::optional<UnitVector3>& warm_start, Vec3& normal) {
  const Vec3 to_light = l - c, to_camera = o - c;
  const double a = to_light.norm(), b = to_camera.norm();
  const Vec3 e1 = to_light / a, toward_camera = to_camera / b;
  const double cos_g = toward_camera.dot(e1);
  // off's direction is e2. Its rounding error is about 1e-16 whatever g,
  // and the normal's angle from e1 shrinks with sin g, so even a nearly
  // collinear layout gives a normal good to rounding.
  const Vec3 off = toward_camera - cos_g * e1;
  const double sin_g = off.norm();
  if (!(sin_g > 0)) {
    // Light, centre and camera in line: the glint faces both, or there
    // is none (the light straight behind the eye).
    normal = e1;
    return cos_g > 0;
  }
  const PlanarLayout layout{a, b, cos_g, sin_g, radius};

  double lo = 0, hi = sin_g / (1 + cos_g);  // tau at t = 0 and t = g
  double tau = 0.5 * hi;
  if (warm_start) {
    const Vec3 n(warm_start->x(), warm_start->y(), warm_start->z());
    const double guess = n.dot(off) / sin_g / (1 + n.dot(e1));  // tan(t / 2) = sin t / (1 + cos t)
    if (guess > lo && guess < hi) tau = guess;
  }
  double derivative = 0;
  bool converged = false;
  constexpr int max_iterations = 60;
  for (int i = 0; i < max_iterations && !converged; ++i) {
    const double value = layout.f(tau, derivative);
    if (value == 0) {  // the root itself
      converged = true;
      break;
    }
    if (value > 0) {
      lo = tau;
    } else {
      hi = tau;
    }
    const double next = tau - value / derivative;
    if (next > lo && next < hi) {
      // Newton's error squares with each step: a last step of 1e-9
      // leaves about 1e-18.
      converged = std::abs(next - tau) < 1e-9 * (1 + tau);
      tau = next;
    } else {
      tau = 0.5 * (lo + hi);  // Newton left the bracket
      converged = hi - lo < 1e-15 * (1 + hi);
    }
  }
  if (!converged) return false;
  const double w = 1 / (1 + tau * tau);
  normal = ((1 - tau * tau) * w) * e1 + (2 * tau * w / sin_g) * off;
  return true;
}

// Two unit vectors across n, as the rows of a 2 x 3 matrix.
Eigen::Matrix<double, 2, 3> tangent_basis(const Vec3& n) {
  Vec3 axis = Vec3::Zero();
  int least = 0;
  n.cwiseAbs().minCoeff(&least);
  axis[least] = 1;
  Eigen::Matrix<double, 2, 3> t;
  t.row(0) = n.cross(axis).normalized().transpose();
  t.row(1) = n.cross(t.row(0).transpose()).transpose();
  return t;
}

// The unit directions from P to the light and to the camera, and
// A = (I - l l^T) / |L - P| + (I - o o^T) / |O - P|, minus the derivative
// of their sum by P: what both laws of reflection below differentiate.
struct Directions {
  Vec3 to_light, to_camera;
  Eigen::Matrix3d spread;
};

Directions directions_from(const Vec3& p, const Vec3& l, const Vec3& o) {
  const Vec3 to_light = l - p, to_camera = o - p;
  const double dl = to_light.norm(), dc = to_camera.norm();
  Directions d{to_light / dl, to_camera / dc, Eigen::Matrix3d::Identity()};
  d.spread = (Eigen::Matrix3d::Identity() - d.to_light * d.to_light.transpose()) / dl +
             (Eigen::Matrix3d::Identity() - d.to_camera * d.to_camera.transpose()) / dc;
  return d;
}

// d(pixel)/d(centre, radius) from d(pixel)/dP and dP/d(centre, radius).
void chain(const std::array<double, 6>& d_pixel_d_point, const Eigen::Matrix<double, 3, 4>& d_point,
           CorneaGlint& out) {
  const Eigen::Map<const Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> d_pixel(d_pixel_d_point.data());
  const Eigen::Matrix<double, 2, 4> chained = d_pixel * d_point;
  for (int row = 0; row < 2; ++row) {
    for (int k = 0; k < 4; ++k) out.d_pixel[4 * row + k] = chained(row, k);
  }
}

// The law of reflection on a conicoid, in world terms. With s = P - C and
// z = a.s along the axis a, the surface x^2 + y^2 + (1 + Q) w^2 - 2 R w = 0
// (w = R - z from the apex) is
//   F = |s|^2 - z^2 + (1 + Q)(R - z)^2 - 2 R (R - z) = 0,
// with gradient g = 2 s - 2 Q (R - z) a (outward) and Hessian
// H = 2 I + 2 Q a a^T. The glint solves E(P) = 0: F / |g| and the
// tangent components of hu - n, hu the unit sum of the directions from P
// to the light and to the camera, n = g / |g|.
struct ConicoidReflection {
  Vec3 c, a, l, o;
  double radius, q;
  Eigen::Matrix3d hessian;

  struct At {
    Vec3 residual, n;
    Eigen::Matrix3d jacobian;             // dE/dP
    Eigen::Matrix<double, 2, 3> tangent;  // rows: a basis of the tangent plane
    double g_norm = 0;
    double z = 0;  // a.(P - C)
  };

  At at(const Vec3& p) const {
    At e;
    const Vec3 s = p - c;
    e.z = a.dot(s);
    const double z = e.z;
    const Vec3 g = 2 * s - 2 * q * (radius - z) * a;
    e.g_norm = g.norm();
    e.n = g / e.g_norm;
    const double f = s.squaredNorm() - z * z + (1 + q) * (radius - z) * (radius - z) - 2 * radius * (radius - z);
    const Directions d = directions_from(p, l, o);
    const Vec3 h = d.to_light + d.to_camera;
    const double h_norm = h.norm();
    const Vec3 hu = h / h_norm;
    e.tangent = tangent_basis(e.n);
    const Eigen::Matrix3d i3 = Eigen::Matrix3d::Identity();
    // dF/dP / |g| = n where F = 0; the tangent basis is held fixed, which
    // costs nothing at the answer, where hu - n = 0.
    e.jacobian.row(0) = e.n.transpose();
    e.jacobian.bottomRows<2>() = e.tangent * (-(i3 - hu * hu.transpose()) * d.spread / h_norm -
                                              (i3 - e.n * e.n.transpose()) * hessian / e.g_norm);
    e.residual = {f / e.g_norm, e.tangent.row(0).dot(hu - e.n), e.tangent.row(1).dot(hu - e.n)};
    return e;
  }
};

// The glint at P with normal n as the camera images it (with
// d(pixel)/dP when asked); nullopt behind the camera.
std::optional<CorneaGlint> imaged(const Camera& camera, const Vec3& p, const Vec3& n, bool with_derivatives,
                                  std::array<double, 6>& d_pixel_d_point) {
  CorneaGlint out;
  out.point = {p.x(), p.y(), p.z()};
  out.normal = UnitVector3::from_normalized_unchecked({n.x(), n.y(), n.z()});
  const Projection projection =
      with_derivatives ? camera.project(out.point, d_pixel_d_point) : camera.project(out.point);
  if (projection.status == ProjectionStatus::behind_camera) return std::nullopt;
  out.pixel = projection.pixel;
  return out;
}

}  // namespace

std::optional<CorneaGlint> sphere_glint(const Camera& camera, const Point3& center, double radius_mm,
                                        const Point3& light, const std::optional<UnitVector3>& warm_start,
                                        bool with_derivatives) {
  if (!(radius_mm > 0) || !center.is_finite() || !light.is_finite()) return std::nullopt;
  const Vec3 c = eigen(center), l = eigen(light), o = eigen(camera.center());
  if (!((l - c).norm() > radius_mm) || !((o - c).norm() > radius_mm)) return std::nullopt;
  Vec3 n;
  if (!glint_normal(c, radius_mm, l, o, warm_start, n)) return std::nullopt;
  const Vec3 p = c + radius_mm * n;
  const Vec3 to_light = l - p, to_camera = o - p;
  // Past grazing, the point cannot see the light or the camera.
  if (!(to_light.dot(n) > 0) || !(to_camera.dot(n) > 0)) return std::nullopt;

  std::array<double, 6> d_pixel_d_point{};
  std::optional<CorneaGlint> out = imaged(camera, p, n, with_derivatives, d_pixel_d_point);
  if (!out || !with_derivatives) return out;

  // The implicit function theorem on the law of reflection, m = |m| n
  // with m the sum of the unit directions from P to the light and to the
  // camera. Differentiating, with dm = -A dP, A = (I - l l^T) / |L - P| +
  // (I - o o^T) / |O - P|, dP = dC + n dR + R dn and dn = U y in the
  // tangent plane (U = [u v]):
  //   (|m| I + R U^T A U) y = -U^T A (dC + n dR).
  const Directions d = directions_from(p, l, o);
  const double m = (d.to_light + d.to_camera).norm();
  const Eigen::Matrix<double, 3, 2> u = tangent_basis(n).transpose();
  const Eigen::Matrix<double, 2, 3> ua = u.transpose() * d.spread;
  const Eigen::Matrix2d system = m * Eigen::Matrix2d::Identity() + radius_mm * ua * u;
  const Eigen::Matrix2d inverse = system.inverse();
  // dP/d(C, R), 3 x 4: I + R dn/dC, and n + R dn/dR.
  Eigen::Matrix<double, 3, 4> d_point;
  d_point.leftCols<3>() = Eigen::Matrix3d::Identity() - radius_mm * u * inverse * ua;
  d_point.col(3) = n - radius_mm * u * (inverse * (ua * n));
  chain(d_pixel_d_point, d_point, *out);
  return out;
}

std::optional<CorneaGlint> conicoid_glint(const Camera& camera, const Point3& center, const UnitVector3& optical_axis,
                                          const Conicoid& cornea, const Point3& light,
                                          const std::optional<UnitVector3>& warm_start, bool with_derivatives) {
  if (cornea.is_sphere()) {
    return sphere_glint(camera, center, cornea.radius_mm, light, warm_start, with_derivatives);
  }
  const double radius = cornea.radius_mm, q = cornea.asphericity;
  if (!(q > -1) || !std::isfinite(q)) return std::nullopt;
  // The apex sphere osculates the conicoid at the apex: its glint is the start.
  const std::optional<CorneaGlint> start = sphere_glint(camera, center, radius, light, warm_start, false);
  if (!start) return std::nullopt;
  const Vec3 a(optical_axis.x(), optical_axis.y(), optical_axis.z());
  const ConicoidReflection law{eigen(center), a, eigen(light), eigen(camera.center()), radius, q,
                               2 * Eigen::Matrix3d::Identity() + 2 * q * a * a.transpose()};
  Vec3 p = eigen(start->point);
  bool converged = false;
  for (int i = 0; i < 30 && !converged; ++i) {
    const ConicoidReflection::At e = law.at(p);
    Vec3 step = -e.jacobian.partialPivLu().solve(e.residual);
    if (!step.allFinite()) return std::nullopt;
    // Newton's error squares with each step: after a step of 1e-8 R,
    // rounding is left.
    converged = step.norm() < 1e-8 * radius;
    const double longest = 0.25 * radius;  // a long step would leave the cap
    if (step.norm() > longest) step *= longest / step.norm();
    p += step;
  }
  if (!converged) return std::nullopt;
  const ConicoidReflection::At e = law.at(p);
  // Beyond the equator (w > R / (1 + Q)) the surface faces into the head.
  if (!(e.z > radius - radius / (1 + q))) return std::nullopt;
  if (!((law.l - p).dot(e.n) > 0) || !((law.o - p).dot(e.n) > 0)) return std::nullopt;

  std::array<double, 6> d_pixel_d_point{};
  std::optional<CorneaGlint> out = imaged(camera, p, e.n, with_derivatives, d_pixel_d_point);
  if (!out || !with_derivatives) return out;

  // The implicit function theorem on the same equations: dP/d(C, R) =
  // -(dE/dP)^-1 dE/d(C, R). F depends on C through s (dF/dC = -g) and on
  // R directly; n through g (dg/dC = -H, dg/dR = -2 Q a).
  Eigen::Matrix<double, 3, 4> d_equations;
  d_equations.block<1, 3>(0, 0) = -e.n.transpose();
  d_equations(0, 3) = (2 * q * (radius - e.z) - 2 * radius) / e.g_norm;
  d_equations.block<2, 3>(1, 0) = e.tangent * law.hessian / e.g_norm;
  d_equations.block<2, 1>(1, 3) = e.tangent * (2 * q * a) / e.g_norm;
  chain(d_pixel_d_point, -e.jacobian.partialPivLu().solve(d_equations), *out);
  return out;
}

}  // namespace purkinje::trackers
