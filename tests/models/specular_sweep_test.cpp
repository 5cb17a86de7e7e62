// A randomized sweep over eyes, poses and lights: every solved path obeys
// the law of reflection or Snell's law to a tight tolerance, checked with
// surface normals computed here from the conicoid's equation (not with the
// solver's own), and every configuration either converges or returns a
// status. No NaN anywhere.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <random>

#include "purkinje/models/specular.h"

namespace purkinje {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Outward normal of x^2 + y^2 + (1+Q) w^2 - 2 R w = 0, w = apex_z - z, in
// the eye frame; the gradient of that implicit function.
Vector3 conicoid_normal(const Conicoid& c, double apex_z, const Point3& p) {
  const double w = apex_z - p.z;
  const Vector3 g{2 * p.x, 2 * p.y, -2 * (1 + c.asphericity) * w + 2 * c.radius_mm};
  return g / g.norm();
}

double conicoid_implicit(const Conicoid& c, double apex_z, const Point3& p) {
  const double w = apex_z - p.z;
  return p.x * p.x + p.y * p.y + (1 + c.asphericity) * w * w - 2 * c.radius_mm * w;
}

// Snell's law as the mismatch of tangential components, in radians-like
// units: |n1 t1 - n2 t2| / n2 is sin of the angle error to first order.
double snell_residual(const Vector3& in_dir, const Vector3& out_dir, const Vector3& normal,
                      double n_in, double n_out) {
  const Vector3 t_in = in_dir - normal * dot(in_dir, normal);
  const Vector3 t_out = out_dir - normal * dot(out_dir, normal);
  return (t_in * n_in - t_out * n_out).norm() / n_out;
}

bool finite(const Refraction& r) {
  return r.anterior_point.is_finite() && r.anterior_normal.vector().is_finite() &&
         r.inner_direction.vector().is_finite() && r.outer_direction.vector().is_finite() &&
         std::isfinite(r.inner_angle_rad) && std::isfinite(r.outer_angle_rad) &&
         (!r.posterior_point || r.posterior_point->is_finite());
}

bool finite(const Reflection& r) {
  return r.point.is_finite() && r.normal.vector().is_finite() && r.incident.vector().is_finite() &&
         r.reflected.vector().is_finite() && std::isfinite(r.incidence_rad);
}

struct SweepStats {
  int configurations = 0;
  std::map<std::string, int> statuses;
  double max_residual = 0;
};

struct Sweep {
  std::mt19937_64 rng{20261122};
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }

  // A direction within `max_angle` of `axis`, uniform in angle and azimuth.
  UnitVector3 tilt(const UnitVector3& axis, double max_angle) {
    const Vector3 helper = std::abs(axis.x()) < 0.9 ? Vector3{1, 0, 0} : Vector3{0, 1, 0};
    const UnitVector3 side = UnitVector3::normalize(cross(axis, helper));
    const UnitVector3 around = rotate(side, axis, uniform(0, 2 * kPi));
    return rotate(axis, around, uniform(0, max_angle));
  }

  EyeModel model(int kind) {
    EyeModel m;
    m.anterior_cornea = {uniform(7.0, 8.6), 0.0};
    m.aqueous_index = 1.3375;
    if (kind == 1) m.anterior_cornea.asphericity = uniform(-0.8, 0.4);
    if (kind == 2) {
      m.anterior_cornea.asphericity = uniform(-0.5, 0.0);
      m.posterior_cornea = PosteriorCornea{{uniform(6.2, 6.8), uniform(-0.4, 0.2)}, 0.55, 1.376};
      m.aqueous_index = 1.336;
    }
    m.limbus_radius_mm = 5.9;
    m.iris_depth_mm = uniform(2.8, 3.8);
    m.pupil_radius_mm = uniform(0.5, 4.5);
    return m;
  }

  // Eye 20 mm to 2 m from a camera at the origin looking along +z, turned
  // up to 45 degrees away from the camera.
  Eye eye(int kind) {
    const double distance = std::exp(uniform(std::log(20.0), std::log(2000.0)));
    const UnitVector3 where = tilt(UnitVector3::unit_z(), 0.35);
    const Point3 centre = Point3::origin() + where * distance;
    const UnitVector3 toward_camera = -where;
    return Eye::with_cornea_center(model(kind), centre, tilt(toward_camera, 45 * kPi / 180));
  }

  // Anywhere in front of the eye (on the camera's side of the cornea
  // centre), outside a 15 mm ball around it, within 1.5 eye distances.
  Point3 light_in_front(const Eye& e) {
    const double d = distance(e.cornea_center(), Point3::origin());
    for (;;) {
      const Vector3 offset{uniform(-1.5, 1.5) * d, uniform(-1.5, 1.5) * d, uniform(-1.5, 1.5) * d};
      const Point3 p = e.cornea_center() + offset;
      const Vector3 to_camera = Point3::origin() - e.cornea_center();
      if (offset.norm() > 15.0 && dot(offset, to_camera) > 0) return p;
    }
  }
};

void check_reflection(Sweep& s, int kind, int count, SweepStats& stats) {
  for (int i = 0; i < count; ++i) {
    const Eye e = s.eye(kind);
    const Point3 light = s.light_in_front(e);
    const Reflection r = solve_reflection(e, light, Point3::origin());
    ++stats.configurations;
    ++stats.statuses[to_string(r.status)];
    ASSERT_TRUE(finite(r)) << "configuration " << i;
    if (r.status != PathStatus::ok && r.status != PathStatus::off_cornea) continue;
    const Point3 p = e.eye_from_world() * r.point;
    const Conicoid& c = e.model().anterior_cornea;
    ASSERT_LT(std::abs(conicoid_implicit(c, c.radius_mm, p)), 1e-10) << "not on the cornea";
    const Vector3 n = e.world_from_eye() * conicoid_normal(c, c.radius_mm, p);
    const Vector3 in = UnitVector3::normalize(r.point - light);
    const Vector3 out = UnitVector3::normalize(Point3::origin() - r.point);
    // The front of the cornea, not its back: both ends see the point.
    ASSERT_GT(dot(out, n), 0.0);
    ASSERT_GT(dot(-in, n), 0.0);
    const Vector3 mirrored = in - n * (2 * dot(in, n));
    stats.max_residual = std::max(stats.max_residual, angle_between(mirrored, out));
  }
}

void check_refraction(Sweep& s, int kind, int count, SweepStats& stats) {
  for (int i = 0; i < count; ++i) {
    const Eye e = s.eye(kind);
    const EyeModel& m = e.model();
    // A point of the pupil's border (half the time) or of its disc.
    const double inside = s.uniform(0.0, 1.0) < 0.5 ? 1.0 : s.uniform(0.0, 1.0);
    const Point3 border = e.pupil_border_point(s.uniform(0, 2 * kPi));
    const Point3 target = e.pupil_center() + (border - e.pupil_center()) * inside;
    const Refraction r = solve_refraction(e, target, Point3::origin());
    ++stats.configurations;
    ++stats.statuses[to_string(r.status)];
    ASSERT_TRUE(finite(r)) << "configuration " << i;
    if (r.status != PathStatus::ok && r.status != PathStatus::off_cornea) continue;
    const Conicoid& front = m.anterior_cornea;
    const Point3 p1 = e.eye_from_world() * r.anterior_point;
    ASSERT_LT(std::abs(conicoid_implicit(front, front.radius_mm, p1)), 1e-10);
    const Vector3 n1 = e.world_from_eye() * conicoid_normal(front, front.radius_mm, p1);
    const Vector3 out = UnitVector3::normalize(Point3::origin() - r.anterior_point);
    ASSERT_GT(dot(out, n1), 0.0) << "exit point not visible from the camera";
    if (!m.posterior_cornea) {
      const Vector3 in = UnitVector3::normalize(r.anterior_point - target);
      stats.max_residual =
          std::max(stats.max_residual, snell_residual(in, out, n1, m.aqueous_index, 1.0));
      continue;
    }
    ASSERT_TRUE(r.posterior_point.has_value());
    const PosteriorCornea& pc = *m.posterior_cornea;
    const double apex2 = front.radius_mm - pc.thickness_mm;
    const Point3 p2 = e.eye_from_world() * *r.posterior_point;
    ASSERT_LT(std::abs(conicoid_implicit(pc.surface, apex2, p2)), 1e-10);
    const Vector3 n2 = e.world_from_eye() * conicoid_normal(pc.surface, apex2, p2);
    const Vector3 in = UnitVector3::normalize(*r.posterior_point - target);
    const Vector3 mid = UnitVector3::normalize(r.anterior_point - *r.posterior_point);
    stats.max_residual =
        std::max({stats.max_residual, snell_residual(mid, out, n1, pc.cornea_index, 1.0),
                  snell_residual(in, mid, n2, m.aqueous_index, pc.cornea_index)});
  }
}

void print(const char* what, const SweepStats& s) {
  std::printf("%s: %d configurations, max residual %.3g rad;", what, s.configurations,
              s.max_residual);
  for (const auto& [k, v] : s.statuses) std::printf(" %s %d", k.c_str(), v);
  std::printf("\n");
}

TEST(SpecularSweep, SphereGlintsObeyTheLawOfReflection) {
  Sweep s;
  SweepStats stats;
  check_reflection(s, 0, 4000, stats);
  print("sphere glints", stats);
  EXPECT_LE(stats.max_residual, 1e-12);
  EXPECT_GT(stats.statuses["ok"], 1000);
}

TEST(SpecularSweep, ConicoidGlintsObeyTheLawOfReflection) {
  Sweep s;
  s.rng.seed(2);
  SweepStats stats;
  check_reflection(s, 1, 3000, stats);
  print("conicoid glints", stats);
  EXPECT_LE(stats.max_residual, 1e-10);
  EXPECT_GT(stats.statuses["ok"], 1000);
}

TEST(SpecularSweep, SpherePupilPointsObeySnell) {
  Sweep s;
  s.rng.seed(3);
  SweepStats stats;
  check_refraction(s, 0, 4000, stats);
  print("sphere pupil points", stats);
  EXPECT_LE(stats.max_residual, 1e-12);
  EXPECT_GT(stats.statuses["ok"], 3000);
}

TEST(SpecularSweep, ConicoidPupilPointsObeySnell) {
  Sweep s;
  s.rng.seed(4);
  SweepStats stats;
  check_refraction(s, 1, 3000, stats);
  print("conicoid pupil points", stats);
  EXPECT_LE(stats.max_residual, 1e-10);
  EXPECT_GT(stats.statuses["ok"], 2000);
}

TEST(SpecularSweep, TwoSurfacePupilPointsObeySnellAtBothSurfaces) {
  Sweep s;
  s.rng.seed(5);
  SweepStats stats;
  check_refraction(s, 2, 3000, stats);
  print("two-surface pupil points", stats);
  EXPECT_LE(stats.max_residual, 1e-10);
  EXPECT_GT(stats.statuses["ok"], 2000);
}

}  // namespace
}  // namespace purkinje
