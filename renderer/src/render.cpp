// The integrator: camera rays through the scene, shading, glints, sensor.
// Physics and its approximations are documented in docs/rendering.md.

#include "purkinje/renderer/render.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <atomic>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>

#include "integrator.h"
#include "sampler.h"
#include "screen_cache.h"
#include "purkinje/renderer/ray_tracer.h"
#include "purkinje/renderer/sensor_model.h"

namespace purkinje::renderer {

const char* to_string(RenderMode mode) {
  switch (mode) {
    case RenderMode::fast: return "fast";
    case RenderMode::reference: return "reference";
  }
  return "unknown";
}

namespace {

constexpr double kInvPi = 1.0 / std::numbers::pi;
// Interfaces crossed or reflected at before a path is dropped: enough for
// both corneal surfaces in and out plus a reflection.
constexpr int kMaxSpecularDepth = 6;
// A branch whose weight falls below this cannot change an 8- to 16-bit
// pixel noticeably.
constexpr double kMinBranchWeight = 1e-4;

// Angular half-width (1/e) of the fundus's retro-reflection lobe: bright
// pupil needs a light within a few degrees of the camera as seen from the eye.
constexpr double kFundusLobeRad = 1.5 * std::numbers::pi / 180;

// The diffuse cache (screen_cache.h): node spacings, gather rays per node,
// and the fewer rays gathered where no node serves a point. Coarse cells
// whose corners differ by at most kDiffuseTolerance of the direct light
// need no fine nodes: far from the eye, where interreflection is smooth
// and small, that is most of a remote camera's image.
constexpr GridSpacing kDiffuseCacheSpacing{32, 8};
constexpr double kDiffuseTolerance = 0.005;
constexpr int kDiffuseCacheRays = 64;
constexpr int kDiffuseMissRays = 16;
// The visibility cache (screen_cache.h): its nodes trace every light's
// shadow ray; a point between four that agree traces none. Coarse nodes
// every 8 px, and every 2 px in the coarse cells whose corners disagree or
// see different surfaces: no shadow in the bundled scenes is missed (the
// images are those of tracing every shadow ray), but a shadow narrower
// than 8 px inside a cell whose four corners are lit would be.
constexpr GridSpacing kVisibilitySpacing{8, 2};
// Iris grids (iris_grid_sizes): node spacings in the image.
constexpr double kIrisNodeSpacingPx = 2.0;
constexpr double kIrisIndirectSpacingPx = 6.0;
// A gathered ray's branches at the cornea are followed while they carry
// this much of the ray's weight: what they gather is itself a few percent
// of the image.
constexpr double kGatherMinBranch = 1e-2;

// Adaptive sampling (RenderOptions::edge_samples_per_pixel, see
// find_edges): a pixel whose radiance bends by more than kEdgeContrast of
// its local level is refined; by more than kStrongEdgeContrast (a lit
// surface against a dark one, as at the lids' margins), it gets all the
// edge rays, which there still leave the most error per pixel; outlines
// and weaker bends get half of them, and the iris's texture a third: its
// error is the iris caches' interpolation more than its sampling
// (headset, iris pixels: 1.9% of the iris's mean at 4 rays, 1.4% at 24).
constexpr double kEdgeContrast = 0.02;
constexpr double kStrongEdgeContrast = 0.5;

}  // namespace

std::vector<Light> lights_of(const Scene& scene, const Camera& camera) {
  std::vector<Light> lights;
  for (const Illuminator& l : scene.illuminators) {
    lights.push_back({l.position, l.radiant_intensity_w_sr,
                      electrons_per_unit_radiance(camera.sensor(), l.wavelength_nm),
                      0.5 * l.emitter_diameter_mm});
  }
  return lights;
}

PixelClass class_of(Surface s) {
  switch (s) {
    case Surface::skin: return PixelClass::skin;
    // Glasses, hands, occluders: not part of the eye, so in the
    // segmentation with what surrounds it.
    case Surface::mesh: return PixelClass::skin;
    case Surface::sclera: return PixelClass::sclera;
    case Surface::iris: return PixelClass::iris;
    case Surface::pupil: return PixelClass::pupil;
    default: return PixelClass::background;
  }
}

void record_hit(const Hit& hit, const Camera& camera, int depth, PrimaryRecord* record) {
  if (!record) return;
  if (depth == 0 && hit.surface != Surface::none) {
    record->hit = true;
    record->depth_mm = (camera.camera_from_world() * hit.point).z;
    record->normal = hit.normal;
    record->through_cornea = hit.surface == Surface::cornea_anterior;
  }
  record->pixel_class = class_of(hit.surface);
}

double diffuse_albedo(const Scene& scene, const Hit& hit) {
  switch (hit.surface) {
    case Surface::skin:
      // The lids' inner side: real lids rest on the globe, so what lies
      // behind their margins is dark, not a lit gap between lid and eye.
      return hit.front_face ? scene.eyes[hit.eye].appearance().skin_albedo : 0.0;
    case Surface::mesh:
      return scene.meshes[hit.mesh].albedo;
    case Surface::sclera:
      return hit.front_face ? scene.eyes[hit.eye].appearance().sclera_albedo : 0.0;
    case Surface::iris: {
      const Eye& eye = scene.eyes[hit.eye];
      const Point3 local = eye.eye_from_world() * hit.point;
      return iris_albedo(eye.model(), eye.appearance(), local.x, local.y);
    }
    default:
      return 0;
  }
}

InterfaceCrossing cross_interface(const Scene& scene, const Ray& ray, const Hit& hit) {
  const EyeModel& m = scene.eyes[hit.eye].model();
  double n_outer = 1.0, n_inner = anterior_inner_index(m);
  if (hit.surface == Surface::cornea_posterior) {
    n_outer = m.posterior_cornea->cornea_index;
    n_inner = m.aqueous_index;
  }
  const Vector3 d = ray.direction.vector();
  const bool entering = dot(d, hit.normal.vector()) < 0;
  const double n1 = entering ? n_outer : n_inner;
  const double n2 = entering ? n_inner : n_outer;
  InterfaceCrossing c;
  c.facing = entering ? hit.normal.vector() : -hit.normal.vector();
  c.eta = n1 / n2;
  const double cos_i = std::clamp(-dot(d, c.facing), 0.0, 1.0);
  c.reflectance = fresnel_reflectance(cos_i, n1, n2);
  if (c.reflectance < 1.0) {
    const double k = 1.0 - c.eta * c.eta * (1.0 - cos_i * cos_i);
    c.transmitted = UnitVector3::try_normalize(d * c.eta + c.facing * (c.eta * cos_i - std::sqrt(std::max(k, 0.0))));
  }
  c.reflected = UnitVector3::try_normalize(d + c.facing * (2.0 * cos_i));
  return c;
}

// Retro-reflection from the fundus: of the light entering the pupil, a
// fraction fundus_reflectance returns through it into a narrow Gaussian
// lobe about the direction back to its source. Seen at an angle alpha
// from that direction, a pupil point under irradiance E has radiance
// rho E exp(-(alpha/alpha0)^2) / (pi alpha0^2), the lobe's solid angle
// being pi alpha0^2. Far from the camera's axis (alpha >> alpha0) the
// pupil stays dark.
double bright_pupil_radiance(const Eye& eye, const Point3& light, const Point3& camera_center,
                             double irradiance_w_m2) {
  const double rho = eye.appearance().fundus_reflectance;
  if (!(rho > 0) || !(irradiance_w_m2 > 0)) return 0;
  const Point3 c = eye.cornea_center();
  const double x = angle_between(light - c, camera_center - c) / kFundusLobeRad;
  if (x > 6) return 0;  // exp(-36): nothing
  return rho * irradiance_w_m2 * std::exp(-x * x) / (std::numbers::pi * kFundusLobeRad * kFundusLobeRad);
}

int edge_samples_per_pixel(const RenderOptions& options) {
  if (options.mode == RenderMode::reference) return options.samples_per_pixel;
  return std::max(options.samples_per_pixel, options.edge_samples_per_pixel);
}

namespace {

// Nodes per side of an eye's iris grids: the lights' caches (the option,
// or from the iris's size in the image: a node every 2 px, odd, 9 to
// 33) and the indirect light's (a node every 6 px, 7 to 13). Finer than
// the pixels resolve gains nothing; a remote camera's iris is 49 px wide.
struct IrisGridSizes {
  int direct = 33, indirect = 13;
};
IrisGridSizes iris_grid_sizes(const Camera& camera, const Eye& eye, const RenderOptions& options) {
  IrisGridSizes sizes;
  const double z = (camera.camera_from_world() * eye.cornea_center()).z;
  if (z > 0) {
    const double diameter_px = 2 * eye.model().iris_radius_mm * camera.intrinsics().fx / z;
    const auto odd = [&](double spacing_px, int lo, int hi) {
      return std::clamp(2 * static_cast<int>(std::lround(diameter_px / (2 * spacing_px))) + 1, lo, hi);
    };
    sizes.direct = odd(kIrisNodeSpacingPx, 9, 33);
    sizes.indirect = odd(kIrisIndirectSpacingPx, 7, 13);
  }
  if (options.iris_cache_resolution > 0) sizes.direct = options.iris_cache_resolution;
  return sizes;
}

// Fast mode: Fresnel-weighted splitting at the cornea, direct light from
// point lights with shadow rays, iris light from the exact caches.
class FastIntegrator final : public PathIntegrator {
 public:
  // `traced`: the pixels that will be sampled (the caches cover them).
  FastIntegrator(const Scene& scene, const Camera& camera, const RayTracer& tracer,
                 const RenderOptions& options, const PixelRegion& traced)
      : scene_(scene), camera_(camera), tracer_(tracer), lights_(lights_of(scene, camera)), seed_(options.seed) {
    const IrisIrradianceCache::Visibility visible = [this](const Point3& light, const Point3& cornea) {
      return !tracer_.occluded_except_cornea(light, cornea);
    };
    for (const Light& l : lights_) {
      const auto same = std::find(group_electrons_.begin(), group_electrons_.end(), l.electrons_per_radiance);
      group_of_light_.push_back(static_cast<std::size_t>(same - group_electrons_.begin()));
      if (same == group_electrons_.end()) group_electrons_.push_back(l.electrons_per_radiance);
    }
    iris_.resize(scene.eyes.size());
    for (std::size_t e = 0; e < scene.eyes.size(); ++e) {
      const IrisGridSizes sizes = iris_grid_sizes(camera, scene.eyes[e], options);
      for (const Light& l : lights_) {
        iris_[e].emplace_back(scene.eyes[e], l.position, l.intensity_w_sr, sizes.direct, visible);
      }
      build_iris_indirect(static_cast<int>(e), sizes.indirect);
      build_iris_light(static_cast<int>(e), sizes.direct);
    }
    diffuse_ = std::make_unique<DiffuseCache>(
        camera, traced, kDiffuseCacheSpacing,
        lights_.size(), [this](const Pixel& p) { return diffuse_point_at(p); },
        [this](const DiffusePoint& p, std::uint64_t key, double* e) {
          gather_hemisphere(p.point, p.normal, kDiffuseCacheRays, kCacheNodeStream, key, e);
        },
        [this](const DiffusePoint& p) { return unshadowed_irradiance(p.point, p.normal); }, kDiffuseTolerance);
    visibility_ = std::make_unique<VisibilityCache>(
        camera, traced, kVisibilitySpacing,
        lights_.size(), [this](const Pixel& p) { return diffuse_point_at(p); },
        [this](const DiffusePoint& p, std::size_t light) { return lit(p.point, p.normal, lights_[light]); });
  }

  void sample(const Ray& ray, const Hit& first_hit, const Pixel& image_position, std::uint64_t path,
              Contribution& out, PrimaryRecord& record, double reflection_weight) const override {
    const Primary primary{&record, image_position, path, reflection_weight};
    trace(ray, first_hit, 0, 1.0, out, &primary);
  }

 private:
  // What the transmitted chain of a camera ray carries.
  struct Primary {
    PrimaryRecord* record;
    Pixel image_position;
    std::uint64_t path;
    double reflection_weight = 1;  // of the branches the cornea reflects off this chain
  };

  // Radiance arriving along `ray`, times `weight`, added to `out`.
  // `primary` is given along the transmitted chain of a camera ray.
  void trace(const Ray& ray, int depth, double weight, Contribution& out, const Primary* primary) const {
    trace(ray, tracer_.intersect(ray), depth, weight, out, primary);
  }
  // The same, where the ray's first hit is known.
  void trace(const Ray& ray, const Hit& hit, int depth, double weight, Contribution& out,
             const Primary* primary) const {
    record_hit(hit, camera_, depth, primary ? primary->record : nullptr);
    switch (hit.surface) {
      case Surface::none:
        return;
      case Surface::skin:
      case Surface::sclera:
      case Surface::mesh:
        if (const double albedo = diffuse_albedo(scene_, hit); albedo > 0) {
          if (!primary) {
            direct_light(hit, albedo * weight, out);
            return;
          }
          // Where the camera sees the surface directly, shadows come from
          // the visibility cache where it knows them, and interreflection
          // is added: seen in the cornea's mirror it is a few percent of a
          // few percent.
          const DiffusePoint p = diffuse_point(ray, hit);
          const VisibilityCache::Agreement agreed = visibility_->at(primary->image_position, p);
          direct_light(hit, albedo * weight, out, &agreed);
          interreflection(p, albedo * weight, *primary, out);
        }
        return;
      case Surface::iris: {
        const Point3 local = scene_.eyes[hit.eye].eye_from_world() * hit.point;
        const double scaled_albedo = weight * diffuse_albedo(scene_, hit) * kInvPi;
        for (std::size_t g = 0; g < group_electrons_.size(); ++g) {
          out.add(scaled_albedo * iris_light_[hit.eye].at(local, g), group_electrons_[g]);
        }
        return;
      }
      case Surface::pupil:
        add_bright_pupil(scene_.eyes[hit.eye], lights_, camera_.center(), weight,
                         [&](std::size_t k) { return iris_[hit.eye][k].irradiance_w_m2(hit.point); }, out);
        return;
      case Surface::cornea_anterior:
      case Surface::cornea_posterior:
        interface(ray, hit, depth, weight, out, primary);
        return;
    }
  }

  static DiffusePoint diffuse_point(const Ray& ray, const Hit& hit) {
    DiffusePoint p;
    p.surface = hit.surface;
    p.owner = hit.surface == Surface::mesh ? hit.mesh : hit.eye;
    p.point = hit.point;
    p.normal = hit.front_face ? hit.normal.vector() : -hit.normal.vector();
    p.cos_view = std::abs(dot(p.normal, ray.direction.vector()));
    return p;
  }

  // The first diffuse point along the transmitted chain of the camera ray
  // through `image_position` (for the diffuse cache's nodes).
  DiffusePoint diffuse_point_at(const Pixel& image_position) const {
    Ray ray{camera_.center(), camera_.back_project(image_position)};
    double path_mm = 0;
    for (int depth = 0; depth <= kMaxSpecularDepth; ++depth) {
      const Hit hit = tracer_.intersect(ray);
      path_mm += hit.t;
      switch (hit.surface) {
        case Surface::skin:
        case Surface::sclera:
        case Surface::mesh: {
          if (!(diffuse_albedo(scene_, hit) > 0)) return {};
          DiffusePoint p = diffuse_point(ray, hit);
          p.path_mm = path_mm;
          return p;
        }
        case Surface::cornea_anterior:
        case Surface::cornea_posterior: {
          const InterfaceCrossing c = cross_interface(scene_, ray, hit);
          if (!c.transmitted) return {};
          ray = {hit.point - c.facing * kRayOffsetMm, *c.transmitted};
          break;
        }
        default:
          return {};  // the iris has its own cache; the pupil, nothing
      }
    }
    return {};
  }

  // Irradiance from light that bounced off other diffuse surfaces, at a
  // diffuse hit the camera sees: from the cache, or gathered here where no
  // cache node serves the point.
  void interreflection(const DiffusePoint& p, double scaled_albedo, const Primary& primary,
                       Contribution& out) const {
    constexpr std::size_t kStackLights = 16;
    std::array<double, kStackLights> stack;  // written by the cache or the gather
    std::vector<double> heap(lights_.size() > kStackLights ? lights_.size() : 0);
    double* e = heap.empty() ? stack.data() : heap.data();
    if (!diffuse_->irradiance(primary.image_position, p, e)) {
      std::fill(e, e + lights_.size(), 0.0);
      gather_hemisphere(p.point, p.normal, kDiffuseMissRays, kCacheMissStream, primary.path, e);
    }
    for (std::size_t k = 0; k < lights_.size(); ++k) out.add(scaled_albedo * kInvPi * e[k], lights_[k]);
  }

  // Irradiance at `point` (facing `normal`) from diffuse surfaces one
  // bounce away, per light into `e`: `rays` cosine-distributed
  // low-discrepancy directions, shifted by random numbers keyed by
  // (stream, key).
  void gather_hemisphere(const Point3& point, const Vector3& normal, int rays, std::uint64_t stream,
                         std::uint64_t key, double* e) const {
    const double shift_u = uniform01(seed_, stream, 2 * key), shift_v = uniform01(seed_, stream, 2 * key + 1);
    gather_hemisphere(point, normal, rays, shift_u, shift_v, e);
  }
  void gather_hemisphere(const Point3& point, const Vector3& normal, int rays, double shift_u, double shift_v,
                         double* e) const {
    Vector3 a = std::abs(normal.x) < 0.9 ? cross(normal, Vector3{1, 0, 0}) : cross(normal, Vector3{0, 1, 0});
    a = a * (1.0 / a.norm());
    const Vector3 b = cross(normal, a);
    const Point3 origin = point + normal * kRayOffsetMm;
    // Cosine-distributed directions: E = pi * mean radiance.
    const double weight = std::numbers::pi / rays;
    // From one point: first hits in packets of 16.
    constexpr int kPacket = 16;
    std::array<Ray, kPacket> packet;
    std::array<Hit, kPacket> hits;
    int count = 0;
    const auto flush = [&] {
      tracer_.intersect(std::span<const Ray>(packet.data(), count), std::span<Hit>(hits.data(), count));
      for (int j = 0; j < count; ++j) gather(packet[j], hits[j], 0, weight, kGatherMinBranch * weight, e);
      count = 0;
    };
    for (int i = 0; i < rays; ++i) {
      const auto [u, v] = r2_point(i, shift_u, shift_v);
      const double s = std::sqrt(u), phi = 2 * std::numbers::pi * v;
      const auto dir = UnitVector3::try_normalize(normal * std::sqrt(std::max(0.0, 1 - u)) +
                                                  a * (s * std::cos(phi)) + b * (s * std::sin(phi)));
      if (!dir) continue;
      packet[count++] = {origin, *dir};
      if (count == kPacket) flush();
    }
    if (count > 0) flush();
  }

  // Lambertian surface lit directly by the point lights; `scaled_albedo`
  // carries the path weight.
  void direct_light(const Hit& hit, double scaled_albedo, Contribution& out,
                    const VisibilityCache::Agreement* agreed = nullptr) const {
    direct_light(hit, scaled_albedo, [&](std::size_t k, double radiance) { out.add(radiance, lights_[k]); }, agreed);
  }
  // `agreed`: what the visibility cache knows of the lights here.
  template <typename AddPerLight>
  void direct_light(const Hit& hit, double scaled_albedo, const AddPerLight& add,
                    const VisibilityCache::Agreement* agreed = nullptr) const {
    const Vector3 n = hit.front_face ? hit.normal.vector() : -hit.normal.vector();
    const Point3 origin = hit.point + n * kRayOffsetMm;
    for (std::size_t k = 0; k < lights_.size(); ++k) {
      const Light& l = lights_[k];
      const Vector3 to_light = l.position - hit.point;
      const double d2 = to_light.squared_norm();
      const double cos_theta = dot(n, to_light) / std::sqrt(d2);
      if (!(cos_theta > 0)) continue;
      if (agreed && k < VisibilityCache::kMaxLights && (agreed->known >> k & 1)) {
        if (!(agreed->lit >> k & 1)) continue;
      } else if (tracer_.occluded(origin, l.position)) {
        continue;
      }
      add(k, scaled_albedo * kInvPi * l.intensity_w_sr * cos_theta / d2 * kPerSquareMm);
    }
  }

  // Irradiance (W/m^2) at a point facing `normal` from every light it
  // faces, shadows ignored.
  double unshadowed_irradiance(const Point3& point, const Vector3& normal) const {
    double e = 0;
    for (const Light& l : lights_) {
      const Vector3 to_light = l.position - point;
      const double d2 = to_light.squared_norm();
      e += std::max(0.0, dot(normal, to_light)) / (d2 * std::sqrt(d2)) * l.intensity_w_sr * kPerSquareMm;
    }
    return e;
  }

  // Whether `light` lights a point facing `normal`.
  bool lit(const Point3& point, const Vector3& normal, const Light& light) const {
    return dot(normal, light.position - point) > 0 && !tracer_.occluded(point + normal * kRayOffsetMm, light.position);
  }

  // A square grid of nodes on an eye's iris plane (eye frame, centred on
  // the optical axis), `channels` values per node, interpolated bilinearly
  // and clamped at the edges.
  struct IrisGrid {
    double half_mm = 0, step_mm = 1;
    int side = 0;
    std::size_t channels = 0;
    std::vector<double> values;  // [node][channel]
    void resize(double half_size_mm, int nodes_per_side, std::size_t channel_count) {
      half_mm = half_size_mm;
      side = nodes_per_side;
      step_mm = 2 * half_mm / (side - 1);
      channels = channel_count;
      values.assign(static_cast<std::size_t>(side) * side * channels, 0.0);
    }
    Point3 node_point(int node, double z_mm) const {
      return {-half_mm + step_mm * (node % side), -half_mm + step_mm * (node / side), z_mm};
    }
    double* node_values(int node) { return values.data() + static_cast<std::size_t>(node) * channels; }
    double at(const Point3& eye_frame_point, std::size_t channel) const {
      if (side == 0) return 0;
      const double fx = std::clamp((eye_frame_point.x + half_mm) / step_mm, 0.0, side - 1.0);
      const double fy = std::clamp((eye_frame_point.y + half_mm) / step_mm, 0.0, side - 1.0);
      const int x0 = std::min(static_cast<int>(fx), side - 2), y0 = std::min(static_cast<int>(fy), side - 2);
      const double tx = fx - x0, ty = fy - y0;
      const auto v = [&](int x, int y) { return values[(static_cast<std::size_t>(y) * side + x) * channels + channel]; };
      return (1 - ty) * ((1 - tx) * v(x0, y0) + tx * v(x0 + 1, y0)) + ty * ((1 - tx) * v(x0, y0 + 1) + tx * v(x0 + 1, y0 + 1));
    }
  };

  // Light that reaches the iris after one diffuse bounce elsewhere: iris
  // light that the cornea's inner side reflects back (totally, beyond the
  // critical angle) and lids and skin seen through the cornea. A few
  // percent of the iris's light, more near the limbus, and smooth over the
  // iris: so computed at the nodes of a coarse grid (channels: lights) by
  // gathering over the hemisphere (kIndirectRays low-discrepancy
  // directions, cosine-distributed).
  static constexpr int kIndirectRays = 32;

  void build_iris_indirect(int eye_index, int side) {
    const Eye& eye = scene_.eyes[eye_index];
    const EyeModel& m = eye.model();
    IrisGrid& cache = iris_indirect_[eye_index];
    cache.resize(m.iris_radius_mm, side, lights_.size());
    const double z = m.anterior_cornea.radius_mm - m.iris_depth_mm;
    // Nodes outside the iris gather as if at its rim, so that lookups near
    // the rim interpolate between iris values.
    const double r_max = 0.98 * m.iris_radius_mm;
    const UnitVector3 n = eye.world_from_eye().rotation() * UnitVector3::unit_z();
    tbb::parallel_for(0, cache.side * cache.side, [&](int node) {
      Point3 p = cache.node_point(node, z);
      const double r = std::hypot(p.x, p.y);
      if (r > r_max) p.x *= r_max / r, p.y *= r_max / r;
      gather_hemisphere(eye.world_from_eye() * p, n.vector(), kIndirectRays, 0.5, 0.5, cache.node_values(node));
    });
  }

  // The iris's irradiance from all lights, direct through the cornea and
  // indirect, tabulated once per eye: a camera ray then looks up one value
  // per group of lights (lights with one wavelength response add up)
  // instead of every light's cache. Nodes at half the spacing of the
  // lights' own caches, out to where an iris point's cell ends.
  void build_iris_light(int eye_index, int cache_resolution) {
    const Eye& eye = scene_.eyes[eye_index];
    const EyeModel& m = eye.model();
    IrisGrid& table = iris_light_[eye_index];
    if (lights_.empty()) return;
    const std::vector<IrisIrradianceCache>& direct = iris_[eye_index];
    table.resize(direct.front().half_size_mm(), 2 * cache_resolution - 1, group_electrons_.size());
    const double z = m.anterior_cornea.radius_mm - m.iris_depth_mm;
    const double r_max = direct.front().half_size_mm() + 1.5 * table.step_mm;
    tbb::parallel_for(0, table.side * table.side, [&](int node) {
      const Point3 local = table.node_point(node, z);
      if (std::hypot(local.x, local.y) > r_max) return;
      const Point3 world = eye.world_from_eye() * local;
      double* e = table.node_values(node);
      for (std::size_t k = 0; k < lights_.size(); ++k) {
        e[group_of_light_[k]] += direct[k].irradiance_w_m2(world) + iris_indirect_[eye_index].at(local, k);
      }
    });
  }

  // Radiance arriving along a ray leaving the iris, after one more
  // diffuse reflection, times `weight`, per light into `e`.
  void gather(const Ray& ray, int depth, double weight, double min_weight, double* e) const {
    gather(ray, tracer_.intersect(ray), depth, weight, min_weight, e);
  }
  // The same, where the ray's first hit is known.
  void gather(const Ray& ray, const Hit& hit, int depth, double weight, double min_weight, double* e) const {
    const auto add = [&](std::size_t k, double radiance) { e[k] += radiance; };
    switch (hit.surface) {
      case Surface::skin:
      case Surface::sclera:
      case Surface::mesh:
        if (const double albedo = diffuse_albedo(scene_, hit); albedo > 0) direct_light(hit, weight * albedo, add);
        return;
      case Surface::iris: {
        const double albedo = diffuse_albedo(scene_, hit);
        for (std::size_t k = 0; k < lights_.size(); ++k) {
          add(k, weight * albedo * kInvPi * iris_[hit.eye][k].irradiance_w_m2(hit.point));
        }
        return;
      }
      case Surface::cornea_anterior:
      case Surface::cornea_posterior: {
        if (depth >= kMaxSpecularDepth) return;
        const InterfaceCrossing c = cross_interface(scene_, ray, hit);
        const double w_t = weight * (1 - c.reflectance) * c.eta * c.eta, w_r = weight * c.reflectance;
        if (c.transmitted && w_t > min_weight) {
          gather({hit.point - c.facing * kRayOffsetMm, *c.transmitted}, depth + 1, w_t, min_weight, e);
        }
        if (c.reflected && w_r > min_weight) {
          gather({hit.point + c.facing * kRayOffsetMm, *c.reflected}, depth + 1, w_r, min_weight, e);
        }
        return;
      }
      default:
        return;  // the pupil (the eye's dark inside) or nothing
    }
  }

  // Fresnel reflection and refraction at a corneal surface, both traced.
  // Radiance crossing from index n2 into n1 scales by (n1 / n2)^2.
  void interface(const Ray& ray, const Hit& hit, int depth, double weight, Contribution& out,
                 const Primary* primary) const {
    if (depth >= kMaxSpecularDepth) return;
    const InterfaceCrossing c = cross_interface(scene_, ray, hit);
    if (c.transmitted) {
      const double w = weight * (1.0 - c.reflectance) * c.eta * c.eta;
      if (w > kMinBranchWeight * 1e-3) {
        trace({hit.point - c.facing * kRayOffsetMm, *c.transmitted}, depth + 1, w, out, primary);
      }
    }
    // Which reflections are traced does not depend on the sample's share
    // of its pixel's reflection; their weight does.
    const double w_reflected = weight * c.reflectance;
    const double share = primary ? primary->reflection_weight : 1.0;
    if (w_reflected > kMinBranchWeight && c.reflected && share > 0) {
      trace({hit.point + c.facing * kRayOffsetMm, *c.reflected}, depth + 1, w_reflected * share, out, nullptr);
    }
  }

  const Scene& scene_;
  const Camera& camera_;
  const RayTracer& tracer_;
  std::vector<Light> lights_;
  std::vector<std::vector<IrisIrradianceCache>> iris_;  // [eye][light]
  std::vector<IrisGrid> iris_indirect_ = std::vector<IrisGrid>(scene_.eyes.size());  // [eye], channels: lights
  // Lights with one wavelength response form a group (usually all of them).
  std::vector<double> group_electrons_;        // [group]: electrons per unit radiance
  std::vector<std::size_t> group_of_light_;    // [light]
  std::vector<IrisGrid> iris_light_ = std::vector<IrisGrid>(scene_.eyes.size());  // [eye], channels: groups
  std::uint64_t seed_ = 0;
  std::unique_ptr<DiffuseCache> diffuse_;
  std::unique_ptr<VisibilityCache> visibility_;
};


void validate(const Scene& scene, int camera, const RenderOptions& options) {
  if (camera < 0 || camera >= static_cast<int>(scene.cameras.size())) {
    throw std::invalid_argument("render: camera index " + std::to_string(camera) +
                                " is out of range (scene has " +
                                std::to_string(scene.cameras.size()) + " cameras)");
  }
  if (options.samples_per_pixel < 1 || options.samples_per_pixel > 1 << 20) {
    throw std::invalid_argument("render: samples_per_pixel = " +
                                std::to_string(options.samples_per_pixel) +
                                ": must be in [1, 1048576]");
  }
  if (options.edge_samples_per_pixel < 0 || options.edge_samples_per_pixel > 1 << 20) {
    throw std::invalid_argument("render: edge_samples_per_pixel = " +
                                std::to_string(options.edge_samples_per_pixel) +
                                ": must be in [0, 1048576] (0: no adaptive sampling)");
  }
  if (options.iris_cache_resolution != 0 &&
      (options.iris_cache_resolution < 2 || options.iris_cache_resolution > 513)) {
    throw std::invalid_argument("render: iris_cache_resolution = " +
                                std::to_string(options.iris_cache_resolution) +
                                ": must be 0 (from the iris's size in the image) or in [2, 513]");
  }
  if (options.region) {
    const PixelRegion& r = *options.region;
    const Intrinsics& k = scene.cameras[camera].intrinsics();
    if (r.x0 < 0 || r.y0 < 0 || r.x1 > k.width || r.y1 > k.height || r.x0 >= r.x1 || r.y0 >= r.y1) {
      throw std::invalid_argument("render: region [" + std::to_string(r.x0) + ", " + std::to_string(r.x1) +
                                  ") x [" + std::to_string(r.y0) + ", " + std::to_string(r.y1) +
                                  ") must be a non-empty part of the " + std::to_string(k.width) + "x" +
                                  std::to_string(k.height) + " image");
    }
  }
  if (options.threads < 0) {
    throw std::invalid_argument("render: threads = " + std::to_string(options.threads) +
                                ": must be >= 0 (0: all)");
  }
  if (options.reference_photons_per_light < 1 || options.reference_photons_per_light > (std::int64_t{1} << 30)) {
    throw std::invalid_argument("render: reference_photons_per_light = " +
                                std::to_string(options.reference_photons_per_light) +
                                ": must be in [1, 2^30]");
  }
}

// Why find_edges refines a pixel.
enum class Refine : std::uint8_t { no = 0, texture, outline, strong_edge };

// The pixels of `region` whose first pass undersamples them: where the
// class changes (an outline), samples disagree on it, or the radiance
// bends by more than kEdgeContrast of its local level (texture, shadow
// edges; strong edges beyond kStrongEdgeContrast). The second difference
// is zero on a gradient, which a lone centre sample gets right, so smooth
// skin is left alone. Neighbours come from `traced`, the region and a
// margin of one pixel, so that a region is decided as in the whole image.
std::vector<Refine> find_edges(const ImagePlane& radiance, const ImagePlane& id,
                               const std::array<ImagePlane, 5>& coverage, const PixelRegion& region,
                               const PixelRegion& traced) {
  const auto inside = [&](int u, int v) { return u >= traced.x0 && v >= traced.y0 && u < traced.x1 && v < traced.y1; };
  std::vector<Refine> edges(radiance.values.size(), Refine::no);
  for (int y = region.y0; y < region.y1; ++y) {
    for (int x = region.x0; x < region.x1; ++x) {
      bool outline = coverage[static_cast<int>(id.at(x, y))].at(x, y) < 1.0f;
      double bend = 0;  // the largest second difference, over the local level
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          if (!inside(x + dx, y + dy)) continue;
          if (id.at(x + dx, y + dy) != id.at(x, y)) outline = true;
          if (!inside(x - dx, y - dy)) continue;
          const double a = radiance.at(x + dx, y + dy), b = radiance.at(x, y), d = radiance.at(x - dx, y - dy);
          const double level = (a + b + d) / 3;
          if (level > 0) bend = std::max(bend, std::abs(a - 2 * b + d) / level);
        }
      }
      edges[static_cast<std::size_t>(y) * radiance.width + x] = bend > kStrongEdgeContrast ? Refine::strong_edge
                                                                : outline                   ? Refine::outline
                                                                : bend > kEdgeContrast      ? Refine::texture
                                                                                            : Refine::no;
    }
  }
  return edges;
}

// Image memory to reuse: fresh memory costs a page fault per 4 KB when
// first written, a tenth of a remote render. A render takes its planes
// from the previous result's and from what this thread's earlier renders
// left (their scratch planes), and leaves its own scratch planes for the
// next; never more than kKeptScratchBytes per thread.
class PlanePool {
 public:
  PlanePool(int width, int height) : width_(width), height_(height) {
    for (std::vector<float>& v : kept()) spare_.push_back(std::move(v));
    kept().clear();
  }
  ~PlanePool() {
    std::size_t bytes = 0;
    for (std::vector<float>& v : spare_) {
      bytes += v.capacity() * sizeof(float);
      if (bytes > kKeptScratchBytes) break;
      kept().push_back(std::move(v));
    }
  }
  PlanePool(const PlanePool&) = delete;
  PlanePool& operator=(const PlanePool&) = delete;

  // A plane of zeros of the image's size.
  ImagePlane take() {
    ImagePlane plane;
    plane.width = width_;
    plane.height = height_;
    if (!spare_.empty()) {
      plane.values = std::move(spare_.back());
      spare_.pop_back();
    }
    plane.values.assign(static_cast<std::size_t>(width_) * height_, 0.0f);
    return plane;
  }
  void give(ImagePlane& plane) {
    if (plane.values.capacity() > 0) spare_.push_back(std::move(plane.values));
    plane = {};
  }

 private:
  static constexpr std::size_t kKeptScratchBytes = std::size_t{64} << 20;
  static std::vector<std::vector<float>>& kept() {
    thread_local std::vector<std::vector<float>> planes;
    return planes;
  }
  int width_, height_;
  std::vector<std::vector<float>> spare_;
};

}  // namespace

RenderResult render(const Scene& scene, int camera_index, const RenderOptions& options) {
  RenderResult result;
  render(scene, camera_index, options, result);
  return result;
}

void render(const Scene& scene, int camera_index, const RenderOptions& options, RenderResult& result) {
  validate(scene, camera_index, options);
  const Camera& camera = scene.cameras[camera_index];
  const Intrinsics& k = camera.intrinsics();
  const int width = k.width, height = k.height;

  tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);

  PlanePool pool(width, height);
  pool.give(result.radiance);
  pool.give(result.electrons);
  for (NamedPlane& aov : result.aovs) pool.give(aov.plane);
  result.aovs.clear();
  result.glints.clear();
  result.camera = camera_index;
  const RayTracer tracer(scene);
  // Labels agree with what the camera can see: a glint or pupil point whose
  // light or view the lids, the sclera or a mesh blocks is occluded.
  TruthOptions truth_options;
  truth_options.occluded = [&](const Point3& from, const Point3& to) { return tracer.occluded_except_cornea(from, to); };
  result.truth = compute_truth(scene, truth_options);

  const int spp = options.samples_per_pixel;
  const int edge_spp = edge_samples_per_pixel(options);
  const PixelRegion region = options.region.value_or(PixelRegion{0, 0, width, height});
  // Adaptive sampling looks at each pixel's neighbours: the first pass
  // traces a margin of one pixel around the region, cleared at the end.
  const PixelRegion traced = edge_spp > spp ? PixelRegion{std::max(region.x0 - 1, 0), std::max(region.y0 - 1, 0),
                                                          std::min(region.x1 + 1, width), std::min(region.y1 + 1, height)}
                                            : region;

  std::unique_ptr<PathIntegrator> integrator;
  arena.execute([&] {
    if (options.mode == RenderMode::reference) {
      integrator = make_reference_integrator(scene, camera, tracer, options);
    } else {
      integrator = std::make_unique<FastIntegrator>(scene, camera, tracer, options, traced);
    }
  });

  result.radiance = pool.take();
  ImagePlane diffuse_electrons = pool.take();
  ImagePlane depth = pool.take(), nx = pool.take(), ny = pool.take(), nz = pool.take();
  ImagePlane id = pool.take();
  constexpr int kClasses = 5;
  std::array<ImagePlane, kClasses> coverage;
  for (ImagePlane& c : coverage) c = pool.take();
  ImagePlane cornea = pool.take();

  const Point3 center = camera.center();
  const UnitVector3 axis = camera.world_from_camera().rotation() * UnitVector3::unit_z();

  // Natural vignetting: irradiance on the sensor falls as cos^4 of the
  // field angle.
  const auto vignetting_at = [&](const UnitVector3& centre_ray) {
    const double cos_field = dot(centre_ray, axis);
    return cos_field * cos_field * cos_field * cos_field;
  };

  // The camera ray through an image position.
  const auto camera_ray = [&](const Pixel& image_position) {
    return Ray{center, camera.back_project(image_position)};
  };
  // Camera rays are traced in packets of this many: neighbouring rays
  // share Embree's traversal (a third off each ray's cost).
  constexpr int kPacket = 16;

  // A pixel's planes from its samples' sum, the record of the class most
  // of them saw, and how many saw each class and the cornea.
  const auto store_pixel = [&](int x, int y, const Contribution& sum, int samples, const UnitVector3& centre_ray,
                               const PrimaryRecord& r, const std::array<int, kClasses>& counts, int cornea_hits) {
    result.radiance.at(x, y) = static_cast<float>(sum.radiance / samples);
    diffuse_electrons.at(x, y) = static_cast<float>(sum.electrons / samples * vignetting_at(centre_ray));
    id.at(x, y) = static_cast<float>(static_cast<int>(r.pixel_class));
    depth.at(x, y) = r.hit ? static_cast<float>(r.depth_mm) : 0.0f;
    nx.at(x, y) = static_cast<float>(r.normal.x);
    ny.at(x, y) = static_cast<float>(r.normal.y);
    nz.at(x, y) = static_cast<float>(r.normal.z);
    for (int c = 0; c < kClasses; ++c) coverage[c].at(x, y) = static_cast<float>(counts[c]) / samples;
    cornea.at(x, y) = static_cast<float>(cornea_hits) / samples;
  };

  // A lone sample through the pixel's centre, exact where the radiance is
  // linear across the pixel, along `ray` (the centre's camera ray) whose
  // first hit was traced with its row's packet. Nothing to tally: the
  // first pass of most images is this for every pixel.
  const auto render_centre = [&](int x, int y, const Ray& ray, const Hit& hit) {
    const Pixel image_position{double(x), double(y)};
    Contribution sum;
    PrimaryRecord record;
    const std::uint64_t path = (static_cast<std::uint64_t>(y) * width + x) * edge_spp;
    integrator->sample(ray, hit, image_position, path, sum, record, 1.0);
    std::array<int, kClasses> counts{};
    counts[static_cast<int>(record.pixel_class)] = 1;
    store_pixel(x, y, sum, 1, ray.direction, record, counts, record.through_cornea ? 1 : 0);
  };

  // A pixel's `samples` (more than one) with a per-pixel shift of the R2
  // sequence, which decorrelates pixels; traced in packets. With `centre`
  // the first pass's lone centre sample, read back from the planes, is one
  // of them and `samples - 1` more are traced. (A refined pixel traces its
  // first-pass samples again when there were several: simpler than
  // keeping every pixel's partial sums.)
  const auto render_pixel = [&](int x, int y, int samples, bool centre) {
    const std::uint64_t pixel = static_cast<std::uint64_t>(y) * width + x;
    const double shift_u = uniform01(options.seed, kJitterStream, 2 * pixel);
    const double shift_v = uniform01(options.seed, kJitterStream, 2 * pixel + 1);
    const UnitVector3 centre_ray = camera.back_project({double(x), double(y)});  // for the vignetting
    Contribution sum;
    std::array<int, kClasses> counts{};
    std::array<PrimaryRecord, kClasses> first_of_class{};
    int cornea_hits = 0;
    if (centre) {
      PrimaryRecord& r = first_of_class[static_cast<int>(id.at(x, y))];
      r.pixel_class = static_cast<PixelClass>(id.at(x, y));
      r.depth_mm = depth.at(x, y);
      r.hit = r.pixel_class != PixelClass::background;
      r.normal = {nx.at(x, y), ny.at(x, y), nz.at(x, y)};
      counts[static_cast<int>(r.pixel_class)] = 1;
      cornea_hits = cornea.at(x, y) > 0 ? 1 : 0;
      sum.radiance = result.radiance.at(x, y);
      sum.electrons = diffuse_electrons.at(x, y) / vignetting_at(centre_ray);
    }
    // With the centre sample kept, the first new sample traces the cornea's
    // reflection for all the new ones, and the others none: the
    // reflection (a few percent of the pixel) needs fewer rays than the
    // texture and outlines seen through it, which refined the pixel.
    const auto reflection_weight = [&](int s) {
      if (!centre || options.mode != RenderMode::fast) return 1.0;
      return s == 1 ? static_cast<double>(samples - 1) : 0.0;
    };
    std::array<Pixel, kPacket> positions;
    std::array<Ray, kPacket> rays;
    std::array<Hit, kPacket> hits;
    for (int first = centre ? 1 : 0; first < samples; first += kPacket) {
      const int count = std::min(kPacket, samples - first);
      for (int i = 0; i < count; ++i) {
        const auto [ou, ov] = r2_point(first + i, shift_u, shift_v);
        positions[i] = {x - 0.5 + ou, y - 0.5 + ov};
        rays[i] = camera_ray(positions[i]);
      }
      tracer.intersect(std::span<const Ray>(rays.data(), count), std::span<Hit>(hits.data(), count));
      for (int i = 0; i < count; ++i) {
        PrimaryRecord record;
        const int s = first + i;
        integrator->sample(rays[i], hits[i], positions[i], pixel * edge_spp + s, sum, record, reflection_weight(s));
        const int c = static_cast<int>(record.pixel_class);
        if (counts[c]++ == 0) first_of_class[c] = record;
        cornea_hits += record.through_cornea ? 1 : 0;
      }
    }
    const int majority = static_cast<int>(std::max_element(counts.begin(), counts.end()) - counts.begin());
    store_pixel(x, y, sum, samples, centre_ray, first_of_class[majority], counts, cornea_hits);
  };

  // Rows y0 <= y < y1 in parallel, reporting progress from `progress_from`
  // over `progress_span`.
  const auto each_row = [&](int y0, int y1, double progress_from, double progress_span, const auto& row) {
    std::atomic<int> rows_done{0};
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<int>(y0, y1), [&](const tbb::blocked_range<int>& r) {
        for (int y = r.begin(); y < r.end(); ++y) row(y);
        if (options.progress) {
          options.progress(progress_from + progress_span * (rows_done += static_cast<int>(r.size())) / (y1 - y0));
        }
      });
    });
  };
  // With edge samples, the first pass is half the progress.
  const double first_pass_span = edge_spp > spp ? 0.5 : 1.0;
  each_row(traced.y0, traced.y1, 0.0, first_pass_span, [&](int y) {
    if (spp > 1) {
      for (int x = traced.x0; x < traced.x1; ++x) render_pixel(x, y, spp, false);
      return;
    }
    // Lone centre rays: a packet along the row.
    std::array<Ray, kPacket> rays;
    std::array<Hit, kPacket> hits;
    for (int x0 = traced.x0; x0 < traced.x1; x0 += kPacket) {
      const int count = std::min(kPacket, traced.x1 - x0);
      for (int i = 0; i < count; ++i) rays[i] = camera_ray({double(x0 + i), double(y)});
      tracer.intersect(std::span<const Ray>(rays.data(), count), std::span<Hit>(hits.data(), count));
      for (int i = 0; i < count; ++i) render_centre(x0 + i, y, rays[i], hits[i]);
    }
  });
  if (edge_spp > spp) {
    const std::vector<Refine> edges = find_edges(result.radiance, id, coverage, region, traced);
    // Rays per refined pixel by why it is refined (see kStrongEdgeContrast).
    const int ordinary_spp = std::max(spp + 1, edge_spp / 2), iris_texture_spp = std::max(spp + 1, edge_spp / 3);
    each_row(region.y0, region.y1, first_pass_span, 1.0 - first_pass_span, [&](int y) {
      for (int x = region.x0; x < region.x1; ++x) {
        const Refine refine = edges[static_cast<std::size_t>(y) * width + x];
        if (refine == Refine::no) continue;
        const bool iris = id.at(x, y) == static_cast<float>(PixelClass::iris);
        const int samples = refine == Refine::strong_edge        ? edge_spp
                            : refine == Refine::texture && iris ? iris_texture_spp
                                                                : ordinary_spp;
        // After a lone centre sample, the refined pixel keeps it.
        render_pixel(x, y, samples, spp == 1);
      }
    });
    // The margin: outside the region, so left at 0 as promised.
    for (int y = traced.y0; y < traced.y1; ++y) {
      for (int x = traced.x0; x < traced.x1; ++x) {
        if (x >= region.x0 && x < region.x1 && y >= region.y0 && y < region.y1) continue;
        for (ImagePlane* plane : {&result.radiance, &diffuse_electrons, &depth, &nx, &ny, &nz, &id, &cornea}) {
          plane->at(x, y) = 0;
        }
        for (ImagePlane& c : coverage) c.at(x, y) = 0;
      }
    }
  }

  // Optics: one point spread per image, at the depth of the nearest eye in
  // front of the camera (without one, no defocus).
  PointSpread psf{camera.sensor().psf_sigma_px, 0.0};
  double nearest = std::numeric_limits<double>::infinity();
  for (const Eye& eye : scene.eyes) {
    const double z = (camera.camera_from_world() * eye.cornea_center()).z;
    if (z > camera.focal_length_mm() && z < nearest) nearest = z;
  }
  if (std::isfinite(nearest)) psf = point_spread(camera, nearest);
  ImagePlane scratch = pool.take();
  result.electrons = pool.take();
  arena.execute([&] { blur(diffuse_electrons, psf, result.electrons, scratch); });
  pool.give(scratch);
  pool.give(diffuse_electrons);

  // Glints: explicit, from the solver, imaged through the same optics.
  // Per-light planes only when their masks are asked for: a full image per
  // LED is memory and summing that most renders do not need.
  const std::size_t n_lights = scene.illuminators.size();
  ImagePlane glint_total = pool.take();
  std::vector<ImagePlane> glint_planes;
  for (std::size_t l = 0; l < (options.per_light_glint_masks ? n_lights : 0); ++l) glint_planes.push_back(pool.take());
  for (const EyeInCameraTruth& view : result.truth.views) {
    if (view.camera != camera_index) continue;
    for (const GlintTruth& g : view.glints) {
      GlintImage image;
      image.eye = view.eye;
      image.illuminator = g.illuminator;
      image.status = g.status;
      const Illuminator& light = scene.illuminators[g.illuminator];
      if (g.status == PathStatus::ok) {
        // An ok glint's reflection lies on the cap: its radiometry is ok too.
        image.radiometry = glint_radiometry(scene.eyes[view.eye], light, camera, g.reflection);
        image.electrons = image.radiometry.power_w * electrons_per_watt(camera.sensor(), light.wavelength_nm);
        if (image.electrons > 0 && std::isfinite(image.electrons)) {
          add_point_image(glint_total, g.pixel.u, g.pixel.v, image.electrons, psf,
                          image.radiometry.source_cov_px2);
          if (options.per_light_glint_masks) {
            add_point_image(glint_planes[g.illuminator], g.pixel.u, g.pixel.v, image.electrons, psf,
                            image.radiometry.source_cov_px2);
          }
        }
      }
      result.glints.push_back(image);
    }
  }
  for (std::size_t i = 0; i < glint_total.values.size(); ++i) {
    result.electrons.values[i] += glint_total.values[i];
  }

  Sensor sensor = camera.sensor();
  if (!options.noise) sensor.noise = false;
  arena.execute([&] { result.sensor = expose(result.electrons, sensor, options.seed); });

  // AOVs. A glint mask is the fraction of a pixel's signal that the glint
  // carries (computed in the glint's own plane).
  const auto fraction_of_signal = [&](ImagePlane& part) {
    for (std::size_t i = 0; i < part.values.size(); ++i) {
      const float total = result.electrons.values[i];
      part.values[i] = total > 0 ? std::clamp(part.values[i] / total, 0.0f, 1.0f) : 0.0f;
    }
    return std::move(part);
  };
  pool.give(coverage[0]);  // the background's: only adaptive sampling needed it
  result.aovs.push_back({"depth", std::move(depth)});
  result.aovs.push_back({"N.x", std::move(nx)});
  result.aovs.push_back({"N.y", std::move(ny)});
  result.aovs.push_back({"N.z", std::move(nz)});
  result.aovs.push_back({"id", std::move(id)});
  result.aovs.push_back({"skin", std::move(coverage[1])});
  result.aovs.push_back({"sclera", std::move(coverage[2])});
  result.aovs.push_back({"iris", std::move(coverage[3])});
  result.aovs.push_back({"pupil", std::move(coverage[4])});
  result.aovs.push_back({"cornea", std::move(cornea)});
  result.aovs.push_back({"glint", fraction_of_signal(glint_total)});
  if (options.per_light_glint_masks) {
    for (std::size_t l = 0; l < n_lights; ++l) {
      result.aovs.push_back({"glint." + scene.illuminators[l].name, fraction_of_signal(glint_planes[l])});
    }
  }
}

}  // namespace purkinje::renderer
