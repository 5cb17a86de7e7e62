// Spectacle lenses in the renderer: the ray tracer meets their surfaces
// (occlusion queries look through them), the lights seen through them
// (SeenLights) against each point's own exact image, the power of a glint
// and a ghost seen through a lens against brute force (the share of a fine
// grid of rays from the LED, traced by hand, that enters the aperture),
// and rendered ghosts and glints where their labels put them with the
// electrons they give.

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "lens_light.h"
#include "materials.h"
#include "mirror_radiometry.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/models/specular.h"
#include "purkinje/models/truth.h"
#include "purkinje/renderer/radiometry.h"
#include "purkinje/renderer/ray_tracer.h"
#include "purkinje/renderer/render.h"

namespace purkinje::renderer {
namespace {

Scene glasses() { return load_scene(std::string(PURKINJE_SOURCE_DIR) + "/assets/scenes/remote_glasses.json"); }

// ------------------------------------------------------- rays by hand

struct Ray3 {
  Point3 origin;
  Vector3 direction;
};

std::optional<Point3> next_crossing(const Ray3& ray, const Point3& centre, double radius) {
  const Vector3 m = ray.origin - centre;
  const double b = dot(m, ray.direction), c = m.squared_norm() - radius * radius;
  const double disc = b * b - c;
  if (disc < 0) return std::nullopt;
  const double t = c < 0 ? -b + std::sqrt(disc) : -b - std::sqrt(disc);
  if (!(t > 1e-9)) return std::nullopt;
  return ray.origin + ray.direction * t;
}

// Snell's law at a sphere (n1 into n2), the transmitted ray and its
// Fresnel transmittance.
std::optional<Ray3> refract_at(const Ray3& ray, const Point3& centre, double radius, double n1, double n2,
                               double& weight) {
  const std::optional<Point3> p = next_crossing(ray, centre, radius);
  if (!p) return std::nullopt;
  Vector3 n = (*p - centre) / radius;
  if (dot(n, ray.direction) > 0) n = -n;
  const double eta = n1 / n2, cos_i = -dot(n, ray.direction);
  const double k = 1 - eta * eta * (1 - cos_i * cos_i);
  if (k < 0) return std::nullopt;
  weight *= 1 - fresnel_reflectance(cos_i, n1, n2);
  const Vector3 t = ray.direction * eta + n * (eta * cos_i - std::sqrt(k));
  return Ray3{*p, t / t.norm()};
}

std::optional<Ray3> reflect_at(const Ray3& ray, const Point3& centre, double radius, double n_outside,
                               double n_inside, double& weight) {
  const std::optional<Point3> p = next_crossing(ray, centre, radius);
  if (!p) return std::nullopt;
  const Vector3 n = (*p - centre) / radius;
  const bool from_outside = dot(n, ray.direction) < 0;
  weight *= fresnel_reflectance(std::abs(dot(n, ray.direction)), from_outside ? n_outside : n_inside,
                                from_outside ? n_inside : n_outside);
  return Ray3{*p, ray.direction - n * (2 * dot(n, ray.direction))};
}

Point3 front_centre(const SpectacleLens& l) { return l.world_from_lens * Point3{0, 0, -l.front_radius_mm}; }
Point3 back_centre(const SpectacleLens& l) {
  return l.world_from_lens * Point3{0, 0, -l.center_thickness_mm - l.back_radius_mm};
}

// Where a ray crosses the plane through `p` with normal `n`, if ahead.
std::optional<Point3> on_plane(const Ray3& ray, const Point3& p, const Vector3& n) {
  const double along = dot(ray.direction, n);
  if (along == 0) return std::nullopt;
  const double t = dot(p - ray.origin, n) / along;
  if (!(t > 0)) return std::nullopt;
  return ray.origin + ray.direction * t;
}

// The power (W) a path from the light sends into the camera's aperture,
// by brute force: rays on a fine grid of directions about `central` (the
// light's direction along the path), over a square of `half_rad` each
// way, traced by `path` (nullopt: lost), each carrying its Fresnel
// weight; those that cross the aperture's plane within its disc count.
template <class Path>
double brute_force_power(const Illuminator& light, const Camera& camera, const UnitVector3& central, double half_rad,
                         const Path& path, int grid = 1200) {
  const Vector3 a = UnitVector3::normalize(cross(central, Vector3{0, 1, 0})).vector();
  const Vector3 b = cross(central, a);
  const double aperture = camera.focal_length_mm() / camera.sensor().f_number / 2;
  const Vector3 axis = camera.world_from_camera().rotation().column(2).vector();
  const double cell = 2 * half_rad / grid;
  double sum = 0;
  for (int j = 0; j < grid; ++j) {
    for (int i = 0; i < grid; ++i) {
      const double x = -half_rad + (i + 0.5) * cell, y = -half_rad + (j + 0.5) * cell;
      // Directions on the tangent plane of the unit sphere: solid angle
      // cell^2 / (1 + x^2 + y^2)^(3/2).
      const Vector3 d = central.vector() + a * x + b * y;
      const double r2 = x * x + y * y;
      double weight = 1;
      const std::optional<Ray3> out = path(Ray3{light.position, d / d.norm()}, weight);
      if (!out) continue;
      const std::optional<Point3> hit = on_plane(*out, camera.center(), axis);
      if (!hit || distance(*hit, camera.center()) > aperture) continue;
      sum += weight * cell * cell / std::pow(1 + r2, 1.5);
    }
  }
  return light.radiant_intensity_w_sr * sum;
}

// ------------------------------------------------------- tests

TEST(SpectacleLensTracing, CameraRaysMeetTheLensAndShadowRaysPassIt) {
  const Scene scene = glasses();
  const RayTracer tracer(scene);
  const Camera& camera = scene.cameras[0];
  // Straight at the eye: the lens's front first, then its back.
  const Ray ray{camera.center(), UnitVector3::normalize(scene.eyes[0].cornea_center() - camera.center())};
  const Hit front = tracer.intersect(ray);
  ASSERT_EQ(front.surface, Surface::spectacle_lens);
  EXPECT_EQ(front.lens, 0);
  EXPECT_EQ(front.eye, -1);
  EXPECT_NEAR(front.point.z, 577.5, 1e-9);
  EXPECT_TRUE(front.front_face);  // the normal points out of the glass, toward the camera
  const Hit back = tracer.intersect({front.point, ray.direction, 1e-6});
  ASSERT_EQ(back.surface, Surface::spectacle_lens);
  EXPECT_NEAR(back.point.z, 579.5, 1e-9);
  EXPECT_FALSE(back.front_face);  // leaving the glass... into the air behind, against its normal
  // A shadow ray from the cornea to a light passes the lens.
  EXPECT_FALSE(tracer.occluded(scene.eyes[0].corneal_apex() + Vector3{0, 0, -0.01}, scene.illuminators[0].position));
  EXPECT_EQ(tracer.occluder_except_cornea(scene.eyes[0].corneal_apex() + Vector3{0, 0, -0.01}, camera.center()),
            Surface::none);
  // The lens's edge (the elliptic cylinder 23.5 mm out), met sideways
  // (without the frame, which holds it).
  Scene bare = scene;
  bare.meshes.clear();
  const RayTracer lens_only(bare);
  const Hit edge = lens_only.intersect({Point3{40, 0, 582}, -UnitVector3::unit_x()});
  ASSERT_EQ(edge.surface, Surface::spectacle_lens);
  EXPECT_NEAR(edge.point.x, 23.5, 1e-9);
}

TEST(SeenLightsThroughALens, LightTheEyesRegionAsEachPointsOwnPathDoesTo0_1Percent) {
  Scene scene = glasses();
  const Camera& camera = scene.cameras[0];
  for (const double power : {-6.0, -3.0, 2.0}) {
    SpectacleLens& lens = scene.spectacle_lenses[0];
    lens.center_thickness_mm = power > 0 ? 3.5 : 2;
    lens.back_radius_mm =
        back_radius_for_power_mm(power, lens.front_radius_mm, lens.center_thickness_mm, lens.refractive_index);
    const std::vector<Light> lights = lights_of(scene, camera);
    const SeenLights seen(scene, lights);
    double worst_irradiance = 0, worst_angle = 0;
    const Point3 apex = scene.eyes[0].corneal_apex();
    for (int i = 0; i < 40; ++i) {
      // Over the eye and the lids about it, 0 to 14 mm off the apex and
      // up to 10 mm deeper.
      const Point3 x = apex + Vector3{(i % 8) * 1.75 * std::cos(i * 2.1), (i % 8) * 1.75 * std::sin(i * 2.1),
                                      (i % 5) * 2.5};
      for (std::size_t k = 0; k < lights.size(); ++k) {
        const Light l = seen.at(x, k);
        const LightThroughLens exact = light_through_lens(lens, lights[k].position, x);
        ASSERT_EQ(exact.status, PathStatus::ok);
        const double e_exact = lights[k].intensity_w_sr * lens_transmittance(exact.passage, lens.refractive_index) *
                               exact.solid_angle_per_area;
        const double e_seen = l.intensity_w_sr / (l.position - x).squared_norm();
        worst_irradiance = std::max(worst_irradiance, std::abs(e_seen / e_exact - 1));
        worst_angle = std::max(worst_angle, angle_between(l.position - x, exact.passage.leaving));
      }
    }
    EXPECT_LT(worst_irradiance, 1e-3) << power;
    EXPECT_LT(worst_angle, 5e-4) << power;
    std::printf("%+g D: irradiance within %.1e, direction within %.1e rad\n", power, worst_irradiance, worst_angle);
  }
}

TEST(GlintThroughGlasses, ItsPowerIsTheShareOfTheLightsRaysThatEnterTheAperture) {
  const Scene scene = glasses();
  const Camera& camera = scene.cameras[0];
  const Eye& eye = scene.eyes[0];
  const SpectacleLens& lens = scene.spectacle_lenses[0];
  // A keratometric cornea (one sphere) keeps the hand tracing simple.
  Scene sphere = scene;
  sphere.eyes[0] = Eye(keratometric_eye(), eye.world_from_eye());
  sphere.eyes[0].set_appearance(eye.appearance());
  const Eye& k_eye = sphere.eyes[0];
  const double n = lens.refractive_index, n_eye = anterior_inner_index(k_eye.model());
  const SceneTruth truth = compute_truth(sphere);
  for (int l = 0; l < 2; ++l) {
    const GlintTruth& g = truth.views[0].glints[l];
    ASSERT_EQ(g.status, PathStatus::ok);
    const Illuminator& light = sphere.illuminators[l];
    const GlintRadiometry r = glint_radiometry(k_eye, light, camera, g.reflection, &sphere);
    ASSERT_EQ(r.status, PathStatus::ok);
    const SeenHighlight h = see_highlight(sphere, light.position, camera.center(), [&](const Point3& s, const Point3& t) {
      return solve_reflection(k_eye, s, t);
    });
    const auto path = [&](const Ray3& from_light, double& w) -> std::optional<Ray3> {
      auto in = refract_at(from_light, front_centre(lens), lens.front_radius_mm, 1, n, w);
      if (in) in = refract_at(*in, back_centre(lens), lens.back_radius_mm, n, 1, w);
      if (in) in = reflect_at(*in, k_eye.cornea_center(), k_eye.model().anterior_cornea.radius_mm, 1, n_eye, w);
      if (in) in = refract_at(*in, back_centre(lens), lens.back_radius_mm, 1, n, w);
      if (in) in = refract_at(*in, front_centre(lens), lens.front_radius_mm, n, 1, w);
      return in;
    };
    // The rays that reach a 5.7 mm aperture at 600 mm off a 7.8 mm mirror
    // leave the LED within about 6e-5 rad of the central one.
    const double brute = brute_force_power(light, camera, h.from_light(), 1.2e-4, path);
    EXPECT_NEAR(r.power_w / brute, 1, 3e-3) << l;
    // And the lens matters: without it the glint differs by more.
    const GlintRadiometry bare = glint_radiometry(k_eye, light, camera, solve_reflection(k_eye, light.position, camera.center()));
    EXPECT_GT(std::abs(bare.power_w / brute - 1), 0.05) << l;
  }
}

TEST(GhostsOfGlasses, TheirPowerIsTheShareOfTheLightsRaysThatEnterTheAperture) {
  Scene scene = glasses();
  // A third LED far to the side: 12 deg of incidence on the front (from
  // 400 mm aside its front ghost would lie beyond the outline).
  Illuminator far = scene.illuminators[0];
  far.position = {250, 0, 0};
  scene.illuminators.push_back(far);
  const Camera& camera = scene.cameras[0];
  const SpectacleLens& lens = scene.spectacle_lenses[0];
  const double n = lens.refractive_index;
  for (const LensSurface surface : {LensSurface::front, LensSurface::back}) {
    for (int l = 0; l < 3; ++l) {
      const Illuminator& light = scene.illuminators[l];
      const LensReflection g = solve_lens_reflection(lens, surface, light.position, camera.center());
      ASSERT_EQ(g.status, PathStatus::ok);
      const GlintRadiometry r = ghost_radiometry(lens, surface, light, camera);
      ASSERT_EQ(r.status, PathStatus::ok);
      const auto path = [&](const Ray3& from_light, double& w) -> std::optional<Ray3> {
        if (surface == LensSurface::front) return reflect_at(from_light, front_centre(lens), lens.front_radius_mm, 1, n, w);
        auto in = refract_at(from_light, front_centre(lens), lens.front_radius_mm, 1, n, w);
        if (in) in = reflect_at(*in, back_centre(lens), lens.back_radius_mm, n, 1, w);  // the glass outside the sphere
        if (in) in = refract_at(*in, front_centre(lens), lens.front_radius_mm, n, 1, w);
        return in;
      };
      // A ~95 mm mirror spreads less: the cone is wider than a glint's.
      const double brute = brute_force_power(light, camera, g.from_source, 1e-3, path);
      EXPECT_NEAR(r.power_w / brute, 1, 3e-3) << to_string(surface) << " " << l;
    }
  }
}

TEST(SeenLightsThroughALens, PastAPlusLensFocusTheLightStaysFiniteAndFallsOff) {
  // A +20 D lens focuses an LED 600 mm away about 55 mm behind itself:
  // points on the axis from 30 to 120 mm behind it see a finite light,
  // brightest about the focus, from the lens's side.
  Scene scene = glasses();
  SpectacleLens& lens = scene.spectacle_lenses[0];
  lens.front_radius_mm = 1000 * (lens.refractive_index - 1) / 20;
  lens.outline_semi_axes_mm = {15, 12};
  lens.center_thickness_mm = 8;
  lens.back_radius_mm = back_radius_for_power_mm(20, lens.front_radius_mm, 8, lens.refractive_index);
  check_spectacle_lens(lens);
  const std::vector<Light> lights{{Point3{0, 0, 0}, 0.3, 1, 0}};
  const SeenLights seen(scene, lights);
  const Point3 back = lens.world_from_lens * Point3{0, 0, -lens.center_thickness_mm};
  double brightest = 0, at_brightest = 0, last = 0;
  for (double d = 30; d <= 120; d += 2) {
    const Point3 p = back + Vector3{0, 0, d};
    const Light l = seen.at(p, 0);
    const double e = l.intensity_w_sr / (l.position - p).squared_norm();
    ASSERT_TRUE(std::isfinite(e) && e > 0) << d;
    EXPECT_LT((l.position - p).z, 0) << d;  // toward the lens (world -z)
    if (e > brightest) {
      brightest = e;
      at_brightest = d;
    }
    last = e;
  }
  EXPECT_GT(at_brightest, 40);
  EXPECT_LT(at_brightest, 70);
  EXPECT_LT(last, brightest / 4);
  EXPECT_LT(brightest, 1e4 * 0.3 / (600.0 * 600.0) * 1e3);  // capped, not 1e12 times
}

// Dark glasses scene: every albedo 0, so that only glints and ghosts light it.
Scene dark_glasses() {
  Scene scene = glasses();
  EyeAppearance look = scene.eyes[0].appearance();
  look.iris_albedo = look.sclera_albedo = look.skin_albedo = look.fundus_reflectance = 0;
  scene.eyes[0].set_appearance(look);
  for (Mesh& m : scene.meshes) m.albedo = 0;
  return scene;
}

const ImagePlane& plane(const RenderResult& result, const std::string& name) {
  for (const NamedPlane& p : result.aovs) {
    if (p.name == name) return p.plane;
  }
  throw std::runtime_error("no " + name + " AOV");
}

// The centroid and sum of a masked plane's light within 4 px of a pixel.
struct Blob {
  double sum = 0, u = 0, v = 0;
};
Blob blob(const ImagePlane& mask, const ImagePlane& e, const Pixel& at) {
  Blob b;
  for (int y = static_cast<int>(at.v) - 4; y <= static_cast<int>(at.v) + 4; ++y) {
    for (int x = static_cast<int>(at.u) - 4; x <= static_cast<int>(at.u) + 4; ++x) {
      const double w = double(mask.at(x, y)) * e.at(x, y);
      b.sum += w;
      b.u += w * x;
      b.v += w * y;
    }
  }
  b.u /= b.sum;
  b.v /= b.sum;
  return b;
}

TEST(GhostsOfGlasses, LieWhereTheLabelsSayWithTheirElectronsAsTheGlintsSeenThroughTheLensDo) {
  const Scene scene = dark_glasses();
  RenderOptions options;
  options.noise = false;
  options.per_light_glint_masks = true;  // the two glints lie 5 px apart
  const RenderResult result = render(scene, 0, options);
  const EyeInCameraTruth& view = result.truth.views[0];
  ASSERT_EQ(view.distractors.size(), result.distractors.size());
  const ImagePlane& e = result.electrons;
  int ghosts = 0;
  for (std::size_t k = 0; k < view.distractors.size(); ++k) {
    const DistractorTruth& d = view.distractors[k];
    if (d.status != PathStatus::ok) continue;
    ASSERT_GE(d.spectacle_lens, 0);
    // Alone within 10 px (the other lens's ghosts crowd at its edge).
    bool crowded = false;
    for (const DistractorTruth& o : view.distractors) {
      crowded |= &o != &d && o.status == PathStatus::ok && std::hypot(o.pixel.u - d.pixel.u, o.pixel.v - d.pixel.v) < 10;
    }
    if (crowded) continue;
    ++ghosts;
    const Blob b = blob(plane(result, "distractor"), e, d.pixel);
    EXPECT_NEAR(b.sum / result.distractors[k].electrons, 1, 1e-3) << k;
    EXPECT_NEAR(b.u, d.pixel.u, 0.02) << k;
    EXPECT_NEAR(b.v, d.pixel.v, 0.02) << k;
  }
  EXPECT_GE(ghosts, 4);  // both surfaces of the eye's lens, both LEDs
  for (std::size_t l = 0; l < view.glints.size(); ++l) {
    const GlintTruth& g = view.glints[l];
    ASSERT_EQ(g.status, PathStatus::ok);
    const Blob b = blob(plane(result, "glint." + scene.illuminators[l].name), e, g.pixel);
    EXPECT_NEAR(b.sum / result.glints[l].electrons, 1, 1e-3) << l;
    EXPECT_NEAR(b.u, g.pixel.u, 0.02) << l;
    EXPECT_NEAR(b.v, g.pixel.v, 0.02) << l;
  }
}

}  // namespace
}  // namespace purkinje::renderer
