// The renderer's driver: the truth (with the ray tracer's occlusion), the
// integrator, the camera's rays through the film's pixels with adaptive
// sampling, the optics, the glints from the solver, the sensor. Physics
// and its approximations are documented in docs/rendering.md.

#include "purkinje/renderer/render.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <tuple>

#include "film.h"
#include "integrator.h"
#include "pixel_filter.h"
#include "sampler.h"
#include "mirror_radiometry.h"
#include "scene_geometry.h"
#include "tear_meniscus.h"
#include "purkinje/models/check.h"
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

const char* to_string(PixelFilterKind kind) {
  switch (kind) {
    case PixelFilterKind::box: return "box";
    case PixelFilterKind::gaussian: return "gaussian";
    case PixelFilterKind::blackman_harris: return "blackman-harris";
  }
  return "unknown";
}

namespace {
constexpr PixelFilterKind kPixelFilterKinds[] = {PixelFilterKind::box, PixelFilterKind::gaussian,
                                                 PixelFilterKind::blackman_harris};
}  // namespace

std::optional<PixelFilterKind> pixel_filter_kind(const std::string& name) {
  for (const PixelFilterKind k : kPixelFilterKinds) {
    if (name == to_string(k)) return k;
  }
  return std::nullopt;
}

const std::vector<std::string>& pixel_filter_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const PixelFilterKind k : kPixelFilterKinds) out.emplace_back(to_string(k));
    return out;
  }();
  return names;
}

bool pixel_filter_width_allowed(double width_px) { return width_px == 0 || (width_px >= 0.25 && width_px <= 16); }

double pixel_filter_width_px(const PixelFilter& filter) {
  if (filter.width_px != 0) return filter.width_px;
  return filter.kind == PixelFilterKind::box ? 1.0 : 3.0;
}

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
  // The scene file's rules for what a camera adds and how eyes move, for
  // scenes built in code: checked before the rays are traced, not after.
  const Sensor& sensor = scene.cameras[camera].sensor();
  const std::string sensor_name = "render: cameras[" + std::to_string(camera) + "].sensor.";
  const auto reject = [](const std::string& key, double value, const std::string& rule) {
    throw std::invalid_argument(key + " = " + check::format_number(value) + ": " + rule);
  };
  if (!(sensor.corner_illumination > 0 && sensor.corner_illumination <= 1)) {
    reject(sensor_name + "corner_illumination", sensor.corner_illumination, "must be > 0 and <= 1");
  }
  if (!(sensor.hot_pixel_fraction >= 0 && sensor.hot_pixel_fraction <= 0.01)) {
    reject(sensor_name + "hot_pixel_fraction", sensor.hot_pixel_fraction, "must be between 0 and 0.01");
  }
  if (!(sensor.hot_pixel_e_per_s >= 0 && std::isfinite(sensor.hot_pixel_e_per_s))) {
    reject(sensor_name + "hot_pixel_e_per_s", sensor.hot_pixel_e_per_s, "must be finite and >= 0");
  }
  if (sensor.jpeg_quality && (*sensor.jpeg_quality < 1 || *sensor.jpeg_quality > 100)) {
    reject(sensor_name + "jpeg_quality", *sensor.jpeg_quality, "must be an integer from 1 to 100");
  }
  if (sensor.jpeg_quality && sensor.bits != 8) {
    reject(sensor_name + "jpeg_quality", *sensor.jpeg_quality,
           "needs 8-bit images (bits = " + std::to_string(sensor.bits) + "): JPEG holds 8 bits");
  }
  for (std::size_t e = 0; e < scene.eyes.size(); ++e) {
    const EyeMotion& m = scene.eyes[e].motion();
    for (const auto& [key, rate] : {std::pair{"yaw_deg_s", m.yaw_deg_s}, std::pair{"pitch_deg_s", m.pitch_deg_s}}) {
      if (!(std::abs(rate) <= 1000)) {
        reject("render: eyes[" + std::to_string(e) + "].motion." + key, rate, "must be between -1000 and 1000");
      }
    }
    if (const std::optional<TearFilm>& film = scene.eyes[e].appearance().tear_film) {
      if (!(film->sclera_roughness_deg >= 0 && film->sclera_roughness_deg <= 10)) {
        reject("render: eyes[" + std::to_string(e) + "].appearance.tear_film.sclera_roughness_deg",
               film->sclera_roughness_deg, "must be between 0 and 10");
      }
    }
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
  if (const double w = options.pixel_filter.width_px; !pixel_filter_width_allowed(w)) {
    throw std::invalid_argument("render: pixel_filter width_px = " + check::format_number(w) + ": " +
                                kPixelFilterWidthRule);
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


// Camera rays are traced in packets of this many: neighbouring rays share
// Embree's traversal (a third off each ray's cost).
constexpr int kPacket = 16;

// The camera's rays through the film's pixels: a first pass over the
// traced pixels, then (adaptive sampling) more rays where the film says a
// pixel is undersampled. Every sample goes through the integrator and
// lands in the film.
class CameraPass {
 public:
  CameraPass(const Camera& camera, const RayTracer& tracer, const PathIntegrator& integrator,
             const RenderOptions& options, Film& film)
      : camera_(camera), tracer_(tracer), integrator_(integrator), options_(options), film_(film),
        width_(camera.intrinsics().width), edge_spp_(edge_samples_per_pixel(options)),
        center_(camera.center()), axis_(camera.world_from_camera().rotation() * UnitVector3::unit_z()),
        filter_(options.pixel_filter) {}

  // One row of the first pass: lone centre rays in packets along the row,
  // or `spp` samples a pixel.
  void first_pass_row(int y, int x0, int x1) const {
    const int spp = options_.samples_per_pixel;
    if (spp > 1) {
      for (int x = x0; x < x1; ++x) render_pixel(x, y, spp, false);
      return;
    }
    std::array<Ray, kPacket> rays;
    std::array<Hit, kPacket> hits;
    for (int first = x0; first < x1; first += kPacket) {
      const int count = std::min(kPacket, x1 - first);
      for (int i = 0; i < count; ++i) rays[i] = camera_ray({double(first + i), double(y)});
      tracer_.intersect(std::span<const Ray>(rays.data(), count), std::span<Hit>(hits.data(), count));
      for (int i = 0; i < count; ++i) render_centre(first + i, y, rays[i], hits[i]);
    }
  }

  // One row of the refining pass over `region`, as `refine` says.
  void refine_row(int y, int x0, int x1, const std::vector<Refine>& refine) const {
    const int spp = options_.samples_per_pixel;
    // Rays per refined pixel by why it is refined (see film.cpp's kStrongEdgeContrast).
    const int ordinary_spp = std::max(spp + 1, edge_spp_ / 2), iris_texture_spp = std::max(spp + 1, edge_spp_ / 3);
    for (int x = x0; x < x1; ++x) {
      const Refine r = refine[static_cast<std::size_t>(y) * width_ + x];
      if (r == Refine::no) continue;
      const bool iris = film_.pixel_class(x, y) == PixelClass::iris;
      const int samples = r == Refine::strong_edge        ? edge_spp_
                          : r == Refine::texture && iris ? iris_texture_spp
                                                         : ordinary_spp;
      // After a lone centre sample, the refined pixel keeps it.
      render_pixel(x, y, samples, spp == 1);
    }
  }

 private:
  // Vignetting at a pixel whose centre's ray is `centre_ray`: the natural
  // cos^4 of the field angle, times the lens's own (sensor.corner_illumination).
  double vignetting_at(int x, int y, const UnitVector3& centre_ray) const {
    const double cos_field = dot(centre_ray, axis_);
    return cos_field * cos_field * cos_field * cos_field * lens_illumination(camera_, x, y);
  }

  // The camera ray through an image position.
  Ray camera_ray(const Pixel& image_position) const { return Ray{center_, camera_.back_project(image_position)}; }

  // A lone sample through the pixel's centre, exact where the radiance is
  // linear across the pixel, along `ray` (the centre's camera ray) whose
  // first hit was traced with its row's packet. Nothing to tally: the
  // first pass of most images is this for every pixel.
  void render_centre(int x, int y, const Ray& ray, const Hit& hit) const {
    const Pixel image_position{double(x), double(y)};
    Contribution sum;
    PrimaryRecord record;
    const std::uint64_t path = (static_cast<std::uint64_t>(y) * width_ + x) * edge_spp_;
    integrator_.sample(ray, hit, image_position, path, sum, record, 1.0);
    std::array<int, kClasses> counts{};
    counts[static_cast<int>(record.pixel_class)] = 1;
    film_.store(x, y, sum, 1, vignetting_at(x, y, ray.direction), record, counts, record.through_cornea ? 1 : 0);
  }

  // A pixel's `samples` (more than one) with a per-pixel shift of the R2
  // sequence, which decorrelates pixels; traced in packets. With `centre`
  // the first pass's lone centre sample, read back from the film, is one
  // of them and `samples - 1` more are traced. (A refined pixel traces its
  // first-pass samples again when there were several: simpler than
  // keeping every pixel's partial sums.)
  void render_pixel(int x, int y, int samples, bool centre) const {
    const std::uint64_t pixel = static_cast<std::uint64_t>(y) * width_ + x;
    const double shift_u = uniform01(options_.seed, kJitterStream, 2 * pixel);
    const double shift_v = uniform01(options_.seed, kJitterStream, 2 * pixel + 1);
    const UnitVector3 centre_ray = camera_.back_project({double(x), double(y)});  // for the vignetting
    const double vignetting = vignetting_at(x, y, centre_ray);
    Contribution sum;
    std::array<int, kClasses> counts{};
    std::array<PrimaryRecord, kClasses> first_of_class{};
    int cornea_hits = 0;
    if (centre) {
      const Film::Centre stored = film_.centre(x, y, vignetting);
      const int c = static_cast<int>(stored.record.pixel_class);
      first_of_class[c] = stored.record;
      counts[c] = 1;
      cornea_hits = stored.through_cornea ? 1 : 0;
      sum = stored.sum;
    }
    // With the centre sample kept, the first new sample traces the cornea's
    // reflection for all the new ones, and the others none: the
    // reflection (a few percent of the pixel) needs fewer rays than the
    // texture and outlines seen through it, which refined the pixel.
    const auto reflection_weight = [&](int s) {
      if (!centre || options_.mode != RenderMode::fast) return 1.0;
      return s == 1 ? static_cast<double>(samples - 1) : 0.0;
    };
    std::array<Pixel, kPacket> positions;
    std::array<Ray, kPacket> rays;
    std::array<Hit, kPacket> hits;
    for (int first = centre ? 1 : 0; first < samples; first += kPacket) {
      const int count = std::min(kPacket, samples - first);
      for (int i = 0; i < count; ++i) {
        const auto [ou, ov] = r2_point(first + i, shift_u, shift_v);
        positions[i] = {x + filter_.offset(ou), y + filter_.offset(ov)};
        rays[i] = camera_ray(positions[i]);
      }
      tracer_.intersect(std::span<const Ray>(rays.data(), count), std::span<Hit>(hits.data(), count));
      for (int i = 0; i < count; ++i) {
        PrimaryRecord record;
        const int s = first + i;
        integrator_.sample(rays[i], hits[i], positions[i], pixel * edge_spp_ + s, sum, record, reflection_weight(s));
        const int c = static_cast<int>(record.pixel_class);
        if (counts[c]++ == 0) first_of_class[c] = record;
        cornea_hits += record.through_cornea ? 1 : 0;
      }
    }
    const int majority = static_cast<int>(std::max_element(counts.begin(), counts.end()) - counts.begin());
    film_.store(x, y, sum, samples, vignetting, first_of_class[majority], counts, cornea_hits);
  }

  const Camera& camera_;
  const RayTracer& tracer_;
  const PathIntegrator& integrator_;
  const RenderOptions& options_;
  Film& film_;
  const int width_, edge_spp_;
  const Point3 center_;
  const UnitVector3 axis_;
  const PixelFilterSampler filter_;
};

// Optics: one point spread per image, at the depth of the nearest eye in
// front of the camera (without one, no defocus).
PointSpread image_point_spread(const Scene& scene, const Camera& camera) {
  PointSpread psf{camera.sensor().psf_sigma_px, 0.0};
  double nearest = std::numeric_limits<double>::infinity();
  for (const Eye& eye : scene.eyes) {
    const double z = (camera.camera_from_world() * eye.cornea_center()).z;
    if (z > camera.focal_length_mm() && z < nearest) nearest = z;
  }
  if (std::isfinite(nearest)) psf = point_spread(camera, nearest);
  return psf;
}

// Glints: explicit, from the solver's paths in the truth, imaged through
// the same optics into `total` (and into each light's plane of `per_light`
// when given), each described in `glints`. A glint whose radiometry fails
// (its beam's spread not found by finite differences: rare, never in the
// recorded scenes) is not drawn, and its label says why: the labels must
// not promise a glint the image lacks. The truth's only change after
// compute_truth, since only rendering finds it.
void image_glints(const Scene& scene, int camera_index, SceneTruth& truth, const PointSpread& psf,
                  ImagePlane& total, std::vector<ImagePlane>* per_light, std::vector<GlintImage>& glints) {
  const Camera& camera = scene.cameras[camera_index];
  for (EyeInCameraTruth& view : truth.views) {
    if (view.camera != camera_index) continue;
    for (GlintTruth& g : view.glints) {
      GlintImage image;
      image.eye = view.eye;
      image.illuminator = g.illuminator;
      image.status = g.status;
      const Illuminator& light = scene.illuminators[g.illuminator];
      if (g.status == PathStatus::ok) {
        image.radiometry = glint_radiometry(scene.eyes[view.eye], light, camera, g.reflection, &scene);
        if (image.radiometry.status != PathStatus::ok) g.status = image.status = image.radiometry.status;
        // The natural falloff is in the power through the aperture; the
        // lens's own vignetting is not.
        image.electrons = image.radiometry.power_w * electrons_per_watt(camera.sensor(), light.wavelength_nm) *
                          lens_illumination(camera, g.pixel.u, g.pixel.v);
        if (image.electrons > 0 && std::isfinite(image.electrons)) {
          add_point_image(total, g.pixel.u, g.pixel.v, image.electrons, psf, image.radiometry.source_cov_px2);
          if (per_light) {
            add_point_image((*per_light)[g.illuminator], g.pixel.u, g.pixel.v, image.electrons, psf,
                            image.radiometry.source_cov_px2);
          }
        }
      }
      glints.push_back(image);
    }
  }
}

// The highlights of the tear menisci of `camera_index`'s views' eyes,
// appended to their distractors (after the sclera's): the lower lid's,
// then the upper's, each in light order and each light's along the lid.
void add_meniscus_highlights(const Scene& scene, int camera_index, const std::vector<TearMeniscus>& menisci,
                             const TruthOptions& options, SceneTruth& truth) {
  const Camera& camera = scene.cameras[camera_index];
  for (const TearMeniscus& meniscus : menisci) {
    for (EyeInCameraTruth& view : truth.views) {
      if (view.camera != camera_index || view.eye != meniscus.eye()) continue;
      const Eye& eye = scene.eyes[view.eye];
      for (int l = 0; l < static_cast<int>(scene.illuminators.size()); ++l) {
        const Point3& light = scene.illuminators[l].position;
        for (const Reflection& r : meniscus.highlights(light, camera.center())) {
          if (scene.spectacle_lenses.empty()) {
            view.distractors.push_back(
                distractor_truth(meniscus_kind(meniscus.lid()), r, scene, eye, l, camera, options));
            continue;
          }
          // Through the lenses: the same circle's highlight, found again
          // with the legs' directions (see_highlight); gone when the lens
          // moves it beyond that circle's reach.
          const double circle = meniscus.circle_of(r.point);
          const SeenHighlight seen = see_highlight(scene, light, camera.center(), [&](const Point3& s, const Point3& t) {
            return meniscus.highlight_near(circle, s, t);
          });
          if (seen.reflection.status != PathStatus::ok) continue;
          view.distractors.push_back(
              distractor_truth(meniscus_kind(meniscus.lid()), seen, scene, eye, l, camera, options));
        }
      }
    }
  }
}

// Distractors: each view's highlights whose light reaches the camera.
// Scleral ones as light before the optics (the LED disc's image and the
// facets' spread, no point spread): each drawn alone into `scratch`
// (zeros, left so), kept where the camera sees sclera (its coverage of
// each pixel) and added to `light`, which the caller blurs. A meniscus's
// as a glint's, through the optics (`psf`) and whole, into `sharp`: the
// strip of tears it lies on is narrower than a pixel, and a mask drawn
// before the point spread would round the highlight to its pixel. A
// spectacle lens's ghost the same way: the lens is clear.
// Described in `images` in the truth's order, with the electrons the image
// holds. A highlight whose radiometry fails is not drawn, and its label
// says why.
void image_distractors(const Scene& scene, int camera_index, const std::vector<TearMeniscus>& menisci,
                       const PointSpread& psf, SceneTruth& truth, const ImagePlane& sclera, ImagePlane& scratch,
                       ImagePlane& light, ImagePlane& sharp, std::vector<GlintImage>& images) {
  const Camera& camera = scene.cameras[camera_index];
  for (EyeInCameraTruth& view : truth.views) {
    if (view.camera != camera_index) continue;
    const Eye& eye = scene.eyes[view.eye];
    for (DistractorTruth& d : view.distractors) {
      GlintImage image;
      image.eye = view.eye;
      image.illuminator = d.illuminator;
      image.status = d.status;
      const Illuminator& led = scene.illuminators[d.illuminator];
      const bool on_sclera = d.kind == DistractorKind::sclera;
      if (d.status == PathStatus::ok) {
        if (on_sclera) {
          image.radiometry =
              scleral_highlight_radiometry(eye, *eye.appearance().tear_film, led, camera, d.reflection, &scene);
        } else if (d.spectacle_lens >= 0) {
          const LensSurface surface =
              d.kind == DistractorKind::spectacle_lens_front ? LensSurface::front : LensSurface::back;
          image.radiometry = ghost_radiometry(scene.spectacle_lenses[d.spectacle_lens], surface, led, camera);
        } else {
          const auto meniscus = std::find_if(menisci.begin(), menisci.end(), [&](const TearMeniscus& m) {
            return m.eye() == view.eye && meniscus_kind(m.lid()) == d.kind;
          });
          // Only this render's menisci label such highlights.
          image.radiometry = meniscus == menisci.end()
                                 ? failed_radiometry(PathStatus::not_converged)
                                 : meniscus_highlight_radiometry(*meniscus, led, camera, d.reflection, &scene);
        }
        if (image.radiometry.status != PathStatus::ok) d.status = image.status = image.radiometry.status;
        const double whole = image.radiometry.power_w * electrons_per_watt(camera.sensor(), led.wavelength_nm) *
                             lens_illumination(camera, d.pixel.u, d.pixel.v);
        if (whole > 0 && std::isfinite(whole)) {
          const double* a = image.radiometry.source_cov_px2;
          const double* b = image.radiometry.roughness_cov_px2;
          const double cov[3] = {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
          const PointSpread spread = on_sclera ? PointSpread{0, 0} : psf;
          add_point_image(scratch, d.pixel.u, d.pixel.v, whole, spread, cov);
          // add_point_image reaches 5 sigma (or the nearest pixel).
          const double isotropic = spread.sigma_px * spread.sigma_px + 0.25 * spread.defocus_radius_px * spread.defocus_radius_px;
          const int half_u = static_cast<int>(std::ceil(5 * std::sqrt(cov[0] + isotropic))) + 2;
          const int half_v = static_cast<int>(std::ceil(5 * std::sqrt(cov[2] + isotropic))) + 2;
          const int x0 = std::max(0, static_cast<int>(std::floor(d.pixel.u)) - half_u);
          const int x1 = std::min(light.width - 1, static_cast<int>(std::ceil(d.pixel.u)) + half_u);
          const int y0 = std::max(0, static_cast<int>(std::floor(d.pixel.v)) - half_v);
          const int y1 = std::min(light.height - 1, static_cast<int>(std::ceil(d.pixel.v)) + half_v);
          ImagePlane& target = on_sclera ? light : sharp;
          double seen = 0;
          for (int y = y0; y <= y1; ++y) {
            for (int x = x0; x <= x1; ++x) {
              const float e = on_sclera ? scratch.at(x, y) * sclera.at(x, y) : scratch.at(x, y);
              target.at(x, y) += e;
              seen += e;
              scratch.at(x, y) = 0;
            }
          }
          image.electrons = seen;
        }
      }
      images.push_back(image);
    }
  }
}

// A glint mask: the fraction of a pixel's signal that the glint carries
// (computed in the glint's own plane, replaced by the fraction).
ImagePlane fraction_of_signal(ImagePlane& part, const ImagePlane& electrons) {
  for (std::size_t i = 0; i < part.values.size(); ++i) {
    const float total = electrons.values[i];
    part.values[i] = total > 0 ? std::clamp(part.values[i] / total, 0.0f, 1.0f) : 0.0f;
  }
  return std::move(part);
}

}  // namespace

RenderResult render(const Scene& scene, int camera_index, const RenderOptions& options) {
  RenderResult result;
  render(scene, camera_index, options, result);
  return result;
}

namespace {

// The scene's light at one instant: everything render() gives but the
// sensor image (options validated), its parallel work in `arena`.
void render_instant(const Scene& scene, int camera_index, const RenderOptions& options, tbb::task_arena& arena,
                    RenderResult& result) {
  const Camera& camera = scene.cameras[camera_index];
  const Intrinsics& k = camera.intrinsics();
  const int width = k.width, height = k.height;

  PlanePool pool(width, height);
  pool.give(result.radiance);
  pool.give(result.electrons);
  for (NamedPlane& aov : result.aovs) pool.give(aov.plane);
  result.aovs.clear();
  result.glints.clear();
  result.distractors.clear();
  result.camera = camera_index;
  const RayTracer tracer(scene);
  // Labels agree with what the camera can see: a glint or pupil point whose
  // light or view the lids, a lash or brow, the sclera or a mesh blocks is occluded,
  // with what the camera sees in front of it (or what shadows it).
  TruthOptions truth_options;
  truth_options.occluded = [&](const Point3& from, const Point3& to) {
    switch (tracer.occluder_except_cornea(from, to)) {
      case Surface::none: return Occluder::none;
      case Surface::skin: return Occluder::skin;
      case Surface::lash: return Occluder::lash;
      case Surface::brow: return Occluder::brow;
      case Surface::mesh: return Occluder::mesh;
      default: return Occluder::eye;
    }
  };
  result.truth = compute_truth(scene, truth_options);
  // The lids' tear menisci: the faces' margins are built here, so
  // their highlights join the labels here.
  const std::vector<TearMeniscus> menisci = build_tear_menisci(scene);
  add_meniscus_highlights(scene, camera_index, menisci, truth_options, result.truth);

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
    integrator = options.mode == RenderMode::reference ? make_reference_integrator(scene, camera, tracer, options)
                                                       : make_fast_integrator(scene, camera, tracer, options, traced);
  });
  Film film(pool);
  const CameraPass pass(camera, tracer, *integrator, options, film);

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
  each_row(traced.y0, traced.y1, 0.0, first_pass_span, [&](int y) { pass.first_pass_row(y, traced.x0, traced.x1); });
  if (edge_spp > spp) {
    const std::vector<Refine> refine = film.refinement(region, traced);
    each_row(region.y0, region.y1, first_pass_span, 1.0 - first_pass_span,
             [&](int y) { pass.refine_row(y, region.x0, region.x1, refine); });
    // The margin: outside the region, so left at 0 as promised.
    for (int y = traced.y0; y < traced.y1; ++y) {
      for (int x = traced.x0; x < traced.x1; ++x) {
        if (x < region.x0 || x >= region.x1 || y < region.y0 || y >= region.y1) film.clear(x, y);
      }
    }
  }
  result.radiance = film.take_radiance();

  const PointSpread psf = image_point_spread(scene, camera);
  ImagePlane scratch = pool.take();
  result.electrons = pool.take();
  arena.execute([&] { blur(film.diffuse_electrons(), psf, result.electrons, scratch); });
  pool.give(film.diffuse_electrons());
  // Distractors: light on the sclera, through the same optics; their mask
  // only for a scene that has some (its files keep their planes otherwise).
  const bool distractors = scene_has_distractors(scene);
  ImagePlane distractor_total;
  if (distractors) {
    ImagePlane light = pool.take(), spot = pool.take(), sharp = pool.take();
    image_distractors(scene, camera_index, menisci, psf, result.truth, film.coverage(PixelClass::sclera), spot,
                      light, sharp, result.distractors);
    pool.give(spot);
    distractor_total = pool.take();
    arena.execute([&] { blur(light, psf, distractor_total, scratch); });
    pool.give(light);
    for (std::size_t i = 0; i < sharp.values.size(); ++i) distractor_total.values[i] += sharp.values[i];
    pool.give(sharp);
    for (std::size_t i = 0; i < distractor_total.values.size(); ++i) {
      result.electrons.values[i] += distractor_total.values[i];
    }
  }
  pool.give(scratch);

  // Per-light planes only when their masks are asked for: a full image per
  // LED is memory and summing that most renders do not need.
  const std::size_t n_lights = scene.illuminators.size();
  ImagePlane glint_total = pool.take();
  std::vector<ImagePlane> glint_planes;
  for (std::size_t l = 0; l < (options.per_light_glint_masks ? n_lights : 0); ++l) glint_planes.push_back(pool.take());
  image_glints(scene, camera_index, result.truth, psf, glint_total,
               options.per_light_glint_masks ? &glint_planes : nullptr, result.glints);
  for (std::size_t i = 0; i < glint_total.values.size(); ++i) result.electrons.values[i] += glint_total.values[i];

  film.add_aovs(result.aovs, pool, scene_has_lashes(scene), scene_has_brows(scene));
  result.aovs.push_back({"glint", fraction_of_signal(glint_total, result.electrons)});
  for (std::size_t l = 0; l < glint_planes.size(); ++l) {
    result.aovs.push_back({"glint." + scene.illuminators[l].name, fraction_of_signal(glint_planes[l], result.electrons)});
  }
  if (distractors) result.aovs.push_back({"distractor", fraction_of_signal(distractor_total, result.electrons)});
}

// A distractor as one instant of a moving eye's exposure has it: its
// label, its image, and how many instants from mid-exposure.
struct Highlight {
  DistractorTruth truth;
  GlintImage image;
  int from_middle = 0;
};

// `result`'s distractors with their labels (its camera's views in order,
// as image_distractors lists them).
std::vector<Highlight> highlights_of(const RenderResult& result) {
  std::vector<Highlight> out;
  std::size_t next = 0;
  for (const EyeInCameraTruth& view : result.truth.views) {
    if (view.camera != result.camera) continue;
    for (const DistractorTruth& d : view.distractors) out.push_back({d, result.distractors.at(next++), 0});
  }
  return out;
}

// One highlight across a moving eye's instants: its eye, kind and light;
// the instant nearest mid-exposure that has it; where the latest instant
// had it; its electrons over the exposure.
struct HighlightTrack {
  int eye = 0;
  DistractorKind kind = DistractorKind::sclera;
  int illuminator = 0;
  Highlight nearest;
  Point3 last;
  double electrons = 0;
};

// A meniscus's highlights of one light are told apart across instants by
// where they lie: the nearest one the last instant had, within this.
constexpr double kTrackReachMm = 0.5;

// Adds the instant's highlights to their tracks, or starts new ones: a
// sclera has one per eye and light; a meniscus's join the tracks of their
// eye and light whose last points lie within kTrackReachMm, the closest
// pairs first.
void follow_highlights(std::vector<Highlight> instant, int from_middle, int frames, std::vector<HighlightTrack>& tracks) {
  const std::size_t old_tracks = tracks.size();
  std::vector<int> track_of(instant.size(), -1);
  std::vector<bool> fed(old_tracks, false);
  std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;  // distance, highlight, track
  for (std::size_t k = 0; k < instant.size(); ++k) {
    const DistractorTruth& d = instant[k].truth;
    for (std::size_t t = 0; t < old_tracks; ++t) {
      const HighlightTrack& track = tracks[t];
      if (track.eye != instant[k].image.eye || track.kind != d.kind || track.illuminator != d.illuminator) continue;
      const double gap = d.kind == DistractorKind::sclera ? 0.0 : distance(track.last, d.reflection.point);
      if (gap <= kTrackReachMm) pairs.emplace_back(gap, k, t);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  for (const auto& [gap, k, t] : pairs) {
    if (track_of[k] >= 0 || fed[t]) continue;
    track_of[k] = static_cast<int>(t);
    fed[t] = true;
  }
  for (std::size_t k = 0; k < instant.size(); ++k) {
    Highlight& h = instant[k];
    h.from_middle = from_middle;
    const DistractorTruth& d = h.truth;
    if (track_of[k] < 0) {
      tracks.push_back({h.image.eye, d.kind, d.illuminator, h, d.reflection.point, 0});
      track_of[k] = static_cast<int>(tracks.size()) - 1;
    }
    HighlightTrack& track = tracks[track_of[k]];
    track.last = d.reflection.point;
    if (h.image.electrons > 0 && std::isfinite(h.image.electrons)) track.electrons += h.image.electrons / frames;
    if (from_middle < track.nearest.from_middle) track.nearest = h;
  }
}

// The AOVs that are a highlight's share of the light: summed over a
// moving eye's instants by that share.
bool is_highlight_mask(const std::string& name) {
  return name == "glint" || name.starts_with("glint.") || name == "distractor";
}

// Motion blur renders this many instants at most: an eye whose image
// moves farther during the exposure is refused.
constexpr double kMaxTravelPx = 128;

// The instants (s from mid-exposure) that sample the exposure: {0} when
// no eye moves; else an odd number, the midpoints of equal slices, enough
// that the moving eyes' images move at most half a pixel between two
// (their corneal apex and pupil centre, seen from this camera).
std::vector<double> exposure_instants(const Scene& scene, const Camera& camera) {
  const double exposure = camera.sensor().exposure_s;
  double travel_px = 0;
  for (std::size_t e = 0; e < scene.eyes.size(); ++e) {
    const Eye& eye = scene.eyes[e];
    if (eye.motion().still()) continue;
    const Eye first = eye.at_time(-exposure / 2), last = eye.at_time(exposure / 2);
    for (const auto& [a, b] : {std::pair{first.corneal_apex(), last.corneal_apex()},
                               std::pair{first.pupil_center(), last.pupil_center()}}) {
      const Projection pa = camera.project(a), pb = camera.project(b);
      if (pa.status == ProjectionStatus::behind_camera || pb.status == ProjectionStatus::behind_camera) continue;
      travel_px = std::max(travel_px, std::hypot(pa.pixel.u - pb.pixel.u, pa.pixel.v - pb.pixel.v));
    }
    if (travel_px > kMaxTravelPx) {
      throw std::invalid_argument("render: eyes[" + std::to_string(e) + "] moves " + check::format_number(travel_px) +
                                  " px in camera " + camera.name() + " during its exposure: motion blur renders at most " +
                                  check::format_number(kMaxTravelPx) + " px (a shorter exposure_s or a slower motion)");
    }
  }
  if (travel_px == 0) return {0.0};
  const int frames = 2 * static_cast<int>(std::ceil(travel_px)) + 1;
  std::vector<double> instants(frames);
  for (int k = 0; k < frames; ++k) instants[k] = ((k + 0.5) / frames - 0.5) * exposure;
  instants[frames / 2] = 0;  // exactly
  return instants;
}

}  // namespace

void render(const Scene& scene, int camera_index, const RenderOptions& options, RenderResult& result) {
  validate(scene, camera_index, options);
  const Camera& camera = scene.cameras[camera_index];
  const std::vector<double> instants = exposure_instants(scene, camera);
  const int frames = static_cast<int>(instants.size()), middle = frames / 2;
  tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
  if (frames == 1) {
    render_instant(scene, camera_index, options, arena, result);
  } else {
    // Motion blur: the light of every instant summed, and the glints' and
    // distractors' (their masks: their share of the summed light; each
    // one's electrons); the labels, radiance and other AOVs are the
    // mid-exposure instant's (the scene as given).
    std::vector<double> sum;
    std::vector<std::vector<double>> glint_sums;  // per "glint" and "glint.<light>" AOV, in order
    std::vector<double> glint_electrons;           // per glint image, over the exposure
    // The distractors, followed across the instants: one may come and go
    // as the eye turns. One missing at mid-exposure is labelled as at the
    // instant nearest it where it exists.
    std::vector<HighlightTrack> tracks;
    RenderResult other;
    Scene moved = scene;
    for (int k = 0; k < frames; ++k) {
      RenderOptions instant_options = options;
      if (options.progress) {
        instant_options.progress = [&options, k, frames](double f) { options.progress((k + f) / frames); };
      }
      RenderResult& target = k == middle ? result : other;
      if (k == middle) {
        render_instant(scene, camera_index, instant_options, arena, result);
      } else {
        for (std::size_t e = 0; e < scene.eyes.size(); ++e) moved.eyes[e] = scene.eyes[e].at_time(instants[k]);
        render_instant(moved, camera_index, instant_options, arena, other);
      }
      const std::vector<float>& light = target.electrons.values;
      sum.resize(light.size(), 0.0);
      glint_electrons.resize(target.glints.size(), 0.0);
      for (std::size_t i = 0; i < glint_electrons.size(); ++i) {
        if (target.glints[i].electrons > 0 && std::isfinite(target.glints[i].electrons)) {
          glint_electrons[i] += target.glints[i].electrons / frames;
        }
      }
      follow_highlights(highlights_of(target), std::abs(k - middle), frames, tracks);
      for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += light[i];
      std::size_t g = 0;
      for (const NamedPlane& aov : target.aovs) {
        if (!is_highlight_mask(aov.name)) continue;
        if (g == glint_sums.size()) glint_sums.emplace_back(light.size(), 0.0);
        for (std::size_t i = 0; i < light.size(); ++i) glint_sums[g][i] += double(aov.plane.values[i]) * light[i];
        ++g;
      }
    }
    for (std::size_t i = 0; i < sum.size(); ++i) result.electrons.values[i] = static_cast<float>(sum[i] / frames);
    // A glint's electrons are the whole exposure's (its label's place and
    // status stay the mid-exposure instant's).
    for (std::size_t i = 0; i < result.glints.size(); ++i) result.glints[i].electrons = glint_electrons[i];
    // Each view's distractors: the mid-exposure instant's, and as at the
    // nearest instant those it has not; in each instant's order: the
    // sclera's by light, the lenses' ghosts by lens, surface and light,
    // the lower lid's meniscus's by light and along the lid (head-frame x),
    // then the upper's.
    const auto along_lid = [&](const HighlightTrack& t) {
      if (t.kind != DistractorKind::tear_meniscus && t.kind != DistractorKind::upper_tear_meniscus) return 0.0;
      return (head_placement(scene, t.eye).world_from_head.inverse() * t.nearest.truth.reflection.point).x;
    };
    const auto rank = [](DistractorKind kind) {
      switch (kind) {
        case DistractorKind::sclera: return 0;
        case DistractorKind::spectacle_lens_front:
        case DistractorKind::spectacle_lens_back: return 1;
        case DistractorKind::tear_meniscus: return 2;
        case DistractorKind::upper_tear_meniscus: return 3;
      }
      return 4;
    };
    std::vector<std::tuple<int, int, int, DistractorKind, int, double, std::size_t>> order;
    for (std::size_t t = 0; t < tracks.size(); ++t) {
      const HighlightTrack& track = tracks[t];
      order.emplace_back(track.eye, rank(track.kind), track.nearest.truth.spectacle_lens, track.kind,
                         track.illuminator, along_lid(track), t);
    }
    std::sort(order.begin(), order.end());
    std::vector<GlintImage> images;
    for (EyeInCameraTruth& view : result.truth.views) {
      if (view.camera != camera_index) continue;
      view.distractors.clear();
      for (const auto& entry : order) {
        const HighlightTrack& track = tracks[std::get<6>(entry)];
        if (track.eye != view.eye) continue;
        view.distractors.push_back(track.nearest.truth);
        GlintImage image = track.nearest.image;
        image.electrons = track.electrons;
        images.push_back(image);
      }
    }
    result.distractors = std::move(images);
    std::size_t g = 0;
    for (NamedPlane& aov : result.aovs) {
      if (!is_highlight_mask(aov.name)) continue;
      for (std::size_t i = 0; i < sum.size(); ++i) {
        aov.plane.values[i] = sum[i] > 0 ? static_cast<float>(std::clamp(glint_sums[g][i] / sum[i], 0.0, 1.0)) : 0.0f;
      }
      ++g;
    }
  }

  Sensor sensor = camera.sensor();
  if (!options.noise) sensor.noise = false;
  arena.execute([&] { result.sensor = expose(result.electrons, sensor, options.seed); });
  if (sensor.jpeg_quality) compress_jpeg(result.sensor, *sensor.jpeg_quality);
}

}  // namespace purkinje::renderer
