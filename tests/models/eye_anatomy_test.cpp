// anatomy_problem: one set of rules for eye models read from scene files
// and built in code. Expected depths come from R - sqrt(R^2 - r^2), not
// from the cancellation-free form the code uses.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "purkinje/models/check.h"
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

// Where the iris ends: in a two-surface eye at the chamber angle, where the
// posterior cornea (which runs down to the iris plane) meets it; in a
// one-surface eye at the sclera's sphere. By hand, for the presets' shared
// anatomy (iris plane 3.6 mm deep, posterior apex 0.55 mm deep, R 6.5 mm;
// sclera R 12 mm about a centre 13.5 mm deep).
TEST(EyeAnatomy, TheIrisEndsAtTheChamberAngleOrAtTheSclera) {
  const double w = 3.6 - 0.55;
  EXPECT_NEAR(navarro_eye().iris_outer_radius_mm(), std::sqrt(6.5 * 6.5 - (6.5 - w) * (6.5 - w)), 1e-12);
  EXPECT_NEAR(le_grand_eye().iris_outer_radius_mm(), std::sqrt(6.5 * 6.5 - (6.5 - w) * (6.5 - w)), 1e-12);
  EXPECT_NEAR(keratometric_eye().iris_outer_radius_mm(), std::sqrt(12.0 * 12.0 - 9.9 * 9.9), 1e-12);
  // An aspheric posterior surface: x^2 + y^2 = 2 R w - (1 + Q) w^2.
  EyeModel prolate = navarro_eye();
  prolate.posterior_cornea->surface.asphericity = -0.4;
  EXPECT_NEAR(prolate.iris_outer_radius_mm(), std::sqrt(2 * 6.5 * w - 0.6 * w * w), 1e-12);
  // A wide sclera meets the limbus plane in an annulus; a narrow one joins it
  // by a band of the limbus's radius, which the iris meets when its plane
  // lies beside the band: sphere radius 6 mm about a centre 8.5 mm deep
  // reaches 5.9 mm from the axis sqrt(36 - 5.9^2) = 1.091 mm above the
  // centre, 7.409 mm deep, behind an iris 3.6 mm deep.
  EyeModel small = keratometric_eye();
  small.sclera_radius_mm = 6.0;
  small.rotation_center_depth_mm = 8.5;
  small.iris_radius_mm = 5.0;
  ASSERT_FALSE(anatomy_problem(small)) << anatomy_problem(small)->rule;
  EXPECT_EQ(small.iris_outer_radius_mm(), 5.9);
  // An iris in front of the limbus plane in a two-surface eye: the
  // posterior cornea stops at the limbus plane, the iris is its own size.
  EyeModel shallow = navarro_eye();
  shallow.iris_depth_mm = 2.4;  // the limbus is 2.571 mm deep
  shallow.pupil_radius_mm = 1.0;
  EXPECT_EQ(shallow.iris_outer_radius_mm(), 5.5);
}

// The posterior cornea, run on down to the iris plane, must stay within the
// limbus: at iris depth 4.5 mm it is sqrt(2 6.5 3.95 - 3.95^2) = 5.979 mm
// from the axis, beyond the limbus's 5.9 mm.
TEST(EyeAnatomy, APosteriorCorneaReachingTheIrisPlaneOutsideTheLimbusIsRefused) {
  EyeModel m = navarro_eye();
  m.iris_depth_mm = 4.5;
  const std::optional<AnatomyProblem> problem = anatomy_problem(m);
  ASSERT_TRUE(problem);
  EXPECT_EQ(problem->key, "iris.depth_mm");
  EXPECT_EQ(problem->value, "4.5");
  EXPECT_NE(problem->rule.find("beyond cornea.limbus_radius_mm (5.9)"), std::string::npos) << problem->rule;
  const double r = std::sqrt(2 * 6.5 * 3.95 - 3.95 * 3.95);
  EXPECT_NE(problem->rule.find(check::format_number(r) + " mm from the axis"), std::string::npos) << problem->rule;
  EXPECT_EQ(reader_message(R"({ "model": "navarro", "iris": { "depth_mm": 4.5 } })"),
            "eye.json: eyes[0].iris.depth_mm = 4.5: " + problem->rule);
  m.iris_depth_mm = 4.4;  // 5.94 mm: still beyond
  EXPECT_TRUE(anatomy_problem(m));
  m.iris_depth_mm = 4.3;  // sqrt(2 6.5 3.75 - 3.75^2) = 5.897 mm: within
  EXPECT_FALSE(anatomy_problem(m));
  // Past the posterior surface's equator it is no single-valued cap: an
  // oblate ellipsoid R 3 mm, Q 0.5 turns at w = R / (1 + Q) = 2 mm below
  // its apex, and the iris plane lies 3.4 mm below it.
  EyeModel deep = navarro_eye();
  deep.posterior_cornea->surface = {3.0, 0.5};
  deep.posterior_cornea->thickness_mm = 0.2;
  deep.limbus_radius_mm = 2.4;
  deep.iris_radius_mm = 2.4;
  deep.pupil_radius_mm = 0.5;
  const std::optional<AnatomyProblem> turned = anatomy_problem(deep);
  ASSERT_TRUE(turned);
  EXPECT_EQ(turned->key, "iris.depth_mm") << turned->rule;
  EXPECT_NE(turned->rule.find("single-valued cap there"), std::string::npos) << turned->rule;
}

}  // namespace
}  // namespace purkinje
