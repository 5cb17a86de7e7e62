#pragma once
// Rendering a scene as one of its cameras sees it: near-infrared radiance
// from the eye, lids and skin, glints from the specular-path solver, the
// sensor's response, AOVs, and labels that agree with the pixels.
//
// Fast mode (the default) is deterministic apart from sub-pixel jitter:
// camera rays with Fresnel-weighted reflection and refraction at the
// cornea, direct light with shadow rays, iris light through the cornea
// from an exact cache on the iris plane (IrisIrradianceCache), glints
// computed explicitly and imaged through the point-spread function.
// Reference mode estimates the same light transport by brute force, to
// validate the fast mode: camera paths with diffuse interreflection and
// emitters of their finite size sampled at every diffuse bounce; light
// reaching the iris through the cornea from photons traced from the LEDs
// through the cornea (reflections inside it included) and binned on the
// iris plane. Glints are imaged explicitly in both modes: camera rays
// cannot find them (docs/rendering.md).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "purkinje/models/output_file.h"
#include "purkinje/models/scene.h"
#include "purkinje/models/truth.h"
#include "purkinje/renderer/image.h"
#include "purkinje/renderer/image_io.h"
#include "purkinje/renderer/radiometry.h"

namespace purkinje::renderer {

enum class RenderMode { fast, reference };
const char* to_string(RenderMode mode);

// A rectangle of pixels, [x0, x1) x [y0, y1).
struct PixelRegion {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

// How a pixel weighs the image plane about its centre: its camera rays go
// through positions drawn from the filter (filter importance sampling,
// separable in x and y), each weighing alike. Box, one pixel wide, is the
// pixel's own square; the others are what renderers such as Cycles use,
// for comparing images with theirs (docs/rendering.md).
enum class PixelFilterKind { box, gaussian, blackman_harris };
const char* to_string(PixelFilterKind kind);  // "box", "gaussian", "blackman-harris"
std::optional<PixelFilterKind> pixel_filter_kind(const std::string& name);
// Every kind's name, in the enum's order.
const std::vector<std::string>& pixel_filter_names();

struct PixelFilter {
  PixelFilterKind kind = PixelFilterKind::box;
  // Width of its square of support, in pixels: 0 for the kind's usual
  // (box 1; Gaussian 3, its sigma a sixth of the width; Blackman-Harris 3).
  double width_px = 0;
};
// The width a filter has (its own, or its kind's usual one).
double pixel_filter_width_px(const PixelFilter& filter);
// Whether `width_px` may be given: 0 (the kind's usual) or within
// [0.25, 16] px; the rule as render() states it when it is broken.
bool pixel_filter_width_allowed(double width_px);
inline constexpr const char* kPixelFilterWidthRule = "must be 0 (the filter's usual width) or in [0.25, 16]";

struct RenderOptions {
  RenderMode mode = RenderMode::fast;
  // Camera rays per pixel, low-discrepancy with a seeded shift; a single
  // ray goes through the pixel's centre.
  int samples_per_pixel = 1;
  // Adaptive sampling (fast mode): when larger than samples_per_pixel, the
  // pixels that the first pass finds on outlines, textures or shadow edges
  // are rendered again, strong edges with this many rays, the others with
  // fewer (docs/rendering.md). 0: off. The reference mode samples every
  // pixel alike: choosing pixels by their noisy first samples would bias it.
  int edge_samples_per_pixel = 16;
  PixelFilter pixel_filter;       // box, one pixel wide
  std::uint64_t seed = 0;         // sub-pixel jitter, emitter sampling and sensor noise
  bool noise = true;              // false: no shot or read noise whatever the sensor says
  // Nodes per side of each iris irradiance cache (fast mode). 0: from the
  // iris's size in the image, a node every 2 px or so (odd, 9 to 33).
  int iris_cache_resolution = 0;
  // Reference mode: photons traced from each light into each eye for the
  // light that reaches the iris after reflecting inside the cornea (about
  // 1e-5 of its light), binned on the iris plane.
  std::int64_t reference_photons_per_light = std::int64_t{1} << 18;
  bool per_light_glint_masks = false;
  // Trace only these pixels (the rest stay 0 in radiance and AOVs); glints,
  // tear menisci's highlights and the sensor still cover the whole image.
  // A wet sclera's highlights are light on the sclera the traced pixels
  // see: only the region's part is drawn, and their labels' electrons
  // count it. Absent: every pixel.
  std::optional<PixelRegion> region;
  int threads = 0;                // 0: all hardware threads; results do not depend on it
  // Called from worker threads with the fraction of rows done; must be thread-safe.
  std::function<void(double fraction)> progress;
};

// The most rays a pixel that adaptive sampling refines gets (on a strong
// edge): samples_per_pixel when it is off (reference mode, or edge samples
// no more than samples).
int edge_samples_per_pixel(const RenderOptions& options);

// Pixel classes of the segmentation AOV ("id"): the first diffuse surface
// seen through the cornea where the ray passes it; per pixel, the class
// most of its samples see.
enum class PixelClass : int { background = 0, skin = 1, sclera = 2, iris = 3, pupil = 4, lash = 5, brow = 6 };

struct GlintImage {
  int eye = 0;
  int illuminator = 0;
  PathStatus status = PathStatus::no_solution;  // as labelled (occluded when lids hide it)
  GlintRadiometry radiometry;
  double electrons = 0;  // total signal before saturation
};

struct RenderResult {
  int camera = 0;
  // Scene radiance averaged over each pixel, W m^-2 sr^-1, before the
  // point-spread function and without glints (they are not resolved by
  // pixel sampling; see `electrons`).
  ImagePlane radiance;
  // The noise-free linear image in electrons: radiance through the optics
  // (point-spread function), glints added as point images.
  ImagePlane electrons;
  SensorImage sensor;           // noise, saturation, quantization
  std::vector<NamedPlane> aovs; // depth, N.x/N.y/N.z, id, class coverages, glint masks, distractor mask
  SceneTruth truth;             // compute_truth with the ray tracer's occlusion (every camera's views)
  std::vector<GlintImage> glints;
  // The highlights of eyes with a tear film (their sclera's, with the
  // roughness's spread, and their tear menisci's), as glints: each view's
  // DistractorTruth in order.
  std::vector<GlintImage> distractors;
};

RenderResult render(const Scene& scene, int camera, const RenderOptions& options = {});
// The same into `result`, overwritten whole, reusing its images' memory: a
// loop over many images renders without allocating each one anew (fresh
// memory costs a page fault per 4 KB, a tenth of a remote render). Either
// form also keeps its scratch images for the thread's next render (at most
// 64 MB per thread); the images do not depend on any of this. Bad options
// throw before `result` is touched; a later failure leaves it valid but
// unspecified.
void render(const Scene& scene, int camera, const RenderOptions& options, RenderResult& result);

// The files of one rendered image: the sensor image (PNG), float radiance
// with AOVs (EXR), the pixel classes (indexed PNG) and the labels (JSON:
// the `purkinje truth` schema plus a "render" section with file names and
// checks, sensor settings and glint radiometry). A file not chosen has an
// empty path.
struct RenderFiles {
  std::filesystem::path image, exr, labels, segmentation;
};

// Which files an image gets and how: `render` writes the defaults, a data
// set chooses (models/dataset_spec.h).
struct ImageFileChoice {
  bool image = true;                    // <stem>.png
  bool exr = true;                      // <stem>.exr
  std::vector<std::string> exr_planes;  // empty: every plane (exr_plane_names)
  ExrSettings exr_settings;
  bool segmentation = false;            // <stem>_classes.png
  bool indent_labels = true;            // false: one line, a third smaller
  // A JSON object whose members join the labels' top level (a data set's
  // "dataset" section); empty: none.
  std::string labels_extra;
};

// The planes an EXR of `scene` rendered with `options` holds, in order.
std::vector<std::string> exr_plane_names(const Scene& scene, const RenderOptions& options);

// Adds <dir>/<stem>.png, .exr, _classes.png and .json (as `choice` says)
// to `files` (copying what they need), so that several images can be
// committed all-or-nothing together. Throws std::invalid_argument for an
// EXR plane the render does not have.
RenderFiles add_render(FileSet& files, const std::filesystem::path& dir, const std::string& stem,
                       const Scene& scene, const RenderResult& result, const RenderOptions& options,
                       const ImageFileChoice& choice = {});
// Writes <dir>/<stem>.png, .exr and .json all-or-nothing (FileSet);
// throws OutputError naming the file and the reason.
RenderFiles write_render(const std::filesystem::path& dir, const std::string& stem, const Scene& scene,
                         const RenderResult& result, const RenderOptions& options);
// The options that decide an image's bytes besides the scene (mode,
// samples, seed, caches, glint masks, photons, the sensor as rendered), as
// the labels' "render" section records them: JSON, one line. A resumed
// set keeps a unit only when its labels record these.
std::string render_settings_json(const Scene& scene, int camera, const RenderOptions& options);

}  // namespace purkinje::renderer
