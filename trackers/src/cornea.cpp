#include "purkinje/trackers/cornea.h"

#include <Eigen/Dense>

#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include "purkinje/models/eye.h"
#include "purkinje/models/optimizer.h"
#include "purkinje/models/specular.h"

namespace purkinje::trackers {

namespace {

struct Observed {
  Point3 light;
  Pixel pixel;
};

// A spherical cornea centred at `c`, facing the camera: a sphere's glints
// do not depend on its axis, only the corneal cap's border does, and the
// glints a camera sees lie on the side facing it.
std::optional<Eye> eye_at(const Camera& camera, const EyeModel& model, const Point3& c) {
  const Vector3 toward = camera.center() - c;
  if (!(toward.norm() > 0)) return std::nullopt;
  return Eye::with_cornea_center(model, c, UnitVector3::normalize(toward));
}

// Where the eye puts a light's glint in the camera; false when there is
// no glint there.
bool glint_pixel(const Camera& camera, const Eye& eye, const Point3& light, Pixel& pixel) {
  const Reflection r = solve_reflection(eye, light, camera.center());
  if (r.status != PathStatus::ok) return false;
  const Projection p = camera.project(r.point);
  if (p.status == ProjectionStatus::behind_camera) return false;
  pixel = p.pixel;
  return true;
}

}  // namespace

CorneaCenterEstimate estimate_cornea_center(const Camera& camera, const std::vector<Illuminator>& lights,
                                            const std::vector<Glint>& glints, const Point3& start,
                                            const CorneaCenterSettings& s) {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("CorneaCenterSettings: " + what); };
  if (!(s.cornea_radius_mm > 0 && s.cornea_radius_mm < 100)) {
    fail("cornea_radius_mm = " + std::to_string(s.cornea_radius_mm) + ": must be in (0, 100)");
  }
  if (!(s.pixel_noise_px > 0 && std::isfinite(s.pixel_noise_px))) {
    fail("pixel_noise_px = " + std::to_string(s.pixel_noise_px) + ": must be > 0");
  }
  if (!(s.max_condition > 1)) fail("max_condition = " + std::to_string(s.max_condition) + ": must be > 1");

  std::vector<Observed> observed;
  for (const Glint& g : glints) {
    if (g.illuminator < 0) continue;
    if (g.illuminator >= static_cast<int>(lights.size())) {
      throw std::invalid_argument("estimate_cornea_center: a glint of light " + std::to_string(g.illuminator) +
                                  " of " + std::to_string(lights.size()));
    }
    observed.push_back({lights[g.illuminator].position, g.centre});
  }
  EyeModel model = keratometric_eye();
  model.anterior_cornea = {s.cornea_radius_mm, 0.0};
  model.limbus_radius_mm = std::min(model.limbus_radius_mm, 0.95 * s.cornea_radius_mm);
  model.iris_radius_mm = std::min(model.iris_radius_mm, model.limbus_radius_mm);
  model.pupil_radius_mm = std::min(model.pupil_radius_mm, 0.5 * model.iris_radius_mm);

  CorneaCenterEstimate out;
  out.center = start;
  out.glints_used = static_cast<int>(observed.size());
  if (observed.size() < 2) {
    out.warnings.push_back("fewer than two glints with their light told: the cornea's centre is not determined");
    return out;
  }

  const int m = 2 * static_cast<int>(observed.size());
  // Residuals: predicted less observed pixels; the Jacobian by central
  // differences (the solver's glint is smooth in the centre).
  const auto predict = [&](const double* x, double* r) {
    const std::optional<Eye> eye = eye_at(camera, model, {x[0], x[1], x[2]});
    if (!eye) return false;
    for (std::size_t i = 0; i < observed.size(); ++i) {
      Pixel p;
      if (!glint_pixel(camera, *eye, observed[i].light, p)) return false;
      r[2 * i] = p.u - observed[i].pixel.u;
      r[2 * i + 1] = p.v - observed[i].pixel.v;
    }
    return true;
  };
  constexpr double kStep = 1e-5;  // mm: the solver's glints are good to about 1e-10 mm
  std::vector<double> plus(m), minus(m);
  const optimizer::ResidualFunction residuals = [&](const double* x, double* r, double* jacobian) {
    if (!predict(x, r)) return false;
    if (!jacobian) return true;
    for (int k = 0; k < 3; ++k) {
      double xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]};
      xp[k] += kStep, xm[k] -= kStep;
      if (!predict(xp, plus.data()) || !predict(xm, minus.data())) return false;
      for (int i = 0; i < m; ++i) jacobian[3 * i + k] = (plus[i] - minus[i]) / (2 * kStep);
    }
    return true;
  };
  std::array<double, 3> x{start.x, start.y, start.z};
  const optimizer::Summary summary = optimizer::solve(m, x, residuals);
  out.center = {x[0], x[1], x[2]};
  out.converged = summary.converged;

  std::vector<double> r(m), jacobian(3 * m);
  if (!residuals(x.data(), r.data(), jacobian.data())) {
    out.converged = false;
    out.warnings.push_back("no glint of some light on a cornea at the estimate: the fit failed");
    return out;
  }
  double sum = 0;
  for (const double e : r) sum += e * e;
  out.rms_residual_px = std::sqrt(sum / m);
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>> j(jacobian.data(), m, 3);
  const Eigen::Matrix3d normal = j.transpose() * j;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(normal);
  const double lo = eigen.eigenvalues()(0), hi = eigen.eigenvalues()(2);
  out.condition = lo > 0 ? hi / lo : INFINITY;
  if (!(out.condition <= s.max_condition)) {
    out.warnings.push_back("the glints hardly constrain the centre along one direction (condition " +
                           std::to_string(out.condition) + "): it is not identifiable from them");
    if (!std::isfinite(out.condition)) out.condition = 0;
    return out;
  }
  const Eigen::Matrix3d covariance = s.pixel_noise_px * s.pixel_noise_px * normal.inverse();
  std::array<double, 9> c{};
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) c[3 * a + b] = covariance(a, b);
  }
  out.covariance_mm2 = c;
  if (!out.converged) out.warnings.push_back("the fit stopped before converging: " + summary.message);
  return out;
}

}  // namespace purkinje::trackers
