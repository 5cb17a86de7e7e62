#include "lens_light.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "purkinje/models/specular.h"
#include "purkinje/models/truth.h"
#include "purkinje/renderer/radiometry.h"

namespace purkinje::renderer {
namespace {

// The grid's spacing on the plane behind the lens: at 2.5 mm the
// interpolated irradiance stays within 0.1% of the exact one for -6 to
// +2 D lenses (SeenLightsThroughALens).
constexpr double kNodeSpacingMm = 2.5;
// Beyond the outline, so that points behind the lens's rim interpolate.
constexpr double kGridMarginMm = 3;
// A collimated beam's light comes from this far.
constexpr double kFarMm = 1e6;
// At a plus lens's focus the beam's width goes to 0 and its irradiance
// without bound (an LED's size and the lens's aberrations keep it finite):
// capped at 1e4 times the node's, 1% of the width.
constexpr double kMinSpread = 1e-2;

// Where the eye behind the lens is, or 12 mm behind its back vertex.
Point3 region_of(const Scene& scene, int lens_index) {
  const int eye = eye_behind(scene, lens_index);
  if (eye >= 0) return scene.eyes[eye].corneal_apex();
  const SpectacleLens& lens = scene.spectacle_lenses[lens_index];
  return lens.world_from_lens * Point3{0, 0, -lens.center_thickness_mm - 12};
}

}  // namespace

double lens_transmittance(const LensPassage& p, double n) {
  const double in = fresnel_reflectance(std::abs(dot(p.leaving, p.first_normal)), 1.0, n);
  const double out = fresnel_reflectance(std::abs(dot(p.inside, p.second_normal)), n, 1.0);
  return (1 - in) * (1 - out);
}

SeenLights::Field::Field(const SpectacleLens& spectacle, const Point3& light_position, const Point3& near,
                         double spacing_mm)
    : lens(spectacle.world_from_lens),
      front{spectacle.front_radius_mm, 0.0, spectacle.outline_semi_axes_mm[0], spectacle.outline_semi_axes_mm[1], 1.0},
      back{spectacle.back_radius_mm, -spectacle.center_thickness_mm, spectacle.outline_semi_axes_mm[0],
           spectacle.outline_semi_axes_mm[1], -1.0},
      light(light_position),
      light_local(lens.to_local(light_position)) {
  plane_z = lens.to_local(near).z;
  half_x = spectacle.outline_semi_axes_mm[0] + kGridMarginMm;
  half_y = spectacle.outline_semi_axes_mm[1] + kGridMarginMm;
  nx = std::max(2, static_cast<int>(std::ceil(2 * half_x / spacing_mm)) + 1);
  ny = std::max(2, static_cast<int>(std::ceil(2 * half_y / spacing_mm)) + 1);
  step_x = 2 * half_x / (nx - 1);
  step_y = 2 * half_y / (ny - 1);
  const double n = spectacle.refractive_index;
  const auto node_at = [&](const Point3& world) {
    Node node;
    const LightThroughLens l = light_through_lens(spectacle, light, world);
    if (l.status != PathStatus::ok) return node;
    node.valid = true;
    node.direction = l.passage.leaving.vector();
    node.vergence = l.vergence_per_mm;
    node.irradiance = lens_transmittance(l.passage, n) * l.solid_angle_per_area;
    return node;
  };
  centre = node_at(near);
  // The rays about the apex meet at the lens's image of the light there
  // (behind the plane when they converge; parallel when collimated).
  const Point3 near_local = lens.to_local(near);
  const Vector3 d = lens.to_local(centre.valid ? centre.direction : (light - near) / distance(light, near));
  const double s = centre.valid && centre.vergence != 0 ? std::clamp(1 / centre.vergence, -kFarMm, kFarMm) : kFarMm;
  central_image_local = near_local + d * s;
  nodes.resize(static_cast<std::size_t>(nx) * ny);
  // Five solved passages a node, some 400 nodes: in parallel.
  tbb::parallel_for(0, ny, [&](int j) {
    for (int i = 0; i < nx; ++i) {
      const Point3 local{-half_x + i * step_x, -half_y + j * step_y, plane_z};
      nodes[static_cast<std::size_t>(j) * nx + i] = node_at(lens.world_from_local() * local);
    }
  });
}

bool SeenLights::Field::crosses(const Point3& p) const {
  const Point3 q = lens.to_local(p);
  const Vector3 d = light_local - q;
  const double length = d.norm();
  if (!(length > 0)) return false;
  const surfaces::Segment s{q, d / length, 0.0, length};
  double t;
  return front.first_hit(s, t) || back.first_hit(s, t);
}

SeenLights::Field::Node SeenLights::Field::at(const Point3& p, double& depth_mm, Point3& on_plane) const {
  const Point3 q = lens.to_local(p);
  // The ray through p, to first order the line from it to the apex's
  // image, crosses the plane at (x, y); p lies `depth` behind.
  const Vector3 toward = central_image_local - q;
  const double t = std::abs(toward.z) > 1e-12 ? (plane_z - q.z) / toward.z : 0.0;
  const double x = q.x + toward.x * t, y = q.y + toward.y * t;
  depth_mm = std::copysign((toward * t).norm(), plane_z - q.z);
  const double fx = std::clamp((x + half_x) / step_x, 0.0, nx - 1.0);
  const double fy = std::clamp((y + half_y) / step_y, 0.0, ny - 1.0);
  const int x0 = std::min(static_cast<int>(fx), nx - 2), y0 = std::min(static_cast<int>(fy), ny - 2);
  const double tx = fx - x0, ty = fy - y0;
  Node out;
  double weights = 0;
  for (int c = 0; c < 4; ++c) {
    const int i = x0 + (c & 1), j = y0 + (c >> 1);
    const Node& node = nodes[static_cast<std::size_t>(j) * nx + i];
    const double w = ((c & 1) ? tx : 1 - tx) * ((c >> 1) ? ty : 1 - ty);
    if (!node.valid || w == 0) continue;
    out.direction += node.direction * w;
    out.vergence += node.vergence * w;
    out.irradiance += node.irradiance * w;
    weights += w;
  }
  on_plane = lens.world_from_local() * Point3{x, y, plane_z};
  // Beyond the lens's rim every node's passage may fail: the apex's.
  if (!(weights > 0)) return centre;
  const auto unit = UnitVector3::try_normalize(out.direction);
  if (!unit) return centre;
  out.valid = true;
  out.direction = unit->vector();
  out.vergence /= weights;
  out.irradiance /= weights;
  return out;
}

SeenLights::SeenLights(const Scene& scene, const std::vector<Light>& lights) : lights_(&lights) {
  for (int k = 0; k < static_cast<int>(scene.spectacle_lenses.size()); ++k) {
    const Point3 near = region_of(scene, k);
    for (const Light& l : lights) fields_.emplace_back(scene.spectacle_lenses[k], l.position, near, kNodeSpacingMm);
  }
}

Light SeenLights::through_lens(const Point3& p, std::size_t k) const {
  const Light& light = (*lights_)[k];
  const std::size_t count = lights_->size();
  for (std::size_t f = k; f < fields_.size(); f += count) {
    const Field& field = fields_[f];
    if (!field.crosses(p)) continue;
    double depth = 0;
    Point3 on_plane;
    const Field::Node node = field.at(p, depth, on_plane);
    if (!node.valid) return light;
    // Carried along the ray: the beam's width grows as 1 + vergence depth
    // (signed: past a plus lens's focus it grows again, turned over).
    const double signed_spread = 1 + node.vergence * depth;
    const double spread = std::max(std::abs(signed_spread), kMinSpread);
    const double irradiance = node.irradiance / (spread * spread);
    const double v = node.vergence / signed_spread;  // at p; past a focus, diverging from it
    const double far = v == 0 || !std::isfinite(v) ? kFarMm : std::min(std::abs(1 / v), kFarMm);
    // From p toward the image seen at the plane's point (p need not lie
    // exactly on the ray through it: this corrects its direction to first
    // order); the light comes from the lens's side whether the image is
    // virtual, a real focus ahead of p or one p has passed.
    Vector3 direction = node.direction;
    if (std::abs(node.vergence) > 1 / kFarMm) {
      const Point3 image = on_plane + node.direction / node.vergence;
      const double toward_image = (node.vergence > 0) == (signed_spread > 0) ? 1.0 : -1.0;
      if (const auto d = UnitVector3::try_normalize((image - p) * toward_image)) direction = d->vector();
    }
    Light seen = light;
    seen.position = p + direction * far;
    seen.intensity_w_sr = light.intensity_w_sr * irradiance * far * far;
    seen.emitter_radius_mm = light.emitter_radius_mm * far / distance(light.position, p);
    return seen;
  }
  return light;
}

}  // namespace purkinje::renderer
