// The brute-force reference integrator, against which the fast mode is
// measured. It shares none of the fast mode's shortcuts: no irradiance
// caches or interpolation, no point lights.
//
// - Camera paths: the camera's specular chain through the cornea is split
//   into its Fresnel-weighted reflected and refracted branches, as in the
//   fast mode; after the first diffuse bounce a path chooses one branch
//   with probability equal to its Fresnel weight. Each diffuse hit (skin,
//   sclera, iris) adds next-event estimation to every light, sampled over
//   the LED's emitting disc (soft shadows), and continues in a
//   cosine-distributed direction (interreflection between skin, lids and
//   sclera, and light that the cornea's inner side reflects back onto the
//   iris), up to kMaxDiffuseBounces, with Russian roulette after the first.
// - Light reaching the iris and pupil through the cornea (a caustic that
//   camera paths cannot find: at 600 mm an LED subtends about 1e-6 sr) in
//   two parts. Along the path that refracts straight through: at each
//   iris or pupil hit, from a random point of each LED's disc, the path
//   solved exactly there and its irradiance I T dOmega/dA
//   (refracted_irradiance_w_m2; manifold next-event estimation, as Cycles'
//   MNEE does): unbiased, with no edge smeared. Along paths that reflect
//   inside the cornea on the way (about 1e-5 of the light): photons from
//   each LED's disc, in directions filling the cone toward the cornea,
//   through every corneal interface with Fresnel-weighted splitting,
//   binned where they land on the iris plane after a reflection. Photon
//   directions come from a randomly shifted low-discrepancy sequence (R4);
//   each bin's irradiance is flux / area; lookups interpolate bilinearly
//   between bin centres. (All the light came from photons before: their
//   bins smeared the lit region's edges, which near the limbus left the
//   reference up to 10% off its own converged value at 2^20 photons.)
// Every random number is a pure function of (seed, purpose, index), and
// photon flux is summed in integers, so results do not depend on threads.

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "integrator.h"
#include "lens_light.h"
#include "sampler.h"
#include "purkinje/renderer/radiometry.h"
#include "purkinje/renderer/sensor_model.h"

namespace purkinje::renderer {
namespace {

constexpr int kMaxSpecularDepth = 8;     // interface crossings per straight segment chain
constexpr int kMaxDiffuseBounces = 4;    // albedos <= 0.55: the 5th bounce carries < 2%
constexpr double kMinBranchWeight = 1e-6;
// Photon flux is summed in units of 2^-32 of a photon's flux, so that sums
// are exact integers whatever the order of the threads (at most 2^30
// photons of weight about 1 keep a bin below 2^63).
constexpr double kFluxQuantum = 4294967296.0;
// About this many photons per bin on average over the grid (the iris and
// pupil fill about 70% of it); bins stay between 8 and 512 per side.
constexpr double kPhotonsPerBin = 250;

// Orthonormal vectors perpendicular to a direction (of any length).
Perpendiculars basis(const Vector3& direction) {
  return perpendiculars(UnitVector3::from_normalized_unchecked(direction * (1.0 / direction.norm())));
}

// A uniform point of the disc of radius r about `center`, facing `normal`.
Point3 point_on_disc(const Point3& center, const Vector3& normal, double r, double u, double v) {
  if (!(r > 0)) return center;
  const auto [a, b] = basis(normal);
  const double rho = r * std::sqrt(u), phi = 2 * std::numbers::pi * v;
  return center + a * (rho * std::cos(phi)) + b * (rho * std::sin(phi));
}

// The randomly shifted R4 sequence (Roberts' generalized golden ratio),
// computed in 64-bit fixed point so that it stays exact for any index.
class R4Sequence {
 public:
  R4Sequence(std::uint64_t seed, std::uint64_t stream_index) {
    constexpr double phi4 = 1.1673039782614187;  // the real root of x^5 = x + 1
    double alpha = 1.0;
    for (int i = 0; i < 4; ++i) {
      alpha /= phi4;
      step_[i] = static_cast<std::uint64_t>(std::ldexp(alpha, 64));
      shift_[i] = static_cast<std::uint64_t>(
          std::ldexp(uniform01(seed, kPhotonStream, 4 * stream_index + i), 64));
    }
  }
  double at(std::uint64_t n, int dim) const {
    return std::ldexp(static_cast<double>((shift_[dim] + n * step_[dim]) >> 11), -53);
  }

 private:
  std::uint64_t step_[4] = {}, shift_[4] = {};
};


// Irradiance on one eye's iris plane from one light, from traced photons.
class IrisPhotonMap {
 public:
  IrisPhotonMap(const Scene& scene, int eye_index, const Light& light, int light_index,
                const RayTracer& tracer, std::int64_t photons, std::uint64_t seed)
      : scene_(scene), eye_(scene.eyes[eye_index]), tracer_(tracer) {
    const EyeModel& m = eye_.model();
    eye_from_world_ = eye_.eye_from_world();
    half_ = m.iris_outer_radius_mm() + 0.1;
    side_ = std::clamp(static_cast<int>(std::sqrt(static_cast<double>(photons) / kPhotonsPerBin)), 8, 512);
    bin_ = 2 * half_ / side_;

    // Every point of the anterior cap lies within this distance of the
    // cornea centre: x^2 + y^2 + z^2 = R^2 - Q w^2 there.
    const double q = m.anterior_cornea.asphericity;
    const double d_l = m.limbus_depth_mm();
    const double bound = std::sqrt(m.anterior_cornea.radius_mm * m.anterior_cornea.radius_mm +
                                   std::max(0.0, -q) * d_l * d_l) + 0.05;
    const Point3 center = eye_.cornea_center();
    const Vector3 disc_normal = center - light.position;

    const auto one_minus_cos_cone = [&](const Point3& from) {
      const double dist = (center - from).norm();
      const double s2 = (bound / dist) * (bound / dist);  // sin^2 of the half-angle
      return dist > bound ? s2 / (1 + std::sqrt(1 - s2)) : 1.0;
    };
    const double cone0 = one_minus_cos_cone(light.position);
    const R4Sequence sequence(seed, static_cast<std::uint64_t>(eye_index) * 4096 + light_index);
    tbb::combinable<std::vector<std::uint64_t>> partial(
        [n = side_ * side_] { return std::vector<std::uint64_t>(n, 0); });
    constexpr std::int64_t kBatch = 4096;
    const std::int64_t batches = (photons + kBatch - 1) / kBatch;
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, batches), [&](const auto& range) {
      std::vector<std::uint64_t>& bins = partial.local();
      for (std::int64_t batch = range.begin(); batch < range.end(); ++batch) {
        const std::int64_t end = std::min(photons, (batch + 1) * kBatch);
        for (std::int64_t i = batch * kBatch; i < end; ++i) {
          const auto n = static_cast<std::uint64_t>(i);
          const Point3 origin = point_on_disc(light.position, disc_normal, light.emitter_radius_mm,
                                              sequence.at(n, 0), sequence.at(n, 1));
          const Vector3 to_center = center - origin;
          const double dist = to_center.norm();
          const double cos_cone = 1 - one_minus_cos_cone(origin);
          // Uniform in the cone: cos(theta) uniform in [cos_cone, 1].
          const double cos_t = 1 - sequence.at(n, 2) * (1 - cos_cone);
          const double sin_t = std::sqrt(std::max(0.0, 1 - cos_t * cos_t));
          const double phi = 2 * std::numbers::pi * sequence.at(n, 3);
          const Vector3 axis = to_center * (1.0 / dist);
          const auto [a, b] = basis(axis);
          const Vector3 dir = axis * cos_t + a * (sin_t * std::cos(phi)) + b * (sin_t * std::sin(phi));
          // Flux I * Omega / N, Omega = 2 pi (1 - cos_cone): relative to
          // the cone from the disc's centre.
          trace_photon({origin, UnitVector3::normalize(dir)}, (1 - cos_cone) / cone0, 0, false, bins);
        }
      }
    });
    std::vector<std::uint64_t> total(side_ * side_, 0);
    partial.combine_each([&](const std::vector<std::uint64_t>& bins) {
      for (std::size_t i = 0; i < total.size(); ++i) total[i] += bins[i];
    });
    // A photon of weight 1 carries I * 2 pi (1 - cos_cone) / N watts from
    // the disc's centre; weights hold the ratio of cones and the Fresnel
    // transmittances.
    const double watts_per_quantum = light.intensity_w_sr * 2 * std::numbers::pi * cone0 /
                                     static_cast<double>(photons) / kFluxQuantum;
    // Photons land only inside the eye's shell: a bin on its rim holds the
    // flux of the part of it inside, so dividing by the whole bin would
    // darken the iris's edge.
    irradiance_.assign(total.size(), 0.0);
    inside_.assign(total.size(), false);
    const double rim = m.iris_outer_radius_mm();
    constexpr int kSub = 8;
    for (int y = 0; y < side_; ++y) {
      for (int x = 0; x < side_; ++x) {
        int in = 0;
        for (int j = 0; j < kSub; ++j) {
          for (int i = 0; i < kSub; ++i) {
            in += std::hypot(-half_ + (x + (i + 0.5) / kSub) * bin_, -half_ + (y + (j + 0.5) / kSub) * bin_) < rim;
          }
        }
        if (in == 0) continue;
        const std::size_t b = static_cast<std::size_t>(y) * side_ + x;
        const double area_m2 = bin_ * bin_ * in / (kSub * kSub) / kPerSquareMm;
        irradiance_[b] = static_cast<double>(total[b]) * watts_per_quantum / area_m2;
        inside_[b] = true;
      }
    }
  }

  // Bilinear between the centres of bins inside the shell; 0 outside the grid.
  double irradiance_w_m2(const Point3& world) const {
    const Point3 p = eye_from_world_ * world;
    const double fx = (p.x + half_) / bin_ - 0.5, fy = (p.y + half_) / bin_ - 0.5;
    if (!(fx > -1 && fy > -1 && fx < side_ && fy < side_)) return 0;
    const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
    const double tx = fx - x0, ty = fy - y0;
    double sum = 0, weights = 0;
    const auto add = [&](int x, int y, double w) {
      if (x < 0 || y < 0 || x >= side_ || y >= side_) return;
      const std::size_t b = static_cast<std::size_t>(y) * side_ + x;
      if (!inside_[b]) return;
      sum += w * irradiance_[b];
      weights += w;
    };
    add(x0, y0, (1 - tx) * (1 - ty));
    add(x0 + 1, y0, tx * (1 - ty));
    add(x0, y0 + 1, (1 - tx) * ty);
    add(x0 + 1, y0 + 1, tx * ty);
    return weights > 0 ? sum / weights : 0;
  }

 private:
  // Follows a photon of relative weight `weight` through the cornea,
  // splitting at every interface; deposits where it meets the iris plane.
  void trace_photon(const Ray& ray, double weight, int depth, bool reflected,
                    std::vector<std::uint64_t>& bins) const {
    const Hit hit = tracer_.intersect(ray);
    switch (scattering_of(hit.surface)) {
      case Scattering::iris:
      case Scattering::pupil: {
        if (!reflected) return;  // refracted_irradiance_w_m2's light, solved per sample
        const Point3 p = eye_from_world_ * hit.point;
        const int x = static_cast<int>(std::floor((p.x + half_) / bin_));
        const int y = static_cast<int>(std::floor((p.y + half_) / bin_));
        if (x >= 0 && y >= 0 && x < side_ && y < side_) {
          bins[static_cast<std::size_t>(y) * side_ + x] += static_cast<std::uint64_t>(std::llround(weight * kFluxQuantum));
        }
        return;
      }
      case Scattering::interface: {
        if (depth >= max_depth_) return;
        const InterfaceCrossing c = cross_interface(scene_, ray, hit);
        const double w_t = weight * (1 - c.reflectance), w_r = weight * c.reflectance;
        if (c.transmitted && w_t > kMinBranchWeight) {
          trace_photon({hit.point - c.facing * kRayOffsetMm, *c.transmitted}, w_t, depth + 1, reflected, bins);
        }
        // Light reflected off the front of the cornea leaves the eye.
        const bool outside = hit.surface == Surface::cornea_anterior && dot(ray.direction.vector(), hit.normal.vector()) < 0;
        if (!outside && c.reflected && w_r > kMinBranchWeight) {
          trace_photon({hit.point + c.facing * kRayOffsetMm, *c.reflected}, w_r, depth + 1, true, bins);
        }
        return;
      }
      default:
        return;  // lids, skin, the sclera, or nothing: this photon does not reach the iris
    }
  }

  const Scene& scene_;
  const Eye& eye_;
  const RayTracer& tracer_;
  Pose eye_from_world_;
  double half_ = 0, bin_ = 0;
  int side_ = 0;
  std::vector<double> irradiance_;
  std::vector<bool> inside_;  // the bin reaches inside the shell
  int max_depth_ = specular_depth(scene_, kMaxSpecularDepth);
};

class ReferenceIntegrator final : public PathIntegrator {
 public:
  ReferenceIntegrator(const Scene& scene, const Camera& camera, const RayTracer& tracer,
                      const RenderOptions& options)
      : scene_(scene), camera_(camera), tracer_(tracer), lights_(lights_of(scene, camera)), seen_(scene, lights_),
        seed_(options.seed) {
    iris_.resize(scene.eyes.size());
    for (std::size_t e = 0; e < scene.eyes.size(); ++e) {
      for (std::size_t k = 0; k < lights_.size(); ++k) {
        iris_[e].emplace_back(scene, static_cast<int>(e), lights_[k], static_cast<int>(k), tracer,
                              options.reference_photons_per_light, options.seed);
      }
    }
  }

  void sample(const Ray& ray, const Hit& first_hit, const Pixel&, std::uint64_t path, Contribution& out,
              PrimaryRecord& record, double /*reflection_weight: always 1 here*/) const override {
    PathSampler rng(seed_, path);
    trace(ray, first_hit, 0, 0, 1.0, rng, out, &record);
  }

 private:
  void trace(const Ray& ray, int depth, int bounces, double weight, PathSampler& rng, Contribution& out,
             PrimaryRecord* record) const {
    trace(ray, tracer_.intersect(ray), depth, bounces, weight, rng, out, record);
  }
  // The same, where the ray's first hit is known.
  void trace(const Ray& ray, const Hit& hit, int depth, int bounces, double weight, PathSampler& rng,
             Contribution& out, PrimaryRecord* record) const {
    record_hit(hit, camera_, depth, record);
    switch (scattering_of(hit.surface)) {
      case Scattering::none:
        return;
      case Scattering::diffuse: {
        const double albedo = diffuse_albedo(scene_, hit);
        if (albedo == 0) return;  // the eye's dark inside
        direct_light(hit, weight * albedo, rng, out);
        indirect_light(hit, bounces, weight, albedo, rng, out);
        return;
      }
      case Scattering::iris: {
        const double albedo = diffuse_albedo(scene_, hit);
        for (std::size_t k = 0; k < lights_.size(); ++k) {
          out.add(weight * albedo * kInvPi * iris_irradiance(hit, k, rng), lights_[k]);
        }
        indirect_light(hit, bounces, weight, albedo, rng, out);
        return;
      }
      case Scattering::pupil: {
        // Only the fundus's retro-reflection comes back out of the pupil.
        std::vector<double> e(lights_.size());
        for (std::size_t k = 0; k < lights_.size(); ++k) e[k] = iris_irradiance(hit, k, rng);
        add_bright_pupil(scene_.eyes[hit.eye], lights_, camera_.center(), weight,
                         [&](std::size_t k) { return e[k]; }, out);
        return;
      }
      case Scattering::interface: {
        if (depth >= max_depth_) return;
        const InterfaceCrossing c = cross_interface(scene_, ray, hit);
        const Ray reflected{hit.point + c.facing * kRayOffsetMm, c.reflected.value_or(ray.direction)};
        if (bounces == 0) {  // the camera's own chain: both branches
          if (c.transmitted) {
            const double w = weight * (1 - c.reflectance) * c.eta * c.eta;
            if (w > kMinBranchWeight) {
              trace({hit.point - c.facing * kRayOffsetMm, *c.transmitted}, depth + 1, bounces, w, rng, out, record);
            }
          }
          if (c.reflected && weight * c.reflectance > kMinBranchWeight) {
            trace(reflected, depth + 1, bounces, weight * c.reflectance, rng, out, nullptr);
          }
        } else if (rng.next() < c.reflectance) {
          if (c.reflected) trace(reflected, depth + 1, bounces, weight, rng, out, nullptr);
        } else if (c.transmitted) {
          trace({hit.point - c.facing * kRayOffsetMm, *c.transmitted}, depth + 1, bounces,
                weight * c.eta * c.eta, rng, out, nullptr);
        }
        return;
      }
    }
  }

  // Light `k` on the iris plane at `hit`: along the path refracted through
  // the cornea from one point of the LED's disc (facing the eye), solved
  // there (manifold next-event estimation), plus the photons that reached
  // it after reflecting inside the cornea.
  double iris_irradiance(const Hit& hit, std::size_t k, PathSampler& rng) const {
    const Light l = seen_.at(hit.point, k);
    const Eye& eye = scene_.eyes[hit.eye];
    const double u = rng.next(), v = rng.next();
    const Point3 q = point_on_disc(l.position, eye.cornea_center() - l.position, l.emitter_radius_mm, u, v);
    const auto visible = [this](const Point3& light, const Point3& cornea) {
      return !tracer_.occluded_except_cornea(light, cornea);
    };
    return refracted_irradiance_w_m2(eye, q, l.intensity_w_sr, hit.point, visible) +
           iris_[hit.eye][k].irradiance_w_m2(hit.point);
  }

  // Next-event estimation: one point of each LED's disc (facing the lit
  // point), visible or not.
  void direct_light(const Hit& hit, double scaled_albedo, PathSampler& rng, Contribution& out) const {
    const Vector3 n = facing_normal(hit);
    const Point3 origin = hit.point + n * kRayOffsetMm;
    for (std::size_t k = 0; k < lights_.size(); ++k) {
      const Light l = seen_.at(hit.point, k);
      const double u = rng.next(), v = rng.next();
      const Point3 q = point_on_disc(l.position, hit.point - l.position, l.emitter_radius_mm, u, v);
      const Vector3 to_light = q - hit.point;
      const double d2 = to_light.squared_norm();
      const double cos_theta = dot(n, to_light) / std::sqrt(d2);
      if (!(cos_theta > 0)) continue;
      if (tracer_.occluded(origin, q)) continue;
      out.add(lambert_radiance(scaled_albedo, l, cos_theta, d2), l);
    }
  }

  // Light arriving from other surfaces: one cosine-distributed direction.
  void indirect_light(const Hit& hit, int bounces, double weight, double albedo, PathSampler& rng,
                      Contribution& out) const {
    if (bounces >= kMaxDiffuseBounces || !(albedo > 0)) return;
    double w = weight * albedo;
    if (bounces >= 1) {  // Russian roulette on the albedo
      const double survive = std::min(1.0, albedo);
      if (rng.next() >= survive) return;
      w /= survive;
    }
    const Vector3 n = facing_normal(hit);
    const auto [a, b] = basis(n);
    const double u = rng.next(), v = rng.next();
    const double r = std::sqrt(u), phi = 2 * std::numbers::pi * v;
    const Vector3 dir = n * std::sqrt(std::max(0.0, 1 - u)) + a * (r * std::cos(phi)) + b * (r * std::sin(phi));
    const auto unit = UnitVector3::try_normalize(dir);
    if (!unit) return;
    trace({hit.point + n * kRayOffsetMm, *unit}, 0, bounces + 1, w, rng, out, nullptr);
  }

  const Scene& scene_;
  const Camera& camera_;
  const RayTracer& tracer_;
  std::vector<Light> lights_;
  SeenLights seen_;  // the lights through spectacle lenses
  int max_depth_ = specular_depth(scene_, kMaxSpecularDepth);
  std::uint64_t seed_;
  std::vector<std::vector<IrisPhotonMap>> iris_;  // [eye][light]
};

}  // namespace

std::unique_ptr<PathIntegrator> make_reference_integrator(const Scene& scene, const Camera& camera,
                                                          const RayTracer& tracer,
                                                          const RenderOptions& options) {
  return std::make_unique<ReferenceIntegrator>(scene, camera, tracer, options);
}

}  // namespace purkinje::renderer
