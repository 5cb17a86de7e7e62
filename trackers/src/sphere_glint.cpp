#include "purkinje/trackers/sphere_glint.h"

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

}  // namespace

std::optional<SphereGlint> sphere_glint(const Camera& camera, const Point3& center, double radius_mm,
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

  SphereGlint out;
  out.point = {p.x(), p.y(), p.z()};
  out.normal = UnitVector3::from_normalized_unchecked({n.x(), n.y(), n.z()});
  std::array<double, 6> d_pixel_d_point{};
  const Projection projection =
      with_derivatives ? camera.project(out.point, d_pixel_d_point) : camera.project(out.point);
  if (projection.status == ProjectionStatus::behind_camera) return std::nullopt;
  out.pixel = projection.pixel;
  if (!with_derivatives) return out;

  // The implicit function theorem on the law of reflection, m = |m| n
  // with m the sum of the unit directions from P to the light and to the
  // camera. Differentiating, with dm = -A dP, A = (I - l l^T) / |L - P| +
  // (I - o o^T) / |O - P|, dP = dC + n dR + R dn and dn = U y in the
  // tangent plane (U = [u v]):
  //   (|m| I + R U^T A U) y = -U^T A (dC + n dR).
  const double dl = to_light.norm(), dc = to_camera.norm();
  const Vec3 lu = to_light / dl, cu = to_camera / dc;
  const Eigen::Matrix3d a = (Eigen::Matrix3d::Identity() - lu * lu.transpose()) / dl +
                            (Eigen::Matrix3d::Identity() - cu * cu.transpose()) / dc;
  const double m = (lu + cu).norm();
  Vec3 axis = Vec3::Zero();
  int least = 0;
  n.cwiseAbs().minCoeff(&least);
  axis[least] = 1;
  Eigen::Matrix<double, 3, 2> u;
  u.col(0) = n.cross(axis).normalized();
  u.col(1) = n.cross(u.col(0));
  const Eigen::Matrix<double, 2, 3> ua = u.transpose() * a;
  const Eigen::Matrix2d system = m * Eigen::Matrix2d::Identity() + radius_mm * ua * u;
  const Eigen::Matrix2d inverse = system.inverse();
  // dP/d(C, R), 3 x 4: I + R dn/dC, and n + R dn/dR.
  Eigen::Matrix<double, 3, 4> d_point;
  d_point.leftCols<3>() = Eigen::Matrix3d::Identity() - radius_mm * u * inverse * ua;
  d_point.col(3) = n - radius_mm * u * (inverse * (ua * n));
  const Eigen::Map<const Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> d_pixel(d_pixel_d_point.data());
  const Eigen::Matrix<double, 2, 4> chained = d_pixel * d_point;
  for (int row = 0; row < 2; ++row) {
    for (int k = 0; k < 4; ++k) out.d_pixel[4 * row + k] = chained(row, k);
  }
  return out;
}

}  // namespace purkinje::trackers
