// The iris irradiance cache against a paraxial closed form and against an
// independent forward Monte Carlo written here (analytic ray-conicoid
// intersections, vector Snell, Fresnel from the angle form), plus the
// procedural iris albedo's contract.

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <vector>
#include <utility>

#include "purkinje/models/eye.h"
#include "purkinje/models/specular.h"
#include "purkinje/renderer/radiometry.h"

namespace purkinje::renderer {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

// An eye posed obliquely in the world, so that every test also exercises
// the world <-> eye frame transforms.
Eye posed(const EyeModel& model) {
  return Eye::with_cornea_center(model, {12.0, -7.0, 540.0},
                                 optical_axis_from_yaw_pitch(0.25, -0.15));
}

Point3 world(const Eye& eye, double x, double y, double z) {
  return eye.world_from_eye() * Point3{x, y, z};
}

double iris_plane_z(const EyeModel& m) { return m.anterior_cornea.radius_mm - m.iris_depth_mm; }

// Light in the eye frame at `angle` from the optical axis (toward eye +x),
// `distance` from the anterior cornea's centre of curvature.
Point3 light_at(const Eye& eye, double angle, double distance) {
  return world(eye, distance * std::sin(angle), 0.0, distance * std::cos(angle));
}

// Mean of the cache over the square [cx +- h] x [cy +- h] of the iris plane
// (eye frame), by the midpoint rule.
double cache_mean(const IrisIrradianceCache& cache, const Eye& eye, double cx, double cy, double h,
                  int n = 24) {
  const double z = iris_plane_z(eye.model());
  double sum = 0;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double x = cx - h + (i + 0.5) * 2 * h / n, y = cy - h + (j + 0.5) * 2 * h / n;
      sum += cache.irradiance_w_m2(world(eye, x, y, z));
    }
  }
  return sum / (n * n);
}

// ---------------------------------------------------------------------------
// Test-side optics, independent of the library's.

struct V {
  double x, y, z;
};
V operator+(V a, V b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V operator-(V a, V b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V operator*(V a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dot(V a, V b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V unit(V a) { return a * (1.0 / std::sqrt(dot(a, a))); }

// Unpolarized Fresnel reflectance from the angle form (Born & Wolf).
double fresnel_angle_form(double cos_i, double n1, double n2) {
  const double ti = std::acos(std::clamp(cos_i, 0.0, 1.0));
  const double st = n1 / n2 * std::sin(ti);
  if (st >= 1.0) return 1.0;
  const double tt = std::asin(st);
  if (ti < 1e-7) return ((n1 - n2) / (n1 + n2)) * ((n1 - n2) / (n1 + n2));
  const double rs = std::sin(ti - tt) / std::sin(ti + tt);
  const double rp = std::tan(ti - tt) / std::tan(ti + tt);
  return 0.5 * (rs * rs + rp * rp);
}

// x^2 + y^2 + k w^2 - 2 R w = 0, w = apex_z - z, front sheet (w <= R / k).
struct Conic {
  double apex_z, R, k;
  V normal(V p) const { return unit({p.x, p.y, R - k * (apex_z - p.z)}); }
  // Nearest t > 0 where o + t d meets the front sheet; < 0 if none.
  double hit(V o, V d) const {
    const double w0 = apex_z - o.z;
    const double a = d.x * d.x + d.y * d.y + k * d.z * d.z;
    const double b = 2 * (o.x * d.x + o.y * d.y) - 2 * k * w0 * d.z + 2 * R * d.z;
    const double c = o.x * o.x + o.y * o.y + k * w0 * w0 - 2 * R * w0;
    double roots[2];
    int count = 0;
    if (std::abs(a) < 1e-14) {
      roots[count++] = -c / b;
    } else {
      const double disc = b * b - 4 * a * c;
      if (disc < 0) return -1;
      const double s = std::sqrt(disc);
      roots[count++] = (-b - s) / (2 * a);
      roots[count++] = (-b + s) / (2 * a);
      if (roots[0] > roots[1]) std::swap(roots[0], roots[1]);
    }
    for (int i = 0; i < count; ++i) {
      const double t = roots[i];
      if (t <= 1e-9) continue;
      const double w = apex_z - (o.z + d.z * t);
      if (k > 0 && w > R / k) continue;
      return t;
    }
    return -1;
  }
};

// Refracts unit d at unit normal n facing the incoming side; false on TIR.
bool snell(V d, V n, double n1, double n2, V& out, double& cos_i) {
  cos_i = -dot(d, n);
  const double eta = n1 / n2;
  const double k = 1 - eta * eta * (1 - cos_i * cos_i);
  if (k < 0) return false;
  out = unit(d * eta + n * (eta * cos_i - std::sqrt(k)));
  return true;
}

struct Bin {
  double cx, cy, half;
};

struct BinEstimate {
  double mean_w_m2, sigma_w_m2;
};

// Photons from the light, jittered-stratified in a cone over the cornea,
// traced through the eye's corneal surfaces to the iris plane. Returns per
// bin the mean over `replicas` independent runs and its standard error
// from their spread.
std::vector<BinEstimate> monte_carlo(const EyeModel& m, V light, double intensity,
                                     const std::vector<Bin>& bins, int strata, int replicas) {
  const double R = m.anterior_cornea.radius_mm;
  const Conic front{R, R, 1 + m.anterior_cornea.asphericity};
  const bool two = m.posterior_cornea.has_value();
  const Conic back = two ? Conic{R - m.posterior_cornea->thickness_mm,
                                 m.posterior_cornea->surface.radius_mm,
                                 1 + m.posterior_cornea->surface.asphericity}
                         : front;
  const double n_front = two ? m.posterior_cornea->cornea_index : m.aqueous_index;
  const double z_iris = iris_plane_z(m);
  const double limbus_depth = m.limbus_depth_mm();
  // Every cap point lies within 8.5 mm of the eye-frame origin here.
  const double cover = 8.5;
  const V axis = unit(V{0, 0, 0} - light);
  const double cos_max = std::sqrt(1 - cover * cover / dot(light, light));
  const V helper = std::abs(axis.x) < 0.7 ? V{1, 0, 0} : V{0, 1, 0};
  V e1 = unit(helper - axis * dot(helper, axis));
  const V e2{axis.y * e1.z - axis.z * e1.y, axis.z * e1.x - axis.x * e1.z,
             axis.x * e1.y - axis.y * e1.x};
  const double cone = 2 * kPi * (1 - cos_max);
  const double power = intensity * cone / (static_cast<double>(strata) * strata);  // W per photon

  std::uint64_t state = 0x243f6a8885a308d3ULL;
  auto uniform = [&state]() {  // splitmix64
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return static_cast<double>((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
  };
  std::vector<std::vector<double>> runs(bins.size(), std::vector<double>(replicas, 0.0));
  for (int r = 0; r < replicas; ++r) {
    for (int a = 0; a < strata; ++a) {
      for (int b = 0; b < strata; ++b) {
        const double cos_t = 1 - (a + uniform()) / strata * (1 - cos_max);
        const double phi = 2 * kPi * (b + uniform()) / strata;
        const double sin_t = std::sqrt(1 - cos_t * cos_t);
        const V d = axis * cos_t + e1 * (sin_t * std::cos(phi)) + e2 * (sin_t * std::sin(phi));
        const double t1 = front.hit(light, d);
        if (t1 < 0) continue;
        V p = light + d * t1;
        if (R - p.z >= limbus_depth) continue;  // the sclera beyond the limbus
        V dir;
        double cos_i;
        if (!snell(d, front.normal(p), 1.0, n_front, dir, cos_i)) continue;
        double weight = power * (1 - fresnel_angle_form(cos_i, 1.0, n_front));
        if (two) {
          const double t2 = back.hit(p, dir);
          if (t2 < 0) continue;
          p = p + dir * t2;
          V next;
          if (!snell(dir, back.normal(p), n_front, m.aqueous_index, next, cos_i)) continue;
          weight *= 1 - fresnel_angle_form(cos_i, n_front, m.aqueous_index);
          dir = next;
        }
        if (dir.z >= 0) continue;
        const V q = p + dir * ((z_iris - p.z) / dir.z);
        for (std::size_t k = 0; k < bins.size(); ++k) {
          if (std::abs(q.x - bins[k].cx) < bins[k].half && std::abs(q.y - bins[k].cy) < bins[k].half) {
            runs[k][r] += weight;
          }
        }
      }
    }
  }
  std::vector<BinEstimate> out;
  for (std::size_t k = 0; k < bins.size(); ++k) {
    const double area_m2 = 4 * bins[k].half * bins[k].half * 1e-6;
    double mean = 0, var = 0;
    for (double v : runs[k]) mean += v / area_m2 / replicas;
    for (double v : runs[k]) var += (v / area_m2 - mean) * (v / area_m2 - mean) / (replicas - 1);
    out.push_back({mean, std::sqrt(var / replicas)});
  }
  return out;
}

V eye_light(double angle, double distance) {
  return {distance * std::sin(angle), 0.0, distance * std::cos(angle)};
}

// Cache mean over each bin against the Monte Carlo's, within 4 standard
// errors plus 0.2% (the Monte Carlo's own limits: the errors' estimate has
// few degrees of freedom, and the stratification leaves a small bias at
// bin edges).
void expect_matches_monte_carlo(const EyeModel& model, double angle, double distance,
                                const std::vector<Bin>& bins) {
  const Eye eye = posed(model);
  const double intensity = 0.05;
  const IrisIrradianceCache cache(eye, light_at(eye, angle, distance), intensity, 33);
  const std::vector<BinEstimate> mc = monte_carlo(model, eye_light(angle, distance), intensity, bins,
                                                  360, 8);
  const Point3 light = light_at(eye, angle, distance);
  const double z = iris_plane_z(model);
  for (std::size_t k = 0; k < bins.size(); ++k) {
    const double cached = cache_mean(cache, eye, bins[k].cx, bins[k].cy, bins[k].half);
    ASSERT_GT(mc[k].mean_w_m2, 0) << "bin " << k;
    const double tolerance = 4 * mc[k].sigma_w_m2 + 2e-3 * mc[k].mean_w_m2;
    EXPECT_NEAR(cached, mc[k].mean_w_m2, tolerance)
        << model.name << " light " << angle / kDeg << " deg at " << distance << " mm, bin (" << bins[k].cx
        << ", " << bins[k].cy << "): Monte Carlo " << mc[k].mean_w_m2 << " +- " << mc[k].sigma_w_m2
        << " W/m^2, deviation " << (cached - mc[k].mean_w_m2) / mc[k].mean_w_m2 * 100 << " %";
    // The reference mode's per-point solve (no cache), over the same bin.
    constexpr int kPoints = 12;
    double solved = 0;
    for (int j = 0; j < kPoints; ++j) {
      for (int i = 0; i < kPoints; ++i) {
        const double x = bins[k].cx - bins[k].half + (i + 0.5) * 2 * bins[k].half / kPoints;
        const double y = bins[k].cy - bins[k].half + (j + 0.5) * 2 * bins[k].half / kPoints;
        solved += refracted_irradiance_w_m2(eye, light, intensity, world(eye, x, y, z)) / (kPoints * kPoints);
      }
    }
    EXPECT_NEAR(solved, mc[k].mean_w_m2, tolerance)
        << model.name << " light " << angle / kDeg << " deg at " << distance << " mm, bin (" << bins[k].cx
        << ", " << bins[k].cy << "): solved per point " << solved << ", Monte Carlo " << mc[k].mean_w_m2;
  }
}

// ---------------------------------------------------------------------------

// A spherical refracting surface images the on-axis light at v behind the
// apex (n / v = (n - 1) / R - 1 / d); the converging beam's cross-section
// at depth t is ((v - t) / v)^2 of its area at the apex, where it is d^2
// per steradian.
TEST(IrisIrradianceCache, MatchesParaxialClosedFormOnTheAxis) {
  const EyeModel m = keratometric_eye();
  const Eye eye = posed(m);
  const double n = m.aqueous_index, R = m.anterior_cornea.radius_mm, t = m.iris_depth_mm;
  const double intensity = 0.02;
  for (const double d : {600.0, 35.0}) {
    const Point3 light = world(eye, 0, 0, R + d);
    const IrisIrradianceCache cache(eye, light, intensity, 33);
    const double v = n / ((n - 1) / R - 1 / d);
    const double t0 = 1 - ((n - 1) / (n + 1)) * ((n - 1) / (n + 1));
    const double expected = intensity / (d * d) * t0 * (v / (v - t)) * (v / (v - t)) * 1e6;
    EXPECT_NEAR(cache.irradiance_w_m2(world(eye, 0, 0, iris_plane_z(m))), expected, 1e-3 * expected)
        << "d = " << d;
    EXPECT_NEAR(refracted_irradiance_w_m2(eye, light, intensity, world(eye, 0, 0, iris_plane_z(m))), expected,
                1e-3 * expected)
        << "d = " << d;
  }
}

// A remote tracker's light, 30 deg off axis and 600 mm away.
TEST(IrisIrradianceCache, MatchesMonteCarloForRemoteObliqueLight) {
  expect_matches_monte_carlo(keratometric_eye(), 30 * kDeg, 600,
                             {{0, 0, 0.75}, {2.5, 0, 0.75}, {-2.5, 0, 0.75}, {0, 2.5, 0.75}, {-3.8, -1.5, 0.75}});
}

// A headset's light, 30 deg off axis and 35 mm away: the far side of the
// cornea receives it at grazing incidence and the iris darkens steeply.
TEST(IrisIrradianceCache, MatchesMonteCarloForNearObliqueLight) {
  expect_matches_monte_carlo(keratometric_eye(), 30 * kDeg, 35,
                             {{0, 0, 0.75}, {3.0, 0, 0.75}, {-2.5, 1.0, 0.75}, {-4.4, 0, 0.5}});
}

TEST(IrisIrradianceCache, MatchesMonteCarloThroughTwoAsphericSurfaces) {
  expect_matches_monte_carlo(navarro_eye(), 30 * kDeg, 35,
                             {{0, 0, 0.75}, {3.0, 0, 0.75}, {-2.5, -1.0, 0.75}, {-4.3, 0, 0.5}});
}

TEST(IrisIrradianceCache, MatchesMonteCarloThroughTwoSphericalSurfaces) {
  // Near the iris' rim, where the iris plane meets the posterior cornea.
  expect_matches_monte_carlo(le_grand_eye(), 20 * kDeg, 600,
                             {{0, 0, 0.75}, {4.7, 0, 0.5}, {0, -4.7, 0.5}, {-3.0, 2.0, 0.75}});
}

// E = I T dOmega/dA with dOmega/dA from the solver alone: the directions
// from the light to the anterior point for iris points 1e-4 mm apart,
// |du/dx x du/dy . u|; T from the angle-form Fresnel factors.
double solver_irradiance(const Eye& eye, const Point3& light, double intensity, double x, double y) {
  const EyeModel& m = eye.model();
  const double z = iris_plane_z(m);
  const Point3 light_eye = eye.eye_from_world() * light;
  const auto direction = [&](double px, double py) {
    const Refraction r = solve_refraction(eye, world(eye, px, py, z), light);
    EXPECT_EQ(r.status, PathStatus::ok) << px << ", " << py;
    const Vector3 u = eye.eye_from_world() * r.anterior_point - light_eye;
    return u / u.norm();
  };
  const double d = 1e-4;
  const Refraction r = solve_refraction(eye, world(eye, x, y, z), light);
  EXPECT_EQ(r.status, PathStatus::ok) << x << ", " << y;
  const Vector3 du_dx = (direction(x + d, y) - direction(x - d, y)) / (2 * d);
  const Vector3 du_dy = (direction(x, y + d) - direction(x, y - d)) / (2 * d);
  const double solid_angle_per_area = std::abs(purkinje::dot(cross(du_dx, du_dy), direction(x, y)));
  double transmittance;
  if (m.posterior_cornea) {
    const double n_c = m.posterior_cornea->cornea_index;
    transmittance = 1 - fresnel_angle_form(std::cos(r.outer_angle_rad), 1.0, n_c);
    // The posterior sphere's centre, eye frame: its apex is the thickness
    // behind the anterior apex.
    const PosteriorCornea& back = *m.posterior_cornea;
    const Point3 centre{0, 0, m.anterior_cornea.radius_mm - back.thickness_mm - back.surface.radius_mm};
    const Point3 x1 = eye.eye_from_world() * r.anterior_point;
    const Point3 x2 = eye.eye_from_world() * *r.posterior_point;
    const Vector3 inside = x1 - x2, normal = x2 - centre;
    const double cos_back = purkinje::dot(inside, normal) / (inside.norm() * normal.norm());
    transmittance *= 1 - fresnel_angle_form(cos_back, n_c, m.aqueous_index);
  } else {
    transmittance = 1 - fresnel_angle_form(std::cos(r.outer_angle_rad), 1.0, m.aqueous_index);
  }
  return intensity * transmittance * solid_angle_per_area * 1e6;
}

// At the grid's nodes the cache holds the exact irradiance.
TEST(IrisIrradianceCache, NodesHoldTheSolversIrradiance) {
  for (const EyeModel& m : {keratometric_eye(), navarro_eye()}) {
    const Eye eye = posed(m);
    const Point3 light = light_at(eye, 30 * kDeg, 35);
    const IrisIrradianceCache cache(eye, light, 0.01, 9);
    const double h = cache.half_size_mm();
    for (const auto& [i, j] : {std::pair{4, 4}, std::pair{2, 4}, std::pair{6, 3}, std::pair{3, 6}}) {
      const double x = -h + 2 * h * i / 8, y = -h + 2 * h * j / 8;
      const double expected = solver_irradiance(eye, light, 0.01, x, y);
      EXPECT_NEAR(cache.irradiance_w_m2(world(eye, x, y, iris_plane_z(m))), expected, 1e-6 * expected)
          << m.name << " node " << i << ", " << j;
    }
  }
}

// Between the nodes, at 33 per side, within 0.5% wherever the iris gets a
// tenth of the light's peak or more, for a remote and a near light.
TEST(IrisIrradianceCache, InterpolatesWithinHalfAPercent) {
  for (const EyeModel& m : {keratometric_eye(), navarro_eye()}) {
    const Eye eye = posed(m);
    for (const double distance : {600.0, 35.0}) {
      const Point3 light = light_at(eye, 30 * kDeg, distance);
      const IrisIrradianceCache cache(eye, light, 1.0, 33);
      const double peak = solver_irradiance(eye, light, 1.0, 1.0, 0.0);
      int checked = 0;
      for (int k = 0; k < 24; ++k) {
        // Spread over the iris (away from its rim, where the iris plane
        // meets the posterior cornea), off the nodes.
        const double angle = k * 2.399963, r = 2.0 + 3.2 * std::sqrt((k + 0.5) / 24);
        const double x = r * std::cos(angle), y = r * std::sin(angle);
        const double cached = cache.irradiance_w_m2(world(eye, x, y, iris_plane_z(m)));
        if (cached < 0.1 * peak) continue;
        const double exact = solver_irradiance(eye, light, 1.0, x, y);
        EXPECT_NEAR(cached, exact, 5e-3 * exact) << m.name << " at " << distance << " mm, " << x << ", " << y;
        ++checked;
      }
      EXPECT_GT(checked, 15) << m.name << " at " << distance << " mm";
    }
  }
}

TEST(IrisIrradianceCache, LightBehindTheEyeGivesNothing) {
  for (const EyeModel& m : {keratometric_eye(), navarro_eye()}) {
    const Eye eye = posed(m);
    const IrisIrradianceCache cache(eye, light_at(eye, 150 * kDeg, 300), 1.0, 17);
    for (double y = -6.5; y <= 6.5; y += 0.25) {
      for (double x = -6.5; x <= 6.5; x += 0.25) {
        ASSERT_EQ(cache.irradiance_w_m2(world(eye, x, y, iris_plane_z(m))), 0.0) << x << ", " << y;
      }
    }
  }
}

TEST(IrisIrradianceCache, HiddenCorneaGivesNothing) {
  const EyeModel m = navarro_eye();
  const Eye eye = posed(m);
  std::atomic<int> calls = 0;  // the cache asks from several threads
  const IrisIrradianceCache cache(eye, light_at(eye, 10 * kDeg, 400), 1.0, 17,
                                  [&calls](const Point3&, const Point3&) {
                                    ++calls;
                                    return false;
                                  });
  EXPECT_GT(calls, 100);
  for (double y = -6.5; y <= 6.5; y += 0.25) {
    for (double x = -6.5; x <= 6.5; x += 0.25) {
      ASSERT_EQ(cache.irradiance_w_m2(world(eye, x, y, iris_plane_z(m))), 0.0) << x << ", " << y;
    }
  }
}

TEST(IrisIrradianceCache, VisibilityIsAskedForTheLightAndAnteriorCorneaPoints) {
  const EyeModel m = keratometric_eye();
  const Eye eye = posed(m);
  const Point3 light = light_at(eye, 10 * kDeg, 400);
  // An upper lid: corneal points above eye y = 1 mm are hidden.
  const IrisIrradianceCache cache(eye, light, 1.0, 33, [&](const Point3& from, const Point3& cornea) {
    EXPECT_EQ(from, light);
    EXPECT_NEAR(distance(cornea, eye.cornea_center()), m.anterior_cornea.radius_mm, 1e-9);
    EXPECT_TRUE(eye.on_cap(cornea));
    return (eye.eye_from_world() * cornea).y < 1.0;
  });
  const double z = iris_plane_z(m);
  const IrisIrradianceCache open(eye, light, 1.0, 33);
  // Light reaches the iris nearly straight down from the cornea.
  for (const double x : {-3.0, 0.0, 3.0}) {
    EXPECT_EQ(cache.irradiance_w_m2(world(eye, x, 3.0, z)), 0.0) << x;
    const Point3 lit = world(eye, x, -2.0, z);
    EXPECT_EQ(cache.irradiance_w_m2(lit), open.irradiance_w_m2(lit)) << x;
    EXPECT_GT(open.irradiance_w_m2(lit), 0.0);
  }
}

// Between nodes on either side of an eyelid's shadow edge, a lookup is
// dark exactly where the solver's path crosses the cornea behind the lid,
// and elsewhere what it is without the lid: the edge is not smeared over
// the interpolation's nodes.
TEST(IrisIrradianceCache, AnEyelidsShadowEdgeIsSharpBetweenNodes) {
  const EyeModel m = keratometric_eye();
  const Eye eye = posed(m);
  const Point3 light = light_at(eye, 10 * kDeg, 400);
  const auto below_lid = [&](const Point3& cornea) { return (eye.eye_from_world() * cornea).y < 1.0; };
  const IrisIrradianceCache lidded(eye, light, 1.0, 33,
                                   [&](const Point3&, const Point3& cornea) { return below_lid(cornea); });
  const IrisIrradianceCache open(eye, light, 1.0, 33);
  const double z = iris_plane_z(m);
  int lit = 0, dark = 0;
  // Across the edge in steps much finer than the nodes' 0.4 mm, off the
  // nodes' columns.
  for (double y = -1.0; y <= 3.0; y += 0.01) {
    const Point3 p = world(eye, 0.77, y, z);
    const Refraction path = solve_refraction(eye, p, light);
    ASSERT_EQ(path.status, PathStatus::ok) << y;
    const double crossing_y = (eye.eye_from_world() * path.anterior_point).y;
    // The cache's crossing is interpolated: within a micrometre of the solver's.
    if (std::abs(crossing_y - 1.0) < 1e-3) continue;
    if (crossing_y < 1.0) {
      ++lit;
      EXPECT_GT(open.irradiance_w_m2(p), 0.0) << y;
      EXPECT_DOUBLE_EQ(lidded.irradiance_w_m2(p), open.irradiance_w_m2(p)) << y;
    } else {
      ++dark;
      EXPECT_EQ(lidded.irradiance_w_m2(p), 0.0) << y;
    }
  }
  EXPECT_GT(lit, 50);
  EXPECT_GT(dark, 50);
}

TEST(IrisIrradianceCache, RejectsBadInputs) {
  const Eye eye = posed(keratometric_eye());
  const Point3 light = light_at(eye, 0, 500);
  for (const int resolution : {1, 0, -4}) {
    EXPECT_THROW(IrisIrradianceCache(eye, light, 1.0, resolution), std::invalid_argument) << resolution;
  }
  for (const double intensity : {-1e-3, std::numeric_limits<double>::quiet_NaN(),
                                 std::numeric_limits<double>::infinity()}) {
    EXPECT_THROW(IrisIrradianceCache(eye, light, intensity, 9), std::invalid_argument) << intensity;
  }
  EXPECT_THROW(IrisIrradianceCache(eye, {0, std::numeric_limits<double>::quiet_NaN(), 0}, 1.0, 9),
               std::invalid_argument);
  try {
    IrisIrradianceCache(eye, light, 1.0, 1);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("resolution = 1"), std::string::npos) << e.what();
  }
}

TEST(IrisIrradianceCache, ZeroIntensityAndPointsOffTheGridGiveZero) {
  const EyeModel m = keratometric_eye();
  const Eye eye = posed(m);
  const Point3 light = light_at(eye, 0, 500);
  const IrisIrradianceCache dark(eye, light, 0.0, 9);
  EXPECT_EQ(dark.irradiance_w_m2(world(eye, 0, 0, iris_plane_z(m))), 0.0);
  const IrisIrradianceCache cache(eye, light, 1.0, 2);  // the smallest grid works
  EXPECT_EQ(cache.resolution(), 2);
  const double h = cache.half_size_mm();
  // Out to the sclera at the iris plane: 12 mm sphere, 9.9 mm below its centre.
  EXPECT_NEAR(h, std::sqrt(12.0 * 12.0 - 9.9 * 9.9), 1e-12);
  EXPECT_EQ(cache.irradiance_w_m2(world(eye, h * 1.01, 0, iris_plane_z(m))), 0.0);
  EXPECT_EQ(cache.irradiance_w_m2(world(eye, 0, -h * 1.01, iris_plane_z(m))), 0.0);
  EXPECT_EQ(cache.irradiance_w_m2({std::numeric_limits<double>::quiet_NaN(), 0, 0}), 0.0);
}

// Grazing and total internal reflection: a light far to the side leaves
// most of the grid without a path, and what remains must stay finite.
TEST(IrisIrradianceCache, StaysFiniteAndNonNegativeAtGrazingLight) {
  for (const EyeModel& m : {keratometric_eye(), le_grand_eye(), navarro_eye()}) {
    const Eye eye = posed(m);
    for (const double angle : {60.0, 80.0, 95.0}) {
      const IrisIrradianceCache cache(eye, light_at(eye, angle * kDeg, 40), 1.0, 17);
      int lit = 0;
      for (double y = -7; y <= 7; y += 0.13) {
        for (double x = -7; x <= 7; x += 0.13) {
          const double e = cache.irradiance_w_m2(world(eye, x, y, iris_plane_z(m)));
          ASSERT_TRUE(std::isfinite(e) && e >= 0) << m.name << " " << angle << ": " << e;
          lit += e > 0;
        }
      }
      if (angle < 90) {
        EXPECT_GT(lit, 0) << m.name << " " << angle;
      }
    }
  }
}

// Doubling the resolution changes the mean over the iris by < 0.5%: at 33
// nodes for the keratometric eye, already at 17 for Navarro's (whose
// solves cost more in a debug build).
TEST(IrisIrradianceCache, MeanOverTheIrisConvergesWithResolution) {
  for (const EyeModel& m : {keratometric_eye(), navarro_eye()}) {
    const Eye eye = posed(m);
    const Point3 light = light_at(eye, 35 * kDeg, 30);
    const int n = m.posterior_cornea ? 17 : 33;
    const IrisIrradianceCache coarse(eye, light, 1.0, n), fine(eye, light, 1.0, 2 * n - 1);
    double sum_coarse = 0, sum_fine = 0;
    for (double y = -m.iris_radius_mm; y <= m.iris_radius_mm; y += 0.07) {
      for (double x = -m.iris_radius_mm; x <= m.iris_radius_mm; x += 0.07) {
        const double r = std::hypot(x, y);
        if (r < m.pupil_radius_mm || r > m.iris_radius_mm) continue;
        const Point3 p = world(eye, x, y, iris_plane_z(m));
        sum_coarse += coarse.irradiance_w_m2(p);
        sum_fine += fine.irradiance_w_m2(p);
      }
    }
    ASSERT_GT(sum_fine, 0);
    EXPECT_NEAR(sum_coarse / sum_fine, 1.0, 5e-3) << m.name;
  }
}

TEST(IrisIrradianceCache, IsDeterministic) {
  const EyeModel m = navarro_eye();
  const Eye eye = posed(m);
  const Point3 light = light_at(eye, 40 * kDeg, 35);
  const IrisIrradianceCache a(eye, light, 1.0, 21), b(eye, light, 1.0, 21);
  for (double y = -6; y <= 6; y += 0.37) {
    for (double x = -6; x <= 6; x += 0.37) {
      const Point3 p = world(eye, x, y, iris_plane_z(m));
      ASSERT_EQ(a.irradiance_w_m2(p), b.irradiance_w_m2(p));
    }
  }
}

// ---------------------------------------------------------------------------
// iris_albedo

struct IrisStats {
  double mean = 0, sd = 0, min = 1, max = 0;
};

IrisStats iris_stats(const EyeModel& m, const EyeAppearance& a, double step = 0.03) {
  IrisStats s;
  double sum = 0, sum2 = 0;
  int n = 0;
  for (double y = -m.iris_radius_mm; y <= m.iris_radius_mm; y += step) {
    for (double x = -m.iris_radius_mm; x <= m.iris_radius_mm; x += step) {
      if (std::hypot(x, y) > m.iris_radius_mm ||
          std::hypot(x - m.pupil_decentration_x_mm, y - m.pupil_decentration_y_mm) < m.pupil_radius_mm) {
        continue;
      }
      const double v = iris_albedo(m, a, x, y);
      sum += v;
      sum2 += v * v;
      s.min = std::min(s.min, v);
      s.max = std::max(s.max, v);
      ++n;
    }
  }
  s.mean = sum / n;
  s.sd = std::sqrt(std::max(0.0, sum2 / n - s.mean * s.mean));
  return s;
}

TEST(IrisAlbedo, IsDeterministicAndWithinZeroToOne) {
  EyeModel m = navarro_eye();
  m.pupil_decentration_x_mm = 0.3;
  for (const double contrast : {0.5, 1.0, 3.0}) {
    for (const double albedo : {0.05, 0.25, 0.9}) {
      EyeAppearance a;
      a.iris_albedo = albedo;
      a.iris_texture_contrast = contrast;
      for (double y = -7; y <= 7; y += 0.11) {
        for (double x = -7; x <= 7; x += 0.11) {
          const double v = iris_albedo(m, a, x, y);
          ASSERT_TRUE(v >= 0 && v <= 1) << v << " at " << x << ", " << y;
          ASSERT_EQ(v, iris_albedo(m, a, x, y));
        }
      }
    }
  }
  EyeAppearance a;
  EXPECT_EQ(iris_albedo(m, a, std::numeric_limits<double>::quiet_NaN(), 0), a.iris_albedo);
}

TEST(IrisAlbedo, MeanIsTheAppearancesAlbedo) {
  EyeModel m = navarro_eye();
  for (const double pupil : {1.5, 2.0, 3.0}) {
    for (const std::uint64_t seed : {1u, 2u, 99u}) {
      m.pupil_radius_mm = pupil;
      m.pupil_decentration_x_mm = seed == 2 ? 0.4 : 0.0;
      EyeAppearance a;
      a.iris_seed = seed;
      a.iris_albedo = 0.3;
      const IrisStats s = iris_stats(m, a);
      EXPECT_NEAR(s.mean, 0.3, 0.03) << "pupil " << pupil << " seed " << seed;
      // Structure: a textured iris, not a flat one, at the default contrast.
      EXPECT_GT(s.sd, 0.12 * s.mean) << "pupil " << pupil << " seed " << seed;
      EXPECT_LT(s.min, 0.5 * s.mean);
      EXPECT_GT(s.max, 1.3 * s.mean);
    }
  }
}

TEST(IrisAlbedo, ZeroContrastIsFlat) {
  const EyeModel m = le_grand_eye();
  EyeAppearance a;
  a.iris_texture_contrast = 0;
  a.iris_albedo = 0.37;
  for (double y = -7; y <= 7; y += 0.23) {
    for (double x = -7; x <= 7; x += 0.23) {
      ASSERT_EQ(iris_albedo(m, a, x, y), 0.37);
    }
  }
}

TEST(IrisAlbedo, SeedsGiveDifferentIrises) {
  const EyeModel m = navarro_eye();
  EyeAppearance a, b;
  a.iris_seed = 1;
  b.iris_seed = 2;
  int differ = 0, total = 0;
  for (double y = -5; y <= 5; y += 0.1) {
    for (double x = -5; x <= 5; x += 0.1) {
      const double r = std::hypot(x, y);
      if (r < 2.2 || r > 5.3) continue;
      differ += std::abs(iris_albedo(m, a, x, y) - iris_albedo(m, b, x, y)) > 0.01;
      ++total;
    }
  }
  EXPECT_GT(differ, total / 2);
}

// Fibres run radially: neighbours 0.05 mm apart along a radius are more
// alike than neighbours as far apart across it.
TEST(IrisAlbedo, FibresRunRadially) {
  const EyeModel m = navarro_eye();
  const EyeAppearance a;
  double along = 0, across = 0;
  for (int k = 0; k < 3000; ++k) {
    const double angle = k * 2 * kPi / 3000;
    const double r = 3.0 + 1.5 * std::sin(k * 0.37);
    const double c = std::cos(angle), s = std::sin(angle);
    const double v = iris_albedo(m, a, r * c, r * s);
    along += std::abs(iris_albedo(m, a, (r + 0.05) * c, (r + 0.05) * s) - v);
    across += std::abs(iris_albedo(m, a, r * c - 0.05 * s, r * s + 0.05 * c) - v);
  }
  EXPECT_LT(along, 0.5 * across);
}

// The pattern lives on the normalized radius between the pupil's border
// and the iris', so it stretches with the pupil.
TEST(IrisAlbedo, PatternStretchesWithThePupil) {
  EyeModel small = navarro_eye(), large = navarro_eye();
  small.pupil_radius_mm = 1.5;
  large.pupil_radius_mm = 3.0;
  const EyeAppearance a;
  for (int k = 0; k < 200; ++k) {
    const double angle = k * 0.731, rho = 0.02 + 0.96 * (k % 17) / 16.0;
    const double rs = 1.5 + rho * (5.5 - 1.5), rl = 3.0 + rho * (5.5 - 3.0);
    EXPECT_NEAR(iris_albedo(small, a, rs * std::cos(angle), rs * std::sin(angle)),
                iris_albedo(large, a, rl * std::cos(angle), rl * std::sin(angle)), 1e-6)
        << "rho " << rho << " angle " << angle;
  }
}

// Angular means at normalized radius rho: the ruff at the pupil, the
// collarette at about a third, the limbal ring at the edge are darker than
// the iris between them; beyond the iris the limbal value holds.
TEST(IrisAlbedo, RingsAreDarker) {
  const EyeModel m = navarro_eye();
  EyeAppearance a;
  a.iris_albedo = 0.3;
  auto ring_mean = [&](double rho) {
    double sum = 0;
    const int n = 4000;
    for (int k = 0; k < n; ++k) {
      const double angle = 2 * kPi * k / n, r = 2.0 + rho * 3.5;
      sum += iris_albedo(m, a, r * std::cos(angle), r * std::sin(angle));
    }
    return sum / n;
  };
  const double mid = ring_mean(0.6), inner = ring_mean(0.2);
  EXPECT_LT(ring_mean(0.005), 0.8 * std::min(mid, inner));  // pupillary ruff
  EXPECT_LT(ring_mean(0.33), std::min(mid, inner) - 0.01);   // collarette
  EXPECT_LT(ring_mean(0.99), 0.8 * mid);                     // limbal ring
  const double beyond = iris_albedo(m, a, 5.8, 0.3);
  EXPECT_LT(beyond, 0.8 * 0.3);
  EXPECT_EQ(beyond, iris_albedo(m, a, -0.2, -6.5));
}

// Contraction furrows (iris_furrow_contrast, on a flat iris so that they
// alone vary it): broken dark rings only over the outer third, at most
// 0.8 of the mean darker; none at 0.
TEST(IrisAlbedo, FurrowsAreBrokenDarkRingsOverTheOuterThird) {
  const EyeModel m = navarro_eye();
  EyeAppearance a;
  a.iris_albedo = 0.3;
  a.iris_texture_contrast = 0;
  a.iris_furrow_contrast = 1;
  const double pupil = m.pupil_radius_mm, span = m.iris_radius_mm - pupil;
  ASSERT_EQ(m.pupil_decentration_x_mm, 0);
  ASSERT_EQ(m.pupil_decentration_y_mm, 0);
  const int n = 2000;
  double darkest_ring = 1;
  for (double rho = 0.02; rho < 0.99; rho += 0.005) {
    double sum = 0, darkest = 1;
    int dark = 0, untouched = 0;
    for (int k = 0; k < n; ++k) {
      const double angle = 2 * kPi * k / n, r = pupil + rho * span;
      const double v = iris_albedo(m, a, r * std::cos(angle), r * std::sin(angle));
      EXPECT_GE(v, 0.3 * (1 - 0.8) - 1e-12);
      sum += v;
      darkest = std::min(darkest, v);
      dark += v < 0.3 * 0.7;
      untouched += v == 0.3;
    }
    if (rho < 0.55) {
      EXPECT_EQ(darkest, 0.3) << "a furrow inside the outer third, at rho " << rho;
      continue;
    }
    darkest_ring = std::min(darkest_ring, sum / n);
    // Broken: no ring is dark all round.
    if (dark > 0) {
      EXPECT_GT(untouched, n / 10) << "rho " << rho;
    }
  }
  EXPECT_LT(darkest_ring, 0.3 * 0.85);
  // The mean falls by the darkened area's share (scene-format.md: 4%).
  const double mean = iris_stats(m, a).mean;
  RecordProperty("mean_fall", std::to_string(1 - mean / 0.3));
  EXPECT_LT(mean, 0.3 * 0.985);
  EXPECT_GT(mean, 0.3 * 0.95);
  a.iris_furrow_contrast = 0;
  EXPECT_EQ(iris_albedo(m, a, 0, pupil + 0.72 * span), 0.3);
}

// Freckles (iris_freckles, on a flat iris): that many round dark spots
// 0.1 to 0.3 mm across, 0.4 to 0.7 of the mean darker at their middles,
// elsewhere with another seed; none at 0.
TEST(IrisAlbedo, FrecklesAreThatManyRoundSpots) {
  const EyeModel m = navarro_eye();
  EyeAppearance a;
  a.iris_albedo = 0.3;
  a.iris_texture_contrast = 0;
  a.iris_freckles = 6;
  const double step = 0.01, extent = m.iris_radius_mm;
  const int size = static_cast<int>(2 * extent / step) + 1;
  std::vector<int> label(static_cast<std::size_t>(size) * size, 0);  // -1 dark, unlabelled; k > 0 spot k
  const auto at = [&](int i, int j) -> int& { return label[static_cast<std::size_t>(j) * size + i]; };
  double darkest = 1;
  for (int j = 0; j < size; ++j) {
    for (int i = 0; i < size; ++i) {
      const double v = iris_albedo(m, a, -extent + i * step, -extent + j * step);
      darkest = std::min(darkest, v);
      if (std::hypot(-extent + i * step, -extent + j * step) <= extent && v < 0.3 * 0.9) at(i, j) = -1;
    }
  }
  EXPECT_LT(darkest, 0.3 * (1 - 0.4) + 0.01);
  EXPECT_GE(darkest, 0.3 * (1 - 0.7) - 1e-12);
  // Connected dark regions, each round: its extent across x and y alike,
  // and no wider than 0.3 mm.
  int spots = 0;
  for (int j = 0; j < size; ++j) {
    for (int i = 0; i < size; ++i) {
      if (at(i, j) != -1) continue;
      ++spots;
      int x0 = i, x1 = i, y0 = j, y1 = j;
      std::vector<std::pair<int, int>> stack{{i, j}};
      at(i, j) = spots;
      while (!stack.empty()) {
        const auto [u, v] = stack.back();
        stack.pop_back();
        x0 = std::min(x0, u), x1 = std::max(x1, u), y0 = std::min(y0, v), y1 = std::max(y1, v);
        for (const auto& [du, dv] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
          const int p = u + du, q = v + dv;
          if (p < 0 || q < 0 || p >= size || q >= size || at(p, q) != -1) continue;
          at(p, q) = spots;
          stack.push_back({p, q});
        }
      }
      const double w = (x1 - x0 + 1) * step, h = (y1 - y0 + 1) * step;
      EXPECT_LT(std::max(w, h), 0.3 + 2 * step) << "spot " << spots;
      EXPECT_LT(std::max(w, h) / std::min(w, h), 1.35) << "spot " << spots << ": " << w << " x " << h << " mm";
    }
  }
  EXPECT_EQ(spots, 6);
  // Another seed, other places.
  EyeAppearance b = a;
  b.iris_seed = 2;
  int moved = 0;
  for (int j = 0; j < size; j += 2) {
    for (int i = 0; i < size; i += 2) {
      if (at(i, j) > 0) moved += iris_albedo(m, b, -extent + i * step, -extent + j * step) >= 0.3 * 0.9;
    }
  }
  EXPECT_GT(moved, 0);
  a.iris_freckles = 0;
  for (int k = 0; k < 50; ++k) EXPECT_EQ(iris_albedo(m, a, 3.5 * std::cos(k), 3.5 * std::sin(k)), 0.3);
}

}  // namespace
}  // namespace purkinje::renderer
