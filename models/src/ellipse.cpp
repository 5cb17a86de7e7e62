// Direct least-squares ellipse fit: R. Halir and J. Flusser, "Numerically
// stable direct least squares fitting of ellipses", WSCG 1998 (the stable
// form of Fitzgibbon, Pilu and Fisher's method).

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <optional>
#include <utility>
#include <vector>

#include "purkinje/models/truth.h"

namespace purkinje {

namespace {

// Conic A x^2 + B x y + C y^2 + D x + E y + F = 0.
using Conic = Eigen::Matrix<double, 6, 1>;

// Wraps an axis orientation (defined modulo pi) into (-pi/2, pi/2].
double wrap_axis_angle(double angle) {
  constexpr double pi = std::numbers::pi;
  angle = std::remainder(angle, pi);  // [-pi/2, pi/2]
  return angle <= -pi / 2 ? angle + pi : angle;
}

}  // namespace

std::optional<Ellipse> fit_ellipse(const std::vector<Pixel>& points) {
  const auto n = static_cast<Eigen::Index>(points.size());
  if (n < 6) return std::nullopt;

  // Whiten the points: centre them and scale along the principal axes of
  // their scatter so that both have unit RMS. Pupil images are ~30 px across
  // at ~1000 px from the origin, and may be thin; in whitened coordinates a
  // well-sampled ellipse is close to a circle and the fit well conditioned.
  // The fit is affine-equivariant (the constraint 4AC - B^2 only scales
  // under a linear map), so this changes rounding, not the answer.
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const Pixel& p : points) {
    if (!std::isfinite(p.u) || !std::isfinite(p.v)) return std::nullopt;
    mean += Eigen::Vector2d(p.u, p.v);
  }
  mean /= static_cast<double>(n);
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const Pixel& p : points) {
    const Eigen::Vector2d d = Eigen::Vector2d(p.u, p.v) - mean;
    scatter += d * d.transpose();
  }
  scatter /= static_cast<double>(n);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> principal(scatter);
  const Eigen::Vector2d variances = principal.eigenvalues();  // ascending
  // Collinear (or coincident) points have no spread across their line.
  if (!(variances(0) > 1e-20 * variances(1)) || !(variances(1) > 0)) return std::nullopt;
  const Eigen::Matrix2d axes = principal.eigenvectors();
  const Eigen::Vector2d spreads = variances.cwiseSqrt();

  // The design matrix split into quadratic and linear parts (Halir-Flusser).
  Eigen::MatrixX3d quadratic(n, 3), linear(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Pixel& p = points[static_cast<size_t>(i)];
    const Eigen::Vector2d w =
        (axes.transpose() * (Eigen::Vector2d(p.u, p.v) - mean)).cwiseQuotient(spreads);
    quadratic.row(i) << w.x() * w.x(), w.x() * w.y(), w.y() * w.y();
    linear.row(i) << w.x(), w.y(), 1;
  }
  const Eigen::Matrix3d s1 = quadratic.transpose() * quadratic;
  const Eigen::Matrix3d s2 = quadratic.transpose() * linear;
  const Eigen::Matrix3d s3 = linear.transpose() * linear;

  // S3 is singular when the points are collinear; whitened, it is close to
  // n times the identity otherwise.
  const Eigen::FullPivLU<Eigen::Matrix3d> s3_lu(s3);
  if (s3_lu.rank() < 3) return std::nullopt;
  const Eigen::Matrix3d t = -s3_lu.solve(s2.transpose());  // linear part = T * quadratic part
  const Eigen::Matrix3d reduced_scatter = s1 + s2 * t;
  // Fewer than five points in general position leave a family of conics.
  const Eigen::JacobiSVD<Eigen::Matrix3d> reduced_svd(reduced_scatter);
  if (!(reduced_svd.singularValues()(1) > 1e-12 * reduced_svd.singularValues()(0))) {
    return std::nullopt;
  }
  // Premultiply by the inverse of the constraint matrix C1 = [0 0 2; 0 -1 0; 2 0 0].
  Eigen::Matrix3d m;
  m.row(0) = reduced_scatter.row(2) / 2;
  m.row(1) = -reduced_scatter.row(1);
  m.row(2) = reduced_scatter.row(0) / 2;

  const Eigen::EigenSolver<Eigen::Matrix3d> eigen(m);
  if (eigen.info() != Eigen::Success) return std::nullopt;

  // Exactly one eigenvector satisfies the ellipse constraint 4AC - B^2 > 0
  // in exact arithmetic; with rounding, keep the candidate whose algebraic
  // error under that normalization is smallest.
  std::optional<Conic> best;
  double best_error = 0;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3cd vc = eigen.eigenvectors().col(k);
    if (vc.imag().norm() > 1e-9 * vc.real().norm()) continue;
    Eigen::Vector3d quadratic_part = vc.real();
    const double constraint = 4 * quadratic_part(0) * quadratic_part(2) -
                              quadratic_part(1) * quadratic_part(1);
    if (!(constraint > 0)) continue;
    quadratic_part /= std::sqrt(constraint);
    Conic conic;
    conic << quadratic_part, t * quadratic_part;
    const double error = (quadratic * conic.head<3>() + linear * conic.tail<3>()).squaredNorm();
    if (!best || error < best_error) {
      best = conic;
      best_error = error;
    }
  }
  if (!best) return std::nullopt;

  double a = (*best)(0), b = (*best)(1), c = (*best)(2), d = (*best)(3), e = (*best)(4),
         f = (*best)(5);
  // Make the quadratic form positive definite (the sign of a conic is free).
  if (a + c < 0) {
    a = -a, b = -b, c = -c, d = -d, e = -e, f = -f;
  }
  const double det = 4 * a * c - b * b;
  if (!(det > 0)) return std::nullopt;
  // Centre in whitened coordinates, and the conic's value there: the
  // ellipse is (w - w0)^T Q (w - w0) = -f0 with Q = [a b/2; b/2 c].
  const Eigen::Vector2d w0((b * e - 2 * c * d) / det, (b * d - 2 * a * e) / det);
  const double f0 = f + (d * w0.x() + e * w0.y()) / 2;
  if (!(-f0 > 0)) return std::nullopt;  // an imaginary ellipse

  // Back along the principal axes (unwhitened, unrotated): z = spreads * w,
  // so the ellipse is (z - z0)^T G (z - z0) = 1 with G below. For a thin,
  // well-sampled ellipse G is nearly diagonal; a Jacobi rotation finds its
  // eigenvalues without the cancellation of the closed-form roots.
  const double g11 = a / (-f0 * spreads(0) * spreads(0));
  const double g22 = c / (-f0 * spreads(1) * spreads(1));
  const double g12 = b / 2 / (-f0 * spreads(0) * spreads(1));
  double lambda_1 = g11, lambda_2 = g22;  // for eigenvectors (cos, -sin), (sin, cos)
  double cos_phi = 1, sin_phi = 0;
  if (g12 != 0) {
    const double theta = (g22 - g11) / (2 * g12);
    const double tan_phi =
        (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1));
    cos_phi = 1 / std::sqrt(tan_phi * tan_phi + 1);
    sin_phi = tan_phi * cos_phi;
    lambda_1 = g11 - tan_phi * g12;
    lambda_2 = g22 + tan_phi * g12;
  }
  if (!(lambda_1 > 0) || !(lambda_2 > 0)) return std::nullopt;
  Eigen::Vector2d direction_1 = axes * Eigen::Vector2d(cos_phi, -sin_phi);
  Eigen::Vector2d direction_2 = axes * Eigen::Vector2d(sin_phi, cos_phi);
  // Semi-axis 1 is the major one: the smaller eigenvalue of G.
  if (lambda_1 > lambda_2) {
    std::swap(lambda_1, lambda_2);
    std::swap(direction_1, direction_2);
  }

  const Eigen::Vector2d center = mean + axes * spreads.cwiseProduct(w0);
  Ellipse ellipse;
  ellipse.center = {center.x(), center.y()};
  ellipse.semi_axis_1_px = 1 / std::sqrt(lambda_1);
  ellipse.semi_axis_2_px = 1 / std::sqrt(lambda_2);
  ellipse.angle_rad = wrap_axis_angle(std::atan2(direction_1.y(), direction_1.x()));
  const bool finite = std::isfinite(ellipse.center.u) && std::isfinite(ellipse.center.v) &&
                      std::isfinite(ellipse.semi_axis_1_px) &&
                      std::isfinite(ellipse.semi_axis_2_px) && std::isfinite(ellipse.angle_rad);
  if (!finite || !(ellipse.semi_axis_2_px > 0)) return std::nullopt;
  return ellipse;
}

}  // namespace purkinje
