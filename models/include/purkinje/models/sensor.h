#pragma once
// The image sensor and lens aperture behind a camera: what turns scene
// radiance into digital numbers. Plain data; the renderer applies it.

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
};

}  // namespace purkinje
