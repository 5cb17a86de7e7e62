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

int edge_samples_per_pixel(const RenderOptions& options) {
  if (options.mode == RenderMode::reference) return options.samples_per_pixel;
  return std::max(options.samples_per_pixel, options.edge_samples_per_pixel);
}

namespace {

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
      integrator = make_fast_integrator(scene, camera, tracer, options, traced);
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
