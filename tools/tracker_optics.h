#pragma once
// What a tracker knows of its own optics, told to purkinje's glint
// detector by the commands that have a scene (`purkinje calibrate`,
// `purkinje track --scene`).

#include <vector>

#include "purkinje/models/camera.h"
#include "purkinje/models/illuminator.h"
#include "purkinje/trackers/glints.h"

namespace purkinje::tools {

// The glint detector's settings for images from `camera` of an eye whose
// cornea is near `nominal_cornea`: the sensor's noise (which weighs a
// saturated glint's pixels), and the spot's width when it is the camera's
// point spread wherever the eye is (no defocus at that depth, point
// lights); else the detector estimates the width from each frame.
trackers::BlobGlintSettings glint_settings_for(const Camera& camera, const std::vector<Illuminator>& lights,
                                               const Point3& nominal_cornea);

}  // namespace purkinje::tools
