// The fast integrator: Fresnel-weighted splitting at the cornea, direct
// light from point lights with shadow rays (a screen-space visibility
// cache where the camera sees the surface), the iris's light from exact
// caches through the cornea, interreflection from a screen-space diffuse
// cache (gathered per sample where none serves: surfaces seen in the
// cornea's mirror, creases). Physics and approximations: docs/rendering.md.

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numbers>
#include <span>
#include <vector>

#include "integrator.h"
#include "lens_light.h"
#include "sampler.h"
#include "screen_cache.h"
#include "purkinje/renderer/radiometry.h"

namespace purkinje::renderer {
namespace {

// Interfaces crossed or reflected at before a path is dropped: enough for
// both corneal surfaces in and out plus a reflection.
constexpr int kMaxSpecularDepth = 6;
// A branch whose weight falls below this cannot change an 8- to 16-bit
// pixel noticeably.
constexpr double kMinBranchWeight = 1e-4;

// The diffuse cache (screen_cache.h): node spacings, gather rays per node,
// and the fewer rays gathered where no node serves a point. Coarse cells
// whose corners differ by at most kDiffuseTolerance of the direct light
// need no fine nodes: far from the eye, where interreflection is smooth
// and small, that is most of a remote camera's image.
constexpr GridSpacing kDiffuseCacheSpacing{32, 8};
constexpr double kDiffuseTolerance = 0.005;
constexpr int kDiffuseCacheRays = 64;
constexpr int kDiffuseMissRays = 16;
// A hair (no cache node lies on one: they are seen through) takes the
// cached light behind it, or gathers fewer: its albedo is low, its pixels few.
constexpr int kHairGatherRays = 4;
// A surface seen in the cornea's mirror gathers its own interreflection
// (no cache serves it) with a few rays: what the cornea reflects is a few
// percent of the iris pixel it lies over, but near the limbus, where the
// reflectance rises and the lids' corners are mirrored, the lids' bounced
// light left out made the iris 1-1.6% too dark (docs/rendering.md).
constexpr int kMirrorGatherRays = 4;
// The visibility cache (screen_cache.h): its nodes trace every light's
// shadow ray; a point between four that agree traces none. Coarse nodes
// every 8 px, and every 2 px in the coarse cells whose corners disagree or
// see different surfaces: no shadow in the bundled scenes is missed (the
// images are those of tracing every shadow ray), but a shadow narrower
// than 8 px inside a cell whose four corners are lit would be.
constexpr GridSpacing kVisibilitySpacing{8, 2};
// Iris grids (iris_grid_sizes): node spacings in the image. The indirect
// light's rings are fine in radius near the limbus: light that the cornea's
// inner side reflects totally back onto the iris rises there within a few
// tenths of a mm (0.4 mm, 5 px of a 150 px iris, from 0.5% to 5% of the
// iris's light); a square grid of 9 x 9 to 13 x 13 nodes smeared that rise
// into errors of -1.9% to +0.6% against the reference. The rings lie at
// radii R sqrt(i / (n - 1)), a pixel apart at the rim (at most 25 rings:
// 0.11 mm), coarser toward the axis where the light varies slowly. Around
// the axis it varies slowly too: 8 azimuths did as well as 16 (worst ring
// 0.49% against 0.55% on the facing eyes), in 3% less time; 16 rays a node
// instead of 32 saved 3% more but doubled the error.
constexpr double kIrisNodeSpacingPx = 2.0;
constexpr double kIrisRingSpacingPx = 1.0;  // at the rim
constexpr int kIrisMinRings = 9, kIrisMaxRings = 25;
constexpr int kIrisRingAzimuths = 8;
// A gathered ray's branches at the cornea are followed while they carry
// this much of the ray's weight: what they gather is itself a few percent
// of the image.
constexpr double kGatherMinBranch = 1e-2;
// Light bounced more than once (gather_hemisphere): the share of a gather
// that diffuse surfaces send on is capped below 1, where a closed white
// cavity's light would grow without bound.
constexpr double kMaxOnwardShare = 0.95;

// One number per light, zeroed: on the stack for the usual few lights
// (these live per pixel and per gathered point), on the heap beyond.
class PerLight {
 public:
  explicit PerLight(std::size_t lights) : heap_(lights > kStack ? lights : 0, 0.0) {}
  double* data() { return heap_.empty() ? stack_.data() : heap_.data(); }

 private:
  static constexpr std::size_t kStack = 16;
  std::array<double, kStack> stack_{};
  std::vector<double> heap_;
};

// Nodes per side of the lights' iris caches (the option, or from the
// iris's size in the image: a node every 2 px, odd, 9 to 33) and rings of
// the indirect light's (a pixel apart at the rim, 9 to 25). Finer than the
// pixels resolve gains nothing; a remote camera's iris is 49 px wide.
struct IrisGridSizes {
  int direct = 33, rings = kIrisMaxRings;
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
    // Rings at radii R sqrt(i / (n - 1)): the outermost spacing is R / (2 (n - 1)).
    sizes.rings = std::clamp(static_cast<int>(std::lround(diameter_px / (4 * kIrisRingSpacingPx))) + 1,
                             kIrisMinRings, kIrisMaxRings);
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
      : scene_(scene),
        camera_(camera),
        tracer_(tracer),
        hair_(tracer.has_hair()),
        lights_(lights_of(scene, camera)),
        seen_(scene, lights_),
        seed_(options.seed) {
    const IrisIrradianceCache::Visibility visible = [this](const Point3& light, const Point3& cornea) {
      return !tracer_.occluded_except_cornea(light, cornea);
    };
    for (const Light& l : lights_) {
      if (hair_) hair_shadows_.push_back(tracer_.hair_shadows(l.position));
      const auto same = std::find(group_electrons_.begin(), group_electrons_.end(), l.electrons_per_radiance);
      group_of_light_.push_back(static_cast<std::size_t>(same - group_electrons_.begin()));
      if (same == group_electrons_.end()) group_electrons_.push_back(l.electrons_per_radiance);
    }
    iris_.resize(scene.eyes.size());
    for (std::size_t e = 0; e < scene.eyes.size(); ++e) {
      for (std::size_t k = 0; k < lights_.size(); ++k) {
        // Through a spectacle lens: its image of the light as the cornea sees it.
        const Light l = seen_.at(scene.eyes[e].cornea_center(), k);
        iris_[e].emplace_back(scene.eyes[e], l.position, l.intensity_w_sr,
                              iris_grid_sizes(camera, scene.eyes[e], options).direct, visible);
      }
    }
    // Every eye's caches first: an iris's gathered rays may reach another
    // eye's iris.
    for (std::size_t e = 0; e < scene.eyes.size(); ++e) {
      const IrisGridSizes sizes = iris_grid_sizes(camera, scene.eyes[e], options);
      build_iris_indirect(static_cast<int>(e), sizes.rings);
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
        [this](const DiffusePoint& p, std::size_t light) { return lit(p.point, p.normal, seen_.at(p.point, light)); });
  }

  void sample(const Ray& ray, const Hit& first_hit, const Pixel& image_position, std::uint64_t path,
              Contribution& out, PrimaryRecord& record, double reflection_weight) const override {
    const Primary primary{&record, image_position, path, reflection_weight};
    trace(ray, first_hit, 0, 1.0, out, primary);
  }

 private:
  // What a camera sample's chains carry: the transmitted one (its record,
  // the pixel whose caches serve it) and those reflected off its way.
  struct Primary {
    PrimaryRecord* record;
    Pixel image_position;
    std::uint64_t path;
    double reflection_weight = 1;  // of the branches the cornea reflects off this chain
    // A mirrored chain's points are not served by the caches, built for
    // what the camera sees directly. Those a cornea mirrors (also after or
    // before a lens) gather their bounced light (kMirrorGatherRays); a lens
    // alone mirrors the camera's side, dark in our scenes: gathering there
    // cost a glasses scene 1.7 times the time.
    enum class Seen { directly, mirrored_by_lens, mirrored_by_cornea };
    Seen seen = Seen::directly;
  };

  // Radiance arriving along `ray`, times `weight`, added to `out`.
  void trace(const Ray& ray, int depth, double weight, Contribution& out, const Primary& primary) const {
    trace(ray, tracer_.intersect(ray), depth, weight, out, primary);
  }
  // The same, where the ray's first hit is known.
  void trace(const Ray& ray, const Hit& hit, int depth, double weight, Contribution& out,
             const Primary& primary) const {
    record_hit(hit, camera_, depth, primary.record);
    switch (scattering_of(hit.surface)) {
      case Scattering::none:
        return;
      case Scattering::diffuse:
        if (const double albedo = diffuse_albedo(scene_, hit); albedo > 0) {
          if (primary.seen != Primary::Seen::directly) {
            direct_light(hit, albedo * weight, out);
            if (primary.seen == Primary::Seen::mirrored_by_cornea && !is_hair(hit.surface)) {
              interreflection(diffuse_point(ray, hit), albedo * weight, primary, out);
            }
            return;
          }
          // Where the camera sees the surface directly, shadows come from
          // the visibility cache where it knows them.
          const DiffusePoint p = diffuse_point(ray, hit);
          const VisibilityCache::Agreement agreed = visibility_->at(primary.image_position, p);
          direct_light(hit, albedo * weight, out, &agreed);
          interreflection(p, albedo * weight, primary, out);
        }
        return;
      case Scattering::iris: {
        const Point3 local = scene_.eyes[hit.eye].eye_from_world() * hit.point;
        const double scaled_albedo = weight * diffuse_albedo(scene_, hit) * kInvPi;
        const IrisGrid& table = iris_light_[hit.eye];
        if (table.side == 0) return;
        for (std::size_t g = 0; g < group_electrons_.size(); ++g) {
          out.add(scaled_albedo * iris_indirect_[hit.eye].at(local, g), group_electrons_[g]);
        }
        // Each light from the table, cut at the rim of the disc inside the
        // cornea; where its lit region ends inside the cell, from its own
        // cache, which keeps the edge sharp (build_iris_light).
        const IrisGrid::Lookup cell = table.lookup(local);
        const std::size_t lights = lights_.size();
        const std::uint8_t* edge = &iris_edge_cells_[hit.eye][static_cast<std::size_t>(cell.cell) * lights];
        const double r = iris_[hit.eye].front().inside_radius_mm();
        const bool inside = local.x * local.x + local.y * local.y < r * r;
        for (std::size_t k = 0; k < lights; ++k) {
          const double e = edge[k] ? iris_[hit.eye][k].irradiance_w_m2(hit.point) : inside ? table.at(cell, k) : 0.0;
          out.add(scaled_albedo * e, lights_[k]);
        }
        return;
      }
      case Scattering::pupil:
        add_bright_pupil(scene_.eyes[hit.eye], lights_, camera_.center(), weight,
                         [&](std::size_t k) { return iris_[hit.eye][k].irradiance_w_m2(hit.point); }, out);
        return;
      case Scattering::interface:
        interface(ray, hit, depth, weight, out, primary);
        return;
    }
  }

  static DiffusePoint diffuse_point(const Ray& ray, const Hit& hit) {
    DiffusePoint p;
    p.surface = hit.surface;
    p.owner = hit.surface == Surface::mesh ? hit.mesh : hit.eye;
    p.point = hit.point;
    p.normal = facing_normal(hit);
    p.cos_view = std::abs(dot(p.normal, ray.direction.vector()));
    return p;
  }

  // The first diffuse point along the transmitted chain of the camera ray
  // through `image_position`, seen through the hairs (for the caches'
  // nodes: what lies behind a hair is smooth, a hair's own light is
  // gathered by its samples).
  DiffusePoint diffuse_point_at(const Pixel& image_position) const {
    Ray ray{camera_.center(), camera_.back_project(image_position)};
    double path_mm = 0;
    for (int depth = 0; depth <= max_depth_; ++depth) {
      const Hit hit = tracer_.intersect_except_hair(ray);
      path_mm += hit.t;
      switch (scattering_of(hit.surface)) {
        case Scattering::diffuse: {
          if (!(diffuse_albedo(scene_, hit) > 0)) return {};
          DiffusePoint p = diffuse_point(ray, hit);
          p.path_mm = path_mm;
          return p;
        }
        case Scattering::interface: {
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
  // diffuse hit: from the cache where the camera sees the point and a node
  // serves it, gathered here otherwise.
  void interreflection(const DiffusePoint& p, double scaled_albedo, const Primary& primary,
                       Contribution& out) const {
    PerLight scratch(lights_.size());  // written by the cache or the gather
    double* e = scratch.data();
    // A hair takes the cached light of the surface behind it, a few
    // millimetres away (no node lies on a hair).
    const bool hair = is_hair(p.surface);
    if (primary.seen != Primary::Seen::directly) {
      gather_hemisphere(p.point, p.normal, kMirrorGatherRays, kMirrorGatherStream, primary.path, e);
    } else if (!diffuse_->irradiance(primary.image_position, hair ? diffuse_point_at(primary.image_position) : p, e)) {
      std::fill(e, e + lights_.size(), 0.0);
      gather_hemisphere(p.point, p.normal, hair ? kHairGatherRays : kDiffuseMissRays, kCacheMissStream,
                        primary.path, e);
    }
    for (std::size_t k = 0; k < lights_.size(); ++k) out.add(scaled_albedo * kInvPi * e[k], lights_[k]);
  }

  // Irradiance at `point` (facing `normal`) from diffuse surfaces, per
  // light added into `e`: `rays` cosine-distributed low-discrepancy
  // directions, shifted by random numbers keyed by (stream, key), each
  // ending in direct light (one bounce). Light bounced more than once is
  // taken as a geometric series: the surfaces the rays met (their share
  // S of the hemisphere, weighted by albedo / pi and Fresnel factors) get
  // about the light this point gets, and pass on S of it, so the point's
  // irradiance is E1 / (1 - S). Exact inside a closed diffuse sphere (the
  // integrating sphere, S = rho); in a face's concave corners, where lids
  // and canthi close round the eye, it recovers most of the 1-4% that one
  // bounce misses (docs/rendering.md). It needs nothing but this point's
  // own rays, so a region renders exactly as that part of the whole image.
  void gather_hemisphere(const Point3& point, const Vector3& normal, int rays, std::uint64_t stream,
                         std::uint64_t key, double* e) const {
    const double shift_u = uniform01(seed_, stream, 2 * key), shift_v = uniform01(seed_, stream, 2 * key + 1);
    PerLight scratch(lights_.size());
    double* once = scratch.data();
    double onward = 0;
    const auto [a, b] = perpendiculars(UnitVector3::from_normalized_unchecked(normal));
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
      for (int j = 0; j < count; ++j) gather(packet[j], hits[j], 0, weight, kGatherMinBranch * weight, once, onward);
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
    const double bounced = 1 / (1 - std::min(onward, kMaxOnwardShare));
    for (std::size_t k = 0; k < lights_.size(); ++k) e[k] += once[k] * bounced;
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
    const Vector3 n = facing_normal(hit);
    const Point3 origin = hit.point + n * kRayOffsetMm;
    for (std::size_t k = 0; k < lights_.size(); ++k) {
      const Light l = seen_.at(hit.point, k);
      const Vector3 to_light = l.position - hit.point;
      const double d2 = to_light.squared_norm();
      const double cos_theta = dot(n, to_light) / std::sqrt(d2);
      if (!(cos_theta > 0)) continue;
      if (agreed && k < VisibilityCache::kMaxLights && (agreed->known >> k & 1)) {
        // The cache's nodes ignore the hairs (lit()): their thin shadows
        // are traced here, against the hairs alone.
        if (!(agreed->lit >> k & 1) || (hair_ && occluded_by_hair(origin, k, l))) continue;
      } else if (tracer_.occluded(origin, l.position)) {
        continue;
      }
      add(k, lambert_radiance(scaled_albedo, l, cos_theta, d2));
    }
  }

  // Whether a hair shades `origin` from light k, seen as `l`: from the
  // light's map, unless a spectacle lens moves its image with the point.
  bool occluded_by_hair(const Point3& origin, std::size_t k, const Light& l) const {
    return l.position == lights_[k].position ? hair_shadows_[k].occluded(origin)
                                             : tracer_.occluded_by_hair(origin, l.position);
  }

  // Irradiance (W/m^2) at a point facing `normal` from every light it
  // faces, shadows ignored.
  double unshadowed_irradiance(const Point3& point, const Vector3& normal) const {
    double e = 0;
    for (std::size_t k = 0; k < lights_.size(); ++k) {
      const Light l = seen_.at(point, k);
      const Vector3 to_light = l.position - point;
      const double d2 = to_light.squared_norm();
      e += std::max(0.0, dot(normal, to_light)) / (d2 * std::sqrt(d2)) * l.intensity_w_sr * kPerSquareMm;
    }
    return e;
  }

  // Whether `light` lights a point facing `normal`, hairs aside (the
  // visibility cache's nodes: hairs' shadows are too thin to interpolate;
  // direct_light traces them per sample).
  bool lit(const Point3& point, const Vector3& normal, const Light& light) const {
    return dot(normal, light.position - point) > 0 &&
           !tracer_.occluded_except_hair(point + normal * kRayOffsetMm, light.position);
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
    // Where a point falls: its cell (x + (side - 1) y, of its lower node)
    // and the bilinear weights there, computed once for every channel.
    struct Lookup {
      int cell = 0;
      std::size_t node = 0;  // the cell's lower node
      double tx = 0, ty = 0;
    };
    Lookup lookup(const Point3& eye_frame_point) const {
      const double fx = std::clamp((eye_frame_point.x + half_mm) / step_mm, 0.0, side - 1.0);
      const double fy = std::clamp((eye_frame_point.y + half_mm) / step_mm, 0.0, side - 1.0);
      const int x0 = std::min(static_cast<int>(fx), side - 2), y0 = std::min(static_cast<int>(fy), side - 2);
      return {x0 + (side - 1) * y0, static_cast<std::size_t>(y0) * side + x0, fx - x0, fy - y0};
    }
    double at(const Lookup& l, std::size_t channel) const {
      const auto v = [&](std::size_t node) { return values[node * channels + channel]; };
      const std::size_t up = l.node + static_cast<std::size_t>(side);
      return (1 - l.ty) * ((1 - l.tx) * v(l.node) + l.tx * v(l.node + 1)) +
             l.ty * ((1 - l.tx) * v(up) + l.tx * v(up + 1));
    }
  };

  // Values at nodes on rings about an eye's optical axis in its iris plane
  // (eye frame), `channels` per node: ring i at radius R sqrt(i / (n - 1)),
  // ring 0 the axis; interpolated bilinearly in squared radius and in
  // azimuth, clamped beyond the last ring.
  struct IrisRings {
    double radius_mm = 1;  // of the last ring
    int rings = 0, azimuths = 0;
    std::size_t channels = 0;
    std::vector<double> values;  // [node][channel]: the axis, then ring by ring
    void resize(double last_radius_mm, int ring_count, int azimuth_count, std::size_t channel_count) {
      rings = ring_count;
      azimuths = azimuth_count;
      radius_mm = last_radius_mm;
      channels = channel_count;
      values.assign(nodes() * channels, 0.0);
    }
    std::size_t nodes() const { return 1 + static_cast<std::size_t>(rings - 1) * azimuths; }
    std::size_t node(int ring, int azimuth) const {
      return ring == 0 ? 0 : 1 + static_cast<std::size_t>(ring - 1) * azimuths + azimuth;
    }
    Point3 node_point(std::size_t n, double z_mm) const {
      if (n == 0) return {0, 0, z_mm};
      const int ring = 1 + static_cast<int>((n - 1) / azimuths), azimuth = static_cast<int>((n - 1) % azimuths);
      const double r = radius_mm * std::sqrt(static_cast<double>(ring) / (rings - 1));
      const double phi = 2 * std::numbers::pi * azimuth / azimuths;
      return {r * std::cos(phi), r * std::sin(phi), z_mm};
    }
    double* node_values(std::size_t n) { return values.data() + n * channels; }
    double at(const Point3& eye_frame_point, std::size_t channel) const {
      const double x = eye_frame_point.x / radius_mm, y = eye_frame_point.y / radius_mm;
      const double fr = std::min((x * x + y * y) * (rings - 1), rings - 1.0);
      if (rings == 0 || !(fr >= 0)) return 0;  // also NaN
      const int r0 = std::min(static_cast<int>(fr), rings - 2);
      const double tr = fr - r0;
      double fa = std::atan2(eye_frame_point.y, eye_frame_point.x) * (azimuths / (2 * std::numbers::pi));
      if (fa < 0) fa += azimuths;
      const int a0 = std::min(static_cast<int>(fa), azimuths - 1), a1 = (a0 + 1) % azimuths;
      const double ta = fa - a0;
      const auto v = [&](int ring, int azimuth) { return values[node(ring, azimuth) * channels + channel]; };
      return (1 - tr) * ((1 - ta) * v(r0, a0) + ta * v(r0, a1)) + tr * ((1 - ta) * v(r0 + 1, a0) + ta * v(r0 + 1, a1));
    }
  };

  // Light that reaches the iris after one diffuse bounce elsewhere: iris
  // light that the cornea's inner side reflects back (totally, beyond the
  // critical angle) and lids and skin seen through the cornea. A few
  // percent of the iris's light, more near the limbus; it varies slowly
  // around the axis but rises steeply near the limbus (kIrisRingSpacingPx),
  // so it is gathered at the nodes of rings (channels: groups of lights)
  // over the hemisphere, out to where the iris ends: low-discrepancy
  // directions, cosine-distributed, shifted node by node. The same
  // directions at every node (all share the iris plane's normal) made one
  // error of all of them: with a face, whose lids close bright round the
  // limbus in a thin band of the hemisphere, the iris was 1.4% too dark
  // (the headset's). A face's eye takes four times the rays: with 32 the
  // shifted nodes' noise left rings 1% off, with 128 0.4% (docs/rendering.md).
  static constexpr int kIndirectRays = 32, kIndirectRaysWithFace = 128;

  void build_iris_indirect(int eye_index, int rings) {
    const Eye& eye = scene_.eyes[eye_index];
    const EyeModel& m = eye.model();
    IrisRings& cache = iris_indirect_[eye_index];
    const std::size_t lights = lights_.size(), groups = group_electrons_.size();
    cache.resize(m.iris_outer_radius_mm(), rings, kIrisRingAzimuths, groups);
    const double z = m.anterior_cornea.radius_mm - m.iris_depth_mm;
    const UnitVector3 n = eye.world_from_eye().rotation() * UnitVector3::unit_z();
    const int rays = eye.appearance().face ? kIndirectRaysWithFace : kIndirectRays;
    tbb::parallel_for(std::size_t{0}, cache.nodes(), [&](std::size_t node) {
      std::vector<double> e(lights, 0.0);
      gather_hemisphere(eye.world_from_eye() * cache.node_point(node, z), n.vector(), rays, kIrisIndirectStream,
                        (static_cast<std::uint64_t>(eye_index) << 32) + node, e.data());
      double* out = cache.node_values(node);
      for (std::size_t k = 0; k < lights; ++k) out[group_of_light_[k]] += e[k];
    });
  }

  // Each light's irradiance on the iris through the cornea, tabulated once
  // per eye at half the spacing of the lights' own caches, out to where an
  // iris point's cell ends, read bilinearly: cheaper than a light's cache
  // (Catmull-Rom over 16 nodes and the exact cosine and Fresnel factor).
  // The direct light ends at the rim of the disc inside the cornea (inside
  // the iris of a one-surface eye): the table holds its continuation beyond,
  // and a lookup cuts at the rim. A cell whose corners disagree about
  // whether a light reaches them holds that light's edge (the limbus's or
  // a lid's shadow, the light's horizon on the cornea), and there a lookup
  // reads that light's own cache. Smeared over a cell, those edges
  // darkened the iris's outermost pixels by up to a third.
  void build_iris_light(int eye_index, int cache_resolution) {
    const Eye& eye = scene_.eyes[eye_index];
    const EyeModel& m = eye.model();
    IrisGrid& table = iris_light_[eye_index];
    if (lights_.empty()) return;
    const std::vector<IrisIrradianceCache>& direct = iris_[eye_index];
    const std::size_t lights = lights_.size();
    table.resize(direct.front().half_size_mm(), 2 * cache_resolution - 1, lights);
    const double z = m.anterior_cornea.radius_mm - m.iris_depth_mm;
    const double r_max = direct.front().half_size_mm() + 1.5 * table.step_mm;
    tbb::parallel_for(0, table.side * table.side, [&](int node) {
      const Point3 local = table.node_point(node, z);
      if (std::hypot(local.x, local.y) > r_max) return;
      const Point3 world = eye.world_from_eye() * local;
      double* e = table.node_values(node);
      for (std::size_t k = 0; k < lights; ++k) e[k] = direct[k].continued_irradiance_w_m2(world);
    });
    const int cells = table.side - 1;
    std::vector<std::uint8_t>& edge = iris_edge_cells_[eye_index];
    edge.assign(static_cast<std::size_t>(cells) * cells * lights, 0);
    for (int y = 0; y < cells; ++y) {
      for (int x = 0; x < cells; ++x) {
        const auto lit = [&](int dx, int dy, std::size_t k) {
          return table.values[(static_cast<std::size_t>(y + dy) * table.side + x + dx) * lights + k] > 0;
        };
        for (std::size_t k = 0; k < lights; ++k) {
          const bool a = lit(0, 0, k);
          if (lit(1, 0, k) != a || lit(0, 1, k) != a || lit(1, 1, k) != a) {
            edge[(static_cast<std::size_t>(y) * cells + x) * lights + k] = 1;
          }
        }
      }
    }
  }

  // Radiance arriving along a ray after one diffuse reflection, times
  // `weight`, per light into `e`; the diffuse surface's share of the light
  // it would pass on after more bounces (weight times albedo / pi) into
  // `onward`.
  void gather(const Ray& ray, int depth, double weight, double min_weight, double* e, double& onward) const {
    gather(ray, tracer_.intersect(ray), depth, weight, min_weight, e, onward);
  }
  // The same, where the ray's first hit is known.
  void gather(const Ray& ray, const Hit& hit, int depth, double weight, double min_weight, double* e,
              double& onward) const {
    const auto add = [&](std::size_t k, double radiance) { e[k] += radiance; };
    switch (scattering_of(hit.surface)) {
      case Scattering::diffuse:
        if (const double albedo = diffuse_albedo(scene_, hit); albedo > 0) {
          direct_light(hit, weight * albedo, add);
          onward += weight * albedo * kInvPi;
        }
        return;
      case Scattering::iris: {
        const double albedo = diffuse_albedo(scene_, hit);
        onward += weight * albedo * kInvPi;
        for (std::size_t k = 0; k < lights_.size(); ++k) {
          add(k, weight * albedo * kInvPi * iris_[hit.eye][k].irradiance_w_m2(hit.point));
        }
        return;
      }
      case Scattering::interface: {
        if (depth >= max_depth_) return;
        const InterfaceCrossing c = cross_interface(scene_, ray, hit);
        const double w_t = weight * (1 - c.reflectance) * c.eta * c.eta, w_r = weight * c.reflectance;
        if (c.transmitted && w_t > min_weight) {
          gather({hit.point - c.facing * kRayOffsetMm, *c.transmitted}, depth + 1, w_t, min_weight, e, onward);
        }
        if (c.reflected && w_r > min_weight) {
          gather({hit.point + c.facing * kRayOffsetMm, *c.reflected}, depth + 1, w_r, min_weight, e, onward);
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
                 const Primary& primary) const {
    if (depth >= max_depth_) return;
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
    const double share = primary.reflection_weight;
    if (w_reflected > kMinBranchWeight && c.reflected && share > 0) {
      const Primary mirror{nullptr, primary.image_position, primary.path, 1.0,
                           primary.seen == Primary::Seen::mirrored_by_cornea || hit.surface != Surface::spectacle_lens
                               ? Primary::Seen::mirrored_by_cornea
                               : Primary::Seen::mirrored_by_lens};
      trace({hit.point + c.facing * kRayOffsetMm, *c.reflected}, depth + 1, w_reflected * share, out, mirror);
    }
  }

  const Scene& scene_;
  const Camera& camera_;
  const RayTracer& tracer_;
  bool hair_;  // the scene has lashes or brows: settled shadow rays are traced against them
  std::vector<Light> lights_;
  std::vector<HairShadows> hair_shadows_;  // [light], with hairs
  SeenLights seen_;  // the lights through spectacle lenses
  int max_depth_ = specular_depth(scene_, kMaxSpecularDepth);
  std::vector<std::vector<IrisIrradianceCache>> iris_;  // [eye][light]
  std::vector<IrisRings> iris_indirect_ = std::vector<IrisRings>(scene_.eyes.size());  // [eye], channels: groups
  // Lights with one wavelength response form a group (usually all of them).
  std::vector<double> group_electrons_;        // [group]: electrons per unit radiance
  std::vector<std::size_t> group_of_light_;    // [light]
  std::vector<IrisGrid> iris_light_ = std::vector<IrisGrid>(scene_.eyes.size());  // [eye], channels: lights
  std::vector<std::vector<std::uint8_t>> iris_edge_cells_ = std::vector<std::vector<std::uint8_t>>(scene_.eyes.size());  // [eye][cell][light]
  std::uint64_t seed_ = 0;
  std::unique_ptr<DiffuseCache> diffuse_;
  std::unique_ptr<VisibilityCache> visibility_;
};

}  // namespace

std::unique_ptr<PathIntegrator> make_fast_integrator(const Scene& scene, const Camera& camera,
                                                     const RayTracer& tracer, const RenderOptions& options,
                                                     const PixelRegion& traced) {
  return std::make_unique<FastIntegrator>(scene, camera, tracer, options, traced);
}

}  // namespace purkinje::renderer
