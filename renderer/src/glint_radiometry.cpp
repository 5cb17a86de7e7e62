// Glint radiometry measured from the specular-path solver itself: the
// solid angle at the LED of the rays that reach the aperture, and the image
// of the LED's emitting disc, both from central differences of solved
// reflections. Nothing here assumes a sphere, so conicoids and two-surface
// eyes get the same treatment as the keratometric eye.

#include <cmath>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>

#include "lens_light.h"
#include "mirror_radiometry.h"
#include "purkinje/models/check.h"
#include "purkinje/models/truth.h"

namespace purkinje::renderer {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Step of the central differences, as a fraction of the lever arm it acts
// over (glint point to aperture centre, LED to glint point). Truncation
// grows as step^2 (about 0.7 step^2 relative, 90 step^2 at 89 degrees of
// incidence); the solver's points carry ~1e-11 mm of noise, which a step
// too small turns into error (3e-6 at 600 mm with a step of 1e-5).
// Measured against the closed form of a spherical mirror and of conicoids
// in their meridional plane, 1e-4 leaves 2e-9 to 1.2e-7 up to 85 degrees of
// incidence and 9e-7 at 89 degrees.
constexpr double kRelativeStep = 1e-4;

using check::require_non_negative;
using check::require_positive;

// A perturbed reflection is usable for differencing whenever its geometry
// exists: a neighbour of a glint near the limbus may fall just off the cap,
// and the surface is smooth across the limbus.
bool has_geometry(const Reflection& r) {
  return r.status == PathStatus::ok || r.status == PathStatus::off_cornea;
}

// d f / d s at s = 0 from samples at +-step; one-sided from the centre value
// when one neighbour has no path, nullopt when neither has.
template <class Sample>
std::optional<Vector3> difference(const Sample& sample, const Vector3& centre, double step) {
  const std::optional<Vector3> plus = sample(step), minus = sample(-step);
  if (plus && minus) return (*plus - *minus) / (2 * step);
  if (plus) return (*plus - centre) / step;
  if (minus) return (centre - *minus) / step;
  return std::nullopt;
}

GlintRadiometry failed(PathStatus status) { return failed_radiometry(status); }

}  // namespace

UnitVector3 perpendicular(const UnitVector3& d) {
  const Vector3 any = std::abs(d.x()) < 0.9 ? Vector3{1, 0, 0} : Vector3{0, 1, 0};
  return UnitVector3::normalize(any - d.vector() * dot(any, d));
}

GlintRadiometry failed_radiometry(PathStatus status) {
  GlintRadiometry out;
  out.status = status;
  return out;
}

void check_radiometry_inputs(const Illuminator& light, const Camera& camera) {
  require_non_negative("light '" + light.name + "': radiant_intensity_w_sr",
                       light.radiant_intensity_w_sr);
  require_non_negative("light '" + light.name + "': emitter_diameter_mm",
                       light.emitter_diameter_mm);
  require_positive("camera '" + camera.name() + "': sensor.f_number", camera.sensor().f_number);
  require_positive("camera '" + camera.name() + "': sensor.pixel_pitch_mm",
                   camera.sensor().pixel_pitch_mm);
}

namespace {

// mirror_radiometry without lenses.
GlintRadiometry straight_radiometry(const Mirror& mirror, double reflectance, const Illuminator& light,
                                    const Camera& camera, const Reflection& reflection);

}  // namespace

GlintRadiometry mirror_radiometry(const Mirror& mirror, double reflectance, const Illuminator& light,
                                  const Camera& camera, const Reflection& reflection, const Scene* lenses) {
  if (!lenses || lenses->spectacle_lenses.empty()) return straight_radiometry(mirror, reflectance, light, camera, reflection);
  // Each of the mirror's reflections as the camera sees it through the
  // lenses: what the differences below need of a reflection is where the
  // camera sees it and the direction in which its light leaves the LED.
  const auto as_seen = [](const SeenHighlight& h) {
    Reflection r = h.reflection;
    r.point = h.seen_at();
    r.incident = h.from_light();
    return r;
  };
  const auto seen = [&](const Point3& source, const Point3& target) {
    return as_seen(see_highlight(*lenses, source, target, mirror));
  };
  const SeenHighlight central = see_highlight(*lenses, light.position, camera.center(), mirror);
  if (central.reflection.status != PathStatus::ok ||
      distance(central.reflection.point, reflection.point) > 1e-9) {
    return failed(PathStatus::not_converged);  // not this highlight's path
  }
  GlintRadiometry out = straight_radiometry(seen, reflectance, light, camera, as_seen(central));
  for (const Leg* leg : {&central.to_camera, &central.to_light}) {
    if (leg->passage) out.power_w *= lens_transmittance(*leg->passage, lenses->spectacle_lenses[leg->lens].refractive_index);
  }
  return out;
}

namespace {

GlintRadiometry straight_radiometry(const Mirror& mirror, double reflectance, const Illuminator& light,
                                    const Camera& camera, const Reflection& reflection) {
  GlintRadiometry out;
  out.status = PathStatus::ok;
  out.fresnel = reflectance;

  // Solid angle at the LED per unit aperture area: how the incident
  // direction turns as the target slides over the aperture plane. The
  // parallelogram of the two derivatives, projected on the incident
  // direction, is the area element on the unit sphere of directions.
  // The centre's value stands for the whole disc: the disc's own average
  // differs by about 0.4 (aperture radius / distance)^2 (Monte Carlo:
  // 5e-4 for a 2.1 mm aperture at 30 mm, under 1e-4 for usual apertures).
  const Point3 aperture_center = camera.center();
  const Rotation& camera_axes = camera.world_from_camera().rotation();
  const Vector3 incident = reflection.incident.vector();
  const double aperture_step = kRelativeStep * distance(reflection.point, aperture_center);
  const auto incident_toward = [&](const UnitVector3& axis) {
    return [&, axis](double s) -> std::optional<Vector3> {
      const Reflection r = mirror(light.position, aperture_center + axis * s);
      if (!has_geometry(r)) return std::nullopt;
      return r.incident.vector();
    };
  };
  const std::optional<Vector3> d_dx =
      difference(incident_toward(camera_axes.column(0)), incident, aperture_step);
  const std::optional<Vector3> d_dy =
      difference(incident_toward(camera_axes.column(1)), incident, aperture_step);
  if (!d_dx || !d_dy) return failed(PathStatus::not_converged);
  const double solid_angle_per_area = std::abs(dot(cross(*d_dx, *d_dy), incident));  // sr/mm^2
  const double aperture_diameter = camera.focal_length_mm() / camera.sensor().f_number;
  const double aperture_area = 0.25 * kPi * aperture_diameter * aperture_diameter;  // mm^2
  out.power_w =
      light.radiant_intensity_w_sr * out.fresnel * solid_angle_per_area * aperture_area;

  // The LED's disc: how the glint pixel moves as the emitter point slides
  // across the disc, which faces the glint point.
  if (light.emitter_diameter_mm > 0) {
    const Projection centre = camera.project(reflection.point);
    if (centre.status != ProjectionStatus::behind_camera) {
      const Vector3 centre_px{centre.pixel.u, centre.pixel.v, 0};
      const double source_step = kRelativeStep * distance(light.position, reflection.point);
      const auto pixel_moving_along = [&](const UnitVector3& axis) {
        return [&, axis](double s) -> std::optional<Vector3> {
          const Reflection r = mirror(light.position + axis * s, aperture_center);
          if (!has_geometry(r)) return std::nullopt;
          const Projection p = camera.project(r.point);
          if (p.status == ProjectionStatus::behind_camera) return std::nullopt;
          return Vector3{p.pixel.u, p.pixel.v, 0};
        };
      };
      const UnitVector3 e1 = perpendicular(reflection.incident);
      const UnitVector3 e2 = UnitVector3::normalize(cross(reflection.incident, e1));
      const std::optional<Vector3> j1 = difference(pixel_moving_along(e1), centre_px, source_step);
      const std::optional<Vector3> j2 = difference(pixel_moving_along(e2), centre_px, source_step);
      if (!j1 || !j2) return failed(PathStatus::not_converged);
      // A uniform disc of radius r has variance r^2 / 4 along any axis of
      // its plane; J carries it to the image. Any orthonormal e1, e2 give
      // the same J J^T.
      const double r = 0.5 * light.emitter_diameter_mm;
      const double var = 0.25 * r * r;
      out.source_cov_px2[0] = var * (j1->x * j1->x + j2->x * j2->x);
      out.source_cov_px2[1] = var * (j1->x * j1->y + j2->x * j2->y);
      out.source_cov_px2[2] = var * (j1->y * j1->y + j2->y * j2->y);
    }
  }

  const bool finite = std::isfinite(out.power_w) && std::isfinite(out.fresnel) &&
                      std::isfinite(out.source_cov_px2[0]) &&
                      std::isfinite(out.source_cov_px2[1]) && std::isfinite(out.source_cov_px2[2]);
  if (!finite) return failed(PathStatus::not_converged);
  return out;
}

}  // namespace

bool roughness_spread(const double shape[3], const UnitVector3& t1, const UnitVector3& t2, double sigma_rad,
                      const Illuminator& light, const Camera& camera, const Reflection& reflection,
                      double cov_px2[3]) {
  const Point3& x = reflection.point;
  const Vector3 to_light = -reflection.incident.vector(), to_camera = reflection.reflected.vector();
  const double d_s = distance(light.position, x), d_c = distance(camera.center(), x);
  const double half_norm = (to_light + to_camera).norm();  // 2 cos(incidence)
  // t_a . (S + [P_s/d_s + P_c/d_c] / |s + c|) t_b; dot(t1, t2) = 0.
  const auto m = [&](const UnitVector3& a, const UnitVector3& b, double a_dot_b, double s_ab) {
    const double p_s = a_dot_b - dot(a, to_light) * dot(b, to_light);
    const double p_c = a_dot_b - dot(a, to_camera) * dot(b, to_camera);
    return s_ab + (p_s / d_s + p_c / d_c) / half_norm;
  };
  const double m11 = m(t1, t1, 1, shape[0]), m12 = m(t1, t2, 0, shape[1]), m22 = m(t2, t2, 1, shape[2]);
  // M^-1 (symmetric); the spread on the surface is sigma^2 M^-2.
  const double det = m11 * m22 - m12 * m12;
  const double i11 = m22 / det, i12 = -m12 / det, i22 = m11 / det;
  const double s11 = sigma_rad * sigma_rad * (i11 * i11 + i12 * i12);
  const double s12 = sigma_rad * sigma_rad * (i11 * i12 + i12 * i22);
  const double s22 = sigma_rad * sigma_rad * (i12 * i12 + i22 * i22);
  // The camera's projection of tangent moves on the surface.
  const double step = kRelativeStep * d_c;
  const auto pixel_along = [&](const UnitVector3& t) -> std::optional<Vector3> {
    const Projection plus = camera.project(x + t * step), minus = camera.project(x - t * step);
    if (plus.status == ProjectionStatus::behind_camera || minus.status == ProjectionStatus::behind_camera) {
      return std::nullopt;
    }
    return Vector3{plus.pixel.u - minus.pixel.u, plus.pixel.v - minus.pixel.v, 0} / (2 * step);
  };
  const std::optional<Vector3> j1 = pixel_along(t1), j2 = pixel_along(t2);
  if (!j1 || !j2 || det == 0) return false;
  // J S J^T with J = [j1 j2] (columns: pixel per mm along t1, t2).
  const auto cov = [&](double a_u, double a_v, double b_u, double b_v) {
    return a_u * (s11 * b_u + s12 * b_v) + a_v * (s12 * b_u + s22 * b_v);
  };
  cov_px2[0] = cov(j1->x, j2->x, j1->x, j2->x);
  cov_px2[1] = cov(j1->x, j2->x, j1->y, j2->y);
  cov_px2[2] = cov(j1->y, j2->y, j1->y, j2->y);
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(cov_px2[i])) return false;
  }
  return true;
}

GlintRadiometry ghost_radiometry(const SpectacleLens& lens, LensSurface surface, const Illuminator& light,
                                 const Camera& camera) {
  check_radiometry_inputs(light, camera);
  // What mirror_radiometry differences: where the camera sees the ghost
  // and the direction in which its light leaves the LED.
  const Mirror seen = [&](const Point3& source, const Point3& target) {
    const LensReflection g = solve_lens_reflection(lens, surface, source, target);
    Reflection r = g.mirror;
    r.status = g.status;
    r.point = g.exit;
    r.incident = g.from_source;
    return r;
  };
  const LensReflection ghost = solve_lens_reflection(lens, surface, light.position, camera.center());
  if (ghost.status != PathStatus::ok) return failed(ghost.status);
  const double n = lens.refractive_index;
  const double cos_mirror = std::cos(ghost.mirror.incidence_rad);
  double reflectance = fresnel_reflectance(cos_mirror, 1.0, n);
  if (surface == LensSurface::back) {
    // Inside the glass, and through the front surface in and out.
    const Point3 centre = lens.world_from_lens * Point3{0, 0, -lens.front_radius_mm};
    const auto crossing = [&](const Point3& p, const UnitVector3& in_air) {
      return 1 - fresnel_reflectance(std::abs(dot(in_air, UnitVector3::normalize(p - centre))), 1.0, n);
    };
    reflectance = fresnel_reflectance(cos_mirror, n, 1.0) * crossing(ghost.entry, ghost.from_source) *
                  crossing(ghost.exit, ghost.to_target);
  }
  return mirror_radiometry(seen, reflectance, light, camera, seen(light.position, camera.center()));
}

GlintRadiometry glint_radiometry(const Eye& eye, const Illuminator& light, const Camera& camera,
                                 const Reflection& reflection, const Scene* lenses) {
  check_radiometry_inputs(light, camera);
  if (reflection.status != PathStatus::ok) return failed(reflection.status);
  if (!reflection.on_cap) return failed(PathStatus::off_cornea);
  const Mirror cornea = [&](const Point3& source, const Point3& target) {
    return solve_reflection(eye, source, target);
  };
  return mirror_radiometry(cornea,
                           fresnel_reflectance(std::cos(reflection.incidence_rad), 1.0, anterior_inner_index(eye.model())),
                           light, camera, reflection, lenses);
}

GlintRadiometry scleral_highlight_radiometry(const Eye& eye, const TearFilm& film, const Illuminator& light,
                                             const Camera& camera, const Reflection& reflection, const Scene* lenses) {
  check_radiometry_inputs(light, camera);
  require_non_negative("tear_film.sclera_roughness_deg", film.sclera_roughness_deg);
  if (reflection.status != PathStatus::ok) return failed(reflection.status);
  // The sphere goes on smoothly under the cornea: neighbours of a
  // highlight by the seam keep their paths.
  const Point3 centre = eye.rotation_center();
  const double R = eye.model().sclera_radius_mm;
  const Mirror sphere = [&](const Point3& source, const Point3& target) {
    return solve_sphere_reflection(centre, R, source, target);
  };
  GlintRadiometry out = mirror_radiometry(
      sphere, fresnel_reflectance(std::cos(reflection.incidence_rad), 1.0, kTearFilmIndex), light, camera, reflection, lenses);
  if (out.status != PathStatus::ok || film.sclera_roughness_deg == 0) return out;
  // A sphere: S = I / R in any tangent basis.
  const UnitVector3 t1 = perpendicular(reflection.normal);
  const UnitVector3 t2 = UnitVector3::normalize(cross(reflection.normal, t1));
  const double shape[3] = {1 / R, 0, 1 / R};
  const double sigma = film.sclera_roughness_deg * kPi / 180;
  // A convex sphere's M is positive definite: no caustic.
  if (!roughness_spread(shape, t1, t2, sigma, light, camera, reflection, out.roughness_cov_px2)) {
    return failed(PathStatus::not_converged);
  }
  return out;
}

}  // namespace purkinje::renderer
