#pragma once
// The image sensor and lens aperture behind a camera: what turns scene
// radiance into digital numbers. Plain data; the renderer applies it.

#include <cstdint>
#include <optional>

namespace purkinje {

struct Sensor {
  double pixel_pitch_mm = 0.006;      // square pixels; with fx gives the focal length in mm
  double f_number = 2.8;              // aperture diameter = focal length / f_number
  double exposure_s = 0.004;
  double quantum_efficiency = 0.3;    // electrons per photon at the illuminators' wavelength
  double full_well_e = 10000;         // electrons; a pixel saturates here
  double read_noise_e = 4;            // Gaussian, electrons RMS
  // Analog gain: 1 maps the full well onto the ADC's full range;
  // DN = electrons * gain * (2^bits - 1) / full_well_e, clipped to the range.
  double gain = 1.0;
  int bits = 8;                       // ADC depth: 8, 10, 12 or 16
  double psf_sigma_px = 0.5;          // Gaussian point-spread function of the optics
  // Thin-lens focus; absent: everything is in focus (no defocus blur).
  std::optional<double> focus_distance_mm;
  bool noise = true;                  // shot and read noise
  // Lens vignetting beyond the natural cos^4 falloff (always applied): the
  // relative illumination at the image corner farthest from the principal
  // point; in between 1 - (1 - corner) rho^2, rho the distance from the
  // principal point over that corner's (cos^n's leading term). 1: none.
  double corner_illumination = 1;
  // Hot pixels, a fixed pattern of the sensor: this fraction of its pixels
  // (picked by hot_pixel_seed: the same pixels in every image) collect dark
  // charge at hot_pixel_e_per_s times a factor in [0.5, 1.5) each, over
  // the exposure, shot noise included.
  double hot_pixel_fraction = 0;
  double hot_pixel_e_per_s = 2e6;
  std::uint64_t hot_pixel_seed = 1;
  // The 8-bit image compressed as a JPEG of this quality (1-100) and
  // decoded again, as headset cameras streaming MJPEG deliver their
  // frames. Absent: raw.
  std::optional<int> jpeg_quality;
};

}  // namespace purkinje
