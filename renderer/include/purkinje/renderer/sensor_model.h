#pragma once
// From light to digital numbers: radiometric conversion, blur by the
// optics' point spread (models/camera_optics.h), point images (glints),
// shot and read noise, gain, saturation and quantization.
// Everything random is a pure function of (seed, pixel): results do not
// depend on thread count or order.

#include <cstdint>
#include <vector>

#include "purkinje/models/camera.h"
#include "purkinje/models/camera_optics.h"
#include "purkinje/models/sensor.h"
#include "purkinje/renderer/image.h"

namespace purkinje::renderer {

// Electrons collected by one pixel from a scene of uniform radiance
// 1 W m^-2 sr^-1 filling it, on the optical axis (no cos^4 falloff):
// (pi / 4) / N^2 * pixel area * exposure * QE * lambda / (h c).
double electrons_per_unit_radiance(const Sensor& sensor, double wavelength_nm);
// Electrons from optical power (W) entering the aperture and landing on
// the sensor: power * exposure * QE * lambda / (h c).
double electrons_per_watt(const Sensor& sensor, double wavelength_nm);
// Convolves a plane with the point spread (edges clamped). Energy is
// conserved away from the borders. The input is taken as pixel averages
// (as rendered), so the kernel's variance is the point spread's own,
// sigma^2 + r^2 / 4 per axis, exactly: the Gaussian is the discrete
// Gaussian exp(-t) I_n(t), t = sigma^2 (a sampled Gaussian is 14% narrow
// at sigma 0.5), and the disc kernel weighs each pixel by the disc's area
// inside it, with the disc shrunk slightly (to sqrt(r^2 - 1/3) for large r)
// so the pixel footprint is not counted twice. sigma 0 and r 0 return the
// input unchanged.
ImagePlane blur(const ImagePlane& plane, const PointSpread& psf);
// The same into `out`, with `scratch` for the intermediate pass: both are
// resized and their memory reused (for callers rendering many images).
// Throws std::invalid_argument unless the three planes are distinct.
void blur(const ImagePlane& plane, const PointSpread& psf, ImagePlane& out, ImagePlane& scratch);

// Adds the image of a point source carrying `total_electrons`, centred at
// pixel (u, v) (OpenCV convention: pixel centres at integers), spread by
// the point spread and by the source's own image, a Gaussian of covariance
// `source_cov_px2` (u-u, u-v, v-v), e.g. an LED's finite size. The
// defocus disc enters as a Gaussian of the same covariance (r^2 / 4 per
// axis): right second moments, soft edge. Each pixel receives the integral
// over its square of the combined Gaussian (erf when it is axis-aligned,
// Gauss-Legendre along one axis otherwise), within +-5 sigma; light beyond
// the image is lost. The pixel-weighted centroid is then (u, v) up to the
// sampling bias of a narrow spot: at most 0.0023 px for a total sigma of
// 0.5 px, 0.0003 at 0.6, but 0.006 at 0.45, 0.014 at 0.4 and 0.05 at 0.3.
// The second moments are the covariance plus 1/12 px^2 (the pixel).
// A total sigma of 0 puts everything into the nearest pixel. Throws
// std::invalid_argument on a non-finite position, negative or non-finite
// electrons, or a covariance that is not positive semi-definite.
void add_point_image(ImagePlane& electrons, double u, double v, double total_electrons,
                     const PointSpread& psf, const double source_cov_px2[3]);

// Lens vignetting beyond the natural cos^4 at image position (u, v):
// 1 - (1 - sensor.corner_illumination) rho^2, rho the distance from the
// principal point over that of the farthest image corner (the pixel
// edges', half a pixel beyond the corner pixels' centres).
double lens_illumination(const Camera& camera, double u, double v);

// A sensor's hot pixels in an image of width x height: pixel (x, y) is hot
// when a counter-based draw keyed by (hot_pixel_seed, y * width + x) falls
// below hot_pixel_fraction; its dark charge over the exposure is
// hot_pixel_e_per_s * exposure_s * (0.5 + another draw). The same pixels
// and charges in every image of the sensor; none when the fraction is 0.
struct HotPixel {
  int x = 0, y = 0;
  double dark_e = 0;
};
std::vector<HotPixel> hot_pixels(const Sensor& sensor, int width, int height);

// Noise (when sensor.noise), full-well clipping, gain and quantization:
// DN = round(clip(e, 0, full well) * gain * (2^bits - 1) / full well),
// clipped to 2^bits - 1. NaN or negative electrons count as 0; +inf saturates.
// Shot noise is Poisson, exact: inversion below 10 electrons, Hormann's
// transformed rejection (PTRS) above, normal only above 1e10; read noise
// Gaussian (ziggurat). Both are drawn from a counter-based generator keyed by
// (seed, pixel index): the image does not depend on the thread count.
// Hot pixels' dark charge (hot_pixels) is added to their light before the
// noise, with or without it: they are a fixed pattern, not noise.
// Throws std::invalid_argument for bits other than 8, 10, 12 or 16 and for
// a full well <= 0 or a negative gain or read noise.
SensorImage expose(const ImagePlane& electrons, const Sensor& sensor, std::uint64_t seed);

// The sensor image as a camera streaming MJPEG delivers it: encoded as a
// baseline JPEG of `quality` (1-100, libjpeg's scaling of its standard
// tables; one grey channel, so no chroma subsampling) and decoded again,
// in place. Throws std::invalid_argument unless the image has 8 bits and
// the quality is in range.
void compress_jpeg(SensorImage& image, int quality);

// A counter-based random number in [0, 1) from (seed, stream, index): the
// same inputs always give the same number. The renderer's own streams
// (src/sampler.h) are 1 to 4 and, for expose's noise, one above 2^63.
double uniform01(std::uint64_t seed, std::uint64_t stream, std::uint64_t index);

}  // namespace purkinje::renderer
