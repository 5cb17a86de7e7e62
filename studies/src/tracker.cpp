#include "purkinje/studies/tracker.h"

namespace purkinje::studies {

Tracker::Tracker() : glint_detector_(glint_settings_) {}

Tracker::Tracker(const Camera& camera, const std::vector<Illuminator>& lights, const Eye& nominal_eye)
    : glint_settings_(trackers::glint_settings_for(camera, lights, nominal_eye.cornea_center())),
      glint_detector_(glint_settings_),
      layout_(trackers::nominal_glint_layout(camera, lights, nominal_eye)) {}

trackers::Detections Tracker::track(const trackers::GreyView& image) const {
  trackers::Detections found;
  found.glints = glint_detector_.detect(image);
  if (identifies_glints()) trackers::identify_glints(found.glints, layout_);
  if (const std::optional<trackers::PupilDetection> pupil = pupil_detector_.detect(image, found.glints)) {
    found.pupils.push_back({pupil->ellipse.center, pupil->ellipse, pupil->confidence});
  }
  return found;
}

}  // namespace purkinje::studies
