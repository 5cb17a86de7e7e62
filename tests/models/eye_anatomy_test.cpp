// anatomy_problem: one set of rules for eye models read from scene files
// and built in code. Expected depths come from R - sqrt(R^2 - r^2), not
// from the cancellation-free form the code uses.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "purkinje/models/eye.h"
#include "purkinje/models/scene_file.h"

namespace purkinje {
namespace {

// The scene reader's message for an eye given as JSON, or "(read)".
std::string reader_message(const std::string& eye) {
  try {
    parse_scene(R"({ "format": 1,
      "cameras": [ { "resolution_px": [64, 48], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                     "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] } ],
      "eyes": [ )" + eye + R"( ] })",
                "eye.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(read)";
}

TEST(EyeAnatomy, PresetsBreakNoRuleAndTheirNamesComeFromThePresets) {
  EXPECT_EQ(eye_model_preset_names(), (std::vector<std::string>{"keratometric", "le_grand", "navarro"}));
  for (const std::string& name : eye_model_preset_names()) {
    const std::optional<EyeModel> m = eye_model_preset(name);
    ASSERT_TRUE(m) << name;
    EXPECT_EQ(m->name, name);
    EXPECT_FALSE(anatomy_problem(*m)) << name << ": " << anatomy_problem(*m)->key;
  }
  // The reader's list of valid names is the presets'.
  EXPECT_NE(reader_message(R"({ "model": "gullstrand" })")
                .find("unknown eye model (valid: keratometric, le_grand, navarro)"),
            std::string::npos);
}

// A posterior cornea whose apex lies behind the limbus plane (keratometric
// curvature: the limbus 5.9 mm from the axis is 7.8 - sqrt(7.8^2 - 5.9^2) =
// 2.69804 mm deep): the reader used to accept it and the renderer refused
// it; both now name the same rule.
TEST(EyeAnatomy, APosteriorCorneaStartingBehindTheLimbusIsRefusedByTheReaderAndInCode) {
  EyeModel m = *eye_model_preset("le_grand");
  m.anterior_cornea = {7.8, 0.0};
  m.limbus_radius_mm = 5.9;
  m.posterior_cornea->thickness_mm = 2.8;
  const std::optional<AnatomyProblem> problem = anatomy_problem(m);
  ASSERT_TRUE(problem);
  EXPECT_EQ(problem->key, "posterior_cornea.thickness_mm");
  EXPECT_EQ(problem->value, "2.8");
  const double depth = 7.8 - std::sqrt(7.8 * 7.8 - 5.9 * 5.9);
  const std::string lead = "must be < the limbus's depth behind the corneal apex (";
  ASSERT_EQ(problem->rule.rfind(lead, 0), 0u) << problem->rule;
  EXPECT_NEAR(std::stod(problem->rule.substr(lead.size())), depth, 1e-12) << problem->rule;
  const std::string message = reader_message(
      R"({ "model": "le_grand", "cornea": { "radius_mm": 7.8, "asphericity": 0, "limbus_radius_mm": 5.9 },
           "posterior_cornea": { "thickness_mm": 2.8 } })");
  EXPECT_EQ(message, "eye.json: eyes[0].posterior_cornea.thickness_mm = 2.8: " + problem->rule);
}

// Models built in code reach no reader: sizes that make no eye are named.
TEST(EyeAnatomy, SizesThatMakeNoEyeAreNamedByTheirKeys) {
  const EyeModel good = *eye_model_preset("keratometric");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case {
    void (*set)(EyeModel&, double);
    double value;
    const char* key;
  };
  const Case cases[] = {
      {[](EyeModel& m, double v) { m.anterior_cornea.radius_mm = v; }, nan, "cornea.radius_mm"},
      {[](EyeModel& m, double v) { m.anterior_cornea.radius_mm = v; }, -7.8, "cornea.radius_mm"},
      {[](EyeModel& m, double v) { m.anterior_cornea.asphericity = v; }, -1.5, "cornea.asphericity"},
      {[](EyeModel& m, double v) { m.limbus_radius_mm = v; }, 0.0, "cornea.limbus_radius_mm"},
      {[](EyeModel& m, double v) { m.iris_depth_mm = v; }, INFINITY, "iris.depth_mm"},
      {[](EyeModel& m, double v) { m.pupil_radius_mm = v; }, -1.0, "pupil.radius_mm"},
      {[](EyeModel& m, double v) { m.sclera_radius_mm = v; }, 0.0, "sclera_radius_mm"},
      {[](EyeModel& m, double v) { m.rotation_center_depth_mm = v; }, nan, "rotation_center_depth_mm"},
  };
  for (const Case& c : cases) {
    EyeModel m = good;
    c.set(m, c.value);
    const std::optional<AnatomyProblem> problem = anatomy_problem(m);
    ASSERT_TRUE(problem) << c.key;
    EXPECT_EQ(problem->key, c.key);
  }
  // A limbus beyond the cap (R / sqrt(1 + Q) = 7.8 mm for a sphere).
  EyeModel wide = good;
  wide.limbus_radius_mm = 8.0;
  ASSERT_TRUE(anatomy_problem(wide));
  EXPECT_EQ(anatomy_problem(wide)->key, "cornea.limbus_radius_mm");
  EXPECT_EQ(anatomy_problem(wide)->rule,
            "must be < radius_mm / sqrt(1 + asphericity) = 7.8 mm, where the cornea stops being a single-valued cap");
}

}  // namespace
}  // namespace purkinje
