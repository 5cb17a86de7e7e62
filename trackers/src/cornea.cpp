#include "purkinje/trackers/cornea.h"
#include "purkinje/models/check.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>

#include "purkinje/models/optimizer.h"
#include "purkinje/trackers/cornea_glint.h"

namespace purkinje::trackers {

namespace {

// Beyond this, J^T J's inverse is rounding noise in double precision: the
// glints do not determine the unknowns at all.
constexpr double kSingularCondition = 1e12;

using check::format_number;
// Warnings' numbers: three significant digits read better than every digit.
std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", value);
  return text;
}

void check(const CorneaFitSettings& s) {
  const auto fail = [](const std::string& key, double value, const std::string& rule) {
    throw std::invalid_argument("CorneaFitSettings: " + key + " = " + format_number(value) + ": " + rule);
  };
  if (!(s.cornea_radius_mm > 0 && s.cornea_radius_mm < 100)) {
    fail("cornea_radius_mm", s.cornea_radius_mm, "must be in (0, 100)");
  }
  if (!(s.radius_prior_sd_mm >= 0 && std::isfinite(s.radius_prior_sd_mm))) {
    fail("radius_prior_sd_mm", s.radius_prior_sd_mm, "must be >= 0 (0: no prior)");
  }
  if (!(s.pixel_noise_px > 0 && std::isfinite(s.pixel_noise_px))) {
    fail("pixel_noise_px", s.pixel_noise_px, "must be > 0");
  }
  if (!(s.max_sd_mm > 0)) fail("max_sd_mm", s.max_sd_mm, "must be > 0");
  if (!(s.cornea_asphericity > -1 && s.cornea_asphericity < 10)) {
    fail("cornea_asphericity", s.cornea_asphericity, "must be in (-1, 10): an ellipsoid's Q");
  }
}

// The direction an uncertainty runs along, for a warning.
std::string direction(const Eigen::Vector3d& v) {
  char text[96];
  std::snprintf(text, sizeof text, "(%.3g, %.3g, %.3g)", v.x(), v.y(), v.z());
  return text;
}

// A start for one frame's centre from one camera's glints, exact for
// exact glints of a sphere (the construction of Guestrin and Eizenman
// 2006): each glint's ray and its light span a plane through the camera
// and the centre, so the centre lies on the planes' common line; along
// it, the depth is where the rays meet the sphere at points whose normals
// obey the law of reflection. nullopt when the planes do not meet in a
// line (lights in line with the camera and the eye) or no depth fits.
std::optional<Point3> closed_form_center(const Camera& camera, const std::vector<Illuminator>& lights,
                                         const std::vector<GlintObservation>& glints, int frame,
                                         int camera_index, double radius) {
  struct Ray {
    Eigen::Vector3d light, direction, plane_normal;
  };
  const Point3 o = camera.center();
  const Eigen::Vector3d origin(o.x, o.y, o.z);
  std::vector<Ray> rays;
  Eigen::Matrix3d planes = Eigen::Matrix3d::Zero();
  for (const GlintObservation& g : glints) {
    if (g.frame != frame || g.camera != camera_index) continue;
    const UnitVector3 ray = camera.back_project(g.pixel);
    const Point3& l = lights[g.light].position;
    const Eigen::Vector3d light(l.x, l.y, l.z), direction(ray.x(), ray.y(), ray.z());
    const Eigen::Vector3d normal = (light - origin).cross(direction);
    if (!(normal.norm() > 1e-12 * (light - origin).norm())) continue;  // a light on its own glint's ray
    rays.push_back({light, direction, normal.normalized()});
    planes += rays.back().plane_normal * rays.back().plane_normal.transpose();
  }
  if (rays.size() < 2) return std::nullopt;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(planes);
  // Planes that (nearly) coincide leave the line undetermined.
  if (!(eigen.eigenvalues()(1) > 1e-8 * eigen.eigenvalues()(2))) return std::nullopt;
  Eigen::Vector3d d = eigen.eigenvectors().col(0);
  if (d.dot(rays[0].direction) < 0) d = -d;

  // Mean over the glints of the signed angle (its sine) from the normal
  // where the ray meets a sphere centred at depth `depth` to the law of
  // reflection's normal there; `missed` when some ray passes the sphere by.
  const auto mismatch = [&](double depth, bool& missed) {
    double sum = 0;
    missed = false;
    for (const Ray& r : rays) {
      const double along = r.direction.dot(d);
      const double discriminant = radius * radius - depth * depth * (1 - along * along);
      if (discriminant < 0) {
        missed = true;
        return 0.0;
      }
      const Eigen::Vector3d p = origin + (depth * along - std::sqrt(discriminant)) * r.direction;
      const Eigen::Vector3d n = (p - (origin + depth * d)) / radius;
      const Eigen::Vector3d bisector = (r.light - p).normalized() - r.direction;
      sum += n.cross(bisector).dot(r.plane_normal) / bisector.norm();
    }
    return sum / static_cast<double>(rays.size());
  };
  // Depths from just outside the camera to where the first ray grazes.
  double far = INFINITY;
  for (const Ray& r : rays) {
    const double along = r.direction.dot(d);
    const double off = std::sqrt(std::max(0.0, 1 - along * along));
    if (off > 0) far = std::min(far, radius / off);
  }
  if (!std::isfinite(far)) return std::nullopt;
  double lo = radius * (1 + 1e-9), hi = far * (1 - 1e-12);
  bool missed = false;
  double f_lo = mismatch(lo, missed);
  if (missed) return std::nullopt;
  double f_hi = mismatch(hi, missed);
  if (missed || !(f_lo * f_hi < 0)) return std::nullopt;
  // Regula falsi, Illinois variant: superlinear, and never leaves the bracket.
  int side = 0;
  double depth = lo;
  for (int i = 0; i < 100 && hi - lo > 1e-10 * hi; ++i) {
    depth = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
    const double f = mismatch(depth, missed);
    if (missed) return std::nullopt;
    if (f * f_hi > 0) {
      hi = depth, f_hi = f;
      if (side == 1) f_lo /= 2;
      side = 1;
    } else if (f * f_lo > 0) {
      lo = depth, f_lo = f;
      if (side == -1) f_hi /= 2;
      side = -1;
    } else {
      break;  // exactly zero
    }
  }
  const Eigen::Vector3d c = origin + depth * d;
  return Point3{c.x(), c.y(), c.z()};
}

}  // namespace

std::array<double, 9> CorneaFit::center_covariance(int frame) const {
  const int n = static_cast<int>(std::lround(std::sqrt(static_cast<double>(covariance_mm2.size()))));
  if (!has_covariance() || frame < 0 || 3 * frame + 3 > n) {
    throw std::out_of_range("CorneaFit::center_covariance: no covariance for frame " + std::to_string(frame));
  }
  std::array<double, 9> block{};
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) block[3 * a + b] = covariance_mm2[(3 * frame + a) * n + 3 * frame + b];
  }
  return block;
}

double CorneaFit::radius_sd_mm() const {
  if (!radius_fitted) return 0;
  if (!has_covariance()) throw std::out_of_range("CorneaFit::radius_sd_mm: no covariance");
  return std::sqrt(covariance_mm2.back());
}

namespace {

// How many glints each frame has and which cameras see them; throws for a
// glint naming a frame, camera or light that is not there, or a bad s.d.
struct GlintCounts {
  std::vector<int> per_frame;
  std::vector<int> cameras_used;
};

GlintCounts count_glints(const std::vector<Camera>& cameras, const std::vector<Illuminator>& lights,
                         const std::vector<GlintObservation>& glints, int frames) {
  std::vector<int> per_frame(frames, 0);
  std::vector<int> cameras_used;
  for (const GlintObservation& g : glints) {
    const auto bad = [&](const std::string& what, int value, std::size_t size) {
      throw std::invalid_argument("fit_cornea: a glint's " + what + " = " + std::to_string(value) +
                                  ": must be in [0, " + std::to_string(size) + ")");
    };
    if (g.frame < 0 || g.frame >= frames) bad("frame", g.frame, static_cast<std::size_t>(frames));
    if (g.camera < 0 || g.camera >= static_cast<int>(cameras.size())) bad("camera", g.camera, cameras.size());
    if (g.light < 0 || g.light >= static_cast<int>(lights.size())) bad("light", g.light, lights.size());
    for (const double sd : {g.sd_u_px, g.sd_v_px}) {
      if (!(sd >= 0 && std::isfinite(sd))) {
        throw std::invalid_argument("fit_cornea: a glint's standard deviation (sd_u_px or sd_v_px) = " + format_number(sd) +
                                    ": must be finite and >= 0 (0: pixel_noise_px)");
      }
    }
    ++per_frame[g.frame];
    if (std::find(cameras_used.begin(), cameras_used.end(), g.camera) == cameras_used.end()) {
      cameras_used.push_back(g.camera);
    }
  }
  return {per_frame, cameras_used};
}

// Each frame starts where its first camera's glints put a sphere of the
// start's radius (for a conicoid, its apex sphere: millimetres off in
// depth), or at the caller's start where they do not.
std::vector<double> start_point(const std::vector<Camera>& cameras, const std::vector<Illuminator>& lights,
                                const std::vector<GlintObservation>& glints, const std::vector<Point3>& starts,
                                const CorneaFitSettings& s, int n) {
  std::vector<double> x(n);
  for (int f = 0; f < static_cast<int>(starts.size()); ++f) {
    Point3 start = starts[f];
    const auto first = std::find_if(glints.begin(), glints.end(), [&](const GlintObservation& g) { return g.frame == f; });
    const std::optional<Point3> closed =
        closed_form_center(cameras[first->camera], lights, glints, f, first->camera, s.cornea_radius_mm);
    if (closed && closed->is_finite()) start = *closed;
    x[3 * f] = start.x, x[3 * f + 1] = start.y, x[3 * f + 2] = start.z;
  }
  if (s.fit_radius) x[n - 1] = s.cornea_radius_mm;
  return x;
}

// The covariance of the unknowns from the whitened Jacobian at the
// estimate, and the warnings it gives: unknowns the glints do not
// determine, or determine only weakly at the assumed noise. False when J^T
// J is singular (no covariance).
bool add_covariance(CorneaFit& out, const std::vector<double>& jacobian, int m, int n, int frames,
                    const CorneaFitSettings& s, const std::function<std::string()>& noise) {
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> j(
      jacobian.data(), m, n);
  // Coefficient by coefficient: a few columns (3 per frame) need no blocked product.
  const Eigen::MatrixXd normal = j.transpose().lazyProduct(j);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(normal);
  const double lo = eigen.eigenvalues()(0), hi = eigen.eigenvalues()(n - 1);
  out.condition = lo > 0 ? hi / lo : INFINITY;
  if (!(out.condition <= kSingularCondition)) {
    out.warnings.push_back("the glints do not determine the unknowns (condition of J^T J " +
                           number(out.condition) + "), e.g. lights at one place or in line with the eye");
    if (!std::isfinite(out.condition)) out.condition = 0;
    return false;
  }
  const Eigen::VectorXd inverse_values = eigen.eigenvalues().cwiseInverse();
  const Eigen::MatrixXd covariance =
      eigen.eigenvectors() * inverse_values.asDiagonal() * eigen.eigenvectors().transpose();
  out.covariance_mm2.assign(covariance.data(), covariance.data() + n * n);  // symmetric: either order

  for (int f = 0; f < frames; ++f) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> block(covariance.block<3, 3>(3 * f, 3 * f));
    const double sd = std::sqrt(std::max(0.0, block.eigenvalues()(2)));
    if (sd > s.max_sd_mm) {
      out.warnings.push_back("frame " + std::to_string(f) + "'s cornea centre is weakly determined: " +
                             number(sd) + " mm standard deviation along " +
                             direction(block.eigenvectors().col(2)) + " at " + noise());
    }
  }
  if (s.fit_radius && std::sqrt(covariance(n - 1, n - 1)) > s.max_sd_mm) {
    out.warnings.push_back("the cornea's radius is weakly determined: " +
                           number(std::sqrt(covariance(n - 1, n - 1))) + " mm standard deviation at " + noise());
  }
  return true;
}

CorneaFit fit_once(const std::vector<Camera>& cameras, const std::vector<Illuminator>& lights,
                   const std::vector<GlintObservation>& glints, const std::vector<Point3>& starts,
                   const CorneaFitSettings& s, const std::vector<UnitVector3>& axes) {
  const int frames = static_cast<int>(starts.size());
  if (frames == 0) throw std::invalid_argument("fit_cornea: no frames (starts is empty)");
  const GlintCounts counts = count_glints(cameras, lights, glints, frames);
  const std::vector<int>& per_frame = counts.per_frame;

  CorneaFit out;
  out.centers = starts;
  out.cornea_radius_mm = s.cornea_radius_mm;
  out.radius_fitted = s.fit_radius;
  out.glints_used = static_cast<int>(glints.size());
  for (int f = 0; f < frames; ++f) {
    if (per_frame[f] < 2) {
      out.warnings.push_back("frame " + std::to_string(f) + " has " + std::to_string(per_frame[f]) +
                             " glint(s) with their light told; two or more are needed: the cornea's centre "
                             "is not determined");
    }
  }
  if (!out.warnings.empty()) return out;
  const bool prior = s.fit_radius && s.radius_prior_sd_mm > 0;
  if (s.fit_radius && !prior && frames == 1 && counts.cameras_used.size() == 1) {
    out.warnings.push_back(
        "the radius is fitted from one frame of one camera: radius and depth trade against each other "
        "there, so the radius is hardly determined; use several frames with the eye in different places, "
        "a second camera, or a prior (radius_prior_sd_mm)");
  }

  const int n = 3 * frames + (s.fit_radius ? 1 : 0);
  const int m = 2 * static_cast<int>(glints.size()) + (prior ? 1 : 0);
  std::vector<std::optional<UnitVector3>> warm(glints.size());
  const bool sphere = s.cornea_asphericity == 0;
  // Each glint's pixel over its standard deviation: the residuals are
  // whitened, so that J^T J is the inverse covariance.
  std::vector<double> sd(2 * glints.size());
  bool own_noise = false;
  for (std::size_t i = 0; i < glints.size(); ++i) {
    sd[2 * i] = glints[i].sd_u_px > 0 ? glints[i].sd_u_px : s.pixel_noise_px;
    sd[2 * i + 1] = glints[i].sd_v_px > 0 ? glints[i].sd_v_px : s.pixel_noise_px;
    own_noise = own_noise || glints[i].sd_u_px > 0 || glints[i].sd_v_px > 0;
  }
  const auto noise = [&] {
    return own_noise ? "the glints' own noise (" + number(s.pixel_noise_px) + " px where none is given)"
                     : number(s.pixel_noise_px) + " px of glint noise";
  };
  // The last point whose Jacobian was evaluated, with its residuals and
  // Jacobian: the solver ends at such a point, whose covariance needs them
  // (one of a one-frame fit's five or six Jacobian evaluations saved).
  std::vector<double> last_x, last_r, last_jacobian;
  const optimizer::ResidualFunction residuals = [&](const double* x, double* r, double* jacobian) {
    const double radius = s.fit_radius ? x[n - 1] : s.cornea_radius_mm;
    if (jacobian != nullptr) std::fill_n(jacobian, static_cast<std::size_t>(m) * n, 0.0);
    for (std::size_t i = 0; i < glints.size(); ++i) {
      const GlintObservation& o = glints[i];
      const double* c = x + 3 * o.frame;
      // A sphere's glint needs no axis (conicoid_glint takes it to sphere_glint).
      const std::optional<CorneaGlint> g =
          conicoid_glint(cameras[o.camera], {c[0], c[1], c[2]}, sphere ? UnitVector3::unit_z() : axes[o.frame],
                         Conicoid{radius, s.cornea_asphericity}, lights[o.light].position, warm[i],
                         jacobian != nullptr);
      if (!g) return false;
      warm[i] = g->normal;
      r[2 * i] = (g->pixel.u - o.pixel.u) / sd[2 * i];
      r[2 * i + 1] = (g->pixel.v - o.pixel.v) / sd[2 * i + 1];
      if (jacobian == nullptr) continue;
      for (int row = 0; row < 2; ++row) {
        double* j = jacobian + (2 * i + row) * n;
        for (int k = 0; k < 3; ++k) j[3 * o.frame + k] = g->d_pixel[4 * row + k] / sd[2 * i + row];
        if (s.fit_radius) j[n - 1] = g->d_pixel[4 * row + 3] / sd[2 * i + row];
      }
    }
    if (prior) {
      r[m - 1] = (radius - s.cornea_radius_mm) / s.radius_prior_sd_mm;
      if (jacobian != nullptr) jacobian[static_cast<std::size_t>(m - 1) * n + n - 1] = 1 / s.radius_prior_sd_mm;
    }
    if (jacobian != nullptr) {
      last_x.assign(x, x + n);
      last_r.assign(r, r + m);
      last_jacobian.assign(jacobian, jacobian + static_cast<std::size_t>(m) * n);
    }
    return true;
  };

  std::vector<double> x = start_point(cameras, lights, glints, starts, s, n);
  // Steps below 1e-10 of the centre's distance (4e-9 mm at 35 mm, 6e-8 mm
  // at 600 mm) are far below any glint's noise and the 1e-6 mm the fit
  // must reach from exact glints; with noisy glints Gauss-Newton
  // converges only linearly, and chasing rounding would cost iterations
  // that each change nothing.
  optimizer::Options options;
  options.parameter_tolerance = 1e-10;
  options.function_tolerance = 1e-12;
  const optimizer::Summary summary = optimizer::solve(m, x, residuals, options);
  for (int f = 0; f < frames; ++f) out.centers[f] = {x[3 * f], x[3 * f + 1], x[3 * f + 2]};
  if (s.fit_radius) out.cornea_radius_mm = x[n - 1];
  out.converged = summary.converged;

  std::vector<double> r(m), jacobian(static_cast<std::size_t>(m) * n);
  if (last_x == x) {
    r = last_r;
    jacobian = last_jacobian;
  } else if (!residuals(x.data(), r.data(), jacobian.data())) {
    out.converged = false;
    out.warnings.push_back("some light has no glint on the cornea at the estimate: the fit failed (" +
                           summary.message + ")");
    return out;
  }
  double sum = 0;
  for (std::size_t i = 0; i < glints.size(); ++i) {
    const double du = r[2 * i] * sd[2 * i], dv = r[2 * i + 1] * sd[2 * i + 1];
    sum += du * du + dv * dv;
    out.glint_residuals_px.push_back(std::hypot(du, dv));
    out.glint_residuals_sd.push_back(std::hypot(r[2 * i], r[2 * i + 1]));
  }
  out.rms_residual_px = std::sqrt(sum / (2.0 * glints.size()));

  if (!add_covariance(out, jacobian, m, n, frames, s, noise)) return out;
  if (!out.converged) out.warnings.push_back("the fit stopped before converging: " + summary.message);
  return out;
}

}  // namespace

CorneaFit fit_cornea(const std::vector<Camera>& cameras, const std::vector<Illuminator>& lights,
                     const std::vector<GlintObservation>& glints, const std::vector<Point3>& starts,
                     const CorneaFitSettings& s, const std::vector<UnitVector3>& optical_axes) {
  check(s);
  if (s.cornea_asphericity != 0 && optical_axes.size() != starts.size()) {
    throw std::invalid_argument("fit_cornea: a conicoid cornea (cornea_asphericity = " +
                                format_number(s.cornea_asphericity) + ") needs one optical axis per frame: " +
                                std::to_string(optical_axes.size()) + " for " + std::to_string(starts.size()) +
                                " frames");
  }
  if (!(s.reject_beyond_sd >= 0)) {
    throw std::invalid_argument("CorneaFitSettings: reject_beyond_sd = " + format_number(s.reject_beyond_sd) +
                                ": must be >= 0 (0: no rejection)");
  }
  std::vector<int> kept(glints.size());
  for (std::size_t i = 0; i < glints.size(); ++i) kept[i] = static_cast<int>(i);
  std::vector<int> rejected;
  std::vector<double> rejected_residuals, rejected_residuals_sd;
  std::vector<std::string> notes;
  for (;;) {
    std::vector<GlintObservation> used;
    for (const int i : kept) used.push_back(glints[i]);
    CorneaFit fit = fit_once(cameras, lights, used, starts, s, optical_axes);
    // The worst glint beyond the bound whose frame can spare it.
    int worst = -1;
    if (s.reject_beyond_sd > 0 && fit.converged && fit.has_covariance() &&
        fit.glint_residuals_sd.size() == used.size()) {
      std::vector<int> per_frame(starts.size(), 0);
      for (const GlintObservation& g : used) ++per_frame[g.frame];
      double largest = s.reject_beyond_sd;
      for (std::size_t k = 0; k < used.size(); ++k) {
        if (per_frame[used[k].frame] >= 4 && fit.glint_residuals_sd[k] > largest) {
          largest = fit.glint_residuals_sd[k];
          worst = static_cast<int>(k);
        }
      }
    }
    if (worst < 0) {
      // Residuals in the caller's order, the rejected at their last fit's.
      std::vector<double> residuals(glints.size(), 0.0), in_sd(glints.size(), 0.0);
      for (std::size_t k = 0; k < kept.size() && k < fit.glint_residuals_px.size(); ++k) {
        residuals[kept[k]] = fit.glint_residuals_px[k];
        in_sd[kept[k]] = fit.glint_residuals_sd[k];
      }
      for (std::size_t k = 0; k < rejected.size(); ++k) {
        residuals[rejected[k]] = rejected_residuals[k];
        in_sd[rejected[k]] = rejected_residuals_sd[k];
      }
      fit.glint_residuals_px = residuals;
      fit.glint_residuals_sd = in_sd;
      fit.rejected = rejected;
      fit.warnings.insert(fit.warnings.begin(), notes.begin(), notes.end());
      return fit;
    }
    const GlintObservation& g = used[worst];
    notes.push_back("rejected the glint of light " + std::to_string(g.light) + " in frame " +
                    std::to_string(g.frame) + " of camera " + std::to_string(g.camera) + ": " +
                    number(fit.glint_residuals_px[worst]) + " px from the fit, " +
                    number(fit.glint_residuals_sd[worst]) + " of its standard deviations, over " +
                    number(s.reject_beyond_sd));
    rejected.push_back(kept[worst]);
    rejected_residuals.push_back(fit.glint_residuals_px[worst]);
    rejected_residuals_sd.push_back(fit.glint_residuals_sd[worst]);
    kept.erase(kept.begin() + worst);
  }
}

GlintObservation observation_of(const Glint& glint, int frame, int camera, double glint_sd_scale) {
  if (!(glint_sd_scale >= 0 && std::isfinite(glint_sd_scale))) {
    throw std::invalid_argument("glint_sd_scale = " + format_number(glint_sd_scale) +
                                ": must be finite and >= 0 (0: the glints' own deviations are not used)");
  }
  GlintObservation o{frame, camera, glint.illuminator, glint.centre};
  if (glint_sd_scale > 0 && glint.centre_sd_u_px > 0 && glint.centre_sd_v_px > 0) {
    o.sd_u_px = glint_sd_scale * glint.centre_sd_u_px;
    o.sd_v_px = glint_sd_scale * glint.centre_sd_v_px;
  }
  return o;
}

void add_observations(std::vector<GlintObservation>& out, const std::vector<Glint>& glints, int frame,
                      int camera, double glint_sd_scale) {
  for (const Glint& g : glints) {
    if (g.illuminator >= 0) out.push_back(observation_of(g, frame, camera, glint_sd_scale));
  }
}

CorneaFit estimate_cornea_center(const Camera& camera, const std::vector<Illuminator>& lights,
                                 const std::vector<Glint>& glints, const Point3& start,
                                 const CorneaFitSettings& settings, const std::optional<UnitVector3>& optical_axis) {
  std::vector<GlintObservation> observed;
  add_observations(observed, glints, 0);
  std::vector<UnitVector3> axes;
  if (optical_axis) axes.push_back(*optical_axis);
  return fit_cornea({camera}, lights, observed, {start}, settings, axes);
}

}  // namespace purkinje::trackers
