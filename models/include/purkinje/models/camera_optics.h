#pragma once
// What a camera's lens does to the image of a point: its aperture and
// the blur at a depth. The renderer draws with it; a tracker that knows
// its camera tells its glint detector the spot's width with it.

#include "purkinje/models/camera.h"

namespace purkinje {

// Aperture diameter in mm: focal length / N.
double aperture_diameter_mm(const Camera& camera);

// Blur kernel of the optics at one depth: a Gaussian of psf_sigma_px
// convolved with a uniform disc of the thin-lens blur circle's radius
// (0 when the sensor has no focus distance).
struct PointSpread {
  double sigma_px = 0.5;
  double defocus_radius_px = 0.0;
};
// The point spread for objects at `depth_mm` (camera z) seen by `camera`.
// Throws std::invalid_argument for depth <= 0 or a focus distance not
// beyond the focal length.
PointSpread point_spread(const Camera& camera, double depth_mm);

}  // namespace purkinje
