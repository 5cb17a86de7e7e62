#pragma once
// purkinje's tracker on one image, assembled once: glints detected, each
// told its light, then the pupil detected with the glints masked. Built
// knowing nothing (the detectors' defaults; glints keep illuminator -1) or
// knowing the rig it watches: the camera's optics tell the glint detector
// the spot's width and the sensor's noise (trackers::glint_settings_for),
// and where the rig's lights put glints on the nominal eye says which
// glint is whose (trackers::identify_glints).

#include <optional>
#include <vector>

#include "purkinje/models/camera.h"
#include "purkinje/models/eye.h"
#include "purkinje/models/illuminator.h"
#include "purkinje/trackers/glints.h"
#include "purkinje/trackers/image.h"
#include "purkinje/trackers/pupil.h"
#include "purkinje/trackers/scoring.h"

namespace purkinje::studies {

class Tracker {
 public:
  // The detectors' defaults; no glint is told its light.
  Tracker();
  // For images of `camera` with `lights` of an eye near `nominal_eye`.
  Tracker(const Camera& camera, const std::vector<Illuminator>& lights, const Eye& nominal_eye);

  // The glints, brightest first, and the pupil if found (its centre, its
  // ellipse and the detector's confidence).
  trackers::Detections track(const trackers::GreyView& image) const;

  // What the glint detector was told (the spot's width 0: estimated per frame).
  const trackers::BlobGlintSettings& glint_settings() const { return glint_settings_; }
  // Whether glints are told their lights.
  bool identifies_glints() const { return !layout_.empty(); }

 private:
  trackers::BlobGlintSettings glint_settings_;
  trackers::BlobGlintDetector glint_detector_;
  trackers::StarburstPupilDetector pupil_detector_;
  std::vector<std::optional<Pixel>> layout_;  // per light, on the nominal eye; empty: no identity
};

}  // namespace purkinje::studies
