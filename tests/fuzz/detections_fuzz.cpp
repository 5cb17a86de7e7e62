// Fuzz target: the detections CSV reader (parse_detections_csv), which
// reads another tracker's output for scoring. It documents
// std::runtime_error only; anything else escaping, a crash or a sanitizer
// report is a finding. On success, every detection must pass the rules the
// header states: finite centres, a light's index from 0 (or -1, not told),
// an ellipse of positive finite semi-axes, confidence in [0, 1].

#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

#include "fuzz_target.h"
#include "purkinje/trackers/detections_file.h"

namespace {

bool finite(const purkinje::Pixel& p) { return std::isfinite(p.u) && std::isfinite(p.v); }

}  // namespace

PURKINJE_FUZZ_TARGET(detections) {
  std::map<std::string, purkinje::trackers::Detections> detections;
  try {
    detections = purkinje::trackers::parse_detections_csv(std::string(reinterpret_cast<const char*>(data), size),
                                                          "fuzz.csv");
  } catch (const std::runtime_error&) {
    return 0;
  }
  for (const auto& [image, d] : detections) {
    PURKINJE_FUZZ_CHECK(!image.empty());
    for (const purkinje::trackers::Glint& g : d.glints) {
      PURKINJE_FUZZ_CHECK(finite(g.centre));
      PURKINJE_FUZZ_CHECK(g.illuminator >= -1);
    }
    for (const purkinje::trackers::PupilFound& p : d.pupils) {
      PURKINJE_FUZZ_CHECK(finite(p.centre));
      if (p.ellipse) {
        PURKINJE_FUZZ_CHECK(p.ellipse->semi_axis_1_px > 0 && std::isfinite(p.ellipse->semi_axis_1_px));
        PURKINJE_FUZZ_CHECK(p.ellipse->semi_axis_2_px > 0 && std::isfinite(p.ellipse->semi_axis_2_px));
        PURKINJE_FUZZ_CHECK(std::isfinite(p.ellipse->angle_rad));
        PURKINJE_FUZZ_CHECK(p.ellipse->center == p.centre);
      }
      if (p.confidence) PURKINJE_FUZZ_CHECK(*p.confidence >= 0 && *p.confidence <= 1);
    }
  }
  return 0;
}
