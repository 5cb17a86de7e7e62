// Fuzz target: the labels reader (parse_image_labels), which reads back
// the JSON `purkinje render` writes beside each image. It documents
// std::runtime_error only; anything else escaping (nlohmann's own
// exceptions among them), a crash or a sanitizer report is a finding. On
// success, every value must pass the rules the reader checks: sizes and
// bits in range, glints' lights among the file's, and finite numbers
// (docs/labels.md: no NaN, ever).

#include <cmath>
#include <stdexcept>
#include <string_view>

#include "fuzz_target.h"
#include "purkinje/models/labels.h"

namespace {

bool finite(const purkinje::Pixel& p) { return std::isfinite(p.u) && std::isfinite(p.v); }

}  // namespace

PURKINJE_FUZZ_TARGET(labels) {
  purkinje::ImageLabels labels;
  try {
    labels = purkinje::parse_image_labels(std::string_view(reinterpret_cast<const char*>(data), size),
                                          "fuzz/labels.json");
  } catch (const std::runtime_error&) {
    return 0;
  }
  PURKINJE_FUZZ_CHECK(labels.width_px >= 1 && labels.height_px >= 1);
  PURKINJE_FUZZ_CHECK(labels.bits >= 1 && labels.bits <= 16);
  PURKINJE_FUZZ_CHECK(labels.image.parent_path() == "fuzz");
  for (const purkinje::EyeInCameraTruth& view : labels.views) {
    PURKINJE_FUZZ_CHECK(view.camera >= 0 && view.eye >= 0);
    for (const purkinje::GlintTruth& glint : view.glints) {
      PURKINJE_FUZZ_CHECK(glint.illuminator >= 0);
      PURKINJE_FUZZ_CHECK(finite(glint.pixel));
    }
    for (const purkinje::PupilBorderPointTruth& point : view.pupil.border) {
      PURKINJE_FUZZ_CHECK(std::isfinite(point.angle_rad) && finite(point.pixel));
    }
    if (view.pupil.ellipse_valid) {
      const purkinje::Ellipse& e = view.pupil.ellipse;
      PURKINJE_FUZZ_CHECK(finite(e.center) && std::isfinite(e.angle_rad));
      PURKINJE_FUZZ_CHECK(e.semi_axis_1_px > 0 && e.semi_axis_2_px > 0);
      PURKINJE_FUZZ_CHECK(std::isfinite(e.semi_axis_1_px) && std::isfinite(e.semi_axis_2_px));
    }
    PURKINJE_FUZZ_CHECK(finite(view.pupil.refracted_center));
  }
  return 0;
}
