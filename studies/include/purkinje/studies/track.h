#pragma once
// Trackers over a labelled image set, scored against its labels:
// purkinje's own (track_images, `purkinje track`) or another tracker's
// detections file (score_detections, `purkinje score`).

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "purkinje/models/scene.h"
#include "purkinje/studies/image_set.h"
#include "purkinje/trackers/detections_file.h"
#include "purkinje/trackers/scoring.h"

namespace purkinje::studies {

struct TrackedSet {
  trackers::Score score;
  std::map<std::string, trackers::Detections> detections;  // by image name
  double seconds = 0;  // in the detectors, over all images
};

// purkinje's tracker (tracker.h) over the images, in order, `step` called
// after each. Without a rig (null) the detectors' defaults; with one, a
// tracker per camera of the rig, told its optics and which light makes
// which glint on the rig's first eye. Throws std::runtime_error naming
// an image whose pixels fail their labels' checks, or whose labels'
// camera and lights are not the rig's (`rig_file` names the rig); what
// the image reader, the detectors and the scorer throw passes through.
TrackedSet track_images(const std::vector<LabelledImage>& images, const Scene* rig, const std::string& rig_file,
                        const trackers::ScoringSettings& settings, const std::function<void()>& step = {});

struct ScoredSet {
  trackers::Score score;
  std::map<std::string, trackers::Detections> detections;  // by labelled image name: the rows scored
  std::vector<std::string> notes;  // for people, a line each: what was left out, and why
};

// A detections file's rows (`file_name` names it) scored against the
// images. A row names its image by file name, by a path ending in it, or
// by the name without its extension when only one image has it; rows of
// images outside the set are left out (a tracker run over a whole folder
// is scored on the part that is labelled), and so are pupils reported
// less confident than `min_confidence`. A feature without rows is not
// scored. Throws std::runtime_error when two names of the file mean one
// image (cam0/f1.png and cam1/f1.png would merge two images' detections).
ScoredSet score_detections(const std::vector<LabelledImage>& images, const trackers::DetectionsFile& file,
                           const std::string& file_name, trackers::ScoringSettings settings, double min_confidence);

}  // namespace purkinje::studies
